"""The circle EKF of seed 001: a circle's polar parameters refined point by point (§3.3, §4.6).

The points of one scan segment, rays ``phi_i`` (rad, counter-clockwise from the sensor's x
axis) with measured ranges ``r_i`` (m), are fused one at a time, in the order given, into the
circle ``(rho, theta, R)`` of :mod:`perception.circles.model` (sensor frame), starting from an
initial estimate (e.g. a fit of :mod:`perception.circles.fits`). The circle does not move
(``F = I``, no process noise), so there is no prediction step: each point is an update.

Symbols, as in :mod:`perception.estimation.kalman` (filterpy):

- ``x`` (n,): the state, ``(rho, theta, R)`` (m, rad, m) for Algorithm 1 or
  ``(r, rho, theta, R)`` (m, m, rad, m) for Algorithm 4; ``P`` (n, n): its covariance;
  ``P0``: its initial value;
- ``z`` (m): a measured range ``r_i``; ``h(x)`` (m): the range predicted at ``phi_i``;
- ``H`` (n,): the Jacobian of ``h`` (the measurement is scalar, so ``H`` is one row);
- ``sigma`` (m): the standard deviation of a range, ``sigma^2`` its variance (filterpy's ``R``,
  here ``range_sigma_m``: the radius already owns the letter);
- ``y`` (m): the innovation ``z - h(x)``; ``S`` (m^2): ``H P H^T + sigma^2``;
- ``K`` (n,): the gain ``P H^T / S``.

The two variants of the seed (``CircleEkfConfig.variant``):

- ``"tikhonov"``, Algorithm 1 (§3.3, after Muñoz Bañón 2016): 3 states, ``h`` eq. 3.2 and
  ``H`` from :func:`~perception.circles.model.polar_jacobian` (the seed's eq. 3.6 has typos,
  see that module); the mean moves by the ordinary gain, the covariance takes a Tikhonov term::

      P <- (P^-1 + (H^T H + lambda I) / sigma^2)^-1

  The seed writes ``(P^-1 + H^T H + lambda I)^-1`` for ``P`` normalised by ``sigma^2``
  (``P / sigma^2``, its "error equal to 1"); in the units of ``x`` that is the update above, so
  ``lambda`` is unitless, added to the normalised information ``sigma^2 P^-1``. With
  ``lambda = 0`` it is the exact Kalman update ``(I - K H) P`` in information form; it is
  computed as the Joseph update below followed by the ``lambda`` term (eigenvalues ``p`` of
  ``P`` to ``p / (1 + lambda p / sigma^2)``), the same matrix, which stays positive definite
  under rounding where inverting ``P`` does not. ``lambda > 0`` adds, at every point, information
  that no measurement brought: it damps the steps along directions the points barely constrain
  (the seed's "ill-conditioned regression") and makes ``P`` smaller than the error it
  describes. The seed gives no value: the default is 0. The seed's innovation covariance
  ``S = 1 + H P H^T + R`` counts the measurement variance twice (the normalised "1" and
  ``R``); here ``S = H P H^T + sigma^2``.
- ``"joseph"``, Algorithm 4 (§4.6, the seed's final design): 4 states ``(r, rho, theta, R)``,
  ``H = (1, dr/drho, dr/dtheta, dr/dR)`` (eq. 4.12), ``P0 = I``, ``sigma = 0.02`` m and the
  Joseph update ``(I - K H) P (I - K H)^T + K sigma^2 K^T``
  (:func:`~perception.estimation.kalman.joseph_update`; the seed puts the transpose on ``H``
  alone and drops ``K sigma^2 K^T``, without which ``P`` is too small by exactly that term).
  The seed calls ``r`` "the distance with the detected point at each iteration", but under its
  ``F = I`` no state can follow a range that changes with every ray, and the only measurement
  model whose Jacobian is ``(1, eq. 3.6)`` is ``h(x) = r + r(phi; rho, theta, R)``. So ``r`` is
  here a range offset (m) shared by the segment's points (a bias of the laser, a surface in
  front of the circle): prior mean 0, prior standard deviation ``initial_offset_std_m`` (1 m,
  the seed's ``P0 = I``). On a short arc it is nearly confounded with ``rho`` and ``R`` (to
  second order in ``phi - theta`` an arc only fixes ``r + rho - R`` and its curvature), so
  this variant's ``rho`` and ``R`` are far less certain than Algorithm 1's; on the 7 points of
  a circle 4 m away it cannot tell the circle from others that fit them as well.

Linearisation (``CircleEkfConfig.linearisation``), over up to ``max_passes`` passes, each
starting from the previous pass's estimate with ``P`` reset to ``P0`` (fusing the same points
again into the same ``P`` would count their information twice):

- ``"point"``, the seed's EKF: each point's ``h`` and ``H`` are taken at the running estimate.
  With the seed's ``P0 = I``, far looser than ``sigma^2``, the first two or three points (arc
  neighbours) decide the estimate alone and can throw it far off; its ``P`` is then much too
  small (tests/perception/test_circle_ekf.py measures it).
- ``"pass"``: all points of a pass are linearised at the estimate the pass starts from,
  ``h(x) ~ h(x_pass) + H (x - x_pass)``, so a pass is one Gauss-Newton step damped by ``P0^-1``
  (Levenberg-Marquardt with a fixed damping matrix, Tikhonov's regularisation again). Passes
  converge to the least-squares circle, and ``P`` to its covariance with ``P0`` added in as
  information once more: negligible for ``P0 = I``, not for a ``P0`` as tight as the data.

Details the seed leaves open, decided here:

- A ray that misses the estimate it is linearised at (eq. 3.2 has no real root, or the ray is
  at or past a tangent, where ``H`` is infinite) is skipped and counted in ``n_missed``: its
  range is not fused, so nothing NaN reaches ``x`` or ``P`` (the seed kept the real part of the
  complex ranges, §3.3.2, which fuses ranges of another curve). With ``"point"`` linearisation,
  an update that would leave no valid circle (``0 < R < rho``) is refused the same way and
  counted in ``n_rejected``; with ``"pass"`` only the end of a pass must be one (else the run
  stops, ``"diverged"``, keeping the previous pass).
- ``P`` is symmetrised and checked (symmetric positive definite) after every update.
- The running MSE (eq. 2.7; Algorithm 1's last line reads as a sum) is the mean of the squared
  innovations ``y_i^2`` (m^2) of the points fused so far in the current pass.
- Stop rules (§3.3.1): with ``mse_rise_limit = k``, a pass stops when the running MSE has risen
  at ``k`` consecutive points, the seed's sign that the points have left the segment (outliers,
  a missed break-point): those ``k`` points are undone and no further pass runs. Passes stop
  early when a pass moved the circle less than ``state_tol_m`` (the larger of the centre's
  displacement and the radius' change, m) or changed the MSE less than ``mse_tol_m2``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from perception.circles.model import BRANCHES, Branch, PolarCircle, polar_jacobian, polar_range
from perception.estimation.kalman import joseph_update
from perception.geometry import FloatArray, wrap_angle
from perception.validation import (
    InvalidTypeError,
    check_choice,
    check_covariance,
    check_finite,
    check_int,
    check_positive,
    finite_vector,
)

Variant = Literal["tikhonov", "joseph"]
VARIANTS: tuple[Variant, ...] = ("tikhonov", "joseph")
Linearisation = Literal["point", "pass"]
LINEARISATIONS: tuple[Linearisation, ...] = ("point", "pass")
StopReason = Literal[
    "max_passes", "state_converged", "mse_converged", "mse_rising", "no_update", "diverged"
]


@dataclass(frozen=True, kw_only=True)
class CircleEkfConfig:
    """Model, prior and stop rules of :func:`estimate_circle` (module docstring for the maths).

    - ``variant``: ``"tikhonov"`` (Algorithm 1, 3 states) or ``"joseph"`` (Algorithm 4,
      4 states with the range offset ``r``).
    - ``branch``: the side of the circle the ranges lie on, ``"convex"`` (the near side the
      laser sees, the seed's minus sign) or ``"concave"``.
    - ``range_sigma_m`` (m, > 0): standard deviation of a measured range (seed: 0.02 m).
    - ``initial_std`` (3 floats > 0): prior standard deviations of ``(rho, theta, R)`` (m, rad,
      m); ``P0`` is diagonal (seed: identity, the parameters taken as uncorrelated).
    - ``initial_offset_std_m`` (m, > 0): prior standard deviation of Algorithm 4's range offset
      ``r`` (seed: 1); unused by Algorithm 1.
    - ``tikhonov_lambda`` (>= 0, unitless: it is added to the normalised information
      ``sigma^2 P^-1``): Algorithm 1's regularisation; unused by Algorithm 4.
    - ``linearisation``: ``"point"`` (the seed's EKF: at the running estimate) or ``"pass"``
      (at each pass's start: Gauss-Newton passes).
    - ``max_passes`` (>= 1): passes over the points at most.
    - ``state_tol_m`` (m, > 0, or None to disable): stop after a pass that moved the centre and
      changed the radius by less than this.
    - ``mse_tol_m2`` (m^2, > 0, or None to disable): stop after a pass whose MSE differs from
      the previous pass's by less than this.
    - ``mse_rise_limit`` (>= 1, or None to disable): stop when the running MSE has risen at
      this many consecutive points, undoing them.
    """

    variant: Variant = "joseph"
    branch: Branch = "convex"
    range_sigma_m: float = 0.02  # m: std of one range (seed 001 §3.2, §4.6.1)
    initial_std: tuple[float, float, float] = (1.0, 1.0, 1.0)  # (m, rad, m): P0 = identity
    initial_offset_std_m: float = 1.0  # m: std of Algorithm 4's range offset r (P0 = identity)
    tikhonov_lambda: float = 0.0  # unitless; the seed gives no value, 0 = exact Kalman update
    linearisation: Linearisation = "point"  # the seed's EKF
    max_passes: int = 1  # the seed makes one pass over a segment
    state_tol_m: float | None = None  # m: a pass moving the circle less than this ends the run
    mse_tol_m2: float | None = None  # m^2: a pass changing the MSE less than this ends the run
    mse_rise_limit: int | None = None  # consecutive rises of the running MSE that end the run

    def __post_init__(self) -> None:
        owner = "CircleEkfConfig"
        check_choice(owner, "variant", self.variant, VARIANTS)
        check_choice(owner, "branch", self.branch, BRANCHES)
        check_positive(owner, "range_sigma_m", self.range_sigma_m)
        std = finite_vector(self.initial_std, f"{owner}.initial_std", 3)
        if not (std > 0.0).all():
            raise ValueError(f"{owner}.initial_std must be 3 numbers > 0, got {self.initial_std}")
        object.__setattr__(self, "initial_std", tuple(float(s) for s in std))
        check_positive(owner, "initial_offset_std_m", self.initial_offset_std_m)
        check_positive(owner, "tikhonov_lambda", self.tikhonov_lambda, allow_zero=True)
        check_choice(owner, "linearisation", self.linearisation, LINEARISATIONS)
        check_int(owner, "max_passes", self.max_passes, 1)
        if self.state_tol_m is not None:
            check_positive(owner, "state_tol_m", self.state_tol_m)
        if self.mse_tol_m2 is not None:
            check_positive(owner, "mse_tol_m2", self.mse_tol_m2)
        check_int(owner, "mse_rise_limit", self.mse_rise_limit, 1, optional=True)

    @property
    def state_size(self) -> int:
        """n: 3 for Algorithm 1 ``(rho, theta, R)``, 4 for Algorithm 4 ``(r, rho, theta, R)``."""
        return 3 if self.variant == "tikhonov" else 4

    @property
    def initial_covariance(self) -> FloatArray:
        """``P0`` (n, n), diagonal: the variances of ``initial_offset_std_m`` (Algorithm 4
        only) and ``initial_std``."""
        std = (
            self.initial_std
            if self.variant == "tikhonov"
            else (self.initial_offset_std_m, *self.initial_std)
        )
        return np.diag(np.square(std))


@dataclass(frozen=True, kw_only=True, eq=False)
class CircleEkfResult:
    """What :func:`estimate_circle` found.

    - ``state`` (n,) and ``state_covariance`` (n, n): the final ``x`` and ``P`` (module
      docstring; for Algorithm 4 ``state[0]`` is the range offset ``r``, m);
    - ``mse`` (m^2): the running MSE at the end of the last pass, None when no point was fused;
    - ``mse_history`` (n_updates,): the running MSE after each fused point, all passes in order
      (it restarts with each pass);
    - ``passes``: the passes run (the last one included, even when it fused nothing);
    - ``n_updates``: points fused, all passes together (undone ones not counted);
    - ``n_missed``: points skipped because their ray missed the estimate, all passes;
    - ``n_rejected``: points skipped because their update left no valid circle, all passes;
    - ``stop_reason``: ``"max_passes"``, ``"state_converged"``, ``"mse_converged"``,
      ``"mse_rising"`` (module docstring), ``"no_update"`` (the last pass fused no point) or
      ``"diverged"`` (the last pass ended at no valid circle); in the last two cases the last
      pass is dropped, ``x`` and ``P`` are the previous pass's (``initial`` and ``P0`` after
      none).
    """

    state: FloatArray
    state_covariance: FloatArray
    mse: float | None
    mse_history: FloatArray
    passes: int
    n_updates: int
    n_missed: int
    n_rejected: int
    stop_reason: StopReason

    @property
    def circle(self) -> PolarCircle:
        """The estimated circle (sensor frame)."""
        rho, theta, R = self.state[-3:]
        return PolarCircle(float(rho), float(theta), float(R))

    @property
    def covariance(self) -> FloatArray:
        """The (3, 3) covariance of ``(rho, theta, R)`` (entries in m^2, m rad and rad^2)."""
        return self.state_covariance[-3:, -3:].copy()


def range_model(
    x: ArrayLike, phi: ArrayLike, branch: Branch = "convex"
) -> tuple[FloatArray, FloatArray]:
    """``h(x)`` (N,) (m) and its Jacobian ``H`` (N, n) at the N rays ``phi`` (rad, flattened).

    ``x`` is ``(rho, theta, R)`` (3,), where ``h`` is eq. 3.2, or ``(r, rho, theta, R)`` (4,),
    where ``h`` adds the range offset ``r`` and ``H = (1, eq. 3.6)`` (eq. 4.12). NaN in ``h``
    and non-finite rows of ``H`` where a ray misses the circle or grazes it.
    """
    x = np.asarray(x, dtype=np.float64)
    if x.shape not in ((3,), (4,)):
        raise ValueError(f"x must have shape (3,) or (4,), got shape {x.shape}")
    phi = np.ravel(phi)
    rho, theta, R = x[-3:]
    z_hat = polar_range(phi, rho, theta, R, branch)
    H = polar_jacobian(phi, rho, theta, R, branch)
    if len(x) == 3:
        return z_hat, H
    return x[0] + z_hat, np.column_stack([np.ones(len(phi)), H])


def circle_update(
    x: ArrayLike, P: ArrayLike, phi: float, z: float, config: CircleEkfConfig
) -> tuple[FloatArray, FloatArray, float] | None:
    """One EKF update of ``x`` (n,) and ``P`` (n, n) by the range ``z`` (m) at the ray ``phi``
    (rad), linearised at ``x``.

    Returns the new ``x`` (``theta`` wrapped to [-pi, pi)), the new ``P`` (symmetric positive
    definite, checked) and the innovation ``y = z - h(x)`` (m); None when the ray misses the
    circle of ``x`` (nothing is fused). ``n`` is ``config.state_size``. The new ``x`` may
    describe no valid circle (``R >= rho``, ``R <= 0``): :func:`estimate_circle` refuses such
    updates.
    """
    n = config.state_size
    x = finite_vector(x, "x", n)
    P = check_covariance(P, "P", n)
    check_finite("", "phi", phi)
    check_positive("", "z", z)
    z_hat, H = range_model(x, phi, config.branch)
    y = float(z - z_hat[0])
    if not (math.isfinite(y) and np.isfinite(H).all()):
        return None
    return *_fuse(x, P, y, H[0], config), y


def estimate_circle(
    phi: ArrayLike,
    r: ArrayLike,
    initial: PolarCircle,
    config: CircleEkfConfig | None = None,
) -> CircleEkfResult:
    """Refine ``initial`` with the points of one segment (module docstring for the rules).

    ``phi`` (N,) are the rays (rad, sensor frame) and ``r`` (N,) the measured ranges (m, > 0),
    fused in this order, N >= 1; ``config`` defaults to :class:`CircleEkfConfig` ().
    """
    config = CircleEkfConfig() if config is None else config
    if not isinstance(config, CircleEkfConfig):
        raise InvalidTypeError(f"config must be a CircleEkfConfig, got {type(config).__name__}")
    if not isinstance(initial, PolarCircle):
        raise InvalidTypeError(f"initial must be a PolarCircle, got {type(initial).__name__}")
    phi, r = _scan(phi, r)
    P0 = config.initial_covariance
    x = initial.vector if config.variant == "tikhonov" else np.concatenate([[0.0], initial.vector])
    P = P0
    mse: float | None = None
    history: list[float] = []
    counts = _Counts()
    reason: StopReason = "max_passes"
    passes = 0
    while passes < config.max_passes:
        passes += 1
        run = _run_pass(phi, r, x, P0, config, counts)
        if not run.mse_history:
            reason = "no_update"
            break
        if not _is_circle(run.x):
            reason = "diverged"
            break
        circle_change = _circle_change(x, run.x)
        mse_change = math.inf if mse is None else abs(run.mse_history[-1] - mse)
        x, P, mse = run.x, run.P, run.mse_history[-1]
        history.extend(run.mse_history)
        if run.rising:
            reason = "mse_rising"
            break
        if config.state_tol_m is not None and circle_change < config.state_tol_m:
            reason = "state_converged"
            break
        if config.mse_tol_m2 is not None and mse_change < config.mse_tol_m2:
            reason = "mse_converged"
            break
    return CircleEkfResult(
        state=x,
        state_covariance=P,
        mse=mse,
        mse_history=np.array(history),
        passes=passes,
        n_updates=len(history),
        n_missed=counts.missed,
        n_rejected=counts.rejected,
        stop_reason=reason,
    )


@dataclass
class _Counts:
    """Points skipped, all passes together."""

    missed: int = 0
    rejected: int = 0


@dataclass
class _Pass:
    """One pass's outcome: its last ``x`` and ``P``, the running MSE after each fused point and
    whether it ended on ``mse_rise_limit`` rises."""

    x: FloatArray
    P: FloatArray
    mse_history: list[float]
    rising: bool


def _run_pass(
    phi: FloatArray,
    r: FloatArray,
    x: FloatArray,
    P0: FloatArray,
    config: CircleEkfConfig,
    counts: _Counts,
) -> _Pass:
    """Fuse the points in order, starting from ``x`` and ``P0``, linearised as configured."""
    x_pass = x
    if config.linearisation == "pass":
        z_pass, H_pass = range_model(x_pass, phi, config.branch)
    P = P0
    history: list[float] = []
    sum_sq = 0.0
    rises = 0
    before_rises = (x, P, 0)  # x, P and the number of fused points before the current rises
    for i, (phi_i, z_i) in enumerate(zip(phi.tolist(), r.tolist(), strict=True)):
        if config.linearisation == "point":
            z_hat, H_hat = range_model(x, phi_i, config.branch)
            y, H = float(z_i - z_hat[0]), H_hat[0]
        else:  # h(x) ~ h(x_pass) + H (x - x_pass)
            H = H_pass[i]
            y = float(z_i - z_pass[i] - H @ _difference(x, x_pass))
        if not (math.isfinite(y) and np.isfinite(H).all()):
            counts.missed += 1
            continue
        x_new, P_new = _fuse(x, P, y, H, config)
        if config.linearisation == "point" and not _is_circle(x_new):
            counts.rejected += 1
            continue
        if rises == 0:
            before_rises = (x, P, len(history))
        x, P = x_new, P_new
        sum_sq += y * y
        history.append(sum_sq / (len(history) + 1))
        rises = rises + 1 if len(history) > 1 and history[-1] > history[-2] else 0
        if config.mse_rise_limit is not None and rises >= config.mse_rise_limit:
            x, P, fused = before_rises
            return _Pass(x, P, history[:fused], rising=True)
    return _Pass(x, P, history, rising=False)


def _fuse(
    x: FloatArray, P: FloatArray, y: float, H: FloatArray, config: CircleEkfConfig
) -> tuple[FloatArray, FloatArray]:
    """The updated ``x`` (n,) and ``P`` (n, n) after the innovation ``y`` (m) with the Jacobian
    ``H`` (n,), by the configured variant; ``P`` symmetrised and checked."""
    sigma2 = config.range_sigma_m**2
    x_new, P_new = joseph_update(x, P, [y], H[None, :], [[sigma2]])
    if config.variant == "tikhonov" and config.tikhonov_lambda > 0.0:
        # (P_new^-1 + lambda / sigma^2 I)^-1 through the eigenvalues p -> p / (1 + c p): positive
        # by construction, where inverting P_new loses definiteness once P0 >> sigma^2.
        c = config.tikhonov_lambda / sigma2
        p, V = np.linalg.eigh(P_new)
        P_new = (V * (p / (1.0 + c * p))) @ V.T
        P_new = 0.5 * (P_new + P_new.T)
    x_new[-2] = float(wrap_angle(x_new[-2]))
    return x_new, check_covariance(P_new, "P", len(x))


def _difference(x: FloatArray, x_ref: FloatArray) -> FloatArray:
    """``x - x_ref`` (n,) with the ``theta`` entry wrapped to [-pi, pi)."""
    d = x - x_ref
    d[-2] = float(wrap_angle(d[-2]))
    return d


def _is_circle(x: FloatArray) -> bool:
    """Whether the last three entries of ``x`` are a valid :class:`PolarCircle`."""
    rho, _, R = x[-3:].tolist()
    return bool(np.isfinite(x).all()) and 0.0 < R < rho


def _circle_change(x_old: FloatArray, x_new: FloatArray) -> float:
    """The larger of the centre's displacement and the radius' change (m) from ``x_old`` to
    ``x_new``."""
    rho0, theta0, R0 = x_old[-3:].tolist()
    rho1, theta1, R1 = x_new[-3:].tolist()
    shift = math.hypot(
        rho1 * math.cos(theta1) - rho0 * math.cos(theta0),
        rho1 * math.sin(theta1) - rho0 * math.sin(theta0),
    )
    return max(shift, abs(R1 - R0))


def _scan(phi: ArrayLike, r: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """``phi`` and ``r`` as finite float arrays (N,) of one length N >= 1, ``r`` > 0."""
    n = int(np.size(phi))
    phi_array = finite_vector(phi, "phi", n)
    r_array = finite_vector(r, "r", n)
    if n == 0:
        raise ValueError("phi and r must hold at least one point, got none")
    if not (r_array > 0.0).all():
        raise ValueError(f"r must be ranges > 0 (m), got {r_array}")
    return phi_array, r_array
