"""Oracle providers: which poles they report (known geometry) and the noise they add (chi-square
bands on many draws with fixed seeds)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from perception.pipeline import PerceptionPipeline, PipelineConfig
from perception.providers.base import PerceptionContext
from perception.providers.oracles import (
    OracleConfig,
    OraclePoleSightings,
    OracleRobotSightings,
    OracleSelfPose,
)
from perception.representations import POLE_SIGHTINGS, SELF_POSE, Prior
from perception.types import (
    CameraModel,
    CameraState,
    GroundTruth,
    PoleCode,
    PoleGeometry,
    SensorFrame,
    SlamEstimate,
)

CODES = (
    PoleCode(landmark_id=1, top="pink", bottom="yellow"),
    PoleCode(landmark_id=2, top="pink", bottom="blue"),
    PoleCode(landmark_id=3, top="pink", bottom="green"),
)
HFOV_DEG = 60.0  # half field of view 30 deg
TINY = 1e-9  # noise std small enough for exact geometry checks
BAND = 0.999  # two-sided probability of the chi-square bands


def context(hfov_deg: float = HFOV_DEG) -> PerceptionContext:
    return PerceptionContext(CameraModel(hfov_deg=hfov_deg), CODES, PoleGeometry())


def camera(head_yaw: float) -> CameraState:
    return CameraState(position=np.array([0.0, 0.0, 0.5]), head_yaw=head_yaw, head_pitch=0.1)


def polar(ranges_bearings: list[tuple[float, float]]) -> np.ndarray:
    """Field points (N, 2) at (range, bearing deg) from the origin facing +x."""
    return np.array(
        [[r * math.cos(math.radians(b)), r * math.sin(math.radians(b))] for r, b in ranges_bearings]
    )


def chi2_band(dof: int) -> tuple[float, float]:
    return stats.chi2.ppf((1 - BAND) / 2, dof), stats.chi2.ppf((1 + BAND) / 2, dof)


def exact_oracle(max_range_m: float = 8.0, hfov_deg: float = HFOV_DEG) -> OraclePoleSightings:
    config = OracleConfig(range_std_m=TINY, bearing_std_rad=TINY, max_range_m=max_range_m)
    oracle = OraclePoleSightings(config, context(hfov_deg))
    oracle.reset(Prior(pose=np.zeros(3), rng=np.random.default_rng(0)))
    return oracle


# Poles around a robot at the origin facing +x: id -> (range m, bearing deg).
POLES = {
    9: (3.0, 0.0),  # straight ahead
    4: (5.0, 20.0),  # inside the 30 deg half FOV
    7: (2.0, -25.0),  # inside, to the right
    2: (4.0, 40.0),  # outside at yaw 0, inside at yaw 35 deg
    5: (9.0, 5.0),  # beyond 8 m
    3: (3.0, 180.0),  # behind
    8: (6.0, 70.0),  # inside only at yaw 60 deg
}


def truth_of(poles: dict[int, tuple[float, float]], pose=(0.0, 0.0, 0.0)) -> GroundTruth:
    """Ground truth with the poles placed relative to ``pose`` (range, bearing deg)."""
    ids = np.array(list(poles), dtype=np.int64)
    local = polar(list(poles.values()))
    x, y, t = pose
    c, s = math.cos(t), math.sin(t)
    field = np.column_stack(
        [x + c * local[:, 0] - s * local[:, 1], y + s * local[:, 0] + c * local[:, 1]]
    )
    return GroundTruth(
        robot_pose=np.array(pose, dtype=np.float64), landmark_ids=ids, landmarks=field
    )


@pytest.mark.parametrize(
    ("head_yaw_deg", "seen"),
    [
        # off-axis angles by hand (half FOV 30 deg; 5 lies beyond 8 m, always unseen):
        (0.0, [4, 7, 9]),  # 9: 0, 4: 20, 7: 25; 2: 40 and 8: 70 out
        (35.0, [2, 4]),  # 2: 5, 4: 15; 9: 35, 8: 35, 7: 60 out
        (60.0, [2, 8]),  # 2: 20, 8: 10; 4: 40, 9: 60 out
        (-70.0, []),  # 7: 45, 9: 70, everything else further
        (175.0, [3]),  # 3: 5 (behind the body, the head turned round)
    ],
)
@pytest.mark.parametrize("pose", [(0.0, 0.0, 0.0), (1.5, -2.0, 2.5)])
def test_oracle_sees_exactly_the_poles_in_range_and_fov(
    head_yaw_deg: float, seen: list[int], pose: tuple[float, float, float]
) -> None:
    """Poles placed at known ranges and bearings from the robot (at the origin facing +x, or
    moved and turned with its poles): exactly those within 8 m and 30 deg of the head yaw, in
    id order, at their true range and bearing."""
    found = exact_oracle().update(
        {"truth": truth_of(POLES, pose), "camera_state": camera(math.radians(head_yaw_deg))}, 0.0
    )
    assert [s.landmark_id for s in found] == seen
    for s in found:
        r, b = POLES[s.landmark_id]
        assert s.range_m == pytest.approx(r, abs=1e-6)
        assert abs(math.remainder(s.bearing_rad - math.radians(b), 2 * math.pi)) < 1e-6
        assert -math.pi <= s.bearing_rad < math.pi
        np.testing.assert_allclose(s.cov, np.diag([TINY**2, TINY**2]))


def test_oracle_max_range_is_configured() -> None:
    found = exact_oracle(max_range_m=4.5).update(
        {"truth": truth_of(POLES), "camera_state": camera(0.0)}, 0.0
    )
    assert [s.landmark_id for s in found] == [7, 9]  # 4 at 5 m is now out of range


def test_oracle_fov_is_the_camera_fov() -> None:
    """The default Nao camera: 56.3 deg, half 28.15 deg: 27 deg is in, 29.5 deg is out, on
    either side."""
    poles = {1: (3.0, 27.0), 2: (3.0, 29.5), 3: (3.0, -27.0), 4: (3.0, -29.5)}
    found = exact_oracle(hfov_deg=56.3).update(
        {"truth": truth_of(poles), "camera_state": camera(0.0)}, 0.0
    )
    assert [s.landmark_id for s in found] == [1, 3]


def test_oracle_without_landmarks_and_before_reset() -> None:
    empty = GroundTruth(
        robot_pose=np.zeros(3), landmark_ids=np.zeros(0, np.int64), landmarks=np.zeros((0, 2))
    )
    assert exact_oracle().update({"truth": empty, "camera_state": camera(0.0)}, 0.0) == ()
    fresh = OraclePoleSightings(OracleConfig(), context())
    with pytest.raises(RuntimeError, match="reset"):
        fresh.update({"truth": truth_of(POLES), "camera_state": camera(0.0)}, 0.0)
    with pytest.raises(RuntimeError, match="reset"):
        OracleSelfPose(OracleConfig()).update({"truth": truth_of(POLES)}, 0.0)


@pytest.mark.parametrize("name", ["range_std_m", "bearing_std_rad", "max_range_m"])
def test_oracle_config_refuses_non_positive_values(name: str) -> None:
    with pytest.raises(ValueError, match=name):
        OracleConfig(**{name: 0.0})


# ----- noise --------------------------------------------------------------------------------------
def test_oracle_sighting_noise_has_the_configured_std() -> None:
    """Over N frames of two poles, the normalised squared errors of range and bearing each sum
    to a chi-square(2N) variable (zero mean, the configured std); their means are near zero; the
    reported covariance is diag(std²)."""
    config = OracleConfig(range_std_m=0.08, bearing_std_rad=0.03)
    oracle = OraclePoleSightings(config, context())
    oracle.reset(Prior(pose=np.zeros(3), rng=np.random.default_rng(11)))
    poles = {1: (4.0, 10.0), 2: (2.5, -15.0)}
    truth = truth_of(poles, pose=(0.3, -0.7, 1.0))
    n = 3000
    errors = np.empty((n, 2, 2))
    for k in range(n):
        found = oracle.update({"truth": truth, "camera_state": camera(0.0)}, 0.1 * k)
        assert [s.landmark_id for s in found] == [1, 2]
        for j, s in enumerate(found):
            r, b = poles[s.landmark_id]
            errors[k, j] = (
                s.range_m - r,
                math.remainder(s.bearing_rad - math.radians(b), 2 * math.pi),
            )
            if k == 0:
                np.testing.assert_allclose(s.cov, np.diag([0.08**2, 0.03**2]), rtol=1e-12)
    lo, hi = chi2_band(2 * n)
    for column, std in ((0, 0.08), (1, 0.03)):
        z = errors[:, :, column] / std
        assert lo <= float(np.sum(z**2)) <= hi, (column, np.std(z))
        assert abs(float(np.mean(z))) < 3.3 / math.sqrt(2 * n)  # 99.9 % of a standard normal


def test_oracle_self_pose_covariances_and_nees() -> None:
    """The covariances are the configured diagonals; over N draws the pose NEES sums to a
    chi-square(3N) variable and the landmark errors to chi-square(2 L N)."""
    config = OracleConfig(position_std_m=0.07, heading_std_rad=0.04, landmark_std_m=0.03)
    oracle = OracleSelfPose(config)
    oracle.reset(Prior(pose=np.zeros(3), rng=np.random.default_rng(5)))
    pose = np.array([2.0, -1.0, math.pi - 0.01])  # near pi: the heading error must be wrapped
    truth = truth_of(POLES, pose=tuple(pose))
    n_landmarks = len(POLES)
    p_inv = np.diag(1.0 / np.array([0.07, 0.07, 0.04]) ** 2)
    n = 3000
    nees = lm_nees = 0.0
    for k in range(n):
        est = oracle.update({"truth": truth}, 0.1 * k)
        assert isinstance(est, SlamEstimate)
        if k == 0:
            np.testing.assert_allclose(est.pose_cov, np.diag([0.07**2, 0.07**2, 0.04**2]))
            np.testing.assert_allclose(est.landmark_covs, np.tile(np.eye(2) * 0.03**2, (7, 1, 1)))
            np.testing.assert_array_equal(est.landmark_ids, list(POLES))
        e = est.pose - pose
        e[2] = math.remainder(e[2], 2 * math.pi)
        assert -math.pi <= est.pose[2] < math.pi
        nees += float(e @ p_inv @ e)
        lm_nees += float(np.sum((est.landmarks - truth.landmarks) ** 2) / 0.03**2)
    lo, hi = chi2_band(3 * n)
    assert lo <= nees <= hi
    lo, hi = chi2_band(2 * n_landmarks * n)
    assert lo <= lm_nees <= hi


def test_reset_with_the_same_seed_repeats_the_draws() -> None:
    def draws(seed: int) -> list[np.ndarray]:
        out = []
        pipeline = PerceptionPipeline(
            PipelineConfig(pole_sightings="oracle", self_pose="oracle"),
            context(),
            outputs=[SELF_POSE, POLE_SIGHTINGS],
        )
        pipeline.reset(np.zeros(3), np.random.default_rng(seed))
        frame = SensorFrame(time_s=0.0, camera_state=camera(0.0), truth=truth_of(POLES))
        for _ in range(5):
            result = pipeline.step(frame)
            out.append(result[SELF_POSE].pose)
            out.append(np.array([[s.range_m, s.bearing_rad] for s in result[POLE_SIGHTINGS]]))
        return out

    first, again, other = draws(3), draws(3), draws(4)
    for a, b in zip(first, again, strict=True):
        np.testing.assert_array_equal(a, b)
    assert not all(np.array_equal(a, b) for a, b in zip(first, other, strict=True))


def test_oracle_pipeline_reads_only_truth_and_camera_state() -> None:
    pipeline = PerceptionPipeline(
        PipelineConfig(pole_sightings="oracle", self_pose="oracle"),
        context(),
        outputs=[SELF_POSE, POLE_SIGHTINGS],
    )
    assert pipeline.frame_inputs == frozenset({"truth", "camera_state"})
    pipeline.reset(np.zeros(3), np.random.default_rng(0))
    with pytest.raises(ValueError, match="truth"):
        pipeline.step(SensorFrame(time_s=0.0, camera_state=camera(0.0)))


def test_oracle_robot_sightings_report_the_robots_in_view_with_their_teams() -> None:
    config = OracleConfig(range_std_m=TINY, bearing_std_rad=TINY, max_range_m=4.0)
    oracle = OracleRobotSightings(config, context())
    oracle.reset(Prior(pose=np.zeros(3), rng=np.random.default_rng(0)))
    # (range m, bearing deg): in view, outside the 30 deg half FOV, too far, in view on the left
    robots = polar([(1.5, 10.0), (2.0, 40.0), (5.0, 0.0), (3.0, -25.0)])
    truth = GroundTruth(
        robot_pose=np.zeros(3),
        landmark_ids=np.zeros(0, dtype=np.int64),
        landmarks=np.zeros((0, 2)),
        robots=robots,
        robot_teams=np.array([1, 0, 1, 0]),
    )
    seen = oracle.update({"truth": truth, "camera_state": camera(0.0)}, 0.0)
    got = [(s.team, round(s.range_m, 6), round(math.degrees(s.bearing_rad), 6)) for s in seen]
    assert got == [(1, 1.5, 10.0), (0, 3.0, -25.0)]
    # turning the head 35 deg left brings the 40 deg robot in and the -25 deg one out
    seen = oracle.update({"truth": truth, "camera_state": camera(math.radians(35.0))}, 0.1)
    assert [s.team for s in seen] == [1, 0]
    assert all(np.allclose(s.cov, np.diag([TINY**2, TINY**2])) for s in seen)
