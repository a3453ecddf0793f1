"""Estimation metrics: position errors, NEES and landmark-map errors (SI units, field frame)."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from perception.geometry import FloatArray, range_bearing, wrap_angle


def position_error(true_pose: ArrayLike, estimate: ArrayLike) -> float:
    """Euclidean distance (m) between the xy of two poses (3,) or points (2,)."""
    t = np.asarray(true_pose, dtype=np.float64)
    e = np.asarray(estimate, dtype=np.float64)
    return float(np.hypot(t[0] - e[0], t[1] - e[1]))


def pose_nees(true_pose: ArrayLike, estimate: ArrayLike, cov: ArrayLike) -> float:
    """Normalised estimation error squared of a pose (3,) with covariance (3, 3).

    For a consistent filter its expectation is 3 (chi-square with 3 dof); the heading residual
    is wrapped so that errors near ±pi count as small.
    """
    e = np.asarray(true_pose, dtype=np.float64) - np.asarray(estimate, dtype=np.float64)
    e[2] = float(wrap_angle(e[2]))
    return float(e @ np.linalg.solve(np.asarray(cov, dtype=np.float64), e))


def landmark_range_bearing(
    pose: ArrayLike, ids: ArrayLike, landmarks: ArrayLike
) -> dict[int, FloatArray]:
    """Range (m) and bearing (rad, robot frame) (2,) from ``pose`` (3,) to each of the (L, 2)
    ``landmarks``, keyed by their ids (L,): the truth a sighting is scored against."""
    rb = range_bearing(pose, landmarks)
    return {int(i): rb[k] for k, i in enumerate(np.asarray(ids))}


def landmark_errors(
    true_ids: ArrayLike, true_xy: ArrayLike, est_ids: ArrayLike, est_xy: ArrayLike
) -> FloatArray:
    """Errors (m) of the estimated landmarks (K,) against the true ones with the same ids."""
    truth = {
        int(i): np.asarray(xy, dtype=np.float64)
        for i, xy in zip(np.asarray(true_ids), np.asarray(true_xy), strict=True)
    }
    return np.array(
        [
            float(np.hypot(*(truth[int(i)] - np.asarray(xy))))
            for i, xy in zip(np.asarray(est_ids), np.asarray(est_xy), strict=True)
            if int(i) in truth
        ]
    )
