"""Kalman filter steps for a linear(ised) model: pure functions, no filter state.

Symbols, as in filterpy and Bar-Shalom, Li & Kirubarajan, *Estimation with Applications to
Tracking and Navigation*:

- ``x`` (n,): state mean; ``P`` (n, n): its covariance;
- ``F`` (n, n): state transition (for an EKF the Jacobian of the motion model at ``x``);
- ``Q`` (n, n): covariance of the process noise one prediction adds;
- ``z`` (m,): a measurement; ``z_hat`` (m,): the measurement predicted from ``x``;
- ``H`` (m, n): measurement matrix (for an EKF the Jacobian of the measurement model); when
  only some of its columns are nonzero it may be given as those columns, (m, k), with their
  state indices ``index`` (k,) (a sparse ``H``);
- ``R`` (m, m): measurement noise covariance;
- ``y`` (m,): innovation ``z - z_hat``;
- ``S`` (m, m): innovation covariance ``H P H^T + R``;
- ``K`` (n, m): Kalman gain ``P H^T S^-1``.

Units and frames are the caller's: each entry of ``x`` and ``z`` has its own, and the
covariances are in the products of those units.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from perception.geometry import FloatArray, wrap_angle
from perception.validation import check_covariance, is_symmetric


def predict(
    x: ArrayLike, P: ArrayLike, F: ArrayLike, Q: ArrayLike
) -> tuple[FloatArray, FloatArray]:
    """Linear prediction: ``x`` (n,) -> ``F x``, ``P`` (n, n) -> ``F P F^T + Q`` (symmetrised).

    An EKF predicts its mean with the nonlinear motion model instead and keeps only the ``P``.
    Every argument must be finite, else ValueError naming it; ``P`` and ``Q`` are trusted to be
    covariances (a definiteness test costs O(n^3)).
    """
    x, P, F, Q = (np.asarray(a, dtype=np.float64) for a in (x, P, F, Q))
    n = _state_size(x, P)
    _require_shape("F", F, (n, n))
    _require_shape("Q", Q, (n, n))
    _require_finite(x=x, P=P, F=F, Q=Q)
    P_new = F @ P @ F.T + Q
    return F @ x, 0.5 * (P_new + P_new.T)


def innovation_covariance(
    P: ArrayLike, H: ArrayLike, R: ArrayLike, index: ArrayLike | None = None
) -> FloatArray:
    """``S = H P H^T + R`` (m, m) for ``P`` (n, n), ``H`` (m, n) or sparse, and ``R`` (m, m).

    With ``index`` (k,), ``H`` (m, k) holds only the columns of the full ``H`` at those state
    indices (the others are zero), and only the (k, k) block of ``P`` enters. ``S`` is not
    symmetrised: it is exactly what :func:`joseph_update` gets when it computes ``S`` itself.
    """
    P, H, R = (np.asarray(a, dtype=np.float64) for a in (P, H, R))
    idx = _measurement_size(len(P), H, R, index)[1]
    block = P if idx is None else P[np.ix_(idx, idx)]
    S: FloatArray = H @ block @ H.T + R
    return S


def joseph_update(
    x: ArrayLike,
    P: ArrayLike,
    y: ArrayLike,
    H: ArrayLike,
    R: ArrayLike,
    index: ArrayLike | None = None,
    *,
    S: ArrayLike | None = None,
) -> tuple[FloatArray, FloatArray]:
    """Measurement update: the new ``x`` (n,) and ``P`` (n, n) after fusing innovation ``y``.

    ``x + K y`` and ``(I - K H) P (I - K H)^T + K R K^T`` (symmetrised) with the optimal gain
    ``K = P H^T S^-1``. ``H`` is (m, n), or (m, k) with the state indices ``index`` (k,) of its
    nonzero columns, which keeps the update O(n^2 m) (as :func:`innovation_covariance`). ``S``
    (m, m): the innovation covariance when already computed (e.g. to gate ``y``), else computed
    here. ``y`` must already be wrapped where it holds angles (:func:`wrapped_residual`).

    ``x``, ``y`` and ``H`` must be finite, ``R`` a covariance (symmetric positive
    semidefinite) and ``S`` one that is positive definite, else ValueError naming them; ``P``
    is trusted to be one (its shape and finiteness are checked: a definiteness test costs
    O(n^3)).
    """
    x, P, y, H, R = (np.asarray(a, dtype=np.float64) for a in (x, P, y, H, R))
    _state_size(x, P)
    m, idx = _measurement_size(len(x), H, R, index)
    _require_shape("y", y, (m,))
    _require_finite(x=x, P=P, y=y, H=H)
    if not is_symmetric(P):  # O(n^2): a cheap part of the trust
        raise ValueError(f"P must be symmetric, got {P.tolist()}")
    R = check_covariance(R, "R", m, singular_ok=True)
    S = check_covariance(innovation_covariance(P, H, R, idx) if S is None else S, "S", m)

    P_Ht = _times_h_transpose(P, H, idx)
    K = np.linalg.solve(S, P_Ht.T).T  # S and P are symmetric, so this is P H^T S^-1
    # Joseph form: a sum of PSD terms, so P stays PSD under rounding (and for any K) where the
    # short form (I - K H) P can lose it. (I - K H) P (I - K H)^T expands to A - A H^T K^T with
    # A = (I - K H) P = P - K (P H^T)^T.
    IKH_P = P - K @ P_Ht.T
    joseph = IKH_P - _times_h_transpose(IKH_P, H, idx) @ K.T + K @ R @ K.T
    return x + K @ y, 0.5 * (joseph + joseph.T)


def wrapped_residual(z: ArrayLike, z_hat: ArrayLike, angles: Sequence[int]) -> FloatArray:
    """Innovation ``z - z_hat`` (..., m) with its entries at ``angles`` wrapped to [-pi, pi).

    ``z`` and ``z_hat`` broadcast over leading axes; ``angles`` are indices into the last
    axis of the entries that are angles (rad), such as a bearing, whose plain difference can
    be off by 2 pi across ±pi. Raises ValueError naming ``z`` or ``z_hat`` if it holds a NaN
    or an infinity.
    """
    y = np.subtract(z, z_hat, dtype=np.float64)
    if not np.isfinite(y).all():
        _require_finite(z=np.asarray(z, dtype=np.float64), z_hat=np.asarray(z_hat, np.float64))
    for i in angles:
        y[..., i] = wrap_angle(y[..., i])
    return y


def _times_h_transpose(A: FloatArray, H: FloatArray, idx: NDArray[np.intp] | None) -> FloatArray:
    """``A H^T`` (n, m) for ``A`` (n, n): only the columns of ``A`` that ``H`` uses enter."""
    product: FloatArray = (A if idx is None else A[:, idx]) @ H.T
    return product


def _state_size(x: FloatArray, P: FloatArray) -> int:
    """n, after checking ``x`` is (n,) and ``P`` (n, n)."""
    if x.ndim != 1:
        raise ValueError(f"x must have shape (n,), got shape {x.shape}")
    n = len(x)
    _require_shape("P", P, (n, n))
    return n


def _measurement_size(
    n: int, H: FloatArray, R: FloatArray, index: ArrayLike | None
) -> tuple[int, NDArray[np.intp] | None]:
    """m, and ``index`` as an int array, after checking them against ``H``, ``R`` and n."""
    if H.ndim != 2:
        raise ValueError(f"H must be 2-D (m, n) or (m, k), got shape {H.shape}")
    m = len(H)
    _require_shape("R", R, (m, m))
    if index is None:
        _require_shape("H", H, (m, n))
        return m, None
    idx = np.asarray(index)
    if idx.dtype.kind not in "iu" or idx.shape != (H.shape[1],):
        raise ValueError(
            f"index must be {H.shape[1]} ints (one per column of H), got {idx.dtype} {idx.shape}"
        )
    values = idx.tolist()  # plain ints: much faster than numpy for the few indices of a block
    if values and (min(values) < 0 or max(values) >= n or len(set(values)) < len(values)):
        raise ValueError(f"index must hold distinct state indices in [0, {n}), got {idx}")
    return m, idx.astype(np.intp, copy=False)


def _require_finite(**arrays: FloatArray) -> None:
    """ValueError naming the first of ``arrays`` that holds a NaN or an infinity."""
    for name, array in arrays.items():
        if not np.isfinite(array).all():
            raise ValueError(f"{name} must be finite, got {array.tolist()}")


def _require_shape(name: str, array: FloatArray, shape: tuple[int, ...]) -> None:
    """Raise ValueError naming ``name`` unless ``array`` has ``shape``."""
    if array.shape != shape:
        raise ValueError(f"{name} must have shape {shape}, got shape {array.shape}")
