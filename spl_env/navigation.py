"""Seed 001's navigation for the differential-drive robot: Braitenberg, a waypoint route, both.

Seed 001 (§5.2) moves its Pioneer 3-DX about with three controllers, each returning an action
(2,) in [-1, 1] for :func:`spl_env.robots.diff_drive.wheel_speeds_from_action` (left, right
wheel speed as a fraction of the maximum; + = forward):

- :func:`braitenberg_action`, purely reactive obstacle avoidance from the 16 sonars (§5.2.1):
  each wheel runs at a base speed plus a weighted sum of the normalised sonar detections,
  ``v_m' = v_m + Σ_c w_c d_c``, and nothing beyond a maximum detection distance counts, so
  that the robot does not oscillate;
- :class:`WaypointFollower`, a route of waypoints visited in order and looped (§5.2.2): turn
  in place towards the next waypoint until the heading error is within a tolerance (20° in the
  seed), then drive both wheels at the same speed;
- :class:`HybridNavigator`, the two combined (the seed's hybrid paradigm): the route's action,
  plus the Braitenberg correction whenever a front sonar sees an obstacle.

Sonar ranges are (S,) float64 (m, S = 16 on the Pioneer), in the sonar ring's order of
:data:`spl_env.robots.diff_drive.PIONEER_SONAR_RING` (ARIA: 0 = left +90°, 1-6 the front
sweep, 7 = right -90°, 8-15 the rear ring), NaN where a sonar has no echo. Poses are (3,)
``(x, y, θ)`` in the field frame (m, rad, counter-clockwise); waypoints (N, 2) field points (m).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from perception.geometry import FloatArray, wrap_angle
from perception.validation import (
    InvalidTypeError,
    check_finite,
    check_int,
    check_nested_configs,
    check_positive,
    finite_points,
    finite_vector,
)

# Weights of CoppeliaSim's Pioneer 3-DX Braitenberg demo (per front sonar, left to right:
# braitenbergL = -0.2, -0.4, ..., -1.6 and braitenbergR the reverse, rear sonars 0, with a base
# v0 = 2 rad/s), scaled by 0.4 / 2 to this module's base action of 0.4: an obstacle on the left
# slows the right wheel most and the robot turns right, away from it, and vice versa. (The
# demo's detection runs from 0.2 m to 0.5 m; the default here reaches 0.6 m.)
_FRONT_LEFT_WHEEL = (-0.04, -0.08, -0.12, -0.16, -0.20, -0.24, -0.28, -0.32)
_REAR = (0.0,) * 8


def _check_weights(owner: str, name: str, weights: object) -> None:
    """Raise unless ``weights`` is a non-empty tuple of finite real numbers."""
    if not isinstance(weights, tuple):
        raise InvalidTypeError(
            f"{owner}.{name} must be a non-empty tuple of numbers, "
            f"got {type(weights).__name__} {weights!r}"
        )
    if not weights:
        raise ValueError(f"{owner}.{name} must be a non-empty tuple of numbers, got ()")
    for k, weight in enumerate(weights):
        check_finite(owner, f"{name}[{k}]", weight)


@dataclass(frozen=True, kw_only=True)
class BraitenbergConfig:
    """Base action, detection distances and per-sonar weights of :func:`braitenberg_action`.

    A sonar's detection ``d`` is 1 at ``full_detection_m`` or closer, falls linearly to 0 at
    ``max_detection_m`` and is 0 beyond it or without an echo. The weights are action fractions
    per unit detection, one per sonar in ring order; both tuples have the ring's length.
    """

    base_action: float = 0.4  # both wheels' action without obstacles, (0, 1]
    max_detection_m: float = 0.6  # farther echoes count for nothing (no oscillation)
    full_detection_m: float = 0.2  # closer echoes count as a full detection, 1
    left_weights: tuple[float, ...] = _FRONT_LEFT_WHEEL + _REAR
    right_weights: tuple[float, ...] = _FRONT_LEFT_WHEEL[::-1] + _REAR

    def __post_init__(self) -> None:
        owner = "BraitenbergConfig"
        check_positive(owner, "base_action", self.base_action, upper=1.0, upper_inclusive=True)
        check_positive(owner, "max_detection_m", self.max_detection_m)
        check_positive(
            owner,
            "full_detection_m",
            self.full_detection_m,
            allow_zero=True,
            upper=self.max_detection_m,
        )
        _check_weights(owner, "left_weights", self.left_weights)
        _check_weights(owner, "right_weights", self.right_weights)
        if len(self.right_weights) != len(self.left_weights):
            raise ValueError(
                f"{owner}.right_weights must have as many weights as left_weights "
                f"({len(self.left_weights)}), got {len(self.right_weights)}"
            )

    def weights(self) -> FloatArray:
        """The weights (2, S): rows left wheel, right wheel; columns sonars in ring order."""
        return np.array([self.left_weights, self.right_weights], dtype=np.float64)


def sonar_detections(sonar_ranges: ArrayLike, config: BraitenbergConfig) -> FloatArray:
    """Normalised detections (S,) in [0, 1] of sonar ranges (S,) (m; NaN = no echo).

    ``d = 1 - (range - full) / (max - full)`` clipped into [0, 1]: 1 at ``full_detection_m`` or
    closer, 0 at ``max_detection_m`` or beyond and without an echo. ``S`` must be the number of
    weights; a negative or infinite range raises ValueError.
    """
    size = len(config.left_weights)
    try:
        ranges = np.array(sonar_ranges, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise InvalidTypeError(
            f"sonar_ranges must be {size} numbers, got {sonar_ranges!r}"
        ) from error
    if ranges.shape != (size,):
        raise ValueError(f"sonar_ranges must have shape ({size},), got shape {ranges.shape}")
    echo = ~np.isnan(ranges)
    if np.any(np.isinf(ranges)) or np.any(ranges[echo] < 0.0):
        raise ValueError(
            f"sonar_ranges must be finite and >= 0 (m) or NaN (no echo), got {ranges.tolist()}"
        )
    span = config.max_detection_m - config.full_detection_m
    detections = np.zeros(size)
    detections[echo] = np.clip(1.0 - (ranges[echo] - config.full_detection_m) / span, 0.0, 1.0)
    return detections


def braitenberg_action(sonar_ranges: ArrayLike, config: BraitenbergConfig) -> FloatArray:
    """Braitenberg action (2,) in [-1, 1] (left, right) for sonar ranges (S,) (m; NaN = no echo).

    ``base_action + Σ_c w_c d_c`` on each wheel (seed 001 §5.2.1), saturated into [-1, 1]:
    several close obstacles may ask more of a motor than it can give, and it then runs at its
    limit, as a real motor would.
    """
    correction = config.weights() @ sonar_detections(sonar_ranges, config)
    return np.clip(config.base_action + correction, -1.0, 1.0)


@dataclass(frozen=True, kw_only=True)
class WaypointConfig:
    """How a :class:`WaypointFollower` turns, drives and arrives."""

    heading_tolerance_deg: float = 20.0  # drive straight within this heading error (seed 001)
    arrival_radius_m: float = 0.3  # a waypoint closer than this is reached
    drive_fraction: float = 0.5  # both wheels' action when driving, (0, 1]
    turn_fraction: float = 0.3  # the wheels' action magnitude when turning in place, (0, 1]

    def __post_init__(self) -> None:
        owner = "WaypointConfig"
        check_positive(owner, "heading_tolerance_deg", self.heading_tolerance_deg, upper=180.0)
        check_positive(owner, "arrival_radius_m", self.arrival_radius_m)
        for name in ("drive_fraction", "turn_fraction"):
            check_positive(owner, name, getattr(self, name), upper=1.0, upper_inclusive=True)


class WaypointFollower:
    """Drives round a loop of waypoints (N, 2) (field frame, m) in order (seed 001 §5.2.2).

    Each :meth:`action` call first moves on to the next waypoint (after the last, the first
    again) if the robot is within ``arrival_radius_m`` of the current one; then it turns in
    place towards the target while the heading error exceeds ``heading_tolerance_deg``, and
    drives straight otherwise. N >= 2.
    """

    def __init__(self, waypoints: ArrayLike, config: WaypointConfig) -> None:
        if not isinstance(config, WaypointConfig):
            raise InvalidTypeError(
                f"config must be a WaypointConfig, got {type(config).__name__} {config!r}"
            )
        self.waypoints = finite_points(waypoints, "waypoints", 2)
        self.config = config
        self._tolerance_rad = math.radians(config.heading_tolerance_deg)
        self._index = 0
        self._laps = 0

    def reset(self) -> None:
        """Head for waypoint 0 again, with no laps done."""
        self._index = 0
        self._laps = 0

    @property
    def target_index(self) -> int:
        """Index of the waypoint being driven to."""
        return self._index

    @property
    def target(self) -> FloatArray:
        """The waypoint being driven to (2,) (field frame, m)."""
        return self.waypoints[self._index].copy()

    @property
    def laps(self) -> int:
        """Complete loops since :meth:`reset`: arrivals at the last waypoint."""
        return self._laps

    def action(self, pose: ArrayLike) -> FloatArray:
        """Action (2,) (left, right) from the robot's field pose (3,) ``(x, y, θ)``."""
        x, y, heading = finite_vector(pose, "pose", 3)
        if math.hypot(*(self.waypoints[self._index] - (x, y))) < self.config.arrival_radius_m:
            self._index = (self._index + 1) % len(self.waypoints)
            if self._index == 0:
                self._laps += 1
        dx, dy = self.waypoints[self._index] - (x, y)
        error = float(wrap_angle(math.atan2(dy, dx) - heading))
        if abs(error) > self._tolerance_rad:
            turn = math.copysign(self.config.turn_fraction, error)  # + = left: right wheel ahead
            return np.array([-turn, turn])
        return np.full(2, self.config.drive_fraction)


@dataclass(frozen=True, kw_only=True)
class HybridConfig:
    """A :class:`HybridNavigator`'s route following, obstacle avoidance and front sonars."""

    waypoint: WaypointConfig = field(default_factory=WaypointConfig)
    braitenberg: BraitenbergConfig = field(default_factory=BraitenbergConfig)
    front_sonars: tuple[int, ...] = (1, 2, 3, 4, 5, 6)  # ring indices, the Pioneer's front sweep

    def __post_init__(self) -> None:
        check_nested_configs(self)
        owner = "HybridConfig"
        if not isinstance(self.front_sonars, tuple) or not self.front_sonars:
            raise InvalidTypeError(
                f"{owner}.front_sonars must be a non-empty tuple of sonar indices, "
                f"got {type(self.front_sonars).__name__} {self.front_sonars!r}"
            )
        size = len(self.braitenberg.left_weights)
        for k, index in enumerate(self.front_sonars):
            check_int(owner, f"front_sonars[{k}]", index, 0)
            if index >= size:
                raise ValueError(
                    f"{owner}.front_sonars[{k}] must be a sonar index < {size} (the "
                    f"braitenberg weights' length), got {index}"
                )


class HybridNavigator:
    """Route following with Braitenberg obstacle avoidance (seed 001's hybrid navigation).

    The :class:`WaypointFollower`'s action; when any front sonar has an echo closer than
    ``max_detection_m``, plus the Braitenberg correction ``Σ_c w_c d_c`` (the weighted
    detections of all sonars, without the base action), saturated into [-1, 1].
    """

    def __init__(self, waypoints: ArrayLike, config: HybridConfig) -> None:
        if not isinstance(config, HybridConfig):
            raise InvalidTypeError(
                f"config must be a HybridConfig, got {type(config).__name__} {config!r}"
            )
        self.config = config
        self.follower = WaypointFollower(waypoints, config.waypoint)
        self._front = np.array(config.front_sonars)

    def reset(self) -> None:
        """Restart the route at waypoint 0."""
        self.follower.reset()

    def action(self, pose: ArrayLike, sonar_ranges: ArrayLike) -> FloatArray:
        """Action (2,) (left, right) from the field pose (3,) and sonar ranges (S,) (m; NaN =
        no echo)."""
        detections = sonar_detections(sonar_ranges, self.config.braitenberg)
        route = self.follower.action(pose)
        if not np.any(detections[self._front] > 0.0):
            return route
        correction = self.config.braitenberg.weights() @ detections
        return np.clip(route + correction, -1.0, 1.0)
