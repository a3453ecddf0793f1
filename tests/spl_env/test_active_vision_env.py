"""Gymnasium contract of every registered env id: checkers, spaces, determinism, bad input."""

from __future__ import annotations

import warnings
from collections.abc import Iterator

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env as gym_check_env

from spl_env import ENV_IDS

FAST = {"episode_s": 3.0}  # 30 steps: short episodes keep the suite quick


@pytest.fixture(params=ENV_IDS)
def env(request: pytest.FixtureRequest) -> Iterator[gym.Env]:
    e = gym.make(request.param, render_mode="rgb_array", **FAST)
    yield e
    e.close()


def test_gymnasium_check_env_without_warnings(env: gym.Env) -> None:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        gym_check_env(env.unwrapped, skip_render_check=False)
    assert [str(w.message) for w in caught] == []


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_sb3_check_env_without_warnings(env_id: str) -> None:
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    e = gym.make(env_id, **FAST)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        sb3_check_env(e.unwrapped, warn=True)
    e.close()
    assert [str(w.message) for w in caught] == []


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_random_rollout_stays_inside_observation_space(env_id: str) -> None:
    e = gym.make(env_id, episode_s=30.0)
    e.action_space.seed(1)
    obs, info = e.reset(seed=1)
    assert e.observation_space.contains(obs)
    for _ in range(300):
        obs, reward, terminated, truncated, info = e.step(e.action_space.sample())
        assert e.observation_space.contains(obs), {k: (v.min(), v.max()) for k, v in obs.items()}
        assert np.isfinite(reward)
        assert reward == pytest.approx(sum(info["reward_terms"].values()))
        cov = info["perception"]["pose_cov"]
        np.testing.assert_allclose(cov, cov.T, atol=1e-12)
        assert np.linalg.eigvalsh(cov).min() >= -1e-12
        if terminated or truncated:
            obs, info = e.reset()
    e.close()


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_same_seed_same_observations(env_id: str) -> None:
    def rollout() -> list[dict[str, np.ndarray]]:
        e = gym.make(env_id, **FAST)
        actions = np.random.default_rng(7).uniform(-1, 1, size=(20, 2)).astype(np.float32)
        obs, _ = e.reset(seed=42)
        out = [obs]
        for a in actions:
            out.append(e.step(a)[0])
        e.close()
        return out

    first, second = rollout(), rollout()
    for a, b in zip(first, second, strict=True):
        for key in a:
            np.testing.assert_array_equal(a[key], b[key])


def test_reset_with_same_seed_repeats_episode(env: gym.Env) -> None:
    a = np.array([0.5, 0.0], dtype=np.float32)

    def episode(seed: int) -> list[dict[str, np.ndarray]]:
        env.reset(seed=seed)
        return [env.step(a)[0] for _ in range(5)]

    first = episode(3)
    other = episode(4)  # a different episode in between must leave no trace
    second = episode(3)
    assert any(
        not np.array_equal(f["self_pose_field"], o["self_pose_field"])
        for f, o in zip(first, other, strict=True)
    )
    for f, s in zip(first, second, strict=True):
        for key in f:
            np.testing.assert_array_equal(f[key], s[key])


def test_info_contract(env: gym.Env) -> None:
    _, info = env.reset(seed=0)
    _, _, _, _, info = env.step(env.action_space.sample())
    per, gt = info["perception"], info["ground_truth"]
    assert per["pose"].shape == (3,) and per["pose_cov"].shape == (3, 3)
    assert per["odometry_pose"].shape == (3,)
    assert per["landmarks"].shape == (len(per["landmark_ids"]), 2)
    assert gt["robot_pose"].shape == (3,) and gt["landmarks"].shape == (6, 2)
    assert set(info["reward_terms"]) == {"position_error", "uncertainty"}
    assert set(info["timing"]) == {"physics", "render", "sensors", "perception"}


def test_truncates_after_episode_length(env: gym.Env) -> None:
    env.reset(seed=0)
    steps, truncated = 0, False
    while not truncated:
        *_, terminated, truncated, _ = env.step(np.zeros(2, dtype=np.float32))
        assert not terminated
        steps += 1
    assert steps == 30


def test_render_returns_rgb_image(env: gym.Env) -> None:
    env.reset(seed=0)
    env.step(env.action_space.sample())
    image = env.render()
    assert image.dtype == np.uint8 and image.ndim == 3 and image.shape[2] == 3
    assert image.shape[0] > 100 and image.shape[1] > 100


def test_close_twice(env: gym.Env) -> None:
    env.reset(seed=0)
    env.close()
    env.close()


@pytest.mark.parametrize(
    "action, match",
    [
        (np.array([np.nan, 0.0], dtype=np.float32), "finite"),
        (np.array([1.5, 0.0], dtype=np.float32), r"\[-1, 1\]"),
        (np.zeros(3, dtype=np.float32), "shape"),
    ],
)
def test_bad_actions_raise(env: gym.Env, action: np.ndarray, match: str) -> None:
    env.reset(seed=0)
    with pytest.raises(ValueError, match=match):
        env.step(action)


def test_step_before_reset_raises() -> None:
    e = gym.make(ENV_IDS[0], **FAST)
    with pytest.raises(gym.error.ResetNeeded):
        e.step(np.zeros(2, dtype=np.float32))
    with pytest.raises(RuntimeError, match="reset"):
        e.unwrapped.step(np.zeros(2, dtype=np.float32))
    e.close()


def test_make_kwargs_override_config_fields() -> None:
    e = gym.make(ENV_IDS[0], episode_s=2.0, n_other_robots=1, noise_std=0.0)
    cfg = e.unwrapped.config
    assert cfg.episode_s == 2.0 and cfg.sim.n_other_robots == 1 and cfg.sim.camera.noise_std == 0.0
    e.close()
    with pytest.raises(TypeError, match="unknown config field"):
        gym.make(ENV_IDS[0], no_such_field=1)
    with pytest.raises(ValueError, match="episode_s"):
        gym.make(ENV_IDS[0], episode_s=-1.0)
