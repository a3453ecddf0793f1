"""The circle EKF of seed 001 (perception.circles.ekf): its measurement model against finite
differences, single updates against closed-form Kalman steps, noiseless arcs of the §4.5 circles
against the truth, noisy arcs against the chi-square band of the returned covariance, the
stop rules, the handling of rays that miss, and the checks of its inputs."""

from __future__ import annotations

import math

import numpy as np
import pytest

from perception.circles.ekf import (
    CircleEkfConfig,
    CircleEkfResult,
    circle_update,
    estimate_circle,
    range_model,
)
from perception.circles.model import BRANCHES, Branch, PolarCircle, polar_jacobian, polar_range
from perception.geometry import FloatArray, wrap_angle
from perception.validation import InvalidTypeError

# Seed 001 §4.5: (rho m, theta rad, R m); the laser sweeps 0..179 degrees in 1-degree steps
CIRCLES = [(1.5, math.pi / 2, 0.25), (1.41, 0.78, 0.25), (4.0, 1.57, 0.25)]
SIGMA = 0.02  # m, seed 001 §3.2 and §4.6.1
CHI2_3DOF_99 = 11.344866730144373  # chi-square quantile, 3 degrees of freedom, p = 0.99
VARIANTS = ("tikhonov", "joseph")


def _arc(circle: tuple[float, float, float]) -> tuple[FloatArray, FloatArray]:
    """The rays (rad) of a 1-degree laser sweep that meet ``circle``, and their noiseless
    convex-side ranges (m), in scan order."""
    phi = np.deg2rad(np.arange(180.0))
    r = polar_range(phi, *circle)
    hit = np.isfinite(r)
    return phi[hit], r[hit]


def _error(result: CircleEkfResult, truth: tuple[float, float, float]) -> FloatArray:
    """``(rho, theta, R)`` estimate minus truth (3,), theta wrapped."""
    e = result.circle.vector - np.array(truth)
    e[1] = wrap_angle(e[1])
    return e


def _nees(result: CircleEkfResult, truth: tuple[float, float, float]) -> float:
    """``e^T P^-1 e`` of the 3-D error with the returned (3, 3) covariance."""
    e = _error(result, truth)
    return float(e @ np.linalg.solve(result.covariance, e))


# --- the measurement model and single updates ---------------------------------------------------


@pytest.mark.parametrize("circle", CIRCLES)
@pytest.mark.parametrize("branch", BRANCHES)
def test_four_state_jacobian_matches_central_differences(
    circle: tuple[float, float, float], branch: Branch
) -> None:
    x = np.array([0.03, *circle])  # (r, rho, theta, R), with a range offset
    alpha = math.asin(circle[2] / circle[0])
    phi = circle[1] + np.linspace(-0.9 * alpha, 0.9 * alpha, 9)  # away from the tangents
    z_hat, H = range_model(x, phi, branch)
    assert z_hat.shape == (9,)
    assert H.shape == (9, 4)
    np.testing.assert_array_equal(H[:, 0], 1.0)  # eq. 4.12's leading 1
    np.testing.assert_allclose(z_hat, 0.03 + polar_range(phi, *circle, branch), rtol=1e-15)
    step = 1e-6
    for k in range(4):
        dx = np.zeros(4)
        dx[k] = step
        numeric = (range_model(x + dx, phi, branch)[0] - range_model(x - dx, phi, branch)[0]) / (
            2.0 * step
        )
        np.testing.assert_allclose(H[:, k], numeric, rtol=1e-6, atol=1e-7)


def test_three_state_model_is_eq_3_2_and_its_jacobian() -> None:
    rho, theta, R = CIRCLES[0]
    phi = theta + np.array([-0.1, 0.0, 0.05])
    z_hat, H = range_model([rho, theta, R], phi)
    np.testing.assert_array_equal(z_hat, polar_range(phi, rho, theta, R))
    np.testing.assert_array_equal(H, polar_jacobian(phi, rho, theta, R))


@pytest.mark.parametrize("variant", VARIANTS)
def test_one_update_is_the_closed_form_kalman_step(variant: str) -> None:
    # On the central ray phi = theta: h = r + rho - R and H = (1, 1, 0, -1) ((1, 0, -1) without
    # the offset r). With P = diag(p) the gain is K = P H^T / S and P - K S K^T the new P.
    rho, theta, R = 1.5, math.pi / 2, 0.25
    config = CircleEkfConfig(variant=variant)  # type: ignore[arg-type]
    if variant == "tikhonov":
        x, p, H = np.array([rho, theta, R]), np.array([0.04, 0.01, 0.09]), np.array([1, 0, -1])
        z_hat = rho - R
    else:
        x, p = np.array([0.01, rho, theta, R]), np.array([0.16, 0.04, 0.01, 0.09])
        H, z_hat = np.array([1, 1, 0, -1]), 0.01 + rho - R
    z = 1.30
    S = float(np.sum(p * H**2)) + SIGMA**2  # H P H^T + sigma^2 = sum of the p at H != 0
    K = p * H / S
    step = circle_update(x, np.diag(p), theta, z, config)
    assert step is not None
    x_new, P_new, y = step
    assert y == pytest.approx(z - z_hat, rel=1e-14)
    np.testing.assert_allclose(x_new, x + K * (z - z_hat), rtol=1e-14)
    np.testing.assert_allclose(P_new, np.diag(p) - S * np.outer(K, K), rtol=1e-12, atol=1e-17)
    assert P_new[-2, -2] == pytest.approx(p[-2], rel=1e-14)  # theta untouched on this ray


def test_tikhonov_term_is_the_closed_form_information_update() -> None:
    # P = I: (I + (H^T H + lambda I) / sigma^2)^-1 = (I - H^T H / (a sigma^2 + |H|^2)) / a with
    # a = 1 + lambda / sigma^2 (Sherman-Morrison); the mean moves by the ordinary gain.
    rho, theta, R = 1.5, math.pi / 2, 0.25
    lam = 1e-3
    config = CircleEkfConfig(variant="tikhonov", tikhonov_lambda=lam)
    phi = theta + 0.07
    H = polar_jacobian(phi, rho, theta, R)[0]
    step = circle_update([rho, theta, R], np.eye(3), phi, 1.28, config)
    assert step is not None
    x_new, P_new, y = step
    a = 1.0 + lam / SIGMA**2
    expected = (np.eye(3) - np.outer(H, H) / (a * SIGMA**2 + H @ H)) / a
    np.testing.assert_allclose(P_new, expected, rtol=1e-10, atol=1e-16)
    np.testing.assert_allclose(x_new, [rho, theta, R] + H * y / (H @ H + SIGMA**2), rtol=1e-14)
    # lambda > 0 only shrinks P: the plain update minus a positive semidefinite matrix
    plain = circle_update(
        [rho, theta, R], np.eye(3), phi, 1.28, CircleEkfConfig(variant="tikhonov")
    )
    assert plain is not None
    assert np.linalg.eigvalsh(plain[1] - P_new).min() > 0.0


@pytest.mark.parametrize("variant", VARIANTS)
@pytest.mark.parametrize("lam", [0.0, 0.01])
def test_covariance_stays_symmetric_positive_definite_at_every_step(
    variant: str, lam: float
) -> None:
    circle = CIRCLES[0]
    phi, r = _arc(circle)
    r = r + np.random.default_rng(3).normal(0.0, SIGMA, len(r))
    # a prior of a few cm: with P0 = I Algorithm 4 jumps off the arc after 4 points here
    config = CircleEkfConfig(
        variant=variant,  # type: ignore[arg-type]
        tikhonov_lambda=lam,
        initial_std=(0.05, 0.03, 0.05),
        initial_offset_std_m=0.05,
    )
    x = np.array([1.53, 1.59, 0.23]) if variant == "tikhonov" else np.array([0, 1.53, 1.59, 0.23])
    P = config.initial_covariance
    checked = 0
    for phi_i, r_i in zip(phi, r, strict=True):
        step = circle_update(x, P, phi_i, r_i, config)
        if step is None:
            continue
        x_new, P_new, _ = step
        np.testing.assert_array_equal(P_new, P_new.T)
        assert np.linalg.eigvalsh(P_new).min() > 0.0
        checked += 1
        if 0.0 < x_new[-1] < x_new[-3]:  # as estimate_circle, keep valid circles only
            x, P = x_new, P_new
    assert checked >= len(phi) - 2


# --- noiseless arcs ------------------------------------------------------------------------------

PERTURBATIONS = [(0.05, 0.03, -0.03), (-0.05, -0.02, 0.03)]


@pytest.mark.parametrize(
    ("variant", "linearisation", "circle"),
    [("tikhonov", lin, circle) for lin in ("point", "pass") for circle in CIRCLES]
    # Algorithm 4 on the 7 points of the circle 4 m away is not identifiable: its range offset
    # trades off against rho and R and the passes settle on another circle through the points.
    + [("joseph", "pass", circle) for circle in CIRCLES[:2]],
)
@pytest.mark.parametrize("perturbation", PERTURBATIONS)
def test_noiseless_arc_converges_to_the_truth(
    variant: str,
    linearisation: str,
    circle: tuple[float, float, float],
    perturbation: tuple[float, float, float],
) -> None:
    phi, r = _arc(circle)
    initial = PolarCircle(*(np.array(circle) + perturbation))
    config = CircleEkfConfig(
        variant=variant,  # type: ignore[arg-type]
        linearisation=linearisation,  # type: ignore[arg-type]
        max_passes=40,
        state_tol_m=1e-11,
    )
    result = estimate_circle(phi, r, initial, config)
    assert result.stop_reason == "state_converged"
    np.testing.assert_allclose(_error(result, circle), 0.0, atol=1e-9)
    assert result.mse is not None
    assert result.mse < 1e-18
    assert result.n_rejected <= 3


@pytest.mark.parametrize("variant", VARIANTS)
def test_starting_on_the_truth_stays_there(variant: str) -> None:
    circle = CIRCLES[1]
    phi, r = _arc(circle)
    config = CircleEkfConfig(variant=variant)  # type: ignore[arg-type]
    result = estimate_circle(phi, r, PolarCircle(*circle), config)
    np.testing.assert_allclose(_error(result, circle), 0.0, atol=1e-14)
    assert result.mse == pytest.approx(0.0, abs=1e-28)
    assert (result.n_updates, result.n_missed, result.n_rejected) == (len(phi), 0, 0)
    assert result.stop_reason == "max_passes"
    assert result.passes == 1


# --- noisy arcs: the returned covariance against the error -------------------------------------


def _fraction_in_band(config: CircleEkfConfig, repetitions: int = 100) -> tuple[float, float]:
    """Over ``repetitions`` noisy arcs of the first §4.5 circle (sigma = 0.02 m, fixed seed),
    each started from the truth plus N(0, (3 cm)^2) on rho and R and the same arc length on
    theta: the fraction of 3-D errors inside the 99 % chi-square band of the returned
    covariance, and the median of ``e^T P^-1 e``."""
    circle = CIRCLES[0]
    phi, r0 = _arc(circle)
    rng = np.random.default_rng(2024)
    nees = []
    for _ in range(repetitions):
        r = r0 + rng.normal(0.0, SIGMA, len(r0))
        offset = rng.normal(0.0, 0.03, 3) * np.array([1.0, 1.0 / circle[0], 1.0])
        result = estimate_circle(phi, r, PolarCircle(*(np.array(circle) + offset)), config)
        nees.append(_nees(result, circle))
    return float(np.mean(np.array(nees) < CHI2_3DOF_99)), float(np.median(nees))


@pytest.mark.parametrize("variant", VARIANTS)
def test_the_seed_filter_is_overconfident(variant: str) -> None:
    # The seed's EKF (one pass, linearised at the running estimate, P0 = I): P0 is so loose
    # next to sigma^2 that the first two or three neighbouring points decide the estimate on
    # their own and throw it off, and P does not know. Measured: 0.52 of the errors inside the
    # 99 % band for Algorithm 4 and 0.42 for Algorithm 1, median NEES 10.4 and 17.6 where a
    # chi-square with 3 dof has 2.37.
    fraction, median = _fraction_in_band(CircleEkfConfig(variant=variant))  # type: ignore[arg-type]
    assert 0.35 <= fraction <= 0.65
    assert median > 6.0


def test_gauss_newton_passes_reach_the_least_squares_consistency() -> None:
    # Passes linearised at their start (Algorithm 1, lambda = 0): measured 0.91 inside the 99 %
    # band, median NEES 2.5. Not 0.99: even the exact least-squares circle with its own
    # linearised covariance lands about 0.9 there on this 19-point arc at sigma = 0.02, the
    # range being far from linear in (rho, theta, R) near the tangent rays. (Algorithm 4 the
    # same way: 0.68, its range offset barely separable from rho and R.)
    config = CircleEkfConfig(
        variant="tikhonov", linearisation="pass", max_passes=10, state_tol_m=1e-6
    )
    fraction, median = _fraction_in_band(config)
    assert fraction >= 0.84
    assert median < 4.0


# --- misses, refused updates and stop rules ------------------------------------------------------


def test_rays_that_miss_are_skipped_and_counted() -> None:
    circle = CIRCLES[0]
    phi, r = _arc(circle)
    config = CircleEkfConfig(variant="tikhonov")
    initial = PolarCircle(1.52, 1.58, 0.24)
    reference = estimate_circle(phi, r, initial, config)
    # rays beside the circle, behind the sensor and at the tangent's edge, with plausible ranges
    extra_phi = circle[1] + np.array([0.5, -0.5, math.pi, 0.2])
    mixed_phi = np.insert(phi, [0, 5, 10, len(phi)], extra_phi)
    mixed_r = np.insert(r, [0, 5, 10, len(r)], [1.4, 1.4, 1.4, 1.4])
    result = estimate_circle(mixed_phi, mixed_r, initial, config)
    assert result.n_missed == reference.n_missed + 4
    assert np.isfinite(result.state).all()
    assert np.isfinite(result.state_covariance).all()
    np.testing.assert_array_equal(result.state, reference.state)
    np.testing.assert_array_equal(result.state_covariance, reference.state_covariance)
    np.testing.assert_array_equal(result.mse_history, reference.mse_history)
    assert circle_update([*circle], np.eye(3), circle[1] + math.pi, 1.0, config) is None


def test_an_update_leaving_no_circle_is_refused() -> None:
    # the central ray at 3 m when the circle puts it at 1.25 m: with P0 = I the update takes
    # R below zero
    circle = CIRCLES[0]
    config = CircleEkfConfig(variant="tikhonov")
    result = estimate_circle([circle[1]], [3.0], PolarCircle(*circle), config)
    assert result.n_rejected == 1
    assert result.stop_reason == "no_update"
    assert result.mse is None
    np.testing.assert_array_equal(result.state, circle)
    np.testing.assert_array_equal(result.state_covariance, config.initial_covariance)


def test_running_mse_is_the_mean_of_the_squared_innovations() -> None:
    circle = CIRCLES[1]
    phi, r = _arc(circle)
    r = r + np.random.default_rng(5).normal(0.0, SIGMA, len(r))
    config = CircleEkfConfig(variant="joseph")
    initial = PolarCircle(1.40, 0.80, 0.26)
    x, P = np.array([0.0, *initial.vector]), config.initial_covariance
    innovations = []
    for phi_i, r_i in zip(phi, r, strict=True):
        step = circle_update(x, P, phi_i, r_i, config)
        if step is not None and 0.0 < step[0][-1] < step[0][-3]:
            x, P, y = step
            innovations.append(y)
    result = estimate_circle(phi, r, initial, config)
    squares = np.square(innovations)
    np.testing.assert_allclose(
        result.mse_history, np.cumsum(squares) / np.arange(1, len(squares) + 1), rtol=1e-12
    )
    np.testing.assert_array_equal(result.state, x)
    np.testing.assert_array_equal(result.state_covariance, P)


@pytest.mark.parametrize("variant", VARIANTS)
def test_rising_mse_stops_and_undoes_the_rising_points(variant: str) -> None:
    # The last 4 points stand 5 cm to 20 cm in front of the circle (a second object): started
    # on the truth, the innovations are 0 up to there, then the running MSE rises at each.
    circle = CIRCLES[0]
    phi, r = _arc(circle)
    r = r.copy()
    r[-4:] -= [0.05, 0.1, 0.15, 0.2]
    config = CircleEkfConfig(variant=variant, mse_rise_limit=3, max_passes=5)  # type: ignore[arg-type]
    result = estimate_circle(phi, r, PolarCircle(*circle), config)
    assert result.stop_reason == "mse_rising"
    assert result.passes == 1
    assert result.n_updates == len(phi) - 4
    np.testing.assert_allclose(_error(result, circle), 0.0, atol=1e-14)
    assert result.mse == pytest.approx(0.0, abs=1e-28)
    np.testing.assert_array_equal(
        result.state_covariance,
        estimate_circle(phi[:-4], r[:-4], PolarCircle(*circle), config).state_covariance,
    )
    without = estimate_circle(phi, r, PolarCircle(*circle), CircleEkfConfig(variant=variant))  # type: ignore[arg-type]
    assert np.abs(_error(without, circle)).max() > 0.005  # the rule did matter


def test_stop_rules_of_the_passes() -> None:
    circle = CIRCLES[0]
    phi, r = _arc(circle)
    initial = PolarCircle(1.55, 1.60, 0.22)
    base = {"variant": "tikhonov", "linearisation": "pass"}
    ran_out = estimate_circle(phi, r, initial, CircleEkfConfig(**base, max_passes=3))  # type: ignore[arg-type]
    assert (ran_out.stop_reason, ran_out.passes) == ("max_passes", 3)
    moved = estimate_circle(
        phi,
        r,
        initial,
        CircleEkfConfig(**base, max_passes=50, state_tol_m=1e-6),  # type: ignore[arg-type]
    )
    assert moved.stop_reason == "state_converged"
    assert 2 <= moved.passes < 50
    np.testing.assert_allclose(_error(moved, circle), 0.0, atol=1e-5)
    flat = estimate_circle(
        phi,
        r,
        initial,
        CircleEkfConfig(**base, max_passes=50, mse_tol_m2=1e-8),  # type: ignore[arg-type]
    )
    assert flat.stop_reason == "mse_converged"
    assert 2 <= flat.passes < 50
    # updates over all passes, the running MSE restarting with each
    assert ran_out.n_updates == len(ran_out.mse_history) == 3 * len(phi) - ran_out.n_missed


def test_no_ray_meeting_the_circle_returns_the_initial_estimate() -> None:
    circle = CIRCLES[0]
    config = CircleEkfConfig()
    result = estimate_circle([0.0, 0.1, 3.0], [1.0, 1.0, 1.0], PolarCircle(*circle), config)
    assert (result.stop_reason, result.n_missed, result.n_updates) == ("no_update", 3, 0)
    assert result.mse is None
    assert result.mse_history.shape == (0,)
    np.testing.assert_array_equal(result.circle.vector, PolarCircle(*circle).vector)
    np.testing.assert_array_equal(result.covariance, np.eye(3))


# --- configuration and bad input -----------------------------------------------------------------


def test_defaults_are_the_seed_algorithm_4() -> None:
    config = CircleEkfConfig()
    assert config.variant == "joseph"
    assert config.range_sigma_m == 0.02
    assert config.state_size == 4
    np.testing.assert_array_equal(config.initial_covariance, np.eye(4))
    assert (config.linearisation, config.max_passes) == ("point", 1)
    np.testing.assert_array_equal(CircleEkfConfig(variant="tikhonov").initial_covariance, np.eye(3))
    scaled = CircleEkfConfig(initial_std=[0.1, 0.2, 0.3], initial_offset_std_m=0.5)  # type: ignore[arg-type]
    assert scaled.initial_std == (0.1, 0.2, 0.3)
    np.testing.assert_allclose(
        np.diag(scaled.initial_covariance), [0.25, 0.01, 0.04, 0.09], rtol=1e-15
    )


@pytest.mark.parametrize(
    ("field", "value", "error"),
    [
        ("variant", "kalman", ValueError),
        ("variant", 1, InvalidTypeError),
        ("branch", "near", ValueError),
        ("range_sigma_m", 0.0, ValueError),
        ("range_sigma_m", -0.02, ValueError),
        ("range_sigma_m", math.nan, ValueError),
        ("range_sigma_m", "0.02", InvalidTypeError),
        ("initial_std", (1.0, 0.0, 1.0), ValueError),
        ("initial_std", (1.0, math.nan, 1.0), ValueError),
        ("initial_std", (1.0, 1.0), ValueError),
        ("initial_std", "abc", InvalidTypeError),
        ("initial_offset_std_m", 0.0, ValueError),
        ("tikhonov_lambda", -1e-3, ValueError),
        ("tikhonov_lambda", math.inf, ValueError),
        ("linearisation", "batch", ValueError),
        ("max_passes", 0, ValueError),
        ("max_passes", 2.0, InvalidTypeError),
        ("max_passes", True, InvalidTypeError),
        ("state_tol_m", 0.0, ValueError),
        ("state_tol_m", math.nan, ValueError),
        ("mse_tol_m2", -1.0, ValueError),
        ("mse_rise_limit", 0, ValueError),
        ("mse_rise_limit", 1.5, InvalidTypeError),
    ],
)
def test_bad_config_raises_naming_the_field(field: str, value: object, error: type) -> None:
    with pytest.raises(error, match=f"CircleEkfConfig.{field}"):
        CircleEkfConfig(**{field: value})  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("phi", "r", "error", "match"),
    [
        ([1.5, 1.6], [1.3], ValueError, "r must have shape"),
        ([1.5, math.nan], [1.3, 1.3], ValueError, "phi must be finite"),
        ([1.5, 1.6], [1.3, math.nan], ValueError, "r must be finite"),
        ([1.5, 1.6], [1.3, 0.0], ValueError, "r must be ranges > 0"),
        ([1.5, 1.6], [1.3, -1.0], ValueError, "r must be ranges > 0"),
        ([], [], ValueError, "at least one point"),
        ([[1.5, 1.6]], [[1.3, 1.3]], ValueError, "phi must have shape"),
        (["a"], [1.3], InvalidTypeError, "phi"),
    ],
)
def test_bad_points_raise_naming_the_argument(
    phi: object, r: object, error: type, match: str
) -> None:
    with pytest.raises(error, match=match):
        estimate_circle(phi, r, PolarCircle(*CIRCLES[0]))  # type: ignore[arg-type]


def test_bad_initial_estimate_and_config_raise() -> None:
    with pytest.raises(InvalidTypeError, match="initial must be a PolarCircle"):
        estimate_circle([1.5], [1.3], (1.5, 1.57, 0.25))  # type: ignore[arg-type]
    with pytest.raises(InvalidTypeError, match="config must be a CircleEkfConfig"):
        estimate_circle([1.5], [1.3], PolarCircle(*CIRCLES[0]), {"variant": "joseph"})  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("x", "P", "phi", "z", "match"),
    [
        ([1.5, 1.57, 0.25], np.eye(3), 1.5, 1.3, "x must have shape"),  # default: 4 states
        ([0.0, 1.5, math.nan, 0.25], np.eye(4), 1.5, 1.3, "x must be finite"),
        ([0.0, 1.5, 1.57, 0.25], np.eye(3), 1.5, 1.3, "P must be a finite"),
        ([0.0, 1.5, 1.57, 0.25], -np.eye(4), 1.5, 1.3, "P must be positive definite"),
        ([0.0, 1.5, 1.57, 0.25], np.eye(4), math.nan, 1.3, "phi must be finite"),
        ([0.0, 1.5, 1.57, 0.25], np.eye(4), 1.5, math.nan, "z must be finite"),
        ([0.0, 1.5, 1.57, 0.25], np.eye(4), 1.5, 0.0, "z must be finite and in"),
    ],
)
def test_bad_update_input_raises_naming_the_argument(
    x: object, P: object, phi: float, z: float, match: str
) -> None:
    with pytest.raises(ValueError, match=match):
        circle_update(x, P, phi, z, CircleEkfConfig())  # type: ignore[arg-type]
