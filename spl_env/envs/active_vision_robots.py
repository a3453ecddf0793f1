"""``SPL/ActiveVision-v1``: ActiveVision-v0 plus the other robots, detected and tracked."""

from __future__ import annotations

from dataclasses import dataclass, field

from spl_env.config import EnvConfig
from spl_env.envs.active_vision import ACTIVE_VISION_ALIASES
from spl_env.envs.core import SplEnv
from spl_env.tasks.robot_awareness import RobotAwarenessTask, RobotAwarenessTaskConfig

ACTIVE_VISION_V1_ALIASES: dict[str, str] = {
    **ACTIVE_VISION_ALIASES,
    "robot_frontend": "perception.robot_sightings",
}


@dataclass(frozen=True, kw_only=True)
class ActiveVisionRobotsConfig(EnvConfig):
    """:class:`spl_env.config.EnvConfig` with the robot-awareness task."""

    task: RobotAwarenessTaskConfig = field(default_factory=RobotAwarenessTaskConfig)


class ActiveVisionRobotsEnv(SplEnv):
    """Active vision among robots: localise from the poles and keep track of the robots nearby.

    Everything of ``SPL/ActiveVision-v0`` (:class:`spl_env.envs.active_vision.ActiveVisionEnv`:
    body walk, action, pole and self-pose observation keys, localisation reward, camera modes,
    configuration), plus the other robots as perception tracks them (seed 004 ch. 6):
    ``robot_frontend="vision"`` (the default: seed 004 §6.2's indents in the field's edge, the
    team from jersey and waistband colours, then Algorithm 2's sonar check: a sighting at a
    filtered sonar range takes it, one with neither a team nor a sonar return is dropped),
    ``"vision_only"`` (without the sonar check), ``"cnn"`` (the packaged CNN's ``robot``
    detections, ground point of the box bottom; the same CNN pass as the poles; no team) or
    ``"oracle"`` (truth plus noise, for ablations); the sightings move to the field with the
    SLAM pose (its covariance in the noise) and feed a constant-velocity multi-robot Kalman
    tracker (chi-square gate, global nearest neighbour, confirmed after 3 hits, dropped 2 s
    unseen). The geometric camera mode emulates the ``vision`` or ``cnn`` front end's robot
    sightings (in view, unhidden, their detection chance, team and noise measured on rendered
    frames; :mod:`spl_env.sensors.emulation.robots`).

    **Observation**: v0's keys plus, for up to K = 8 confirmed tracks (nearest first; rows past
    the last are zero):

    ======================  ======  =========================================================
    key                     shape   content
    ======================  ======  =========================================================
    ``robots_cos_bearing``  (K,)    cos of the track's bearing from the SLAM pose (robot frame)
    ``robots_sin_bearing``  (K,)    sin of that bearing
    ``robots_range``        (K,)    r / (r + 3 m)
    ``robots_velocity_x``   (K,)    forward velocity (robot frame) v / (|v| + 0.3 m/s)
    ``robots_velocity_y``   (K,)    leftward velocity (robot frame) v / (|v| + 0.3 m/s)
    ``robots_std``          (K,)    s / (s + 0.5 m), s = sqrt(trace of the position cov)
    ``robots_team``         (K,)    +1 ours, -1 theirs, 0 unknown (the CNN sees no team)
    ``robots_since_seen``   (K,)    t / (t + 2 s) since the track's last sighting
    ``robots_mask``         (K,)    1 where a track fills the row
    ======================  ======  =========================================================

    **Reward**: v0's ``position_error``, ``uncertainty`` and ``information`` plus
    ``robot_awareness``: ``-0.5 * (1 - share)``, ``share`` the share of the robots within 3 m
    tracked within 0.3 m (0 when no robot is that near); each term in ``info["reward_terms"]``.

    **info**: v0's, plus in ``perception`` the confirmed tracks (16 rows, by track id):
    ``robots`` (16, 2), ``robot_velocities`` (16, 2), ``robot_covs`` (16, 2, 2),
    ``robot_teams`` (16,) (-1 unknown), ``robot_track_ids`` (16,), ``robots_tracked`` (16,) bool.

    **Configuration**: :class:`ActiveVisionRobotsConfig`; v0's aliases plus ``robot_frontend``;
    the task's fields under ``task.`` (``task.max_tracked_robots``, ``task.awareness_weight``).

    Version history: v1 adds the tracked robots to v0's observation and reward.
    """

    task_class = RobotAwarenessTask
    config_class = ActiveVisionRobotsConfig
    aliases = ACTIVE_VISION_V1_ALIASES
