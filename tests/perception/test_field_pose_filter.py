"""The pose filter against closed forms: textbook Kalman steps written out here, the scalar
Kalman formula along a seen line, EKF SLAM's motion model, chi-square gates and NEES bands."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest
from numpy.typing import ArrayLike
from scipy.stats import chi2

from perception.field.pose_filter import PoseFilter, PoseFilterConfig
from perception.field.pose_observation import PoseObservation
from perception.geometry import FloatArray, compose, wrap_angle
from perception.slam.ekf_slam import EkfSlamConfig, motion

PRIOR_COV = np.array(  # (m², m², rad²): correlated, as after some walking
    [[0.04, 0.01, 0.004], [0.01, 0.03, -0.003], [0.004, -0.003, 0.01]]
)


def observation(pose: ArrayLike, information: ArrayLike) -> PoseObservation:
    """A PoseObservation of ``pose`` (3,) with ``information`` (3, 3)."""
    return PoseObservation(
        pose=np.asarray(pose, dtype=np.float64),
        information=np.asarray(information, dtype=np.float64),
        rms_error_m=0.02,
        features=3,
    )


def filter_at(pose: ArrayLike, cov: ArrayLike = PRIOR_COV, **config: object) -> PoseFilter:
    """A PoseFilter reset to ``pose`` with ``cov``; ``config`` overrides PoseFilterConfig."""
    pose_filter = PoseFilter(PoseFilterConfig(**config), pose)  # type: ignore[arg-type]
    pose_filter.reset(pose, cov)
    return pose_filter


def random_spd(rng: np.random.Generator, scales: ArrayLike) -> FloatArray:
    """A random symmetric positive definite (3, 3) with eigenvalues ``scales`` (3,)."""
    Q, _ = np.linalg.qr(rng.standard_normal((3, 3)))
    C: FloatArray = (Q * np.asarray(scales)) @ Q.T
    return 0.5 * (C + C.T)


def random_information(rng: np.random.Generator, rank: int) -> FloatArray:
    """A random PSD (3, 3) of ``rank`` whose nonzero eigenvalues span 1 to 1e6."""
    Q, _ = np.linalg.qr(rng.standard_normal((3, 3)))
    eigenvalues = np.zeros(3)
    eigenvalues[:rank] = 10.0 ** rng.uniform(0.0, 6.0, rank)
    L: FloatArray = (Q * eigenvalues) @ Q.T
    return 0.5 * (L + L.T)


# 1. Update: closed forms


def test_full_information_observation_is_the_standard_kalman_update() -> None:
    rng = np.random.default_rng(1)
    x = np.array([1.2, -0.7, 0.4])
    L = random_spd(rng, [1 / 0.05**2, 1 / 0.08**2, 1 / 0.03**2])
    z = x + np.array([0.05, -0.03, 0.02])
    pose_filter = filter_at(x, gate_probability=None)
    assert pose_filter.update(observation(z, L))
    R = np.linalg.inv(L)
    K = PRIOR_COV @ np.linalg.inv(PRIOR_COV + R)  # H = I
    np.testing.assert_allclose(pose_filter.pose, x + K @ (z - x), rtol=0, atol=1e-12)
    np.testing.assert_allclose(pose_filter.cov, (np.eye(3) - K) @ PRIOR_COV, rtol=1e-9, atol=0)


def test_information_only_in_y_is_the_scalar_kalman_update() -> None:
    """A line along x (seen from straight on): x's mean and variance stay, y's as in 1-D."""
    prior = np.diag([0.04, 0.03, 0.01])
    prior[0, 2] = prior[2, 0] = 0.004  # x correlated with theta; y with neither
    x = np.array([1.0, 2.0, 0.3])
    sigma_y = 0.05  # m
    z = np.array([-8.0, 2.06, 3.0])  # far off in x and theta, which it does not inform
    pose_filter = filter_at(x, prior)
    assert pose_filter.update(observation(z, np.diag([0.0, 1 / sigma_y**2, 0.0])))
    p_y, r_y = prior[1, 1], sigma_y**2
    assert pose_filter.pose[1] == pytest.approx(2.0 + p_y / (p_y + r_y) * 0.06, abs=1e-12)
    assert pose_filter.cov[1, 1] == pytest.approx(p_y * r_y / (p_y + r_y), rel=1e-12)
    np.testing.assert_allclose(pose_filter.pose[[0, 2]], x[[0, 2]], rtol=0, atol=1e-14)
    np.testing.assert_allclose(
        pose_filter.cov[np.ix_([0, 2], [0, 2])], prior[np.ix_([0, 2], [0, 2])], rtol=1e-13
    )


def test_oblique_line_with_heading_is_the_kalman_update_with_its_two_rows() -> None:
    """A line at 30° plus heading: H = [n^T; e_theta^T], R = diag(1/lambda) by hand."""
    angle, lam_n, lam_t = math.radians(30), 1 / 0.04**2, 1 / 0.02**2
    n = np.array([math.cos(angle), math.sin(angle), 0.0])
    L = lam_n * np.outer(n, n) + lam_t * np.diag([0.0, 0.0, 1.0])
    x = np.array([0.5, 0.5, -1.0])
    z = x + np.array([0.03, 0.02, -0.015]) + 5.0 * np.array([-n[1], n[0], 0.0])  # 5 m along
    pose_filter = filter_at(x)
    assert pose_filter.update(observation(z, L))
    H = np.array([n, [0.0, 0.0, 1.0]])
    R = np.diag([1 / lam_n, 1 / lam_t])
    K = PRIOR_COV @ H.T @ np.linalg.inv(H @ PRIOR_COV @ H.T + R)
    np.testing.assert_allclose(pose_filter.pose, x + K @ H @ (z - x), rtol=0, atol=1e-12)
    np.testing.assert_allclose(pose_filter.cov, (np.eye(3) - K @ H) @ PRIOR_COV, rtol=0, atol=1e-12)


def test_random_updates_equal_the_information_form_and_stay_symmetric_psd() -> None:
    """(P^-1 + L)^-1 and x + P+ L e for random L of every rank, through 300 steps."""
    rng = np.random.default_rng(2)
    pose_filter = filter_at([0.0, 0.0, 0.0], gate_probability=None)
    for step in range(300):
        pose_filter.predict(rng.uniform([-0.1, -0.05, -0.3], [0.1, 0.05, 0.3]))
        x, P = pose_filter.pose, pose_filter.cov
        L = random_information(rng, step % 4)
        z = x + rng.normal(0.0, 0.2, 3)
        fused = pose_filter.update(observation(z, L))
        assert fused == (step % 4 > 0)
        P_plus = np.linalg.inv(np.linalg.inv(P) + L)
        e = z - x
        e[2] = wrap_angle(e[2])
        expected = x + P_plus @ L @ e
        P_new, x_new = pose_filter.cov, pose_filter.pose
        np.testing.assert_allclose(P_new, P_plus, rtol=0, atol=1e-9 * np.abs(P).max())
        np.testing.assert_allclose(x_new[:2], expected[:2], rtol=0, atol=1e-9)
        assert abs(wrap_angle(x_new[2] - expected[2])) < 1e-9
        assert np.array_equal(P_new, P_new.T)
        assert np.linalg.eigvalsh(P_new).min() >= 0.0


def test_covariance_stays_psd_with_a_pinned_component_and_huge_information() -> None:
    pose_filter = filter_at([1.0, 1.0, 0.0], np.diag([0.0, 0.04, 0.01]), gate_probability=None)
    for _ in range(200):
        assert pose_filter.update(observation([1.1, 0.9, 0.1], np.diag([1e12, 1e12, 1e10])))
        assert pose_filter.pose[0] == 1.0  # a zero prior variance keeps x where it is
        P = pose_filter.cov
        assert np.array_equal(P, P.T) and np.linalg.eigvalsh(P).min() >= -1e-15
        assert P[0, 0] == 0.0


def test_heading_residual_wraps_across_pi() -> None:
    p, r = 0.01, 0.01 / 3  # rad²: prior and observation heading variances, gain 3/4
    pose_filter = filter_at([0.0, 0.0, -math.pi + 0.01], np.diag([0.01, 0.01, p]))
    assert pose_filter.update(observation([0.0, 0.0, math.pi - 0.01], np.diag([0, 0, 1 / r])))
    # 0.02 rad apart across the boundary: the estimate moves 3/4 of it, to pi - 0.005
    assert wrap_angle(pose_filter.pose[2] - (math.pi - 0.005)) == pytest.approx(0.0, abs=1e-12)
    assert -math.pi <= pose_filter.pose[2] < math.pi
    assert pose_filter.cov[2, 2] == pytest.approx(p * r / (p + r), rel=1e-12)


def test_observation_without_information_changes_nothing() -> None:
    pose_filter = filter_at([0.3, 0.2, 0.1])
    before = pose_filter.pose
    assert not pose_filter.update(observation([5.0, 5.0, 2.0], np.zeros((3, 3))))
    np.testing.assert_array_equal(pose_filter.pose, before)
    np.testing.assert_array_equal(pose_filter.cov, PRIOR_COV)
    assert pose_filter.rejected == 0
    assert pose_filter.mahalanobis(observation([5.0, 5.0, 2.0], np.zeros((3, 3)))) == (0.0, 0)


# 2. Gate


@pytest.mark.parametrize("sigmas, fused", [(10.0, False), (3.0, False), (1.0, True)])
def test_gate_on_a_line_observation(sigmas: float, fused: bool) -> None:
    """Information in y only: 1 dof, d = |y residual| / sqrt(P_yy + 1 / L_yy); x is free.

    3 sigma (d² = 9) is beyond chi2(1)'s 99 % quantile (6.63) but within chi2(3)'s (11.34).
    """
    pose_filter = filter_at([0.0, 0.0, 0.0])
    L_yy = 1 / 0.05**2
    offset = sigmas * math.sqrt(PRIOR_COV[1, 1] + 1 / L_yy)
    obs = observation([7.0, offset, 0.0], np.diag([0.0, L_yy, 0.0]))  # 7 m off along the line
    d2, dof = pose_filter.mahalanobis(obs)
    assert dof == 1 and d2 == pytest.approx(sigmas**2, rel=1e-12)
    assert pose_filter.gate_threshold(1) == pytest.approx(chi2.ppf(0.99, 1))
    assert pose_filter.update(obs) is fused
    assert pose_filter.rejected == (0 if fused else 1)
    if not fused:
        np.testing.assert_array_equal(pose_filter.pose, [0.0, 0.0, 0.0])
        np.testing.assert_array_equal(pose_filter.cov, PRIOR_COV)


@pytest.mark.parametrize("sigmas, fused", [(10.0, False), (3.0, True), (1.0, True)])
def test_gate_on_a_full_observation(sigmas: float, fused: bool) -> None:
    """3 dof: d² = e^T (P + L^-1)^-1 e, along a random direction scaled to ``sigmas``."""
    rng = np.random.default_rng(3)
    L = random_spd(rng, [400.0, 900.0, 2500.0])
    S = PRIOR_COV + np.linalg.inv(L)
    direction = rng.standard_normal(3)
    e = sigmas * direction / math.sqrt(direction @ np.linalg.solve(S, direction))
    pose_filter = filter_at([1.0, -1.0, 0.5])
    obs = observation(np.array([1.0, -1.0, 0.5]) + e, L)
    d2, dof = pose_filter.mahalanobis(obs)
    assert dof == 3 and d2 == pytest.approx(sigmas**2, rel=1e-9)
    assert pose_filter.gate_threshold(3) == pytest.approx(chi2.ppf(0.99, 3))
    assert pose_filter.update(obs) is fused
    assert pose_filter.rejected == (0 if fused else 1)


def test_no_gate_fuses_an_observation_far_off() -> None:
    pose_filter = filter_at([0.0, 0.0, 0.0], gate_probability=None)
    assert pose_filter.update(observation([3.0, 3.0, 1.0], np.eye(3) * 400.0))
    assert pose_filter.gate_threshold(3) == math.inf


def test_reset_restores_pose_covariance_and_rejection_count() -> None:
    pose_filter = filter_at([0.0, 0.0, 0.0])
    assert not pose_filter.update(observation([3.0, 3.0, 1.0], np.eye(3) * 400.0))
    pose_filter.reset([1.0, 2.0, 4.0])
    np.testing.assert_allclose(pose_filter.pose, [1.0, 2.0, 4.0 - 2 * math.pi])
    np.testing.assert_array_equal(
        pose_filter.cov, np.diag(np.square(EkfSlamConfig().initial_pose_std))
    )
    assert pose_filter.rejected == 0


# 3. Predict


def test_predict_is_ekf_slam_motion_with_the_random_walk_noise() -> None:
    noise: dict[str, Any] = dict(
        translation_noise_m_per_sqrt_m=0.2,
        translation_noise_m_per_sqrt_rad=0.03,
        heading_noise_rad_per_sqrt_m=0.04,
        rotation_noise_rad_per_sqrt_rad=0.07,
    )
    x = np.array([0.4, -1.1, 2.9])
    delta = np.array([0.06, -0.02, 0.4])
    pose_filter = filter_at(x, **noise)
    pose_filter.predict(delta)
    expected, G, V = motion(x, delta)
    d, turn = math.hypot(0.06, -0.02), 0.4  # M written out from the random-walk model
    var_xy = 0.2**2 * d + 0.03**2 * turn
    M = np.diag([var_xy, var_xy, 0.04**2 * d + 0.07**2 * turn])
    np.testing.assert_allclose(pose_filter.pose, expected, rtol=0, atol=1e-15)
    np.testing.assert_allclose(pose_filter.cov, G @ PRIOR_COV @ G.T + V @ M @ V.T, rtol=1e-13)
    np.testing.assert_allclose(
        pose_filter.config.odometry_cov(delta), EkfSlamConfig(**noise).odometry_cov(delta)
    )
    assert -math.pi <= pose_filter.pose[2] < math.pi  # 2.9 + 0.4 wrapped


def test_defaults_are_ekf_slams() -> None:
    config, slam = PoseFilterConfig(), EkfSlamConfig()
    for name in (
        "translation_noise_m_per_sqrt_m",
        "translation_noise_m_per_sqrt_rad",
        "heading_noise_rad_per_sqrt_m",
        "rotation_noise_rad_per_sqrt_rad",
        "initial_pose_std",
    ):
        assert getattr(config, name) == getattr(slam, name), name


# 4. Consistency


def test_nees_of_simulated_runs_lies_in_chi_square_band() -> None:
    """50 runs of 60 steps: a random walk with odometry noise drawn from the filter's model,
    observed every step by full, line-like or heading-only pose observations drawn from their
    information, with arbitrary offsets along the (translation) directions they do not inform.

    The 99 % gate refuses about 1 % of these correct observations, mostly when the filter is
    far off, which lifts the mean NEES by about 3 % (3.08 over 20 seeds; 3.00 without a gate).
    """
    config = PoseFilterConfig()
    runs, steps = 50, 60
    rng = np.random.default_rng(4)
    line_along_x = np.array([[0.0, 0.0, 0.0], [0.0, 400.0, 150.0], [0.0, 150.0, 900.0]])
    J = np.array([[-math.sin(0.7), math.cos(0.7), 0.0], [0.0, 0.0, 1.0]])  # across, heading
    kinds = [
        np.diag([400.0, 600.0, 2500.0]),  # several features: all of the pose
        line_along_x,  # seed eq. 7: y and theta
        np.diag([0.0, 0.0, 2500.0]),  # heading only
        J.T @ np.array([[625.0, 300.0], [300.0, 400.0]]) @ J,  # a line at 0.7 rad
    ]
    nees = np.zeros((runs, steps))
    for run in range(runs):
        start = np.array([-2.0, 1.0, 0.3])
        true_pose = start + np.asarray(config.initial_pose_std) * rng.standard_normal(3)
        pose_filter = PoseFilter(config, start)
        for k in range(steps):
            delta = np.array([0.08, 0.01, rng.uniform(-0.2, 0.2)])  # the odometry's reading
            M = config.odometry_cov(delta)
            true_pose = compose(true_pose, rng.multivariate_normal(delta, M))
            pose_filter.predict(delta)
            L = kinds[k % len(kinds)]
            eigenvalues, U = np.linalg.eigh(L)
            informed = eigenvalues > 1e-9 * eigenvalues.max()
            noise = U[:, informed] @ (
                rng.standard_normal(informed.sum()) / np.sqrt(eigenvalues[informed])
            )
            noise += U[:, ~informed] @ rng.uniform(-3.0, 3.0, (~informed).sum())  # free
            pose_filter.update(observation(true_pose + noise, L))
            error = pose_filter.pose - true_pose
            error[2] = wrap_angle(error[2])
            nees[run, k] = error @ np.linalg.solve(pose_filter.cov, error)
    low, high = chi2.ppf([0.025, 0.975], df=3 * runs) / runs
    per_step = nees.mean(axis=0)
    assert low < nees.mean() < high, (low, nees.mean(), high)
    assert np.mean((per_step > low) & (per_step < high)) >= 0.85, per_step


# 5. Inputs


@pytest.mark.parametrize(
    "field, value, error",
    [
        ("translation_noise_m_per_sqrt_m", -0.1, ValueError),
        ("translation_noise_m_per_sqrt_rad", math.nan, ValueError),
        ("heading_noise_rad_per_sqrt_m", math.inf, ValueError),
        ("rotation_noise_rad_per_sqrt_rad", True, TypeError),
        ("rotation_noise_rad_per_sqrt_rad", "0.1", TypeError),
        ("initial_pose_std", (0.1, 0.1), ValueError),
        ("initial_pose_std", (0.1, -0.1, 0.1), ValueError),
        ("initial_pose_std", [0.1, 0.1, 0.1], ValueError),
        ("initial_pose_std", (0.1, math.nan, 0.1), ValueError),
        ("gate_probability", 0.0, ValueError),
        ("gate_probability", 1.0, ValueError),
        ("gate_probability", math.nan, ValueError),
        ("gate_probability", "0.9", TypeError),
    ],
)
def test_config_rejects_bad_fields(field: str, value: object, error: type[Exception]) -> None:
    with pytest.raises(error, match=f"PoseFilterConfig.{field}"):
        PoseFilterConfig(**{field: value})  # type: ignore[arg-type]


def test_filter_rejects_bad_arguments_and_stays_unchanged() -> None:
    with pytest.raises(TypeError, match="config"):
        PoseFilter(EkfSlamConfig(), [0.0, 0.0, 0.0])  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="initial_pose"):
        PoseFilter(PoseFilterConfig(), [0.0, math.nan, 0.0])
    pose_filter = filter_at([0.1, 0.2, 0.3])
    before = pose_filter.pose
    bad_calls = [
        (lambda: pose_filter.predict([0.1, math.nan, 0.0]), ValueError, "odometry_delta"),
        (lambda: pose_filter.predict([0.1, 0.0]), ValueError, "odometry_delta"),
        (lambda: pose_filter.predict("abc"), TypeError, "odometry_delta"),
        (lambda: pose_filter.reset([0.0, 0.0, math.inf]), ValueError, "pose"),
        (lambda: pose_filter.reset([0.0, 0.0, 0.0], -np.eye(3)), ValueError, "cov"),
        (lambda: pose_filter.reset([0.0, 0.0, 0.0], np.eye(2)), ValueError, "cov"),
        (lambda: pose_filter.reset([0.0, 0.0, 0.0], np.triu(np.ones((3, 3)))), ValueError, "cov"),
        (lambda: pose_filter.update(np.zeros(3)), TypeError, "observation"),  # type: ignore[arg-type]
        (lambda: pose_filter.mahalanobis(None), TypeError, "observation"),  # type: ignore[arg-type]
        (lambda: pose_filter.gate_threshold(0), ValueError, "dof"),
        (lambda: pose_filter.gate_threshold(4), ValueError, "dof"),
        (lambda: pose_filter.gate_threshold(True), TypeError, "dof"),
    ]
    for call, error, name in bad_calls:
        with pytest.raises(error, match=name):
            call()
        np.testing.assert_array_equal(pose_filter.pose, before)
        np.testing.assert_array_equal(pose_filter.cov, PRIOR_COV)


def test_observation_rejects_non_psd_information() -> None:
    """The filter relies on PoseObservation's checks for what it fuses."""
    with pytest.raises(ValueError, match="information"):
        observation([0.0, 0.0, 0.0], np.diag([1.0, -1.0, 1.0]))
    with pytest.raises(ValueError, match="pose"):
        observation([0.0, math.nan, 0.0], np.eye(3))


def test_an_observation_weight_fuses_that_share_of_the_information() -> None:
    P0 = np.diag([0.04, 0.09, 0.01])
    z = np.array([0.3, -0.2, 0.1])
    L = np.diag([400.0, 100.0, 900.0])
    weighted = PoseFilter(
        PoseFilterConfig(observation_weight=0.25, gate_probability=None), np.zeros(3)
    )
    weighted.reset(np.zeros(3), P0)
    assert weighted.update(PoseObservation(z, L, 0.0, 1))
    P = np.linalg.inv(np.linalg.inv(P0) + 0.25 * L)  # information form with a quarter of L
    np.testing.assert_allclose(weighted.cov, P, rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(weighted.pose, P @ (0.25 * L) @ z, rtol=1e-9, atol=1e-12)
    with pytest.raises(ValueError, match="observation_weight"):
        PoseFilterConfig(observation_weight=0.0)
