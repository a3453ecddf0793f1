"""The ray-casting interface the range sensors use, so that they need no physics engine.

The PyBullet world provides it behind ``rayTestBatch``; tests provide closed-form scenes.
"""

from __future__ import annotations

import math
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from perception.geometry import FloatArray


class RayCaster(Protocol):
    """Casts a batch of straight rays and reports the first thing each one hits."""

    def __call__(
        self, starts: FloatArray, ends: FloatArray
    ) -> tuple[FloatArray, NDArray[np.int64]]:
        """Cast rays from (N, 3) ``starts`` to (N, 3) ``ends`` (field frame, m).

        Returns the (N,) hit fraction in [0, 1] along each ray (1.0 = no hit) and the (N,) id of
        the body hit (-1 = none).
        """
        ...


class RayFan:
    """Horizontal rays from a sensor on a robot, laid out once in the robot frame.

    The sensor sits ``mount_x_m`` ahead of the robot origin at ``mount_height_m``; ``angles``
    (N,) are the ray directions in the robot frame (rad, 0 = forward, + = left) and every ray is
    ``length_m`` long.
    """

    def __init__(
        self, *, mount_x_m: float, mount_height_m: float, angles: FloatArray, length_m: float
    ) -> None:
        angles = np.asarray(angles, dtype=np.float64)
        local_ends = np.column_stack(
            [mount_x_m + length_m * np.cos(angles), length_m * np.sin(angles)]
        )
        # (N + 1,) robot-frame x and y of the sensor, then of each ray's end
        local = np.vstack([[[mount_x_m, 0.0]], local_ends])
        self._local_x, self._local_y = local[:, 0].copy(), local[:, 1].copy()
        # (N, 3) field-frame rays' template: x and y filled in per pose, z the mount's height
        self._template = np.full((len(angles), 3), float(mount_height_m))

    def rays(self, robot_pose: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """The rays as (N, 3) field-frame starts and ends (m) from the robot at ``robot_pose``,
        the (3,) field pose ``(x, y, theta)``."""
        pose = np.asarray(robot_pose, dtype=np.float64)
        if pose.shape != (3,) or not all(math.isfinite(v) for v in pose.tolist()):
            raise ValueError(f"robot_pose must be a finite (3,) pose (x, y, theta), got {pose!r}")
        x, y, theta = pose  # the sums of :func:`perception.geometry.transform_points`
        c, s = np.cos(theta), np.sin(theta)
        lx, ly = self._local_x, self._local_y
        field_x, field_y = x + c * lx - s * ly, y + s * lx + c * ly
        starts, ends = self._template.copy(), self._template.copy()
        starts[:, 0], starts[:, 1] = field_x[0], field_y[0]
        ends[:, 0], ends[:, 1] = field_x[1:], field_y[1:]
        return starts, ends


def cast(
    ray_caster: RayCaster, starts: FloatArray, ends: FloatArray, ignore_body: int
) -> tuple[FloatArray, NDArray[np.int64]]:
    """Cast rays; return their hit distances (N,) (m from the start) and hit body ids (N,).

    A ray counts as a hit when it stops short of its end on a body other than ``ignore_body``
    (the robot carrying the sensor); the others get distance NaN and body -1.
    """
    fractions, bodies = ray_caster(starts, ends)
    fractions = np.asarray(fractions, dtype=np.float64)
    bodies = np.asarray(bodies, dtype=np.int64)
    n = len(starts)
    if fractions.shape != (n,) or bodies.shape != (n,):
        raise ValueError(
            f"ray_caster must return two arrays of shape ({n},), "
            f"got {fractions.shape} and {bodies.shape}"
        )
    hit = (fractions < 1.0) & (bodies >= 0) & (bodies != ignore_body)
    lengths = np.linalg.norm(ends - starts, axis=1)
    return np.where(hit, fractions * lengths, np.nan), np.where(hit, bodies, -1)
