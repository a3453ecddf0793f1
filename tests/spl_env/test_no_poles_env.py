"""SPL envs without poles: the robot localises from the field's own features (seed 004 ch. 2)."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import spl_env  # noqa: F401  (registers the ids)
from perception.field.features import FEATURE_KINDS
from spl_env import NO_POLES_KWARGS

NO_POLES_IDS = ("SPL/ActiveVision-NoPoles-v1", "SPL/LookAround-NoPoles-v0")
GEOMETRIC = {"camera_mode": "geometric", "frontend": "colour"}


@pytest.mark.parametrize("env_id", NO_POLES_IDS)
def test_check_env_passes_without_poles(env_id: str) -> None:
    env = gym.make(env_id, episode_s=1.0, **GEOMETRIC)
    check_env(env.unwrapped, skip_render_check=True)
    env.close()


def test_the_field_holds_no_poles_and_the_observation_no_pole_map() -> None:
    env = gym.make("SPL/ActiveVision-NoPoles-v1", episode_s=1.0, **GEOMETRIC)
    obs, info = env.reset(seed=0)
    assert not any(key.startswith("landmarks_") for key in obs)
    assert obs["field_features_since_seen"].shape == (len(FEATURE_KINDS),)
    assert info["ground_truth"]["landmarks"].shape == (0, 2)
    assert env.unwrapped.scene.codes == ()
    env.close()


def test_the_info_lists_the_frames_field_features_in_fixed_shapes() -> None:
    env = gym.make("SPL/ActiveVision-NoPoles-v1", episode_s=1.0, **GEOMETRIC)
    env.reset(seed=0)
    shapes = set()
    for _ in range(5):
        _, _, _, _, info = env.step(np.array([0.0, 0.3], dtype=np.float32))
        p = info["perception"]
        shapes.add((p["field_features"].shape, p["field_feature_kinds"].shape))
        count = int(p["field_features_count"])
        assert (p["field_feature_kinds"][:count] >= 0).all()
        assert (p["field_feature_kinds"][count:] == -1).all()
    assert len(shapes) == 1
    env.close()


def test_field_features_keep_the_pose_over_a_walk() -> None:
    """A minute's patrol with the head scanning: the pose from the field features stays close,
    where the walk odometry alone drifts away."""
    env = gym.make("SPL/ActiveVision-NoPoles-v1", episode_s=60.0, **GEOMETRIC)
    env.reset(seed=3)
    errors, drift = [], []
    done, k = False, 0
    while not done:
        action = np.array([np.sin(0.3 * k), -0.2], dtype=np.float32)  # a slow head scan
        _, _, terminated, truncated, info = env.step(action)
        truth = info["ground_truth"]["robot_pose"][:2]
        errors.append(np.hypot(*(info["perception"]["pose"][:2] - truth)))
        drift.append(np.hypot(*(info["perception"]["odometry_pose"][:2] - truth)))
        done, k = terminated or truncated, k + 1
    assert np.mean(errors) < 0.15 < np.mean(drift)
    env.close()


def test_the_pole_slam_cannot_run_without_poles() -> None:
    with pytest.raises(ValueError, match="poles_enabled"):
        gym.make("SPL/ActiveVision-v1", **{"scene.poles_enabled": False})


def test_the_no_poles_ids_are_their_pole_envs_with_two_settings() -> None:
    assert NO_POLES_KWARGS == {"scene.poles_enabled": False, "self_pose": "field_features"}
    a = gym.make("SPL/ActiveVision-NoPoles-v1", episode_s=1.0, **GEOMETRIC)
    b = gym.make("SPL/ActiveVision-v1", episode_s=1.0, **GEOMETRIC, **NO_POLES_KWARGS)
    obs_a, _ = a.reset(seed=2)
    obs_b, _ = b.reset(seed=2)
    for key in obs_a:
        np.testing.assert_array_equal(obs_a[key], obs_b[key])
    a.close()
    b.close()
