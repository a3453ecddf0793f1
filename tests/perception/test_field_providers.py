"""Field features and the pose from them through the perception pipeline: the oracle's features
at a known pose, and the field-feature pose tracking a walk that dead reckoning loses."""

from __future__ import annotations

import math

import numpy as np
import pytest

from perception.field.visibility import FeatureViewConfig
from perception.geometry import compose, wrap_angle
from perception.landmarks.field_end import AWAY, FieldEndBelief
from perception.pipeline import PerceptionPipeline, PipelineConfig
from perception.providers.base import PerceptionContext
from perception.providers.field import FieldFeaturePose, RelocalisationConfig
from perception.representations import (
    FIELD_END,
    FIELD_FEATURES,
    ODOMETRY,
    ODOMETRY_POSE,
    SELF_POSE,
    Prior,
)
from perception.types import (
    CameraModel,
    CameraState,
    GroundTruth,
    OdometryStep,
    PoleGeometry,
    SensorFrame,
)

STATE = CameraState(
    position=np.array([0.05, 0.0, 0.5]), head_yaw=0.0, head_pitch=0.0, tilt=math.radians(20)
)


def context() -> PerceptionContext:
    return PerceptionContext(CameraModel(), (), PoleGeometry())


def frame(k: int, delta: np.ndarray, truth_pose: np.ndarray) -> SensorFrame:
    truth = GroundTruth(
        robot_pose=truth_pose, landmark_ids=np.zeros(0, dtype=np.int64), landmarks=np.zeros((0, 2))
    )
    return SensorFrame(
        time_s=0.1 * k, odometry_delta=delta, camera_state=STATE, camera=CameraModel(), truth=truth
    )


def test_the_oracle_reports_the_features_in_view_at_the_true_pose() -> None:
    config = PipelineConfig(field_features="oracle")
    pipeline = PerceptionPipeline(config, context(), outputs=[FIELD_FEATURES])
    pipeline.reset(np.array([-1.5, 0.0, 0.0]), np.random.default_rng(0))
    features = pipeline.step(frame(1, np.zeros(3), np.array([-1.5, 0.0, 0.0])))[FIELD_FEATURES]
    assert sorted(f.kind for f in features) == ["centre_circle", "line", "x_junction", "x_junction"]


def test_field_features_hold_the_pose_that_odometry_loses() -> None:
    """A 30 s walk towards and around the centre circle; the odometry drifts by a biased turn
    rate (0.05 rad/s, unknown to the filter's mean), the field features keep the pose."""
    rng = np.random.default_rng(4)
    view = FeatureViewConfig(point_std_m=0.01, point_std_per_m=0.01)
    config = PipelineConfig(self_pose="field_features", field_features="oracle", feature_view=view)
    pipeline = PerceptionPipeline(config, context(), outputs=[SELF_POSE, ODOMETRY_POSE])
    truth = np.array([-2.0, -0.5, 0.2])
    pipeline.reset(truth.copy(), np.random.default_rng(1))
    errors, drift = [], []
    for k in range(1, 301):
        step = np.array([0.015, 0.0, 0.01])  # 0.15 m/s, a slow left turn
        truth = compose(truth, step)
        measured = step + np.array([0.0, 0.0, 0.005]) + rng.normal(0.0, [0.002, 0.002, 0.002])
        output = pipeline.step(frame(k, measured, truth))
        pose = output[SELF_POSE].pose
        errors.append(np.hypot(*(pose[:2] - truth[:2])))
        drift.append(np.hypot(*(output[ODOMETRY_POSE][:2] - truth[:2])))
        assert abs(float(wrap_angle(pose[2] - truth[2]))) < 0.1
    assert drift[-1] > 0.5  # dead reckoning is lost ...
    assert max(errors) < 0.15 and np.mean(errors[100:]) < 0.05  # ... the field features are not


def test_the_oracle_needs_a_camera() -> None:
    config = PipelineConfig(field_features="oracle")
    with pytest.raises(ValueError, match="camera"):
        PerceptionPipeline(config, PerceptionContext(None, (), PoleGeometry()), [FIELD_FEATURES])


def test_a_kidnapped_robot_relocalises_on_the_true_pose_or_its_twin() -> None:
    """The filter starts 3 m off; the gate refuses every observation until the relocalisation
    restarts it from one frame's features: at the truth, or at the field's twin of it."""
    config = PipelineConfig(self_pose="field_features", field_features="oracle")
    pipeline = PerceptionPipeline(config, context(), outputs=[SELF_POSE])
    truth = np.array([-1.5, 0.3, 0.1])  # the centre circle and the halfway line in view
    pipeline.reset(np.array([1.5, -1.5, 2.0]), np.random.default_rng(2))
    twin = np.array([1.5, -0.3, 0.1 + math.pi])
    limit = config.relocalisation.after_refused_frames
    poses = [pipeline.step(frame(k, np.zeros(3), truth))[SELF_POSE].pose for k in range(1, 20)]
    assert np.hypot(*(poses[limit - 2][:2] - truth[:2])) > 2.0  # still lost before the limit
    final = poses[-1]
    off = min(np.hypot(*(final[:2] - p[:2])) for p in (truth, twin))
    assert off < 0.1


def test_field_end_observations_turn_a_mirrored_filter_round() -> None:
    """The camera sees the away end while the filter's heading faces home: with no agreeing
    frame, P(mirrored) = (1 + d) / (2 + d) passes 0.75 at the third disagreeing observation."""
    config = PipelineConfig()
    relocalisation = RelocalisationConfig(end_window_frames=10, end_confidence=0.75)
    provider = FieldFeaturePose(config.sensor_model, config.pose_filter, relocalisation, context())
    provider.reset(Prior(pose=np.array([1.0, 0.5, math.pi - 0.2]), rng=np.random.default_rng(0)))
    cov = np.array([[0.04, 0.01, 0.003], [0.01, 0.09, -0.002], [0.003, -0.002, 0.01]])
    provider.filter.reset(provider.filter.pose, cov)

    def belief(observation: int) -> FieldEndBelief:
        return FieldEndBelief(
            p_away=0.5,
            certain=0,
            away_observations=0,
            home_observations=0,
            votes=2 * observation,
            hits=(),
            observation=observation,
        )

    still = OdometryStep(delta=np.zeros(3), walk_delta=np.zeros(3))
    inputs = {ODOMETRY: still, FIELD_FEATURES: (), "camera_state": STATE}
    for k, observation in enumerate((AWAY, 0, AWAY)):  # two disagreeing views, one frame none
        provider.update({**inputs, FIELD_END: belief(observation)}, 0.1 * k)
        np.testing.assert_allclose(provider.filter.pose, [1.0, 0.5, math.pi - 0.2])
    provider.update({**inputs, FIELD_END: belief(AWAY)}, 0.3)
    np.testing.assert_allclose(provider.filter.pose, [-1.0, -0.5, -0.2], atol=1e-12)
    # standing still adds no odometry noise: the covariance is the half turn of the old one
    flip = np.diag([-1.0, -1.0, 1.0])
    np.testing.assert_allclose(provider.filter.cov, flip @ cov @ flip, atol=1e-15)
    # now the views agree with the heading: nothing more happens
    for k in range(5):
        provider.update({**inputs, FIELD_END: belief(AWAY)}, 0.4 + 0.1 * k)
    np.testing.assert_allclose(provider.filter.pose, [-1.0, -0.5, -0.2], atol=1e-12)


def test_bad_relocalisation_settings_are_refused() -> None:
    with pytest.raises(ValueError, match="end_confidence"):
        RelocalisationConfig(end_confidence=0.4)
    with pytest.raises((ValueError, TypeError), match="end_window_frames"):
        RelocalisationConfig(end_window_frames=0)
