"""Estimation metrics: position errors, NEES, landmark-map and circle-map errors (SI units, field
frame)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import linear_sum_assignment

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


@dataclass(frozen=True)
class CircleMatch:
    """Mapped circles matched one to one to the true ones (:func:`match_circles`).

    ``mapped_index`` (K,): the mapped circle matched to each true circle, -1 when missed;
    ``centre_error_m`` and ``radius_error_m`` (K,): its errors (m), NaN when missed;
    ``spurious`` (M,) bool: the mapped circles matched to no true circle.
    """

    mapped_index: NDArray[np.intp]
    centre_error_m: FloatArray
    radius_error_m: FloatArray
    spurious: NDArray[np.bool_]

    @property
    def missed(self) -> NDArray[np.bool_]:
        """(K,) bool: the true circles without a mapped one."""
        return self.mapped_index < 0


def match_circles(mapped: ArrayLike, truth: ArrayLike, gate_m: float) -> CircleMatch:
    """Match ``mapped`` (M, 3) circles ``(x, y, R)`` (m) to the ``truth`` (K, 3) one to one,
    minimising the sum of centre distances (Hungarian assignment), each pair closer than
    ``gate_m`` (m)."""
    m = np.asarray(mapped, dtype=np.float64).reshape(-1, 3)
    t = np.asarray(truth, dtype=np.float64).reshape(-1, 3)
    distances = np.hypot(*(t[:, None, :2] - m[None, :, :2]).transpose(2, 0, 1))
    index = np.full(len(t), -1, dtype=np.intp)
    if len(m) and len(t):
        rows, cols = linear_sum_assignment(np.where(distances < gate_m, distances, 1e9))
        close = distances[rows, cols] < gate_m
        index[rows[close]] = cols[close]
    found = index >= 0
    centre = np.full(len(t), np.nan)
    radius = np.full(len(t), np.nan)
    centre[found] = distances[found, index[found]]
    radius[found] = np.abs(m[index[found], 2] - t[found, 2])
    spurious = np.ones(len(m), dtype=bool)
    spurious[index[found]] = False
    return CircleMatch(index, centre, radius, spurious)
