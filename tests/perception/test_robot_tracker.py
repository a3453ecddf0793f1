"""The multi-robot tracker against independent truths: a Kalman step worked out by hand per
axis, the closed-form first-order covariance of a sighting moved by an uncertain pose (and a
Monte Carlo of it), simulated constant-velocity targets, and chi-square consistency bands."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numpy.typing import ArrayLike
from scipy.stats import chi2

from perception.geometry import FloatArray
from perception.tracking import RobotTracker, RobotTrackerConfig
from perception.types import RobotSighting, RobotTrack, SlamEstimate
from perception.validation import InvalidTypeError

POSE0 = np.zeros(3)  # identity pose (m, m, rad)
EXACT = np.zeros((3, 3))  # covariance of an exactly known pose
COV = np.diag([0.05**2, 0.02**2])  # (m², rad²) range and bearing noise of a sighting


def robot_sighting(
    range_m: float, bearing_rad: float, cov: ArrayLike = COV, team: int | None = None
) -> RobotSighting:
    """A RobotSighting with the given (range, bearing) and covariance."""
    return RobotSighting(
        range_m=float(range_m),
        bearing_rad=float(bearing_rad),
        cov=np.asarray(cov, dtype=np.float64),
        team=team,
    )


def observe(
    pose: ArrayLike,
    point: ArrayLike,
    rng: np.random.Generator | None = None,
    cov: ArrayLike = COV,
    team: int | None = None,
) -> RobotSighting:
    """The sighting of the field ``point`` (2,) from the true ``pose`` (3,), with noise drawn
    from ``cov`` when ``rng`` is given."""
    x, y, theta = np.asarray(pose, dtype=np.float64)
    dx, dy = np.asarray(point, dtype=np.float64) - (x, y)
    z = np.array([math.hypot(dx, dy), math.atan2(dy, dx) - theta])
    if rng is not None:
        z = z + rng.multivariate_normal(np.zeros(2), np.asarray(cov, dtype=np.float64))
    return robot_sighting(z[0], z[1], cov, team)


def nearest(tracks: Sequence[RobotTrack], point: ArrayLike) -> RobotTrack:
    """The track whose position is nearest to ``point`` (2,)."""
    return min(tracks, key=lambda t: float(np.linalg.norm(t.state[:2] - np.asarray(point))))


def assert_psd(cov: FloatArray) -> None:
    """``cov`` is exactly symmetric and positive semidefinite up to rounding."""
    np.testing.assert_array_equal(cov, cov.T)
    assert np.linalg.eigvalsh(cov).min() >= -1e-12 * max(1.0, float(np.abs(cov).max()))


# --- the Kalman step by hand ------------------------------------------------------------------


def test_birth_predict_and_update_match_a_kalman_step_worked_out_per_axis() -> None:
    q, v0, dt = 0.2, 0.5, 0.5
    var_r, var_b = 0.01, 0.0025
    cov = np.diag([var_r, var_b])
    tracker = RobotTracker(RobotTrackerConfig(acceleration_psd=q, initial_velocity_std=v0))

    # Birth at t = 0 from a sighting straight ahead at 2 m: bearing 0, so range is along x and
    # the bearing noise across it, r sigma_b on y.
    (track,) = tracker.update(0.0, [robot_sighting(2.0, 0.0, cov)], (POSE0, EXACT))
    np.testing.assert_allclose(track.state, [2.0, 0.0, 0.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(track.cov, np.diag([var_r, 4.0 * var_b, v0**2, v0**2]), atol=1e-15)
    assert (track.track_id, track.confirmed, track.last_seen_s) == (0, False, 0.0)

    # Each axis is a (position, velocity) pair with its own scalars; x and y are uncorrelated.
    def predicted(p0: float) -> tuple[float, float, float]:
        """(Ppp, Ppv, Pvv) after dt of P0 = diag(p0, v0²) under white acceleration q."""
        return p0 + dt**2 * v0**2 + q * dt**3 / 3, dt * v0**2 + q * dt**2 / 2, v0**2 + q * dt

    # Predict only: a frame without sightings.
    (track,) = tracker.update(dt, [], (POSE0, EXACT))
    (xpp, xpv, xvv), (ypp, ypv, yvv) = predicted(var_r), predicted(4.0 * var_b)
    expected = np.array(
        [[xpp, 0, xpv, 0], [0, ypp, 0, ypv], [xpv, 0, xvv, 0], [0, ypv, 0, yvv]], dtype=float
    )
    np.testing.assert_allclose(track.state, [2.0, 0.0, 0.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(track.cov, expected, rtol=1e-12)

    # Update at the same time with a sighting at 2.1 m straight ahead: scalar Kalman per axis.
    r2 = 2.1
    (track,) = tracker.update(dt, [robot_sighting(r2, 0.0, cov)], (POSE0, EXACT))
    rx, ry = var_r, r2**2 * var_b
    sx, sy = xpp + rx, ypp + ry
    kxp, kxv, kyp, kyv = xpp / sx, xpv / sx, ypp / sy, ypv / sy
    nu = r2 - 2.0
    np.testing.assert_allclose(track.state, [2.0 + kxp * nu, 0.0, kxv * nu, 0.0], atol=1e-14)
    posterior = np.array(
        [
            [xpp - kxp * kxp * sx, 0, xpv - kxp * kxv * sx, 0],
            [0, ypp - kyp * kyp * sy, 0, ypv - kyp * kyv * sy],
            [xpv - kxp * kxv * sx, 0, xvv - kxv * kxv * sx, 0],
            [0, ypv - kyp * kyv * sy, 0, yvv - kyv * kyv * sy],
        ]
    )
    np.testing.assert_allclose(track.cov, posterior, rtol=1e-10, atol=1e-15)
    assert track.last_seen_s == dt


# --- the pose covariance in R -----------------------------------------------------------------


def closed_form_r(
    pose: FloatArray, pose_cov: FloatArray, range_m: float, bearing: float, cov: FloatArray
) -> FloatArray:
    """R of a sighting, from the geometry: along the ray ``u`` the range noise, across it ``n``
    the bearing and heading noise scaled by the range, plus the pose's position covariance and
    its correlation with the heading (the heading moves the point by ``range * n``)."""
    phi = pose[2] + bearing
    u, n = np.array([math.cos(phi), math.sin(phi)]), np.array([-math.sin(phi), math.cos(phi)])
    var_r, var_b, cov_rb = cov[0, 0], cov[1, 1], cov[0, 1]
    sensor = var_r * np.outer(u, u) + range_m**2 * var_b * np.outer(n, n)
    sensor += range_m * cov_rb * (np.outer(u, n) + np.outer(n, u))
    p_xy, p_xt, var_t = pose_cov[:2, :2], pose_cov[:2, 2], pose_cov[2, 2]
    pose_part = p_xy + range_m * (np.outer(p_xt, n) + np.outer(n, p_xt))
    return sensor + pose_part + range_m**2 * var_t * np.outer(n, n)


def test_the_pose_covariance_enters_r_and_widens_far_sightings_across_the_ray() -> None:
    pose = np.array([1.0, -0.5, 0.4])
    pose_cov = np.array([[0.01, 0.002, 0.003], [0.002, 0.02, -0.004], [0.003, -0.004, 0.2**2]])
    cov = np.array([[0.05**2, 0.0002], [0.0002, 0.02**2]])
    bearing = 0.3
    n = np.array([-math.sin(pose[2] + bearing), math.cos(pose[2] + bearing)])
    cross_range, without_heading = {}, {}
    for range_m in (0.5, 4.0):
        tracker = RobotTracker()
        (track,) = tracker.update(0.0, [robot_sighting(range_m, bearing, cov)], (pose, pose_cov))
        R = track.cov[:2, :2]  # a new track's position covariance is its sighting's R
        np.testing.assert_allclose(R, closed_form_r(pose, pose_cov, range_m, bearing, cov))
        np.testing.assert_allclose(track.cov[2:, 2:], 0.5**2 * np.eye(2))
        np.testing.assert_array_equal(track.cov[:2, 2:], 0.0)
        cross_range[range_m] = float(n @ R @ n)
        # without the heading variance the far sighting's cross-range variance is much smaller
        exact = pose_cov.copy()
        exact[2, :] = exact[:, 2] = 0.0
        (track,) = RobotTracker().update(
            0.0, [robot_sighting(range_m, bearing, cov)], (pose, exact)
        )
        without_heading[range_m] = float(n @ track.cov[:2, :2] @ n)
        np.testing.assert_allclose(
            cross_range[range_m] - without_heading[range_m],
            range_m**2 * pose_cov[2, 2] + 2 * range_m * float(n @ pose_cov[:2, 2]),
            rtol=1e-10,
        )
    assert cross_range[4.0] > 10 * cross_range[0.5]
    assert cross_range[4.0] > 10 * without_heading[4.0]


def test_r_matches_a_monte_carlo_of_the_pose_and_sighting_noise() -> None:
    """First order is close for small angle noise: sample the pose and the sighting, move the
    sighting into the field with the exact trigonometry and compare covariances."""
    rng = np.random.default_rng(3)
    pose = np.array([-1.0, 2.0, -2.5])
    pose_cov = np.diag([0.03**2, 0.02**2, 0.03**2])
    range_m, bearing = 3.0, 1.0
    (track,) = RobotTracker().update(
        0.0, [robot_sighting(range_m, bearing, COV)], SlamEstimate_of(pose, pose_cov)
    )
    n_samples = 200_000
    poses = rng.multivariate_normal(pose, pose_cov, n_samples)
    zs = rng.multivariate_normal([range_m, bearing], COV, n_samples)
    phi = poses[:, 2] + zs[:, 1]
    points = poses[:, :2] + zs[:, :1] * np.column_stack([np.cos(phi), np.sin(phi)])
    empirical = np.cov(points.T)
    np.testing.assert_allclose(track.state[:2], points.mean(axis=0), atol=3e-3)
    np.testing.assert_allclose(track.cov[:2, :2], empirical, rtol=0.03, atol=2e-5)


def SlamEstimate_of(pose: FloatArray, pose_cov: FloatArray) -> SlamEstimate:  # noqa: N802
    """A SlamEstimate with an empty map."""
    return SlamEstimate(
        pose=pose,
        pose_cov=pose_cov,
        landmark_ids=np.zeros(0, dtype=np.int64),
        landmarks=np.zeros((0, 2)),
        landmark_covs=np.zeros((0, 2, 2)),
    )


def test_the_gate_uses_each_sightings_own_r() -> None:
    """1 m off a well-known track: outside the gate with a precise sighting, inside with a
    sighting whose R is large (S = H P H^T + R of that sighting)."""
    config = RobotTrackerConfig(gate_probability=0.99)
    for sigma_r, expected_tracks in ((0.05, 2), (1.0, 1)):
        tracker = RobotTracker(config)
        for k in range(10):
            tracker.update(0.1 * k, [robot_sighting(2.0, 0.0)], (POSE0, EXACT))
        cov = np.diag([sigma_r**2, 0.02**2])
        tracks = tracker.update(1.0, [robot_sighting(3.0, 0.0, cov)], (POSE0, EXACT))
        assert len(tracks) == expected_tracks


@pytest.mark.parametrize(("offset_m", "winner"), [(0.2, 0), (0.3, 1)])
def test_association_prefers_the_likelier_track_not_the_smaller_mahalanobis_distance(
    offset_m: float, winner: int
) -> None:
    """A precise track 0 at (2, 0) and a diffuse tentative track 1 born 0.45 m beyond it. A
    sighting 0.2 m beyond track 0 is nearer track 1 in Mahalanobis distance (its S is large),
    yet likelier from track 0: ``d² + ln det S`` (the Gaussian negative log-likelihood) decides.
    0.3 m beyond, track 1 is the likelier too."""
    q, dt = 0.1, 0.5
    tracker = RobotTracker(RobotTrackerConfig(acceleration_psd=q))
    for k in range(10):
        tracker.update(0.1 * k, [observe(POSE0, (2.0, 0.0))], (POSE0, EXACT))
    tracks = tracker.update(
        1.0, [observe(POSE0, (2.0, 0.0)), observe(POSE0, (2.45, 0.0))], (POSE0, EXACT)
    )
    assert [t.track_id for t in tracks] == [0, 1]
    point = np.array([2.0 + offset_m, 0.0])
    sighting = observe(POSE0, point)
    R = closed_form_r(POSE0, EXACT, sighting.range_m, sighting.bearing_rad, sighting.cov)
    F = np.block([[np.eye(2), dt * np.eye(2)], [np.zeros((2, 2)), np.eye(2)]])
    Qk = q * np.block(
        [[dt**3 / 3 * np.eye(2), dt**2 / 2 * np.eye(2)], [dt**2 / 2 * np.eye(2), dt * np.eye(2)]]
    )
    d2, nll = [], []
    for track in tracks:
        x, P = F @ track.state, F @ track.cov @ F.T + Qk
        S, y = P[:2, :2] + R, point - x[:2]
        d2.append(float(y @ np.linalg.solve(S, y)))
        nll.append(d2[-1] + math.log(np.linalg.det(S)))
    assert max(d2) < chi2.ppf(0.999, 2)  # both in the gate
    assert int(np.argmin(nll)) == winner
    if offset_m == 0.2:
        assert int(np.argmin(d2)) == 1  # Mahalanobis distance alone would pick track 1
    after = tracker.update(1.0 + dt, [sighting], (POSE0, EXACT))
    assert {t.track_id: t.last_seen_s for t in after} == {winner: 1.5, 1 - winner: 1.0}


# --- simulated targets ------------------------------------------------------------------------


def moving_robot(t: float) -> FloatArray:
    """The sensing robot's pose (3,) at ``t`` s: walking along x and turning its body."""
    return np.array([-3.0 + 0.1 * t, 0.5, 0.3 * math.sin(0.5 * t)])


@pytest.mark.parametrize("seed", range(5))
def test_a_constant_velocity_target_seen_from_a_moving_robot_is_tracked(seed: int) -> None:
    """Noisy sightings (5 cm, 0.02 rad) from 2 to 4 m for 10 s at 10 Hz; a small ``q`` as the
    target really keeps its velocity."""
    rng = np.random.default_rng(seed)
    start, velocity = np.array([-1.0, -1.5]), np.array([0.3, 0.2])
    tracker = RobotTracker(RobotTrackerConfig(acceleration_psd=0.01))
    errors = []
    for k in range(101):
        t = 0.1 * k
        pose, truth = moving_robot(t), start + velocity * t
        tracks = tracker.update(t, [observe(pose, truth, rng)], (pose, EXACT))
        track = next(track for track in tracks if track.track_id == 0)
        errors.append(track.state - np.concatenate([truth, velocity]))
    assert track.confirmed
    late = np.array(errors[-20:])  # the last 2 s
    assert math.sqrt(np.mean(np.sum(late[:, :2] ** 2, axis=1))) < 0.1  # m, rms
    assert math.sqrt(np.mean(np.sum(late[:, 2:] ** 2, axis=1))) < 0.12  # m/s, rms; |v| = 0.36
    error = errors[-1]  # the filter's own covariance covers the final error
    assert error @ np.linalg.solve(track.cov, error) < chi2.ppf(0.9999, 4)


def test_without_process_noise_the_track_is_the_batch_least_squares_line() -> None:
    """With ``q = 0`` the target's motion is a line ``p(t) = p0 + v t``: the Kalman filter's
    final state must equal the weighted least-squares fit of ``(p0, v)`` to every sighting's
    field position ``z_k`` (weights ``R_k^-1``, closed form here) under the birth prior
    ``p0 ~ N(z_0, R_0)``, ``v ~ N(0, v0² I)``, moved to the last time."""
    rng = np.random.default_rng(7)
    v0 = 0.5
    tracker = RobotTracker(RobotTrackerConfig(acceleration_psd=0.0, initial_velocity_std=v0))
    start, velocity = np.array([-1.0, -1.5]), np.array([0.3, 0.2])
    times = np.cumsum(rng.uniform(0.05, 0.2, 40)) - 0.05
    information, vector = np.zeros((4, 4)), np.zeros(4)  # over theta = (p0, v)
    for k, t in enumerate(times):
        pose = moving_robot(t)
        sighting = observe(pose, start + velocity * t, rng)
        tracker.update(float(t), [sighting], (pose, EXACT))
        phi = pose[2] + sighting.bearing_rad
        z = pose[:2] + sighting.range_m * np.array([math.cos(phi), math.sin(phi)])
        R = closed_form_r(pose, EXACT, sighting.range_m, sighting.bearing_rad, sighting.cov)
        W = np.linalg.inv(R)
        if k == 0:  # the prior of the birth: position z_0 at times[0], velocity 0
            A0 = np.hstack([np.eye(2), t * np.eye(2)])  # p(t0) = p0 + v t0
            information += A0.T @ W @ A0 + np.diag([0.0, 0.0, v0**-2, v0**-2])
            vector += A0.T @ W @ z
            continue
        A = np.hstack([np.eye(2), t * np.eye(2)])
        information += A.T @ W @ A
        vector += A.T @ W @ z
    theta = np.linalg.solve(information, vector)
    cov_theta = np.linalg.inv(information)
    T = times[-1]
    G = np.block([[np.eye(2), T * np.eye(2)], [np.zeros((2, 2)), np.eye(2)]])  # (p0, v) -> x(T)
    (track,) = tracker.tracks
    np.testing.assert_allclose(track.state, G @ theta, atol=1e-9)
    np.testing.assert_allclose(track.cov, G @ cov_theta @ G.T, rtol=1e-7, atol=1e-12)


@pytest.mark.parametrize("seed", range(10))
def test_two_robots_crossing_paths_keep_their_track_ids(seed: int) -> None:
    rng = np.random.default_rng(100 + seed)
    # A walks up and B down; their paths cross, and at t = 5 s they pass 0.3 m apart.
    starts = {"A": np.array([-2.0, -0.8]), "B": np.array([-1.7, 0.8])}
    velocities = {"A": np.array([0.4, 0.16]), "B": np.array([0.4, -0.16])}
    pose = np.array([2.5, 0.3, math.pi])  # watching from the opposite side
    tracker = RobotTracker()
    ids: dict[str, int] = {}
    for k in range(101):  # 10 s at 10 Hz
        t = 0.1 * k
        truths = {name: starts[name] + velocities[name] * t for name in starts}
        sightings = [observe(pose, truth, rng) for truth in truths.values()]
        order = rng.permutation(len(sightings))
        tracker.update(t, [sightings[i] for i in order], (pose, EXACT))
        if k == 20:  # 2 s: both confirmed and apart
            confirmed = tracker.confirmed_tracks()
            assert len(confirmed) == 2
            ids = {name: nearest(confirmed, truth).track_id for name, truth in truths.items()}
            assert len(set(ids.values())) == 2
    confirmed = tracker.confirmed_tracks()
    for name, truth in truths.items():
        track = nearest(confirmed, truth)
        assert track.track_id == ids[name]
        assert np.linalg.norm(track.state[:2] - truth) < 0.15  # m
        assert np.linalg.norm(track.state[2:] - velocities[name]) < 0.35  # m/s, q = 0.1


def test_birth_confirmation_and_death() -> None:
    config = RobotTrackerConfig(confirm_hits=3, drop_after_s=1.0)
    tracker = RobotTracker(config)
    target, clutter = (2.0, 0.5), (-2.0, 2.0)
    dt = 0.25  # exact in binary: the drop times below are exact
    seen = []
    for k in range(9):  # the target seen at 0, 0.25, ..., 2 s
        sightings = [observe(POSE0, target)]
        if k == 1:
            sightings.append(observe(POSE0, clutter))  # one clutter sighting at 0.25 s
        tracks = tracker.update(k * dt, sightings, (POSE0, EXACT))
        seen.append({t.track_id: t.confirmed for t in tracks})
    assert seen[0] == {0: False}
    assert seen[1] == {0: False, 1: False}
    assert seen[2] == {0: True, 1: False}  # the third hit confirms
    assert seen[5] == {0: True, 1: False}  # 1.25 s: clutter unseen for 1.0 s, kept
    assert seen[6] == {0: True}  # 1.5 s: unseen for more than 1 s, dropped
    assert all(1 not in s or not s[1] for s in seen)  # the clutter never confirmed
    assert [t.track_id for t in tracker.confirmed_tracks()] == [0]

    # The target disappears after t = 2 s.
    assert [t.track_id for t in tracker.update(3.0, [], (POSE0, EXACT))] == [0]
    assert tracker.update(3.25, [], (POSE0, EXACT)) == ()
    assert tracker.confirmed_tracks() == ()
    # A robot that comes back is a new track with a new id, tentative again.
    (track,) = tracker.update(3.5, [observe(POSE0, target)], (POSE0, EXACT))
    assert (track.track_id, track.confirmed) == (2, False)

    tracker.reset()
    assert tracker.tracks == () and tracker.time_s is None
    (track,) = tracker.update(0.0, [observe(POSE0, target)], (POSE0, EXACT))
    assert track.track_id == 0


def test_a_track_lives_drop_after_s_whatever_the_rounding_of_summed_frame_times() -> None:
    """Frame times summed 0.1 s at a time (as an env keeps its clock) come out a hair over or
    under k * 0.1; a track last seen at any frame survives exactly 20 unseen frames of 0.1 s
    with ``drop_after_s`` 2 and goes on the 21st."""
    config = RobotTrackerConfig(drop_after_s=2.0)
    for last_seen in range(12):
        tracker, t = RobotTracker(config), 0.0
        for _ in range(last_seen + 1):
            tracker.update(t, [observe(POSE0, (2.0, 0.5))], (POSE0, EXACT))
            t += 0.1
        survived = 0
        while tracker.update(t, [], (POSE0, EXACT)):
            survived, t = survived + 1, t + 0.1
        assert survived == 20, last_seen


def test_one_hit_confirms_when_confirm_hits_is_1_and_max_tracks_limits_births() -> None:
    tracker = RobotTracker(RobotTrackerConfig(confirm_hits=1, max_tracks=2))
    points = [(2.0, 0.0), (0.0, 2.0), (-2.0, 0.0)]
    tracks = tracker.update(0.0, [observe(POSE0, p) for p in points], (POSE0, EXACT))
    assert [(t.track_id, t.confirmed) for t in tracks] == [(0, True), (1, True)]
    np.testing.assert_allclose([t.state[:2] for t in tracks], points[:2], atol=1e-12)


def test_nees_of_confirmed_tracks_over_a_monte_carlo_run_lies_in_the_chi_square_band() -> None:
    """Truth drawn from the filter's own model: initial velocity N(0, v0² I), white
    acceleration (exact discrete Q), sighting noise from its cov, and a SLAM pose error drawn
    anew each frame from the pose covariance the tracker is given."""
    q, v0, dt, n_steps, n_runs = 0.02, 0.2, 0.1, 50, 100
    config = RobotTrackerConfig(
        acceleration_psd=q, initial_velocity_std=v0, gate_probability=0.9999
    )
    F = np.block([[np.eye(2), dt * np.eye(2)], [np.zeros((2, 2)), np.eye(2)]])
    Qk = q * np.block(
        [[dt**3 / 3 * np.eye(2), dt**2 / 2 * np.eye(2)], [dt**2 / 2 * np.eye(2), dt * np.eye(2)]]
    )
    true_pose = np.array([-3.0, 0.2, 0.1])
    pose_cov = np.diag([0.02**2, 0.02**2, 0.02**2])
    rng = np.random.default_rng(2024)
    nees = np.full((n_runs, n_steps), np.nan)
    for run in range(n_runs):
        tracker = RobotTracker(config)
        x = np.concatenate([[1.0, 0.0], rng.normal(0.0, v0, 2)])
        for k in range(n_steps):
            if k:
                x = F @ x + rng.multivariate_normal(np.zeros(4), Qk)
            believed = true_pose + rng.multivariate_normal(np.zeros(3), pose_cov)
            tracker.update(k * dt, [observe(true_pose, x[:2], rng)], (believed, pose_cov))
            track = next(t for t in tracker.tracks if t.track_id == 0)
            if track.confirmed:
                error = track.state - x
                nees[run, k] = error @ np.linalg.solve(track.cov, error)
    assert not np.isnan(nees[:, 2:]).any()  # confirmed at the third sighting, never lost
    assert np.isnan(nees[:, :2]).all()
    # Each step's average over the runs is chi2(4 n_runs) / n_runs; all 48 steps lie in the
    # band with probability 99 % (Bonferroni).
    mean = nees[:, 2:].mean(axis=0)
    alpha = 0.01 / len(mean)
    low, high = (chi2.ppf(p, 4 * n_runs) / n_runs for p in (alpha / 2, 1 - alpha / 2))
    assert low <= mean.min() and mean.max() <= high, (mean.min(), mean.max(), low, high)
    # Over time the NEES is correlated, but the runs are independent: the grand mean is 4
    # within 4 standard errors of the per-run averages.
    per_run = nees[:, 2:].mean(axis=1)
    standard_error = per_run.std(ddof=1) / math.sqrt(n_runs)
    assert abs(per_run.mean() - 4.0) < 4 * standard_error, (per_run.mean(), standard_error)


# --- team vote --------------------------------------------------------------------------------


def test_team_is_the_majority_of_the_sightings_that_named_one() -> None:
    tracker = RobotTracker()
    teams: list[int | None] = [None, 1, 0, None, 1, 0, 0]
    expected = [None, 1, None, None, 1, None, 0]
    for k, (team, want) in enumerate(zip(teams, expected, strict=True)):
        (track,) = tracker.update(0.1 * k, [observe(POSE0, (2.0, 0.0), team=team)], (POSE0, EXACT))
        assert track.team == want, k


# --- bad input --------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("field", "value", "error"),
    [
        ("acceleration_psd", -0.1, ValueError),
        ("acceleration_psd", math.nan, ValueError),
        ("gate_probability", 1.0, ValueError),
        ("gate_probability", 0.0, ValueError),
        ("confirm_hits", 0, ValueError),
        ("confirm_hits", 2.0, InvalidTypeError),
        ("drop_after_s", 0.0, ValueError),
        ("drop_after_s", math.inf, ValueError),
        ("initial_velocity_std", 0.0, ValueError),
        ("max_tracks", 0, ValueError),
        ("max_tracks", True, InvalidTypeError),
    ],
)
def test_bad_config_fields_are_named(field: str, value: object, error: type[Exception]) -> None:
    with pytest.raises(error, match=f"RobotTrackerConfig.{field}"):
        RobotTrackerConfig(**{field: value})  # type: ignore[arg-type]


def test_config_must_be_a_config() -> None:
    with pytest.raises(TypeError, match="config"):
        RobotTracker("fast")  # type: ignore[arg-type]


def _bad_updates() -> list[tuple[str, object, object, object, type[Exception], str]]:
    good = [robot_sighting(2.0, 0.1)]
    asymmetric = np.diag([0.01, 0.01, 0.01])
    asymmetric[0, 1] = 0.001
    return [
        ("earlier time", 0.5, good, (POSE0, EXACT), ValueError, "time_s"),
        ("nan time", math.nan, good, (POSE0, EXACT), ValueError, "time_s"),
        ("str time", "2", good, (POSE0, EXACT), TypeError, "time_s"),
        ("one sighting", 2.0, good[0], (POSE0, EXACT), TypeError, "sightings"),
        ("not a sighting", 2.0, [*good, (2.0, 0.1)], (POSE0, EXACT), TypeError, r"sightings\[1\]"),
        ("zero range", 2.0, [robot_sighting(0.0, 0.1)], (POSE0, EXACT), ValueError, "range_m"),
        (
            "nan bearing",
            2.0,
            [robot_sighting(1.0, math.nan)],
            (POSE0, EXACT),
            ValueError,
            r"sightings\[0\].bearing_rad",
        ),
        (
            "nan score",
            2.0,
            [dataclasses.replace(robot_sighting(1.0, 0.0), score=math.nan)],
            (POSE0, EXACT),
            ValueError,
            r"sightings\[0\].score",
        ),
        (
            "singular cov",
            2.0,
            [robot_sighting(1.0, 0.0, np.diag([0.01, 0.0]))],
            (POSE0, EXACT),
            ValueError,
            r"sightings\[0\].cov",
        ),
        (
            "negative team",
            2.0,
            [robot_sighting(1.0, 0.0, team=-1)],
            (POSE0, EXACT),
            ValueError,
            r"sightings\[0\].team",
        ),
        ("nan pose", 2.0, good, ([0.0, math.nan, 0.0], EXACT), ValueError, r"self_pose\[0\]"),
        ("short pose", 2.0, good, ([0.0, 0.0], EXACT), ValueError, r"self_pose\[0\]"),
        ("asymmetric", 2.0, good, (POSE0, asymmetric), ValueError, r"self_pose\[1\]"),
        ("negative", 2.0, good, (POSE0, -np.eye(3)), ValueError, r"self_pose\[1\]"),
        ("nan cov", 2.0, good, (POSE0, np.full((3, 3), np.nan)), ValueError, r"self_pose\[1\]"),
        ("2x2 cov", 2.0, good, (POSE0, np.eye(2)), ValueError, r"self_pose\[1\]"),
        (
            "slam nan",
            2.0,
            good,
            SlamEstimate_of(np.array([np.inf, 0.0, 0.0]), EXACT),
            ValueError,
            r"self_pose.pose",
        ),
        (
            "slam cov",
            2.0,
            good,
            SlamEstimate_of(POSE0, -np.eye(3)),
            ValueError,
            r"self_pose.pose_cov",
        ),
        ("no pose", 2.0, good, POSE0, TypeError, "self_pose"),
    ]


@pytest.mark.parametrize(
    ("time_s", "sightings", "self_pose", "error", "match"),
    [case[1:] for case in _bad_updates()],
    ids=[case[0] for case in _bad_updates()],
)
def test_bad_updates_are_named_and_leave_the_tracker_unchanged(
    time_s: object, sightings: object, self_pose: object, error: type[Exception], match: str
) -> None:
    tracker = RobotTracker()
    tracker.update(0.0, [robot_sighting(2.0, 0.0)], (POSE0, EXACT))
    tracker.update(1.0, [robot_sighting(2.1, 0.0)], (POSE0, EXACT))
    before = tracker.tracks
    with pytest.raises(error, match=match):
        tracker.update(time_s, sightings, self_pose)  # type: ignore[arg-type]
    after = tracker.tracks
    assert tracker.time_s == 1.0 and len(after) == len(before) == 1
    np.testing.assert_array_equal(after[0].state, before[0].state)
    np.testing.assert_array_equal(after[0].cov, before[0].cov)


def test_slam_estimate_and_pair_give_the_same_tracks_and_time_may_repeat() -> None:
    pose, pose_cov = np.array([0.5, -0.2, 0.3]), np.diag([0.01, 0.02, 0.003])
    a, b = RobotTracker(), RobotTracker()
    for t, r in ((0.0, 2.0), (0.2, 2.1), (0.2, 2.05)):
        (ta,) = a.update(t, [robot_sighting(r, 0.2)], SlamEstimate_of(pose, pose_cov))
        (tb,) = b.update(t, [robot_sighting(r, 0.2)], [pose, pose_cov])  # type: ignore[arg-type]
        np.testing.assert_array_equal(ta.state, tb.state)
        np.testing.assert_array_equal(ta.cov, tb.cov)
    assert ta.confirmed  # three hits, two of them at the same time


# --- covariances stay symmetric PSD -----------------------------------------------------------


@st.composite
def frames(draw: st.DrawFn) -> list[tuple[float, list[RobotSighting], FloatArray, FloatArray]]:
    """A random run: times, sightings with random covariances, poses with PSD covariances."""
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    n_frames = draw(st.integers(1, 25))
    t, run = 0.0, []
    for _ in range(n_frames):
        t += draw(st.sampled_from([0.0, 0.01, 0.1, 0.5, 3.0]))
        sightings = []
        for _ in range(draw(st.integers(0, 4))):
            A = rng.normal(size=(2, 2)) * [[0.1], [0.05]]
            cov = A @ A.T + np.diag([1e-6, 1e-8])
            sightings.append(
                robot_sighting(
                    rng.uniform(0.05, 8.0),
                    rng.uniform(-math.pi, math.pi),
                    cov,
                    team=draw(st.sampled_from([None, 0, 1])),
                )
            )
        B = rng.normal(size=(3, draw(st.integers(0, 3)))) * 0.1  # rank 0 to 3
        pose = rng.uniform([-4.5, -3.0, -math.pi], [4.5, 3.0, math.pi])
        run.append((t, sightings, pose, B @ B.T))
    return run


@settings(max_examples=60, deadline=None)
@given(run=frames(), confirm_hits=st.integers(1, 4), max_tracks=st.integers(1, 6))
def test_covariances_stay_symmetric_psd_and_ids_increase(
    run: list[tuple[float, list[RobotSighting], FloatArray, FloatArray]],
    confirm_hits: int,
    max_tracks: int,
) -> None:
    config = RobotTrackerConfig(confirm_hits=confirm_hits, max_tracks=max_tracks)
    tracker = RobotTracker(config)
    last_id = -1
    for t, sightings, pose, pose_cov in run:
        tracks = tracker.update(t, sightings, (pose, pose_cov))
        assert len(tracks) <= max_tracks
        ids = [track.track_id for track in tracks]
        assert ids == sorted(set(ids))
        for track in tracks:
            assert track.state.shape == (4,) and np.isfinite(track.state).all()
            assert_psd(track.cov)
            assert t - track.last_seen_s <= config.drop_after_s + 1e-9
            if track.track_id > last_id:  # born in this frame
                assert track.last_seen_s == t
        last_id = max([last_id, *ids])
        assert {t.track_id for t in tracker.confirmed_tracks()} == {
            t.track_id for t in tracks if t.confirmed
        }


def test_a_sighting_of_a_team_that_does_not_exist_is_refused() -> None:
    sighting = RobotSighting(range_m=1.0, bearing_rad=0.1, cov=np.eye(2) * 1e-3, team=5)
    with pytest.raises(ValueError, match=r"^sightings\[0\]\.team must be 0, 1 or None, got 5"):
        RobotTracker().update(0.0, [sighting], (np.zeros(3), np.zeros((3, 3))))
