"""The four EKF SLAM back ends of seed 000 (classic, gated, minimal view, FEJ) against
independent truths: Kalman steps written out by hand, finite-difference Jacobians at the
documented linearisation points, chi-square quantiles from scipy, and the observability rank
argument of Huang, Mourikis & Roumeliotis (ICRA 2008)."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace

import numpy as np
import pytest
from numpy.typing import ArrayLike
from scipy.stats import chi2

from perception.geometry import FloatArray, compose, range_bearing, wrap_angle
from perception.slam import BACKENDS, GATES, EkfSlam, EkfSlamConfig
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


def h(pose: ArrayLike, landmark: ArrayLike) -> FloatArray:
    """Seed eq. 2.11 without noise: (range, bearing) of a field point seen from ``pose``."""
    x, y, t = np.asarray(pose, dtype=np.float64)
    mx, my = np.asarray(landmark, dtype=np.float64)
    return np.array([math.hypot(mx - x, my - y), math.atan2(my - y, mx - x) - t])


def field_position(pose: ArrayLike, z: ArrayLike) -> FloatArray:
    """Where a sighting ``z = (range, bearing)`` taken from ``pose`` puts the landmark."""
    x, y, t = np.asarray(pose, dtype=np.float64)
    r, b = np.asarray(z, dtype=np.float64)
    return np.array([x + r * math.cos(t + b), y + r * math.sin(t + b)])


def jacobian_fd(
    f: Callable[[FloatArray], FloatArray], x: ArrayLike, eps: float = 1e-6
) -> FloatArray:
    """Central finite-difference Jacobian of ``f`` at ``x``; the second output is an angle."""
    x0 = np.asarray(x, dtype=np.float64)
    columns = []
    for i in range(len(x0)):
        step = np.zeros_like(x0)
        step[i] = eps
        diff = f(x0 + step) - f(x0 - step)
        diff[1] = wrap_angle(diff[1])
        columns.append(diff / (2.0 * eps))
    return np.column_stack(columns)


def h_jacobian_fd(pose: ArrayLike, landmark: ArrayLike, column: int, n: int) -> FloatArray:
    """Full-width (2, n) Jacobian of ``h`` at (pose, landmark) for the landmark at ``column``."""
    point = np.concatenate([np.asarray(pose, float), np.asarray(landmark, float)])
    block = jacobian_fd(lambda s: h(s[:3], s[3:]), point)
    H = np.zeros((2, n))
    H[:, :3], H[:, column : column + 2] = block[:, :3], block[:, 3:]
    return H


def kalman_step(
    mu: FloatArray, sigma: FloatArray, H: FloatArray, y: FloatArray, Q: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Textbook EKF correction: ``mu + K y`` and ``(I - K H) Sigma``."""
    S = H @ sigma @ H.T + Q
    K = sigma @ H.T @ np.linalg.inv(S)
    return mu + K @ y, (np.eye(len(mu)) - K @ H) @ sigma


def odometry_cov_written_out(config: EkfSlamConfig, delta: ArrayLike) -> FloatArray:
    """M: variances growing with distance walked and angle turned, per the config's densities."""
    dx, dy, dt = np.asarray(delta, dtype=np.float64)
    d, a = math.hypot(dx, dy), abs(dt)
    var_xy = config.translation_noise_m_per_sqrt_m**2 * d
    var_xy += config.translation_noise_m_per_sqrt_rad**2 * a
    var_t = config.heading_noise_rad_per_sqrt_m**2 * d
    var_t += config.rotation_noise_rad_per_sqrt_rad**2 * a
    return np.diag([var_xy, var_xy, var_t])


def propagate_by_hand(
    config: EkfSlamConfig, sigma: FloatArray, G: FloatArray, theta: float, delta: ArrayLike
) -> FloatArray:
    """``Phi Sigma Phi^T + V M V^T`` with ``Phi = blkdiag(G, I)`` and ``V`` at ``theta``."""
    n = len(sigma)
    Phi = np.eye(n)
    Phi[:3, :3] = G
    c, s = math.cos(theta), math.sin(theta)
    V = np.zeros((n, 3))
    V[:3] = [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
    return Phi @ sigma @ Phi.T + V @ odometry_cov_written_out(config, delta) @ V.T


def assert_symmetric_psd(cov: FloatArray) -> None:
    assert np.array_equal(cov, cov.T)
    assert np.linalg.eigvalsh(cov).min() >= -1e-12


def assert_unchanged(slam: EkfSlam, mean: FloatArray, cov: FloatArray) -> None:
    np.testing.assert_array_equal(slam.mean, mean)
    np.testing.assert_array_equal(slam.cov, cov)


LANDMARKS = np.array([[2.0, 1.0], [-1.5, 2.0], [1.0, -2.5], [-2.0, -1.0]])


def walk(slam: EkfSlam, steps: int, seed: int, outliers: float = 0.0) -> list[int]:
    """Noisy walk among LANDMARKS; returns what each update returned. Same seed, same inputs."""
    rng = np.random.default_rng(seed)
    true_pose = slam.mean[:3]
    fused = []
    for _ in range(steps):
        # About 0.05 m and 0.06 rad a step: circles of ~0.8 m radius among the landmarks.
        delta = np.array(
            [rng.uniform(0.02, 0.08), rng.uniform(-0.02, 0.02), rng.normal(0.06, 0.05)]
        )
        true_pose = compose(true_pose, delta)
        slam.predict(delta + rng.normal(0.0, [0.005, 0.005, 0.005]))
        z = range_bearing(true_pose, LANDMARKS) + rng.normal(0.0, [0.03, 0.02], size=(4, 2))
        wrong = rng.random(4) < outliers
        z[wrong] = np.column_stack([rng.uniform(0.5, 4.0, 4), rng.uniform(-3, 3, 4)])[wrong]
        seen = [j for j in rng.permutation(4)[:2] if z[j, 0] < 4.5]
        fused.append(slam.update([sighting(int(j), z[j]) for j in seen]))
        assert_symmetric_psd(slam.cov)
        assert -math.pi <= slam.mean[2] < math.pi
    return fused


# 1. Configuration


@pytest.mark.parametrize(
    ("kwargs", "min_views", "gate"),
    [
        ({}, 1, "none"),
        ({"backend": "gated"}, 1, "thresholds"),
        ({"backend": "minimal_view"}, 3, "none"),
        ({"backend": "fej"}, 1, "none"),
        ({"backend": "fej", "min_views": 5}, 5, "none"),
        ({"backend": "fej", "min_views": 3, "gate": "mahalanobis"}, 3, "mahalanobis"),
        ({"backend": "gated", "gate": "none"}, 1, "none"),
        ({"backend": "minimal_view", "min_views": 1, "gate": "thresholds"}, 1, "thresholds"),
    ],
)
def test_resolved_min_views_and_gate(kwargs: dict[str, object], min_views: int, gate: str) -> None:
    config = EkfSlamConfig(**kwargs)  # type: ignore[arg-type]
    assert config.resolved_min_views == min_views
    assert config.resolved_gate == gate


def test_backend_and_gate_names() -> None:
    assert BACKENDS == ("classic", "gated", "minimal_view", "fej")
    assert GATES == ("none", "thresholds", "mahalanobis")
    config = EkfSlamConfig()
    assert (config.gate_range_m, config.gate_bearing_rad) == (0.4, math.pi / 3)  # seed §3.2


@pytest.mark.parametrize("p", [0.5, 0.9, 0.99, 0.999])
def test_mahalanobis_threshold_is_the_chi_square_2_quantile(p: float) -> None:
    threshold = EkfSlamConfig(gate_probability=p).gate_mahalanobis_threshold
    assert threshold == pytest.approx(chi2.ppf(p, df=2), rel=1e-12)


@pytest.mark.parametrize(
    ("field", "value", "error"),
    [
        ("backend", "ekf", ValueError),
        ("backend", "Classic", ValueError),
        ("backend", None, TypeError),
        ("backend", 1, TypeError),
        ("gate", "chi2", ValueError),
        ("gate", 0, TypeError),
        ("min_views", 0, ValueError),
        ("min_views", -2, ValueError),
        ("min_views", 2.0, TypeError),
        ("min_views", True, TypeError),
        ("min_views", "3", TypeError),
        ("gate_range_m", 0.0, ValueError),
        ("gate_range_m", -0.4, ValueError),
        ("gate_range_m", math.inf, ValueError),
        ("gate_range_m", "0.4", TypeError),
        ("gate_bearing_rad", math.nan, ValueError),
        ("gate_bearing_rad", 3.2, ValueError),
        ("gate_bearing_rad", 0.0, ValueError),
        ("gate_probability", 1.0, ValueError),
        ("gate_probability", 0.0, ValueError),
        ("gate_probability", True, TypeError),
        ("min_views_radius_m", 0.0, ValueError),
        ("min_views_radius_m", None, TypeError),
    ],
)
def test_bad_backend_config_raises_naming_the_field(
    field: str, value: object, error: type[Exception]
) -> None:
    with pytest.raises(error, match=rf"EkfSlamConfig\.{field} must be"):
        EkfSlamConfig(**{field: value})  # type: ignore[arg-type]


def test_bounds_are_accepted() -> None:
    config = EkfSlamConfig(gate_bearing_rad=math.pi, min_views=1, gate_probability=0.5)
    assert config.gate_bearing_rad == math.pi


def test_counters_are_read_only_copies() -> None:
    slam = EkfSlam(EkfSlamConfig(backend="minimal_view"), [0.0, 0.0, 0.0])
    slam.update([sighting(3, (2.0, 0.1))])
    views = slam.pending_views
    views[3] = 99
    assert slam.pending_views == {3: 1}
    with pytest.raises(AttributeError):
        slam.rejected = 5  # type: ignore[misc]
    with pytest.raises(AttributeError):
        slam.pending_views = {}  # type: ignore[misc]


# 2. Back ends that must reproduce the classic filter


@pytest.mark.parametrize(
    "kwargs",
    [
        pytest.param({"gate": "none", "min_views": 1}, id="classic-explicit"),
        pytest.param({"backend": "gated", "gate": "none"}, id="gated-no-gate"),
        pytest.param({"backend": "gated"}, id="gated-thresholds-nothing-rejected"),
        pytest.param({"backend": "gated", "gate": "mahalanobis", "gate_probability": 1 - 1e-9}),
        pytest.param({"backend": "minimal_view", "min_views": 1}, id="minimal-view-n1"),
    ],
)
def test_unfiltered_back_ends_reproduce_classic_bit_for_bit(kwargs: dict[str, object]) -> None:
    classic = EkfSlam(EkfSlamConfig(), [0.2, -0.1, 0.3])
    other = EkfSlam(EkfSlamConfig(**kwargs), [0.2, -0.1, 0.3])  # type: ignore[arg-type]
    fused_classic = walk(classic, 60, seed=11)
    fused_other = walk(other, 60, seed=11)
    assert other.rejected == 0 and other.pending_views == {}
    assert fused_other == fused_classic
    assert sum(fused_classic) > 60  # corrections happened, not only additions
    np.testing.assert_array_equal(other.mean, classic.mean)
    np.testing.assert_array_equal(other.cov, classic.cov)


def test_fej_matches_classic_until_a_correction_moves_the_estimate() -> None:
    config = EkfSlamConfig(initial_pose_std=(0.1, 0.1, 0.05))
    classic, fej = (
        EkfSlam(config, [0.0, 0.0, 0.0]),
        EkfSlam(replace(config, backend="fej"), [0, 0, 0]),
    )
    steps = [
        ((0.1, 0.02, 0.1), [sighting(1, (2.0, 0.4))]),
        ((0.05, -0.03, -0.2), [sighting(2, (1.5, -0.7))]),
        ((0.1, 0.0, 0.3), []),
        ((0.08, 0.01, 0.0), [sighting(1, (1.85, 0.05))]),  # first correction: same points
    ]
    for delta, observations in steps:
        for slam in (classic, fej):
            slam.predict(delta)
            slam.update(observations)
        np.testing.assert_allclose(fej.mean, classic.mean, rtol=0, atol=1e-14)
        np.testing.assert_allclose(fej.cov, classic.cov, rtol=0, atol=1e-14)
    for slam in (classic, fej):  # now the pose and landmark 2 sit off their linearisation points
        slam.update([sighting(2, (1.6, -0.5))])
        slam.predict((0.1, 0.0, 0.1))
    assert np.abs(fej.cov - classic.cov).max() > 1e-6


# 3. One landmark, known motion: the Kalman step by hand


@pytest.mark.parametrize(
    "kwargs",
    [
        pytest.param({}, id="classic"),
        pytest.param({"backend": "gated"}, id="gated"),
        pytest.param({"backend": "minimal_view", "min_views": 1}, id="minimal-view-n1"),
        pytest.param({"backend": "fej"}, id="fej"),
    ],
)
def test_one_landmark_kalman_step_by_hand(kwargs: dict[str, object]) -> None:
    config = EkfSlamConfig(initial_pose_std=(0.1, 0.1, 0.05), **kwargs)  # type: ignore[arg-type]
    slam = EkfSlam(config, [0.0, 0.0, 0.0])
    Q = np.diag([0.04**2, 0.02**2])
    slam.update([sighting(7, (2.0, 0.0), Q)])  # landmark at (2, 0)
    sigma0 = np.diag([0.1**2, 0.1**2, 0.05**2])
    A = np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 0, 0], [0, 1, 2.0]])  # d(state)/d(pose)
    B = np.array([[0, 0], [0, 0], [0, 0], [1, 0], [0, 2.0]])  # d(m)/d(range, bearing) at r=2
    sigma = A @ sigma0 @ A.T + B @ Q @ B.T
    np.testing.assert_allclose(slam.mean, [0, 0, 0, 2, 0], rtol=0, atol=1e-15)
    np.testing.assert_allclose(slam.cov, sigma, rtol=0, atol=1e-15)

    slam.predict([0.5, 0.0, 0.0])  # straight ahead: G has dy/dtheta = 0.5, V = I
    Phi = np.eye(5)
    Phi[1, 2] = 0.5
    M = np.zeros((5, 5))
    M[:2, :2] = np.eye(2) * config.translation_noise_m_per_sqrt_m**2 * 0.5
    M[2, 2] = config.heading_noise_rad_per_sqrt_m**2 * 0.5
    sigma = Phi @ sigma @ Phi.T + M
    mu = np.array([0.5, 0.0, 0.0, 2.0, 0.0])
    np.testing.assert_allclose(slam.mean, mu, rtol=0, atol=1e-15)
    np.testing.assert_allclose(slam.cov, sigma, rtol=0, atol=1e-15)

    # Landmark 1.5 m straight ahead: d range = (-1, 0, 0, 1, 0),
    # d bearing = (0, -1/1.5, -1, 0, 1/1.5).
    H = np.array([[-1.0, 0.0, 0.0, 1.0, 0.0], [0.0, -1 / 1.5, -1.0, 0.0, 1 / 1.5]])
    z = np.array([1.45, 0.02])
    y = z - np.array([1.5, 0.0])
    S = H @ sigma @ H.T + Q
    K = sigma @ H.T @ np.linalg.inv(S)
    assert slam.update([sighting(7, z, Q)]) == 1
    np.testing.assert_allclose(slam.mean, mu + K @ y, rtol=0, atol=1e-13)
    np.testing.assert_allclose(slam.cov, (np.eye(5) - K @ H) @ sigma, rtol=0, atol=1e-13)


# 4. Threshold gate (seed §3.2: 0.4 m in range, pi/3 in bearing)


def mapped_landmark_filter(config: EkfSlamConfig, z: ArrayLike) -> EkfSlam:
    """A filter at the origin with landmark 4 mapped from sighting ``z``."""
    slam = EkfSlam(config, [0.0, 0.0, 0.0])
    slam.update([sighting(4, z)])
    return slam


@pytest.mark.parametrize(
    ("z", "fused"),
    [
        pytest.param((2.39, 0.3), True, id="range+0.39"),
        pytest.param((2.41, 0.3), False, id="range+0.41"),
        pytest.param((1.61, 0.3), True, id="range-0.39"),
        pytest.param((1.59, 0.3), False, id="range-0.41"),
        pytest.param((2.0, 0.3 + math.pi / 3 - 0.01), True, id="bearing+inside"),
        pytest.param((2.0, 0.3 + math.pi / 3 + 0.01), False, id="bearing+outside"),
        pytest.param((2.0, 0.3 - math.pi / 3 + 0.01), True, id="bearing-inside"),
        pytest.param((2.0, 0.3 - math.pi / 3 - 0.01), False, id="bearing-outside"),
    ],
)
def test_threshold_gate(z: tuple[float, float], fused: bool) -> None:
    slam = mapped_landmark_filter(EkfSlamConfig(backend="gated"), (2.0, 0.3))
    check_gate(slam, sighting(4, z), fused)
    ungated = mapped_landmark_filter(EkfSlamConfig(), (2.0, 0.3))
    check_gate(ungated, sighting(4, z), True)  # the gate, not the filter, rejects


@pytest.mark.parametrize(
    ("offset", "fused"),
    [(math.pi / 3 - 0.01, True), (math.pi / 3 + 0.01, False), (-math.pi / 3 - 0.01, False)],
)
def test_threshold_gate_wraps_the_bearing_across_pi(offset: float, fused: bool) -> None:
    slam = mapped_landmark_filter(EkfSlamConfig(backend="gated"), (2.0, 2.9))  # nearly behind
    bearing = float(wrap_angle(2.9 + offset))
    if offset > 0:
        assert bearing < 0  # the sighting is reported on the other side of ±pi
    check_gate(slam, sighting(4, (2.0, bearing)), fused)


def check_gate(slam: EkfSlam, observation: LandmarkObservation, fused: bool) -> None:
    """Update with one sighting; it is fused, or rejected leaving the filter bit-for-bit."""
    mean, cov, rejected = slam.mean, slam.cov, slam.rejected
    assert slam.update([observation]) == int(fused)
    assert slam.rejected == rejected + (not fused)
    if fused:
        assert np.abs(slam.mean - mean).max() > 1e-4
    else:
        assert_unchanged(slam, mean, cov)


def test_gate_rejects_only_the_outlier_of_a_batch() -> None:
    slam = EkfSlam(EkfSlamConfig(backend="gated"), [0.0, 0.0, 0.0])
    slam.update([sighting(1, (2.0, 0.3)), sighting(2, (1.5, -1.0))])
    reference = EkfSlam(EkfSlamConfig(), [0.0, 0.0, 0.0])
    reference.update([sighting(1, (2.0, 0.3)), sighting(2, (1.5, -1.0))])
    batch = [sighting(1, (2.05, 0.32)), sighting(2, (3.0, -1.0)), sighting(9, (1.0, 0.0))]
    assert slam.update(batch) == 2  # landmark 1 corrected, landmark 9 added
    assert slam.rejected == 1
    reference.update([batch[0], batch[2]])
    np.testing.assert_array_equal(slam.mean, reference.mean)
    np.testing.assert_array_equal(slam.cov, reference.cov)


# 5. Mahalanobis gate at the chi-square boundary


@pytest.mark.parametrize(("factor", "fused"), [(0.999, True), (1.001, False)])
@pytest.mark.parametrize("backend", ["gated", "fej"])
def test_mahalanobis_gate_at_the_chi_square_boundary(
    factor: float, fused: bool, backend: str
) -> None:
    p = 0.95
    config = EkfSlamConfig(
        backend=backend,
        gate="mahalanobis",
        gate_probability=p,
        initial_pose_std=(0.1, 0.1, 0.05),
    )
    slam = EkfSlam(config, [0.0, 0.0, 0.0])
    slam.update([sighting(4, (2.0, 0.3)), sighting(5, (1.2, -0.8))])
    slam.predict([0.3, 0.1, 0.2])
    slam.update([sighting(5, (0.95, -1.1))])  # moves the estimates off FEJ's first estimates
    mu, sigma = slam.mean, slam.cov
    if backend == "fej":  # the step's predicted pose and landmark 4's first estimate
        pose, landmark = slam.predicted_pose, field_position([0.0, 0.0, 0.0], (2.0, 0.3))
    else:
        pose, landmark = mu[:3], mu[3:5]
    H = h_jacobian_fd(pose, landmark, 3, len(mu))
    S = H @ sigma @ H.T + Q_DEFAULT
    u = np.array([1.0, -2.0]) / math.sqrt(5.0)
    alpha = math.sqrt(chi2.ppf(p, df=2) / (u @ np.linalg.solve(S, u)))
    z = h(mu[:3], mu[3:5]) + factor * alpha * u
    observation = sighting(4, z)
    y_filter, S_filter = slam.innovation(observation)
    np.testing.assert_allclose(y_filter, factor * alpha * u, rtol=0, atol=1e-12)
    np.testing.assert_allclose(S_filter, S, rtol=1e-7, atol=0)
    check_gate(slam, observation, fused)


# 6. Minimal view


def test_minimal_view_adds_at_the_nth_consistent_sighting_from_the_last() -> None:
    config = EkfSlamConfig(backend="minimal_view", initial_pose_std=(0.05, 0.05, 0.03))
    slam = EkfSlam(config, [0.0, 0.0, 0.0])
    dead_reckoning = EkfSlam(EkfSlamConfig(initial_pose_std=(0.05, 0.05, 0.03)), [0, 0, 0])
    landmark = np.array([2.0, 1.0])
    deltas = [(0.2, 0.0, 0.3), (0.1, 0.1, -0.5), (0.0, 0.2, 0.4)]
    jitters = [(0.05, 0.01), (-0.06, -0.02), (0.02, 0.015)]  # field positions within 0.1 m
    for n, (delta, jitter) in enumerate(zip(deltas, jitters, strict=True), start=1):
        slam.predict(delta)
        dead_reckoning.predict(delta)
        z = h(slam.mean[:3], landmark) + jitter  # from a moving robot: the same field spot
        fused = slam.update([sighting(6, z)])
        if n < 3:
            assert fused == 0 and slam.landmark_ids == () and slam.pending_views == {6: n}
            assert_unchanged(slam, dead_reckoning.mean, dead_reckoning.cov)
    assert fused == 1 and slam.landmark_ids == (6,) and slam.pending_views == {}
    np.testing.assert_allclose(slam.mean[3:], field_position(slam.mean[:3], z), atol=1e-12)
    dead_reckoning.update([sighting(6, z)])  # classic: the same sighting as the first one
    np.testing.assert_array_equal(slam.mean, dead_reckoning.mean)
    np.testing.assert_array_equal(slam.cov, dead_reckoning.cov)


@pytest.mark.parametrize(
    ("z", "count"),
    [
        pytest.param((2.05 + 0.49, 0.0), 3, id="0.49m-farther"),
        pytest.param((2.05 + 0.51, 0.0), 1, id="0.51m-farther"),
        pytest.param((2.05 - 0.49, 0.0), 3, id="0.49m-nearer"),
        pytest.param((2.05, 0.24), 3, id="0.49m-sideways"),  # 2 * 2.05 * sin(0.12) = 0.49 m
        pytest.param((2.05, 0.26), 1, id="0.53m-sideways"),  # a bearing-only offset counts too
    ],
)
def test_minimal_view_radius_around_the_buffer_mean(z: tuple[float, float], count: int) -> None:
    slam = EkfSlam(EkfSlamConfig(backend="minimal_view", min_views=4), [0.0, 0.0, 0.0])
    slam.update([sighting(2, (2.0, 0.0)), sighting(2, (2.1, 0.0))])  # buffer mean (2.05, 0)
    assert slam.pending_views == {2: 2}
    slam.update([sighting(2, z)])
    assert slam.pending_views == {2: count} and slam.landmark_ids == ()


def test_minimal_view_restart_then_add_from_the_new_place() -> None:
    slam = EkfSlam(EkfSlamConfig(backend="minimal_view"), [0.5, -0.5, 1.0])
    ranges = [2.0, 2.1, 3.0, 3.05, 2.98]  # a false first place, then the true one
    counts = [1, 2, 1, 2]
    for r, count in zip(ranges[:-1], counts, strict=True):
        assert slam.update([sighting(8, (r, 0.2))]) == 0
        assert slam.pending_views == {8: count}
    assert slam.update([sighting(8, (ranges[-1], 0.2))]) == 1
    np.testing.assert_allclose(
        slam.mean[3:], field_position([0.5, -0.5, 1.0], (2.98, 0.2)), rtol=0, atol=1e-12
    )


def test_minimal_view_buffers_are_per_landmark() -> None:
    slam = EkfSlam(EkfSlamConfig(backend="minimal_view"), [0.0, 0.0, 0.0])
    slam.update([sighting(1, (2.0, 0.5)), sighting(2, (1.5, -0.5))])
    slam.update([sighting(2, (2.5, -0.5)), sighting(1, (2.02, 0.5))])  # 2 jumps 1 m: restarts
    assert slam.pending_views == {1: 2, 2: 1}
    assert slam.update([sighting(1, (1.98, 0.5)), sighting(2, (2.5, -0.52))]) == 1
    assert slam.landmark_ids == (1,) and slam.pending_views == {2: 2}
    # A mapped landmark's sightings are fused, not buffered.
    assert slam.update([sighting(1, (2.0, 0.49)), sighting(2, (2.48, -0.5))]) == 2
    assert slam.landmark_ids == (1, 2) and slam.pending_views == {}


# 7. FEJ linearisation points


def fej_after_a_correction() -> tuple[EkfSlam, FloatArray, FloatArray]:
    """FEJ with landmark 1 mapped in step 0, landmark 2 in step 1, a correction by 1 in step 2.

    Returns the filter and the first estimates of landmarks 1 and 2. (Landmarks mapped from
    the same pose would not do: with first-estimate Jacobians a sighting of one tells nothing
    about the other, whose estimate then stays put.)
    """
    config = EkfSlamConfig(backend="fej", initial_pose_std=(0.1, 0.1, 0.05))
    slam = EkfSlam(config, [0.0, 0.0, 0.0])
    z1, z2 = (2.0, 0.4), (1.6, -0.6)
    slam.update([sighting(1, z1)])
    slam.predict([0.2, 0.05, 0.1])
    first1, first2 = field_position([0, 0, 0], z1), field_position(slam.mean[:3], z2)
    slam.update([sighting(2, z2)])
    slam.predict([0.15, -0.05, 0.2])
    slam.update([sighting(1, (1.6, 0.05))])
    return slam, first1, first2


def test_fej_measurement_jacobian_at_predicted_pose_and_first_estimate() -> None:
    slam, first1, first2 = fej_after_a_correction()
    mu, sigma, predicted = slam.mean, slam.cov, slam.predicted_pose
    step1 = compose([0, 0, 0], [0.2, 0.05, 0.1])
    np.testing.assert_allclose(predicted, compose(step1, [0.15, -0.05, 0.2]), atol=1e-15)
    assert np.hypot(*(mu[:2] - predicted[:2])) > 1e-3  # the correction moved the pose...
    assert np.hypot(*(mu[5:7] - first2)) > 1e-3  # ...and landmark 2 through their correlation
    pose, landmark = slam.linearisation_point(2)
    np.testing.assert_array_equal(pose, predicted)
    np.testing.assert_allclose(landmark, first2, rtol=0, atol=1e-15)

    H = h_jacobian_fd(predicted, first2, 5, len(mu))
    np.testing.assert_allclose(slam.measurement_jacobian(2), H, rtol=0, atol=1e-8)
    z = np.array([1.55, -0.75])
    y = z - h(mu[:3], mu[5:7])  # innovation at the current estimate
    expected_mean, expected_cov = kalman_step(mu, sigma, H, y, Q_DEFAULT)
    slam.update([sighting(2, z)])
    np.testing.assert_allclose(slam.mean, expected_mean, rtol=0, atol=1e-9)
    np.testing.assert_allclose(slam.cov, expected_cov, rtol=0, atol=1e-9)

    slam.predict([0.1, 0.0, -0.2])  # next step: landmark 1 still at its first estimate
    assert np.hypot(*(slam.mean[3:5] - first1)) > 1e-3
    H1 = h_jacobian_fd(slam.predicted_pose, first1, 3, len(mu))
    np.testing.assert_allclose(slam.measurement_jacobian(1), H1, rtol=0, atol=1e-8)


def test_classic_measurement_jacobian_at_the_current_estimate() -> None:
    config = EkfSlamConfig(initial_pose_std=(0.1, 0.1, 0.05))
    slam = EkfSlam(config, [0.0, 0.0, 0.0])
    slam.update([sighting(1, (2.0, 0.4)), sighting(2, (1.6, -0.6))])
    slam.predict([0.2, 0.05, 0.1])
    slam.update([sighting(1, (1.7, 0.2))])
    mu = slam.mean
    pose, landmark = slam.linearisation_point(2)
    np.testing.assert_array_equal(pose, mu[:3])
    np.testing.assert_array_equal(landmark, mu[5:7])
    H = h_jacobian_fd(mu[:3], mu[5:7], 5, len(mu))
    np.testing.assert_allclose(slam.measurement_jacobian(2), H, rtol=0, atol=1e-8)
    with pytest.raises(ValueError, match="landmark_id 3 is not mapped"):
        slam.linearisation_point(3)


@pytest.mark.parametrize("backend", ["fej", "classic"])
def test_motion_jacobian_linearisation_point(backend: str) -> None:
    """FEJ's G uses p_{k+1|k} - p_{k|k-1}; classic's p_{k+1|k} - p_{k|k}."""
    config = EkfSlamConfig(backend=backend, initial_pose_std=(0.1, 0.1, 0.05))
    slam = EkfSlam(config, [0.0, 0.0, 0.0])
    slam.update([sighting(1, (2.0, 0.4)), sighting(2, (1.6, -0.6))])
    slam.predict([0.2, 0.05, 0.1])
    p_prior = slam.mean[:3]  # p_{1|0}
    slam.update([sighting(1, (1.7, 0.2))])
    mu, sigma = slam.mean, slam.cov  # p_{1|1} != p_{1|0}
    assert np.hypot(*(mu[:2] - p_prior[:2])) > 1e-3
    delta = np.array([0.15, -0.05, 0.25])
    slam.predict(delta)
    p_next = compose(mu[:3], delta)  # p_{2|1}
    np.testing.assert_allclose(slam.mean[:3], p_next, rtol=0, atol=1e-15)
    base = p_prior if backend == "fej" else mu[:3]
    G = np.array(
        [[1, 0, -(p_next[1] - base[1])], [0, 1, p_next[0] - base[0]], [0, 0, 1]], dtype=float
    )
    np.testing.assert_allclose(slam.motion_jacobian, G, rtol=0, atol=1e-15)
    expected = propagate_by_hand(config, sigma, G, float(mu[2]), delta)
    np.testing.assert_allclose(slam.cov, expected, rtol=0, atol=1e-14)


def test_predicted_pose_starts_at_the_initial_pose() -> None:
    """``p_{0|-1}``: the first FEJ predict takes G from the initial pose."""
    slam = EkfSlam(EkfSlamConfig(backend="fej"), [0.3, -0.2, 0.5 + 2 * math.pi])
    np.testing.assert_allclose(slam.predicted_pose, [0.3, -0.2, 0.5], rtol=0, atol=1e-15)
    np.testing.assert_array_equal(slam.motion_jacobian, np.eye(3))
    slam.predict([0.1, 0.0, 0.2])
    p = compose([0.3, -0.2, 0.5], [0.1, 0.0, 0.2])
    G = np.array([[1, 0, -(p[1] + 0.2)], [0, 1, p[0] - 0.3], [0, 0, 1]], dtype=float)
    np.testing.assert_allclose(slam.motion_jacobian, G, rtol=0, atol=1e-15)
    np.testing.assert_array_equal(slam.predicted_pose, slam.mean[:3])


# 8. Observability (Huang, Mourikis & Roumeliotis 2008)


@pytest.mark.parametrize(("backend", "nullity"), [("fej", 3), ("classic", 2)])
def test_two_step_observability_nullspace(backend: str, nullity: int) -> None:
    """``obs = [H_1; H_2 Phi_1]`` of one landmark: FEJ keeps translation and rotation unobservable;
    classic Jacobians after a correction see a spurious direction of heading information."""
    config = EkfSlamConfig(backend=backend, initial_pose_std=(0.3, 0.3, 0.2))
    slam = EkfSlam(config, [0.0, 0.0, 0.0])
    slam.update([sighting(1, (2.0, 0.5))])
    slam.predict([0.3, 0.1, 0.2])
    H1 = slam.measurement_jacobian(1)
    p_prior, first = slam.predicted_pose, field_position([0, 0, 0], (2.0, 0.5))
    slam.update([sighting(1, (1.5, 0.1))])  # a large innovation: moves pose and landmark
    slam.predict([0.3, -0.1, 0.1])
    Phi = np.eye(5)
    Phi[:3, :3] = slam.motion_jacobian
    obs = np.vstack([H1, slam.measurement_jacobian(1) @ Phi])
    singular = np.linalg.svd(obs, compute_uv=False)
    rank = int((singular > 1e-9 * singular[0]).sum())
    assert 5 - rank == nullity, singular
    translations = np.array([[1, 0, 0, 1, 0], [0, 1, 0, 0, 1]], dtype=float).T
    np.testing.assert_allclose(obs @ translations, 0.0, atol=1e-12)
    rotation = np.array([-p_prior[1], p_prior[0], 1.0, -first[1], first[0]])  # about the origin
    if backend == "fej":
        np.testing.assert_allclose(obs @ rotation, 0.0, atol=1e-12)
    else:
        assert singular[2] > 1e-3 * singular[0]  # well away from rank-deficient


# 9. Invariants over long sequences with outliers


@pytest.mark.parametrize(
    "kwargs",
    [
        {},
        {"backend": "gated"},
        {"backend": "gated", "gate": "mahalanobis"},
        {"backend": "minimal_view"},
        {"backend": "fej"},
        {"backend": "fej", "min_views": 5, "gate": "thresholds"},
        {"backend": "fej", "min_views": 3, "gate": "mahalanobis"},
    ],
)
def test_covariance_stays_symmetric_psd_with_outliers(kwargs: dict[str, object]) -> None:
    slam = EkfSlam(EkfSlamConfig(**kwargs), [0.0, 0.0, 0.0])  # type: ignore[arg-type]
    fused = walk(slam, 250, seed=21, outliers=0.15)
    gate = slam.config.resolved_gate
    assert (slam.rejected > 0) == (gate != "none")
    assert sum(fused) + slam.rejected <= 2 * 250
    assert set(slam.landmark_ids) <= {0, 1, 2, 3} and len(slam.landmark_ids) >= 3
    for covariance in slam.estimate().landmark_covs:
        assert np.linalg.eigvalsh(covariance).min() > 0
