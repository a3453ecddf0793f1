"""The ball's Kalman filter against independent truths: the rolling-with-friction motion worked
out by hand (v t - a t^2 / 2, stopping without reversal), the white-acceleration covariance as
an integral, the robot's own motion as a frame change (and its noise by finite differences), a
Kalman step computed here with numpy, simulated rolling and kicked balls seen from a walking
robot with chi-square bands on the NEES, and the gate's candidate restart."""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Sequence

import numpy as np
import pytest
from numpy.typing import ArrayLike
from scipy.stats import chi2

from perception.geometry import FloatArray
from perception.tracking.ball_filter import (
    BallFilter,
    BallFilterConfig,
    moved_frame,
    rolling_model,
)
from perception.types import BallEstimate, BallSighting, SlamEstimate

COV = np.diag([0.04**2, 0.015**2])  # (m², rad²) range and bearing noise of a sighting
EXACT = np.zeros((3, 3))  # covariance of an exactly known pose
STILL = np.zeros(3)  # odometry of a robot standing still
DT = 0.1  # s between frames


def self_pose(pose: ArrayLike, pose_cov: ArrayLike = EXACT) -> SlamEstimate:
    """A SlamEstimate with ``pose`` (3,) and ``pose_cov`` (3, 3) and no landmarks."""
    return SlamEstimate(
        pose=np.asarray(pose, dtype=np.float64),
        pose_cov=np.asarray(pose_cov, dtype=np.float64),
        landmark_ids=np.zeros(0, dtype=np.int64),
        landmarks=np.zeros((0, 2)),
        landmark_covs=np.zeros((0, 2, 2)),
    )


def sighting(range_m: float, bearing_rad: float, cov: ArrayLike = COV) -> BallSighting:
    return BallSighting(
        range_m=float(range_m), bearing_rad=float(bearing_rad), cov=np.asarray(cov, np.float64)
    )


def observe(
    pose: ArrayLike, point: ArrayLike, rng: np.random.Generator | None = None, cov: FloatArray = COV
) -> BallSighting:
    """The sighting of the field ``point`` (2,) from the true ``pose`` (3,), with noise drawn
    from ``cov`` when ``rng`` is given."""
    x, y, theta = np.asarray(pose, dtype=np.float64)
    dx, dy = np.asarray(point, dtype=np.float64)[:2] - (x, y)
    z = np.array([math.hypot(dx, dy), math.atan2(dy, dx) - theta])
    if rng is not None:
        z = z + np.linalg.cholesky(cov) @ rng.standard_normal(2)
    return sighting(z[0], z[1], cov)


def polar_jacobian(theta: float, range_m: float, bearing: float) -> FloatArray:
    """d(x, y)/d(range, bearing) of ``(x + r cos(theta + b), y + r sin(theta + b))``."""
    phi = theta + bearing
    return np.array(
        [[math.cos(phi), -range_m * math.sin(phi)], [math.sin(phi), range_m * math.cos(phi)]]
    )


def cv_transition(dt: float) -> FloatArray:
    """Constant-velocity transition (4, 4) over ``dt``."""
    F = np.eye(4)
    F[0, 2] = F[1, 3] = dt
    return F


def white_acceleration_q(q: float, dt: float) -> FloatArray:
    """``integral_0^dt Phi(s) G q G^T Phi(s)^T ds`` with ``Phi`` the constant-velocity
    transition and ``G = [0; I]``, by Gauss-Legendre quadrature (exact: the integrand is a
    polynomial of degree 2 in s)."""
    nodes, weights = np.polynomial.legendre.leggauss(4)
    G = np.vstack([np.zeros((2, 2)), np.eye(2)])
    total = np.zeros((4, 4))
    for node, weight in zip(nodes, weights, strict=True):
        s = 0.5 * dt * (node + 1.0)
        phi = cv_transition(s)
        total += 0.5 * dt * weight * (phi @ G @ (q * np.eye(2)) @ G.T @ phi.T)
    return total


def rolled(state: ArrayLike, dt: float, a: float) -> FloatArray:
    """The ball (x, y, vx, vy) after ``dt`` s of rolling at deceleration ``a`` (by hand:
    speed falls linearly to zero, and the distance is the area under it)."""
    x = np.asarray(state, dtype=np.float64)
    speed = math.hypot(x[2], x[3])
    if speed == 0.0:
        return x.copy()
    direction = x[2:] / speed
    t = min(dt, speed / a) if a > 0 else dt
    distance = speed * t - 0.5 * a * t * t
    new_speed = max(speed - a * dt, 0.0)
    return np.concatenate([x[:2] + distance * direction, new_speed * direction])


def rot(angle: float) -> FloatArray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s], [s, c]])


def frame_change(state: ArrayLike, dx: float, dy: float, dtheta: float) -> FloatArray:
    """A ball (x, y, vx, vy) in the robot frame, seen after the robot stepped ``(dx, dy)`` in
    its old frame and turned ``dtheta``: by hand, the point relative to the new origin turned
    back by the turn."""
    x = np.asarray(state, dtype=np.float64)
    back = rot(-dtheta)
    return np.concatenate([back @ (x[:2] - (dx, dy)), back @ x[2:]])


def assert_psd(cov: FloatArray) -> None:
    """``cov`` is exactly symmetric and positive semidefinite up to rounding."""
    np.testing.assert_array_equal(cov, cov.T)
    assert np.linalg.eigvalsh(cov).min() >= -1e-12 * max(1.0, float(np.abs(cov).max()))


def run(
    ball_filter: BallFilter, frames: Sequence[tuple[float, Sequence[BallSighting]]], pose: ArrayLike
) -> list[BallEstimate]:
    return [ball_filter.update(t, s, STILL, self_pose(pose)) for t, s in frames]


# --- rolling_model ------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("speed", "dt", "a", "new_speed", "distance"),
    [
        # v' = v - a dt, d = v dt - a dt² / 2, worked out by hand
        (1.0, 0.5, 0.11, 0.945, 0.48625),
        (1.5, 0.1, 0.11, 1.489, 0.14945),
        (0.3, 2.0, 0.1, 0.1, 0.4),
        # a dt > v: stops after v / a s, having rolled v² / (2 a); never rolls back
        (0.05, 1.0, 0.11, 0.0, 0.05**2 / 0.22),
        (0.2, 10.0, 0.1, 0.0, 0.2),
        (0.11, 1.0, 0.11, 0.0, 0.055),  # stops exactly at the end of dt
    ],
)
def test_rolling_model_decelerates_along_the_direction_and_stops(
    speed: float, dt: float, a: float, new_speed: float, distance: float
) -> None:
    direction = np.array([-0.6, 0.8])
    state = np.array([1.0, -2.0, *(speed * direction)])
    config = BallFilterConfig(deceleration_mps2=a)
    predicted, F, Q = rolling_model(state, dt, config)
    np.testing.assert_allclose(predicted[:2], state[:2] + distance * direction, atol=1e-12)
    np.testing.assert_allclose(predicted[2:], new_speed * direction, atol=1e-12)
    assert predicted[2:] @ direction >= 0.0  # no reversal
    # The covariance's F rolls the uncertainty on at constant velocity (friction a known input)
    expected_F = np.block([[np.eye(2), dt * np.eye(2)], [np.zeros((2, 2)), np.eye(2)]])
    np.testing.assert_allclose(F, expected_F, atol=1e-12)
    assert Q.shape == (4, 4)


def test_rolling_model_distance_is_the_area_under_the_speed() -> None:
    """Many small steps of the model add up to one big step (the closed form composes), and
    the position follows v t - a t² / 2 until the ball stops at v / a."""
    config = BallFilterConfig(deceleration_mps2=0.11)
    v0, direction = 1.2, np.array([0.8, 0.6])
    state = np.array([0.0, 0.0, *(v0 * direction)])
    t = 0.0
    for _ in range(150):  # 15 s: the ball stops at 10.9 s
        state, _, _ = rolling_model(state, 0.1, config)
        t += 0.1
        rolling = min(t, v0 / 0.11)
        expected = v0 * rolling - 0.5 * 0.11 * rolling**2
        np.testing.assert_allclose(state[:2], expected * direction, atol=1e-9)
        assert np.hypot(*state[2:]) == pytest.approx(max(v0 - 0.11 * t, 0.0), abs=1e-9)
    assert np.hypot(*state[:2]) == pytest.approx(v0**2 / (2 * 0.11), abs=1e-9)


@pytest.mark.parametrize("dt", [0.0, 0.033, 0.1, 1.0])
def test_a_ball_at_rest_stays_and_q_is_the_white_acceleration_integral(dt: float) -> None:
    config = BallFilterConfig(acceleration_psd=0.3)
    state = np.array([2.0, -1.0, 0.0, 0.0])
    predicted, F, Q = rolling_model(state, dt, config)
    np.testing.assert_array_equal(predicted, state)
    np.testing.assert_allclose(F, cv_transition(dt), atol=1e-15)
    assert F.shape == Q.shape == (4, 4)
    np.testing.assert_allclose(Q, white_acceleration_q(0.3, dt), rtol=1e-12, atol=1e-15)
    np.testing.assert_array_equal(Q, Q.T)
    # the per-axis closed form: q [[dt³/3, dt²/2], [dt²/2, dt]]
    assert Q[0, 0] == pytest.approx(0.3 * dt**3 / 3) and Q[0, 1] == 0.0
    assert Q[0, 2] == pytest.approx(0.3 * dt**2 / 2) and Q[2, 2] == pytest.approx(0.3 * dt)


@pytest.mark.parametrize("state", [[0.5, 1.0, 1.5, -0.7], [0.0, 0.0, 0.01, 0.0], [3, 4, 0, 0]])
def test_without_deceleration_the_model_is_exactly_constant_velocity(state: list[float]) -> None:
    config = BallFilterConfig(deceleration_mps2=0.0, acceleration_psd=0.05)
    x = np.asarray(state, dtype=np.float64)
    for dt in (0.0, 0.1, 2.5, 40.0):
        predicted, F, Q = rolling_model(x, dt, config)
        np.testing.assert_allclose(predicted, cv_transition(dt) @ x, rtol=1e-14, atol=1e-14)
        np.testing.assert_allclose(F, cv_transition(dt), rtol=1e-14, atol=1e-14)
        np.testing.assert_allclose(Q, white_acceleration_q(0.05, dt), rtol=1e-12, atol=1e-15)


# --- moved_frame: the robot's own motion --------------------------------------------------------


@pytest.mark.parametrize(
    ("state", "odometry"),
    [
        ([2.0, 0.5, 0.0, 0.0], [0.05, 0.0, 0.0]),
        ([1.0, -1.5, 0.6, 0.2], [0.03, -0.01, 0.15]),
        ([-0.5, 2.0, -1.0, 0.4], [0.0, 0.0, -0.3]),
    ],
)
def test_the_robot_motion_moves_the_frame_and_its_noise_is_first_order(
    state: list[float], odometry: list[float]
) -> None:
    config = BallFilterConfig(
        odometry_translation_std_fraction=0.2,
        odometry_turn_std_fraction=0.1,
        odometry_turn_std_floor_rad=0.003,
    )
    x = np.asarray(state, dtype=np.float64)
    dx, dy, dtheta = odometry
    moved, G, Q = moved_frame(x, np.asarray(odometry, dtype=np.float64), config)
    np.testing.assert_allclose(moved, frame_change(x, dx, dy, dtheta), atol=1e-14)
    # G: the Jacobian of the map in the state, by central differences
    eps = 1e-6
    numeric = np.column_stack(
        [
            (frame_change(x + eps * e, dx, dy, dtheta) - frame_change(x - eps * e, dx, dy, dtheta))
            / (2 * eps)
            for e in np.eye(4)
        ]
    )
    np.testing.assert_allclose(G, numeric, atol=1e-8)
    # Q: the walk's noise, isotropic with std 0.2 |d|, on the position, and the turn's noise
    # (std 0.1 |dθ| + 0.003) through the map's derivative in dθ
    d_step = np.column_stack(
        [
            (frame_change(x, dx + eps, dy, dtheta) - frame_change(x, dx - eps, dy, dtheta))
            / (2 * eps),
            (frame_change(x, dx, dy + eps, dtheta) - frame_change(x, dx, dy - eps, dtheta))
            / (2 * eps),
        ]
    )
    d_turn = (frame_change(x, dx, dy, dtheta + eps) - frame_change(x, dx, dy, dtheta - eps)) / (
        2 * eps
    )
    walk_var = (0.2 * math.hypot(dx, dy)) ** 2
    turn_var = (0.1 * abs(dtheta) + 0.003) ** 2
    expected = walk_var * d_step @ d_step.T + turn_var * np.outer(d_turn, d_turn)
    np.testing.assert_allclose(Q, expected, atol=1e-10)
    assert_psd(0.5 * (Q + Q.T))


# --- BallFilter: start and one Kalman step ------------------------------------------------------

EXACT_STEP = BallFilterConfig(odometry_turn_std_floor_rad=0.0)  # no odometry noise standing still
# ... and the first sighting starts the filter (unconfirmed)
EXACT_FIRST = dataclasses.replace(EXACT_STEP, start_confirm_s=None)
# a belief starts from two agreeing sightings, whatever their score
CONFIRMED = BallFilterConfig(start_confirm_s=0.3, start_at_once_score=None)


def test_the_ball_is_unknown_before_the_first_sighting() -> None:
    ball_filter = BallFilter()
    estimates = [
        ball_filter.estimate(self_pose([1, 2, 3])),
        *run(ball_filter, [(0.0, []), (0.5, [])], [1, 2, 3]),
    ]
    for estimate in estimates:
        assert not estimate.known
        assert estimate.last_seen_s == -math.inf
        np.testing.assert_array_equal(estimate.state, np.zeros(4))
        np.testing.assert_array_equal(estimate.relative, np.zeros(4))


@pytest.mark.parametrize(
    "pose_cov",
    [EXACT, np.array([[0.01, 0.002, 0.003], [0.002, 0.02, -0.004], [0.003, -0.004, 0.01]])],
)
def test_unconfirmed_the_first_sighting_starts_the_filter_there(pose_cov: FloatArray) -> None:
    config = BallFilterConfig(initial_velocity_std_mps=0.7, start_confirm_s=None)
    pose = np.array([1.0, -0.5, 0.4])
    r, b = 2.0, 0.3
    cov = np.array([[0.05**2, 0.0003], [0.0003, 0.02**2]])
    ball_filter = BallFilter(config)
    estimate = ball_filter.update(3.0, [sighting(r, b, cov)], STILL, self_pose(pose, pose_cov))
    assert estimate.known and estimate.last_seen_s == 3.0
    expected_z = [1.0 + r * math.cos(0.7), -0.5 + r * math.sin(0.7)]
    np.testing.assert_allclose(estimate.state, [*expected_z, 0.0, 0.0], atol=1e-14)
    np.testing.assert_allclose(
        estimate.relative, [r * math.cos(b), r * math.sin(b), 0.0, 0.0], atol=1e-14
    )
    J = polar_jacobian(0.4, r, b)
    # the pose moves the point by dx, dy and by r (-sin, cos) per radian of heading
    J_pose = np.array([[1.0, 0.0, -r * math.sin(0.7)], [0.0, 1.0, r * math.cos(0.7)]])
    expected_R = J @ cov @ J.T + J_pose @ pose_cov @ J_pose.T
    np.testing.assert_allclose(estimate.cov[:2, :2], expected_R, rtol=1e-12, atol=1e-16)
    np.testing.assert_allclose(estimate.cov[:2, 2:], np.zeros((2, 2)), atol=1e-16)
    np.testing.assert_allclose(estimate.cov[2:, 2:], 0.49 * np.eye(2), rtol=1e-14, atol=1e-16)
    J_rel = polar_jacobian(0.0, r, b)
    np.testing.assert_allclose(estimate.relative_cov[:2, :2], J_rel @ cov @ J_rel.T, rtol=1e-12)
    assert_psd(estimate.cov)
    assert_psd(estimate.relative_cov)


@pytest.mark.parametrize("confirm_s", [None, 0.3])
def test_the_second_sighting_of_a_resting_ball_is_a_kalman_step(confirm_s: float | None) -> None:
    """Worked out here with numpy; the same whether the first sighting started the belief or
    waited for the second to confirm it (``start_confirm_s``)."""
    config = BallFilterConfig(
        acceleration_psd=0.2,
        initial_velocity_std_mps=0.4,
        odometry_turn_std_floor_rad=0.0,
        start_confirm_s=confirm_s,
        start_at_once_score=None,
    )
    pose = np.array([-1.0, 0.5, -0.8])
    ball_filter = BallFilter(config)
    r0, b0, r1, b1 = 1.8, 0.25, 1.84, 0.27
    cov0, cov1 = np.diag([0.03**2, 0.02**2]), np.diag([0.05**2, 0.01**2])
    first = ball_filter.update(1.0, [sighting(r0, b0, cov0)], STILL, self_pose(pose))
    assert first.known == (confirm_s is None)
    dt = 0.25
    estimate = ball_filter.update(1.0 + dt, [sighting(r1, b1, cov1)], STILL, self_pose(pose))

    def point(r: float, b: float) -> FloatArray:  # robot frame
        return np.array([r * math.cos(b), r * math.sin(b)])

    J0, J1 = polar_jacobian(0.0, r0, b0), polar_jacobian(0.0, r1, b1)
    x0 = np.concatenate([point(r0, b0), [0.0, 0.0]])
    P0 = np.zeros((4, 4))
    P0[:2, :2] = J0 @ cov0 @ J0.T
    P0[2:, 2:] = 0.16 * np.eye(2)
    F = cv_transition(dt)  # at rest: no rolling
    x_pred = F @ x0
    P_pred = F @ P0 @ F.T + white_acceleration_q(0.2, dt)
    H = np.hstack([np.eye(2), np.zeros((2, 2))])
    R1 = J1 @ cov1 @ J1.T
    S = H @ P_pred @ H.T + R1
    K = P_pred @ H.T @ np.linalg.inv(S)
    innovation = point(r1, b1) - H @ x_pred
    assert innovation @ np.linalg.solve(S, innovation) < chi2.ppf(0.99, 2)  # inside the gate
    x = x_pred + K @ innovation
    P = (np.eye(4) - K @ H) @ P_pred
    np.testing.assert_allclose(estimate.relative, x, rtol=1e-10, atol=1e-13)
    np.testing.assert_allclose(estimate.relative_cov, P, rtol=1e-9, atol=1e-14)
    # on the field: turned by the heading and moved by the position (exact pose)
    T = np.zeros((4, 4))
    T[:2, :2] = T[2:, 2:] = rot(pose[2])
    np.testing.assert_allclose(estimate.state, [*pose[:2], 0, 0] + T @ x, rtol=1e-10, atol=1e-13)
    np.testing.assert_allclose(estimate.cov, T @ P @ T.T, rtol=1e-9, atol=1e-14)
    assert estimate.last_seen_s == 1.25 and estimate.known
    assert_psd(estimate.cov)


# --- BallFilter: a belief starts from two sightings that agree --------------------------------


def test_a_walking_robot_confirms_as_the_first_sighting_would_have_started() -> None:
    """Walking between the two sightings: the confirmed start is the unconfirmed rule's belief
    after them (standing, both are worked out by hand in the Kalman-step test below; the walk's
    frame change by hand in the odometry tests above)."""
    pose = np.array([0.5, 1.0, -0.3])
    first, second = sighting(2.0, 0.2), sighting(1.98, 0.22, np.diag([0.06**2, 0.01**2]))
    odometry = np.array([0.03, 0.01, 0.02])
    estimates = []
    for confirm in (0.3, None):
        ball_filter = BallFilter(
            BallFilterConfig(start_confirm_s=confirm, start_at_once_score=None)
        )
        one = ball_filter.update(1.0, [first], STILL, self_pose(pose))
        assert one.known == (confirm is None)
        estimates.append(ball_filter.update(1.1, [second], odometry, self_pose(pose)))
    confirmed, unconfirmed = estimates
    assert confirmed.known and confirmed.last_seen_s == 1.1
    np.testing.assert_allclose(confirmed.relative, unconfirmed.relative, rtol=0, atol=1e-15)
    np.testing.assert_allclose(confirmed.relative_cov, unconfirmed.relative_cov, rtol=0, atol=1e-18)
    assert_psd(confirmed.relative_cov)


def test_a_ball_rolling_past_is_believed_from_its_second_sighting() -> None:
    """A ball rolling across the view at 1 m/s, 2 m ahead, seen from a robot standing still
    with a sighting's noise of about a centimetre: the waiting belief rolls its velocity's
    uncertainty on (0.5 m/s for 0.1 s), so the second sighting, 0.1 m on, agrees."""
    pose = [0.0, 0.0, 0.0]
    cov = np.diag([0.02**2, 0.005**2])
    ball_filter = BallFilter(CONFIRMED)
    for k in range(2):
        truth = np.array([2.0, -0.5 + 1.0 * k * DT])
        estimate = ball_filter.update(
            k * DT, [observe(pose, truth, cov=cov)], STILL, self_pose(pose)
        )
        assert estimate.known == (k == 1)
    assert estimate.state[3] > 0.3  # rolling sideways


def test_a_sighting_start_confirm_s_later_on_summed_frame_times_still_confirms() -> None:
    """Frame times summed step by step (0.1 three times is 0.30000000000000004): a sighting
    three frames after the first still confirms it at start_confirm_s = 0.3."""
    pose = [0.0, 0.0, 0.0]
    ball_filter = BallFilter(CONFIRMED)
    t = 0.1
    ball_filter.update(t, [observe(pose, [2.0, 0.0])], STILL, self_pose(pose))
    first = t
    for _ in range(2):
        t += 0.1
        ball_filter.update(t, [], STILL, self_pose(pose))
    t += 0.1
    assert t - first > 0.3
    assert ball_filter.update(t, [observe(pose, [2.0, 0.0])], STILL, self_pose(pose)).known


def test_the_first_sighting_waits_moved_with_the_robot_and_only_start_confirm_s_long() -> None:
    """A robot walking 0.1 m a frame towards a resting ball at (2, 0): the waiting sighting,
    moved with the odometry, agrees with one two frames later (the ball at 1.8 m); one more
    than ``start_confirm_s`` later starts nothing and waits itself."""
    ball = np.array([2.0, 0.0])
    step = np.array([0.1, 0.0, 0.0])

    def pose_at(k: int) -> FloatArray:
        return np.array([0.1 * k, 0.0, 0.0])

    for gap, starts in ((2, True), (4, False)):
        ball_filter = BallFilter(dataclasses.replace(CONFIRMED, start_confirm_s=0.25))
        ball_filter.update(0.0, [observe(pose_at(0), ball)], STILL, self_pose(pose_at(0)))
        for k in range(1, gap):
            estimate = ball_filter.update(k * DT, [], step, self_pose(pose_at(k)))
            assert not estimate.known
        seen = observe(pose_at(gap), ball)
        estimate = ball_filter.update(gap * DT, [seen], step, self_pose(pose_at(gap)))
        assert estimate.known == starts, gap
        if starts:
            np.testing.assert_allclose(estimate.relative[:2], ball - pose_at(gap)[:2], atol=1e-12)
            np.testing.assert_allclose(estimate.state[:2], ball, atol=1e-12)
        else:  # the late one waits in turn: the next frame's agreeing sighting starts it
            k = gap + 1
            estimate = ball_filter.update(
                k * DT, [observe(pose_at(k), ball)], step, self_pose(pose_at(k))
            )
            assert estimate.known and estimate.last_seen_s == pytest.approx(k * DT)


def test_a_sighting_that_disagrees_waits_in_place_of_the_first() -> None:
    """A false first sighting (at (0.5, 2)) and the ball (at (2, 0)): the ball's sighting does
    not agree, so it waits instead; of the next frame's two sightings, the false one first,
    the one that agrees with it (the ball) starts the belief there."""
    pose = [0.0, 0.0, 0.0]
    ball, false = [2.0, 0.0], [0.5, 2.0]
    ball_filter = BallFilter(CONFIRMED)
    ball_filter.update(0.0, [observe(pose, false)], STILL, self_pose(pose))
    estimate = ball_filter.update(DT, [observe(pose, ball)], STILL, self_pose(pose))
    assert not estimate.known
    sightings = [observe(pose, false), observe(pose, ball)]
    estimate = ball_filter.update(2 * DT, sightings, STILL, self_pose(pose))
    assert estimate.known and estimate.last_seen_s == 2 * DT
    np.testing.assert_allclose(estimate.state[:2], ball, atol=1e-12)


def test_every_sighting_of_a_frame_waits_and_the_best_scored_that_agrees_starts() -> None:
    """A frame with a false sighting (scored first) and the ball: both wait; the next frame's
    ball (alone, or scored first beside the false one seen again) starts the belief there."""
    pose = [0.0, 0.0, 0.0]
    ball, false = [2.0, 0.0], [0.5, 2.0]
    for later in ([ball], [ball, false]):
        ball_filter = BallFilter(CONFIRMED)
        both = [observe(pose, false), observe(pose, ball)]
        assert not ball_filter.update(0.0, both, STILL, self_pose(pose)).known
        sightings = [observe(pose, point) for point in later]
        estimate = ball_filter.update(DT, sightings, STILL, self_pose(pose))
        assert estimate.known, later
        np.testing.assert_allclose(estimate.state[:2], ball, atol=1e-12)


def test_the_estimate_shows_where_a_first_sighting_waits() -> None:
    """With the confirmed start, a single sighting at (2, 0) is the estimate's ``candidate``
    (the best-scored of a frame's, the first); after the robot walks 0.5 m ahead it lies at
    (1.5, 0) in the robot frame; past ``start_confirm_s`` it is gone; a started belief has none,
    nor does a filter whose first sighting starts the belief."""
    pose = [0.0, 0.0, 0.0]
    ball_filter = BallFilter(CONFIRMED)
    both = [observe(pose, [2.0, 0.0]), observe(pose, [0.5, 2.0])]
    estimate = ball_filter.update(0.0, both, STILL, self_pose(pose))
    assert not estimate.known and estimate.candidate is not None
    np.testing.assert_allclose(estimate.candidate, [2.0, 0.0], atol=1e-12)
    estimate = ball_filter.update(DT, [], np.array([0.5, 0.0, 0.0]), self_pose([0.5, 0.0, 0.0]))
    assert estimate.candidate is not None
    np.testing.assert_allclose(estimate.candidate, [1.5, 0.0], atol=1e-12)
    assert ball_filter.update(0.4, [], STILL, self_pose(pose)).candidate is None
    ball_filter.update(0.5, [observe(pose, [2.0, 0.0])], STILL, self_pose(pose))
    estimate = ball_filter.update(0.6, [observe(pose, [2.0, 0.0])], STILL, self_pose(pose))
    assert estimate.known and estimate.candidate is None
    first = BallFilter(EXACT_FIRST).update(0.0, both, STILL, self_pose(pose))
    assert first.known and first.candidate is None


def test_a_waiting_sighting_shows_until_start_confirm_s_and_no_longer() -> None:
    pose = [0.0, 0.0, 0.0]
    ball_filter = BallFilter(CONFIRMED)
    ball_filter.update(0.0, [observe(pose, [2.0, 0.0])], STILL, self_pose(pose))
    for k in (1, 2, 3):  # 0.1 s apart, summed: 0.30000000000000004 s is still 0.3 s
        assert ball_filter.update(k * DT, [], STILL, self_pose(pose)).candidate is not None, k
    assert ball_filter.update(4 * DT, [], STILL, self_pose(pose)).candidate is None


def test_a_lost_belief_leaves_the_frame_s_unfitting_sightings_waiting() -> None:
    """A ball believed 2 m ahead, in view and unseen twice; the third frame sees something
    at (1, 1) outside the gate: the belief is lost (0.2³ < 0.01) and that sighting waits,
    shown as the candidate; the next agreeing sighting starts the belief there."""
    pose = [0.0, 0.0, 0.0]
    ball_filter, t = steady_filter(pose, [2.0, 0.0])
    for k in (1, 2):
        ball_filter.update(t + k * DT, [], STILL, self_pose(pose), in_view=always)
    elsewhere = [observe(pose, [1.0, 1.0])]
    estimate = ball_filter.update(t + 3 * DT, elsewhere, STILL, self_pose(pose), in_view=always)
    assert not estimate.known and estimate.candidate is not None
    np.testing.assert_allclose(estimate.candidate, [1.0, 1.0], atol=1e-12)
    estimate = ball_filter.update(t + 4 * DT, elsewhere, STILL, self_pose(pose), in_view=always)
    assert estimate.known
    np.testing.assert_allclose(estimate.relative[:2], [1.0, 1.0], atol=1e-12)


@pytest.mark.parametrize(("score", "at_once"), [(0.8, True), (0.7, True), (0.69, False)])
def test_a_sighting_scored_start_at_once_score_or_more_starts_a_belief_at_once(
    score: float, at_once: bool
) -> None:
    """With ``start_at_once_score`` 0.7, a sighting at (2, 0) scored 0.7 or more starts the
    belief there at once, as the first sighting did without the confirmed start: at rest, the
    position's covariance the sighting's ``J cov Jᵀ`` (by hand, bearing 0: diag(σ_r², r² σ_b²)),
    the velocity's ``initial_velocity_std_mps``² I; one scored less waits for a second (shown
    as the candidate)."""
    pose = [0.0, 0.0, 0.0]
    config = dataclasses.replace(CONFIRMED, start_at_once_score=0.7)
    seen = dataclasses.replace(observe(pose, [2.0, 0.0]), score=score)
    estimate = BallFilter(config).update(0.0, [seen], STILL, self_pose(pose))
    first = BallFilter(EXACT_FIRST).update(0.0, [seen], STILL, self_pose(pose))
    assert estimate.known == at_once and (estimate.candidate is None) == at_once
    if at_once:
        np.testing.assert_allclose(estimate.relative, [2.0, 0.0, 0.0, 0.0], atol=1e-12)
        J = polar_jacobian(0.0, 2.0, 0.0)
        np.testing.assert_allclose(estimate.relative_cov[:2, :2], J @ COV @ J.T, atol=1e-15)
        np.testing.assert_allclose(
            estimate.relative_cov[2:, 2:], config.initial_velocity_std_mps**2 * np.eye(2)
        )
        np.testing.assert_array_equal(estimate.relative_cov, first.relative_cov)


def test_sightings_are_taken_best_scored_first_in_whatever_order_given() -> None:
    """A frame's sightings of a true ball at (1, 0) scored 0.95 and a false one scored 0.5: the
    confident one starts the belief at once (and a waiting candidate is the better of two
    low-scored ones), listed first or last."""
    pose = [0.0, 0.0, 0.0]
    config = dataclasses.replace(CONFIRMED, start_at_once_score=0.7)
    true = dataclasses.replace(observe(pose, [1.0, 0.0]), score=0.95)
    false = dataclasses.replace(observe(pose, [2.0, 2.0]), score=0.5)
    for frame in ([true, false], [false, true]):
        estimate = BallFilter(config).update(0.0, frame, STILL, self_pose(pose))
        assert estimate.known
        np.testing.assert_allclose(estimate.relative[:2], [1.0, 0.0], atol=1e-12)
    low_true, low_false = (dataclasses.replace(s, score=v) for s, v in ((true, 0.6), (false, 0.4)))
    for frame in ([low_true, low_false], [low_false, low_true]):
        estimate = BallFilter(config).update(0.0, frame, STILL, self_pose(pose))
        assert not estimate.known and estimate.candidate is not None
        np.testing.assert_allclose(estimate.candidate, [1.0, 0.0], atol=1e-12)


def test_no_robots_may_come_as_an_empty_list_or_array() -> None:
    pose = [0.0, 0.0, 0.0]
    seen = [observe(pose, [1.0, 0.0])]
    estimates = [
        BallFilter().update(0.0, seen, STILL, self_pose(pose), robots=robots)
        for robots in (None, [], (), np.zeros(0), np.zeros((0, 2)))
    ]
    for estimate in estimates[1:]:
        np.testing.assert_array_equal(estimate.relative, estimates[0].relative)


def test_reset_forgets_the_waiting_sighting() -> None:
    pose = [0.0, 0.0, 0.0]
    ball_filter = BallFilter(CONFIRMED)
    ball_filter.update(0.0, [observe(pose, [2.0, 0.0])], STILL, self_pose(pose))
    ball_filter.reset()
    assert ball_filter.estimate(self_pose(pose)).candidate is None
    estimate = ball_filter.update(DT, [observe(pose, [2.0, 0.0])], STILL, self_pose(pose))
    assert not estimate.known


def test_a_frame_without_sightings_only_predicts() -> None:
    """Standing still, the odometry's turn floor (std 0.002 rad) still turns the frame: a
    resting ball at p gains ``0.002² b bᵀ`` with ``b = (p_y, -p_x)``, the derivative of
    ``R(-dθ) p`` at dθ = 0."""
    config = BallFilterConfig(
        acceleration_psd=0.1, odometry_turn_std_floor_rad=0.002, start_confirm_s=None
    )
    ball_filter = BallFilter(config)
    ball_filter.update(0.0, [sighting(2.0, 0.5)], STILL, self_pose([0, 0, 0]))
    P0 = ball_filter.estimate(self_pose([0, 0, 0])).relative_cov
    estimate = ball_filter.update(0.5, [], STILL, self_pose([0, 0, 0]))
    p = 2.0 * np.array([math.cos(0.5), math.sin(0.5)])
    np.testing.assert_allclose(estimate.relative, [*p, 0.0, 0.0], atol=1e-15)
    F = cv_transition(0.5)
    b = np.array([p[1], -p[0], 0.0, 0.0])
    expected = F @ P0 @ F.T + white_acceleration_q(0.1, 0.5) + 0.002**2 * np.outer(b, b)
    np.testing.assert_allclose(estimate.relative_cov, expected, rtol=1e-12, atol=1e-16)
    assert estimate.last_seen_s == 0.0


def test_of_several_sightings_the_one_nearest_the_prediction_is_fused() -> None:
    """The best-scored sighting comes first; when it is a false one far off, the nearer one
    is fused all the same."""
    pose = [0.0, 0.0, 0.0]
    ball_filter = BallFilter()
    ball_filter.update(0.0, [observe(pose, [2.0, 0.5])], STILL, self_pose(pose))
    far, near = observe(pose, [0.5, -2.0]), observe(pose, [2.02, 0.5])
    estimate = ball_filter.update(0.1, [far, near], STILL, self_pose(pose))
    assert estimate.last_seen_s == 0.1
    assert np.linalg.norm(estimate.state[:2] - [2.0, 0.5]) < 0.03
    # alone, the far one is not fused
    estimate = ball_filter.update(0.2, [observe(pose, [0.5, -2.0])], STILL, self_pose(pose))
    assert estimate.last_seen_s == 0.1
    assert np.linalg.norm(estimate.state[:2] - [2.0, 0.5]) < 0.03


# --- BallFilter: our own kick ---------------------------------------------------------------------


def test_our_own_kick_sets_the_velocity_of_a_ball_within_reach() -> None:
    config = EXACT_FIRST
    kick = np.array([2.0, 0.5])
    ball_filter = BallFilter(config)
    ball_filter.update(0.0, [sighting(0.3, 0.2)], STILL, self_pose([0, 0, 0]))
    P0 = ball_filter.estimate(self_pose([0, 0, 0])).relative_cov
    estimate = ball_filter.update(DT, [], STILL, self_pose([0, 0, 0]), kick_velocity=kick)
    rolling = 0.71 * kick  # the default own_kick_rolling_fraction
    start = np.array([0.3 * math.cos(0.2), 0.3 * math.sin(0.2), *rolling])
    np.testing.assert_allclose(estimate.relative, rolled(start, DT, 0.11), atol=1e-12)
    # the velocity forgets its correlations and takes std 0.3; then one step of rolling, the
    # covariance at constant velocity
    F = np.block([[np.eye(2), DT * np.eye(2)], [np.zeros((2, 2)), np.eye(2)]])
    P = np.zeros((4, 4))
    P[:2, :2] = P0[:2, :2]
    P[2:, 2:] = 0.3**2 * np.eye(2)
    expected = F @ P @ F.T + white_acceleration_q(config.acceleration_psd, DT)
    np.testing.assert_allclose(estimate.relative_cov, expected, rtol=1e-12, atol=1e-16)
    # a ball out of reach (0.5 m > 0.45 m) is not kicked; nor by a zero kick
    for distance, kicked_by in ((0.5, kick), (0.3, np.zeros(2)), (0.3, None)):
        ball_filter = BallFilter(config)
        ball_filter.update(0.0, [sighting(distance, 0.0)], STILL, self_pose([0, 0, 0]))
        estimate = ball_filter.update(DT, [], STILL, self_pose([0, 0, 0]), kicked_by)
        np.testing.assert_allclose(estimate.relative, [distance, 0, 0, 0], atol=1e-15)


def test_a_kick_that_left_the_ball_where_it_was_is_undone_by_the_next_sighting() -> None:
    """Sightings with the range noise found at the feet (3 mm, 1.5 % of 0.2 m) of a resting
    ball 0.2 m ahead; our kick, then no sighting (the belief rolls off at the kick's speed);
    then the ball seen where it was, outside the gate: the belief had gone unconfirmed, so the
    filter restarts there (at rest, the sighting's covariance), not reading a second kick."""
    config, pose, near = EXACT_STEP, [0.0, 0.0, 0.0], np.diag([0.003**2, 0.015**2])
    ball_filter = BallFilter(config)
    for k in range(5):
        ball_filter.update(k * DT, [observe(pose, [0.2, 0.0], cov=near)], STILL, self_pose(pose))
    t = 4 * DT
    kicked = ball_filter.update(t + DT, [], STILL, self_pose(pose), kick_velocity=[2.0, 0.0])
    assert kicked.relative[2] > 1.0  # the belief took the kick
    seen = observe(pose, [0.2, 0.0], cov=near)
    estimate = ball_filter.update(t + 2 * DT, [seen], STILL, self_pose(pose))
    assert estimate.last_seen_s == t + 2 * DT
    np.testing.assert_allclose(estimate.relative, [0.2, 0.0, 0.0, 0.0], atol=1e-12)
    J = polar_jacobian(0.0, seen.range_m, seen.bearing_rad)
    np.testing.assert_allclose(estimate.relative_cov[:2, :2], J @ near @ J.T, rtol=1e-12)
    np.testing.assert_allclose(
        estimate.relative_cov[2:, 2:], config.initial_velocity_std_mps**2 * np.eye(2), rtol=1e-12
    )


def test_a_kick_seen_rolling_is_kept_and_the_ball_left_behind_forgotten() -> None:
    """Our kick of a ball 0.2 m ahead, seen rolling at the kick's speed the next frame: fused
    into the kicked belief, and the belief without the kick dropped (when the kicked belief is
    lost, nothing is left)."""
    pose = [0.0, 0.0, 0.0]
    ball_filter, t = steady_filter(pose, [0.2, 0.0])
    ball_filter.update(t + DT, [], STILL, self_pose(pose), kick_velocity=[2.0, 0.0])
    rolling = BallFilterConfig().own_kick_rolling_fraction * 2.0
    rolled_to = 0.2 + 2 * rolling * DT  # two frames at the kick's rolling speed
    estimate = ball_filter.update(
        t + 2 * DT, [observe(pose, [rolled_to, 0.0])], STILL, self_pose(pose)
    )
    assert estimate.last_seen_s == t + 2 * DT and estimate.relative[2] > 1.0
    for k in range(3, 200):
        estimate = ball_filter.update(t + k * DT, [], STILL, self_pose(pose))
        if not estimate.known:
            break
        assert estimate.relative[2] > 1.0, k  # rolling on to the end
    assert not estimate.known


def lost_after(config: BallFilterConfig, cov: FloatArray) -> int:
    """The first frame (1, 2, ...) without sightings after which a resting ball's covariance
    ``cov`` (4, 4) has a position std over ``config.lost_std_m`` (constant-velocity steps)."""
    F, Q = cv_transition(DT), white_acceleration_q(config.acceleration_psd, DT)
    for k in range(1, 1000):
        cov = F @ cov @ F.T + Q
        if math.sqrt(np.trace(cov[:2, :2])) > config.lost_std_m:
            return k
    raise AssertionError("never lost")


@pytest.mark.parametrize("lost_std_m", [0.3, 1.0])
def test_a_ball_unseen_is_lost_once_its_position_std_passes_lost_std_m(lost_std_m: float) -> None:
    """A resting ball seen five frames, then none: believed (at rest, where it was) up to the
    frame whose predicted position std passes ``lost_std_m`` (worked out with the
    constant-velocity covariance step), forgotten from that frame on (last_seen_s kept); the
    next sighting, anywhere, starts the filter afresh there."""
    config = BallFilterConfig(
        odometry_turn_std_floor_rad=0.0, lost_std_m=lost_std_m, start_confirm_s=None
    )
    pose, ball = [0.0, 0.0, 0.0], [2.0, 0.5]
    ball_filter = BallFilter(config)
    for k in range(5):
        ball_filter.update(k * DT, [observe(pose, ball)], STILL, self_pose(pose))
    t = 4 * DT
    k_lost = lost_after(config, ball_filter.estimate(self_pose(pose)).relative_cov)
    for k in range(1, k_lost + 1):
        estimate = ball_filter.update(t + k * DT, [], STILL, self_pose(pose))
        assert estimate.known == (k < k_lost), k
        assert estimate.last_seen_s == t
    np.testing.assert_array_equal(estimate.state, np.zeros(4))
    np.testing.assert_array_equal(estimate.relative, np.zeros(4))
    far = [0.5, -1.0]
    estimate = ball_filter.update(
        t + (k_lost + 1) * DT, [observe(pose, far)], STILL, self_pose(pose)
    )
    assert estimate.known and estimate.last_seen_s == t + (k_lost + 1) * DT
    np.testing.assert_allclose(estimate.state, [*far, 0.0, 0.0], atol=1e-12)


def test_a_kicked_belief_lost_falls_back_to_the_ball_left_where_it_was() -> None:
    """Our kick of a ball 0.2 m ahead and nothing seen after: the kicked belief (velocity std
    0.3 m/s) is lost first; the filter then believes the ball where it was, at rest, until
    that belief is lost too."""
    pose = [0.0, 0.0, 0.0]
    ball_filter, t = steady_filter(pose, [0.2, 0.0])
    ball_filter.update(t + DT, [], STILL, self_pose(pose), kick_velocity=[2.0, 0.0])
    states = []
    for k in range(2, 200):
        estimate = ball_filter.update(t + k * DT, [], STILL, self_pose(pose))
        if not estimate.known:
            break
        states.append(estimate.relative.copy())
    speeds = np.hypot(np.array(states)[:, 2], np.array(states)[:, 3])
    fell_back = int(np.argmax(speeds < 0.5))
    assert 0 < fell_back < len(states) - 1  # rolling first, then the ball left behind
    assert np.all(speeds[:fell_back] > 1.0) and np.all(speeds[fell_back:] < 1e-9)
    np.testing.assert_allclose(
        np.array(states)[fell_back:, :2], [[0.2, 0.0]] * (len(states) - fell_back), atol=1e-9
    )


def always(point: FloatArray) -> bool:
    return True


def never(point: FloatArray) -> bool:
    return False


def test_a_ball_in_view_but_unseen_is_lost_once_missing_it_each_time_is_unlikely() -> None:
    """A resting ball believed 2 m ahead (the default chance to see it there 0.8): in view
    without a sighting, lost on the third such frame since its last fused sighting (0.2³ < 0.01
    <= 0.2²), whether or not those frames are in a row; out of view (or view unknown) it stays
    believed; a fused sighting starts the count again."""
    pose = [0.0, 0.0, 0.0]
    assert BallFilterConfig().chance_to_see(2.0) == 0.8
    for views in ([always] * 3, [always, never, always, None, always]):
        ball_filter, t = steady_filter(pose, [2.0, 0.0])
        for k, in_view in enumerate(views, start=1):
            estimate = ball_filter.update(t + k * DT, [], STILL, self_pose(pose), in_view=in_view)
            assert estimate.known == (k < len(views)), (views, k)
    ball_filter, t = steady_filter(pose, [2.0, 0.0])
    frames = [[], [], [observe(pose, [2.0, 0.0])], [], []]
    for k, seen in enumerate(frames, start=1):
        estimate = ball_filter.update(t + k * DT, seen, STILL, self_pose(pose), in_view=always)
        assert estimate.known, k


@pytest.mark.parametrize(
    ("range_m", "chance"),
    [(0.3, 0.0), (0.6, 0.0), (0.61, 0.7), (1.0, 0.7), (1.5, 0.8), (2.5, 0.86), (3.01, 0.0)],
)
def test_the_chance_to_see_a_ball_in_view_is_its_range_band_s(
    range_m: float, chance: float
) -> None:
    assert BallFilterConfig().chance_to_see(range_m) == chance


@pytest.mark.parametrize(
    ("robot", "near_chance", "lost_at"),
    [
        (None, 0.0, 3),  # no robot known ([]): 0.2^3 < 0.01
        ([2.0, 0.45], 0.0, None),  # a robot 0.45 m beside the ball: its misses do not count
        ([2.0, 0.55], 0.0, 3),  # 0.55 m away: farther than near_robot_m, as in the open
        ([2.0, 0.45], 0.5, 7),  # counted at 0.5: 0.5^7 < 0.01 <= 0.5^6
        ([2.0, 0.45], 0.95, 3),  # at most the range band's 0.8
    ],
)
def test_misses_beside_a_robot_count_at_the_near_robot_chance(
    robot: list[float] | None, near_chance: float, lost_at: int | None
) -> None:
    """A resting ball believed 2 m ahead, in view and unseen for ten frames, with a robot
    believed beside it (robot frame): lost on the frame where the product of the misses'
    chances (0.8 in the open, at most ``near_robot_detection_chance`` within ``near_robot_m``
    = 0.5 m) falls under ``lost_chance`` = 0.01, or never within ten frames at chance 0."""
    pose = [0.0, 0.0, 0.0]
    config = dataclasses.replace(EXACT_STEP, near_robot_detection_chance=near_chance)
    assert config.chance_to_see(2.0, beside_robot=True) == min(0.8, near_chance)
    ball_filter, t = steady_filter(pose, [2.0, 0.0], config)
    robots = [] if robot is None else [robot, [-3.0, 0.0]]  # [] is no robot, as None
    for k in range(1, 11):
        estimate = ball_filter.update(
            t + k * DT, [], STILL, self_pose(pose), in_view=always, robots=robots
        )
        assert estimate.known == (lost_at is None or k < lost_at), k


def test_a_ball_where_the_camera_cannot_find_it_is_not_lost_by_misses() -> None:
    """Believed 0.4 m and 3.5 m away (a chance of 0 to see it there), in view and unseen for
    ten frames: still believed."""
    pose = [0.0, 0.0, 0.0]
    for ball in ([0.4, 0.0], [3.5, 0.0]):
        ball_filter, t = steady_filter(pose, ball)
        for k in range(1, 11):
            estimate = ball_filter.update(t + k * DT, [], STILL, self_pose(pose), in_view=always)
        assert estimate.known, ball


def test_a_kicked_belief_in_view_unseen_falls_back_to_the_ball_left_behind() -> None:
    """Our kick of a ball 0.2 m ahead; the camera would see anything 0.5 m or more ahead with
    a chance of 0.85, and nothing is seen: the kicked belief is lost on its third frame in
    view (0.15³ < 0.01 <= 0.15²); the filter then believes the ball where it was, at rest, which it
    keeps (out of view)."""
    config = dataclasses.replace(EXACT_STEP, detection_chance=((10.0, 0.85),))
    pose = [0.0, 0.0, 0.0]

    def ahead(point: FloatArray) -> bool:
        return bool(point[0] >= 0.5)

    ball_filter = BallFilter(config)
    for k in range(5):
        ball_filter.update(k * DT, [observe(pose, [0.2, 0.0])], STILL, self_pose(pose))
    t = 4 * DT
    estimate = ball_filter.update(t + DT, [], STILL, self_pose(pose), [2.0, 0.0], in_view=ahead)
    k = 1
    while estimate.relative[0] < 0.5 and k < 20:  # rolling into view: the first miss
        k += 1
        estimate = ball_filter.update(t + k * DT, [], STILL, self_pose(pose), in_view=ahead)
    assert estimate.relative[0] >= 0.5
    for miss in (2, 3):
        estimate = ball_filter.update(
            t + (k + miss - 1) * DT, [], STILL, self_pose(pose), in_view=ahead
        )
        assert estimate.known
        assert (estimate.relative[2] > 1.0) == (miss < 3), miss
    np.testing.assert_allclose(estimate.relative[:2], [0.2, 0.0], atol=1e-9)
    for more in range(1, 6):
        estimate = ball_filter.update(
            t + (k + 2 + more) * DT, [], STILL, self_pose(pose), in_view=ahead
        )
        assert estimate.known


# --- BallFilter: simulated balls ----------------------------------------------------------------


def test_a_rolling_ball_seen_from_a_walking_robot_is_tracked_consistently() -> None:
    """Balls rolling with the model's deceleration, perturbed by the model's own white
    acceleration, seen with the sightings' stated noise by a robot that walks and turns, its
    odometry off the true motion by the model's own odometry noise: after 3 s each run's final
    NEES (robot frame) is chi2(4), so their sum over the runs lies in the chi2(4 n) band; the
    field estimate with the true pose is the truth on the field, and the position error is well
    below one sighting's."""
    config = BallFilterConfig()
    n_runs, n_frames = 100, 30
    L = np.linalg.cholesky(white_acceleration_q(config.acceleration_psd, DT))
    reported = np.array([0.02, 0.005, 0.03])  # per frame: 0.2 m/s forward, 0.3 rad/s left
    walk_std = config.odometry_translation_std_fraction * math.hypot(*reported[:2])
    turn_std = config.odometry_turn_std_fraction * reported[2] + config.odometry_turn_std_floor_rad
    nees, position_errors, single = [], [], []
    for seed in range(n_runs):
        rng = np.random.default_rng(seed)
        truth = np.array([1.5, -0.5, 0.8, 0.5])  # field frame
        pose = np.array([0.5, -1.0, 0.2])  # true pose
        ball_filter = BallFilter(config)
        for k in range(n_frames):
            odometry = STILL
            if k > 0:
                truth = rolled(truth, DT, config.deceleration_mps2) + L @ rng.standard_normal(4)
                step = reported[:2] + walk_std * rng.standard_normal(2)
                turn = reported[2] + turn_std * rng.standard_normal()
                pose = np.array([*(pose[:2] + rot(pose[2]) @ step), pose[2] + turn])
                odometry = reported
            estimate = ball_filter.update(
                k * DT, [observe(pose, truth, rng)], odometry, self_pose(pose)
            )
            assert_psd(estimate.relative_cov)
        back = rot(-pose[2])
        relative = np.concatenate([back @ (truth[:2] - pose[:2]), back @ truth[2:]])
        error = estimate.relative - relative
        nees.append(float(error @ np.linalg.solve(estimate.relative_cov, error)))
        field_error = estimate.state - truth
        np.testing.assert_allclose(field_error[:2], rot(pose[2]) @ error[:2], atol=1e-12)
        position_errors.append(float(np.linalg.norm(error[:2])))
        r = math.dist(pose[:2], truth[:2])
        single.append(math.sqrt(COV[0, 0] + r**2 * COV[1, 1]))  # one sighting's RMS error
        assert estimate.known and estimate.last_seen_s == pytest.approx((n_frames - 1) * DT)
    low, high = chi2.ppf([0.0005, 0.9995], 4 * n_runs)
    assert low <= sum(nees) <= high, np.mean(nees)
    rms = math.sqrt(np.mean(np.square(position_errors)))
    assert rms < 0.8 * float(np.mean(single)), (rms, np.mean(single))


KICK = 1.5 * np.array([0.6, 0.8])  # m/s
KICKED_AT = 10  # the frame the kick is first seen in


@functools.lru_cache(maxsize=1)
def kicked_runs(
    n_seeds: int = 20, n_frames: int = 35
) -> list[tuple[list[BallEstimate], FloatArray]]:
    """Per seed: the estimates of a ball at rest for a second, kicked to 1.5 m/s just after
    frame ``KICKED_AT - 1`` and rolling on, seen with noise from the origin; and the truths."""
    config = BallFilterConfig()
    pose = np.zeros(3)
    runs = []
    for seed in range(n_seeds):
        rng = np.random.default_rng(100 + seed)
        ball_filter = BallFilter(config)
        truth = np.array([2.0, -1.0, 0.0, 0.0])
        estimates, truths = [], []
        for k in range(n_frames):
            if k == KICKED_AT:
                truth[2:] = KICK
            if k >= KICKED_AT:
                truth = rolled(truth, DT, config.deceleration_mps2)
            sightings = [observe(pose, truth, rng)]
            estimates.append(ball_filter.update(k * DT, sightings, STILL, self_pose(pose)))
            truths.append(truth.copy())
        runs.append((estimates, np.array(truths)))
    return runs


def test_a_kick_is_followed_without_a_restart() -> None:
    """The filter is never
    restarted (a restart puts it at rest: zero velocity with the initial velocity variance),
    the position stays within 0.2 m, the covariance PSD, and over the runs the velocity
    converges to the rolling ball's (median error < 0.15 m/s after 2.5 s)."""
    restarted = BallFilterConfig().initial_velocity_std_mps ** 2 * np.eye(2)
    final_velocity_errors = []
    for seed, (estimates, truths) in enumerate(kicked_runs()):
        for k, (estimate, truth) in enumerate(zip(estimates, truths, strict=True)):
            assert_psd(estimate.cov)
            if k > 0:
                assert not (
                    np.all(estimate.state[2:] == 0.0)
                    and np.array_equal(estimate.cov[2:, 2:], restarted)
                ), (seed, k)
            if k >= KICKED_AT:
                assert np.linalg.norm(estimate.state[:2] - truth[:2]) < 0.2, (seed, k)
        assert estimates[-1].last_seen_s == pytest.approx((len(estimates) - 1) * DT)
        final_velocity_errors.append(
            float(np.linalg.norm(estimates[-1].state[2:] - truths[-1, 2:]))
        )
    assert float(np.median(final_velocity_errors)) < 0.15, final_velocity_errors


def test_a_kick_is_followed_within_four_frames() -> None:
    """Every post-kick sighting is fused (last_seen_s each frame) and four frames after the
    kick the speed estimate exceeds 1 m/s with the position within 0.1 m, in every run."""
    for seed, (estimates, truths) in enumerate(kicked_runs()):
        for k in range(KICKED_AT, len(estimates)):
            assert estimates[k].last_seen_s == pytest.approx(k * DT), (seed, k)
        estimate, truth = estimates[KICKED_AT + 4], truths[KICKED_AT + 4]
        assert np.hypot(*estimate.state[2:]) > 1.0, (seed, estimate.state)
        assert np.linalg.norm(estimate.state[:2] - truth[:2]) < 0.1, seed


def test_a_kick_from_a_ball_estimated_nearly_at_rest_is_followed_as_from_rest() -> None:
    """Noise-free sightings of a resting ball, jittered by a centimetre so that the estimated
    speed is small but not zero, then a 1.5 m/s kick (sightings 0.15, 0.30, 0.45 m along y):
    every sighting is fused, the estimate follows the jitter-free one (the model has no jump at
    zero speed: within 0.05 m/s) and the third frame's speed is above 1 m/s."""
    pose = [0.0, 0.0, 0.0]
    followed = []
    for jitter in (0.0, 0.01):
        ball_filter = BallFilter()
        points = [[2.0, 0.0], [2.0 + jitter, 0.0], [2.0, jitter / 2], [2.0 - jitter / 2, 0.0]]
        for k in range(10):
            ball_filter.update(k * DT, [observe(pose, points[k % 4])], STILL, self_pose(pose))
        for k, y in enumerate((0.15, 0.30, 0.45), start=10):
            estimate = ball_filter.update(k * DT, [observe(pose, [2.0, y])], STILL, self_pose(pose))
            assert estimate.last_seen_s == k * DT, (jitter, k)  # fused
        assert estimate.state[3] > 1.0, (jitter, estimate.state)
        followed.append(estimate.state)
    np.testing.assert_allclose(followed[0][2:], followed[1][2:], atol=0.05)


# --- BallFilter: false sightings and the candidate restart -------------------------------------


def steady_filter(
    pose: ArrayLike, ball: ArrayLike, config: BallFilterConfig | None = None
) -> tuple[BallFilter, float]:
    """A filter (``config``, else :data:`EXACT_STEP`) that saw a resting ``ball`` exactly for
    five frames; and the last frame's time."""
    ball_filter = BallFilter(config if config is not None else EXACT_STEP)
    for k in range(5):
        ball_filter.update(k * DT, [observe(pose, ball)], STILL, self_pose(pose))
    return ball_filter, 4 * DT


def test_a_single_far_off_sighting_is_not_fused() -> None:
    pose, ball = [0.5, 0.5, 1.0], [1.5, 2.0]
    ball_filter, t = steady_filter(pose, ball)
    before = ball_filter.estimate(self_pose(pose))
    np.testing.assert_allclose(before.state, [*ball, 0.0, 0.0], atol=1e-12)
    estimate = ball_filter.update(t + DT, [observe(pose, [3.0, 3.5])], STILL, self_pose(pose))
    # a resting ball's prediction: the same state, the covariance of DT more rolling at rest
    np.testing.assert_allclose(estimate.state, before.state, atol=1e-12)
    F = cv_transition(DT)
    expected = F @ before.relative_cov @ F.T + white_acceleration_q(EXACT_STEP.acceleration_psd, DT)
    np.testing.assert_allclose(estimate.relative_cov, expected, rtol=1e-12, atol=1e-16)
    assert estimate.last_seen_s == before.last_seen_s == t
    assert_psd(estimate.cov)


def test_two_agreeing_far_off_sightings_in_a_row_restart_the_filter_there() -> None:
    pose, ball, moved = [0.5, 0.5, 1.0], [1.5, 2.0], [3.0, 3.5]
    config = EXACT_STEP
    ball_filter, t = steady_filter(pose, ball)
    ball_filter.update(t + DT, [observe(pose, moved)], STILL, self_pose(pose))
    second = observe(pose, np.add(moved, [0.01, -0.01]))
    estimate = ball_filter.update(t + 2 * DT, [second], STILL, self_pose(pose))
    assert estimate.known and estimate.last_seen_s == t + 2 * DT
    x, y, theta = pose
    phi = theta + second.bearing_rad
    z = [x + second.range_m * math.cos(phi), y + second.range_m * math.sin(phi)]
    np.testing.assert_allclose(estimate.state, [*z, 0.0, 0.0], atol=1e-12)
    J = polar_jacobian(theta, second.range_m, second.bearing_rad)
    np.testing.assert_allclose(estimate.cov[:2, :2], J @ COV @ J.T, rtol=1e-12)
    np.testing.assert_allclose(estimate.cov[:2, 2:], np.zeros((2, 2)), atol=1e-16)
    np.testing.assert_allclose(
        estimate.cov[2:, 2:], config.initial_velocity_std_mps**2 * np.eye(2), rtol=1e-14, atol=1e-16
    )
    # from there on it follows the moved ball
    estimate = ball_filter.update(t + 3 * DT, [observe(pose, moved)], STILL, self_pose(pose))
    assert estimate.last_seen_s == t + 3 * DT
    assert np.linalg.norm(estimate.state[:2] - moved) < 0.02


def test_a_jump_after_a_fused_frame_is_a_kick_after_an_unfused_one_a_restart() -> None:
    """A resting ball 2 m ahead, then seen 0.3 m to the left (outside the gate, inside the
    kicked gate): right after a fused frame the sighting is fused as a kick (last_seen_s, a
    velocity over 1 m/s to the left); one frame later than that (the last frame fused nothing)
    the filter restarts at the sighting: at rest, the sighting's covariance, the initial
    velocity std."""
    pose, ball, moved = [0.0, 0.0, 0.0], [2.0, 0.0], [2.0, 0.3]
    config = EXACT_STEP
    ball_filter, t = steady_filter(pose, ball)
    estimate = ball_filter.update(t + DT, [observe(pose, moved)], STILL, self_pose(pose))
    assert estimate.last_seen_s == t + DT and estimate.relative[3] > 1.0
    ball_filter, t = steady_filter(pose, ball)
    ball_filter.update(t + DT, [], STILL, self_pose(pose))
    seen = observe(pose, moved)
    estimate = ball_filter.update(t + 2 * DT, [seen], STILL, self_pose(pose))
    assert estimate.last_seen_s == t + 2 * DT
    np.testing.assert_allclose(estimate.relative, [*moved, 0.0, 0.0], atol=1e-12)
    J = polar_jacobian(0.0, seen.range_m, seen.bearing_rad)
    expected = np.zeros((4, 4))
    expected[:2, :2] = J @ COV @ J.T
    expected[2:, 2:] = config.initial_velocity_std_mps**2 * np.eye(2)
    np.testing.assert_allclose(estimate.relative_cov, expected, rtol=1e-12, atol=1e-16)


def test_a_far_off_sighting_between_true_ones_or_disagreeing_ones_restart_nothing() -> None:
    pose, ball = [0.0, 0.0, 0.0], [2.0, 0.0]
    ball_filter, t = steady_filter(pose, ball)
    far_a, far_b = [2.0, 2.0], [0.5, -2.0]
    frames = [
        (far_a, False),  # candidate A
        (ball, True),  # fused: the candidate is forgotten
        (far_a, False),  # a new candidate, not a restart
        (far_b, False),  # disagrees with A: now candidate B
        (ball, True),
    ]
    for k, (point, fused) in enumerate(frames, start=1):
        estimate = ball_filter.update(t + k * DT, [observe(pose, point)], STILL, self_pose(pose))
        assert (estimate.last_seen_s == t + k * DT) == fused, k
        assert np.linalg.norm(estimate.state[:2] - ball) < 1e-9, k
        assert_psd(estimate.cov)
    # B then B again: a restart at B
    for k in (6, 7):
        estimate = ball_filter.update(t + k * DT, [observe(pose, far_b)], STILL, self_pose(pose))
    np.testing.assert_allclose(estimate.state, [*far_b, 0.0, 0.0], atol=1e-12)


# --- BallFilter: time, reset, configuration -----------------------------------------------------


def test_time_must_be_finite_and_must_not_go_back_and_odometry_be_three_numbers() -> None:
    ball_filter = BallFilter()
    pose = self_pose([0, 0, 0])
    ball_filter.update(1.0, [sighting(2.0, 0.1)], STILL, pose)
    before = ball_filter.estimate(pose)
    for bad in (0.99, math.nan, math.inf, -math.inf):
        with pytest.raises(ValueError, match="time_s"):
            ball_filter.update(bad, [sighting(2.0, 0.1)], STILL, pose)
    for odometry in (np.zeros(2), np.array([0.0, math.nan, 0.0])):
        with pytest.raises(ValueError, match="odometry"):
            ball_filter.update(1.1, [sighting(2.0, 0.1)], odometry, pose)
    after = ball_filter.estimate(pose)
    np.testing.assert_array_equal(after.relative, before.relative)
    np.testing.assert_array_equal(after.relative_cov, before.relative_cov)
    ball_filter.update(1.0, [], STILL, pose)  # the same time again is fine
    with pytest.raises(ValueError, match="time_s"):
        BallFilter().update(math.nan, [], STILL, pose)


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"sightings": [sighting(math.nan, 0.1)]}, ValueError, r"sightings\[0\]\.range_m"),
        ({"sightings": [sighting(-1.0, 0.1)]}, ValueError, r"sightings\[0\]\.range_m"),
        ({"sightings": [sighting(2.0, math.inf)]}, ValueError, r"sightings\[0\]\.bearing_rad"),
        (
            {"sightings": [sighting(2.0, 0.1, [[0.01, 0.009], [-0.009, 0.001]])]},
            ValueError,
            r"sightings\[0\]\.cov must be symmetric",
        ),
        ({"sightings": [sighting(2.0, 0.1, np.zeros((2, 2)))]}, ValueError, "positive definite"),
        ({"sightings": [sighting(2.0, 0.1, np.eye(3))]}, ValueError, r"\(2, 2\)"),
        ({"sightings": [None]}, TypeError, r"sightings\[0\] must be a BallSighting"),
        ({"sightings": sighting(2.0, 0.1)}, TypeError, "sequence of BallSighting"),
        ({"kick_velocity": np.array([math.nan, 0.0])}, ValueError, "kick_velocity"),
        ({"kick_velocity": np.zeros(3)}, ValueError, "kick_velocity"),
        ({"self_pose": self_pose([math.nan, 0, 0])}, ValueError, "self_pose.pose"),
        ({"self_pose": self_pose([0, 0, 0], -np.eye(3))}, ValueError, "self_pose.pose_cov"),
        ({"robots": [[2.0, math.nan]]}, ValueError, r"robots must be finite.*rows \[0\]"),
        (
            {"sightings": [dataclasses.replace(sighting(2.0, 0.1), score=math.nan)]},
            ValueError,
            r"sightings\[0\]\.score",
        ),
        ({"robots": [1.0, 2.0, 3.0]}, ValueError, r"robots must have shape \(N, 2\)"),
    ],
)
def test_bad_arguments_raise_naming_them_and_leave_the_filter_as_it_was(
    kwargs: dict[str, object], error: type[Exception], match: str
) -> None:
    """A refused update changes nothing: the same update made right afterwards gives what it
    gives on a filter that never saw the bad one (the odometry is not applied twice)."""
    pose = self_pose([0, 0, 0])
    moved = np.array([0.5, 0.0, 0.0])

    def started() -> BallFilter:
        ball_filter = BallFilter()
        ball_filter.update(0.0, [sighting(0.12, 0.0)], STILL, pose)  # within kick reach
        return ball_filter

    ball_filter = started()
    args = {"sightings": [sighting(2.0, 0.1)], "self_pose": pose, **kwargs}
    with pytest.raises(error, match=match):
        ball_filter.update(0.1, odometry=moved, **args)  # type: ignore[arg-type]
    after = ball_filter.update(0.1, [], moved, pose)
    clean = started().update(0.1, [], moved, pose)
    np.testing.assert_array_equal(after.relative, clean.relative)
    np.testing.assert_array_equal(after.relative_cov, clean.relative_cov)


def test_reset_forgets_the_ball_the_time_and_the_outlier() -> None:
    pose = [0.0, 0.0, 0.0]
    ball_filter, t = steady_filter(pose, [2.0, 0.0])
    ball_filter.update(t + DT, [observe(pose, [0.5, 2.0])], STILL, self_pose(pose))  # outlier
    ball_filter.reset()
    estimate = ball_filter.estimate(self_pose(pose))
    assert not estimate.known and estimate.last_seen_s == -math.inf
    np.testing.assert_array_equal(estimate.state, np.zeros(4))
    # an earlier time is fine after a reset; two sightings start the filter anew
    ball_filter.update(0.0, [observe(pose, [2.0, 0.0])], STILL, self_pose(pose))
    estimate = ball_filter.update(DT, [observe(pose, [2.0, 0.0])], STILL, self_pose(pose))
    assert estimate.known and estimate.last_seen_s == DT
    # the old candidate is gone: one far sighting there is not a restart
    estimate = ball_filter.update(2 * DT, [observe(pose, [0.5, 2.0])], STILL, self_pose(pose))
    assert estimate.last_seen_s == DT
    np.testing.assert_allclose(estimate.state[:2], [2.0, 0.0], atol=1e-12)


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("deceleration_mps2", -0.1),
        ("deceleration_mps2", math.nan),
        ("acceleration_psd", 0.0),
        ("initial_velocity_std_mps", 0.0),
        ("kick_velocity_std_mps", -1.0),
        ("lost_std_m", 0.0),
        ("lost_std_m", math.nan),
        ("lost_chance", 0.0),
        ("lost_chance", 1.0),
        ("detection_chance", ()),
        ("detection_chance", ((1.0, 0.5), (0.5, 0.5))),
        ("detection_chance", ((0.0, 0.5),)),
        ("detection_chance", ((1.0, 1.5),)),
        ("detection_chance", ((math.nan, 0.5),)),
        ("detection_chance", ((1.0, 0.5), (math.inf, 0.5))),
        ("view_margin", 0.5),
        ("gate_probability", 1.0),
        ("gate_probability", 0.0),
        ("odometry_translation_std_fraction", -0.1),
        ("odometry_turn_std_floor_rad", math.inf),
        ("own_kick_reach_m", 0.0),
        ("own_kick_rolling_fraction", 0.0),
        ("own_kick_rolling_fraction", 1.1),
        ("own_kick_std_mps", 0.0),
        ("start_confirm_s", 0.0),
        ("start_confirm_s", -0.1),
        ("start_confirm_s", math.nan),
        ("start_at_once_score", 0.0),
        ("start_at_once_score", 1.5),
        ("start_at_once_score", math.nan),
        ("near_robot_m", -0.1),
        ("near_robot_m", math.inf),
        ("near_robot_detection_chance", -0.1),
        ("near_robot_detection_chance", 1.5),
    ],
)
def test_config_rejects_bad_values(field: str, value: float) -> None:
    with pytest.raises(ValueError, match=f"BallFilterConfig.{field}"):
        BallFilterConfig(**{field: value})


def test_config_wants_detection_chance_as_a_tuple_of_pairs() -> None:
    for bad in ([(1.0, 0.5)], ((1.0, 0.5, 0.1),), ([1.0, 0.5],)):
        with pytest.raises(TypeError, match=r"BallFilterConfig\.detection_chance"):
            BallFilterConfig(detection_chance=bad)  # type: ignore[arg-type]
    for bound in ("1.0", None, True):
        with pytest.raises(TypeError, match=r"BallFilterConfig\.detection_chance\[0\]\[0\]"):
            BallFilterConfig(detection_chance=((bound, 0.5),))  # type: ignore[arg-type]


def test_config_gate_is_the_chi_square_quantile() -> None:
    assert BallFilterConfig(gate_probability=0.99).gate_threshold == pytest.approx(
        -2 * math.log(0.01)
    )
    assert BallFilterConfig(deceleration_mps2=0.0).deceleration_mps2 == 0.0
    assert BallFilterConfig(own_kick_rolling_fraction=1.0).own_kick_rolling_fraction == 1.0
