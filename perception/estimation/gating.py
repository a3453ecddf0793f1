"""Chi-square validation gates on innovations.

Symbols as in :mod:`perception.estimation.kalman`: ``y`` (m,) an innovation, ``S`` (m, m) its
covariance. If ``y`` is drawn from N(0, S), its squared Mahalanobis distance ``y^T S^-1 y`` is
chi-square distributed with m degrees of freedom, so a gate at the chi-square quantile of
probability p lets through a fraction p of correct measurements. All distances and thresholds
are unitless.
"""

from __future__ import annotations

import functools

import numpy as np
from numpy.typing import ArrayLike

from perception.geometry import FloatArray
from perception.validation import check_covariance, check_int, check_positive, check_probability


def chi2_threshold(probability: float, dof: int) -> float:
    """Gate threshold: the chi-square quantile of ``probability`` in (0, 1) with ``dof`` >= 1.

    For 2 dof this is ``-2 ln(1 - p)``; for 1 dof ``Phi^-1((1 + p) / 2)^2`` (a symmetric
    interval of a standard normal). Raises ValueError naming the bad argument.
    """
    check_probability("", "probability", probability)
    check_int("", "dof", dof, 1)
    return _chi2_quantile(float(probability), int(dof))


@functools.lru_cache(maxsize=256)
def _chi2_quantile(probability: float, dof: int) -> float:
    """:func:`chi2_threshold` of checked arguments, computed once per pair (filters that gate
    with a varying number of degrees of freedom ask for it every frame)."""
    from scipy.stats import chi2  # ~0.7 s to import: paid only by users of a chi-square gate

    return float(chi2.ppf(probability, dof))


def mahalanobis_squared(y: ArrayLike, S: ArrayLike) -> FloatArray:
    """``y^T S^-1 y`` for innovations ``y`` (..., m) sharing one covariance ``S`` (m, m).

    Returns shape ``y.shape[:-1]`` (0-d for a single ``y``). ``S`` must be a covariance
    (symmetric positive definite) and ``y`` finite; errors name the argument.
    """
    y = np.asarray(y, dtype=np.float64)
    if y.ndim == 0:
        raise ValueError("y must have shape (..., m), got a scalar")
    m = y.shape[-1]
    S = check_covariance(S, "S", m)
    if not np.isfinite(y).all():
        raise ValueError(f"y must be finite, got {y}")
    Y = y.reshape(-1, m)
    d2: FloatArray = np.einsum("ij,ji->i", Y, np.linalg.solve(S, Y.T)).reshape(y.shape[:-1])
    return d2


def within_gate(y: ArrayLike, S: ArrayLike, threshold: float) -> bool:
    """Whether the innovation ``y`` (m,) with covariance ``S`` (m, m) passes the gate.

    It passes when ``y^T S^-1 y <= threshold`` (>= 0, e.g. from :func:`chi2_threshold`).
    """
    check_positive("", "threshold", threshold, allow_zero=True)
    if np.ndim(y) != 1:
        raise ValueError(f"y must have shape (m,), got shape {np.shape(y)}")
    return bool(mahalanobis_squared(y, S) <= threshold)
