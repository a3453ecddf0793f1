"""Circle fits to 2-D laser points and the KCR lower bound on their covariance.

Every fit takes points ``(N, 2)`` (m, sensor frame: x forward, y left, the sensor at the
origin), ``N >= 3``, and returns a :class:`CircleFit` in the same frame; ``.polar`` gives the
circle in the polar parameters ``(rho, theta, R)`` of :mod:`perception.circles.model`.

- :func:`three_point_circle`: the circle through three points, from the system of seed 001
  §4.4.1 eq. 4.2 (circumcentre by Cramer's rule).
- :func:`geometric_initialisation`: seed 001 §4.4.1 Algorithm 2, the means of the circles
  through disjoint triplets of points.
- :func:`bullock_fit`: seed 001 §4.4.2 Algorithm 3 (Bullock 2017, "Least-squares circle
  fit"; the same estimate as Kåsa 1976), eqs. 4.3-4.8 in centred coordinates.
- :func:`taubin_fit`, :func:`hyper_fit`: the algebraic fits of Taubin (1991) and the "Hyper"
  fit of Al-Sharadqah & Chernov (2009), "Error analysis for circle fitting algorithms",
  Electron. J. Statist. 3, 886-911, which has no essential bias (no ``sigma^2`` term).
- :func:`geometric_fit`: Levenberg-Marquardt on the geometric distances ``|‖p - c‖ - R|``,
  the maximum-likelihood fit under isotropic Gaussian noise.
- :func:`kcr_covariance`, :func:`kcr_polar_covariance`: the KCR lower bound (Kanatani 1996,
  "Statistical Optimization for Geometric Computation"; Chernov 2010, "Circular and Linear
  Regression", ch. 6), which the geometric fit attains to leading order in ``sigma``.

Symbols: ``c = (xc, yc)`` the centre (m), ``R`` the radius (m), ``d_i = ‖p_i - c‖`` the
distance of point ``i`` to the centre (m). Algebraic fits write the circle as
``A z + B x + C y + D = 0`` with ``z = x^2 + y^2`` and minimise ``a^T M a`` (``a = (A, B, C,
D)``, ``M`` the moment matrix of the rows ``(z, x, y, 1)``) subject to ``a^T N a = 1``; the
constraint ``N`` names the fit. They run on data centred at its centroid and scaled to a unit
RMS distance from it, where ``mean(z) = 1`` and both ``N`` are constant.

Each fit also reports the residue of seed 001 eq. 4.9, ``sum_i (d_i - mean_j d_j)^2`` (m^2),
the spread of the distances to the fitted centre, which the seed uses to tell circles from
other segments.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import least_squares

from perception.circles.model import PolarCircle
from perception.geometry import FloatArray
from perception.validation import InvalidTypeError, check_positive, finite_points, finite_vector

_MIN_POINTS = 3  # a circle has three parameters
_DEGENERATE_RTOL = 1e-12  # a relative size below which a determinant (or ``A``) counts as zero
_KCR_MAX_CONDITION = 1e12  # angles this badly conditioned do not pin down a circle
_LM_TOLERANCE = 1e-12  # ftol, xtol and gtol of the Levenberg-Marquardt iterations

# The constraint matrices on (A, B, C, D) for data with mean(x) = mean(y) = 0, mean(z) = 1
# (Al-Sharadqah & Chernov 2009): Taubin's is the gradient weight
# 4 A^2 mean(z) + B^2 + C^2; Hyper's is twice Taubin's minus Pratt's B^2 + C^2 - 4 A D.
_TAUBIN_CONSTRAINT = np.diag([4.0, 1.0, 1.0, 0.0])
_HYPER_CONSTRAINT = np.array(
    [
        [8.0, 0.0, 0.0, 2.0],
        [0.0, 1.0, 0.0, 0.0],
        [0.0, 0.0, 1.0, 0.0],
        [2.0, 0.0, 0.0, 0.0],
    ]
)


@dataclass(frozen=True, eq=False)
class CircleFit:
    """A circle fitted to points.

    ``centre`` (2,) (m, sensor frame) and radius ``R`` (m); ``rms_residual`` (m) is the RMS
    geometric distance ``sqrt(mean_i (d_i - R)^2)`` of the fitted points to the circle and
    ``radial_residue`` (m^2) the residue of seed 001 eq. 4.9, ``sum_i (d_i - mean_j d_j)^2``.
    """

    centre: FloatArray
    R: float
    rms_residual: float
    radial_residue: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "centre", finite_vector(self.centre, "CircleFit.centre", 2))
        check_positive("CircleFit", "R", self.R)
        check_positive("CircleFit", "rms_residual", self.rms_residual, allow_zero=True)
        check_positive("CircleFit", "radial_residue", self.radial_residue, allow_zero=True)

    @property
    def polar(self) -> PolarCircle:
        """The circle as ``(rho, theta, R)``; ValueError if it contains the sensor."""
        return PolarCircle.from_centre(self.centre, self.R)


def three_point_circle(p1: ArrayLike, p2: ArrayLike, p3: ArrayLike) -> CircleFit:
    """The circle through the points ``p1``, ``p2``, ``p3`` (each (2,), m, sensor frame).

    ValueError if they are collinear or two coincide (no circle passes through them).
    """
    a = finite_vector(p1, "three_point_circle.p1", 2)
    b = finite_vector(p2, "three_point_circle.p2", 2)
    c = finite_vector(p3, "three_point_circle.p3", 2)
    centres, valid = _circumcentres(a[None], b[None], c[None])
    if not valid[0]:
        raise ValueError(
            f"three_point_circle: the points {a.tolist()}, {b.tolist()}, {c.tolist()} are "
            f"collinear or coincide, no circle passes through them"
        )
    points = np.stack([a, b, c])
    return _fit_result(points, centres[0], float(np.linalg.norm(a - centres[0])))


def geometric_initialisation(points: ArrayLike) -> CircleFit:
    """Seed 001 §4.4.1 Algorithm 2: the mean centre and radius of the circles through triplets.

    ``points`` (N, 2) (m, sensor frame), in scan order. With ``m = N // 3``, triplet ``k`` is
    ``(p[k], p[k + m], p[k + 2m])``: each point is used at most once, as in the seed, and each
    triplet spans the first ``3m`` points, like the seed's worked example (first, middle and
    last points) when N is a multiple of 3; the last ``N - 3m`` points (one or two) are left
    out, so 4 or 5 points give one triplet of the first three, a narrower arc. The
    seed draws the triplets at random, which can put close points together, whose circle
    noise throws far off (its §4.5 reports large maximal errors). Each circle's radius is its
    distance to the triplet's first point; triplets of collinear points are skipped,
    ValueError if all are.
    """
    p = finite_points(points, "geometric_initialisation.points", _MIN_POINTS)
    m = len(p) // 3
    centres, valid = _circumcentres(p[:m], p[m : 2 * m], p[2 * m : 3 * m])
    if not valid.any():
        raise ValueError("geometric_initialisation: every triplet of points is collinear")
    radii = np.linalg.norm(p[:m][valid] - centres[valid], axis=1)
    return _fit_result(p, centres[valid].mean(axis=0), float(radii.mean()))


def bullock_fit(points: ArrayLike) -> CircleFit:
    """Seed 001 §4.4.2 Algorithm 3: Bullock's least-squares circle (Kåsa's fit).

    Minimises ``sum_i (d_i^2 - R^2)^2`` over the points ``(N, 2)`` (m, sensor frame). In
    coordinates ``(u, v)`` centred at the centroid, the centre solves eqs. 4.6-4.7::

        [S_uu  S_uv] [u_c]         [S_uuu + S_uvv]
        [S_uv  S_vv] [v_c] = 1/2 * [S_vvv + S_vuu]

    and ``R^2 = u_c^2 + v_c^2 + (S_uu + S_vv) / N`` (eq. 4.8). ValueError for collinear points
    (the system is singular). Biased towards small circles on short arcs.
    """
    p = finite_points(points, "bullock_fit.points", _MIN_POINTS)
    centroid = p.mean(axis=0)
    u, v = (p - centroid).T
    S_uu, S_uv, S_vv = u @ u, u @ v, v @ v
    if S_uu * S_vv - S_uv**2 <= _DEGENERATE_RTOL * (S_uu + S_vv) ** 2:
        raise ValueError("bullock_fit: the points are collinear, no circle fits them")
    squares = u**2 + v**2
    rhs = 0.5 * np.array([u @ squares, v @ squares])
    u_c, v_c = np.linalg.solve([[S_uu, S_uv], [S_uv, S_vv]], rhs)
    R = np.sqrt(u_c**2 + v_c**2 + (S_uu + S_vv) / len(p))
    return _fit_result(p, centroid + np.array([u_c, v_c]), float(R))


def taubin_fit(points: ArrayLike) -> CircleFit:
    """Taubin's algebraic fit (Taubin 1991) to the points ``(N, 2)`` (m, sensor frame).

    Minimises ``sum_i (A z_i + B x_i + C y_i + D)^2`` subject to ``4 A^2 mean(z) + B^2 + C^2
    = 1``, the mean squared gradient of the algebraic distance. ValueError for collinear points.
    """
    return _algebraic_fit("taubin_fit", points, _TAUBIN_CONSTRAINT)


def hyper_fit(points: ArrayLike) -> CircleFit:
    """The Hyper fit (Al-Sharadqah & Chernov 2009) to the points ``(N, 2)`` (m, sensor
    frame): the algebraic fit with no essential bias.

    Minimises ``sum_i (A z_i + B x_i + C y_i + D)^2`` subject to ``8 A^2 mean(z) + B^2 + C^2
    + 4 A D = 1`` (centred data), through the generalised eigenproblem ``M a = eta N a`` and
    its smallest positive ``eta``. ValueError for collinear points.
    """
    return _algebraic_fit("hyper_fit", points, _HYPER_CONSTRAINT)


def geometric_fit(points: ArrayLike, initial: CircleFit | None = None) -> CircleFit:
    """The geometric (orthogonal distance) fit to the points ``(N, 2)`` (m, sensor frame).

    Minimises ``sum_i (d_i - R)^2`` by Levenberg-Marquardt from ``initial`` (default: the
    :func:`hyper_fit`). RuntimeError if the iterations do not converge.
    """
    p = finite_points(points, "geometric_fit.points", _MIN_POINTS)
    if initial is None:
        initial = hyper_fit(p)
    elif not isinstance(initial, CircleFit):
        raise InvalidTypeError(
            f"geometric_fit.initial must be a CircleFit or None, got {type(initial).__name__}"
        )
    solution = least_squares(
        _geometric_residuals,
        np.append(initial.centre, initial.R),
        jac=_geometric_jacobian,
        args=(p,),
        method="lm",
        ftol=_LM_TOLERANCE,
        xtol=_LM_TOLERANCE,
        gtol=_LM_TOLERANCE,
    )
    if not solution.success:
        raise RuntimeError(f"geometric_fit did not converge: {solution.message}")
    return _fit_result(p, solution.x[:2], float(solution.x[2]))


def angles_around_centre(points: ArrayLike, centre: ArrayLike) -> FloatArray:
    """The angles ``phi_i`` (N,) (rad, sensor frame axes) of the points ``(N, 2)`` (m) seen from
    ``centre`` (2,) (m): the angles of the true points that :func:`kcr_covariance` takes."""
    p = finite_points(points, "angles_around_centre.points", _MIN_POINTS)
    offsets = p - finite_vector(centre, "angles_around_centre.centre", 2)
    return np.arctan2(offsets[:, 1], offsets[:, 0])


def kcr_covariance(angles: ArrayLike, sigma: float) -> FloatArray:
    """The KCR lower bound (3, 3) on the covariance of ``(xc, yc, R)`` (m^2).

    For points observed at the true angles ``angles`` ``phi_i`` (N,) (rad) around the true
    centre, each with isotropic Gaussian noise of standard deviation ``sigma`` (m) per axis,
    any unbiased fit has ``cov(xc, yc, R) >= sigma^2 (sum_i u_i u_i^T)^-1`` with
    ``u_i = (cos phi_i, sin phi_i, 1)``: the gradient of the distance ``d_i - R`` of point i
    to the circle. The bound does not depend on ``R``. ValueError unless the angles hold at
    least three distinct directions.
    """
    phi = _as_angles("kcr_covariance", angles)
    check_positive("kcr_covariance", "sigma", sigma)
    u = np.column_stack([np.cos(phi), np.sin(phi), np.ones_like(phi)])
    information = u.T @ u
    if np.linalg.cond(information) > _KCR_MAX_CONDITION:
        raise ValueError(
            "kcr_covariance.angles must hold at least 3 distinct directions (modulo 2 pi), "
            f"got {phi}"
        )
    return sigma**2 * np.linalg.inv(information)


def kcr_polar_covariance(circle: PolarCircle, angles: ArrayLike, sigma: float) -> FloatArray:
    """The KCR lower bound (3, 3) on the covariance of ``(rho, theta, R)`` (m, rad, m) of the
    true ``circle``: :func:`kcr_covariance` mapped through the Jacobian ``G`` of
    ``(xc, yc, R) -> (rho, theta, R)``, ``G C G^T``, where::

        G = [[ cos(theta),       sin(theta),       0],
             [-sin(theta) / rho, cos(theta) / rho, 0],
             [ 0,                0,                1]]

    ``angles`` (N,) (rad) and ``sigma`` (m) as in :func:`kcr_covariance`.
    """
    if not isinstance(circle, PolarCircle):
        raise InvalidTypeError(
            f"kcr_polar_covariance.circle must be a PolarCircle, got {type(circle).__name__}"
        )
    c, s = np.cos(circle.theta), np.sin(circle.theta)
    G = np.array([[c, s, 0.0], [-s / circle.rho, c / circle.rho, 0.0], [0.0, 0.0, 1.0]])
    return G @ kcr_covariance(angles, sigma) @ G.T


def _as_angles(owner: str, angles: ArrayLike) -> FloatArray:
    """``angles`` as a new finite float64 (N,) array with N >= 3; errors name ``owner``."""
    try:
        phi = np.array(angles, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise InvalidTypeError(f"{owner}.angles must be numbers, got {angles!r}") from error
    if phi.ndim != 1 or phi.size < 3:
        raise ValueError(f"{owner}.angles must have shape (N,) with N >= 3, got {phi.shape}")
    if not np.isfinite(phi).all():
        raise ValueError(f"{owner}.angles must be finite, got {phi}")
    return phi


def _circumcentres(
    a: FloatArray, b: FloatArray, c: FloatArray
) -> tuple[FloatArray, NDArray[np.bool_]]:
    """The centres (M, 2) of the circles through the rows of ``a``, ``b``, ``c`` (M, 2 each)
    and a mask (M,) of the valid ones (not collinear, no coincident points).

    Eq. 4.2 less its first row is linear in the centre ``a + w``:
    ``2 (b - a) . w = |b - a|^2``, ``2 (c - a) . w = |c - a|^2``, solved by Cramer's rule. The
    seed's closed form for ``y_c`` divides by ``y_2 - y_1`` and fails on a horizontal chord.
    """
    ab, ac = b - a, c - a
    cross = ab[:, 0] * ac[:, 1] - ab[:, 1] * ac[:, 0]
    scale = np.linalg.norm(ab, axis=1) * np.linalg.norm(ac, axis=1)
    valid = np.abs(cross) > _DEGENERATE_RTOL * scale
    ab2, ac2 = (ab**2).sum(axis=1), (ac**2).sum(axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        w = np.column_stack([ac[:, 1] * ab2 - ab[:, 1] * ac2, ab[:, 0] * ac2 - ac[:, 0] * ab2]) / (
            2.0 * cross[:, None]
        )
    return a + w, valid


def _algebraic_fit(owner: str, points: ArrayLike, constraint: FloatArray) -> CircleFit:
    """Minimise ``a^T M a`` subject to ``a^T N a = 1`` (N = ``constraint``) on the normalised
    points; see the module docstring.

    With ``Z = U S V^T`` (rows ``(z, x, y, 1)``) and ``Y = V S V^T``, so that ``Z^T Z = Y^2``
    (``M`` up to a positive factor), ``M a = eta N a`` becomes the symmetric eigenproblem
    ``Y^-1 N Y^-1 b = (1 / eta) b`` with ``a = Y^-1 b``: the smallest positive ``eta`` is its
    largest eigenvalue. A singular ``Z`` means the points lie exactly on a circle, its null
    vector.
    """
    p = finite_points(points, f"{owner}.points", _MIN_POINTS)
    centroid = p.mean(axis=0)
    scale = np.sqrt(((p - centroid) ** 2).sum(axis=1).mean())
    if scale == 0.0:
        raise ValueError(f"{owner}: the points all coincide, no circle fits them")
    q = (p - centroid) / scale
    Z = np.column_stack([(q**2).sum(axis=1), q, np.ones(len(q))])
    if len(Z) < 4:  # three points: a zero row keeps Z^T Z and gives the SVD its null vector
        Z = np.vstack([Z, np.zeros((4 - len(Z), 4))])
    _, s, Vt = np.linalg.svd(Z, full_matrices=False)
    if s[-1] <= _DEGENERATE_RTOL * s[0]:
        coefficients = Vt[-1]
    else:
        Y_inv = Vt.T @ np.diag(1.0 / s) @ Vt
        _, eigenvectors = np.linalg.eigh(Y_inv @ constraint @ Y_inv)
        coefficients = Y_inv @ eigenvectors[:, -1]
    centre, R = _circle_from_coefficients(owner, coefficients)
    return _fit_result(p, centroid + scale * centre, scale * R)


def _circle_from_coefficients(owner: str, coefficients: FloatArray) -> tuple[FloatArray, float]:
    """The centre (2,) and radius of ``A z + B x + C y + D = 0``; ValueError for a line
    (``A`` zero relative to the others)."""
    A, B, C, D = coefficients
    if abs(A) <= _DEGENERATE_RTOL * np.linalg.norm(coefficients):
        raise ValueError(f"{owner}: the points are collinear, no circle fits them")
    centre = -np.array([B, C]) / (2.0 * A)
    return centre, float(np.sqrt(B**2 + C**2 - 4.0 * A * D) / (2.0 * abs(A)))


def _fit_result(points: FloatArray, centre: FloatArray, R: float) -> CircleFit:
    """The :class:`CircleFit` of ``centre`` (2,) and ``R`` with the residuals of ``points``."""
    distances = np.linalg.norm(points - centre, axis=1)
    return CircleFit(
        centre=centre,
        R=R,
        rms_residual=float(np.sqrt(np.mean((distances - R) ** 2))),
        radial_residue=float(np.sum((distances - distances.mean()) ** 2)),
    )


def _geometric_residuals(parameters: FloatArray, points: FloatArray) -> FloatArray:
    """The signed distances (N,) ``d_i - R`` (m) of ``points`` (N, 2) to the circle
    ``parameters = (xc, yc, R)``."""
    return np.linalg.norm(points - parameters[:2], axis=1) - parameters[2]


def _geometric_jacobian(parameters: FloatArray, points: FloatArray) -> FloatArray:
    """The derivatives (N, 3) of :func:`_geometric_residuals` in ``(xc, yc, R)``:
    ``(-(p_i - c) / d_i, -1)``."""
    offsets = points - parameters[:2]
    unit = offsets / np.linalg.norm(offsets, axis=1)[:, None]
    return np.column_stack([-unit, -np.ones(len(points))])
