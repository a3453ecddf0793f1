"""``SPL/Striker-v0``, ``SPL/Goalie-v0``, ``SPL/PenaltyShootout-v0``: behaviour on perceived state.

Each is also registered without poles (``SPL/Striker-NoPoles-v0`` and so on:
:data:`spl_env.NO_POLES_KWARGS`, the pose from the field's features). Our robot's body is the
action (where to walk, when and where to kick); the head is scripted (looks at the believed
ball, or at a first sighting awaiting a second, scans when it is lost) or, with
``head_control="action"``, part of the action. Every observation key is what perception
believes; the scripted opponents and the rewards use the truth.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from perception.pipeline import PipelineConfig
from perception.tracking.robot_tracker import RobotTrackerConfig
from spl_env.config import SPL_ALIASES, EnvConfig
from spl_env.envs.core import SplEnv
from spl_env.tasks.goalie import GoalieTask, GoalieTaskConfig
from spl_env.tasks.penalty import PenaltyTask, PenaltyTaskConfig
from spl_env.tasks.soccer import SoccerTaskConfig, check_head_reach
from spl_env.tasks.striker import StrikerTask, StrikerTaskConfig

SOCCER_ALIASES: dict[str, str] = {
    **SPL_ALIASES,
    "head_control": "task.head_control",
    "ball_frontend": "perception.ball_sightings",
    "robot_frontend": "perception.robot_sightings",
}

_PERCEPTION_DOC = """
    **Perception**: our pose from the poles (the CNN and the gated EKF SLAM, as
    ``SPL/ActiveVision-v0``), the other robots from seed 004's detector with its sonar check and
    the multi-robot tracker (as ``SPL/ActiveVision-v1``), the ball from the same CNN pass's
    ``ball`` boxes and from the bottom camera's image (rendered each step, read by the CNN at
    half resolution; :mod:`perception.vision.cnn_ball`: the ray through the box centre meets the
    plane of the ball's centre) and its Kalman filter relative to the robot
    (:mod:`perception.tracking.ball_filter`: rolling with friction, the odometry, a kick seen as a
    velocity jump, our own kicks known). ``ball_frontend="cnn"`` (the top camera only) or
    ``"oracle"`` (truth plus noise) for ablations; the geometric camera mode
    (``camera_mode="geometric", frontend="colour"``) emulates both cameras' ball sightings with
    the CNN's measured recall and noise (:mod:`spl_env.sensors.emulation.ball`), and the robot
    sightings' sonar check from the sonar's model, so the rig then measures no sonar
    (``sensor_frame.sonar`` is None).

    **Action**: ``Box(-1, 1, (5,), float32)``, or ``(7,)`` with ``head_control="action"``; the
    table is in :mod:`spl_env.tasks.soccer`: walk ``(vx, vy, omega)`` of the speed limits, kick
    (> 0: its strength), kick direction (of ±60°), and the head target.

    **Observation** (``Dict`` of float32 ``Box``; K = 4 robot rows): ``self_pose_field`` (4,),
    ``self_pose_std`` (3,), ``head_angles`` (2,) (as ``SPL/ActiveVision-v0``), ``ball_bearing``
    (2,) cos and sin from the believed pose, ``ball_range`` (1,) r / (r + 3 m),
    ``ball_velocity`` (2,) robot frame v / (|v| + 0.3 m/s), ``ball_std`` (1,) s / (s + 0.5 m),
    ``ball_since_seen`` (1,) t / (t + 2 s) (1 while no ball is believed: not seen yet, or
    lost), the ``robots_*`` keys of ``SPL/ActiveVision-v1`` (K rows) and ``time_fraction``
    (1,).

    **info**: ``reward_terms``; at ``info_level="full"`` also ``perception`` (the pose, pole
    sightings, the tracked robots, and the believed ball: ``ball`` (2,), ``ball_velocity`` (2,),
    ``ball_cov`` (4, 4), ``ball_known``, ``ball_last_seen_s``) and ``ground_truth`` (with the
    true ``ball`` and ``ball_velocity``).
"""


@dataclass(frozen=True, kw_only=True)
class SoccerConfig(EnvConfig):
    """:class:`spl_env.config.EnvConfig` whose ball is seen by both cameras (the top camera
    cannot see a ball nearer than about 0.35 m: the feet, where it is kicked) and whose robot
    tracks outlive 5 s unseen (the head follows the ball: a goalie seen during the run-up is
    still known at the kick). The scripted head's scan and glance must stay within the
    robot's head joints."""

    perception: PipelineConfig = field(
        default_factory=lambda: PipelineConfig(
            ball_sightings="cnn_both_cameras",
            robot_tracker=RobotTrackerConfig(drop_after_s=5.0),
        )
    )
    task: SoccerTaskConfig = field(default_factory=SoccerTaskConfig)

    def __post_init__(self) -> None:
        super().__post_init__()
        check_head_reach(self.task, self.robot)


@dataclass(frozen=True, kw_only=True)
class StrikerConfig(SoccerConfig):
    """:class:`spl_env.config.EnvConfig` with the striker task."""

    task: StrikerTaskConfig = field(default_factory=StrikerTaskConfig)


@dataclass(frozen=True, kw_only=True)
class GoalieConfig(SoccerConfig):
    """:class:`spl_env.config.EnvConfig` with the goalie task."""

    task: GoalieTaskConfig = field(default_factory=GoalieTaskConfig)


@dataclass(frozen=True, kw_only=True)
class PenaltyShootoutConfig(SoccerConfig):
    """:class:`spl_env.config.EnvConfig` with the penalty task."""

    task: PenaltyTaskConfig = field(default_factory=PenaltyTaskConfig)


class StrikerEnv(SplEnv):
    __doc__ = (
        """Score against a scripted goalie (:class:`spl_env.tasks.striker.StrikerTask`).

    Our robot starts in its own half, the ball lies between the centre line and the opponent's
    penalty area; the goalie (the other team) keeps between the ball and its goal; with
    ``n_other_robots > 1`` defenders walk about. One-minute episodes.

    **Reward**: ``goal`` +10 for a goal (-10 own goal), ``progress`` the metres the ball came
    nearer the opponent goal this step, ``time`` -0.01 per step, ``out`` -1 when the ball
    leaves the field elsewhere; terminated on a goal or the ball out.
"""
        + _PERCEPTION_DOC
    )

    task_class = StrikerTask
    config_class = StrikerConfig
    aliases = SOCCER_ALIASES


class GoalieEnv(SplEnv):
    __doc__ = (
        """Keep the ball out against scripted kicks (:class:`spl_env.tasks.goalie.GoalieTask`).

    Our robot starts on its goal line; the ball lies 1.5-3.5 m out; a kicker of the other team
    walks up to it and kicks it once, at full strength, at a random point of our goal.

    **Reward**: ``goal`` -10 when the ball is in our goal, ``save`` +1 when the kicked ball
    stops or the ball leaves the field elsewhere (our own clearance before the shot counts: the
    kicker then stands); terminated then. 30-second episodes.
"""
        + _PERCEPTION_DOC
    )

    task_class = GoalieTask
    config_class = GoalieConfig
    aliases = SOCCER_ALIASES


class PenaltyShootoutEnv(SplEnv):
    __doc__ = (
        """Seed 004's penalty test as a task (:class:`spl_env.tasks.penalty.PenaltyTask`).

    The ball lies on the opponent penalty mark; our robot starts 1.2 m behind it facing the
    goal; the goalie (the other team) stands still just in front of its goal line, up to
    0.45 m to either side: score by kicking to the open side.

    **Reward**: as ``SPL/Striker-v0``; terminated on a goal, the ball out, or the kicked ball
    stopping (missed or saved). 20-second episodes.
"""
        + _PERCEPTION_DOC
    )

    task_class = PenaltyTask
    config_class = PenaltyShootoutConfig
    aliases = SOCCER_ALIASES
