"""Circle fits and the KCR bound against known circles, closed forms and definitions."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pytest
import scipy.linalg

from perception.circles.fits import (
    CircleFit,
    angles_around_centre,
    bullock_fit,
    geometric_fit,
    geometric_initialisation,
    hyper_fit,
    kcr_covariance,
    kcr_polar_covariance,
    taubin_fit,
    three_point_circle,
)
from perception.circles.model import PolarCircle, polar_range
from perception.geometry import FloatArray, wrap_angle
from perception.validation import InvalidTypeError

Fit = Callable[[FloatArray], CircleFit]
FITS: list[Fit] = [geometric_initialisation, bullock_fit, taubin_fit, hyper_fit, geometric_fit]
# seed 001 §4.5's circles (rho, theta, R); its third, (1, 0, 1), puts the sensor on the circle
SEED_CIRCLES = [(1.5, math.pi / 2, 0.25), (1.41, 0.78, 0.25), (2.0, 0.0, 1.0), (4.0, 1.57, 0.25)]


def laser_arc(circle: PolarCircle) -> FloatArray:
    """The points (N, 2) where rays at 1-degree steps around ``theta`` meet the convex side."""
    phi = circle.theta + np.deg2rad(np.arange(-90.0, 91.0))
    r = polar_range(phi, circle.rho, circle.theta, circle.R)
    seen = np.isfinite(r)
    return np.column_stack([r[seen] * np.cos(phi[seen]), r[seen] * np.sin(phi[seen])])


def on_circle(centre: tuple[float, float], R: float, angles: FloatArray) -> FloatArray:
    """The points (N, 2) at ``angles`` (rad) around ``centre`` on the circle of radius ``R``."""
    return np.asarray(centre) + R * np.column_stack([np.cos(angles), np.sin(angles)])


def polar_errors(fits: list[CircleFit], truth: PolarCircle) -> FloatArray:
    """The errors (M, 3) of the fits in ``(rho, theta, R)``, theta wrapped."""
    errors = np.array([fit.polar.vector for fit in fits]) - truth.vector
    errors[:, 1] = wrap_angle(errors[:, 1])
    return errors


# --- noiseless data ------------------------------------------------------------------------


@pytest.mark.parametrize("fit", FITS, ids=lambda f: f.__name__)
@pytest.mark.parametrize("parameters", SEED_CIRCLES, ids=str)
def test_noiseless_laser_arc_gives_the_exact_circle(
    fit: Fit, parameters: tuple[float, float, float]
) -> None:
    truth = PolarCircle(*parameters)
    points = laser_arc(truth)
    assert len(points) >= 7  # the far circle (4, 1.57, 0.25) shows only 7 rays
    result = fit(points)
    np.testing.assert_allclose(result.centre, truth.centre, rtol=0, atol=1e-9 * truth.rho)
    np.testing.assert_allclose(result.R, truth.R, rtol=1e-9)
    np.testing.assert_allclose(result.polar.vector, truth.vector, rtol=1e-9)
    assert result.rms_residual < 1e-12
    assert result.radial_residue < 1e-20


def test_angles_around_centre_of_known_points() -> None:
    angles = np.array([-3.0, -1.0, 0.0, 0.5, 2.0, 3.1])
    points = on_circle((2.0, -1.0), 0.7, angles)
    np.testing.assert_allclose(angles_around_centre(points, [2.0, -1.0]), angles, rtol=1e-14)


def test_laser_sees_the_arc_between_the_tangent_points() -> None:
    # seen from the centre, the tangent points lie at pi/2 - alpha either side of the sensor
    truth = PolarCircle(1.5, math.pi / 2, 0.25)
    phi = angles_around_centre(laser_arc(truth), truth.centre)
    from_sensor_side = wrap_angle(phi - (truth.theta + math.pi))
    assert np.all(np.abs(from_sensor_side) < math.pi / 2 - truth.half_angle)


def test_three_points_of_a_right_triangle_give_the_thales_circle() -> None:
    fit = three_point_circle([0.0, 0.0], [2.0, 0.0], [0.0, 2.0])
    np.testing.assert_allclose(fit.centre, [1.0, 1.0], rtol=0, atol=1e-15)
    np.testing.assert_allclose(fit.R, math.sqrt(2.0), rtol=1e-15)


@pytest.mark.parametrize("fit", [taubin_fit, hyper_fit, geometric_fit])
def test_the_least_squares_fits_pass_through_three_points_exactly(fit) -> None:
    """Three points fix a circle: the algebraic fits' SVD had lost its null vector with three
    rows (Taubin gave R 1.44, Hyper 0.94 for the unit circle)."""
    rng = np.random.default_rng(0)
    for _ in range(50):
        centre, radius = rng.uniform(-2.0, 2.0, 2), rng.uniform(0.05, 1.0)
        angles = np.sort(rng.uniform(-math.pi, math.pi, 3))
        result = fit(on_circle(tuple(centre), radius, angles))
        np.testing.assert_allclose(result.centre, centre, atol=1e-8 * (1 + radius))
        np.testing.assert_allclose(result.R, radius, rtol=1e-8)


def test_three_points_with_a_horizontal_chord_give_their_circle() -> None:
    # p1 and p2 share y: the seed's closed form for y_c divides by y2 - y1 = 0
    p1, p2, p3 = on_circle((0.3, 1.2), 0.5, np.array([math.pi / 6, 5 * math.pi / 6, -1.0]))
    fit = three_point_circle(p1, p2, p3)
    np.testing.assert_allclose(fit.centre, [0.3, 1.2], rtol=1e-14)
    np.testing.assert_allclose(fit.R, 0.5, rtol=1e-14)
    assert fit.rms_residual < 1e-15


@pytest.mark.parametrize(
    "points",
    [[[0.0, 0.0], [1.0, 1.0], [3.0, 3.0]], [[1.0, 2.0], [1.0, 2.0], [0.0, 5.0]]],
    ids=["collinear", "coincident"],
)
def test_three_point_circle_refuses_collinear_points(points: list[list[float]]) -> None:
    with pytest.raises(ValueError, match="collinear or coincide"):
        three_point_circle(*points)


def test_geometric_initialisation_averages_the_circles_of_spanning_triplets() -> None:
    # triplets (p0, p2, p4) and (p1, p3, p5): on circles of centres (0, 0), (2, 0), radii 1, 3
    first = on_circle((0.0, 0.0), 1.0, np.array([0.0, 1.0, 2.0]))
    second = on_circle((2.0, 0.0), 3.0, np.array([0.5, 1.5, 2.5]))
    points = np.stack([first, second], axis=1).reshape(6, 2)
    fit = geometric_initialisation(points)
    np.testing.assert_allclose(fit.centre, [1.0, 0.0], rtol=0, atol=1e-14)
    np.testing.assert_allclose(fit.R, 2.0, rtol=1e-14)


def test_fits_of_a_four_fold_symmetric_ring_have_the_closed_forms() -> None:
    # 8 points at 45-degree steps, alternately at distances r1 and r2 from (1, 2): a rotation
    # by 90 degrees maps them onto themselves, so every fit is centred at (1, 2)
    r1, r2 = 1.0, 1.2
    radii = np.tile([r1, r2], 4)
    angles = np.arange(8) * math.pi / 4
    points = np.array([1.0, 2.0]) + radii[:, None] * np.column_stack(
        [np.cos(angles), np.sin(angles)]
    )
    for fit in (bullock_fit, taubin_fit, hyper_fit, geometric_fit):
        result = fit(points)
        np.testing.assert_allclose(result.centre, [1.0, 2.0], rtol=1e-12)
        assert result.radial_residue == pytest.approx(2.0 * (r1 - r2) ** 2, rel=1e-12)  # eq. 4.9
    np.testing.assert_allclose(
        bullock_fit(points).R, math.hypot(r1, r2) / math.sqrt(2.0)
    )  # eq. 4.8
    geometric = geometric_fit(points)
    np.testing.assert_allclose(geometric.R, (r1 + r2) / 2.0, rtol=1e-12)
    assert geometric.rms_residual == pytest.approx(abs(r1 - r2) / 2.0, rel=1e-12)


@pytest.mark.parametrize("fit", FITS, ids=lambda f: f.__name__)
def test_every_fit_refuses_collinear_points(fit: Fit) -> None:
    points = np.column_stack([np.linspace(0.0, 1.0, 9), 2.0 + 0.5 * np.linspace(0.0, 1.0, 9)])
    with pytest.raises(ValueError, match="collinear"):
        fit(points)


# --- noisy data ----------------------------------------------------------------------------


def smallest_positive_eigenvector(M: FloatArray, N: FloatArray) -> FloatArray:
    """The eigenvector of ``M a = eta N a`` with the smallest positive finite ``eta``."""
    eta, vectors = scipy.linalg.eig(M, N)
    eta = np.where(np.isfinite(eta) & (eta.real > 0.0), eta.real, np.inf)
    return np.asarray(vectors[:, np.argmin(eta)].real)


@pytest.mark.parametrize("fit", [taubin_fit, hyper_fit], ids=lambda f: f.__name__)
def test_algebraic_fits_solve_their_defining_eigenproblem(fit: Fit) -> None:
    # Al-Sharadqah & Chernov 2009 on the raw data: M the moments of (z, x, y, 1), N the
    # constraint with the data's own means of x, y and z
    rng = np.random.default_rng(7)
    points = on_circle((0.4, 1.3), 0.3, rng.uniform(2.0, 4.5, 25))
    points += 0.01 * rng.standard_normal(points.shape)
    x, y = points.T
    z = x**2 + y**2
    Z = np.column_stack([z, x, y, np.ones_like(x)])
    mz, mx, my = z.mean(), x.mean(), y.mean()
    taubin = np.array(
        [[4 * mz, 2 * mx, 2 * my, 0], [2 * mx, 1, 0, 0], [2 * my, 0, 1, 0], [0, 0, 0, 0]]
    )
    pratt = np.array([[0, 0, 0, -2], [0, 1, 0, 0], [0, 0, 1, 0], [-2, 0, 0, 0]])
    N = taubin if fit is taubin_fit else 2 * taubin - pratt
    A, B, C, D = smallest_positive_eigenvector(Z.T @ Z / len(Z), N)
    result = fit(points)
    np.testing.assert_allclose(result.centre, [-B / (2 * A), -C / (2 * A)], rtol=1e-9)
    np.testing.assert_allclose(result.R, math.sqrt(B**2 + C**2 - 4 * A * D) / abs(2 * A), rtol=1e-9)


def test_geometric_fit_is_a_stationary_point_below_the_algebraic_fits() -> None:
    rng = np.random.default_rng(3)
    points = on_circle((1.0, -0.5), 0.4, rng.uniform(-1.0, 1.0, 20))
    points += 0.02 * rng.standard_normal(points.shape)
    result = geometric_fit(points, bullock_fit(points))
    offsets = points - result.centre
    distances = np.linalg.norm(offsets, axis=1)
    residuals = distances - result.R
    gradient = np.column_stack([-offsets / distances[:, None], -np.ones(len(points))]).T
    # zero to the Levenberg-Marquardt tolerances, against terms |r_i| ~ 0.02 summed over 20
    np.testing.assert_allclose(gradient @ residuals, 0.0, atol=1e-8)
    for algebraic in (bullock_fit, taubin_fit, hyper_fit):
        assert result.rms_residual <= algebraic(points).rms_residual


# --- KCR bound -----------------------------------------------------------------------------


def test_kcr_over_the_whole_circle_has_the_closed_form() -> None:
    n, sigma = 12, 0.01
    angles = 2 * math.pi * np.arange(n) / n
    expected = np.diag([2 * sigma**2 / n, 2 * sigma**2 / n, sigma**2 / n])
    np.testing.assert_allclose(kcr_covariance(angles, sigma), expected, rtol=1e-12, atol=1e-20)
    # the centre's isotropic variance maps to var(rho) = 2 sigma^2 / n, var(theta) = that / rho^2
    circle = PolarCircle(2.0, 0.7, 0.5)
    polar = np.diag([2 * sigma**2 / n, 2 * sigma**2 / (n * 4.0), sigma**2 / n])
    np.testing.assert_allclose(
        kcr_polar_covariance(circle, angles, sigma), polar, rtol=1e-12, atol=1e-20
    )


def test_kcr_polar_on_the_x_axis_scales_the_lateral_variance_by_rho() -> None:
    angles = np.linspace(2.0, 4.0, 15)
    cartesian = kcr_covariance(angles, 0.02)
    polar = kcr_polar_covariance(PolarCircle(3.0, 0.0, 1.0), angles, 0.02)
    scale = np.diag([1.0, 1.0 / 3.0, 1.0])  # d(rho, theta, R) / d(xc, yc, R) at (3, 0)
    np.testing.assert_allclose(polar, scale @ cartesian @ scale, rtol=1e-12)


def test_kcr_grows_as_the_arc_shrinks() -> None:
    n, sigma = 30, 0.005
    spans = [2 * math.pi, math.pi, math.pi / 2, math.pi / 4]
    variances = np.array(
        [
            np.diag(kcr_covariance(np.linspace(0.0, span, n, endpoint=False), sigma))
            for span in spans
        ]
    )
    assert np.all(np.diff(variances, axis=0) > 0.0)


def test_kcr_refuses_fewer_than_three_directions() -> None:
    with pytest.raises(ValueError, match="at least 3 distinct directions"):
        kcr_covariance([0.0, 1.0, 1.0, 2 * math.pi], 0.01)


def test_geometric_fit_attains_the_kcr_bound() -> None:
    sigma, n, repetitions = 0.002, 30, 300
    truth = PolarCircle(1.5, math.pi / 2, 0.25)
    angles = truth.theta + math.pi + np.linspace(-math.pi / 2, math.pi / 2, n)  # facing the sensor
    exact = on_circle(tuple(truth.centre), truth.R, angles)
    rng = np.random.default_rng(2024)
    fits = [
        geometric_fit(exact + sigma * rng.standard_normal(exact.shape)) for _ in range(repetitions)
    ]
    rmse = np.sqrt(np.mean(polar_errors(fits, truth) ** 2, axis=0))
    bound = np.sqrt(np.diag(kcr_polar_covariance(truth, angles, sigma)))
    # 300 repetitions estimate an RMSE to about 4 %
    assert np.all(rmse / bound < 1.2), rmse / bound
    assert np.all(rmse / bound > 0.85), rmse / bound


def test_hyper_is_less_biased_than_bullock_on_a_half_circle() -> None:
    # seed 001 §4.5's noise: Kasa/Bullock's sigma^2 bias pulls the circle towards the points
    # (rho and R too small); theta is unbiased for both by the arc's symmetry
    sigma, n = 0.02, 30
    truth = PolarCircle(1.5, math.pi / 2, 0.25)
    angles = truth.theta + math.pi + np.linspace(-math.pi / 2, math.pi / 2, n)
    exact = on_circle(tuple(truth.centre), truth.R, angles)
    rng = np.random.default_rng(11)
    samples = [exact + sigma * rng.standard_normal(exact.shape) for _ in range(300)]
    bound = np.sqrt(np.diag(kcr_polar_covariance(truth, angles, sigma)))
    hyper_bias = polar_errors([hyper_fit(p) for p in samples], truth).mean(axis=0) / bound
    bullock_bias = polar_errors([bullock_fit(p) for p in samples], truth).mean(axis=0) / bound
    assert bullock_bias[0] < -0.4 and bullock_bias[2] < -0.2, bullock_bias
    assert np.all(np.abs(hyper_bias[[0, 2]]) < 0.25 * np.abs(bullock_bias[[0, 2]])), hyper_bias


# --- bad input -----------------------------------------------------------------------------


@pytest.mark.parametrize("fit", FITS, ids=lambda f: f.__name__)
@pytest.mark.parametrize(
    ("points", "error", "message"),
    [
        (np.zeros((5, 3)), ValueError, r"must have shape \(N, 2\) with N >= 3"),
        (np.zeros(6), ValueError, r"got shape \(6,\)"),
        ([[0.0, 0.0], [1.0, 1.0]], ValueError, r"N >= 3, got shape \(2, 2\)"),
        ([[0.0, 0.0], [1.0, np.nan], [2.0, 0.0]], ValueError, r"must be finite.*rows \[1\]"),
        ([["a", "b"], ["c", "d"], ["e", "f"]], InvalidTypeError, "array of numbers"),
    ],
    ids=["three-columns", "flat", "two-points", "nan", "strings"],
)
def test_fits_refuse_bad_points(fit: Fit, points: object, error: type, message: str) -> None:
    with pytest.raises(error, match=rf"{fit.__name__}\.points .*{message}"):
        fit(points)  # type: ignore[arg-type]


def test_bad_arguments_are_refused_with_their_names() -> None:
    with pytest.raises(ValueError, match=r"three_point_circle.p2 must be finite"):
        three_point_circle([0.0, 0.0], [np.inf, 1.0], [1.0, 0.0])
    with pytest.raises(ValueError, match=r"three_point_circle.p3 must have shape \(2,\)"):
        three_point_circle([0.0, 0.0], [0.0, 1.0], [1.0, 0.0, 2.0])
    with pytest.raises(InvalidTypeError, match=r"geometric_fit\.initial must be a CircleFit"):
        geometric_fit(laser_arc(PolarCircle(1.5, 0.0, 0.25)), initial=(0.0, 1.5, 0.25))  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"kcr_covariance.sigma must be finite and in \(0"):
        kcr_covariance([0.0, 1.0, 2.0], 0.0)
    with pytest.raises(ValueError, match=r"kcr_covariance.angles must have shape \(N,\)"):
        kcr_covariance(np.zeros((3, 2)), 0.01)
    with pytest.raises(ValueError, match=r"kcr_covariance\.angles must be finite"):
        kcr_covariance([0.0, np.nan, 2.0], 0.01)
    with pytest.raises(
        InvalidTypeError, match=r"kcr_polar_covariance\.circle must be a PolarCircle"
    ):
        kcr_polar_covariance((1.5, 0.0, 0.25), [0.0, 1.0, 2.0], 0.01)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"CircleFit\.R must be finite and in"):
        CircleFit(centre=np.zeros(2), R=-1.0, rms_residual=0.0, radial_residue=0.0)


def test_polar_of_a_circle_around_the_sensor_is_refused() -> None:
    fit = three_point_circle(*on_circle((0.5, 0.0), 1.0, np.array([0.0, 2.0, 4.0])))
    with pytest.raises(ValueError, match="R must be below rho"):
        _ = fit.polar
