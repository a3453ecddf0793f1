"""Field features and the pose from them through the perception pipeline: the oracle's features
at a known pose, and the field-feature pose tracking a walk that dead reckoning loses."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from perception.field.features import FieldFeature
from perception.field.pose_observation import PoseObservation
from perception.field.sensor_model import SensorModelResult
from perception.field.visibility import FeatureViewConfig
from perception.geometry import compose, wrap_angle
from perception.landmarks.field_end import AWAY, HOME, FieldEndBelief
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


def belief(observation: int) -> FieldEndBelief:
    """A field-end belief holding this frame's ``observation`` (+1 away, -1 home, 0 none)."""
    return FieldEndBelief(
        p_away=0.5,
        certain=0,
        away_observations=0,
        home_observations=0,
        votes=2 * observation,
        hits=(),
        observation=observation,
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

    still = OdometryStep(delta=np.zeros(3), walk_delta=np.zeros(3))
    inputs = {ODOMETRY: still, FIELD_FEATURES: (), "camera_state": STATE}
    for k, observation in enumerate((AWAY, 0, AWAY)):  # two disagreeing views, one frame none
        estimate = provider.update({**inputs, FIELD_END: belief(observation)}, 0.1 * k)
        np.testing.assert_allclose(provider.filter.pose, [1.0, 0.5, math.pi - 0.2])
        assert not estimate.restarted
    estimate = provider.update({**inputs, FIELD_END: belief(AWAY)}, 0.3)
    np.testing.assert_allclose(provider.filter.pose, [-1.0, -0.5, -0.2], atol=1e-12)
    assert estimate.restarted  # the turn is a restart: the field-end provider's trust ends
    # standing still adds no odometry noise: the covariance is the half turn of the old one
    flip = np.diag([-1.0, -1.0, 1.0])
    np.testing.assert_allclose(provider.filter.cov, flip @ cov @ flip, atol=1e-15)
    # now the views agree with the heading: nothing more happens
    for k in range(5):
        estimate = provider.update({**inputs, FIELD_END: belief(AWAY)}, 0.4 + 0.1 * k)
        assert not estimate.restarted
    np.testing.assert_allclose(provider.filter.pose, [-1.0, -0.5, -0.2], atol=1e-12)
    assert provider.half_turns == 1


def test_side_board_observations_turn_a_mirrored_filter_round_too() -> None:
    """The filter's heading faces the +y side (pi / 2) while the camera sees the -y board
    three frames running: the half turn, as for a disagreeing end; then views of the -y board
    agree with the turned heading (-pi / 2) and nothing more happens."""
    config = PipelineConfig()
    relocalisation = RelocalisationConfig(end_window_frames=10, end_confidence=0.75)
    provider = FieldFeaturePose(config.sensor_model, config.pose_filter, relocalisation, context())
    provider.reset(Prior(pose=np.array([1.0, 0.5, math.pi / 2]), rng=np.random.default_rng(0)))
    still = OdometryStep(delta=np.zeros(3), walk_delta=np.zeros(3))
    inputs = {ODOMETRY: still, FIELD_FEATURES: (), "camera_state": STATE}
    minus_y = dataclasses.replace(belief(0), side_observation=-1)
    for k in range(2):
        assert not provider.update({**inputs, FIELD_END: minus_y}, 0.1 * k).restarted
    assert provider.update({**inputs, FIELD_END: minus_y}, 0.2).restarted
    np.testing.assert_allclose(provider.filter.pose, [-1.0, -0.5, -math.pi / 2], atol=1e-12)
    for k in range(5):
        provider.update({**inputs, FIELD_END: minus_y}, 0.3 + 0.1 * k)
    assert provider.half_turns == 1


def test_the_evidence_turns_round_with_the_filter() -> None:
    """After the half turn the three disagreeing views agree: three views of the other end
    then give P(mirrored) = (1 + 3) / (2 + 3 + 3) = 0.5, and the filter stays (had the window
    been cleared, they would have turned it straight back)."""
    config = PipelineConfig()
    relocalisation = RelocalisationConfig(end_window_frames=10, end_confidence=0.75)
    provider = FieldFeaturePose(config.sensor_model, config.pose_filter, relocalisation, context())
    provider.reset(Prior(pose=np.array([1.0, 0.5, math.pi]), rng=np.random.default_rng(0)))
    still = OdometryStep(delta=np.zeros(3), walk_delta=np.zeros(3))
    inputs = {ODOMETRY: still, FIELD_FEATURES: (), "camera_state": STATE}
    for k, observation in enumerate((AWAY, AWAY, AWAY, HOME, HOME, HOME)):
        provider.update({**inputs, FIELD_END: belief(observation)}, 0.1 * k)
    np.testing.assert_allclose(provider.filter.pose, [-1.0, -0.5, 0.0], atol=1e-12)
    assert provider.half_turns == 1


def fake_sensor_model(monkeypatch: pytest.MonkeyPatch, pose: np.ndarray) -> np.ndarray:
    """Every frame's features put the robot at ``pose`` with covariance diag(0.01, 0.02,
    0.005) (m², m², rad²) and a correlation of x and y; returns that covariance."""
    cov = np.array([[0.01, 0.004, 0.0], [0.004, 0.02, 0.0], [0.0, 0.0, 0.005]])
    observation = PoseObservation(pose, np.linalg.inv(cov), 0.01, 4)

    def observe(*args: object) -> SensorModelResult:
        return SensorModelResult(observation, pose, 0.01, 1, ())

    monkeypatch.setattr("perception.providers.field.observe_pose", observe)
    return cov


@pytest.mark.parametrize(
    ("lost_at", "kept"),
    [
        ((1.7, -0.3), True),  # 0.2 m from the twin: the same place, the evidence kept
        ((1.5, 1.5), False),  # 1.8 m from the twin (3.2 m from the truth): a kidnap
    ],
)
def test_a_relocalisation_restarts_on_the_twin_nearer_the_filter(
    monkeypatch: pytest.MonkeyPatch, lost_at: tuple[float, float], kept: bool
) -> None:
    """The features say (-1.5, 0.3, 0.1); the filter, pinned near (1.5, -0.3), refuses them
    for ``after_refused_frames`` frames, then restarts on the twin (1.5, -0.3, 0.1 + pi), the
    nearer, with the covariance turned round (over the share fused). Two views of the away
    end came while it faced home; kept, a third turns it round ((1 + 3) / (2 + 3) > 0.75);
    cleared, it does not."""
    truth = np.array([-1.5, 0.3, 0.1])
    cov = fake_sensor_model(monkeypatch, truth)
    config = PipelineConfig()
    relocalisation = RelocalisationConfig(after_refused_frames=8, end_confidence=0.75)
    provider = FieldFeaturePose(config.sensor_model, config.pose_filter, relocalisation, context())
    provider.reset(Prior(pose=np.array([*lost_at, 0.1 + math.pi]), rng=np.random.default_rng(0)))
    provider.filter.reset(provider.filter.pose, 1e-6 * np.eye(3))
    still = OdometryStep(delta=np.zeros(3), walk_delta=np.zeros(3))
    post = FieldFeature("goal_post", np.array([[2.0, 0.1]]), 1e-4 * np.eye(2)[None])
    inputs = {ODOMETRY: still, FIELD_FEATURES: (post,), "camera_state": STATE}
    restarted = [
        provider.update({**inputs, FIELD_END: belief(AWAY if k < 2 else 0)}, 0.1 * k).restarted
        for k in range(8)
    ]
    assert provider.relocalisations == 1 and provider.half_turns == 0
    assert restarted == [False] * 7 + [True]  # the estimate says so on the restart's frame
    twin = np.array([1.5, -0.3, wrap_angle(0.1 + math.pi)])
    np.testing.assert_allclose(provider.filter.pose, twin, atol=1e-12)
    flip = np.diag([-1.0, -1.0, 1.0])
    weight = config.pose_filter.observation_weight  # the share of the information fused
    np.testing.assert_allclose(provider.filter.cov, flip @ cov @ flip / weight, atol=1e-12)
    provider.update({**inputs, FIELD_FEATURES: (), FIELD_END: belief(AWAY)}, 0.8)
    assert provider.half_turns == (1 if kept else 0)
    np.testing.assert_allclose(provider.filter.pose, truth if kept else twin, atol=1e-12)


def test_bad_relocalisation_settings_are_refused() -> None:
    with pytest.raises(ValueError, match="end_confidence"):
        RelocalisationConfig(end_confidence=0.4)
    with pytest.raises((ValueError, TypeError), match="end_window_frames"):
        RelocalisationConfig(end_window_frames=0)
    with pytest.raises(ValueError, match="same_place_m"):
        RelocalisationConfig(same_place_m=-0.1)
