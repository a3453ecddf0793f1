"""Kinematic placement: free poses, collisions, and one walking (or driving) step with them.

Robots are discs of ``body_radius_m`` in plan view; posts, poles, columns and trees are
``(x, y, radius)`` obstacles; the area's edge (an SPL carpet, a room's walls) bounds everything.
Any robot with a kinematic body moves this way: the Nao (:mod:`spl_env.robots.nao`) and the
differential drive (:mod:`spl_env.robots.diff_drive`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from perception.geometry import FloatArray, compose


class Area(Protocol):
    """A rectangle centred on the origin: its outer edge ``carpet_size_m`` (length, width; m)
    bounds every body, and poses are drawn inside ``half_length_m`` x ``half_width_m`` (m)
    (an SPL field's lines; a room's walls)."""

    @property
    def carpet_size_m(self) -> tuple[float, float]: ...

    @property
    def half_length_m(self) -> float: ...

    @property
    def half_width_m(self) -> float: ...


@dataclass(frozen=True)
class RectangleArea:
    """An :class:`Area` whose edge is where poses are drawn too: a room's inner walls (m)."""

    half_length_m: float
    half_width_m: float

    @property
    def carpet_size_m(self) -> tuple[float, float]:
        """(length, width) (m)."""
        return 2 * self.half_length_m, 2 * self.half_width_m


class Mobile(Protocol):
    """A kinematic robot: a pose (3,) it commits a step's increment to (the Nao's walk, the
    differential drive's wheels)."""

    pose: FloatArray

    def walk_step(self, command: FloatArray, dt_s: float) -> FloatArray: ...

    def commit_motion(
        self, increment: FloatArray | None, contact_xy: FloatArray | None = None, dt_s: float = 0.0
    ) -> None: ...

    def sync(self) -> None: ...


class Placement:
    """Collision tests and free-pose sampling among ``obstacles`` (K, 3) in a ``dimensions``
    area, for robots of radius ``robot_radius_m``; fixed once built (the carpet's bounds and
    the obstacles' reach are worked out from them then)."""

    def __init__(self, dimensions: Area, obstacles: FloatArray, robot_radius_m: float) -> None:
        self.dimensions = dimensions
        self.obstacles = np.asarray(obstacles, dtype=np.float64).reshape(-1, 3)
        self.robot_radius_m = robot_radius_m
        # how far a robot's centre may go from the origin, and come to each obstacle's centre
        length, width = dimensions.carpet_size_m
        self._half_extent = (length / 2 - robot_radius_m, width / 2 - robot_radius_m)
        self._reach = robot_radius_m + self.obstacles[:, 2]

    def collides(self, xy: FloatArray, robots: Sequence[Mobile], clearance: float) -> bool:
        """Whether a robot at ``xy`` (2,) overlaps one of ``robots``, a post or a pole with
        ``clearance`` (m) to spare, or leaves the carpet (the edge takes no clearance)."""
        return self.obstruction(xy, robots, clearance) is not None

    def obstruction(
        self, xy: FloatArray, robots: Sequence[Mobile], clearance: float
    ) -> FloatArray | None:
        """Where a robot at ``xy`` (2,) would touch what it overlaps: the point (2,) (m) of the
        carpet's edge it crosses, or the centre of the first robot, post or pole it overlaps
        with ``clearance`` (m) to spare (the edge takes none); None when it is clear. A
        non-finite ``xy`` raises ValueError."""
        r = self.robot_radius_m
        x, y = float(xy[0]), float(xy[1])
        if not (math.isfinite(x) and math.isfinite(y)):
            raise ValueError(f"xy must be a finite (2,) position, got {xy!r}")
        half_l, half_w = self._half_extent
        if abs(x) > half_l or abs(y) > half_w:
            edge = np.array([np.clip(x, -half_l, half_l), np.clip(y, -half_w, half_w)])
            return edge + np.array([r * np.sign(x - edge[0]), r * np.sign(y - edge[1])])
        for robot in robots:
            if math.hypot(robot.pose[0] - x, robot.pose[1] - y) < 2 * r + clearance:
                return np.asarray(robot.pose[:2], dtype=np.float64).copy()
        d = np.hypot(self.obstacles[:, 0] - x, self.obstacles[:, 1] - y)
        hit = d < self._reach + clearance
        return self.obstacles[hit.argmax(), :2].copy() if hit.any() else None

    def random_pose(self, rng: np.random.Generator, margin_m: float) -> FloatArray:
        """A pose (3,) drawn uniformly inside the field lines shrunk by ``margin_m`` (m), any
        heading."""
        dims = self.dimensions
        return np.array(
            [
                rng.uniform(-dims.half_length_m + margin_m, dims.half_length_m - margin_m),
                rng.uniform(-dims.half_width_m + margin_m, dims.half_width_m - margin_m),
                rng.uniform(-math.pi, math.pi),
            ]
        )

    def free_pose(
        self, rng: np.random.Generator, placed: Sequence[Mobile], margin_m: float = 0.5
    ) -> FloatArray:
        """A :meth:`random_pose` clear of the ``placed`` robots (by 0.3 m), posts and poles."""
        for _ in range(200):
            pose = self.random_pose(rng, margin_m)
            if not self.collides(pose[:2], placed, clearance=0.3):
                return pose
        raise RuntimeError("could not place a robot: the field is too crowded")

    def walk(
        self, robot: Mobile, command: FloatArray, dt_s: float, others: Sequence[Mobile]
    ) -> tuple[FloatArray, bool]:
        """Walk ``robot`` one control step: the walk engine's increment (3,) and whether the
        body was blocked.

        A blocked robot stays where it is while its walk engine (and so its odometry) believes
        it stepped: the slip a real Nao sees when it walks into an obstacle. It is told what it
        ran into (:meth:`obstruction`), so that a Nao may pivot away from it.
        """
        increment = robot.walk_step(command, dt_s)
        new_xy = compose(robot.pose, increment)[:2]
        contact = self.obstruction(new_xy, others, clearance=0.0)
        if contact is None:
            robot.commit_motion(increment)
        else:
            robot.commit_motion(None, contact, dt_s)
        robot.sync()
        return increment, contact is not None
