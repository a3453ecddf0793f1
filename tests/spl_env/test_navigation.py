"""Seed 001's navigation (:mod:`spl_env.navigation`): Braitenberg avoidance against its
normalisation, the ring's mirror symmetry and the turn it must make; the waypoint follower's
turns, arrivals and a kinematic drive round a square; the hybrid against the follower."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from perception.geometry import compose
from spl_env.navigation import (
    BraitenbergConfig,
    HybridConfig,
    HybridNavigator,
    WaypointConfig,
    WaypointFollower,
    braitenberg_action,
)
from spl_env.robots.diff_drive import (
    PIONEER_SONAR_RING,
    DiffDriveConfig,
    wheel_increment,
    wheel_speeds_from_action,
)

BRAITENBERG = BraitenbergConfig()
WAYPOINT = WaypointConfig()
S = len(PIONEER_SONAR_RING)
NO_ECHO = np.full(S, np.nan)


def ranges(**close: float) -> np.ndarray:
    """Sonar ranges (S,): NaN except ``s<k>=range_m``."""
    r = NO_ECHO.copy()
    for name, value in close.items():
        r[int(name[1:])] = value
    return r


def mirror_indices() -> list[int]:
    """For each sonar, the sonar at its mirror image about the robot's x axis (from the ring's
    geometry: y and yaw negated)."""
    ring = [(x, y, yaw) for x, y, yaw in PIONEER_SONAR_RING]
    return [ring.index((x, -y, -yaw)) for x, y, yaw in ring]


# --- Braitenberg ------------------------------------------------------------------------------


def test_no_echo_gives_the_base_action_on_both_wheels() -> None:
    np.testing.assert_array_equal(braitenberg_action(NO_ECHO, BRAITENBERG), [0.4, 0.4])


def test_obstacle_ahead_slightly_left_turns_right_and_mirror_turns_left() -> None:
    assert PIONEER_SONAR_RING[3][2] == 10.0  # sonar 3 looks 10° left of ahead
    left, right = braitenberg_action(ranges(s3=0.3), BRAITENBERG)
    assert left > right
    left, right = braitenberg_action(ranges(s4=0.3), BRAITENBERG)  # 10° right of ahead
    assert right > left


def test_closer_obstacle_turns_harder() -> None:
    turns = [np.subtract(*braitenberg_action(ranges(s2=r), BRAITENBERG)) for r in (0.5, 0.4, 0.3)]
    assert 0 < turns[0] < turns[1] < turns[2]


def test_mirrored_readings_give_swapped_wheels() -> None:
    mirror = mirror_indices()
    assert mirror[:8] == list(range(7, -1, -1))  # the front ring, left to right, reversed
    rng = np.random.default_rng(1)
    for _ in range(20):
        r = rng.uniform(0.0, 1.0, S)
        r[rng.random(S) < 0.3] = np.nan
        action = braitenberg_action(r, BRAITENBERG)
        np.testing.assert_allclose(braitenberg_action(r[mirror], BRAITENBERG), action[::-1])


def test_reading_beyond_the_max_distance_changes_nothing() -> None:
    base = ranges(s2=0.35, s12=0.1)
    expected = braitenberg_action(base, BRAITENBERG)
    for k in np.flatnonzero(np.isnan(base)):
        for far in (BRAITENBERG.max_detection_m, 0.61, 5.0):
            r = base.copy()
            r[k] = far
            np.testing.assert_array_equal(braitenberg_action(r, BRAITENBERG), expected)


def test_detection_is_linear_between_full_and_max_distance_and_the_action_saturates() -> None:
    one_sonar = replace(
        BRAITENBERG, base_action=0.5, left_weights=(-1.0,) + (0.0,) * 15, right_weights=(0.0,) * 16
    )
    # d = 1 at 0.2 m or closer, 0.5 half way to 0.6 m, 0.25 at 0.5 m
    for r, d in ((0.0, 1.0), (0.1, 1.0), (0.2, 1.0), (0.4, 0.5), (0.5, 0.25), (0.6, 0.0)):
        np.testing.assert_allclose(
            braitenberg_action(ranges(s0=r), one_sonar), [0.5 - d, 0.5], atol=1e-12
        )
    strong = replace(one_sonar, left_weights=(-3.0,) + (0.0,) * 15)
    np.testing.assert_array_equal(braitenberg_action(ranges(s0=0.1), strong), [-1.0, 0.5])


def test_braitenberg_validation_names_the_argument() -> None:
    with pytest.raises(ValueError, match=r"sonar_ranges must have shape \(16,\)"):
        braitenberg_action(np.ones(8), BRAITENBERG)
    with pytest.raises(ValueError, match="sonar_ranges must be finite and >= 0"):
        braitenberg_action(ranges(s3=-0.1), BRAITENBERG)
    with pytest.raises(ValueError, match="sonar_ranges must be finite and >= 0"):
        braitenberg_action(ranges(s3=np.inf), BRAITENBERG)
    with pytest.raises(TypeError, match="sonar_ranges"):
        braitenberg_action(["a"] * S, BRAITENBERG)
    with pytest.raises(ValueError, match=r"BraitenbergConfig\.right_weights must have as many"):
        BraitenbergConfig(right_weights=(0.0,) * 8)
    with pytest.raises(TypeError, match=r"BraitenbergConfig\.left_weights must be a non-empty"):
        BraitenbergConfig(left_weights=[0.0] * 16)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"BraitenbergConfig\.left_weights\[2\] must be finite"):
        BraitenbergConfig(left_weights=(0.0, 0.0, math.nan) + (0.0,) * 13)
    with pytest.raises(ValueError, match=r"BraitenbergConfig\.full_detection_m .* got 0\.7"):
        BraitenbergConfig(full_detection_m=0.7)
    with pytest.raises(ValueError, match=r"BraitenbergConfig\.base_action .* got 1\.5"):
        BraitenbergConfig(base_action=1.5)


# --- Waypoint follower ------------------------------------------------------------------------


def test_large_heading_error_turns_in_place_towards_the_target() -> None:
    follower = WaypointFollower([(0.0, 3.0), (3.0, 3.0)], WAYPOINT)
    left, right = follower.action([0.0, 0.0, 0.0])  # target 90° to the left
    assert left < 0 < right and left == -right == -WAYPOINT.turn_fraction
    left, right = follower.action([0.0, 0.0, math.pi])  # now 90° to the right
    assert right < 0 < left and left == -right == WAYPOINT.turn_fraction


def test_small_heading_error_drives_straight_even_across_the_angle_wrap() -> None:
    def route(bearing_deg: float) -> np.ndarray:
        """A waypoint 5 m from the origin at ``bearing_deg``, then one at (1, 1)."""
        b = math.radians(bearing_deg)
        return np.array([(5.0 * math.cos(b), 5.0 * math.sin(b)), (1.0, 1.0)])

    follower = WaypointFollower(route(10.0), WAYPOINT)
    np.testing.assert_array_equal(follower.action([0.0, 0.0, 0.0]), [0.5, 0.5])
    # heading 175°, target bearing -175°: 10° to the left across ±180°
    follower = WaypointFollower(route(-175.0), WAYPOINT)
    np.testing.assert_array_equal(follower.action([0.0, 0.0, math.radians(175.0)]), [0.5, 0.5])
    # 25° off: beyond the 20° tolerance, it turns
    follower = WaypointFollower(route(-25.0), WAYPOINT)
    np.testing.assert_array_equal(follower.action([0.0, 0.0, 0.0]), [0.3, -0.3])


def test_arrival_advances_the_target_and_wraps_after_the_last() -> None:
    follower = WaypointFollower([(1.0, 0.0), (2.0, 0.0), (3.0, 0.0)], WAYPOINT)
    follower.action([0.0, 0.0, 0.0])
    assert follower.target_index == 0 and follower.laps == 0  # 1 m away: not arrived
    np.testing.assert_array_equal(follower.action([0.8, 0.0, 0.0]), [0.5, 0.5])
    np.testing.assert_array_equal(follower.target, [2.0, 0.0])
    follower.action([1.9, 0.1, 0.0])
    np.testing.assert_array_equal(follower.target, [3.0, 0.0])
    left, right = follower.action([2.9, 0.0, 0.0])  # last reached: back to the first, behind
    np.testing.assert_array_equal(follower.target, [1.0, 0.0])
    assert follower.laps == 1 and left == -right and abs(left) == WAYPOINT.turn_fraction
    follower.reset()
    assert follower.target_index == 0 and follower.laps == 0


def segment_distance(point: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    """Distance (m) from ``point`` (2,) to the segment from ``a`` to ``b``."""
    t = np.clip(np.dot(point - a, b - a) / np.dot(b - a, b - a), 0.0, 1.0)
    return float(np.linalg.norm(point - (a + t * (b - a))))


def test_kinematic_robot_drives_round_a_square() -> None:
    robot = DiffDriveConfig()
    corners = np.array([(2.0, 0.0), (2.0, 2.0), (0.0, 2.0), (0.0, 0.0)])
    legs = [(corners[k - 1], corners[k]) for k in range(4)]
    follower = WaypointFollower(corners, WAYPOINT)
    pose, dt = np.array([1.0, 0.0, 0.0]), 0.1  # half way to the first corner
    first_visit: dict[int, int] = {}
    for step in range(400):  # 40 s for 8 m at 0.6 m/s plus four quarter turns
        action = follower.action(pose)
        pose = compose(pose, wheel_increment(wheel_speeds_from_action(action, robot) * dt, robot))
        assert min(segment_distance(pose[:2], a, b) for a, b in legs) < 0.5
        for k, corner in enumerate(corners):
            if np.hypot(*(pose[:2] - corner)) < WAYPOINT.arrival_radius_m:
                first_visit.setdefault(k, step)
        if follower.laps == 1:
            break
    assert follower.laps == 1, f"lap not done in 40 s, stuck at target {follower.target}"
    assert sorted(first_visit, key=first_visit.__getitem__) == [0, 1, 2, 3]


def test_waypoint_validation_names_the_argument() -> None:
    with pytest.raises(ValueError, match=r"waypoints must have shape \(N, 2\) with N >= 2"):
        WaypointFollower([(1.0, 0.0)], WAYPOINT)
    with pytest.raises(ValueError, match="pose must have shape"):
        WaypointFollower([(1.0, 0.0), (0.0, 0.0)], WAYPOINT).action([0.0, 0.0])
    with pytest.raises(TypeError, match="config must be a WaypointConfig"):
        WaypointFollower([(1.0, 0.0), (0.0, 0.0)], BRAITENBERG)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"WaypointConfig\.heading_tolerance_deg .* got 200"):
        WaypointConfig(heading_tolerance_deg=200.0)
    with pytest.raises(ValueError, match=r"WaypointConfig\.turn_fraction .* got 0\.0"):
        WaypointConfig(turn_fraction=0.0)


# --- Hybrid -----------------------------------------------------------------------------------

ROUTE = [(3.0, 0.0), (3.0, 3.0), (0.0, 3.0)]
POSES = [(0.0, 0.0, 0.0), (0.5, 0.2, 1.0), (0.2, -0.3, -2.5)]


def test_hybrid_without_close_front_echo_equals_the_follower() -> None:
    far_front = ranges(s1=0.8, s3=0.6, s6=2.0)
    close_aside = ranges(s0=0.1, s7=0.1, s11=0.1)  # beside and behind: not a front sonar
    for sonars in (NO_ECHO, far_front, close_aside):
        hybrid, follower = HybridNavigator(ROUTE, HybridConfig()), WaypointFollower(ROUTE, WAYPOINT)
        for pose in POSES:
            np.testing.assert_array_equal(hybrid.action(pose, sonars), follower.action(pose))


def test_hybrid_turns_right_of_the_follower_at_a_close_front_left_echo() -> None:
    for sonar in (1, 2, 3):  # 50°, 30°, 10° left
        hybrid, follower = HybridNavigator(ROUTE, HybridConfig()), WaypointFollower(ROUTE, WAYPOINT)
        for pose in POSES:
            left, right = hybrid.action(pose, ranges(**{f"s{sonar}": 0.3}))
            route_left, route_right = follower.action(pose)
            assert left - right > route_left - route_right
            assert min(left, right) >= -1.0 and max(left, right) <= 1.0
    hybrid = HybridNavigator(ROUTE, HybridConfig())
    hybrid.follower.action([2.9, 0.0, 0.0])
    hybrid.reset()
    assert hybrid.follower.target_index == 0


def test_hybrid_validation_names_the_field() -> None:
    with pytest.raises(ValueError, match=r"HybridConfig\.front_sonars\[1\] must be a sonar index"):
        HybridConfig(front_sonars=(1, 16))
    with pytest.raises(TypeError, match=r"HybridConfig\.front_sonars\[0\] must be an int"):
        HybridConfig(front_sonars=(1.0,))  # type: ignore[arg-type]
    with pytest.raises(TypeError, match=r"HybridConfig\.braitenberg must be a BraitenbergConfig"):
        HybridConfig(braitenberg=WAYPOINT)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="config must be a HybridConfig"):
        HybridNavigator(ROUTE, WAYPOINT)  # type: ignore[arg-type]
