"""Environment configuration: the scene, our robot and its sensors, perception and the task.

Each part's parameters live next to it (``SceneConfig`` in :mod:`spl_env.scenes.spl_field`,
``RigConfig`` in :mod:`spl_env.sensors.rig`, ``PipelineConfig`` in :mod:`perception.pipeline`,
the task's config beside its task); :class:`EnvConfig` joins them. Keyword arguments to
``gym.make`` set a field by its dotted path (``**{"sensors.camera.noise_std": 0.0}``), by a
top-level name (``control_dt_s=0.2``) or by one of the env's aliases (:data:`SPL_ALIASES`,
``frontend="colour"``); see :func:`spl_env.overrides.apply_overrides`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from perception.pipeline import POLE_MAPPING_POSES, PipelineConfig
from perception.validation import (
    check_bool,
    check_choice,
    check_int,
    check_nested_configs,
    check_positive,
)
from spl_env.robots.nao import RobotConfig
from spl_env.scenes.spl_field import SceneConfig
from spl_env.sensors.rig import RigConfig
from spl_env.tasks.base import TaskConfig
from spl_env.tasks.episode import EpisodeConfig

INFO_LEVELS = ("full", "light")

# The common settings of every SPL env, one name each (spl_env.overrides.apply_overrides).
SPL_ALIASES: dict[str, str] = {
    "episode_s": "task.episode_s",
    "n_other_robots": "task.n_other_robots",
    "camera_mode": "sensors.camera_mode",
    "randomise_lighting": "sensors.camera.randomise_lighting",
    "sonar": "sensors.sonar",
    "laser": "sensors.laser",
    "frontend": "perception.pole_sightings",
    "self_pose": "perception.self_pose",
    "field_features": "perception.field_features",
    "backend": "perception.slam.backend",
    "min_views": "perception.slam.min_views",
    "gate": "perception.slam.gate",
    "score_threshold": "perception.cnn_pole_score_threshold",
}


@dataclass(frozen=True, kw_only=True)
class CoreConfig:
    """What every env of the core (:class:`spl_env.envs.core.RobotEnv`) has: perception, the
    control and physics rates, the ``info`` level; each world kind adds its scene, robot and
    sensors, each env narrows ``task`` to its task's config (an :class:`EpisodeConfig`).

    ``info_level``: ``"full"`` (perception, ground truth and reward terms in ``info``) or
    ``"light"`` (reward terms only, for fast training). ``info_timing`` adds the step's
    wall-clock seconds as ``info["timing"]``; off by default, because seconds measure the host,
    not the world, and would break same-seed comparisons of ``info``.
    """

    perception: PipelineConfig = field(default_factory=PipelineConfig)
    task: EpisodeConfig = field(default_factory=EpisodeConfig)
    control_dt_s: float = 0.1  # one control step = one camera frame / laser scan (10 Hz)
    physics_dt_s: float = 0.01  # PyBullet time step (the ball)
    info_level: str = "full"
    info_timing: bool = False

    def __post_init__(self) -> None:
        check_nested_configs(self)
        check_positive(type(self).__name__, "physics_dt_s", self.physics_dt_s)
        check_positive(type(self).__name__, "control_dt_s", self.control_dt_s)
        if not (0 < self.physics_dt_s <= min(self.control_dt_s, 0.1)) or not (
            self.control_dt_s <= 1.0
        ):
            raise ValueError(
                f"{type(self).__name__} needs 0 < physics_dt_s <= min(control_dt_s, 0.1 s) and "
                f"control_dt_s <= 1 s, got {self.physics_dt_s} and {self.control_dt_s}"
            )
        ratio = self.control_dt_s / self.physics_dt_s
        if abs(ratio - round(ratio)) > 1e-6:
            raise ValueError(
                f"{type(self).__name__}.control_dt_s must be a whole multiple of physics_dt_s, "
                f"got {ratio:.4f}"
            )
        steps = self.task.episode_s / self.control_dt_s
        if not (math.isfinite(steps) and steps >= 1 and abs(steps - round(steps)) < 1e-6):
            raise ValueError(
                f"{type(self).__name__}.task.episode_s must be a whole number (>= 1) of control "
                f"steps of {self.control_dt_s} s, got {self.task.episode_s}"
            )
        check_choice(type(self).__name__, "info_level", self.info_level, INFO_LEVELS)
        check_bool(type(self).__name__, "info_timing", self.info_timing)

    @property
    def substeps(self) -> int:
        """Physics steps per control step."""
        return round(self.control_dt_s / self.physics_dt_s)

    @property
    def max_steps(self) -> int:
        """Control steps per episode."""
        return round(self.task.episode_s / self.control_dt_s)


@dataclass(frozen=True, kw_only=True)
class EnvConfig(CoreConfig):
    """Everything an SPL env is made of: the field, the Naos, our robot's sensors, perception
    and the task (:class:`CoreConfig`'s fields besides). With the laser on (``sensors.laser``),
    the observation holds the ``observed_circles`` nearest circles of the circle map and
    ``info`` the whole map.
    """

    scene: SceneConfig = field(default_factory=SceneConfig)
    robot: RobotConfig = field(default_factory=RobotConfig)
    sensors: RigConfig = field(default_factory=RigConfig)
    task: TaskConfig = field(default_factory=TaskConfig)
    observed_circles: int = 12  # circle-map rows of the observation (with the laser on)

    def __post_init__(self) -> None:
        super().__post_init__()
        if not self.scene.poles_enabled and self.perception.self_pose in POLE_MAPPING_POSES:
            raise ValueError(
                "EnvConfig.scene.poles_enabled=False needs a self pose that does not map the "
                "poles: perception.self_pose='field_features' (or 'oracle'), got "
                f"{self.perception.self_pose!r}"
            )
        check_int("EnvConfig", "observed_circles", self.observed_circles, 1)
