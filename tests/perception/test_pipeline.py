"""The perception pipeline: which providers it builds, how it feeds them, and what they compute.

Frames are built by hand (no simulator); expected values are composed, derived or counted by
hand, never read back from the code under test.
"""

from __future__ import annotations

import dataclasses
import math
import re
from typing import Any

import numpy as np
import pytest

from perception.pipeline import PROVIDERS, PerceptionPipeline, PipelineConfig
from perception.providers.base import PREVIOUS, PerceptionContext
from perception.providers.landmarks import WalkOdometry
from perception.providers.odometry import DeadReckoning
from perception.providers.poles import ColourPoleSightings, PoleSightingHistory
from perception.providers.slam import EkfSlamProvider
from perception.representations import (
    CIRCLE_MAP,
    IMAGE_DETECTIONS,
    ODOMETRY,
    ODOMETRY_POSE,
    POLE_LAST_SEEN,
    POLE_SIGHTINGS,
    SELF_POSE,
    PerceptionOutput,
    Prior,
)
from perception.slam import EkfSlam, EkfSlamConfig
from perception.types import (
    CameraModel,
    CameraState,
    LandmarkObservation,
    PoleCode,
    PoleGeometry,
    SensorFrame,
    SlamEstimate,
)

CODES = (
    PoleCode(landmark_id=1, top="pink", bottom="yellow"),
    PoleCode(landmark_id=2, top="pink", bottom="blue"),
    PoleCode(landmark_id=3, top="pink", bottom="green"),
    PoleCode(landmark_id=4, top="yellow", bottom="pink"),
    PoleCode(landmark_id=5, top="blue", bottom="pink"),
    PoleCode(landmark_id=6, top="green", bottom="pink"),
)
CAMERA_STATE = CameraState(position=np.array([0.0, 0.0, 0.5]), head_yaw=0.0, head_pitch=0.0)
# The default ("gated") filter's odometry noise (EkfSlamConfig's documented defaults).
TRANS_PER_SQRT_M = 0.13
HEADING_PER_SQRT_M = 0.035
START_STD = 0.02


def context() -> PerceptionContext:
    return PerceptionContext(CameraModel(), CODES, PoleGeometry())


def sighting(landmark_id: int, range_m: float, bearing_rad: float, cov=(0.01, 0.0004)):
    return LandmarkObservation(
        landmark_id=landmark_id, range_m=range_m, bearing_rad=bearing_rad, cov=np.diag(cov)
    )


def blank_image() -> np.ndarray:
    """A carpet-green image: nothing a colour filter could take for a pole."""
    image = np.zeros((CameraModel().height, CameraModel().width, 3), np.uint8)
    image[:] = (40, 140, 60)
    return image


# ----- which providers are built -------------------------------------------------------------
def test_odometry_pose_alone_builds_the_providers_reading_only_odometry() -> None:
    pipeline = PerceptionPipeline(PipelineConfig(), context(), outputs=[ODOMETRY_POSE])
    assert pipeline.representations == (ODOMETRY, ODOMETRY_POSE)
    assert pipeline.frame_inputs == frozenset({"odometry_delta"})
    assert isinstance(pipeline.provider(ODOMETRY), WalkOdometry)
    assert isinstance(pipeline.provider(ODOMETRY_POSE), DeadReckoning)
    for absent in (POLE_SIGHTINGS, SELF_POSE, IMAGE_DETECTIONS, POLE_LAST_SEEN):
        with pytest.raises(KeyError):
            pipeline.provider(absent)
    # a frame with nothing but odometry is enough (no camera, no image)
    pipeline.reset(np.zeros(3), np.random.default_rng(0))
    out = pipeline.step(SensorFrame(time_s=0.1, odometry_delta=np.array([0.1, 0.0, 0.0])))
    assert set(out) == {ODOMETRY, ODOMETRY_POSE}


def test_self_pose_with_colour_sightings_in_dependency_order() -> None:
    cfg = PipelineConfig(pole_sightings="colour")
    pipeline = PerceptionPipeline(cfg, context(), outputs=[SELF_POSE])
    assert pipeline.representations == (ODOMETRY, POLE_SIGHTINGS, SELF_POSE)
    assert pipeline.frame_inputs == frozenset({"odometry_delta", "image", "camera_state"})
    assert isinstance(pipeline.provider(POLE_SIGHTINGS), ColourPoleSightings)
    assert isinstance(pipeline.provider(SELF_POSE), EkfSlamProvider)


def test_requested_outputs_share_providers() -> None:
    cfg = PipelineConfig(pole_sightings="colour")
    pipeline = PerceptionPipeline(
        cfg, context(), outputs=[POLE_LAST_SEEN, SELF_POSE, ODOMETRY_POSE, POLE_SIGHTINGS]
    )
    order = pipeline.representations
    assert sorted(order) == sorted(
        [ODOMETRY, POLE_SIGHTINGS, POLE_LAST_SEEN, SELF_POSE, ODOMETRY_POSE]
    )
    assert order.index(POLE_SIGHTINGS) < order.index(POLE_LAST_SEEN)
    assert order.index(POLE_SIGHTINGS) < order.index(SELF_POSE)
    assert IMAGE_DETECTIONS not in order  # the colour filter needs no CNN detections
    assert pipeline.frame_inputs == frozenset({"odometry_delta", "image", "camera_state"})


def test_oracle_sightings_read_truth_and_camera_state_only() -> None:
    cfg = PipelineConfig(pole_sightings="oracle")
    pipeline = PerceptionPipeline(cfg, context(), outputs=[POLE_SIGHTINGS])
    assert pipeline.frame_inputs == frozenset({"truth", "camera_state"})


def test_colour_pipeline_steps_on_an_empty_image() -> None:
    cfg = PipelineConfig(pole_sightings="colour")
    pipeline = PerceptionPipeline(cfg, context(), outputs=[POLE_SIGHTINGS, POLE_LAST_SEEN])
    pipeline.reset(np.zeros(3), np.random.default_rng(0))
    out = pipeline.step(SensorFrame(time_s=0.1, image=blank_image(), camera_state=CAMERA_STATE))
    assert out[POLE_SIGHTINGS] == ()
    assert out[POLE_LAST_SEEN] == {}


# ----- emulated representations --------------------------------------------------------------
def test_emulated_sightings_come_from_the_frame_and_build_no_pole_provider() -> None:
    pipeline = PerceptionPipeline(
        PipelineConfig(), context(), outputs=[SELF_POSE, POLE_LAST_SEEN], emulated=[POLE_SIGHTINGS]
    )
    assert POLE_SIGHTINGS not in pipeline.representations
    with pytest.raises(KeyError):
        pipeline.provider(POLE_SIGHTINGS)
    assert IMAGE_DETECTIONS not in pipeline.representations
    assert pipeline.frame_inputs == frozenset({"odometry_delta"})  # no image, no camera state
    pipeline.reset(np.zeros(3), np.random.default_rng(0))
    emulated = (sighting(2, 2.0, 0.3),)
    frame = SensorFrame(
        time_s=0.5,
        odometry_delta=np.zeros(3),
        emulated={POLE_SIGHTINGS: emulated},
    )
    out = pipeline.step(frame)
    assert out[POLE_SIGHTINGS] is emulated
    assert out[POLE_LAST_SEEN] == {2: 0.5}
    assert list(out.get_as(SELF_POSE, SlamEstimate).landmark_ids) == [2]


def test_missing_emulated_representation_raises() -> None:
    pipeline = PerceptionPipeline(
        PipelineConfig(), context(), outputs=[POLE_LAST_SEEN], emulated=[POLE_SIGHTINGS]
    )
    pipeline.reset(np.zeros(3), np.random.default_rng(0))
    with pytest.raises(ValueError, match=POLE_SIGHTINGS):
        pipeline.step(SensorFrame(time_s=0.1))


# ----- errors ----------------------------------------------------------------------------------
def test_missing_frame_input_raises_naming_it() -> None:
    pipeline = PerceptionPipeline(PipelineConfig(), context(), outputs=[ODOMETRY_POSE])
    pipeline.reset(np.zeros(3), np.random.default_rng(0))
    with pytest.raises(ValueError, match="odometry_delta"):
        pipeline.step(SensorFrame(time_s=0.1, camera_state=CAMERA_STATE))


def test_missing_image_raises_naming_it() -> None:
    cfg = PipelineConfig(pole_sightings="colour")
    pipeline = PerceptionPipeline(cfg, context(), outputs=[POLE_SIGHTINGS])
    pipeline.reset(np.zeros(3), np.random.default_rng(0))
    with pytest.raises(ValueError, match="image"):
        pipeline.step(SensorFrame(time_s=0.1, camera_state=CAMERA_STATE))


@pytest.mark.parametrize("name", ["goal", "self_pos", ""])
def test_unknown_representation_raises(name: str) -> None:
    with pytest.raises(ValueError, match="unknown representation"):
        PerceptionPipeline(PipelineConfig(), context(), outputs=[name])


@pytest.mark.parametrize(
    ("field", "value"),
    [("pole_sightings", "sonar"), ("self_pose", "gps"), ("pole_sightings", "CNN")],
)
def test_unknown_provider_name_raises_naming_the_field(field: str, value: str) -> None:
    with pytest.raises(ValueError, match=re.escape(f"PipelineConfig.{field}")) as caught:
        PipelineConfig(**{field: value})
    assert repr(value) in str(caught.value)


def test_registry_names_the_documented_providers() -> None:
    assert set(PROVIDERS[POLE_SIGHTINGS]) == {"cnn", "colour", "oracle"}
    assert set(PROVIDERS[SELF_POSE]) == {
        "ekf_slam",
        "oracle",
        "circle_slam",
        "field_features",
        "ekf_slam_field_features",
    }
    assert set(PROVIDERS[CIRCLE_MAP]) == {"laser", "slam"}


def test_the_slam_circle_map_needs_circle_slam() -> None:
    with pytest.raises(ValueError, match=r"circle_map='slam'.*self_pose='circle_slam'"):
        PerceptionPipeline(PipelineConfig(circle_map="slam"), context(), outputs=[CIRCLE_MAP])


# ----- dead reckoning ----------------------------------------------------------------------------
def test_dead_reckoning_walks_a_known_square() -> None:
    """Four times: 1 m forward while turning a quarter turn left (the increment is the pose of
    the new frame in the old one), from (2, -1, 0): the corners of a unit square, back home."""
    pipeline = PerceptionPipeline(PipelineConfig(), context(), outputs=[ODOMETRY_POSE])
    pipeline.reset(np.array([2.0, -1.0, 0.0]), np.random.default_rng(0))
    corners = [(3.0, -1.0, math.pi / 2), (3.0, 0.0, -math.pi), (2.0, 0.0, -math.pi / 2)]
    corners.append((2.0, -1.0, 0.0))
    for k, corner in enumerate(corners):
        frame = SensorFrame(time_s=k + 1.0, odometry_delta=np.array([1.0, 0.0, math.pi / 2]))
        pose = pipeline.step(frame)[ODOMETRY_POSE]
        np.testing.assert_allclose(pose[:2], corner[:2], atol=1e-12)
        assert abs(math.remainder(pose[2] - corner[2], 2 * math.pi)) < 1e-12


def test_dead_reckoning_sidestep_after_a_turn_and_reset() -> None:
    """A half turn in place, then 0.5 m to the robot's left: (1, 1, 0) -> (1, 0.5, pi)."""
    pipeline = PerceptionPipeline(PipelineConfig(), context(), outputs=[ODOMETRY_POSE])
    for _ in range(2):  # reset starts over from the prior
        pipeline.reset(np.array([1.0, 1.0, 0.0]), np.random.default_rng(0))
        pipeline.step(SensorFrame(time_s=0.1, odometry_delta=np.array([0.0, 0.0, math.pi])))
        pose = pipeline.step(SensorFrame(time_s=0.2, odometry_delta=np.array([0.0, 0.5, 0.0])))[
            ODOMETRY_POSE
        ]
        np.testing.assert_allclose(pose[:2], [1.0, 0.5], atol=1e-12)
        assert abs(abs(pose[2]) - math.pi) < 1e-12


def test_dead_reckoning_output_is_a_copy() -> None:
    pipeline = PerceptionPipeline(PipelineConfig(), context(), outputs=[ODOMETRY_POSE])
    pipeline.reset(np.zeros(3), np.random.default_rng(0))
    first = pipeline.step(SensorFrame(time_s=0.1, odometry_delta=np.array([1.0, 0.0, 0.0])))
    first[ODOMETRY_POSE][:] = 99.0
    second = pipeline.step(SensorFrame(time_s=0.2, odometry_delta=np.array([1.0, 0.0, 0.0])))
    np.testing.assert_allclose(second[ODOMETRY_POSE], [2.0, 0.0, 0.0])


# ----- EKF SLAM provider -------------------------------------------------------------------------
def slam_pipeline() -> PerceptionPipeline:
    return PerceptionPipeline(
        PipelineConfig(), context(), outputs=[SELF_POSE], emulated=[POLE_SIGHTINGS]
    )


def test_ekf_predict_covariance_of_a_straight_step_by_hand() -> None:
    """From (0, 0, 0) with Sigma0 = 0.02² I, a 0.1 m step straight ahead. With theta = 0 the
    motion Jacobian is G = [[1, 0, 0], [0, 1, d], [0, 0, 1]] and V = I, and the odometry noise is
    M = diag(0.13² d, 0.13² d, 0.035² d). Sigma = G Sigma0 G^T + M, term by term."""
    assert PipelineConfig().slam.initial_pose_std == (START_STD,) * 3
    d = 0.1
    s0 = START_STD**2
    pipeline = slam_pipeline()
    pipeline.reset(np.zeros(3), np.random.default_rng(0))
    frame = SensorFrame(
        time_s=0.1, odometry_delta=np.array([d, 0.0, 0.0]), emulated={POLE_SIGHTINGS: ()}
    )
    est = pipeline.step(frame).get_as(SELF_POSE, SlamEstimate)
    np.testing.assert_allclose(est.pose, [d, 0.0, 0.0], atol=1e-15)
    expected = np.array(
        [
            [s0 + TRANS_PER_SQRT_M**2 * d, 0.0, 0.0],
            [0.0, s0 + d**2 * s0 + TRANS_PER_SQRT_M**2 * d, d * s0],
            [0.0, d * s0, s0 + HEADING_PER_SQRT_M**2 * d],
        ]
    )
    np.testing.assert_allclose(est.pose_cov, expected, rtol=1e-12, atol=1e-15)
    assert len(est.landmark_ids) == 0


def test_ekf_new_landmark_covariance_by_hand() -> None:
    """After the step above, a first sighting of pole 5 at range r = 2 m, bearing 0 with
    Q = diag(0.01, 0.0004). The landmark enters at (d + r, 0); to first order its x error is
    x + range error and its y error y + r theta + r bearing error, so
    var(mx) = Sxx + Qrr, var(my) = Syy + 2 r Sytheta + r² Stt + r² Qbb, cov(mx, my) = 0."""
    d, r = 0.1, 2.0
    q_rr, q_bb = 0.01, 0.0004
    s0 = START_STD**2
    sxx = s0 + TRANS_PER_SQRT_M**2 * d
    syy = s0 + d**2 * s0 + TRANS_PER_SQRT_M**2 * d
    syt = d * s0
    stt = s0 + HEADING_PER_SQRT_M**2 * d
    pipeline = slam_pipeline()
    pipeline.reset(np.zeros(3), np.random.default_rng(0))
    frame = SensorFrame(
        time_s=0.1,
        odometry_delta=np.array([d, 0.0, 0.0]),
        emulated={POLE_SIGHTINGS: (sighting(5, r, 0.0, (q_rr, q_bb)),)},
    )
    est = pipeline.step(frame).get_as(SELF_POSE, SlamEstimate)
    assert list(est.landmark_ids) == [5]
    np.testing.assert_allclose(est.landmarks, [[d + r, 0.0]], atol=1e-12)
    expected = np.diag([sxx + q_rr, syy + 2 * r * syt + r**2 * stt + r**2 * q_bb])
    np.testing.assert_allclose(est.landmark_covs[0], expected, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(est.pose, [d, 0.0, 0.0], atol=1e-15)  # adding moves no pose


def test_ekf_provider_matches_ekf_slam_driven_directly() -> None:
    """Wiring check (not an independent truth): the provider predicts with the frame's odometry
    and fuses the frame's sightings, exactly as EkfSlam driven by hand with the same inputs."""
    rng = np.random.default_rng(4)
    prior = np.array([0.5, -0.3, 0.2])
    pipeline = slam_pipeline()
    pipeline.reset(prior, np.random.default_rng(0))
    reference = EkfSlam(PipelineConfig().slam, prior)
    for k in range(15):
        delta = np.array([0.02, 0.005, 0.03]) + rng.normal(0, 0.002, 3)
        obs = (sighting(1, 2.0 + 0.01 * k, 0.3), sighting(4, 3.0, -0.5 + 0.01 * k))
        est = pipeline.step(
            SensorFrame(time_s=0.1 * k, odometry_delta=delta, emulated={POLE_SIGHTINGS: obs})
        )[SELF_POSE]
        reference.predict(delta)
        reference.update(obs)
        ref = reference.estimate()
        np.testing.assert_array_equal(est.pose, ref.pose)
        np.testing.assert_array_equal(est.pose_cov, ref.pose_cov)
        np.testing.assert_array_equal(est.landmarks, ref.landmarks)
    assert pipeline.provider(SELF_POSE).slam.config == PipelineConfig().slam


def test_ekf_provider_reset_starts_a_fresh_filter() -> None:
    pipeline = slam_pipeline()
    pipeline.reset(np.zeros(3), np.random.default_rng(0))
    first = pipeline.provider(SELF_POSE).slam
    pipeline.step(
        SensorFrame(
            time_s=0.1,
            odometry_delta=np.array([0.1, 0.0, 0.0]),
            emulated={POLE_SIGHTINGS: (sighting(3, 1.0, 0.0),)},
        )
    )
    pipeline.reset(np.array([1.0, 2.0, 0.5]), np.random.default_rng(0))
    assert pipeline.provider(SELF_POSE).slam is not first
    est = pipeline.provider(SELF_POSE).slam.estimate()
    np.testing.assert_allclose(est.pose, [1.0, 2.0, 0.5])
    np.testing.assert_allclose(est.pose_cov, np.eye(3) * START_STD**2)
    assert len(est.landmark_ids) == 0


def test_ekf_provider_needs_reset() -> None:
    provider = EkfSlamProvider(EkfSlamConfig())
    with pytest.raises(RuntimeError, match="reset"):
        _ = provider.slam


# ----- pole history ------------------------------------------------------------------------------
def test_pole_sighting_history_records_last_times_and_resets() -> None:
    pipeline = PerceptionPipeline(
        PipelineConfig(), context(), outputs=[POLE_LAST_SEEN], emulated=[POLE_SIGHTINGS]
    )
    assert isinstance(pipeline.provider(POLE_LAST_SEEN), PoleSightingHistory)
    assert pipeline.frame_inputs == frozenset()
    pipeline.reset(np.zeros(3), np.random.default_rng(0))
    frames = [
        (0.1, (sighting(1, 2.0, 0.1), sighting(3, 3.0, -0.2))),
        (0.2, (sighting(3, 3.0, -0.2),)),
        (0.3, ()),
        (0.4, (sighting(6, 4.0, 0.0),)),
    ]
    expected = [{1: 0.1, 3: 0.1}, {1: 0.1, 3: 0.2}, {1: 0.1, 3: 0.2}, {1: 0.1, 3: 0.2, 6: 0.4}]
    for (time_s, seen), want in zip(frames, expected, strict=True):
        out = pipeline.step(SensorFrame(time_s=time_s, emulated={POLE_SIGHTINGS: seen}))
        assert dict(out[POLE_LAST_SEEN]) == want
    pipeline.reset(np.zeros(3), np.random.default_rng(0))
    out = pipeline.step(SensorFrame(time_s=0.1, emulated={POLE_SIGHTINGS: ()}))
    assert dict(out[POLE_LAST_SEEN]) == {}


def test_pole_sighting_history_returns_snapshots() -> None:
    history = PoleSightingHistory()
    history.reset(Prior(pose=np.zeros(3), rng=np.random.default_rng(0)))
    first = history.update({POLE_SIGHTINGS: (sighting(2, 1.0, 0.0),)}, 1.0)
    history.update({POLE_SIGHTINGS: (sighting(2, 1.0, 0.0),)}, 2.0)
    assert first == {2: 1.0}


# ----- the output container ----------------------------------------------------------------------
def test_perception_output_reads_like_a_mapping_with_type_checks() -> None:
    pose = np.array([1.0, 2.0, 0.3])
    out = PerceptionOutput(time_s=0.7, representations={ODOMETRY_POSE: pose, POLE_SIGHTINGS: ()})
    assert len(out) == 2 and set(out) == {ODOMETRY_POSE, POLE_SIGHTINGS}
    assert ODOMETRY_POSE in out and SELF_POSE not in out
    assert out.get(SELF_POSE) is None
    assert out.get_as(ODOMETRY_POSE, np.ndarray) is pose
    assert out.get_as(POLE_SIGHTINGS, tuple) == ()
    with pytest.raises(TypeError, match="SlamEstimate"):
        out.get_as(ODOMETRY_POSE, SlamEstimate)


def test_perception_output_key_error_names_what_is_computed() -> None:
    out = PerceptionOutput(time_s=0.0, representations={ODOMETRY_POSE: np.zeros(3)})
    with pytest.raises(KeyError) as caught:
        _ = out[SELF_POSE]
    message = str(caught.value)
    assert SELF_POSE in message and ODOMETRY_POSE in message
    with pytest.raises(KeyError, match=SELF_POSE):
        out.get_as(SELF_POSE, SlamEstimate)


def test_prior_is_checked() -> None:
    with pytest.raises(ValueError, match=r"Prior\.pose"):
        Prior(pose=np.array([0.0, np.nan, 0.0]), rng=np.random.default_rng(0))
    with pytest.raises(ValueError, match=r"Prior\.pose"):
        Prior(pose=np.zeros(2), rng=np.random.default_rng(0))
    with pytest.raises(TypeError, match="Generator"):
        Prior(pose=np.zeros(3), rng=np.random.RandomState(0))  # type: ignore[arg-type]


# ----- the CNN is built once per context ---------------------------------------------------------
def test_cnn_is_built_once_per_context(monkeypatch: pytest.MonkeyPatch) -> None:
    """Both CNN providers (detections and pole sightings) of one or more pipelines on one
    context share one detector per detector config; a new context builds its own. The detector
    is stubbed out: only its constructions are counted (no torch, no weights)."""
    from perception.vision import cnn_detector

    built: list[Any] = []

    def counting_init(self: Any, config: Any, camera: Any, codes: Any, pole: Any) -> None:
        built.append(config)

    monkeypatch.setattr(cnn_detector.CnnPoleDetector, "__init__", counting_init)
    ctx = context()
    cfg = PipelineConfig(pole_sightings="cnn")
    first = PerceptionPipeline(cfg, ctx, outputs=[POLE_SIGHTINGS, IMAGE_DETECTIONS])
    assert first.representations == (IMAGE_DETECTIONS, POLE_SIGHTINGS)
    assert first.frame_inputs == frozenset({"image", "camera_state"})
    assert len(built) == 1
    PerceptionPipeline(cfg, ctx, outputs=[SELF_POSE])
    assert len(built) == 1
    assert first.provider(POLE_SIGHTINGS).detector is first.provider(IMAGE_DETECTIONS).detector
    other = dataclasses.replace(cfg, cnn=dataclasses.replace(cfg.cnn, score_threshold=0.3))
    PerceptionPipeline(other, ctx, outputs=[POLE_SIGHTINGS])
    assert len(built) == 2  # another detector config is another detector
    PerceptionPipeline(cfg, context(), outputs=[POLE_SIGHTINGS])
    assert len(built) == 3  # another context builds its own


def test_non_cnn_pipelines_build_no_cnn(monkeypatch: pytest.MonkeyPatch) -> None:
    from perception.vision import cnn_detector

    built: list[Any] = []

    def counting_init(self: Any, *args: Any) -> None:
        built.append(args)

    monkeypatch.setattr(cnn_detector.CnnPoleDetector, "__init__", counting_init)
    for name in ("colour", "oracle"):
        cfg = PipelineConfig(pole_sightings=name)
        PerceptionPipeline(cfg, context(), outputs=[SELF_POSE, POLE_LAST_SEEN, ODOMETRY_POSE])
    PerceptionPipeline(PipelineConfig(), context(), outputs=[SELF_POSE], emulated=[POLE_SIGHTINGS])
    assert built == []


def test_a_provider_reads_a_representation_one_frame_late(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    import perception.pipeline as pipeline_module
    from perception.providers.base import Provider

    class EchoPrevious(Provider):
        provides = "echo"
        requires = ()
        requires_previous = (ODOMETRY_POSE,)

        def update(self, inputs, time_s):  # type: ignore[no-untyped-def]
            return inputs[PREVIOUS + ODOMETRY_POSE]

    providers = {**pipeline_module.PROVIDERS, "echo": {"only": lambda c, ctx: EchoPrevious()}}
    monkeypatch.setattr(pipeline_module, "PROVIDERS", providers)
    monkeypatch.setattr(
        pipeline_module, "REPRESENTATIONS", (*pipeline_module.REPRESENTATIONS, "echo")
    )
    pipeline = PerceptionPipeline(PipelineConfig(), context(), outputs=["echo"])
    assert ODOMETRY_POSE in pipeline.representations  # resolved for it, though read late
    pipeline.reset(np.zeros(3), np.random.default_rng(0))
    step = np.array([0.1, 0.0, 0.0])
    first = pipeline.step(SensorFrame(time_s=0.1, odometry_delta=step))
    assert first["echo"] is None  # nothing before the episode's first frame
    second = pipeline.step(SensorFrame(time_s=0.2, odometry_delta=step))
    np.testing.assert_array_equal(second["echo"], first[ODOMETRY_POSE])
    pipeline.reset(np.zeros(3), np.random.default_rng(0))
    assert pipeline.step(SensorFrame(time_s=0.1, odometry_delta=step))["echo"] is None
