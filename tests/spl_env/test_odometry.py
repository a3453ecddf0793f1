"""Walk odometry error model and scripted square walks, against closed-form truths."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.stats import chi2

from perception.geometry import compose, wrap_angle
from spl_env.sensors.odometry import OdometryConfig, WalkOdometry
from spl_env.trajectories import increments, square_walk

NO_NOISE = {
    "translation_scale_error_std": 0.0,
    "heading_drift_std_rad_per_m": 0.0,
    "rotation_scale_error_std": 0.0,
    "translation_noise_m_per_sqrt_m": 0.0,
    "heading_noise_rad_per_sqrt_m": 0.0,
    "rotation_noise_rad_per_sqrt_rad": 0.0,
}


def assert_chi2_std(residuals: np.ndarray, std: float) -> None:
    """Residuals are N(0, std²): their normalised sum of squares lies in a 1e-4 chi-square band."""
    r = np.ravel(residuals) / std
    lo, hi = chi2.ppf([1e-4, 1 - 1e-4], df=r.size)
    assert lo < np.sum(r**2) < hi


def odometry(seed: int = 0, **overrides: float) -> WalkOdometry:
    odo = WalkOdometry(OdometryConfig(**{**NO_NOISE, **overrides}))
    odo.reset(np.random.default_rng(seed))
    return odo


def walk() -> np.ndarray:
    return square_walk(side_m=1.0, speed_mps=0.25, turn_rate_rps=math.pi / 4, dt_s=0.1)


def test_noise_free_odometry_reports_the_true_increments() -> None:
    odo = odometry()
    deltas = increments(walk())
    np.testing.assert_array_equal([odo.measure(d) for d in deltas], deltas)


def test_translation_scale_error_scales_a_straight_walk() -> None:
    odo = odometry(translation_scale_error=0.1)
    pose = np.zeros(3)
    for _ in range(100):
        pose = compose(pose, odo.measure([0.02, 0.0, 0.0]))
    np.testing.assert_allclose(pose, [1.1 * 2.0, 0.0, 0.0], atol=1e-12)


def test_heading_drift_turns_a_straight_walk_by_drift_times_distance() -> None:
    odo = odometry(heading_drift_rad_per_m=0.05)
    total = np.sum([odo.measure([0.03, 0.0, 0.0])[2] for _ in range(100)])
    assert total == pytest.approx(0.05 * 3.0, abs=1e-12)


def test_rotation_scale_error_scales_a_turn_in_place() -> None:
    odo = odometry(rotation_scale_error=-0.2)
    total = np.sum([odo.measure([0.0, 0.0, 0.05])[2] for _ in range(40)])
    assert total == pytest.approx(0.8 * 2.0, abs=1e-12)


def test_translation_noise_std_grows_with_sqrt_of_distance() -> None:
    odo = odometry(translation_noise_m_per_sqrt_m=0.03)
    measured = np.array([odo.measure([0.04, 0.0, 0.0]) for _ in range(4000)])
    assert_chi2_std(measured[:, :2] - [0.04, 0.0], 0.03 * math.sqrt(0.04))
    np.testing.assert_array_equal(measured[:, 2], 0.0)


def test_heading_noise_adds_walked_and_turned_variances() -> None:
    odo = odometry(heading_noise_rad_per_sqrt_m=0.07, rotation_noise_rad_per_sqrt_rad=0.05)
    measured = np.array([odo.measure([0.03, 0.04, -0.1]) for _ in range(4000)])
    std = math.sqrt(0.07**2 * 0.05 + 0.05**2 * 0.1)
    assert_chi2_std(measured[:, 2] + 0.1, std)


def test_systematic_errors_are_drawn_per_episode_around_the_config() -> None:
    config = OdometryConfig(
        **{**NO_NOISE, "heading_drift_rad_per_m": 0.02, "heading_drift_std_rad_per_m": 0.1}
    )
    odo, rng = WalkOdometry(config), np.random.default_rng(5)
    drifts = []
    for _ in range(2000):
        odo.reset(rng)
        drifts.append(odo.errors.heading_drift_rad_per_m)
    assert_chi2_std(np.array(drifts) - 0.02, 0.1)


def test_same_seed_same_measurements_and_other_seed_differs() -> None:
    deltas = increments(walk())[:50]

    def run(seed: int) -> np.ndarray:
        odo = WalkOdometry(OdometryConfig())
        odo.reset(np.random.default_rng(seed))
        return np.array([odo.measure(d) for d in deltas])

    np.testing.assert_array_equal(run(3), run(3))
    assert not np.allclose(run(3), run(4))


def test_measure_before_reset_raises() -> None:
    with pytest.raises(RuntimeError, match="reset"):
        WalkOdometry(OdometryConfig()).measure([0.0, 0.0, 0.0])


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("translation_scale_error", 0.7),
        ("rotation_scale_error_std", -0.1),
        ("heading_drift_rad_per_m", math.nan),
        ("heading_noise_rad_per_sqrt_m", -0.01),
    ],
)
def test_bad_odometry_config_raises_naming_the_field(field: str, value: float) -> None:
    with pytest.raises(ValueError, match=f"odometry.{field}"):
        OdometryConfig(**{field: value})


@pytest.mark.parametrize("delta", [[0.1, 0.0], [0.0, math.inf, 0.0]])
def test_bad_increment_raises(delta: list[float]) -> None:
    with pytest.raises(ValueError, match="true_delta"):
        odometry().measure(delta)


@pytest.mark.parametrize(("laps", "start"), [(1.0, (0.0, 0.0, 0.0)), (2.0, (1.5, -2.0, 2.5))])
def test_square_walk_closes_its_loop(laps: float, start: tuple[float, float, float]) -> None:
    poses = square_walk(
        side_m=1.78, speed_mps=0.15, turn_rate_rps=0.5, dt_s=0.1, start_pose=start, laps=laps
    )
    np.testing.assert_allclose(poses[0], start, atol=1e-12)
    np.testing.assert_allclose(poses[-1, :2], start[:2], atol=1e-9)
    assert abs(wrap_angle(poses[-1, 2] - start[2])) < 1e-9


@pytest.mark.parametrize(("dt", "samples"), [(0.1, 241), (0.07, 344)])
def test_square_walk_duration_and_sampling(dt: float, samples: int) -> None:
    # 1 m sides at 0.25 m/s (4 s) and 90° turns at pi/4 rad/s (2 s): a 24 s lap.
    poses = square_walk(side_m=1.0, speed_mps=0.25, turn_rate_rps=math.pi / 4, dt_s=dt)
    assert poses.shape == (samples, 3)
    deltas = increments(poses)
    assert np.sum(np.hypot(deltas[:, 0], deltas[:, 1])) == pytest.approx(4.0, abs=1e-9)
    assert np.sum(deltas[:, 2]) == pytest.approx(2 * math.pi, abs=1e-9)
    # The first side is walked straight ahead at the commanded speed.
    first_side = deltas[: int(3.9 / dt)]
    np.testing.assert_allclose(
        first_side, np.tile([0.25 * dt, 0.0, 0.0], (len(first_side), 1)), atol=1e-12
    )


def test_quarter_lap_ends_turned_at_the_first_corner() -> None:
    poses = square_walk(
        side_m=2.0,
        speed_mps=0.2,
        turn_rate_rps=0.5,
        dt_s=0.05,
        start_pose=(1.0, 1.0, math.pi),
        laps=0.25,
    )
    np.testing.assert_allclose(poses[-1], [-1.0, 1.0, -math.pi / 2], atol=1e-9)


def test_increments_integrate_back_to_the_poses() -> None:
    poses = square_walk(
        side_m=1.0, speed_mps=0.3, turn_rate_rps=1.0, dt_s=0.1, start_pose=(0.5, -1.0, 0.3)
    )
    rebuilt = [poses[0]]
    for delta in increments(poses):
        rebuilt.append(compose(rebuilt[-1], delta))
    np.testing.assert_allclose(rebuilt, poses, atol=1e-9)


@pytest.mark.parametrize("name", ["side_m", "speed_mps", "turn_rate_rps", "dt_s", "laps"])
def test_square_walk_rejects_non_positive_arguments(name: str) -> None:
    kwargs = {"side_m": 1.0, "speed_mps": 0.2, "turn_rate_rps": 0.5, "dt_s": 0.1, "laps": 1.0}
    kwargs[name] = 0.0
    with pytest.raises(ValueError, match=name):
        square_walk(**kwargs)


def test_bad_start_pose_and_poses_raise() -> None:
    with pytest.raises(ValueError, match="start_pose"):
        square_walk(side_m=1.0, speed_mps=0.2, turn_rate_rps=0.5, dt_s=0.1, start_pose=(0, 0))
    with pytest.raises(ValueError, match="poses"):
        increments(np.zeros((1, 3)))
