"""Circle EKF SLAM against independent truths: finite differences, a Kalman step written out
densely, a noiseless drive, Monte Carlo chi-square bands, and the association rules."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest
from numpy.typing import ArrayLike
from scipy.stats import chi2

from perception.circles.fits import kcr_covariance
from perception.geometry import FloatArray, compose, relative, wrap_angle
from perception.slam.circle_slam import (
    CircleObservation,
    CircleSlam,
    CircleSlamConfig,
    CircleUpdateResult,
    inverse_observe_circle,
    observe_circle,
)
from perception.validation import InvalidTypeError

# Four columns (c_x, c_y, R) (m, world) around a circular drive of radius 2 m about the origin
COLUMNS = np.array([[3.4, 0.5, 0.15], [-0.5, 3.3, 0.2], [-3.2, -0.6, 0.12], [0.6, -3.5, 0.25]])
DRIVE_RADIUS_M = 2.0
STEP_M = 0.1  # m driven per odometry increment
START = np.array([DRIVE_RADIUS_M, 0.0, math.pi / 2])  # counter-clockwise round the origin
INCREMENT = np.array([STEP_M, 0.0, STEP_M / DRIVE_RADIUS_M])  # the commanded increment
LASER_SIGMA_M = 0.02  # seed 001: Gaussian range noise of the laser
MAX_RANGE_M = 5.0  # m: columns farther than this are not seen
QUIET = np.diag([0.01**2, 0.01**2, 0.005**2])  # (m²) a default observation covariance


def fit_covariance(z: ArrayLike) -> FloatArray:
    """KCR covariance (3, 3) of a circle seen at ``z = (x, y, R)`` (m, robot frame): one point
    per degree of a 180-beam laser over the visible arc, sigma 0.02 m."""
    x, y, R = np.asarray(z, dtype=np.float64)
    rho = math.hypot(x, y)
    n_points = max(4, round(2.0 * math.asin(R / rho) / math.radians(1.0)))
    towards_robot = math.atan2(-y, -x)
    half_arc = 0.9 * math.acos(R / rho)
    return kcr_covariance(towards_robot + np.linspace(-half_arc, half_arc, n_points), LASER_SIGMA_M)


def seen(pose: ArrayLike, column: ArrayLike) -> FloatArray:
    """``(x, y, R)`` (3,) of a world column in the frame of ``pose``, by pose inversion."""
    cx, cy, R = np.asarray(column, dtype=np.float64)
    x, y, _ = relative(pose, (cx, cy, 0.0))
    return np.array([x, y, R])


def scan(
    pose: ArrayLike, columns: ArrayLike, rng: np.random.Generator | None = None
) -> list[CircleObservation]:
    """Observations of the columns in front of the robot within range, noisy with their own
    covariance when ``rng`` is given."""
    observations = []
    for column in np.asarray(columns):
        z = seen(pose, column)
        if z[0] <= 0.0 or math.hypot(z[0], z[1]) > MAX_RANGE_M:
            continue
        Q = fit_covariance(z)
        if rng is not None:
            z = z + np.linalg.cholesky(Q) @ rng.standard_normal(3)
        observations.append(CircleObservation(z[:2], float(z[2]), Q))
    return observations


def nearest_columns(circles: FloatArray, columns: FloatArray = COLUMNS) -> FloatArray:
    """The column (K, 3) nearest each mapped circle's centre."""
    distances = np.hypot(*(circles[:, None, :2] - columns[None, :, :2]).transpose(2, 0, 1))
    return columns[np.argmin(distances, axis=1)]


def numerical_jacobian(f: Callable[[FloatArray], FloatArray], x: ArrayLike) -> FloatArray:
    """Central differences of ``f`` at ``x``, one column per entry of ``x``."""
    x = np.asarray(x, dtype=np.float64)
    eps = 1e-6
    columns = [(f(x + eps * e) - f(x - eps * e)) / (2 * eps) for e in np.eye(len(x))]
    return np.column_stack(columns)


def exact_config(**changes: Any) -> CircleSlamConfig:
    """A config with noiseless odometry and a start pose known exactly."""
    base = CircleSlamConfig(
        translation_noise_m_per_sqrt_m=0.0,
        translation_noise_m_per_sqrt_rad=0.0,
        heading_noise_rad_per_sqrt_m=0.0,
        rotation_noise_rad_per_sqrt_rad=0.0,
        initial_pose_std=(0.0, 0.0, 0.0),
    )
    return dataclasses.replace(base, **changes)


# --- the measurement model -----------------------------------------------------------------------


@pytest.mark.parametrize(
    ("pose", "circle"),
    [((0.0, 0.0, 0.0), (2.0, 0.5, 0.2)), ((1.3, -0.7, 2.9), (-1.0, 2.2, 0.4))],
)
def test_measurement_jacobians_match_central_differences(
    pose: tuple[float, float, float], circle: tuple[float, float, float]
) -> None:
    z_hat, H_pose, H_circle = observe_circle(pose, circle)
    np.testing.assert_allclose(z_hat, seen(pose, circle), atol=1e-12)
    np.testing.assert_allclose(
        H_pose, numerical_jacobian(lambda p: observe_circle(p, circle)[0], pose), atol=1e-8
    )
    np.testing.assert_allclose(
        H_circle, numerical_jacobian(lambda c: observe_circle(pose, c)[0], circle), atol=1e-8
    )
    back, J_pose, J_z = inverse_observe_circle(pose, z_hat)
    np.testing.assert_allclose(back, circle, atol=1e-12)
    np.testing.assert_allclose(
        J_pose, numerical_jacobian(lambda p: inverse_observe_circle(p, z_hat)[0], pose), atol=1e-8
    )
    np.testing.assert_allclose(
        J_z, numerical_jacobian(lambda z: inverse_observe_circle(pose, z)[0], z_hat), atol=1e-8
    )


# --- one step against the textbook ----------------------------------------------------------------


def test_initialisation_and_update_match_dense_kalman_step() -> None:
    pose = np.array([1.0, 2.0, 0.3])
    P0 = np.array([[0.04, 0.01, 0.002], [0.01, 0.09, -0.003], [0.002, -0.003, 0.01]])
    slam = CircleSlam(exact_config(min_views=1), pose, P0)
    Q1 = np.array([[0.02, 0.0, 0.01], [0.0, 0.03, 0.0], [0.01, 0.0, 0.02]])
    z1 = np.array([2.0, -0.5, 0.3])
    result = slam.update([CircleObservation(z1[:2], float(z1[2]), Q1)])
    np.testing.assert_array_equal(result.added, [[0, 0]])

    c, s = math.cos(0.3), math.sin(0.3)
    rot = np.array([[c, -s], [s, c]])
    w = rot @ z1[:2]
    np.testing.assert_allclose(slam.circles[0], [1.0 + w[0], 2.0 + w[1], 0.3], atol=1e-12)
    A = np.array([[1.0, 0.0, -w[1]], [0.0, 1.0, w[0]], [0.0, 0.0, 0.0]])  # d circle / d pose
    B = np.zeros((3, 3))
    B[:2, :2], B[2, 2] = rot, 1.0  # d circle / d z
    expected_cov = np.block([[P0, P0 @ A.T], [A @ P0, A @ P0 @ A.T + B @ Q1 @ B.T]])
    np.testing.assert_allclose(slam.cov, expected_cov, atol=1e-14)

    # a second sighting: z = Rot(-theta) (c - p) + noise, H written out densely
    x, P = slam.mean, slam.cov
    Q2 = np.diag([0.01, 0.02, 0.005])
    z2 = np.array([2.1, -0.45, 0.28])
    d = x[3:5] - x[:2]
    h = np.array([c * d[0] + s * d[1], -s * d[0] + c * d[1], x[5]])
    H = np.array(
        [
            [-c, -s, h[1], c, s, 0.0],
            [s, -c, -h[0], -s, c, 0.0],
            [0.0, 0.0, 0.0, 0.0, 0.0, 1.0],
        ]
    )
    K = P @ H.T @ np.linalg.inv(H @ P @ H.T + Q2)
    result = slam.update([CircleObservation(z2[:2], float(z2[2]), Q2)])
    np.testing.assert_array_equal(result.matched, [[0, 0]])
    np.testing.assert_allclose(slam.mean, x + K @ (z2 - h), atol=1e-12)
    np.testing.assert_allclose(slam.cov, (np.eye(6) - K @ H) @ P, atol=1e-12)


def test_predict_moves_only_pose_rows() -> None:
    config = CircleSlamConfig(min_views=1)
    slam = CircleSlam(config, START)
    slam.update(scan(START, COLUMNS[:1]))
    before = slam.cov
    slam.predict(INCREMENT)
    c, s = math.cos(START[2]), math.sin(START[2])
    G = np.array([[1.0, 0.0, -s * STEP_M], [0.0, 1.0, c * STEP_M], [0.0, 0.0, 1.0]])
    V = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    np.testing.assert_allclose(slam.pose, compose(START, INCREMENT), atol=1e-15)
    d, turn = STEP_M, INCREMENT[2]  # the random walk of the config's noise densities
    var_xy, var_theta = 0.05**2 * d + 0.01**2 * turn, 0.05**2 * d + 0.03**2 * turn
    M = np.diag([var_xy, var_xy, var_theta])
    np.testing.assert_allclose(config.odometry_cov(INCREMENT), M, rtol=1e-15)
    expected_pose_cov = G @ before[:3, :3] @ G.T + V @ M @ V.T
    np.testing.assert_allclose(slam.pose_cov, expected_pose_cov, atol=1e-15)
    np.testing.assert_allclose(slam.cov[:3, 3:], G @ before[:3, 3:], atol=1e-15)
    np.testing.assert_array_equal(slam.cov[3:, 3:], before[3:, 3:])
    slam.predict(INCREMENT, np.diag([1e-4, 2e-4, 3e-4]))  # replaces the config's M
    assert slam.pose_cov[2, 2] == pytest.approx(expected_pose_cov[2, 2] + 3e-4)


# --- a noiseless drive ----------------------------------------------------------------------------


def test_noiseless_drive_keeps_the_truth() -> None:
    # exact odometry and circles, although the filter expects noise: every innovation is zero
    slam = CircleSlam(CircleSlamConfig(), START)
    pose = START.copy()
    for _ in range(189):  # one and a half laps, 0.1 m a step
        pose = compose(pose, INCREMENT)
        slam.predict(INCREMENT)
        result = slam.update(scan(pose, COLUMNS))
        assert len(result.ambiguous) == len(result.refused) == 0
    np.testing.assert_allclose(slam.pose[:2], pose[:2], atol=1e-9)
    assert abs(wrap_angle(slam.pose[2] - pose[2])) < 1e-9
    assert slam.n_circles == len(COLUMNS)
    np.testing.assert_allclose(slam.circles, nearest_columns(slam.circles), atol=1e-9)


# --- Monte Carlo consistency ----------------------------------------------------------------------

RUNS = 30
LAP_INCREMENT = np.array([0.2, 0.0, 0.2 / DRIVE_RADIUS_M])  # m, m, rad: 0.2 m a step
LAP_STEPS = 63  # one lap
LOW_NOISE = CircleSlamConfig(  # a quarter of the default odometry noise densities
    translation_noise_m_per_sqrt_m=0.0125,
    translation_noise_m_per_sqrt_rad=0.0025,
    heading_noise_rad_per_sqrt_m=0.0125,
    rotation_noise_rad_per_sqrt_rad=0.0075,
)


def nees(error: FloatArray, cov: FloatArray) -> float:
    """``e^T P^-1 e`` (unitless)."""
    return float(error @ np.linalg.solve(cov, error))


def monte_carlo(config: CircleSlamConfig, seed: int) -> dict[str, FloatArray]:
    """RUNS noisy laps, odometry and circles drawn from the filter's own noise model.

    Returns per run and step (RUNS, LAP_STEPS) the pose NEES of SLAM and the heading errors
    (rad) of SLAM and of dead reckoning (the same filter, never updated); per run (RUNS,) the
    NEES of the final map (3K dof) and K.
    """
    rng = np.random.default_rng(seed)
    motion_noise = np.linalg.cholesky(config.odometry_cov(LAP_INCREMENT))
    pose_nees, heading, dead_heading = np.zeros((3, RUNS, LAP_STEPS))
    map_nees, n_circles = np.zeros(RUNS), np.zeros(RUNS)
    for run in range(RUNS):
        pose = START + np.asarray(config.initial_pose_std) * rng.standard_normal(3)
        slam, dead_reckoning = CircleSlam(config, START), CircleSlam(config, START)
        for k in range(LAP_STEPS):
            pose = compose(pose, LAP_INCREMENT + motion_noise @ rng.standard_normal(3))
            slam.predict(LAP_INCREMENT)
            dead_reckoning.predict(LAP_INCREMENT)
            slam.update(scan(pose, COLUMNS, rng))
            error = slam.pose - pose
            error[2] = wrap_angle(error[2])
            pose_nees[run, k] = nees(error, slam.pose_cov)
            heading[run, k] = error[2]
            dead_heading[run, k] = wrap_angle(dead_reckoning.pose[2] - pose[2])
        cov = slam.cov
        assert np.array_equal(cov, cov.T) and np.linalg.eigvalsh(cov).min() > 0.0
        truth = nearest_columns(slam.circles)
        assert len(np.unique(truth, axis=0)) == slam.n_circles == len(COLUMNS)
        map_nees[run] = nees((slam.circles - truth).ravel(), cov[3:, 3:])
        n_circles[run] = slam.n_circles
    return {
        "pose_nees": pose_nees,
        "heading": heading,
        "dead_heading": dead_heading,
        "map_nees": map_nees,
        "map_dof": 3 * n_circles,
    }


@pytest.fixture(scope="module")
def low_noise_runs() -> dict[str, FloatArray]:
    return monte_carlo(LOW_NOISE, seed=1)


@pytest.fixture(scope="module")
def default_runs() -> dict[str, FloatArray]:
    return monte_carlo(CircleSlamConfig(), seed=2)


def pose_nees_band() -> tuple[float, float]:
    """95 % band of a pose NEES (3 dof) averaged over RUNS runs."""
    low, high = chi2.ppf([0.025, 0.975], df=3 * RUNS) / RUNS
    return float(low), float(high)


def map_nees_per_dof(runs: dict[str, FloatArray]) -> tuple[float, float, float]:
    """The map NEES summed over the runs per degree of freedom, and its 95 % band."""
    dof = runs["map_dof"].sum()
    low, high = chi2.ppf([0.025, 0.975], df=dof) / dof
    return float(runs["map_nees"].sum() / dof), float(low), float(high)


def test_pose_nees_in_band_and_map_nees_near_it_at_low_noise(
    low_noise_runs: dict[str, FloatArray],
) -> None:
    # Seeds 1-6 measured: average pose NEES 2.61, 3.41, 3.07, 2.99, 3.56, 2.98 (95 % band
    # 2.19-3.94), 97-100 % of the steps inside the band; map NEES per dof 0.97, 0.97, 1.02,
    # 1.01, 1.40, 1.09 (band 0.86-1.15): the EKF's linearisation in the heading leaves a few
    # overconfident runs even at this noise (seed 5: one run of 30 at 3.6 per dof).
    average = low_noise_runs["pose_nees"].mean(axis=0)  # (LAP_STEPS,): averaged over the runs
    low, high = pose_nees_band()
    assert low < average.mean() < high, (low, average.mean(), high)
    assert np.mean((average > low) & (average < high)) > 0.9
    per_dof, low, _ = map_nees_per_dof(low_noise_runs)
    assert low < per_dof < 1.5, (low, per_dof)


def test_default_noise_keeps_the_pose_consistent_but_not_the_map(
    default_runs: dict[str, FloatArray],
) -> None:
    # The EKF's known inconsistency: with the default odometry noise, a heading random walk of
    # 0.18 rad a lap, the linearisation in the heading makes the map overconfident. Seeds 1-6
    # measured: average pose NEES 3.19, 3.41, 3.13, 2.85, 3.68, 2.79 (in the band); map NEES
    # per dof 3.52, 2.57, 2.57, 3.99, 3.15, 1.78, most runs near 1 and a few at 10-50. Not the
    # gates: a 99.99 % gate measured 2.28, 2.56, 2.70 (seeds 1-3); nor the changing
    # linearisation point: first-estimates Jacobians (as EkfSlam's "fej") measured 4.11, 2.42,
    # 2.91.
    low, high = pose_nees_band()
    assert low < default_runs["pose_nees"].mean() < high
    per_dof, low, _ = map_nees_per_dof(default_runs)
    assert low < per_dof < 5.0, per_dof


def test_circles_bound_the_heading_error_that_dead_reckoning_accumulates(
    default_runs: dict[str, FloatArray],
) -> None:
    # Seeds 1-6 measured: final RMS heading error 0.14-0.25 rad by dead reckoning and
    # 0.050-0.066 rad with the circles (ratio 2.8-4.4), which at the end is at most 1.06 times
    # what it was a third of a lap in.
    rms = np.sqrt(np.mean(default_runs["heading"] ** 2, axis=0))
    dead_rms = np.sqrt(np.mean(default_runs["dead_heading"] ** 2, axis=0))
    assert dead_rms[-1] > 2.5 * rms[-1], (dead_rms[-1], rms[-1])
    assert rms[-1] < 1.5 * rms[LAP_STEPS // 3], (rms[-1], rms[LAP_STEPS // 3])


# --- association and the map-building rules -------------------------------------------------------


def drive_straight(
    slam: CircleSlam, columns: FloatArray, steps: int, seed: int
) -> tuple[list[CircleUpdateResult], list[list[int]]]:
    """Drive 0.1 m a step along x from the origin with noisy odometry and circles.

    Returns each update's result and the column index of each of its observations.
    """
    rng = np.random.default_rng(seed)
    step = np.array([0.1, 0.0, 0.0])
    noise = np.linalg.cholesky(slam.config.odometry_cov(step))
    pose, results, seen_columns = np.zeros(3), [], []
    for _ in range(steps):
        pose = compose(pose, step + noise @ rng.standard_normal(3))
        slam.predict(step)
        visible = [j for j, c in enumerate(columns) if scan(pose, c[None])]
        results.append(slam.update(scan(pose, columns[visible], rng)))
        seen_columns.append(visible)
    return results, seen_columns


def test_two_columns_half_a_metre_apart_stay_two_circles() -> None:
    columns = np.array([[3.0, 0.25, 0.1], [3.0, -0.25, 0.1]])
    slam = CircleSlam(CircleSlamConfig(), (0.0, 0.0, 0.0))
    results, seen_columns = drive_straight(slam, columns, 20, seed=3)
    assert slam.n_circles == 2
    truth = nearest_columns(slam.circles, columns)
    assert len(np.unique(truth, axis=0)) == 2
    circle_column = [int(np.flatnonzero((columns == t).all(axis=1))[0]) for t in truth]
    pairs = [
        (circle_column[k], visible[j])
        for result, visible in zip(results, seen_columns, strict=True)
        for k, j in result.matched
    ]
    assert all(column == seen_column for column, seen_column in pairs)  # never swapped
    # each column's first three sightings map it (min_views = 3); of the others, 91-100 % were
    # fused over seeds 0-39 (the rest dropped as ambiguous, never swapped)
    assert len(pairs) >= 0.85 * (sum(map(len, seen_columns)) - 6)


def test_a_column_coming_into_view_is_added_once() -> None:
    columns = np.array([[2.0, 1.0, 0.15], [6.5, -1.0, 0.2]])  # the second beyond 5 m at first
    slam = CircleSlam(CircleSlamConfig(), (0.0, 0.0, 0.0))
    results, seen_columns = drive_straight(slam, columns, 30, seed=4)
    added = [
        (n, k, visible[j])
        for n, (result, visible) in enumerate(zip(results, seen_columns, strict=True))
        for k, j in result.added
    ]
    assert [(k, column) for _, k, column in added] == [(0, 0), (1, 1)]
    first_seen = next(n for n, visible in enumerate(seen_columns) if 1 in visible)
    assert added[1][0] == first_seen + 2  # at its third sighting (min_views = 3)
    assert all(len(r.buffered) == 0 for r in results[added[1][0] + 1 :])
    assert slam.n_circles == 2
    for circle, cov, column in zip(slam.circles, slam.circle_covs, columns, strict=True):
        assert nees(circle - column, cov) < chi2.ppf(0.999, 3)


def test_a_single_spurious_circle_stays_out_of_the_map() -> None:
    config = exact_config()
    slam = CircleSlam(config, START)
    for _ in range(3):
        slam.update(scan(START, COLUMNS))
    assert slam.n_circles == 2  # the two columns in front of the start
    spurious = CircleObservation(np.array([1.5, 0.3]), 0.3, QUIET)
    result = slam.update([*scan(START, COLUMNS), spurious])
    np.testing.assert_array_equal(result.buffered, [2])
    assert len(slam.tentative_circles) == 1
    for n in range(config.min_views_max_age):
        assert len(slam.tentative_circles) == 1, n
        slam.update(scan(START, COLUMNS))
    assert slam.n_circles == 2 and len(slam.tentative_circles) == 0  # forgotten, never mapped
    at_once = CircleSlam(dataclasses.replace(config, min_views=1), START)
    assert len(at_once.update([spurious]).added) == 1  # without the minimal view it is mapped


def test_observation_between_the_gates_is_dropped_as_ambiguous() -> None:
    config = exact_config(min_views=1)
    slam = CircleSlam(config, (0.0, 0.0, 0.0))
    slam.update([CircleObservation(np.array([2.0, 0.0]), 0.2, QUIET)])
    mean, cov = slam.mean, slam.cov
    d2 = 0.5 * (config.gate_threshold + config.new_circle_threshold)  # between the two gates
    offset = math.sqrt(d2 * 2.0 * QUIET[0, 0])  # S = 2 Q: the circle's covariance is Q
    result = slam.update([CircleObservation(np.array([2.0 + offset, 0.0]), 0.2, QUIET)])
    np.testing.assert_array_equal(result.ambiguous, [0])
    np.testing.assert_array_equal(slam.mean, mean)
    np.testing.assert_array_equal(slam.cov, cov)
    far = CircleObservation(np.array([2.0 + 2.0 * offset, 0.0]), 0.2, QUIET)  # beyond both
    np.testing.assert_array_equal(slam.update([far]).added, [[1, 0]])


def test_radius_bounds_refuse_observations_and_corrections_without_clipping() -> None:
    config = exact_config(min_views=1, radius_bounds_m=(0.1, 2.0))
    slam = CircleSlam(config, (0.0, 0.0, 0.0))
    slam.update([CircleObservation(np.array([2.0, 0.0]), 0.15, np.diag([1e-4, 1e-4, 1e-2]))])
    mean, cov = slam.mean, slam.cov
    too_big = CircleObservation(np.array([2.0, 0.0]), 2.5, QUIET)
    # x and R of this fit are correlated (0.99): its x 0.15 m long says its R is too long too,
    # so the Kalman step would take the radius to 0.036 m, below the bound
    Q = np.array([[0.01, 0.0, 0.0099], [0.0, 1e-4, 0.0], [0.0099, 0.0, 0.01]])
    pulls_below = CircleObservation(np.array([2.15, 0.0]), 0.12, Q)
    H = np.hstack([np.zeros((3, 3)), np.eye(3)])
    K = cov @ H.T @ np.linalg.inv(H @ cov @ H.T + Q)
    assert (mean + K @ (pulls_below.z - H @ mean))[5] < 0.1
    result = slam.update([too_big, pulls_below])
    np.testing.assert_array_equal(result.refused, [0, 1])
    assert len(result.matched) == len(result.added) == 0
    np.testing.assert_array_equal(slam.mean, mean)
    np.testing.assert_array_equal(slam.cov, cov)


# --- bad input ------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"heading_noise_rad_per_sqrt_m": -0.1}, "heading_noise_rad_per_sqrt_m"),
        ({"heading_noise_rad_per_sqrt_m": math.nan}, "heading_noise_rad_per_sqrt_m"),
        ({"initial_pose_std": (0.1, 0.1)}, "initial_pose_std"),
        ({"gate_probability": 1.0}, "gate_probability"),
        ({"new_circle_probability": 0.9}, "new_circle_probability must be >= gate_probability"),
        ({"min_views": 0}, "min_views"),
        ({"min_views_radius_m": 0.0}, "min_views_radius_m"),
        ({"min_views_max_age": 2.5}, "min_views_max_age"),
        ({"radius_bounds_m": (0.0, 1.0)}, "radius_bounds_m"),
        ({"radius_bounds_m": (1.0, 0.5)}, "radius_bounds_m"),
    ],
)
def test_config_refuses_bad_fields(changes: dict[str, object], message: str) -> None:
    with pytest.raises(ValueError, match=f"CircleSlamConfig.{message}"):
        CircleSlamConfig(**changes)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("centre", "R", "cov", "message"),
    [
        ([1.0, math.nan], 0.1, QUIET, "CircleObservation.centre must be finite"),
        ([1.0, 0.0, 0.0], 0.1, QUIET, r"CircleObservation.centre must have shape \(2,\)"),
        ([1.0, 0.0], 0.0, QUIET, "CircleObservation.R"),
        ([1.0, 0.0], 0.1, np.eye(2), "CircleObservation.cov"),
        ([1.0, 0.0], 0.1, np.diag([1.0, -1.0, 1.0]), "CircleObservation.cov must be positive"),
        ([1.0, 0.0], 0.1, np.triu(np.ones((3, 3))), "CircleObservation.cov must be symmetric"),
    ],
)
def test_observation_refuses_bad_fields(
    centre: list[float], R: float, cov: FloatArray, message: str
) -> None:
    with pytest.raises(ValueError, match=message):
        CircleObservation(np.array(centre), R, cov)


def test_filter_refuses_bad_arguments_and_stays_unchanged() -> None:
    with pytest.raises(InvalidTypeError, match="config must be a CircleSlamConfig"):
        CircleSlam(object())  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="pose must be finite"):
        CircleSlam(CircleSlamConfig(), (0.0, math.inf, 0.0))
    with pytest.raises(ValueError, match="pose_cov must be positive semidefinite"):
        CircleSlam(CircleSlamConfig(), (0.0, 0.0, 0.0), np.diag([1.0, -1.0, 1.0]))
    slam = CircleSlam(exact_config(min_views=1), (0.0, 0.0, 0.0))
    slam.update(scan((0.0, 0.0, 0.0), [[2.0, 0.0, 0.2]]))
    mean, cov = slam.mean, slam.cov
    with pytest.raises(ValueError, match="increment must have shape"):
        slam.predict([0.1, 0.0])
    with pytest.raises(ValueError, match="increment_cov must be a finite"):
        slam.predict([0.1, 0.0, 0.0], np.eye(2))
    with pytest.raises(InvalidTypeError, match="observations must be a sequence"):
        slam.update(scan((0.0, 0.0, 0.0), [[2.0, 0.0, 0.2]])[0])  # type: ignore[arg-type]
    good = scan((0.0, 0.0, 0.0), [[2.0, 0.0, 0.2]])[0]
    with pytest.raises(InvalidTypeError, match=r"observations\[1\] must be a CircleObservation"):
        slam.update([good, (2.0, 0.0, 0.2)])  # type: ignore[list-item]
    with pytest.raises(ValueError, match="index must be below the 1 mapped circles"):
        slam.measurement(1)
    np.testing.assert_array_equal(slam.mean, mean)
    np.testing.assert_array_equal(slam.cov, cov)
