"""Scripted walking behaviours: waypoint following, patrols and random walkers.

Commands are body-frame velocities ``(vx, vy, omega)`` in m/s and rad/s for
:meth:`spl_env.robots.nao.NaoRobot.walk_step`; poses are ``(x, y, theta)`` in the field frame.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from perception.geometry import FloatArray, wrap_scalar
from perception.validation import check_positive
from spl_env.field import FieldDimensions
from spl_env.robots.nao import NaoRobot
from spl_env.sim.placement import Placement


@dataclass(frozen=True, kw_only=True)
class WalkerConfig:
    """How a scripted walker approaches its waypoints."""

    speed_mps: float = 0.15  # forward speed on straight legs
    turn_rate_rps: float = 0.5  # turning speed
    turn_in_place_rad: float = 0.35  # larger heading errors are turned out before walking on
    arrive_radius_m: float = 0.15  # a waypoint closer than this is reached

    def __post_init__(self) -> None:
        for name, value in vars(self).items():
            check_positive("WalkerConfig", name, value)


def waypoint_command(config: WalkerConfig, pose: FloatArray, target: FloatArray) -> FloatArray:
    """Velocity command (3,) that walks from ``pose`` (3,) towards ``target`` (2,).

    Large heading errors are turned out in place first (the seed-000 square walk turns in place);
    small ones are corrected while walking forward.
    """
    dx, dy = target[0] - pose[0], target[1] - pose[1]
    heading_error = wrap_scalar(math.atan2(dy, dx) - pose[2])
    omega = min(max(2.0 * heading_error, -config.turn_rate_rps), config.turn_rate_rps)
    if abs(heading_error) > config.turn_in_place_rad:
        return np.array([0.0, 0.0, omega])
    return np.array([config.speed_mps, 0.0, omega])


class WaypointWalker:
    """Walks through waypoints in order; a random walker draws a new one when it arrives or sticks.

    With ``waypoints`` given the walker loops over them (a patrol or the square walk); without,
    it draws targets uniformly inside the field shrunk by ``margin_m`` from ``rng``.
    """

    def __init__(
        self,
        config: WalkerConfig,
        field: FieldDimensions,
        rng: np.random.Generator,
        waypoints: FloatArray | None = None,
        margin_m: float = 0.5,
    ) -> None:
        if waypoints is not None and (
            waypoints.ndim != 2 or waypoints.shape[1] != 2 or len(waypoints) < 1
        ):
            raise ValueError(f"waypoints must be (N, 2) with N >= 1, got shape {waypoints.shape}")
        self.config = config
        self.field = field
        self.rng = rng
        self.margin_m = margin_m
        self.waypoints = waypoints
        self.index = 0
        self.target = waypoints[0] if waypoints is not None else self._random_target()
        self.stuck_s = 0.0

    def _random_target(self) -> FloatArray:
        hl = self.field.half_length_m - self.margin_m
        hw = self.field.half_width_m - self.margin_m
        return np.array([self.rng.uniform(-hl, hl), self.rng.uniform(-hw, hw)])

    def command(self, pose: FloatArray, dt_s: float, blocked: bool) -> FloatArray:
        """Command (3,) for this control step; ``blocked`` says the last step hit something."""
        self.stuck_s = self.stuck_s + dt_s if blocked else 0.0
        arrived = (
            math.hypot(self.target[0] - pose[0], self.target[1] - pose[1])
            < self.config.arrive_radius_m
        )
        if self.waypoints is not None:
            if arrived:
                self.index = (self.index + 1) % len(self.waypoints)
                self.target = self.waypoints[self.index]
        elif arrived or self.stuck_s > 1.0:
            self.target = self._random_target()
            self.stuck_s = 0.0
        return waypoint_command(self.config, pose, self.target)


class WanderingRobots:
    """Scripted robots that each walk to random waypoints inside the field and, when stuck
    for a second, pick another."""

    def __init__(self, config: WalkerConfig, field: FieldDimensions) -> None:
        self.config = config
        self.field = field
        self._walkers: list[WaypointWalker] = []

    def reset(
        self,
        rng: np.random.Generator,
        robots: Sequence[NaoRobot],
        placement: Placement,
        placed: list[NaoRobot],
    ) -> None:
        """Give each of ``robots`` a walker and a free pose clear of ``placed`` (to which each
        placed robot is appended)."""
        self._walkers = []
        for robot in robots:
            walker = WaypointWalker(self.config, self.field, rng)
            robot.place(placement.free_pose(rng, placed))
            placed.append(robot)
            self._walkers.append(walker)

    def commands(
        self, poses: FloatArray, dt_s: float, blocked: Sequence[bool] | NDArray[np.bool_]
    ) -> list[FloatArray]:
        """Walk commands (3,) of the robots at ``poses`` (N, 3), in :meth:`reset`'s order;
        ``blocked`` (N,) says which bumped into something last step."""
        return [
            walker.command(pose, dt_s, blocked=bool(b))
            for walker, pose, b in zip(self._walkers, poses, blocked, strict=True)
        ]
