"""The differential-drive robot (:mod:`spl_env.robots.diff_drive`): kinematics against closed
forms, wheel encoders and dead reckoning against their noise model, config and action checks,
and the robot moving in a :class:`BulletWorld` as the kinematics say."""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import replace

import numpy as np
import pytest
from scipy.stats import chi2

from perception.geometry import compose, wrap_angle
from perception.sensor_models import LaserModel
from spl_env.field import FieldDimensions
from spl_env.robots.diff_drive import (
    DiffDriveConfig,
    DiffDriveRobot,
    WheelEncoders,
    arc_increment,
    arc_travel,
    dead_reckoning_increment,
    sonar_ring_rays,
    wheel_increment,
    wheel_speeds_from_action,
)
from spl_env.sensors.laser import Laser, LaserConfig
from spl_env.sim.placement import Placement
from spl_env.sim.world import BulletWorld

CONFIG = DiffDriveConfig()
R, L = CONFIG.wheel_radius_m, CONFIG.axle_length_m
TICK = CONFIG.tick_rad
NOISELESS = replace(CONFIG, encoder_scale_error_std=0.0, encoder_noise_rad_per_sqrt_rad=0.0)
DT = 0.1


def circle(wl: float, wr: float) -> tuple[float, float]:
    """Turn rate ω (rad/s) and signed radius (m) of the circle driven at wheel speeds wl, wr."""
    return R * (wr - wl) / L, L / 2 * (wr + wl) / (wr - wl)


def circle_pose(start: np.ndarray, wl: float, wr: float, t: float) -> np.ndarray:
    """Closed-form field pose (3,) after ``t`` s on the circle from ``start``."""
    omega, radius = circle(wl, wr)
    x, y, theta = start
    centre = np.array([x - radius * math.sin(theta), y + radius * math.cos(theta)])
    heading = theta + omega * t
    position = centre + radius * np.array([math.sin(heading), -math.cos(heading)])
    return np.array([*position, float(wrap_angle(heading))])


def encoders(config: DiffDriveConfig, seed: int = 0) -> WheelEncoders:
    enc = WheelEncoders(config)
    enc.reset(np.random.default_rng(seed))
    return enc


def assert_same_pose(a: np.ndarray, b: np.ndarray, atol: float) -> None:
    np.testing.assert_allclose(a[:2], b[:2], atol=atol)
    assert abs(float(wrap_angle(a[2] - b[2]))) < atol


# ----- kinematics ------------------------------------------------------------------------------
def test_equal_wheel_speeds_drive_a_straight_line_of_r_w_dt() -> None:
    w = 7.0
    np.testing.assert_allclose(wheel_increment([w * DT, w * DT], CONFIG), [R * w * DT, 0, 0])
    np.testing.assert_allclose(wheel_increment([-w * DT, -w * DT], CONFIG), [-R * w * DT, 0, 0])


def test_opposite_wheel_speeds_turn_in_place_by_2_r_w_dt_over_l() -> None:
    w = 3.0
    increment = wheel_increment([-w * DT, w * DT], CONFIG)
    np.testing.assert_allclose(increment, [0.0, 0.0, 2 * R * w * DT / L], atol=1e-15)


def test_constant_unequal_speeds_drive_the_analytic_circle_and_close_it() -> None:
    wl, wr = 4.0, 6.0
    omega, radius = circle(wl, wr)
    assert radius == pytest.approx(2.5 * L)  # L/2 (wr + wl) / (wr - wl)
    n = 100
    dt = 2 * math.pi / omega / n  # one period in n steps
    step = wheel_increment([wl * dt, wr * dt], CONFIG)
    start = np.array([0.3, -0.2, 0.4])
    pose = start
    for k in range(1, n + 1):
        pose = compose(pose, step)
        assert_same_pose(pose, circle_pose(start, wl, wr, k * dt), atol=1e-12)
    assert_same_pose(pose, start, atol=1e-12)


def test_an_arc_does_not_depend_on_how_finely_it_is_sliced() -> None:
    one = arc_increment(0.8, 1.3)
    halves = compose(arc_increment(0.4, 0.65), arc_increment(0.4, 0.65))
    np.testing.assert_allclose(one, halves, atol=1e-15)


def test_the_arc_tends_to_the_straight_line_as_the_turn_vanishes() -> None:
    np.testing.assert_allclose(arc_increment(0.5, 1e-9), [0.5, 0.25e-9, 1e-9], rtol=1e-12)
    np.testing.assert_array_equal(arc_increment(0.5, 0.0), [0.5, 0.0, 0.0])


def test_arc_travel_is_seed_001_eqs_5_4_and_5_5() -> None:
    distance, turn = arc_travel([2.0, 5.0], CONFIG)
    assert distance == pytest.approx(R * (5.0 + 2.0) / 2)
    assert turn == pytest.approx(R * (5.0 - 2.0) / L)


# ----- actions and config ----------------------------------------------------------------------
def test_actions_scale_to_the_wheel_speed_limit() -> None:
    top = CONFIG.max_wheel_speed_rad_per_s
    assert top * R == pytest.approx(1.2)  # the P3-DX's 1.2 m/s
    np.testing.assert_allclose(wheel_speeds_from_action([1.0, -0.5], CONFIG), [top, -top / 2])


@pytest.mark.parametrize(
    "action", [[np.nan, 0.0], [0.0, 1.01], [-1.5, 0.0], [0.0, 0.0, 0.0], [[0.0, 0.0]], "ab"]
)
def test_bad_actions_raise_naming_the_action(action: object) -> None:
    with pytest.raises(ValueError, match="action"):
        wheel_speeds_from_action(action, CONFIG)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("field", "value", "error"),
    [
        ("wheel_radius_m", 0.0, ValueError),
        ("axle_length_m", math.nan, ValueError),
        ("max_wheel_speed_rad_per_s", -1.0, ValueError),
        ("body_radius_m", 0.15, ValueError),  # the wheels stick out of the collision disc
        ("laser_mount_x_m", math.inf, ValueError),
        ("laser_mount_height_m", 0.2, ValueError),  # below the deck
        ("sonar_height_m", 0.1, ValueError),  # below the wheel tops
        ("sonar_height_m", 0.3, ValueError),  # above the deck
        ("encoder_ticks_per_rev", 0, ValueError),
        ("encoder_ticks_per_rev", 500.0, TypeError),
        ("encoder_scale_error_std", -0.01, ValueError),
        ("encoder_scale_error_std", 0.5, ValueError),
        ("encoder_noise_rad_per_sqrt_rad", -1e-3, ValueError),
        ("sonar_ring", (), ValueError),
        ("sonar_ring", [(0.1, 0.0, 0.0)], TypeError),
        ("sonar_ring", ((0.1, 0.0),), ValueError),
        ("sonar_ring", ((0.1, math.nan, 0.0),), ValueError),
    ],
)
def test_bad_config_fields_raise_naming_the_field(field: str, value: object, error: type) -> None:
    with pytest.raises(error, match=rf"DiffDriveConfig\.{field}"):
        DiffDriveConfig(**{field: value})  # type: ignore[arg-type]


def test_the_sonar_ring_is_the_pioneer_s_sixteen_mirrored_front_and_rear() -> None:
    yaw = np.rad2deg(CONFIG.sonar_directions_rad())
    positions = CONFIG.sonar_positions_m()
    assert positions.shape == (16, 2)
    np.testing.assert_allclose(yaw[:8], [90, 50, 30, 10, -10, -30, -50, -90])
    # the rear eight mirror the front eight about the axle line, in reverse order
    np.testing.assert_allclose(wrap_angle(np.deg2rad(180 - yaw[:8][::-1] - yaw[8:])), 0.0)
    assert np.all(np.hypot(*positions.T) < CONFIG.body_radius_m + 0.01)


def test_the_laser_moves_to_the_robot_s_mount() -> None:
    laser = CONFIG.mounted_laser(LaserConfig())
    assert isinstance(laser, LaserConfig)
    assert (laser.mount_x_m, laser.mount_height_m) == (0.018, 0.30)
    assert laser.n_beams == LaserModel().n_beams


# ----- encoders and dead reckoning -------------------------------------------------------------
def random_wheel_rotations(n: int, seed: int = 1) -> np.ndarray:
    """(n, 2) wheel rotations of steps at random speeds within the limit, both directions."""
    top = CONFIG.max_wheel_speed_rad_per_s
    return np.random.default_rng(seed).uniform(-top, top, size=(n, 2)) * DT


def test_encoders_must_be_reset_first() -> None:
    with pytest.raises(RuntimeError, match="reset"):
        WheelEncoders(CONFIG).measure([0.1, 0.1])


def test_noiseless_encoders_give_the_true_increments_up_to_tick_quantisation() -> None:
    enc = encoders(NOISELESS)
    rotations = random_wheel_rotations(300)
    heading_bound = 2 * R * TICK / L  # one tick each way on the two wheels
    true_pose, reckoned_pose = np.zeros(3), np.zeros(3)
    position_bound = 0.0
    for rotation in rotations:
        ticks = enc.measure(rotation)
        # a step's count misses its rotation by less than one tick on each wheel
        assert np.all(np.abs(ticks * TICK - rotation) < TICK)
        distance, turn = arc_travel(rotation, CONFIG)
        reckoned_distance, reckoned_turn = arc_travel(ticks * TICK, CONFIG)
        assert abs(reckoned_distance - distance) < R * TICK
        assert abs(reckoned_turn - turn) < heading_bound
        true_pose = compose(true_pose, wheel_increment(rotation, CONFIG))
        reckoned_pose = compose(reckoned_pose, dead_reckoning_increment(ticks, CONFIG))
        # the counter keeps the fractions: the heading error never exceeds one step's bound
        assert abs(float(wrap_angle(reckoned_pose[2] - true_pose[2]))) < heading_bound
        # each chord is off by < r q + H |Δs| / 4 in length and < 1.5 H in direction (the
        # heading's error plus half the turn's), so the position by < r q + 2 H |Δs| a step
        position_bound += R * TICK + 2 * heading_bound * abs(distance)
        assert np.hypot(*(reckoned_pose[:2] - true_pose[:2])) < position_bound


def test_the_same_seed_gives_the_same_ticks() -> None:
    rotations = random_wheel_rotations(50)
    runs = [[encoders(CONFIG, seed).measure(r) for r in rotations] for seed in (5, 5, 6)]
    np.testing.assert_array_equal(runs[0], runs[1])
    assert not np.array_equal(runs[0], runs[2])


def test_the_scale_errors_make_the_heading_drift_at_the_model_s_rate() -> None:
    config = replace(NOISELESS, encoder_scale_error_std=0.01)
    enc = encoders(config, seed=3)
    s_left, s_right = enc.scale_errors
    wheel_turn = 0.8  # rad per step, both wheels: straight ahead
    heading = 0.0
    n = 200
    for _ in range(n):
        heading += dead_reckoning_increment(enc.measure([wheel_turn, wheel_turn]), config)[2]
    driven_m = R * wheel_turn * n
    expected = (s_right - s_left) * driven_m / L
    assert abs(expected) > 100 * TICK  # a drift well beyond the quantisation
    assert heading == pytest.approx(expected, abs=2 * R * TICK / L)


def test_the_heading_drift_rate_spreads_across_episodes_as_the_model_says() -> None:
    n = 2000
    rates = []
    for seed in range(n):
        s_left, s_right = encoders(CONFIG, seed).scale_errors
        rates.append((s_right - s_left) / L)  # rad per metre driven straight
    std = math.sqrt(2) * CONFIG.encoder_scale_error_std / L
    assert std == pytest.approx(0.0186, abs=1e-4)  # the number in DiffDriveConfig's docstring
    lo, hi = chi2.ppf([1e-4, 1 - 1e-4], df=n)
    assert lo < np.sum((np.array(rates) / std) ** 2) < hi


def test_the_white_noise_makes_the_heading_a_random_walk_per_sqrt_metre() -> None:
    k = 0.05  # large, so that the one-tick quantisation is negligible
    config = replace(NOISELESS, encoder_noise_rad_per_sqrt_rad=k)
    wheel_turn, steps, episodes = 0.5, 20, 500
    headings = []
    for seed in range(episodes):
        enc = encoders(config, seed)
        ticks = sum(enc.measure([wheel_turn, wheel_turn]) for _ in range(steps))
        headings.append(dead_reckoning_increment(ticks, config)[2])
    driven_m = R * wheel_turn * steps
    std = k * math.sqrt(2 * R * driven_m) / L
    lo, hi = chi2.ppf([1e-4, 1 - 1e-4], df=episodes)
    assert lo < np.sum((np.array(headings) / std) ** 2) < hi


# ----- the robot in a world --------------------------------------------------------------------
@pytest.fixture(scope="module")
def world() -> Iterator[BulletWorld]:
    world = BulletWorld(time_step_s=0.01)
    yield world
    world.close()


@pytest.fixture(scope="module")
def robot(world: BulletWorld) -> DiffDriveRobot:
    return DiffDriveRobot(world, "pioneer", config=CONFIG)


@pytest.fixture(scope="module")
def placement() -> Placement:
    return Placement(FieldDimensions(), np.zeros((0, 3)), CONFIG.body_radius_m)


def test_the_robot_drives_the_analytic_circle_in_the_world(
    world: BulletWorld, robot: DiffDriveRobot, placement: Placement
) -> None:
    start = np.array([-1.0, 0.5, 0.3])
    robot.place(start)
    wl, wr = 3.0, 5.0
    for k in range(1, 31):
        increment, blocked = placement.walk(robot, np.array([wl, wr]), DT, [])
        assert not blocked
        np.testing.assert_allclose(robot.wheel_rotations(DT), [wl * DT, wr * DT])
        assert_same_pose(robot.pose, circle_pose(start, wl, wr, k * DT), atol=1e-12)
        np.testing.assert_allclose(increment, wheel_increment([wl * DT, wr * DT], CONFIG))
    np.testing.assert_allclose(world.position("pioneer"), [*robot.pose[:2], 0.0], atol=1e-9)


def test_wheel_speeds_beyond_the_limit_are_clipped(robot: DiffDriveRobot) -> None:
    robot.place(np.zeros(3))
    top = CONFIG.max_wheel_speed_rad_per_s
    increment = robot.walk_step(np.array([50.0, -50.0]), DT)
    np.testing.assert_allclose(robot.wheel_speeds, [top, -top])
    np.testing.assert_allclose(increment, [0.0, 0.0, -2 * R * top * DT / L], atol=1e-15)


def test_a_blocked_robot_stays_while_its_wheels_slip(
    robot: DiffDriveRobot, placement: Placement
) -> None:
    carpet_half_length = FieldDimensions().carpet_size_m[0] / 2
    start = np.array([carpet_half_length - CONFIG.body_radius_m - 0.01, 0.0, 0.0])
    robot.place(start)
    _, blocked = placement.walk(robot, np.array([10.0, 10.0]), DT, [])
    assert blocked
    np.testing.assert_array_equal(robot.pose, start)
    ticks = encoders(NOISELESS).measure(robot.wheel_rotations(DT))
    np.testing.assert_allclose(ticks * TICK, [10.0 * DT, 10.0 * DT], atol=TICK)


def test_the_robot_s_own_laser_and_sonar_rays_leave_its_body_clear(
    world: BulletWorld, robot: DiffDriveRobot
) -> None:
    pose = np.array([0.4, -0.3, 2.0])
    robot.place(pose)
    laser_rays = Laser(CONFIG.mounted_laser(LaserModel())).rays(pose)
    for starts, ends in (laser_rays, sonar_ring_rays(CONFIG, pose, length_m=3.0)):
        _, bodies = world.ray_test(starts, ends)
        np.testing.assert_array_equal(bodies, -1)  # nothing in the world but the robot
    # ... while another robot's ray does see it
    _, bodies = world.ray_test(np.array([[2.4, -0.3, 0.15]]), np.array([[0.4, -0.3, 0.15]]))
    assert bodies[0] == world.body("pioneer")


def test_sonar_rays_start_at_the_discs_along_their_axes() -> None:
    pose = np.array([1.0, 2.0, math.pi / 2])
    starts, ends = sonar_ring_rays(CONFIG, pose, length_m=2.0)
    x, y = CONFIG.sonar_positions_m().T
    np.testing.assert_allclose(starts[:, :2], np.column_stack([1.0 - y, 2.0 + x]), atol=1e-12)
    np.testing.assert_allclose(starts[:, 2], CONFIG.sonar_height_m)
    along = ends - starts
    directions = np.arctan2(along[:, 1], along[:, 0])
    np.testing.assert_allclose(
        wrap_angle(directions - CONFIG.sonar_directions_rad() - math.pi / 2), 0.0, atol=1e-12
    )
    np.testing.assert_allclose(np.linalg.norm(ends - starts, axis=1), 2.0)
