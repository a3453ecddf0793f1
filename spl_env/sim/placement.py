"""Kinematic placement on the field: free poses, collisions, and one walking step with them.

Robots are discs of ``body_radius_m`` in plan view; posts and poles are ``(x, y, radius)``
obstacles; the carpet's edge bounds everything.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from perception.geometry import FloatArray, transform_points
from spl_env.field import FieldDimensions
from spl_env.robots.nao import NaoRobot


class Placement:
    """Collision tests and free-pose sampling among ``obstacles`` (K, 3) on a field of
    ``dimensions``, for robots of radius ``robot_radius_m``."""

    def __init__(
        self, dimensions: FieldDimensions, obstacles: FloatArray, robot_radius_m: float
    ) -> None:
        self.dimensions = dimensions
        self.obstacles = np.asarray(obstacles, dtype=np.float64).reshape(-1, 3)
        self.robot_radius_m = robot_radius_m

    def collides(self, xy: FloatArray, robots: Sequence[NaoRobot], clearance: float) -> bool:
        """Whether a robot at ``xy`` (2,) overlaps one of ``robots``, a post or a pole, or leaves
        the carpet, with ``clearance`` (m) to spare."""
        r = self.robot_radius_m
        carpet_l, carpet_w = self.dimensions.carpet_size_m
        if abs(xy[0]) > carpet_l / 2 - r or abs(xy[1]) > carpet_w / 2 - r:
            return True
        for robot in robots:
            if math.hypot(*(robot.pose[:2] - xy)) < 2 * r + clearance:
                return True
        d = np.hypot(self.obstacles[:, 0] - xy[0], self.obstacles[:, 1] - xy[1])
        return bool(np.any(d < r + self.obstacles[:, 2] + clearance))

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
        self, rng: np.random.Generator, placed: Sequence[NaoRobot], margin_m: float = 0.5
    ) -> FloatArray:
        """A :meth:`random_pose` clear of the ``placed`` robots (by 0.3 m), posts and poles."""
        for _ in range(200):
            pose = self.random_pose(rng, margin_m)
            if not self.collides(pose[:2], placed, clearance=0.3):
                return pose
        raise RuntimeError("could not place a robot: the field is too crowded")

    def walk(
        self, robot: NaoRobot, command: FloatArray, dt_s: float, others: Sequence[NaoRobot]
    ) -> tuple[FloatArray, bool]:
        """Walk ``robot`` one control step: the walk engine's increment (3,) and whether the
        body was blocked.

        A blocked robot stays where it is while its walk engine (and so its odometry) believes
        it stepped: the slip a real Nao sees when it walks into an obstacle.
        """
        increment = robot.walk_step(command, dt_s)
        new_xy = transform_points(robot.pose, increment[None, :2])[0]
        blocked = self.collides(new_xy, others, clearance=0.0)
        robot.commit_motion(None if blocked else increment)
        robot.sync()
        return increment, blocked
