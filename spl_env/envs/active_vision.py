"""``SPL/ActiveVision-v0``: decide where the robot looks while its body walks a scripted path."""

from __future__ import annotations

from dataclasses import dataclass, field

from spl_env.config import SPL_ALIASES, EnvConfig
from spl_env.envs.core import SplEnv
from spl_env.tasks.active_vision import ActiveVisionTask, ActiveVisionTaskConfig

ACTIVE_VISION_ALIASES: dict[str, str] = {
    **SPL_ALIASES,
    "body_behaviour": "task.body_behaviour",
    "square_side_m": "task.square_side_m",
}


@dataclass(frozen=True, kw_only=True)
class ActiveVisionConfig(EnvConfig):
    """:class:`spl_env.config.EnvConfig` with the active-vision task."""

    task: ActiveVisionTaskConfig = field(default_factory=ActiveVisionTaskConfig)


class ActiveVisionEnv(SplEnv):
    """Active vision on an SPL field: move the head so that EKF SLAM stays accurate and certain.

    Our Nao walks a scripted path (``body_behaviour="patrol"``: random waypoints inside the
    field; ``"square"``: seed 000's square walk) among four other robots that walk about and
    occlude the view. Six two-coloured poles stand outside the touch lines. Every control step
    (10 Hz) renders one camera frame; a front end detects poles in it and an EKF SLAM back end
    fuses them with noisy walk odometry. The observation is what perception believes, never
    ground truth.

    **Perception** (seed 000), chosen by keyword: ``frontend="colour"`` (HSV colour filter) or
    ``"cnn"`` (the packaged CenterNet-style detector; rendered camera mode only);
    ``backend="classic"`` (Algorithm 5), ``"gated"`` (sightings off by more than 0.4 m or
    π/3 from the prediction are dropped), ``"minimal_view"`` (a pole enters the map after
    ``min_views`` sightings in one place, default 3) or ``"fej"`` (first-estimates Jacobians);
    ``min_views=n`` and ``gate="thresholds" | "mahalanobis" | "none"`` combine with any back
    end. The defaults are the CNN (SLAM takes its detections scoring 0.6 or more with both
    band colours seen) with the gated back end (README, "Choosing the defaults").

    **Action**: ``Box(-1, 1, (2,), float32)``, the head target
    (:func:`spl_env.robots.nao.head_target`): yaw ``a[0] * 119.5°`` and pitch from ``-38.5°``
    (``a[1] = -1``, up) to ``+29.5°`` (``a[1] = 1``, down), linear in between. The head turns
    towards the target at up to 4 rad/s. NaN or out-of-range actions raise ``ValueError``.

    **Observation** (``Dict`` of float32 ``Box``; L = 6 landmark ids, index = id):

    ========================  ======  =======================================================
    key                       shape   content
    ========================  ======  =======================================================
    ``self_pose_field``       (4,)    SLAM pose: x / 5.2 m, y / 3.7 m (carpet half sizes,
                                      saturating at ±1.5), cos θ, sin θ
    ``self_pose_std``         (3,)    std of x, y (m) and θ (rad), each as s / (s + 0.5)
    ``head_angles``           (2,)    head yaw / 119.5°; pitch, [-38.5°, 29.5°] -> [-1, 1]
    ``landmarks_cos_bearing`` (L,)    cos of each mapped pole's bearing from the SLAM pose
                                      (robot frame); 0 if not mapped
    ``landmarks_sin_bearing`` (L,)    sin of that bearing; 0 if not mapped
    ``landmarks_range``       (L,)    r / (r + 3 m), r its range from the SLAM pose; 0 if not
                                      mapped
    ``landmarks_mask``        (L,)    1 where the pole is in the SLAM map
    ``landmarks_std``         (L,)    s / (s + 0.5 m), s = sqrt(trace cov) of a mapped pole;
                                      1 if not mapped
    ``landmarks_since_seen``  (L,)    time since last detection t / (t + 2 s); 1 if never
    ``sonar``                 (3,)    nearest echo of the left, middle and right sonar
                                      sectors, d / (d + 1 m); 1 when no echo
    ``time_fraction``         (1,)    elapsed time / episode length
    ========================  ======  =======================================================

    **Reward** per step, each term in ``info["reward_terms"]``:

    - ``position_error``: ``-error_weight * |p_true - p_slam|`` (m), the true localisation error;
    - ``uncertainty``: ``-uncertainty_weight * sqrt(trace Σ_xy)`` (m), the believed position std;
    - ``information``: ``information_weight`` (default 0) times how much that std fell since the
      previous step (0 at time 0): pays for a step's sightings at once.

    **Episode**: truncated after ``episode_s`` (60 s, 600 steps); never terminated. The body's
    scripted walk steers on the true pose (it is scenery, not the policy's concern).

    **info** (after ``reset`` and every ``step``; SI units, field frame; every entry has a
    fixed shape, so vector envs can stack it; L = 6 poles in id order):

    - ``perception``: ``pose`` (3,), ``pose_cov`` (3, 3), ``odometry_pose`` (3,) (dead
      reckoning from the same start), ``landmark_ids`` (L,), ``landmarks`` (L, 2) and
      ``landmark_covs`` (L, 2, 2) of the SLAM map with ``landmarks_mapped`` (L,) bool (rows of
      unmapped poles are zero), this step's ``sightings`` (L, 2) range and bearing (robot
      frame) with ``sighted`` (L,) bool;
    - ``ground_truth``: ``robot_pose`` (3,), ``head`` (2,), ``landmarks`` (L, 2),
      ``landmark_ids`` (L,), the other ``robots`` (R, 3) with ``robot_teams`` (R,), ``ball``
      (2,), ``ball_velocity`` (2,);
    - ``reward_terms``.

    ``info_level="light"`` keeps only ``reward_terms`` (fast training); ``info_timing=True``
    adds ``timing`` (physics, render, sensors, perception seconds; off by default, because
    seconds measure the host, not the world). Robot tracks are not in v0 (its perception has
    no robot tracker): ``SPL/ActiveVision-v1``
    (:class:`spl_env.envs.active_vision_robots.ActiveVisionRobotsEnv`) adds them. Other keys
    come with settings: ``circles_*`` with the laser on (``laser=FINE_LASER``;
    :mod:`spl_env.observations.circles`), ``field_features_since_seen`` in place of the
    ``landmarks_*`` keys without poles (the ``-NoPoles`` ids;
    :mod:`spl_env.observations.field_features`).

    **Camera modes** (``camera_mode``): ``"rendered"`` (default) renders a frame and runs the
    front end on it; ``"geometric"`` (about 10x faster) projects the poles' band centres
    instead, keeps each with the rendered pipeline's fitted chance under the frame's motion blur
    and adds fitted pixel noise, then measures with the same model. The geometric mode makes no
    false detections and ignores lighting randomisation and image noise (it was fitted under
    default lighting). It emulates the colour front end: pass ``frontend="colour"`` with it
    (the default ``"cnn"`` is refused).

    **Configuration**: :class:`ActiveVisionConfig`. Keyword arguments set a field by dotted
    path (``**{"sensors.camera.noise_std": 0.0}``), top-level name or alias
    (:data:`ACTIVE_VISION_ALIASES`: ``frontend``, ``backend``, ``min_views``, ``gate``,
    ``score_threshold``, ``self_pose``, ``camera_mode``, ``randomise_lighting``, ``sonar``,
    ``laser``, ``episode_s``, ``n_other_robots``, ``body_behaviour``, ``square_side_m``).
    ``frontend="oracle"`` / ``self_pose="oracle"`` switch in the ground truth plus
    configured noise (``perception.oracle``) for ablations.

    Version history: v0, first release; the reshaping onto the env core kept its observations
    (recorded reference rollouts) and made ``info`` vector-safe.
    """

    task_class = ActiveVisionTask
    config_class = ActiveVisionConfig
    aliases = ACTIVE_VISION_ALIASES
