"""The observation builder against hand-computed values and its refusal of non-finite input."""

from __future__ import annotations

import math

import numpy as np
import pytest

from perception.types import PerceptionOutput, SlamEstimate
from spl_env.envs.observation import ObservationBuilder
from spl_env.field import FieldDimensions
from spl_env.sim.robot import RobotConfig

BUILDER = ObservationBuilder(
    dimensions=FieldDimensions(), robot=RobotConfig(), n_landmarks=6, episode_s=60.0
)


def _output(
    pose: np.ndarray, time_s: float = 10.0, landmark_offset: tuple[float, float] = (0.0, 3.0)
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
        time_s=time_s, slam=slam, odometry_pose=pose.copy(), observations=(), last_seen_s={2: 8.0}
    )


def test_values_match_hand_computation() -> None:
    sonar = np.full((3, 10), np.nan)
    sonar[1, :2] = [1.0, 2.0]
    obs = BUILDER.build(_output(np.array([2.6, -1.85, 0.0])), np.array([0.5, 0.0]), sonar)
    np.testing.assert_allclose(obs["self_pose_field"], [0.5, -0.5, 1.0, 0.0], atol=1e-6)
    np.testing.assert_allclose(obs["self_pose_std"], [0.5 / 1.0, 0.1 / 0.6, 0.2 / 0.7], atol=1e-6)
    assert obs["landmarks_mask"].tolist() == [0, 0, 1, 0, 0, 0]
    assert obs["landmarks_cos_bearing"][2] == pytest.approx(0.0, abs=1e-6)
    assert obs["landmarks_sin_bearing"][2] == pytest.approx(1.0)
    assert obs["landmarks_range"][2] == pytest.approx(0.5)  # 3 / (3 + 3)
    assert obs["landmarks_std"][2] == pytest.approx(0.5 / 1.0)  # sqrt(0.25) / (0.5 + 0.5)
    assert obs["landmarks_since_seen"][2] == pytest.approx(2.0 / 4.0)
    assert obs["landmarks_since_seen"][0] == 1.0
    assert obs["sonar"].tolist() == [1.0, 0.5, 1.0]  # only the middle sector echoes, at 1 m
    assert obs["head_angles"][0] == pytest.approx(0.5 / math.radians(119.5))
    # level pitch sits at (0 - mid) / half of [-38.5, 29.5] degrees
    assert obs["head_angles"][1] == pytest.approx(4.5 / 34.0, abs=1e-6)
    assert obs["time_fraction"][0] == pytest.approx(10.0 / 60.0)
    assert BUILDER.space().contains(obs)


def test_bearing_is_in_the_robot_frame_not_the_field_frame() -> None:
    # facing +y (theta = pi/2), a landmark 3 m towards field +x is on the robot's right
    output = _output(np.array([0.0, 0.0, math.pi / 2]), landmark_offset=(3.0, 0.0))
    obs = BUILDER.build(output, np.zeros(2), None)
    assert obs["landmarks_cos_bearing"][2] == pytest.approx(0.0, abs=1e-6)
    assert obs["landmarks_sin_bearing"][2] == pytest.approx(-1.0)
    assert obs["landmarks_range"][2] == pytest.approx(0.5)  # 3 / (3 + 3)
    np.testing.assert_allclose(obs["self_pose_field"], [0.0, 0.0, 0.0, 1.0], atol=1e-6)


def test_far_estimate_saturates_inside_the_box() -> None:
    obs = BUILDER.build(_output(np.array([50.0, -50.0, 1.0])), np.zeros(2), None)
    assert obs["self_pose_field"][:2].tolist() == [1.5, -1.5]
    assert BUILDER.space().contains(obs)


def test_diverged_perception_is_refused() -> None:
    with pytest.raises(FloatingPointError, match="self_pose_field"):
        BUILDER.build(_output(np.array([np.nan, 0.0, 0.0])), np.zeros(2), None)
