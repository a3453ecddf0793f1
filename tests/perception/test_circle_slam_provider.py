"""Circle SLAM as the self-pose provider and its map as the circle map
(perception.providers.circle_slam), driven with noiseless laser scans of two columns traced in
closed form from a robot driving straight with exact odometry: the true map, the true path,
the min_views delay, and the same through the perception pipeline."""

from __future__ import annotations

import math
from collections.abc import Iterator

import numpy as np
import pytest

from perception.circles.scan_circles import ScanCirclesConfig
from perception.geometry import FloatArray
from perception.pipeline import PerceptionPipeline, PipelineConfig
from perception.providers.base import PerceptionContext
from perception.providers.circle_slam import CircleSlamProvider, SlamCircleMap
from perception.representations import CIRCLE_MAP, ODOMETRY, SELF_POSE, Prior
from perception.sensor_models import LaserModel
from perception.slam.circle_slam import CircleSlamConfig
from perception.types import MappedCircle, OdometryStep, PoleGeometry, SensorFrame, SlamEstimate

LASER = LaserModel(mount_x_m=0.018)  # seed 001's laser, on the Pioneer's mount
COLUMNS = np.array([[2.0, 1.6, 0.35], [2.6, -0.9, 0.3]])  # (x, y, R) (m, world)
START = np.array([-0.5, 0.1, 0.15])  # (x, y, theta) (m, m, rad, world)
STEP_M = 0.1  # each frame the robot drives this far straight ahead
N_FRAMES = 8
SIGMA_M = 0.02


def pose_at(k: int) -> FloatArray:
    """The true pose (3,) after ``k`` steps straight ahead from START."""
    x, y, theta = START
    return np.array([x + k * STEP_M * math.cos(theta), y + k * STEP_M * math.sin(theta), theta])


def laser_scan(pose: FloatArray) -> FloatArray:
    """Noiseless ranges (B,) (m, NaN: no return) from the laser of a robot at ``pose`` to the
    nearest column: ray/circle intersections in the world frame."""
    x, y, theta = pose
    origin = np.array(
        [x + LASER.mount_x_m * math.cos(theta), y + LASER.mount_x_m * math.sin(theta)]
    )
    bearings = theta + LASER.beam_angles()
    d = np.column_stack([np.cos(bearings), np.sin(bearings)])
    ranges = np.full(len(bearings), np.inf)
    for cx, cy, R in COLUMNS:
        c = np.array([cx, cy]) - origin
        b = d @ c
        disc = b**2 - (c @ c - R**2)
        t = b - np.sqrt(np.maximum(disc, 0.0))
        ranges = np.where((disc >= 0.0) & (t > 0.0), np.minimum(ranges, t), ranges)
    return np.where(ranges <= LASER.max_range_m, ranges, np.nan)


def frames(
    n: int = N_FRAMES, rng: np.random.Generator | None = None
) -> Iterator[tuple[int, FloatArray, FloatArray]]:
    """(k, exact odometry increment, scan) per frame: the first at START (no motion yet), then
    one STEP_M ahead each; ``rng``: range noise of SIGMA_M."""
    for k in range(n):
        increment = np.array([STEP_M if k else 0.0, 0.0, 0.0])
        scan = laser_scan(pose_at(k))
        if rng is not None:
            scan = scan + SIGMA_M * rng.standard_normal(len(scan))
        yield k, increment, scan


def inputs(increment: FloatArray, scan: FloatArray) -> dict[str, object]:
    odometry = OdometryStep(delta=increment, walk_delta=increment)
    return {ODOMETRY: odometry, "laser": scan, "laser_model": LASER}


def provider(min_views: int = 3) -> CircleSlamProvider:
    slam = CircleSlamProvider(CircleSlamConfig(min_views=min_views), ScanCirclesConfig())
    slam.reset(Prior(pose=START.copy(), rng=np.random.default_rng(0)))
    return slam


def by_truth(circles: tuple[MappedCircle, ...]) -> list[MappedCircle]:
    """The mapped circles in the order of COLUMNS: each the one nearest its column."""
    return [
        min(circles, key=lambda m: float(np.hypot(*(m.state[:2] - column[:2]))))
        for column in COLUMNS
    ]


def test_the_provider_names_what_it_reads_and_provides() -> None:
    assert CircleSlamProvider.provides == SELF_POSE == "self_pose"
    assert set(CircleSlamProvider.requires) == {ODOMETRY, "laser", "laser_model"}
    assert SlamCircleMap.provides == CIRCLE_MAP == "circle_map"
    assert SlamCircleMap.requires == (SELF_POSE,)


def test_the_scans_show_both_columns_whole() -> None:
    # the synthetic scans themselves: each column a run of returns with no return beside it
    for k, _, scan in frames():
        hit = np.isfinite(scan)
        runs = np.flatnonzero(np.diff(hit.astype(int)) == 1).size
        assert runs == 2 and not hit[0] and not hit[-1], k


def test_circles_enter_the_map_at_the_third_sighting_and_converge_to_the_truth() -> None:
    slam = provider()
    for k, increment, scan in frames():
        estimate = slam.update(inputs(increment, scan), 0.1 * k)
        assert isinstance(estimate, SlamEstimate)
        np.testing.assert_allclose(estimate.pose, pose_at(k), atol=1e-6)
        # no point landmarks in a circle map
        assert estimate.landmark_ids.shape == (0,)
        assert np.issubdtype(estimate.landmark_ids.dtype, np.integer)
        assert estimate.landmarks.shape == (0, 2)
        assert estimate.landmark_covs.shape == (0, 2, 2)
        if k < 2:  # the first and second sightings are tentative
            assert estimate.circles == ()
            continue
        assert len(estimate.circles) == 2
        assert [c.circle_id for c in estimate.circles] == [0, 1]
        for mapped, column in zip(by_truth(estimate.circles), COLUMNS, strict=True):
            np.testing.assert_allclose(mapped.state, column, atol=1e-3)
            # added with the third sighting, then one fused sighting a frame
            assert mapped.hits == k - 1
            assert mapped.confirmed
            assert mapped.cov.shape == (3, 3)
            np.testing.assert_allclose(mapped.cov, mapped.cov.T, rtol=1e-9, atol=1e-15)
            assert np.linalg.eigvalsh(mapped.cov).min() > 0.0
    assert {id(c) for c in by_truth(estimate.circles)} == {id(c) for c in estimate.circles}


def test_with_min_views_one_circles_enter_at_once() -> None:
    slam = provider(min_views=1)
    for k, increment, scan in frames(4):
        estimate = slam.update(inputs(increment, scan), 0.1 * k)
        assert len(estimate.circles) == 2
        for mapped, column in zip(by_truth(estimate.circles), COLUMNS, strict=True):
            np.testing.assert_allclose(mapped.state, column, atol=1e-3)
            assert mapped.hits == k + 1


def test_the_map_shrinks_its_uncertainty_as_sightings_are_fused() -> None:
    slam = provider()
    traces = []
    for k, increment, scan in frames():
        estimate = slam.update(inputs(increment, scan), 0.1 * k)
        if estimate.circles:
            traces.append([np.trace(c.cov) for c in by_truth(estimate.circles)])
    assert np.all(np.diff(np.array(traces), axis=0) < 0.0)


def test_noisy_scans_map_the_columns_within_a_few_centimetres() -> None:
    slam = provider()
    for k, increment, scan in frames(12, np.random.default_rng(3)):
        estimate = slam.update(inputs(increment, scan), 0.1 * k)
    assert len(estimate.circles) == 2
    for mapped, column in zip(by_truth(estimate.circles), COLUMNS, strict=True):
        # a single scan's fit has a std of 1-3 cm per coordinate (KCR at 0.02 m noise)
        assert np.all(np.abs(mapped.state - column) < 0.05)
    assert np.hypot(*(estimate.pose[:2] - pose_at(11)[:2])) < 0.05


def test_reset_forgets_the_map() -> None:
    slam = provider()
    for k, increment, scan in frames(4):
        estimate = slam.update(inputs(increment, scan), 0.1 * k)
    assert len(estimate.circles) == 2
    slam.reset(Prior(pose=pose_at(3), rng=np.random.default_rng(1)))
    estimate = slam.update(inputs(np.zeros(3), laser_scan(pose_at(3))), 0.5)
    assert estimate.circles == ()
    np.testing.assert_allclose(estimate.pose, pose_at(3), atol=1e-6)
    assert slam.slam.n_circles == 0


def test_the_filter_needs_a_reset_first() -> None:
    slam = CircleSlamProvider(CircleSlamConfig(), ScanCirclesConfig())
    with pytest.raises(RuntimeError, match="reset"):
        _ = slam.slam
    with pytest.raises(RuntimeError, match="reset"):
        slam.update(inputs(np.zeros(3), laser_scan(START)), 0.0)


def test_the_slam_circle_map_is_the_estimates_circles() -> None:
    slam = provider()
    circle_map = SlamCircleMap()
    for k, increment, scan in frames(5):
        estimate = slam.update(inputs(increment, scan), 0.1 * k)
        assert circle_map.update({SELF_POSE: estimate}, 0.1 * k) is estimate.circles


def test_the_pipeline_maps_the_columns_with_circle_slam() -> None:
    config = PipelineConfig(self_pose="circle_slam", circle_map="slam")
    pipeline = PerceptionPipeline(
        config, PerceptionContext(None, (), PoleGeometry()), outputs=["circle_map"]
    )
    assert pipeline.representations == (ODOMETRY, SELF_POSE, CIRCLE_MAP)
    assert pipeline.frame_inputs == {"odometry_delta", "laser", "laser_model"}
    pipeline.reset(START.copy(), np.random.default_rng(0))
    for k, increment, scan in frames():
        frame = SensorFrame(time_s=0.1 * k, odometry_delta=increment, laser=scan, laser_model=LASER)
        output = pipeline.step(frame)
        circles = output[CIRCLE_MAP]
        assert circles is output[SELF_POSE].circles
        np.testing.assert_allclose(output[SELF_POSE].pose, pose_at(k), atol=1e-6)
        assert len(circles) == (0 if k < 2 else 2)
    for mapped, column in zip(by_truth(circles), COLUMNS, strict=True):
        np.testing.assert_allclose(mapped.state, column, atol=1e-3)
        assert mapped.hits == N_FRAMES - 2


def test_the_pipeline_needs_the_laser() -> None:
    config = PipelineConfig(self_pose="circle_slam", circle_map="slam")
    pipeline = PerceptionPipeline(
        config, PerceptionContext(None, (), PoleGeometry()), outputs=["circle_map"]
    )
    pipeline.reset(START.copy(), np.random.default_rng(0))
    with pytest.raises(ValueError, match="laser"):
        pipeline.step(SensorFrame(time_s=0.0, odometry_delta=np.zeros(3), laser_model=LASER))


def test_the_slam_circle_map_needs_circle_slam() -> None:
    with pytest.raises(ValueError, match="circle_slam"):
        PerceptionPipeline(
            PipelineConfig(circle_map="slam"),
            PerceptionContext(None, (), PoleGeometry()),
            outputs=["circle_map"],
        )
