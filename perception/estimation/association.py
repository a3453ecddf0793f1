"""Global nearest-neighbour (GNN) data association of measurements to tracks.

Symbols as in :mod:`perception.estimation.kalman`: per track ``z_hat`` (m,) its predicted
measurement and ``S`` (m, m) its innovation covariance; ``z`` (m,) a measurement. The cost of
pairing track t with measurement j is the squared Mahalanobis distance (unitless) of
``y = z_j - z_hat_t`` under ``S_t``. GNN takes the one-to-one pairing of all tracks and
measurements at once that minimises the summed cost (an optimal assignment), rather than
letting each track take its nearest measurement in turn, which can leave a later track only a
distant one.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from perception.estimation.gating import mahalanobis_squared
from perception.geometry import FloatArray
from perception.validation import check_positive

IntArray = NDArray[np.intp]
Residual = Callable[[FloatArray, FloatArray], FloatArray]
"""``residual(z, z_hat)`` -> ``y``, broadcasting over leading axes: e.g. ``np.subtract``, or
:func:`perception.estimation.kalman.wrapped_residual` with its angle indices bound."""


@dataclass(frozen=True)
class Association:
    """The result of :func:`global_nearest_neighbour` for T tracks and M measurements.

    ``matches`` (K, 2): (track, measurement) index pairs, by increasing track;
    ``unmatched_tracks`` (T - K,) and ``unmatched_measurements`` (M - K,): increasing indices.
    """

    matches: IntArray
    unmatched_tracks: IntArray
    unmatched_measurements: IntArray


def global_nearest_neighbour(cost: ArrayLike, threshold: float) -> Association:
    """Associate tracks (rows of ``cost``) with measurements (columns) one to one.

    ``cost`` (T, M): squared Mahalanobis distances, >= 0 (+inf allowed: never paired), e.g.
    from :func:`mahalanobis_cost_matrix`. A pair is in the gate when its cost is
    <= ``threshold`` (>= 0, e.g. :func:`perception.estimation.gating.chi2_threshold`); pairs
    outside it are never matched. Among the pairings of in-gate pairs the result has the most
    pairs, and among those the least total cost (``scipy.optimize.linear_sum_assignment``).
    Either T or M may be 0.
    """
    check_positive("", "threshold", threshold, allow_zero=True)
    costs = np.asarray(cost, dtype=np.float64)
    if costs.ndim != 2:
        raise ValueError(f"cost must be a (tracks, measurements) matrix, got shape {costs.shape}")
    if np.isnan(costs).any() or (costs < 0).any():
        raise ValueError(f"cost must hold squared distances >= 0 (not NaN), got {costs}")
    in_gate = costs <= threshold
    tracks = measurements = np.empty(0, dtype=np.intp)
    if in_gate.any():
        from scipy.optimize import linear_sum_assignment  # ~0.4 s to import: here only

        # Out-of-gate pairs cost more than all in-gate pairs together, so the assignment takes
        # as few of them as it can (the most in-gate pairs); they are dropped afterwards.
        # Finite, as linear_sum_assignment needs a feasible full assignment.
        outside = 2.0 * float(costs[in_gate].sum()) + 1.0
        rows, cols = linear_sum_assignment(np.where(in_gate, costs, outside))
        kept = in_gate[rows, cols]
        tracks, measurements = rows[kept].astype(np.intp), cols[kept].astype(np.intp)
    n_tracks, n_measurements = costs.shape
    return Association(
        matches=np.column_stack([tracks, measurements]),
        unmatched_tracks=np.setdiff1d(np.arange(n_tracks, dtype=np.intp), tracks),
        unmatched_measurements=np.setdiff1d(np.arange(n_measurements, dtype=np.intp), measurements),
    )


def mahalanobis_cost_matrix(
    z_hat: ArrayLike, S: ArrayLike, z: ArrayLike, residual: Residual = np.subtract
) -> FloatArray:
    """Costs (T, M): ``y^T S_t^-1 y`` with ``y = residual(z_j, z_hat_t)``.

    ``z_hat`` (T, m) and ``S`` (T, m, m): predicted measurements and innovation covariances of
    T tracks; ``z`` (M, m): M measurements. ``residual`` wraps angles where ``z`` holds any
    (:data:`Residual`). T or M may be 0.
    """
    Z_hat, S_all, Z = (np.asarray(a, dtype=np.float64) for a in (z_hat, S, z))
    if Z.ndim != 2:
        raise ValueError(f"z must have shape (M, m), got shape {Z.shape}")
    n_tracks, m = len(Z_hat), Z.shape[1]
    if n_tracks == 0 and Z_hat.size == 0 and S_all.size == 0:  # no tracks, given as [] too
        Z_hat, S_all = Z_hat.reshape(0, m), S_all.reshape(0, m, m)
    if Z_hat.shape != (n_tracks, m) or S_all.shape != (n_tracks, m, m):
        raise ValueError(
            f"z_hat must have shape (T, {m}) and S (T, {m}, {m}) (m from z), "
            f"got shapes {Z_hat.shape} and {S_all.shape}"
        )
    cost = np.empty((n_tracks, len(Z)))
    for t in range(n_tracks):
        cost[t] = mahalanobis_squared(residual(Z, Z_hat[t]), S_all[t])
    return cost
