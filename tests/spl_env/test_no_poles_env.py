"""SPL envs without poles: the robot localises from the field's own features (seed 004 ch. 2)."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import spl_env
from perception.field.features import FEATURE_KINDS
from spl_env import NO_POLES_KWARGS

NO_POLES_IDS = tuple(i for i in spl_env.ENV_IDS if "-NoPoles-" in i)
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


def test_the_no_poles_ids_are_their_pole_envs_with_the_no_poles_settings() -> None:
    a = gym.make("SPL/ActiveVision-NoPoles-v1", episode_s=1.0, **GEOMETRIC)
    config = a.unwrapped.config
    assert not config.scene.poles_enabled and config.scene.poster_set == "textured"
    assert config.perception.self_pose == "field_features"
    b = gym.make("SPL/ActiveVision-v1", episode_s=1.0, **GEOMETRIC, **NO_POLES_KWARGS)
    obs_a, _ = a.reset(seed=2)
    obs_b, _ = b.reset(seed=2)
    for key in obs_a:
        np.testing.assert_array_equal(obs_a[key], obs_b[key])
    a.close()
    b.close()


def test_the_bottom_camera_adds_what_it_sees_below_the_top_cameras_view() -> None:
    """Rendered only for the provider that reads it; its frame's features join the top
    camera's (which stay as they were: the top image is rendered first, from the same
    generator state)."""
    with_bottom = gym.make(
        "SPL/ActiveVision-NoPoles-v1", field_features="vision_both_cameras", episode_s=1.0
    )
    top_only = gym.make("SPL/ActiveVision-NoPoles-v1", episode_s=1.0)
    with_bottom.reset(seed=3)  # a line at the robot's feet, below the top camera's view
    top_only.reset(seed=3)
    frame = with_bottom.unwrapped.sensor_frame
    assert frame.bottom_image is not None and frame.bottom_image.shape == frame.image.shape
    assert frame.bottom_camera_state.tilt == pytest.approx(np.radians(39.7))
    assert top_only.unwrapped.sensor_frame.bottom_image is None
    both = with_bottom.unwrapped.perception_output["field_features"]
    top = top_only.unwrapped.perception_output["field_features"]
    assert len(both) > len(top)
    for a, b in zip(both[: len(top)], top, strict=True):
        assert a.kind == b.kind
        np.testing.assert_array_equal(a.points, b.points)
    # the bottom camera looks nearer the feet: its features are nearer than the top's
    nearest_bottom = min(f.distance_m for f in both[len(top) :])
    assert nearest_bottom < min(f.distance_m for f in top)
    with_bottom.close()
    top_only.close()


def test_the_geometric_mode_emulates_both_cameras_too() -> None:
    counts = {}
    for provider in ("vision", "vision_both_cameras"):
        env = gym.make(
            "SPL/ActiveVision-NoPoles-v1", field_features=provider, episode_s=2.0, **GEOMETRIC
        )
        env.reset(seed=3)
        counts[provider] = sum(
            int(
                env.step(np.array([0.0, 0.0], dtype=np.float32))[4]["perception"][
                    "field_features_count"
                ]
            )
            for _ in range(10)
        )
        assert env.unwrapped.sensor_frame.bottom_image is None  # nothing rendered
        env.close()
    assert counts["vision_both_cameras"] > counts["vision"]


def test_a_striker_without_poles_keeps_its_pose_from_the_field_features() -> None:
    """The scripted centre-kicking striker on the no-poles field for 30 s: the field holds no
    pole, and the believed pose stays close to the truth, where the walk odometry drifts."""
    from agents.soccer_baselines import SOCCER_BASELINES

    env = gym.make("SPL/Striker-NoPoles-v0", episode_s=30.0, **GEOMETRIC)
    player = SOCCER_BASELINES["centre_kick"].from_config(env.unwrapped.config)
    obs, info = env.reset(seed=4)
    assert info["ground_truth"]["landmarks"].shape == (0, 2)
    errors, drift = [], []
    done = False
    while not done:
        obs, _, terminated, truncated, info = env.step(player.predict(obs)[0])
        truth = info["ground_truth"]["robot_pose"][:2]
        errors.append(np.hypot(*(info["perception"]["pose"][:2] - truth)))
        drift.append(np.hypot(*(info["perception"]["odometry_pose"][:2] - truth)))
        done = terminated or truncated
    assert len(errors) > 50
    assert np.mean(errors) < 0.15 < np.max(drift)
    env.close()


def test_each_no_poles_id_names_its_pole_env() -> None:
    """``pole_env_id`` against the registry: the same entry point, the no-poles settings only
    on the no-poles id; an id with poles is its own."""
    for env_id in NO_POLES_IDS:
        poles = spl_env.pole_env_id(env_id)
        assert poles != env_id and "NoPoles" not in poles
        assert gym.spec(env_id).entry_point == gym.spec(poles).entry_point
        assert gym.spec(env_id).kwargs == NO_POLES_KWARGS and gym.spec(poles).kwargs == {}
        assert spl_env.pole_env_id(poles) == poles
