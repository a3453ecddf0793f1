"""Replaying recorded sightings through back ends, and the synthetic consistency world."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scipy.stats import chi2

from perception.geometry import compose, range_bearing, wrap_angle
from perception.replay import SightingLog, replay
from perception.slam import EkfSlamConfig
from perception.synthetic import CircleWorld, circle_run

LANDMARK_IDS = np.array([0, 1, 2, 3])
LANDMARKS = np.array([[3.0, 3.0], [-3.0, 3.0], [-3.0, -3.0], [3.0, -3.0]])


def _run(seed: int, steps: int = 300, **world: float) -> SightingLog:
    return circle_run(
        CircleWorld(steps=steps, **world),  # type: ignore[arg-type]
        EkfSlamConfig(),
        LANDMARK_IDS,
        LANDMARKS,
        np.random.default_rng(seed),
    )


def test_circle_world_walks_its_circle() -> None:
    world = CircleWorld(steps=10)
    log = _run(0, steps=10)
    # every true pose lies on the circle, heading along its tangent (counter-clockwise)
    r = np.hypot(log.true_poses[:, 0], log.true_poses[:, 1])
    np.testing.assert_allclose(r, world.radius_m, atol=1e-9)
    tangent = np.arctan2(log.true_poses[:, 1], log.true_poses[:, 0]) + math.pi / 2
    np.testing.assert_allclose(wrap_angle(log.true_poses[:, 2] - tangent), 0.0, atol=1e-9)
    step = world.speed_mps * world.dt_s
    arc = world.radius_m * np.diff(
        np.unwrap(np.arctan2(log.true_poses[:, 1], log.true_poses[:, 0]))
    )
    np.testing.assert_allclose(arc, step, rtol=1e-9)


def test_circle_world_noise_has_the_filters_covariances() -> None:
    config = EkfSlamConfig()
    world = CircleWorld(steps=2000)
    log = _run(1, steps=2000)
    truth = world.step_increment()
    M_inv = np.linalg.inv(config.odometry_cov(truth))
    e = log.odometry_deltas[1:] - truth
    d2 = np.einsum("ki,ij,kj->k", e, M_inv, e)
    n = len(d2)  # sum of n chi-square(3) draws is chi-square(3n)
    assert chi2.ppf(0.0005, 3 * n) < d2.sum() < chi2.ppf(0.9995, 3 * n)
    s2 = []
    for pose, seen in zip(log.true_poses, log.sightings["synthetic"], strict=True):
        for obs in seen:
            k = int(np.flatnonzero(obs.landmark_id == LANDMARK_IDS)[0])
            r, b = range_bearing(pose, LANDMARKS[k : k + 1])[0]
            assert r <= world.max_range_m and abs(b) <= world.field_of_view_rad / 2
            y = np.array([obs.range_m - r, wrap_angle(obs.bearing_rad - b)])
            s2.append(y @ np.linalg.solve(obs.cov, y))
    m = len(s2)
    assert m > 500
    assert chi2.ppf(0.0005, 2 * m) < sum(s2) < chi2.ppf(0.9995, 2 * m)


def test_replay_without_noise_recovers_the_truth() -> None:
    quiet = EkfSlamConfig(
        translation_noise_m_per_sqrt_m=1e-6,
        translation_noise_m_per_sqrt_rad=1e-6,
        heading_noise_rad_per_sqrt_m=1e-6,
        rotation_noise_rad_per_sqrt_rad=1e-6,
        initial_pose_std=(1e-6, 1e-6, 1e-6),
    )
    world = CircleWorld(steps=200, range_std_m=1e-6, range_std_per_m=0.0, bearing_std_rad=1e-7)
    log = circle_run(world, quiet, LANDMARK_IDS, LANDMARKS, np.random.default_rng(2))
    result = replay(log, "synthetic", quiet)
    assert np.max(result.position_errors_m) < 1e-4
    assert np.nanmax(result.landmark_errors_m) < 1e-4
    assert set(result.final_landmark_ids.tolist()) <= set(LANDMARK_IDS.tolist())
    # dead reckoning is the composition of the increments from the start belief
    pose = log.believed_start.copy()
    for delta in log.odometry_deltas:
        pose = compose(pose, delta)
    assert result.odometry_errors_m[-1] == pytest.approx(
        float(np.hypot(*(pose[:2] - log.true_poses[-1, :2]))), abs=1e-12
    )


def test_classic_filter_is_consistent_early_on() -> None:
    """Over the first 30 s the linearisation has had no time to mislead the classic filter:
    at 10, 20 and 30 s the NEES averaged over 40 independent runs lies in the chi-square
    band of 40 samples of 3 degrees of freedom, [1.94, 4.34] (0.1 % each side; the runs are
    the independent unit: one run's NEES is correlated over tens of seconds). It sits on the
    cautious side, 2.0-2.4."""
    runs = [replay(_run(10 + k), "synthetic", EkfSlamConfig()) for k in range(40)]
    nees = np.array([r.pose_nees for r in runs])  # (runs, steps)
    assert nees.shape == (40, 301) and np.all(np.isfinite(nees))
    low, high = chi2.ppf([0.001, 0.999], df=3 * len(runs)) / len(runs)
    for step in (100, 200, 300):
        assert low < nees[:, step].mean() < high, (step, low, nees[:, step].mean(), high)


def test_replay_refuses_an_unknown_front_end() -> None:
    with pytest.raises(ValueError, match="frontend must be one of"):
        replay(_run(3, steps=5), "cnn", EkfSlamConfig())


def test_sighting_log_checks_its_shapes() -> None:
    log = _run(4, steps=5)
    with pytest.raises(ValueError, match="odometry_deltas"):
        dataclasses.replace(log, odometry_deltas=log.odometry_deltas[:-1])
    with pytest.raises(ValueError, match="sightings"):
        dataclasses.replace(log, sightings={"synthetic": log.sightings["synthetic"][:-1]})


def test_circle_world_refuses_bad_values() -> None:
    with pytest.raises(ValueError, match="radius_m"):
        CircleWorld(radius_m=0.0)
    with pytest.raises(ValueError, match="sighting_probability"):
        CircleWorld(sighting_probability=1.5)
    with pytest.raises(ValueError, match="steps"):
        CircleWorld(steps=0)
