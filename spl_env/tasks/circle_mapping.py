"""Circle mapping (seed 001): drive a differential-drive robot so that its circle map of a room's
columns or trees becomes complete and accurate, without bumping into anything.

The map's quality against the true circles (:func:`map_quality`) is

    Q = sum_k max(0, 1 - e_k / tolerance_m) - spurious_weight * n_spurious

with ``e_k`` the centre plus radius error (m) of the mapped circle matched to true circle k
(:func:`perception.metrics.match_circles`, pairs closer than ``tolerance_m``; 0 for a missed
circle) and ``n_spurious`` the mapped circles matched to none. The reward of a step is the
change of Q times ``map_weight`` minus ``collision_penalty`` when the robot was blocked, so an
episode's return is the final map's quality minus the collisions (Q starts at 0, empty map).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from gymnasium import spaces

from perception.geometry import FloatArray
from perception.metrics import match_circles
from perception.representations import CIRCLE_MAP, PerceptionOutput
from perception.types import MappedCircle
from perception.validation import check_positive
from spl_env.observations.base import ObservationEncoder
from spl_env.tasks.episode import EpisodeConfig
from spl_env.world_state import RoomState


@dataclass(frozen=True, kw_only=True)
class CircleMappingTaskConfig(EpisodeConfig):
    """Episode, start and reward of :class:`CircleMappingTask` (module docstring)."""

    episode_s: float = 60.0  # seed 001's office run (its backyard runs 180 s)
    start_jitter_m: float = 0.1  # the start is the layout's, moved by up to this in x and y
    start_jitter_rad: float = 0.1  # and turned by up to this
    tolerance_m: float = 0.25  # a mapped circle within this of a true one maps it
    spurious_weight: float = 0.5
    map_weight: float = 1.0
    collision_penalty: float = 0.1

    def __post_init__(self) -> None:
        super().__post_init__()
        owner = "CircleMappingTaskConfig"
        for name in ("start_jitter_m", "start_jitter_rad", "spurious_weight", "collision_penalty"):
            check_positive(owner, name, getattr(self, name), allow_zero=True)
        for name in ("tolerance_m", "map_weight"):
            check_positive(owner, name, getattr(self, name))


def map_quality(
    circles: tuple[MappedCircle, ...], truth: FloatArray, config: CircleMappingTaskConfig
) -> float:
    """Q of the confirmed ``circles`` against the ``truth`` (K, 3) (module docstring)."""
    mapped = np.array([c.state for c in circles if c.confirmed]).reshape(-1, 3)
    match = match_circles(mapped, truth, config.tolerance_m)
    errors = np.nan_to_num(match.centre_error_m + match.radius_error_m, nan=config.tolerance_m)
    scores = np.clip(1.0 - errors / config.tolerance_m, 0.0, 1.0)
    return float(scores.sum() - config.spurious_weight * match.spurious.sum())


class CircleMappingTask:
    """Map a room's circles: the wheel action, the observation's encoders, the reward.

    ``start`` (3,) is the layout's start pose; ``encoders`` the env's observation encoders.
    """

    def __init__(
        self,
        config: CircleMappingTaskConfig,
        start: FloatArray,
        encoders: tuple[ObservationEncoder, ...],
    ) -> None:
        self.config = config
        self.start = np.asarray(start, dtype=np.float64)
        self._encoders = encoders
        self._quality = 0.0

    @property
    def action_space(self) -> spaces.Box:
        """``Box(-1, 1, (2,))``: left and right wheel speed, fractions of the top speed."""
        return spaces.Box(-1.0, 1.0, shape=(2,), dtype=np.float32)

    def encoders(self) -> tuple[ObservationEncoder, ...]:
        return self._encoders

    def reward_requires(self) -> tuple[str, ...]:
        return (CIRCLE_MAP,)

    def start_pose(self, rng: np.random.Generator) -> FloatArray:
        """The layout's start, jittered; the map's quality starts again from 0."""
        c = self.config
        self._quality = 0.0
        jitter = rng.uniform(-1.0, 1.0, 3) * np.array(
            [c.start_jitter_m, c.start_jitter_m, c.start_jitter_rad]
        )
        pose = self.start + jitter
        pose[2] = math.remainder(pose[2], 2 * math.pi)
        return pose

    def reward_terms(self, state: RoomState, output: PerceptionOutput) -> dict[str, float]:
        """``map_improvement`` (the change of Q times ``map_weight``) and ``collision``."""
        quality = map_quality(output[CIRCLE_MAP], state.circles, self.config)
        improvement, self._quality = quality - self._quality, quality
        return {
            "map_improvement": self.config.map_weight * improvement,
            "collision": -self.config.collision_penalty * float(state.blocked),
        }

    def terminated(self, state: RoomState, output: PerceptionOutput) -> bool:
        """Never: the episode ends by truncation."""
        return False
