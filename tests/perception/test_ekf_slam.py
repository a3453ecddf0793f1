"""EKF SLAM against independent truths: the seed's equations written out here, finite
differences, closed-form Kalman steps, Monte Carlo and chi-square consistency bands."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.typing import ArrayLike
from scipy.stats import chi2

from perception.geometry import (
    FloatArray,
    compose,
    invert,
    range_bearing,
    relative,
    wrap_angle,
)
from perception.slam import EkfSlam, EkfSlamConfig
from perception.slam.ekf_slam import motion
from perception.types import LandmarkObservation

Q_DEFAULT = np.diag([0.05**2, 0.03**2])  # (m², rad²) range and bearing noise of a sighting


def sighting(landmark_id: int, z: ArrayLike, cov: ArrayLike = Q_DEFAULT) -> LandmarkObservation:
    """A LandmarkObservation with ``z = (range m, bearing rad)`` and covariance ``cov``."""
    r, bearing = np.asarray(z, dtype=np.float64)
    return LandmarkObservation(
        landmark_id=landmark_id,
        range_m=float(r),
        bearing_rad=float(bearing),
        cov=np.asarray(cov, dtype=np.float64),
    )


def motion_eq_2_6_to_2_9(pose: ArrayLike, delta: ArrayLike) -> FloatArray:
    """Seed eq. 2.6-2.9: the pose after an odometry increment, through rot1, trans and rot2.

    The increment is turned into a pair of odometry poses first: the previous odometry pose is
    arbitrary (the model only uses their difference), the next is the increment applied to it.
    """
    xb, yb, tb = 0.3, -1.2, 2.2  # previous odometry pose (x̄, ȳ, θ̄)
    dx, dy, dt = np.asarray(delta, dtype=np.float64)
    xb2 = xb + math.cos(tb) * dx - math.sin(tb) * dy  # next odometry pose (x̄', ȳ', θ̄')
    yb2 = yb + math.sin(tb) * dx + math.cos(tb) * dy
    tb2 = tb + dt
    rot1 = math.atan2(yb2 - yb, xb2 - xb) - tb  # eq. 2.6
    trans = math.sqrt((xb - xb2) ** 2 + (yb - yb2) ** 2)  # eq. 2.7
    rot2 = tb2 - tb - rot1  # eq. 2.8
    x, y, t = np.asarray(pose, dtype=np.float64)
    return np.array(  # eq. 2.9
        [x + trans * math.cos(t + rot1), y + trans * math.sin(t + rot1), t + rot1 + rot2]
    )


def h_eq_2_11(state: ArrayLike, j: int) -> FloatArray:
    """Seed eq. 2.11 without noise: (range, bearing) of landmark ``j`` of a full SLAM state."""
    s = np.asarray(state, dtype=np.float64)
    x, y, t = s[:3]
    mx, my = s[3 + 2 * j : 5 + 2 * j]
    return np.array([math.sqrt((mx - x) ** 2 + (my - y) ** 2), math.atan2(my - y, mx - x) - t])


def odometry_cov_written_out(config: EkfSlamConfig, delta: ArrayLike) -> FloatArray:
    """M: variances growing with distance walked and angle turned, per the config's densities."""
    dx, dy, dt = np.asarray(delta, dtype=np.float64)
    d, a = math.hypot(dx, dy), abs(dt)
    var_xy = config.translation_noise_m_per_sqrt_m**2 * d
    var_xy += config.translation_noise_m_per_sqrt_rad**2 * a
    var_t = (
        config.heading_noise_rad_per_sqrt_m**2 * d + config.rotation_noise_rad_per_sqrt_rad**2 * a
    )
    return np.diag([var_xy, var_xy, var_t])


def jacobian_fd(
    f: Callable[[FloatArray], FloatArray],
    x: ArrayLike,
    angular: Sequence[int] = (),
    eps: float = 1e-6,
) -> FloatArray:
    """Central finite-difference Jacobian of ``f`` at ``x``; outputs in ``angular`` are wrapped."""
    x0 = np.asarray(x, dtype=np.float64)
    columns = []
    for i in range(len(x0)):
        step = np.zeros_like(x0)
        step[i] = eps
        diff = f(x0 + step) - f(x0 - step)
        diff[list(angular)] = wrap_angle(diff[list(angular)])
        columns.append(diff / (2.0 * eps))
    return np.column_stack(columns)


def assert_symmetric_psd(cov: FloatArray) -> None:
    assert np.array_equal(cov, cov.T)
    assert np.linalg.eigvalsh(cov).min() >= -1e-12


# 1. Prediction mean


@pytest.mark.parametrize(
    "delta",
    [
        pytest.param((0.06, 0.0, 0.02), id="forward"),
        pytest.param((0.0, 0.04, 0.0), id="sidestep-left"),
        pytest.param((-0.03, -0.02, -0.15), id="back-right-turning"),
        pytest.param((0.0, 0.0, 0.3), id="turn-in-place"),
    ],
)
def test_predict_mean_follows_eq_2_6_to_2_9(delta: tuple[float, float, float]) -> None:
    start = np.array([1.0, -0.5, 2.5])
    slam = EkfSlam(EkfSlamConfig(), start)
    slam.predict(delta)
    expected = motion_eq_2_6_to_2_9(start, delta)
    np.testing.assert_allclose(slam.mean[:2], expected[:2], rtol=0, atol=1e-12)
    assert float(wrap_angle(slam.mean[2] - expected[2])) == pytest.approx(0.0, abs=1e-12)


def test_turn_in_place_leaves_position_exactly_unchanged() -> None:
    start = np.array([1.0, -0.5, 2.5])
    slam = EkfSlam(EkfSlamConfig(), start)
    slam.predict([0.0, 0.0, -0.4])
    assert slam.mean[0] == start[0] and slam.mean[1] == start[1]
    assert slam.mean[2] == pytest.approx(2.1, abs=1e-12)


@settings(max_examples=60, deadline=None)
@given(
    pose=st.tuples(st.floats(-4.5, 4.5), st.floats(-3.0, 3.0), st.floats(-math.pi, math.pi - 1e-9)),
    delta=st.tuples(st.floats(-0.2, 0.2), st.floats(-0.2, 0.2), st.floats(-1.0, 1.0)),
)
def test_predict_then_inverse_increment_returns_to_start(
    pose: tuple[float, float, float], delta: tuple[float, float, float]
) -> None:
    slam = EkfSlam(EkfSlamConfig(), pose)
    slam.predict(delta)
    slam.predict(invert(delta))
    np.testing.assert_allclose(slam.mean[:2], pose[:2], rtol=0, atol=1e-12)
    assert float(wrap_angle(slam.mean[2] - pose[2])) == pytest.approx(0.0, abs=1e-12)
    # Moving there and back adds noise: the pose covariance can only grow.
    growth = slam.cov - np.diag(np.square(EkfSlamConfig().initial_pose_std))
    assert np.linalg.eigvalsh(growth).min() >= -1e-15


# 2. Prediction covariance


def test_predict_covariance_matches_closed_form_for_straight_walk_along_x() -> None:
    config = EkfSlamConfig()
    slam = EkfSlam(config, [0.5, -0.3, 0.0])
    slam.update([sighting(7, (2.0, 0.4))])  # a mapped landmark gives pose-landmark cross terms
    prior = slam.cov
    d = 0.04
    slam.predict([d, 0.0, 0.0])
    # theta = 0 and delta = (d, 0, 0): y' = y + d sin(theta) gives dy'/dtheta = d, and V = I.
    G = np.eye(5)
    G[1, 2] = d
    a2, c2 = config.translation_noise_m_per_sqrt_m**2, config.heading_noise_rad_per_sqrt_m**2
    process = np.zeros((5, 5))
    process[:3, :3] = np.diag([a2 * d, a2 * d, c2 * d])
    np.testing.assert_allclose(slam.cov, G @ prior @ G.T + process, rtol=1e-12, atol=1e-18)
    np.testing.assert_allclose(slam.mean[:3], [0.54, -0.3, 0.0], rtol=0, atol=1e-15)


MOTION_CASES = [
    pytest.param((1.0, -0.5, 2.5), (0.06, 0.0, 0.02), id="forward-rotated"),
    pytest.param((-2.0, 1.0, -1.2), (0.0, 0.05, 0.0), id="sidestep"),
    pytest.param((0.3, 0.2, 0.4), (-0.04, 0.03, -0.3), id="diagonal-turning"),
    pytest.param((0.3, 0.2, 3.1), (0.0, 0.0, 0.25), id="turn-in-place"),
]


@pytest.mark.parametrize(("pose", "delta"), MOTION_CASES)
def test_motion_jacobians_match_finite_differences(
    pose: tuple[float, float, float], delta: tuple[float, float, float]
) -> None:
    _, G, V = motion(pose, delta)
    G_fd = jacobian_fd(lambda p: motion_eq_2_6_to_2_9(p, delta), pose, angular=[2])
    V_fd = jacobian_fd(lambda u: motion_eq_2_6_to_2_9(pose, u), delta, angular=[2])
    np.testing.assert_allclose(G, G_fd, rtol=0, atol=1e-8)
    np.testing.assert_allclose(V, V_fd, rtol=0, atol=1e-8)


@pytest.mark.parametrize(("pose", "delta"), MOTION_CASES)
def test_predict_covariance_is_g_sigma_gt_plus_v_m_vt(
    pose: tuple[float, float, float], delta: tuple[float, float, float]
) -> None:
    config = EkfSlamConfig(initial_pose_std=(0.1, 0.05, 0.08))
    slam = EkfSlam(config, pose)
    slam.update([sighting(1, (1.5, 0.3)), sighting(2, (2.5, -1.0))])
    prior = slam.cov
    slam.predict(delta)
    G = np.eye(7)
    G[:3, :3] = jacobian_fd(lambda p: motion_eq_2_6_to_2_9(p, delta), pose, angular=[2])
    V = np.zeros((7, 3))
    V[:3] = jacobian_fd(lambda u: motion_eq_2_6_to_2_9(pose, u), delta, angular=[2])
    expected = G @ prior @ G.T + V @ odometry_cov_written_out(config, delta) @ V.T
    np.testing.assert_allclose(slam.cov, expected, rtol=0, atol=1e-10)


def test_sidestep_is_no_noisier_than_a_step_forward() -> None:
    config = EkfSlamConfig()
    forward, sideways = EkfSlam(config, [0, 0, 0]), EkfSlam(config, [0, 0, 0])
    forward.predict([0.05, 0.0, 0.0])
    sideways.predict([0.0, 0.05, 0.0])
    f, s = forward.cov, sideways.cov
    # Same total noise; only the lever arm of the heading term (theta -> y vs theta -> x) moves.
    assert np.trace(s) == pytest.approx(np.trace(f), rel=1e-12)
    assert s[0, 0] == pytest.approx(f[1, 1], rel=1e-12) and s[1, 1] == pytest.approx(f[0, 0])


# 3. Correction = closed-form Kalman step


def test_update_equals_closed_form_kalman_step() -> None:
    slam = EkfSlam(EkfSlamConfig(initial_pose_std=(0.1, 0.08, 0.05)), [0.2, 0.1, 0.4])
    slam.update([sighting(3, (2.0, 0.3)), sighting(5, (1.5, -0.8))])
    slam.predict([0.1, 0.05, 0.2])
    mu, sigma = slam.mean, slam.cov
    z = np.array([1.8, 0.25])
    Q = np.array([[0.004, 0.0005], [0.0005, 0.002]])
    H = jacobian_fd(lambda s: h_eq_2_11(s, 0), mu, angular=[1])
    y = z - h_eq_2_11(mu, 0)
    y[1] = wrap_angle(y[1])
    S = H @ sigma @ H.T + Q
    K = sigma @ H.T @ np.linalg.inv(S)
    IKH = np.eye(len(mu)) - K @ H
    observation = sighting(3, z, Q)

    y_filter, S_filter = slam.innovation(observation)
    np.testing.assert_allclose(y_filter, y, rtol=0, atol=1e-12)
    np.testing.assert_allclose(S_filter, S, rtol=1e-8, atol=1e-12)
    slam.update([observation])
    np.testing.assert_allclose(slam.mean, mu + K @ y, rtol=0, atol=1e-9)
    np.testing.assert_allclose(slam.cov, IKH @ sigma @ IKH.T + K @ Q @ K.T, rtol=0, atol=1e-11)


def test_two_sightings_in_one_update_are_fused_sequentially() -> None:
    def fresh() -> EkfSlam:
        slam = EkfSlam(EkfSlamConfig(), [0.0, 0.0, 0.0])
        slam.update([sighting(1, (2.0, 0.5)), sighting(2, (3.0, -0.4))])
        slam.predict([0.1, 0.0, 0.05])
        return slam

    batch, one_by_one = fresh(), fresh()
    observations = [sighting(2, (2.95, -0.47)), sighting(1, (1.93, 0.43))]
    batch.update(observations)
    for observation in observations:
        one_by_one.update([observation])
    np.testing.assert_array_equal(batch.mean, one_by_one.mean)
    np.testing.assert_array_equal(batch.cov, one_by_one.cov)


# 4. Landmark initialisation


def test_first_sighting_initialises_landmark_by_inverse_observation() -> None:
    slam = EkfSlam(EkfSlamConfig(initial_pose_std=(0.05, 0.04, 0.03)), [1.0, -0.5, 0.7])
    slam.update([sighting(1, (1.5, -0.4))])  # an earlier landmark, so Sigma has cross terms
    slam.predict([0.2, 0.05, 0.1])
    mu, sigma = slam.mean, slam.cov
    z = np.array([2.0, 0.6])
    Q = np.diag([0.03**2, 0.02**2])
    slam.update([sighting(9, z, Q)])

    def inverse(state: FloatArray, zz: FloatArray) -> FloatArray:
        x, y, t = state[:3]
        return np.array([x + zz[0] * math.cos(t + zz[1]), y + zz[0] * math.sin(t + zz[1])])

    assert slam.landmark_ids == (1, 9)
    np.testing.assert_array_equal(slam.mean[:5], mu)
    np.testing.assert_allclose(slam.mean[5:], inverse(mu, z), rtol=0, atol=1e-12)
    np.testing.assert_array_equal(slam.cov[:5, :5], sigma)

    # First order, with the inverse observation's Jacobians by finite differences.
    J_state = jacobian_fd(lambda s: inverse(s, z), mu)
    J_z = jacobian_fd(lambda zz: inverse(mu, zz), z)
    A = np.vstack([np.eye(5), J_state])  # (new state) ≈ A (old state) + B z
    B = np.vstack([np.zeros((5, 2)), J_z])
    np.testing.assert_allclose(slam.cov, A @ sigma @ A.T + B @ Q @ B.T, rtol=0, atol=1e-10)

    # Monte Carlo: draw state and measurement, push them through the inverse observation.
    rng = np.random.default_rng(4)
    states = rng.multivariate_normal(mu, sigma, size=200_000)
    zs = rng.multivariate_normal(z, Q, size=len(states))
    angles = states[:, 2] + zs[:, 1]
    m = states[:, :2] + zs[:, :1] * np.column_stack([np.cos(angles), np.sin(angles)])
    mc_cov = np.cov(np.column_stack([states, m]), rowvar=False)
    scale = np.sqrt(np.outer(np.diag(mc_cov), np.diag(mc_cov)))
    assert np.abs((slam.cov - mc_cov) / scale).max() < 0.02  # in correlation units


# 5. Convergence


def test_static_robot_converges_on_three_landmarks() -> None:
    """The map seen from the robot converges like 1/sqrt(n); the pose stays near its prior.

    The map's placement in the field frame is only known as well as the start pose (SLAM cannot
    observe it), so the 1/sqrt(n) bound is on the landmarks' positions relative to the robot.
    """
    rng = np.random.default_rng(5)
    pose = np.array([0.4, -0.2, 0.3])
    truth = {0: np.array([2.4, 0.8]), 1: np.array([-0.6, 2.3]), 2: np.array([1.9, -2.2])}
    slam = EkfSlam(EkfSlamConfig(), pose)  # the prior mean is the true pose
    # RMS position error of a landmark placed by one sighting from a known pose (first order).
    ranges = {j: float(np.hypot(*(m - pose[:2]))) for j, m in truth.items()}
    single_rms = {j: math.sqrt(Q_DEFAULT[0, 0] + r**2 * Q_DEFAULT[1, 1]) for j, r in ranges.items()}
    checkpoints = {1, 4, 16, 64, 256}
    for n in range(1, max(checkpoints) + 1):
        sightings = []
        for j, m in truth.items():
            z = range_bearing(pose, m)[0] + rng.multivariate_normal(np.zeros(2), Q_DEFAULT)
            sightings.append(sighting(j, z))
        slam.update(sightings)
        if n in checkpoints:
            estimate = slam.estimate()
            for j, m in zip(estimate.landmark_ids, estimate.landmarks, strict=True):
                seen = relative(estimate.pose, (*m, 0.0))[:2]
                true_seen = relative(pose, (*truth[int(j)], 0.0))[:2]
                error = float(np.hypot(*(seen - true_seen)))
                assert error < 4.0 * single_rms[int(j)] / math.sqrt(n), (n, j, error)
    pose_error = slam.mean[:3] - pose
    assert np.hypot(*pose_error[:2]) < 0.002 and abs(wrap_angle(pose_error[2])) < 0.01


# 6. Consistency


def test_pose_nees_of_circular_walk_lies_in_chi_square_band() -> None:
    config = EkfSlamConfig()
    landmarks = 3.0 * np.column_stack(
        [np.cos(np.arange(6) * np.pi / 3 + 0.3), np.sin(np.arange(6) * np.pi / 3 + 0.3)]
    )
    radius, step = 1.5, 0.075  # m: circle walked counter-clockwise in 126 odometry increments
    delta = np.array([step, 0.0, step / radius])  # the odometry reports the commanded increment
    motion_noise = np.linalg.cholesky(config.odometry_cov(delta))  # M = L L^T
    sighting_noise = np.linalg.cholesky(Q_DEFAULT)
    start = np.array([radius, 0.0, math.pi / 2])
    runs, steps = 30, 126
    rng = np.random.default_rng(6)
    nees = np.zeros((runs, steps))
    for run in range(runs):
        true_pose = start + np.asarray(config.initial_pose_std) * rng.standard_normal(3)
        slam = EkfSlam(config, start)
        for k in range(steps):
            true_pose = compose(true_pose, delta + motion_noise @ rng.standard_normal(3))
            slam.predict(delta)
            z = range_bearing(true_pose, landmarks) + rng.standard_normal((6, 2)) @ sighting_noise.T
            slam.update([sighting(j, z[j]) for j in range(len(z)) if z[j, 0] < 4.0])
            error = slam.mean[:3] - true_pose
            error[2] = wrap_angle(error[2])
            nees[run, k] = error @ np.linalg.solve(slam.cov[:3, :3], error)
    low, high = chi2.ppf([0.005, 0.995], df=3 * runs) / runs
    assert low < nees.mean() < high, (low, nees.mean(), high)


# 7. Bearing wrap


def test_landmark_right_behind_updates_without_two_pi_jump() -> None:
    slam = EkfSlam(EkfSlamConfig(), [0.0, 0.0, 0.0])
    slam.update([sighting(4, (2.0, math.pi - 0.01))])  # just left of straight behind
    before = slam.mean
    observation = sighting(4, (2.0, -math.pi + 0.01))  # just right of straight behind
    y, _ = slam.innovation(observation)
    assert y[0] == pytest.approx(0.0, abs=1e-12)
    assert y[1] == pytest.approx(0.02, abs=1e-12)  # 0.02 rad apart, not 2 pi - 0.02
    slam.update([observation])
    after = slam.mean
    assert np.hypot(*(after[3:] - before[3:])) < 0.04
    assert np.hypot(*(after[:2] - before[:2])) < 0.01 and abs(after[2] - before[2]) < 0.02


# 8. Invariants and input checks


def test_covariance_stays_symmetric_psd_over_a_long_walk() -> None:
    rng = np.random.default_rng(8)
    landmarks = rng.uniform([-4.5, -3.0], [4.5, 3.0], size=(8, 2))
    slam = EkfSlam(EkfSlamConfig(), [0.0, 0.0, 0.0])
    true_pose = np.zeros(3)
    for k in range(600):
        delta = np.array([rng.uniform(-0.05, 0.1), rng.uniform(-0.05, 0.05), rng.normal(0, 0.1)])
        true_pose = compose(true_pose, delta)
        slam.predict(delta + rng.normal(0.0, [0.01, 0.01, 0.01]))
        if k % 3 == 0:
            z = range_bearing(true_pose, landmarks)
            cov = np.array([[0.01, 0.002], [0.002, 0.004]])
            slam.update([sighting(j, z[j], cov) for j in rng.permutation(len(z))[:3]])
        assert_symmetric_psd(slam.cov)
        assert -math.pi <= slam.mean[2] < math.pi
    estimate = slam.estimate()
    assert estimate.landmark_ids.dtype == np.int64 and estimate.landmark_ids.shape == (8,)
    assert estimate.landmarks.shape == (8, 2) and estimate.landmark_covs.shape == (8, 2, 2)
    for covariance in estimate.landmark_covs:
        assert np.linalg.eigvalsh(covariance).min() > 0


def test_estimate_of_an_empty_map() -> None:
    estimate = EkfSlam(EkfSlamConfig(), [1.0, 2.0, 7.0]).estimate()
    np.testing.assert_allclose(estimate.pose, [1.0, 2.0, 7.0 - 2 * math.pi], rtol=0, atol=1e-12)
    np.testing.assert_array_equal(estimate.pose_cov, np.diag([0.02**2] * 3))
    assert estimate.landmark_ids.shape == (0,) and estimate.landmark_ids.dtype == np.int64
    assert estimate.landmarks.shape == (0, 2) and estimate.landmark_covs.shape == (0, 2, 2)


def _obs(**changes: object) -> LandmarkObservation:
    fields: dict[str, object] = {
        "landmark_id": 1,
        "range_m": 2.0,
        "bearing_rad": 0.1,
        "cov": Q_DEFAULT,
    }
    fields.update(changes)
    return LandmarkObservation(**fields)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("call", "error", "match"),
    [
        (lambda s: s.predict([0.1, 0.0]), ValueError, r"odometry_delta .*shape \(3,\)"),
        (lambda s: s.predict([np.nan, 0.0, 0.0]), ValueError, "odometry_delta must be finite"),
        (lambda s: s.predict([0.0, 0.0, np.inf]), ValueError, "odometry_delta must be finite"),
        (lambda s: s.predict("forward"), TypeError, "odometry_delta"),
        (lambda s: s.update(_obs()), TypeError, "observations must be a sequence"),
        (lambda s: s.update([_obs(), "x"]), TypeError, r"observations\[1\] must be a Landmark"),
        (lambda s: s.update([_obs(range_m=0.0)]), ValueError, r"observations\[0\]\.range_m"),
        (lambda s: s.update([_obs(range_m=-1.0)]), ValueError, r"observations\[0\]\.range_m"),
        (lambda s: s.update([_obs(range_m=np.inf)]), ValueError, r"observations\[0\]\.range_m"),
        (lambda s: s.update([_obs(bearing_rad=np.nan)]), ValueError, r"\.bearing_rad must be"),
        (lambda s: s.update([_obs(landmark_id="a")]), TypeError, r"\.landmark_id must be an int"),
        (lambda s: s.update([_obs(cov=np.eye(3))]), ValueError, r"\.cov must be a finite \(2, 2\)"),
        (lambda s: s.update([_obs(cov=[[1, np.nan], [0, 1]])]), ValueError, r"\.cov must be"),
        (lambda s: s.update([_obs(cov=[[1, 0.1], [0, 1]])]), ValueError, r"\.cov must be symm"),
        (lambda s: s.update([_obs(cov=[[1, 0], [0, -1]])]), ValueError, r"\.cov must be positive"),
        (lambda s: s.update([_obs(cov=np.zeros((2, 2)))]), ValueError, r"\.cov must be positive"),
        (lambda s: s.innovation(_obs(landmark_id=99)), ValueError, "landmark_id 99 is not mapped"),
    ],
)
def test_bad_input_raises_and_names_the_argument(
    call: Callable[[EkfSlam], object], error: type[Exception], match: str
) -> None:
    slam = EkfSlam(EkfSlamConfig(), [0.0, 0.0, 0.0])
    with pytest.raises(error, match=match):
        call(slam)


def test_a_bad_observation_leaves_the_filter_unchanged() -> None:
    slam = EkfSlam(EkfSlamConfig(), [0.0, 0.0, 0.0])
    with pytest.raises(ValueError, match=r"observations\[1\]\.range_m"):
        slam.update([_obs(landmark_id=5), _obs(range_m=np.nan)])
    assert slam.landmark_ids == ()
    np.testing.assert_array_equal(slam.cov, np.diag([0.02**2] * 3))


@pytest.mark.parametrize(
    ("args", "error", "match"),
    [
        ((EkfSlamConfig(), [0.0, 0.0]), ValueError, r"initial_pose must have shape \(3,\)"),
        ((EkfSlamConfig(), [0.0, np.nan, 0.0]), ValueError, "initial_pose must be finite"),
        (("config", [0.0, 0.0, 0.0]), TypeError, "config must be an EkfSlamConfig"),
    ],
)
def test_bad_constructor_arguments_raise(
    args: tuple[object, object], error: type[Exception], match: str
) -> None:
    with pytest.raises(error, match=match):
        EkfSlam(*args)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("translation_noise_m_per_sqrt_m", -0.1),
        ("translation_noise_m_per_sqrt_rad", math.nan),
        ("heading_noise_rad_per_sqrt_m", math.inf),
        ("rotation_noise_rad_per_sqrt_rad", "0.05"),
        ("initial_pose_std", (0.1, 0.1)),
        ("initial_pose_std", (0.1, -0.1, 0.1)),
        ("initial_pose_std", (0.1, 0.1, math.nan)),
    ],
)
def test_bad_config_raises_naming_the_field(field: str, value: object) -> None:
    with pytest.raises(ValueError, match=rf"EkfSlamConfig\.{field} must be"):
        EkfSlamConfig(**{field: value})  # type: ignore[arg-type]
