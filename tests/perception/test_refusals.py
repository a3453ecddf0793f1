"""Bad input across the public perception API: refused with a ValueError or TypeError naming the
argument, before anything changes; and valid input that rounding once made look bad (an
innovation covariance a few ulps off symmetric) accepted."""

from __future__ import annotations

import math

import numpy as np
import pytest

from perception.circles.circle_map import CircleMapper
from perception.estimation.kalman import joseph_update
from perception.field.dimensions import FieldDimensions
from perception.field.pose_observation import PoseObservation, whitened_measurement
from perception.landmarks.bag_of_words import tf_idf
from perception.landmarks.horizon_features import HorizonFeatures
from perception.landmarks.surf1d import Surf1dFeatures
from perception.landmarks.visual_odometry import VisualHeadingOdometry, VisualOdometryConfig
from perception.pipeline import PerceptionPipeline, PipelineConfig
from perception.providers.base import PerceptionContext
from perception.sensor_models import SonarModel
from perception.slam import EkfSlam, EkfSlamConfig
from perception.tracking.ball_filter import BallFilter
from perception.tracking.sonar_filter import (
    SonarFilterConfig,
    SonarObservation,
    confirm_with_sonar,
)
from perception.types import (
    BallSighting,
    CameraModel,
    LandmarkObservation,
    PoleGeometry,
    RobotSighting,
    SensorFrame,
)
from perception.validation import is_symmetric

NAN = math.nan
COV = np.diag([0.01, 0.001])
POSE = (np.zeros(3), 1e-4 * np.eye(3))


def sighting(landmark_id: int, range_m: float, bearing_rad: float = 0.0) -> LandmarkObservation:
    return LandmarkObservation(
        landmark_id=landmark_id, range_m=range_m, bearing_rad=bearing_rad, cov=COV
    )


def test_symmetry_is_judged_against_the_variances_scale() -> None:
    """Off-diagonal entries near zero beside variances of 0.02 differ by rounding; a real
    asymmetry does not pass."""
    rounded = np.array([[0.0200, -1.93e-15], [-9.22e-16, 0.0199]])
    assert is_symmetric(rounded)
    assert not is_symmetric(np.array([[3.0, 1.0], [0.0, 3.0]]))
    with pytest.raises(ValueError, match="P must be symmetric"):
        joseph_update(np.zeros(2), [[3.0, 1.0], [0.0, 3.0]], np.zeros(1), [[1.0, 0.0]], np.eye(1))


def test_a_landmark_seen_again_under_a_wide_pose_prior_is_fused() -> None:
    """The case whose innovation covariance came out a few ulps off symmetric."""
    slam = EkfSlam(EkfSlamConfig(initial_pose_std=(5.0, 5.0, 0.5)), [0.0, 0.0, 0.0])
    seen = LandmarkObservation(
        landmark_id=1, range_m=1.0, bearing_rad=-2.8, cov=np.diag([0.01, 0.01])
    )
    slam.update([seen])
    assert slam.update([seen]) == 1
    cov = slam.cov
    assert np.array_equal(cov, cov.T) and np.linalg.eigvalsh(cov).min() > 0


def test_a_slam_update_that_fails_part_way_leaves_the_filter_as_it_was() -> None:
    slam = EkfSlam(EkfSlamConfig(min_views=1), [0.0, 0.0, 0.0])
    slam.update([sighting(1, 2.0), sighting(2, 1e-7)])  # landmark 2 on the robot itself
    mean, cov = slam.mean.copy(), slam.cov.copy()
    with pytest.raises(ValueError, match=r"observations\[1\] cannot be used: .*linearised"):
        slam.update([sighting(1, 2.5, 0.1), sighting(2, 1.0)])
    np.testing.assert_array_equal(slam.mean, mean)
    np.testing.assert_array_equal(slam.cov, cov)


def test_a_circle_scan_from_a_non_finite_mount_is_refused() -> None:
    mapper = CircleMapper()
    angles = np.linspace(-1.0, 1.0, 50)
    with pytest.raises(ValueError, match="mount_x_m"):
        mapper.update(angles, np.full(50, 1.0), math.inf, np.zeros(3), 1e-4 * np.eye(3))
    assert mapper.circles == ()


def test_visual_odometry_refuses_a_nan_walk_heading_change() -> None:
    odometry = VisualHeadingOdometry(VisualOdometryConfig(), lambda a, b: np.zeros((0, 2), int))
    features = HorizonFeatures(
        features=Surf1dFeatures(
            index=np.zeros(0, np.int64),
            x=np.zeros(0),
            scale=np.zeros(0),
            filter_size=np.zeros(0, np.int64),
            laplacian=np.zeros(0, np.int8),
            response=np.zeros(0),
            descriptors=np.zeros((0, 6)),
        ),
        bearings=np.zeros(0),
        head_yaw=0.0,
    )
    with pytest.raises(ValueError, match="walk_delta_rad"):
        odometry.update(features, NAN)


def test_the_pipeline_refuses_frames_it_cannot_use() -> None:
    context = PerceptionContext(CameraModel(), [], PoleGeometry())
    pipeline = PerceptionPipeline(PipelineConfig(), context, ["odometry_pose"])
    pipeline.reset(np.zeros(3), np.random.default_rng(0))
    with pytest.raises(ValueError, match=r"frame.odometry_delta must be finite"):
        pipeline.step(SensorFrame(time_s=0.0, odometry_delta=np.array([NAN, 0.0, 0.0])))
    with pytest.raises(ValueError, match=r"frame.odometry_delta must have shape \(3,\)"):
        pipeline.step(SensorFrame(time_s=0.0, odometry_delta=np.array([1.0, 0.0])))
    with pytest.raises(ValueError, match=r"frame\.time_s"):
        pipeline.step(SensorFrame(time_s=NAN, odometry_delta=np.zeros(3)))
    with pytest.raises(TypeError, match="frame must be a SensorFrame, got NoneType"):
        pipeline.step(None)  # type: ignore[arg-type]
    step = pipeline.step(SensorFrame(time_s=0.0, odometry_delta=np.array([0.1, 0.0, 0.0])))
    np.testing.assert_allclose(step["odometry_pose"], [0.1, 0.0, 0.0])


def test_the_ball_filter_checks_everything_before_it_changes() -> None:
    ball = BallFilter()
    seen = [BallSighting(range_m=1.0, bearing_rad=0.0, cov=COV)]
    with pytest.raises(TypeError, match="in_view"):
        ball.update(0.5, seen, np.zeros(3), POSE, in_view=5)  # type: ignore[arg-type]
    assert not ball.estimate(POSE).known  # the refused frame fused nothing
    with pytest.raises(ValueError, match=r"self_pose\[0\] must be finite"):
        ball.estimate((np.array([NAN, 0.0, 0.0]), np.eye(3)))
    ball.update(0.0, seen, np.zeros(3), POSE)  # the refused time did not stick
    known = ball.update(0.1, seen, np.zeros(3), POSE)  # the second sighting starts it
    assert known.known and known.state[0] == pytest.approx(1.0)


def test_a_sonar_check_refuses_a_sighting_without_a_covariance() -> None:
    bad = RobotSighting(range_m=1.0, bearing_rad=0.0, cov=np.array([[1e-4, 0.0], [0.0, NAN]]))
    echo = SonarObservation(sector=1, range_m=0.85, count=3)
    with pytest.raises(ValueError, match=r"sightings\[0\].cov"):
        confirm_with_sonar([bad], [echo], SonarModel(), SonarFilterConfig())


@pytest.mark.parametrize(
    ("counts", "frequency", "images", "match"),
    [
        ([1, 2], [1, 1], 0, "n_images"),
        ([NAN, 2], [1, 1], 3, "counts must be finite and >= 0"),
        ([-1, 2], [1, 1], 3, "counts must be finite and >= 0"),
        ([1, 2], [1, 4], 3, r"document_frequency must be <= n_images \(3\)"),
        ([1, 2, 3], [1, 1], 3, "must share K"),
    ],
)
def test_tf_idf_refuses_what_has_no_weight(
    counts: list[float], frequency: list[float], images: int, match: str
) -> None:
    with pytest.raises(ValueError, match=match):
        tf_idf(counts, frequency, images)


@pytest.mark.parametrize(
    ("field", "value", "match"),
    [
        ("goal_inner_width_m", 100.0, "goal_inner_width_m must be < goal_area_width_m"),
        ("penalty_mark_distance_m", 20.0, r"penalty_mark_distance_m must be < length_m / 2"),
        ("centre_circle_diameter_m", 20.0, "centre_circle_diameter_m must be <"),
        ("goal_area_length_m", 2.0, "goal_area_length_m must be < penalty_area_length_m"),
    ],
)
def test_field_markings_must_fit_inside_the_lines(field: str, value: float, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        FieldDimensions(**{field: value})
    with pytest.raises(TypeError, match="length_m must be a real number, got str"):
        FieldDimensions(length_m="9")  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("build", "match"),
    [
        (lambda: BallFilter("x"), "config must be a BallFilterConfig or None, got str"),  # type: ignore[arg-type]
        (lambda: CircleMapper("x"), "config must be a CircleMapConfig or None, got str"),  # type: ignore[arg-type]
        (
            lambda: VisualHeadingOdometry(None, lambda a, b: None),  # type: ignore[arg-type]
            "config must be a VisualOdometryConfig, got NoneType",
        ),
        (
            lambda: PerceptionPipeline(None, None, []),  # type: ignore[arg-type]
            "config must be a PipelineConfig, got NoneType",
        ),
        (
            lambda: PerceptionPipeline(PipelineConfig(), None, []),  # type: ignore[arg-type]
            "context must be a PerceptionContext, got NoneType",
        ),
    ],
)
def test_a_config_of_the_wrong_class_is_refused_by_name(build: object, match: str) -> None:
    with pytest.raises(TypeError, match=match):
        build()  # type: ignore[operator]


@pytest.mark.parametrize("weight", [NAN, -1.0, 0.0, 1.5])
def test_a_pose_observation_is_fused_with_a_weight_in_zero_one(weight: float) -> None:
    observation = PoseObservation(np.zeros(3), np.eye(3), 0.01, 3)
    with pytest.raises(ValueError, match="weight"):
        whitened_measurement(observation, np.zeros(3), weight)
