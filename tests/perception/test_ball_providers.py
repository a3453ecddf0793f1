"""The ball's providers: CNN sightings and the filter through a pipeline (frames built by hand:
a ball box projected through the camera model), and the ball oracles (which balls they report,
by known geometry, and the noise they add, by chi-square bands over many seeded draws)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scipy import stats

from perception.geometry import FloatArray, project_points
from perception.pipeline import PerceptionPipeline, PipelineConfig
from perception.providers.ball import CnnBallSightings, TrackedBall, TwoCameraCnnBallSightings
from perception.providers.base import PerceptionContext
from perception.providers.oracles import OracleBall, OracleBallSightings, OracleConfig
from perception.representations import (
    BALL,
    BALL_SIGHTINGS,
    IMAGE_DETECTIONS,
    ODOMETRY,
    ROBOT_TRACKS,
    SELF_POSE,
    Prior,
)
from perception.tracking.ball_filter import BallFilterConfig
from perception.types import (
    BallEstimate,
    BallSighting,
    CameraModel,
    CameraState,
    GroundTruth,
    OdometryStep,
    PoleGeometry,
    RobotTrack,
    SensorFrame,
    SlamEstimate,
)
from perception.vision.cnn_ball import CnnBallConfig
from perception.vision.cnn_detector import CnnDetectorConfig, Detection

CAMERA = CameraModel()
HFOV_DEG = 60.0  # the oracles' camera: half field of view 30 deg
TINY = 1e-9  # noise std small enough for exact geometry checks
BAND = 0.999  # two-sided probability of the chi-square bands
RADIUS = 0.05
STATE = CameraState(position=np.array([0.05, 0.0, 0.5]), head_yaw=0.2, head_pitch=0.3)
POSE = np.array([1.0, 2.0, 0.5])  # the believed (and true) pose, field frame
NO_KICK = np.zeros(2)


def context(hfov_deg: float = CAMERA.hfov_deg) -> PerceptionContext:
    return PerceptionContext(CameraModel(hfov_deg=hfov_deg), (), PoleGeometry())


def rot(angle: float) -> FloatArray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s], [s, c]])


def slam_estimate(pose: FloatArray = POSE) -> SlamEstimate:
    return SlamEstimate(
        pose=np.asarray(pose, dtype=np.float64),
        pose_cov=np.zeros((3, 3)),
        landmark_ids=np.zeros(0, dtype=np.int64),
        landmarks=np.zeros((0, 2)),
        landmark_covs=np.zeros((0, 2, 2)),
    )


def ball_detection(
    range_m: float, bearing: float, rows_up: float = 1.0, score: float = 0.9
) -> Detection:
    """The CNN's box (scored ``score``) of a ball at ``range_m``, ``bearing`` (robot frame) seen
    from ``STATE``, drawn ``rows_up`` rows higher than the camera model (PyBullet's renderer:
    one row)."""
    centre = np.array([range_m * math.cos(bearing), range_m * math.sin(bearing), RADIUS])
    cam = (centre - STATE.position) @ STATE.rotation()
    (pixel,), front = project_points(cam[None], CAMERA.fx, CAMERA.fy, CAMERA.cx, CAMERA.cy)
    assert front.all()
    half = RADIUS * CAMERA.fx / float(np.linalg.norm(centre - STATE.position))
    u, v = pixel[0], pixel[1] - rows_up
    box = np.array([u - half, v - half, u + half, v + half])
    return Detection(class_name="ball", class_id=1, box=box, score=score, keypoint=np.array([u, v]))


# Uniform noise over 0-255: no box is flat in it (the sightings' flat-box check passes them)
TEXTURED = np.random.default_rng(7).integers(0, 256, (CAMERA.height, CAMERA.width, 3), np.uint8)


def cnn_frame(
    time_s: float, detections: tuple[Detection, ...], kick: FloatArray | None = NO_KICK
) -> SensorFrame:
    """A frame of the given CNN detections on the :data:`TEXTURED` image; ``kick`` None: a
    robot that cannot kick (the frame's default)."""
    frame = SensorFrame(
        time_s=time_s,
        odometry_delta=np.zeros(3),
        image=TEXTURED,
        camera=CAMERA,
        camera_state=STATE,
        emulated={IMAGE_DETECTIONS: detections, SELF_POSE: slam_estimate(), ROBOT_TRACKS: ()},
    )
    return frame if kick is None else dataclasses.replace(frame, kick_velocity=kick)


def cnn_pipeline() -> PerceptionPipeline:
    pipeline = PerceptionPipeline(
        PipelineConfig(),
        context(),
        outputs=[BALL],
        emulated=[IMAGE_DETECTIONS, SELF_POSE, ROBOT_TRACKS],
    )
    pipeline.reset(POSE, np.random.default_rng(0))
    return pipeline


def field_point(range_m: float, bearing: float, pose: FloatArray = POSE) -> FloatArray:
    """By hand: ``(x + r cos(theta + b), y + r sin(theta + b))``."""
    phi = pose[2] + bearing
    return np.array([pose[0] + range_m * math.cos(phi), pose[1] + range_m * math.sin(phi)])


# --- the CNN sightings and the filter through a pipeline ----------------------------------------


def test_the_default_ball_pipeline_builds_the_cnn_sightings_and_the_filter() -> None:
    pipeline = cnn_pipeline()
    assert BALL_SIGHTINGS in pipeline.representations and BALL in pipeline.representations
    assert pipeline.representations.index(BALL_SIGHTINGS) < pipeline.representations.index(BALL)
    assert isinstance(pipeline.provider(BALL_SIGHTINGS), CnnBallSightings)
    assert isinstance(pipeline.provider(BALL), TrackedBall)
    assert pipeline.emulated == frozenset({IMAGE_DETECTIONS, SELF_POSE, ROBOT_TRACKS})
    assert pipeline.frame_inputs == frozenset(
        {"image", "camera", "camera_state", "odometry_delta", "kick_velocity"}
    )
    assert PipelineConfig().cnn_ball == CnnBallConfig(row_offset_px=1.0)
    assert PipelineConfig().ball_filter == BallFilterConfig()


def test_a_ball_box_becomes_a_ball_on_the_field() -> None:
    """A box drawn one row high (the default config takes the renderer's row out) of a ball at
    2 m, 0.3 rad, scored 0.9: the sighting reads that range and bearing and the filter starts
    there at once (the default start_at_once_score 0.7), on the field from the believed pose;
    without sightings it keeps the ball; a reset forgets it. The same box scored 0.5 waits for
    a second (shown as the candidate), which starts the belief there."""
    pipeline = cnn_pipeline()
    out = pipeline.step(cnn_frame(0.0, (ball_detection(2.0, 0.3),)))
    (seen,) = out[BALL_SIGHTINGS]
    assert isinstance(seen, BallSighting)
    assert seen.range_m == pytest.approx(2.0, abs=1e-6)
    assert seen.bearing_rad == pytest.approx(0.3, abs=1e-6)
    relative = [2.0 * math.cos(0.3), 2.0 * math.sin(0.3)]
    ball = out[BALL]
    assert isinstance(ball, BallEstimate) and ball.known and ball.last_seen_s == 0.0
    np.testing.assert_allclose(ball.state[:2], field_point(2.0, 0.3), atol=1e-6)
    np.testing.assert_allclose(ball.state[2:], 0.0, atol=1e-12)
    np.testing.assert_allclose(ball.relative[:2], relative, atol=1e-6)
    out = pipeline.step(cnn_frame(0.1, ()))
    assert out[BALL_SIGHTINGS] == ()
    assert out[BALL].known and out[BALL].last_seen_s == 0.0
    np.testing.assert_allclose(out[BALL].state[:2], field_point(2.0, 0.3), atol=1e-6)
    out = pipeline.step(cnn_frame(0.2, (ball_detection(2.02, 0.3),)))
    assert out[BALL].last_seen_s == 0.2
    pipeline.reset(POSE, np.random.default_rng(0))
    out = pipeline.step(cnn_frame(0.0, ()))
    assert not out[BALL].known and out[BALL].last_seen_s == -math.inf
    doubtful = (ball_detection(2.0, 0.3, score=0.5),)
    out = pipeline.step(cnn_frame(0.1, doubtful))
    assert not out[BALL].known and out[BALL].candidate is not None
    np.testing.assert_allclose(out[BALL].candidate, relative, atol=1e-6)
    out = pipeline.step(cnn_frame(0.2, doubtful))
    assert out[BALL].known and out[BALL].last_seen_s == 0.2
    np.testing.assert_allclose(out[BALL].state[:2], field_point(2.0, 0.3), atol=1e-6)


def test_a_robot_that_cannot_kick_still_tracks_the_ball() -> None:
    pipeline = cnn_pipeline()
    out = pipeline.step(cnn_frame(0.0, (ball_detection(2.0, 0.3),), kick=None))
    assert out[BALL].known


def test_tracked_ball_refuses_a_self_pose_or_odometry_of_the_wrong_type() -> None:
    provider = TrackedBall(BallFilterConfig(), 0.05)
    provider.reset(Prior(pose=POSE, rng=np.random.default_rng(0)))
    step = OdometryStep(delta=np.zeros(3), walk_delta=np.zeros(3))
    good = {
        BALL_SIGHTINGS: (),
        ODOMETRY: step,
        SELF_POSE: slam_estimate(),
        ROBOT_TRACKS: (),
        "kick_velocity": NO_KICK,
        "camera": CAMERA,
        "camera_state": STATE,
    }
    assert not provider.update(good, 0.0).known
    with pytest.raises(TypeError, match="self_pose"):
        provider.update({**good, SELF_POSE: POSE}, 0.1)
    with pytest.raises(TypeError, match="odometry"):
        provider.update({**good, ODOMETRY: np.zeros(3)}, 0.1)
    with pytest.raises(TypeError, match="robot_tracks must be RobotTracks"):
        provider.update({**good, ROBOT_TRACKS: (np.zeros(4),)}, 0.1)


def known_through_misses(bearing: float, tracks: tuple[RobotTrack, ...]) -> list[bool]:
    """Whether a :class:`TrackedBall` (default config) still believes a ball after each of ten
    frames without sightings, the ball seen 2 m away at ``bearing`` at 0.0 and 0.1 s (scored
    0.5, under ``start_at_once_score``: the second sighting starts the belief), with the robot
    ``tracks`` believed throughout."""
    provider = TrackedBall(BallFilterConfig(), 0.05)
    provider.reset(Prior(pose=POSE, rng=np.random.default_rng(0)))
    inputs = {
        BALL_SIGHTINGS: (
            BallSighting(range_m=2.0, bearing_rad=bearing, cov=np.diag([1e-4, 1e-4]), score=0.5),
        ),
        ODOMETRY: OdometryStep(delta=np.zeros(3), walk_delta=np.zeros(3)),
        SELF_POSE: slam_estimate(),
        ROBOT_TRACKS: tracks,
        "kick_velocity": NO_KICK,
        "camera": CAMERA,
        "camera_state": STATE,
    }
    assert not provider.update(inputs, 0.0).known  # waits for a second sighting
    assert provider.update(inputs, 0.1).known
    empty = {**inputs, BALL_SIGHTINGS: ()}
    return [provider.update(empty, 0.1 + 0.1 * k).known for k in range(1, 11)]


def lost_on(frame: int | None) -> list[bool]:
    """The beliefs of :func:`known_through_misses` for a ball lost on miss ``frame`` (None:
    never)."""
    return [frame is None or k < frame for k in range(1, 11)]


def test_tracked_ball_loses_a_ball_its_camera_shows_but_does_not_see() -> None:
    """A ball seen twice 2 m along the head's direction (the camera's centre column), then never
    again: lost on the third frame (the chance to see it there 0.8: 0.2³ < 0.01); the same
    ball seen behind the robot, where the camera does not look, is still believed after ten
    frames. The provider's in_view reads the frame's camera and its state."""
    for bearing, lost_at in ((STATE.head_yaw, 3), (math.pi, None)):
        assert known_through_misses(bearing, ()) == lost_on(lost_at), bearing


def test_tracked_ball_counts_no_misses_beside_a_confirmed_robot_track() -> None:
    """The ball of the test above, seen twice 2 m along the head's direction, then never again,
    with a robot track 0.3 m from it on the field (the pose turned and shifted): confirmed, the
    misses beside it are not counted (the default chance 0 there) and the ball is still
    believed after ten frames; unconfirmed, the track is not taken and the ball is lost on the
    third frame."""
    beside = field_point(2.0, STATE.head_yaw) + np.array([0.0, 0.3])
    for confirmed, lost_at in ((True, None), (False, 3)):
        track = RobotTrack(
            track_id=1,
            state=np.array([*beside, 0.0, 0.0]),
            cov=np.eye(4) * 0.01,
            team=None,
            confirmed=confirmed,
            last_seen_s=0.0,
        )
        assert known_through_misses(STATE.head_yaw, (track,)) == lost_on(lost_at), confirmed


def test_cnn_ball_sightings_provider_reads_the_frame_camera() -> None:
    provider = CnnBallSightings(CnnBallConfig(row_offset_px=1.0))
    inputs = {
        IMAGE_DETECTIONS: (ball_detection(1.2, 0.1),),  # a box large enough to judge
        "image": TEXTURED,
        "camera": CAMERA,
        "camera_state": STATE,
    }
    (seen,) = provider.update(inputs, 0.0)
    assert seen.range_m == pytest.approx(1.2, abs=1e-6)
    assert seen.bearing_rad == pytest.approx(0.1, abs=1e-6)
    flat = np.full_like(TEXTURED, 200)  # the same box on a flat frame: a painted mark
    assert provider.update({**inputs, "image": flat}, 0.0) == ()


def test_two_camera_sightings_judge_each_camera_on_its_own_image() -> None:
    """The same ball box in both cameras (the bottom camera's state set to the top one's, its
    detector stubbed): a flat bottom image drops the bottom sighting only, a flat top image the
    top one only."""
    box = ball_detection(1.5, 0.1)

    class Detector:
        def detect_objects_downscaled(self, image: object, factor: int) -> list[Detection]:
            return [box]

    config = CnnBallConfig(row_offset_px=1.0, bottom_downscale=1)
    provider = TwoCameraCnnBallSightings(config, CnnDetectorConfig(), context())
    provider.detector = Detector()  # type: ignore[assignment]
    flat = np.full_like(TEXTURED, 200)
    inputs = {
        IMAGE_DETECTIONS: (box,),
        "image": TEXTURED,
        "camera": CAMERA,
        "camera_state": STATE,
        "bottom_image": TEXTURED,
        "bottom_camera_state": STATE,
    }
    assert len(provider.update(inputs, 0.0)) == 2
    assert len(provider.update({**inputs, "bottom_image": flat}, 0.0)) == 1
    assert len(provider.update({**inputs, "image": flat}, 0.0)) == 1
    assert provider.update({**inputs, "image": flat, "bottom_image": flat}, 0.0) == ()


# --- the oracles ----------------------------------------------------------------------------------


def camera(head_yaw: float) -> CameraState:
    return CameraState(position=np.array([0.0, 0.0, 0.5]), head_yaw=head_yaw, head_pitch=0.1)


def truth_with_ball(
    range_m: float, bearing_deg: float, pose: FloatArray = POSE, velocity=(0.3, -0.4)
) -> GroundTruth:
    """Ground truth with the ball at (range, bearing deg) from ``pose``."""
    ball = field_point(range_m, math.radians(bearing_deg), pose)
    return GroundTruth(
        robot_pose=np.asarray(pose, dtype=np.float64),
        landmark_ids=np.zeros(0, dtype=np.int64),
        landmarks=np.zeros((0, 2)),
        ball=ball,
        ball_velocity=np.array(velocity, dtype=np.float64),
    )


def oracle_sightings(config: OracleConfig, seed: int = 0) -> OracleBallSightings:
    oracle = OracleBallSightings(config, context(HFOV_DEG))
    oracle.reset(Prior(pose=np.zeros(3), rng=np.random.default_rng(seed)))
    return oracle


EXACT = OracleConfig(range_std_m=TINY, bearing_std_rad=TINY, max_range_m=6.0)


@pytest.mark.parametrize(
    ("range_m", "bearing_deg", "head_yaw_deg", "seen"),
    [
        # off-axis angle = |bearing - head yaw|, by hand, against the 30 deg half FOV
        (3.0, 0.0, 0.0, True),
        (3.0, 25.0, 0.0, True),
        (3.0, -29.0, 0.0, True),
        (3.0, 35.0, 0.0, False),
        (3.0, 35.0, 20.0, True),  # 15 deg off the head's axis
        (3.0, -40.0, 20.0, False),  # 60 deg off
        (3.0, 175.0, -170.0, True),  # behind the body, 15 deg off (across +-180)
        (5.9, 10.0, 0.0, True),
        (6.1, 10.0, 0.0, False),  # beyond max_range_m
    ],
)
def test_the_ball_oracle_sees_the_ball_only_in_range_and_fov(
    range_m: float, bearing_deg: float, head_yaw_deg: float, seen: bool
) -> None:
    found = oracle_sightings(EXACT).update(
        {
            "truth": truth_with_ball(range_m, bearing_deg),
            "camera_state": camera(math.radians(head_yaw_deg)),
        },
        0.0,
    )
    assert len(found) == int(seen)
    if seen:
        (s,) = found
        assert s.range_m == pytest.approx(range_m, abs=1e-6)
        assert abs(math.remainder(s.bearing_rad - math.radians(bearing_deg), 2 * math.pi)) < 1e-6
        np.testing.assert_allclose(s.cov, np.diag([TINY**2, TINY**2]))


def test_the_ball_oracle_sees_nothing_without_a_ball() -> None:
    truth = GroundTruth(
        robot_pose=POSE, landmark_ids=np.zeros(0, dtype=np.int64), landmarks=np.zeros((0, 2))
    )
    assert np.isnan(truth.ball).all()
    assert oracle_sightings(EXACT).update({"truth": truth, "camera_state": camera(0.0)}, 0.0) == ()


def chi2_band(dof: int) -> tuple[float, float]:
    return stats.chi2.ppf((1 - BAND) / 2, dof), stats.chi2.ppf((1 + BAND) / 2, dof)


def test_the_ball_sighting_oracle_noise_has_the_configured_std() -> None:
    """Over N draws the normalised squared range and bearing errors each sum to chi2(N) (zero
    mean, the configured std), and their means are near zero; the covariance is diag(std²)."""
    config = OracleConfig(range_std_m=0.07, bearing_std_rad=0.02)
    oracle = oracle_sightings(config, seed=7)
    truth = truth_with_ball(2.5, -12.0)
    n = 3000
    errors = np.empty((n, 2))
    for k in range(n):
        (s,) = oracle.update({"truth": truth, "camera_state": camera(0.0)}, 0.1 * k)
        errors[k] = s.range_m - 2.5, math.remainder(s.bearing_rad + math.radians(12.0), 2 * math.pi)
        if k == 0:
            np.testing.assert_allclose(s.cov, np.diag([0.07**2, 0.02**2]), rtol=1e-12)
    lo, hi = chi2_band(n)
    for column, std in ((0, 0.07), (1, 0.02)):
        z = errors[:, column] / std
        assert lo <= float(np.sum(z**2)) <= hi, (column, np.std(z))
        assert abs(float(np.mean(z))) < 3.3 / math.sqrt(n)


def oracle_ball(config: OracleConfig, seed: int = 0) -> OracleBall:
    oracle = OracleBall(config)
    oracle.reset(Prior(pose=np.zeros(3), rng=np.random.default_rng(seed)))
    return oracle


def test_the_ball_oracle_adds_the_configured_noise_with_its_diagonal_covariance() -> None:
    """Over N draws the 4-d NEES sums to chi2(4 N); each component's mean is near zero; the
    covariance is diag(position std², position std², velocity std², velocity std²); the ball
    is known, seen now, and its relative state is the field state seen from the true pose."""
    config = OracleConfig(position_std_m=0.06, ball_velocity_std_mps=0.1)
    oracle = oracle_ball(config, seed=3)
    truth = truth_with_ball(2.0, 40.0)
    true_state = np.concatenate([truth.ball, truth.ball_velocity])
    std = np.array([0.06, 0.06, 0.1, 0.1])
    n = 1000
    z = np.empty((n, 4))
    back = rot(-POSE[2])
    for k in range(n):
        est = oracle.update({"truth": truth}, 0.5 * k)
        assert est.known and est.last_seen_s == 0.5 * k
        z[k] = (est.state - true_state) / std
        if k == 0:
            np.testing.assert_allclose(est.cov, np.diag(std**2), rtol=1e-12)
        np.testing.assert_allclose(est.relative[:2], back @ (est.state[:2] - POSE[:2]), atol=1e-12)
        np.testing.assert_allclose(est.relative[2:], back @ est.state[2:], atol=1e-12)
    lo, hi = chi2_band(4 * n)
    assert lo <= float(np.sum(z**2)) <= hi
    assert np.all(np.abs(z.mean(axis=0)) < 3.3 / math.sqrt(n)), z.mean(axis=0)


def test_the_ball_oracle_needs_a_ball_and_a_reset() -> None:
    no_ball = GroundTruth(
        robot_pose=POSE, landmark_ids=np.zeros(0, dtype=np.int64), landmarks=np.zeros((0, 2))
    )
    with pytest.raises(ValueError, match="ball"):
        oracle_ball(OracleConfig()).update({"truth": no_ball}, 0.0)
    no_velocity = truth_with_ball(2.0, 0.0, velocity=(math.nan, math.nan))
    with pytest.raises(ValueError, match="ball"):
        oracle_ball(OracleConfig()).update({"truth": no_velocity}, 0.0)
    with pytest.raises(RuntimeError, match="reset"):
        OracleBall(OracleConfig()).update({"truth": truth_with_ball(2.0, 0.0)}, 0.0)
    with pytest.raises(ValueError, match="ball_velocity_std_mps"):
        OracleConfig(ball_velocity_std_mps=0.0)


def test_oracle_ball_pipelines_read_only_what_they_need() -> None:
    both = PerceptionPipeline(
        PipelineConfig(ball_sightings="oracle", ball="oracle"), context(), outputs=[BALL]
    )
    assert both.representations == (BALL,)  # the ball oracle needs no sightings
    assert both.frame_inputs == frozenset({"truth"})
    both.reset(POSE, np.random.default_rng(0))
    out = both.step(SensorFrame(time_s=0.0, truth=truth_with_ball(2.0, 10.0)))
    np.testing.assert_allclose(out[BALL].state[:2], field_point(2.0, math.radians(10.0)), atol=0.3)


def test_the_filter_on_oracle_sightings_finds_the_resting_ball() -> None:
    """Oracle sightings (range std 0.05 m, bearing 0.01 rad) of a resting ball 2 m ahead, the
    oracle's pose: after 30 frames the filter's position error is a few centimetres."""
    pipeline = PerceptionPipeline(
        PipelineConfig(
            ball_sightings="oracle", ball="filter", self_pose="oracle", robot_sightings="oracle"
        ),
        context(HFOV_DEG),
        outputs=[BALL],
    )
    assert pipeline.frame_inputs == frozenset(
        {"truth", "camera", "camera_state", "odometry_delta", "kick_velocity"}
    )
    pipeline.reset(POSE, np.random.default_rng(4))
    truth = truth_with_ball(2.0, 5.0, velocity=(0.0, 0.0))
    for k in range(30):
        frame = SensorFrame(
            time_s=0.1 * k,
            odometry_delta=np.zeros(3),
            camera=CAMERA,
            camera_state=camera(0.0),
            kick_velocity=NO_KICK,
            truth=truth,
        )
        out = pipeline.step(frame)
        assert out[BALL].last_seen_s == pytest.approx(0.1 * k)
    assert np.linalg.norm(out[BALL].state[:2] - truth.ball) < 0.1
    assert np.linalg.norm(out[BALL].relative[:2] - rot(-POSE[2]) @ (truth.ball - POSE[:2])) < 0.05
