"""The observation encoders against hand-computed values, their composition, and the refusal of
non-finite input; the head encoding against the one head mapping."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest
from gymnasium import spaces

from perception.representations import POLE_LAST_SEEN, SELF_POSE, PerceptionOutput
from perception.types import CameraState, SensorFrame, SlamEstimate
from spl_env.field import FieldDimensions
from spl_env.observations.base import EncoderInput, box, compose_space, encode_all, squash
from spl_env.observations.body import EpisodeClockEncoder, HeadEncoder, SonarEncoder
from spl_env.observations.poles import PoleMapEncoder
from spl_env.observations.self_pose import SelfPoseEncoder
from spl_env.robots.nao import RobotConfig, head_action, head_target
from spl_env.sim.placement import Placement
from spl_env.tasks.base import TaskContext
from spl_env.tasks.head_control import HeadControlTaskConfig
from spl_env.tasks.look_around import LookAroundTask

ROBOT = RobotConfig()
ENCODERS = (
    SelfPoseEncoder(FieldDimensions()),
    HeadEncoder(ROBOT),
    PoleMapEncoder(6),
    SonarEncoder(),
    EpisodeClockEncoder(60.0),
)
SPACE = compose_space(ENCODERS)


def _output(
    pose: np.ndarray,
    time_s: float = 10.0,
    landmark_offset: tuple[float, float] = (0.0, 3.0),
    last_seen: dict[int, float] | None = None,
) -> PerceptionOutput:
    """Landmark 2 at ``landmark_offset`` (field frame) from the pose: by default 3 m to +y."""
    slam = SlamEstimate(
        pose=pose,
        pose_cov=np.diag([0.25, 0.01, 0.04]),
        landmark_ids=np.array([2], dtype=np.int64),
        landmarks=np.array([[pose[0] + landmark_offset[0], pose[1] + landmark_offset[1]]]),
        landmark_covs=np.diag([0.09, 0.16])[None],
    )
    return PerceptionOutput(
        time_s=time_s,
        representations={
            SELF_POSE: slam,
            POLE_LAST_SEEN: {2: 8.0} if last_seen is None else last_seen,
        },
    )


def _frame(
    head: tuple[float, float] = (0.0, 0.0), sonar: np.ndarray | None = None, time_s: float = 10.0
) -> SensorFrame:
    state = CameraState(position=np.array([0.05, 0.0, 0.52]), head_yaw=head[0], head_pitch=head[1])
    return SensorFrame(time_s=time_s, camera_state=state, sonar=sonar)


def _observe(output: PerceptionOutput, frame: SensorFrame) -> dict[str, np.ndarray]:
    return encode_all(ENCODERS, EncoderInput(output=output, frame=frame))


def test_values_match_hand_computation() -> None:
    sonar = np.full((3, 10), np.nan)
    sonar[1, :2] = [1.0, 2.0]
    obs = _observe(_output(np.array([2.6, -1.85, 0.0])), _frame((0.5, 0.0), sonar))
    np.testing.assert_allclose(obs["self_pose_field"], [0.5, -0.5, 1.0, 0.0], atol=1e-6)
    np.testing.assert_allclose(obs["self_pose_std"], [0.5 / 1.0, 0.1 / 0.6, 0.2 / 0.7], atol=1e-6)
    assert obs["landmarks_mask"].tolist() == [0, 0, 1, 0, 0, 0]
    assert obs["landmarks_cos_bearing"][2] == pytest.approx(0.0, abs=1e-6)
    assert obs["landmarks_sin_bearing"][2] == pytest.approx(1.0)
    assert obs["landmarks_range"][2] == pytest.approx(0.5)  # 3 / (3 + 3)
    assert obs["landmarks_std"][2] == pytest.approx(0.5 / 1.0)  # sqrt(0.25) / (0.5 + 0.5)
    assert obs["landmarks_since_seen"][2] == pytest.approx(2.0 / 4.0)
    assert obs["landmarks_since_seen"][0] == 1.0
    # unmapped poles: no bearing, no range, std 1
    for key, value in (("cos_bearing", 0.0), ("sin_bearing", 0.0), ("range", 0.0), ("std", 1.0)):
        assert np.delete(obs[f"landmarks_{key}"], 2).tolist() == [value] * 5
    assert obs["sonar"].tolist() == [1.0, 0.5, 1.0]  # only the middle sector echoes, at 1 m
    assert obs["head_angles"][0] == pytest.approx(0.5 / math.radians(119.5))
    # level pitch sits at (0 - mid) / half of [-38.5, 29.5] degrees
    assert obs["head_angles"][1] == pytest.approx(4.5 / 34.0, abs=1e-6)
    assert obs["time_fraction"][0] == pytest.approx(10.0 / 60.0)
    assert SPACE.contains(obs)
    assert set(obs) == set(SPACE.spaces)
    assert all(v.dtype == np.float32 for v in obs.values())


def test_bearing_is_in_the_robot_frame_not_the_field_frame() -> None:
    # facing +y (theta = pi/2), a landmark 3 m towards field +x is on the robot's right
    output = _output(np.array([0.0, 0.0, math.pi / 2]), landmark_offset=(3.0, 0.0))
    obs = _observe(output, _frame())
    assert obs["landmarks_cos_bearing"][2] == pytest.approx(0.0, abs=1e-6)
    assert obs["landmarks_sin_bearing"][2] == pytest.approx(-1.0)
    assert obs["landmarks_range"][2] == pytest.approx(0.5)  # 3 / (3 + 3)
    np.testing.assert_allclose(obs["self_pose_field"], [0.0, 0.0, 0.0, 1.0], atol=1e-6)


def test_far_estimate_saturates_inside_the_box() -> None:
    obs = _observe(_output(np.array([50.0, -50.0, 1.0])), _frame())
    assert obs["self_pose_field"][:2].tolist() == [1.5, -1.5]
    assert SPACE.contains(obs)


def test_unbounded_quantities_squash_into_the_unit_interval() -> None:
    np.testing.assert_allclose(squash(np.array([0.0, 1.0, 3.0, 1e12]), 3.0), [0, 0.25, 0.5, 1])
    huge = _output(np.zeros(3), time_s=1e9, landmark_offset=(1e6, 0.0), last_seen={2: 0.0})
    slam = huge[SELF_POSE]
    slam.pose_cov[:] = np.diag([1e8, 1e8, 1e8])
    slam.landmark_covs[:] = np.diag([1e8, 1e8])
    echoes = np.full((3, 10), np.nan)
    echoes[:, 0] = [1e9, 0.0, 2.0]
    obs = _observe(huge, _frame((math.radians(119.5), math.radians(29.5)), echoes))
    assert SPACE.contains(obs)
    assert obs["time_fraction"][0] == 1.0  # the clock saturates after the episode
    assert obs["landmarks_range"][2] < 1.0 and obs["landmarks_std"][2] < 1.0
    assert obs["sonar"].tolist() == pytest.approx([1.0, 0.0, 2.0 / 3.0], abs=1e-6)
    np.testing.assert_allclose(obs["head_angles"], [1.0, 1.0], atol=1e-6)


def test_nothing_mapped_nothing_seen_and_no_sonar() -> None:
    slam = SlamEstimate(
        pose=np.zeros(3),
        pose_cov=np.eye(3) * 0.01,
        landmark_ids=np.zeros(0, dtype=np.int64),
        landmarks=np.zeros((0, 2)),
        landmark_covs=np.zeros((0, 2, 2)),
    )
    output = PerceptionOutput(time_s=0.0, representations={SELF_POSE: slam, POLE_LAST_SEEN: {}})
    obs = _observe(output, _frame())
    assert obs["landmarks_mask"].tolist() == [0.0] * 6
    assert obs["landmarks_std"].tolist() == [1.0] * 6
    assert obs["landmarks_since_seen"].tolist() == [1.0] * 6
    assert obs["sonar"].tolist() == [1.0] * 3  # frame.sonar is None: no echo anywhere
    assert obs["time_fraction"].tolist() == [0.0]
    assert SPACE.contains(obs)


@pytest.mark.parametrize(
    ("pose", "pose_var", "key"),
    [
        ([np.nan, 0.0, 0.0], 0.01, "self_pose_field"),
        ([0.0, 0.0, np.nan], 0.01, "self_pose_field"),
        ([0.0, 0.0, 0.0], np.inf, "self_pose_std"),
        ([0.0, 0.0, 0.0], np.nan, "self_pose_std"),
    ],
)
def test_diverged_perception_is_refused(pose: list[float], pose_var: float, key: str) -> None:
    output = _output(np.array(pose))
    output[SELF_POSE].pose_cov[0, 0] = pose_var
    with np.errstate(invalid="ignore"), pytest.raises(FloatingPointError, match=key):
        _observe(output, _frame())


def test_a_non_finite_landmark_covariance_is_refused_naming_its_key() -> None:
    output = _output(np.zeros(3))
    output[SELF_POSE].landmark_covs[0, 0, 0] = np.nan
    with pytest.raises(FloatingPointError, match="landmarks_std"):
        _observe(output, _frame())


def test_encoders_read_only_what_they_require() -> None:
    frame = _frame()
    for encoder in ENCODERS:
        needed = {name: _output(np.zeros(3))[name] for name in encoder.requires}
        output = PerceptionOutput(time_s=10.0, representations=needed)
        values = encoder.encode(EncoderInput(output=output, frame=frame))
        assert set(values) == set(encoder.spaces())
    with pytest.raises(KeyError, match="pole_last_seen"):
        PoleMapEncoder(6).encode(
            EncoderInput(
                output=PerceptionOutput(
                    time_s=0.0, representations={SELF_POSE: _output(np.zeros(3))[SELF_POSE]}
                ),
                frame=frame,
            )
        )
    with pytest.raises(ValueError, match="camera_state"):
        HeadEncoder(ROBOT).encode(
            EncoderInput(output=_output(np.zeros(3)), frame=SensorFrame(time_s=0.0))
        )


class _Clash:
    """An encoder whose key another encoder already has."""

    requires: tuple[str, ...] = ()

    def spaces(self) -> dict[str, spaces.Box]:
        return {"sonar": box(0.0, 1.0, 3)}

    def encode(self, data: Any) -> dict[str, np.ndarray]:
        return {"sonar": np.zeros(3)}


def test_compose_space_refuses_a_key_from_two_encoders() -> None:
    with pytest.raises(ValueError, match="'sonar' comes from two encoders"):
        compose_space([*ENCODERS, _Clash()])
    assert compose_space([]) == spaces.Dict({})


def test_head_control_tasks_compose_the_documented_observation() -> None:
    context = TaskContext(
        dimensions=FieldDimensions(),
        robot=ROBOT,
        control_dt_s=0.1,
        n_landmarks=6,
        placement=Placement(FieldDimensions(), np.zeros((0, 3)), ROBOT.body_radius_m),
    )
    space = compose_space(LookAroundTask(HeadControlTaskConfig(), context).encoders())
    shapes = {key: box.shape for key, box in space.spaces.items()}
    assert shapes == {
        "self_pose_field": (4,),
        "self_pose_std": (3,),
        "head_angles": (2,),
        "landmarks_cos_bearing": (6,),
        "landmarks_sin_bearing": (6,),
        "landmarks_range": (6,),
        "landmarks_mask": (6,),
        "landmarks_std": (6,),
        "landmarks_since_seen": (6,),
        "sonar": (3,),
        "time_fraction": (1,),
    }
    assert all(box.dtype == np.float32 for box in space.spaces.values())


# --- the head mapping ---------------------------------------------------------------------------


def test_head_target_covers_the_joint_ranges() -> None:
    np.testing.assert_allclose(
        head_target(ROBOT, np.array([-1.0, -1.0])),
        [-math.radians(119.5), math.radians(-38.5)],
    )
    np.testing.assert_allclose(
        head_target(ROBOT, np.array([1.0, 1.0])), [math.radians(119.5), math.radians(29.5)]
    )
    np.testing.assert_allclose(
        head_target(ROBOT, np.array([0.0, 0.0])), [0.0, math.radians(-4.5)], atol=1e-12
    )


def test_head_encoding_inverts_head_target() -> None:
    rng = np.random.default_rng(0)
    for action in [*rng.uniform(-1.0, 1.0, size=(50, 2)), np.array([-1.0, 1.0])]:
        yaw, pitch = head_target(ROBOT, action)
        np.testing.assert_allclose(head_action(ROBOT, yaw, pitch), action, atol=1e-12)
        # the observation of joints standing at the target reads the action back
        obs = HeadEncoder(ROBOT).encode(
            EncoderInput(output=_output(np.zeros(3)), frame=_frame((yaw, pitch)))
        )
        np.testing.assert_allclose(obs["head_angles"], action, atol=1e-12)
    for yaw, pitch in rng.uniform(-0.6, 0.5, size=(20, 2)):
        np.testing.assert_allclose(
            head_target(ROBOT, head_action(ROBOT, yaw, pitch)), [yaw, pitch], atol=1e-12
        )
    # beyond the joint limits the inverse is not clipped
    assert head_action(ROBOT, 2 * ROBOT.head_yaw_limit_rad, 0.0)[0] == pytest.approx(2.0)
