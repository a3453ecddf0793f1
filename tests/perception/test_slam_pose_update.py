"""EKF SLAM fusing a pose observation (``EkfSlam.update_pose``, the field features' sensor model
on a field with poles) against the information-form closed form written out here, its
chi-square gate, and the fused provider keeping the pose on a walk with no pole in view."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.stats import chi2

from perception.field.pose_filter import PoseFilter, PoseFilterConfig
from perception.field.pose_observation import PoseObservation
from perception.field.visibility import FeatureViewConfig
from perception.geometry import FloatArray, compose, wrap_angle
from perception.pipeline import PerceptionPipeline, PipelineConfig
from perception.providers.base import PerceptionContext
from perception.providers.slam import EkfSlamFieldPose, FieldFusionConfig
from perception.representations import ODOMETRY_POSE, SELF_POSE, Prior
from perception.slam import EkfSlam, EkfSlamConfig
from perception.types import (
    CameraModel,
    CameraState,
    GroundTruth,
    LandmarkObservation,
    PoleGeometry,
    SensorFrame,
)


def mapped_slam(backend: str = "classic") -> EkfSlam:
    """A filter at (0.5, -0.3, 0.2) that has walked a little and mapped two landmarks, so its
    covariance has pose-landmark cross terms."""
    slam = EkfSlam(EkfSlamConfig(backend=backend), [0.5, -0.3, 0.2])
    slam.predict([0.2, 0.05, 0.1])
    cov = np.diag([0.05**2, 0.03**2])
    slam.update(
        [
            LandmarkObservation(landmark_id=1, range_m=2.0, bearing_rad=0.3, cov=cov),
            LandmarkObservation(landmark_id=2, range_m=3.0, bearing_rad=-0.6, cov=cov),
        ]
    )
    slam.predict([0.3, 0.0, -0.2])
    return slam


def closed_form(
    mu: FloatArray, sigma: FloatArray, z: FloatArray, information: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """The information-form update of a state (n,) by a direct pose measurement: with ``J =
    [I3, 0]``, ``Sigma+ = (Sigma^-1 + J^T L J)^-1``, ``mu+ = mu + Sigma+ J^T L (z - pose)``."""
    n = len(mu)
    full = np.zeros((n, n))
    full[:3, :3] = information
    posterior = np.linalg.inv(np.linalg.inv(sigma) + full)
    e = z - mu[:3]
    e[2] = wrap_angle(e[2])
    step = np.zeros(n)
    step[:3] = information @ e
    return mu + posterior @ step, posterior


def observation(pose: list[float], information: FloatArray) -> PoseObservation:
    return PoseObservation(np.array(pose), information, rms_error_m=0.01, features=3)


FULL = np.diag([1 / 0.03**2, 1 / 0.04**2, 1 / 0.02**2])
# a single line along the field's x axis at some angle: informs the normal offset and heading
_u = np.array([math.cos(0.4), math.sin(0.4), 0.0])
_n = np.array([-math.sin(0.4), math.cos(0.4), 0.0])
LINE = np.outer(_n, _n) / 0.02**2 + np.diag([0.0, 0.0, 1 / 0.03**2])


@pytest.mark.parametrize("information", [FULL, LINE], ids=["full rank", "one line (rank 2)"])
@pytest.mark.parametrize("backend", ["classic", "fej"])
def test_the_pose_update_is_the_information_form_closed_form(
    information: FloatArray, backend: str
) -> None:
    slam = mapped_slam(backend)
    mu, sigma = slam.mean, slam.cov
    z = mu[:3] + np.array([0.04, -0.03, 0.02])
    assert slam.update_pose(observation(list(z), information))
    expected_mu, expected_sigma = closed_form(mu, sigma, z, information)
    np.testing.assert_allclose(slam.mean, expected_mu, atol=1e-10)
    np.testing.assert_allclose(slam.cov, expected_sigma, atol=1e-12)
    assert np.allclose(slam.cov, slam.cov.T) and np.linalg.eigvalsh(slam.cov).min() > 0
    # the landmarks moved with the pose through the cross-covariances
    assert not np.allclose(slam.mean[3:], mu[3:])


def test_a_residual_along_the_uninformed_direction_moves_nothing() -> None:
    """One line: the robot's position along it is not observed. A pose observation that
    differs only along the line leaves the pose where it was when that direction is
    uncorrelated with the others."""
    slam = EkfSlam(EkfSlamConfig(initial_pose_std=(0.1, 0.1, 0.05)), [0.0, 0.0, 0.4])
    mu = slam.mean
    z = mu[:3] + 0.3 * _u
    assert slam.update_pose(observation(list(z), LINE))
    np.testing.assert_allclose(slam.mean, mu, atol=1e-12)


def test_a_weight_fuses_that_share_of_the_information() -> None:
    slam, reference = mapped_slam(), mapped_slam()
    z = slam.mean[:3] + np.array([0.05, 0.02, -0.03])
    slam.update_pose(observation(list(z), FULL), weight=0.1)
    reference.update_pose(observation(list(z), 0.1 * FULL))
    np.testing.assert_allclose(slam.mean, reference.mean, atol=1e-12)
    np.testing.assert_allclose(slam.cov, reference.cov, atol=1e-14)


@pytest.mark.parametrize("weight", ["1", None, 0.0, 1.5])
def test_a_weight_that_is_not_a_share_is_refused_by_name(weight: object) -> None:
    slam = mapped_slam()
    with pytest.raises(ValueError, match=r"weight must be"):
        slam.update_pose(observation(list(slam.mean[:3]), FULL), weight=weight)  # type: ignore[arg-type]


def test_a_landmark_id_that_is_not_an_int_is_refused_by_name() -> None:
    with pytest.raises(TypeError, match=r"landmark_id must be an int, got list"):
        mapped_slam().measurement_jacobian([1])  # type: ignore[arg-type]


def test_without_landmarks_it_is_the_field_pose_filter_update() -> None:
    config = PoseFilterConfig(gate_probability=None, observation_weight=0.3)
    slam = EkfSlam(EkfSlamConfig(), [1.0, 2.0, 3.0])
    pose_filter = PoseFilter(config, [1.0, 2.0, 3.0])
    obs = observation([1.05, 1.97, -3.1], FULL)  # the heading across ±pi
    slam.update_pose(obs, weight=0.3)
    pose_filter.update(obs)
    np.testing.assert_allclose(slam.mean, pose_filter.pose, atol=1e-12)
    np.testing.assert_allclose(slam.cov, pose_filter.cov, atol=1e-14)


@pytest.mark.parametrize("information", [FULL, LINE], ids=["3 dof", "2 dof"])
def test_the_gate_refuses_beyond_the_chi_square_quantile(information: FloatArray) -> None:
    """With the fused share ``w`` of ``L``, the distance in the subspace ``w L`` informs,
    written here from its eigenvectors ``U_k`` and eigenvalues ``Lambda_k``:
    ``d² = e_k^T (U_k^T Sigma_pose U_k + Lambda_k^-1)^-1 e_k``, ``e_k = U_k^T e``, against
    chi2(rank L) at 99 %: an observation just inside is fused, one just outside refused. The
    residual also has a large part along the line, which a line does not inform."""
    weight = 0.2
    slam = mapped_slam()
    values, vectors = np.linalg.eigh(weight * information)
    kept = values > 1e-9 * values.max()
    U_k, Lambda_k = vectors[:, kept], values[kept]
    threshold = chi2.ppf(0.99, int(kept.sum()))
    direction = np.array([0.6, -0.5, 0.4]) + (0.0 if kept.all() else 2.0) * _u

    def d2(e: FloatArray) -> float:
        e_k = U_k.T @ e
        inner = U_k.T @ slam.cov[:3, :3] @ U_k + np.diag(1.0 / Lambda_k)
        return float(e_k @ np.linalg.solve(inner, e_k))

    scale = math.sqrt(threshold / d2(direction))
    for factor, fused in ((0.99, True), (1.01, False)):
        trial = mapped_slam()
        before_mu, before_cov = trial.mean, trial.cov
        z = before_mu[:3] + factor * scale * direction
        obs = observation(list(z), information)
        assert trial.update_pose(obs, weight=weight, gate_probability=0.99) is fused
        assert trial.rejected_poses == (0 if fused else 1)
        if not fused:
            np.testing.assert_array_equal(trial.mean, before_mu)
            np.testing.assert_array_equal(trial.cov, before_cov)


def test_the_heading_stays_wrapped_across_pi() -> None:
    """From 3.10 rad, an observation at -3.10 rad (0.08 rad further on, across pi) turns the
    heading on through pi: it comes out in [-pi, pi), as the wrapped closed form."""
    slam = EkfSlam(EkfSlamConfig(initial_pose_std=(0.1, 0.1, 0.3)), [0.0, 0.0, 3.10])
    mu, sigma = slam.mean, slam.cov
    assert slam.update_pose(observation([0.0, 0.0, -3.10], FULL))
    expected, _ = closed_form(mu, sigma, np.array([0.0, 0.0, -3.10]), FULL)
    assert -math.pi <= slam.mean[2] < math.pi
    assert expected[2] > math.pi  # the closed form's own heading went past pi
    assert abs(slam.mean[2] - wrap_angle(expected[2])) < 1e-10


def test_an_observation_without_information_is_not_fused() -> None:
    slam = mapped_slam()
    before_mu, before_cov = slam.mean, slam.cov
    assert not slam.update_pose(
        observation([9.0, 9.0, 0.0], np.zeros((3, 3))), gate_probability=0.99
    )
    np.testing.assert_array_equal(slam.mean, before_mu)
    np.testing.assert_array_equal(slam.cov, before_cov)
    assert slam.rejected_poses == 0  # not fused, and not refused either


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"weight": 0.0}, ValueError, "weight"),
        ({"weight": 1.5}, ValueError, "weight"),
        ({"weight": math.nan}, ValueError, "weight"),
        ({"gate_probability": 1.0}, ValueError, "gate_probability"),
        ({"gate_probability": 0.0}, ValueError, "gate_probability"),
        ({"gate_probability": math.nan}, ValueError, "gate_probability"),
        ({"gate_probability": True}, TypeError, "gate_probability"),
        ({"gate_probability": "0.99"}, TypeError, "gate_probability"),
    ],
)
def test_bad_arguments_raise_naming_them(
    kwargs: dict[str, object], error: type[Exception], match: str
) -> None:
    slam = mapped_slam()
    with pytest.raises(error, match=match):
        slam.update_pose(observation([0.5, -0.3, 0.2], FULL), **kwargs)  # type: ignore[arg-type]


def test_a_non_observation_raises_type_error() -> None:
    with pytest.raises(TypeError, match="PoseObservation"):
        mapped_slam().update_pose(np.zeros(3))  # type: ignore[arg-type]


# ----- the fused provider ---------------------------------------------------------------------

STATE = CameraState(
    position=np.array([0.05, 0.0, 0.5]), head_yaw=0.0, head_pitch=0.0, tilt=math.radians(20)
)


def test_slam_with_the_field_features_holds_a_pose_the_poles_alone_lose() -> None:
    """A 30 s walk about the centre circle with no pole on the field (the context has none);
    the odometry's turn rate is biased by 0.05 rad/s. SLAM alone drifts with it; SLAM with
    the field features' pose observations stays on the walk."""
    view = FeatureViewConfig(point_std_m=0.01, point_std_per_m=0.01)
    errors: dict[str, list[float]] = {}
    for self_pose in ("ekf_slam", "ekf_slam_field_features"):
        config = PipelineConfig(
            self_pose=self_pose,
            pole_sightings="oracle",
            field_features="oracle",
            feature_view=view,
        )
        context = PerceptionContext(CameraModel(), (), PoleGeometry())
        pipeline = PerceptionPipeline(config, context, outputs=[SELF_POSE, ODOMETRY_POSE])
        rng = np.random.default_rng(4)
        truth = np.array([-2.0, -0.5, 0.2])
        pipeline.reset(truth.copy(), np.random.default_rng(1))
        errors[self_pose] = []
        for k in range(1, 301):
            step = np.array([0.015, 0.0, 0.01])
            truth = compose(truth, step)
            measured = step + np.array([0.0, 0.0, 0.005]) + rng.normal(0.0, 0.002, 3)
            ground = GroundTruth(
                robot_pose=truth,
                landmark_ids=np.zeros(0, dtype=np.int64),
                landmarks=np.zeros((0, 2)),
            )
            sensed = SensorFrame(
                time_s=0.1 * k,
                odometry_delta=measured,
                camera_state=STATE,
                camera=CameraModel(),
                truth=ground,
            )
            pose = pipeline.step(sensed)[SELF_POSE].pose
            errors[self_pose].append(float(np.hypot(*(pose[:2] - truth[:2]))))
    assert errors["ekf_slam"][-1] > 0.5  # the poles' SLAM, with no pole, is dead reckoning
    fused = errors["ekf_slam_field_features"]
    assert max(fused) < 0.15 and np.mean(fused[100:]) < 0.05


def test_inflating_the_pose_adds_to_its_block_only() -> None:
    slam = mapped_slam()
    before = slam.cov
    extra = np.outer([0.1, -0.05, 0.2], [0.1, -0.05, 0.2])
    slam.inflate_pose(extra)
    expected = before.copy()
    expected[:3, :3] += extra
    np.testing.assert_array_equal(slam.cov, expected)
    assert np.linalg.eigvalsh(slam.cov).min() > 0


@pytest.mark.parametrize(
    "extra", [-np.eye(3), np.full((3, 3), np.nan), np.eye(2)], ids=["negative", "nan", "shape"]
)
def test_a_bad_inflation_raises_and_changes_nothing(extra: FloatArray) -> None:
    slam = mapped_slam()
    before = slam.cov
    with pytest.raises(ValueError, match="extra_cov"):
        slam.inflate_pose(extra)
    np.testing.assert_array_equal(slam.cov, before)


def blocked_robot_heading_errors(after_refused: int) -> tuple[list[float], int]:
    """A robot blocked in front of the centre circle whose odometry reports a turn of 3° a
    frame for 8 s that never happens; no pole on the field. Heading errors (rad) per frame,
    and the provider's inflations."""
    config = PipelineConfig(
        self_pose="ekf_slam_field_features",
        pole_sightings="oracle",
        field_features="oracle",
        feature_view=FeatureViewConfig(point_std_m=0.01, point_std_per_m=0.01),
        field_fusion=FieldFusionConfig(
            observation_weight=0.1, after_refused_observations=after_refused
        ),
    )
    context = PerceptionContext(CameraModel(), (), PoleGeometry())
    pipeline = PerceptionPipeline(config, context, outputs=[SELF_POSE])
    truth = np.array([-1.5, 0.3, 0.1])  # the circle and the halfway line in view
    pipeline.reset(truth.copy(), np.random.default_rng(1))
    ground = GroundTruth(
        robot_pose=truth, landmark_ids=np.zeros(0, dtype=np.int64), landmarks=np.zeros((0, 2))
    )
    errors = []
    for k in range(1, 81):
        sensed = SensorFrame(
            time_s=0.1 * k,
            odometry_delta=np.array([0.0, 0.0, math.radians(3.0)]),
            camera_state=STATE,
            camera=CameraModel(),
            truth=ground,
        )
        pose = pipeline.step(sensed)[SELF_POSE].pose
        errors.append(abs(float(wrap_angle(pose[2] - truth[2]))))
    provider = pipeline.provider(SELF_POSE)
    assert isinstance(provider, EkfSlamFieldPose)
    return errors, provider.inflations


def test_a_blocked_robot_comes_back_when_refusals_inflate_the_pose() -> None:
    """The odometry claims 240° of turning. Never inflating, the gate ends up refusing every
    field observation and the heading follows the odometry; inflating after 8 refusals in a
    row brings it back each time it runs off (3° a frame, so by a saw tooth of about 25°)."""
    never, none = blocked_robot_heading_errors(0)
    inflated, inflations = blocked_robot_heading_errors(8)
    assert never[-1] > math.radians(90.0) and none == 0
    assert max(inflated) < math.radians(30.0) and np.mean(inflated) < math.radians(15.0)
    assert inflations >= 3  # once per run-off


@pytest.mark.parametrize(
    ("field", "value", "error"),
    [
        ("observation_weight", 0.0, ValueError),
        ("observation_weight", 1.2, ValueError),
        ("gate_probability", 1.0, ValueError),
        ("after_refused_observations", -1, ValueError),
        ("after_refused_observations", 2.5, TypeError),
    ],
)
def test_bad_fusion_config_raises_naming_the_field(
    field: str, value: object, error: type[Exception]
) -> None:
    with pytest.raises(error, match=f"FieldFusionConfig.{field}"):
        FieldFusionConfig(**{field: value})  # type: ignore[arg-type]


def fusing_provider() -> EkfSlamFieldPose:
    """The fused provider with the default FieldFusionConfig, reset at the origin."""
    context = PerceptionContext(CameraModel(), (), PoleGeometry())
    provider = EkfSlamFieldPose(
        EkfSlamConfig(initial_pose_std=(0.02, 0.02, 0.02)),
        PipelineConfig().sensor_model,
        FieldFusionConfig(),
        context,
    )
    provider.reset(Prior(pose=np.zeros(3), rng=np.random.default_rng(0)))
    return provider


def test_refusals_count_in_a_row_and_the_eighth_inflates() -> None:
    """Observations 0.5 rad off a filter sure of its heading to 0.02 rad are refused. Seven,
    one that is fused (which ends the run), seven more: no inflation yet; the eighth in a row
    inflates the pose and is fused, the heading going (nearly) all the way. Seven refused
    after it (further off still) do not inflate again: the count started over."""
    provider = fusing_provider()
    slam = provider.slam
    far, near = observation([0.0, 0.0, 0.5], FULL), observation([0.0, 0.0, 0.0], FULL)
    for obs in [far] * 7 + [near] + [far] * 7:
        provider._fuse(obs)
    assert provider.inflations == 0 and slam.rejected_poses == 14
    provider._fuse(far)
    assert provider.inflations == 1 and abs(slam.mean[2] - 0.5) < 0.05
    farther = observation([0.0, 0.0, 1.5], FULL)
    for _ in range(7):
        provider._fuse(farther)
    assert provider.inflations == 1 and slam.rejected_poses == 22
    provider.reset(Prior(pose=np.zeros(3), rng=np.random.default_rng(0)))
    assert provider.inflations == 0 and provider.slam.rejected_poses == 0


def test_an_observation_without_information_leaves_the_run_of_refusals() -> None:
    provider = fusing_provider()
    far, empty = observation([0.0, 0.0, 0.5], FULL), observation([5.0, 5.0, 0.0], np.zeros((3, 3)))
    for obs in [far] * 7 + [empty]:
        provider._fuse(obs)
    assert provider.inflations == 0
    provider._fuse(far)  # the eighth refused in a row
    assert provider.inflations == 1


def test_the_inflation_is_the_outer_product_of_the_disagreement(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The eighth refused observation in a row inflates the pose block by ``e e^T``, ``e``
    the observation's residual from the SLAM pose (heading wrapped across pi)."""
    provider = fusing_provider()
    slam = provider.slam
    slam.inflate_pose(np.diag([0.0, 0.0, 9.0]))  # let the heading go anywhere ...
    slam.update_pose(observation([0.0, 0.0, 3.1], FULL))  # ... and put it near pi
    seen: list[FloatArray] = []
    inflate = EkfSlam.inflate_pose

    def spy(self: EkfSlam, extra_cov: FloatArray) -> None:
        seen.append(np.array(extra_cov))
        inflate(self, extra_cov)

    monkeypatch.setattr(EkfSlam, "inflate_pose", spy)
    far = observation([0.3, -0.2, -2.9], FULL)  # 0.28 rad on across pi
    for _ in range(8):
        pose = slam.mean[:3]
        provider._fuse(far)
    assert len(seen) == 1
    e = np.array([0.3, -0.2, -2.9]) - pose
    e[2] = math.remainder(e[2], math.tau)
    assert abs(e[2]) < 0.5
    np.testing.assert_allclose(seen[0], np.outer(e, e), atol=1e-12)
