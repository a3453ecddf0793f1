"""SPL envs whose pose is EKF SLAM over the poles with the field features' pose observations
fused in (``self_pose="ekf_slam_field_features"``)."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import spl_env  # noqa: F401  (registers the env ids)
from perception.field.features import FEATURE_KINDS
from perception.providers.slam import EkfSlamFieldPose
from perception.representations import SELF_POSE
from perception.slam import EkfSlam

FUSED = {"camera_mode": "geometric", "frontend": "colour", "self_pose": "ekf_slam_field_features"}


@pytest.mark.parametrize("env_id", ["SPL/ActiveVision-v1", "SPL/Striker-v0"])
def test_check_env_passes_with_the_fused_pose(env_id: str) -> None:
    env = gym.make(env_id, episode_s=1.0, **FUSED)
    check_env(env.unwrapped, skip_render_check=True)
    env.close()


def test_the_observation_holds_the_pole_map_and_the_field_features_clock(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The env builds the fused provider, whose pose updates happen and are fused."""
    results: list[bool] = []
    update_pose = EkfSlam.update_pose

    def counted(self: EkfSlam, *args: object, **kwargs: object) -> bool:
        fused = update_pose(self, *args, **kwargs)  # type: ignore[arg-type]
        results.append(fused)
        return fused

    monkeypatch.setattr(EkfSlam, "update_pose", counted)
    env = gym.make("SPL/ActiveVision-v1", episode_s=2.0, **FUSED)
    obs, _ = env.reset(seed=0)
    assert isinstance(env.unwrapped.pipeline.provider(SELF_POSE), EkfSlamFieldPose)
    assert any(key.startswith("landmarks_") for key in obs)
    assert obs["field_features_since_seen"].shape == (len(FEATURE_KINDS),)
    env.action_space.seed(0)
    for _ in range(20):
        _, _, _, _, info = env.step(env.action_space.sample())
    assert "field_features" in info["perception"]
    # half the frames or more see the field's lines (12 of 20 here), and most are fused
    assert len(results) >= 10 and sum(results) >= 0.75 * len(results)
    env.close()


@pytest.mark.parametrize("mode", ["sync", "async"])
def test_gymnasium_make_vec_runs_the_fused_pose(mode: str) -> None:
    envs = gym.make_vec(
        "SPL/Striker-v0", num_envs=2, vectorization_mode=mode, episode_s=1.0, **FUSED
    )
    try:
        obs, _ = envs.reset(seed=[1, 2])
        if mode == "sync":
            for env in envs.envs:
                assert isinstance(env.unwrapped.pipeline.provider(SELF_POSE), EkfSlamFieldPose)
        assert envs.observation_space.contains(obs)
        envs.action_space.seed(0)
        ended = np.zeros(2, dtype=int)
        for _ in range(12):  # past the 1 s episode: the sub-envs reset themselves
            obs, rewards, terminated, truncated, info = envs.step(envs.action_space.sample())
            assert envs.observation_space.contains(obs) and np.isfinite(rewards).all()
            assert info["perception"]["pose"].shape == (2, 3)
            ended += terminated | truncated
        assert np.all(ended >= 1)
    finally:
        envs.close()


def test_stable_baselines3_vec_env_runs_the_fused_pose() -> None:
    from stable_baselines3.common.vec_env import SubprocVecEnv

    def make() -> gym.Env:
        return gym.make("SPL/Striker-v0", episode_s=1.0, **FUSED)

    envs = SubprocVecEnv([make, make], start_method="fork")
    try:
        envs.seed(3)
        envs.reset()
        for _ in range(12):
            _, rewards, _, infos = envs.step(np.stack([envs.action_space.sample()] * 2))
            assert np.isfinite(rewards).all() and len(infos) == 2
    finally:
        envs.close()
