"""Scripted wheel policies for ``Circles/Office-v0`` and ``Circles/Backyard-v0`` (seed 001
§5.2), with SB3's ``predict`` signature, reading only the observation.

- :class:`WaypointDriver`: the layout's route, visited in order on the believed pose (turn
  until within 20° of the next waypoint, then drive), with Braitenberg avoidance from the
  sonars when something is close ahead (seed 001's hybrid);
- :class:`BraitenbergDriver`: Braitenberg avoidance alone, wandering.

Both decode the believed pose from ``self_pose_field`` and the sonar ranges from
``sonar_ring`` (:class:`spl_env.observations.ranges.SonarRingEncoder`'s d / (d + 1 m)).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from perception.geometry import FloatArray
from spl_env.envs.circles import CirclesConfig
from spl_env.navigation import (
    BraitenbergConfig,
    HybridConfig,
    HybridNavigator,
    braitenberg_action,
)
from spl_env.observations.base import unsquash
from spl_env.observations.body import SONAR_SCALE_M


def believed_pose(obs: dict[str, np.ndarray], half_size_m: tuple[float, float]) -> FloatArray:
    """The believed pose (3,) ``(x, y, θ)`` from ``self_pose_field`` (x and y over the room's
    inner half length and width ``half_size_m``, cos θ, sin θ)."""
    x, y, c, s = np.asarray(obs["self_pose_field"], dtype=np.float64)
    return np.array([x * half_size_m[0], y * half_size_m[1], math.atan2(s, c)])


def sonar_ranges(obs: dict[str, np.ndarray]) -> FloatArray:
    """The sonar ranges (S,) (m) from ``sonar_ring`` (q = d / (d + 1 m)); NaN for no echo."""
    q = np.asarray(obs["sonar_ring"], dtype=np.float64)
    ranges = np.full(len(q), np.nan)
    echo = q < 1.0
    ranges[echo] = unsquash(q[echo], SONAR_SCALE_M)
    return ranges


class _Driver:
    """SB3's ``predict`` over :meth:`act`."""

    def reset(self) -> None:
        """Start of an episode."""

    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        """Action (2,) float32 (left, right wheel) for one observation."""
        raise NotImplementedError

    def predict(
        self,
        obs: dict[str, np.ndarray],
        state: Any = None,
        episode_start: Any = None,
        deterministic: bool = True,
    ) -> tuple[np.ndarray, None]:
        """SB3-style: ``episode_start`` true restarts the policy."""
        if episode_start is not None and np.any(episode_start):
            self.reset()
        return self.act(obs), None


class WaypointDriver(_Driver):
    """The route ``waypoints`` (N, 2) with Braitenberg avoidance (:class:`HybridNavigator`)."""

    def __init__(
        self,
        waypoints: FloatArray,
        half_size_m: tuple[float, float],
        config: HybridConfig | None = None,
    ) -> None:
        self.navigator = HybridNavigator(waypoints, config or HybridConfig())
        self.half_size_m = half_size_m

    @classmethod
    def from_config(cls, config: CirclesConfig) -> WaypointDriver:
        """The driver of the env built from ``config``: its layout's route."""
        return cls(np.array(config.layout.waypoints), config.layout.half_size_m)

    def reset(self) -> None:
        self.navigator.reset()

    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        pose = believed_pose(obs, self.half_size_m)
        return self.navigator.action(pose, sonar_ranges(obs)).astype(np.float32)


class BraitenbergDriver(_Driver):
    """Braitenberg avoidance from the sonar ring alone."""

    def __init__(self, config: BraitenbergConfig | None = None) -> None:
        self.config = config or BraitenbergConfig()

    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        return braitenberg_action(sonar_ranges(obs), self.config).astype(np.float32)
