"""Scripted kinematic walks: ground-truth pose sequences for sensor models and benchmarks.

Poses are (x, y, theta) in the field frame (m, rad); see :mod:`perception.geometry`.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
from numpy.typing import ArrayLike

from perception.geometry import FloatArray, relative, transform_points, wrap_angle

# Corners of a unit square walked anticlockwise from the origin along +x.
_UNIT_CORNERS = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])


def _check_positive(**values: float) -> None:
    for name, value in values.items():
        if not (math.isfinite(value) and value > 0):
            raise ValueError(f"{name} must be finite and > 0, got {value}")


def square_walk(
    *,
    side_m: float,
    speed_mps: float,
    turn_rate_rps: float,
    dt_s: float,
    start_pose: ArrayLike = (0.0, 0.0, 0.0),
    laps: float = 1.0,
) -> FloatArray:
    """True poses (N, 3) of a robot walking a square anticlockwise, sampled every ``dt_s``.

    The robot walks ``side_m`` straight ahead at ``speed_mps``, turns 90° left in place at
    ``turn_rate_rps`` (rad/s), and repeats, starting at ``start_pose`` (a corner, facing along
    the first side). One lap lasts ``4 * (side_m / speed_mps + (pi / 2) / turn_rate_rps)`` s.
    Samples are at ``t = 0, dt_s, 2 dt_s, ...`` plus one at the exact end time ``laps`` laps
    later (so the last interval may be shorter than ``dt_s``); whole laps end at the start pose.
    """
    _check_positive(
        side_m=side_m, speed_mps=speed_mps, turn_rate_rps=turn_rate_rps, dt_s=dt_s, laps=laps
    )
    start = np.asarray(start_pose, dtype=np.float64)
    if start.shape != (3,) or not np.all(np.isfinite(start)):
        raise ValueError(f"start_pose must be a finite (3,) pose, got {start!r}")
    walk_s = side_m / speed_mps
    side_period_s = walk_s + 0.5 * np.pi / turn_rate_rps
    duration_s = 4.0 * laps * side_period_s
    times = np.arange(0.0, duration_s, dt_s)
    times = np.append(times[duration_s - times > 1e-9 * duration_s], duration_s)

    sides_done = np.floor(times / side_period_s)
    in_side_s = times - sides_done * side_period_s
    corner = sides_done.astype(np.int64) % 4
    heading = 0.5 * np.pi * corner
    walked_m = speed_mps * np.minimum(in_side_s, walk_s)
    turned = turn_rate_rps * np.maximum(in_side_s - walk_s, 0.0)
    local_xy = side_m * _UNIT_CORNERS[corner] + walked_m[:, None] * np.column_stack(
        [np.cos(heading), np.sin(heading)]
    )
    xy = transform_points(start, local_xy)
    theta = wrap_angle(start[2] + heading + turned)
    return np.column_stack([xy, theta])


def increments(poses: ArrayLike) -> FloatArray:
    """Robot-frame motion (N-1, 3) ``(dx, dy, dtheta)`` between consecutive (N, 3) poses.

    Row ``k`` is pose ``k + 1`` seen from pose ``k``: what a perfect odometry would report.
    """
    p = np.asarray(poses, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 3 or len(p) < 2:
        raise ValueError(f"poses must have shape (N >= 2, 3), got {p.shape}")
    return np.array([relative(a, b) for a, b in itertools.pairwise(p)])
