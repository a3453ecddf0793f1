"""Every registered env in Gymnasium's and Stable-Baselines3's vector envs, with the default
full info (whose variable-length entries once made the vector envs fail to stack it: "could not
broadcast"). Two sub-envs each, and past an episode's end so that auto-reset runs too."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import gymnasium as gym
import numpy as np
import pytest

import spl_env  # noqa: F401  (registers the ids)
from spl_env import ENV_IDS

SPL_FAST: dict[str, Any] = {"camera_mode": "geometric", "frontend": "colour", "episode_s": 1.0}


def fast(env_id: str) -> dict[str, Any]:
    """Short episodes; the SPL envs in the geometric camera mode."""
    return SPL_FAST if env_id.startswith("SPL/") else {"episode_s": 1.0}


N_ENVS = 2
STEPS = 12  # one episode is 10 steps: the vector envs reset a sub-env on the way


def stacked_layout(info: dict[str, Any]) -> dict[str, tuple[int, ...]]:
    """Shapes of the stacked info entries (the ``_name`` masks left out)."""
    out: dict[str, tuple[int, ...]] = {}
    for key, value in info.items():
        if key.startswith("_"):
            continue
        if isinstance(value, dict):
            out.update({f"{key}.{k}": v for k, v in stacked_layout(value).items()})
        else:
            out[key] = np.shape(value)
    return out


def single_layout(env_id: str, **kwargs: Any) -> dict[str, tuple[int, ...]]:
    """Shapes of one env's info at reset, with a leading axis of N_ENVS."""
    env = gym.make(env_id, **fast(env_id), **kwargs)
    _, info = env.reset(seed=0)
    env.close()

    def walk(d: dict[str, Any], prefix: str = "") -> dict[str, tuple[int, ...]]:
        out: dict[str, tuple[int, ...]] = {}
        for key, value in d.items():
            if isinstance(value, dict):
                out.update(walk(value, f"{prefix}{key}."))
            else:
                out[f"{prefix}{key}"] = (N_ENVS, *np.shape(value))
        return out

    return walk(info)


@pytest.mark.parametrize("mode", ["sync", "async"])
@pytest.mark.parametrize("env_id", ENV_IDS)
@pytest.mark.parametrize("info_level", ["full", "light"])
def test_gymnasium_make_vec(env_id: str, mode: str, info_level: str) -> None:
    envs = gym.make_vec(
        env_id,
        num_envs=N_ENVS,
        vectorization_mode=mode,
        vector_kwargs={"copy": True},
        info_level=info_level,
        **fast(env_id),
    )
    try:
        expected = single_layout(env_id, info_level=info_level)
        assert (info_level == "full") == ("perception.pose" in expected)
        envs.action_space.seed(0)
        obs, info = envs.reset(seed=[1, 2])
        assert envs.observation_space.contains(obs)
        assert stacked_layout(info) == expected
        # different seeds, different robots: the sub-envs are not copies of one another
        if info_level == "full":
            truth = info["ground_truth"]
            poses = truth["robot_pose"]
            if "robots" in truth:  # (the penalty taker always starts on the same spot)
                poses = np.concatenate([poses, truth["robots"].reshape(N_ENVS, -1)], axis=1)
            assert not np.array_equal(poses[0], poses[1])
        resetting = np.zeros(N_ENVS, dtype=bool)  # next-step autoreset: this step resets
        ended = 0
        for _ in range(STEPS):
            obs, reward, terminated, truncated, info = envs.step(envs.action_space.sample())
            assert envs.observation_space.contains(obs)
            assert reward.shape == (N_ENVS,) and np.all(np.isfinite(reward))
            assert terminated.shape == truncated.shape == (N_ENVS,)
            # a reset sub-env reports its reset info: the same layout
            assert stacked_layout(info) == expected
            terms = info["reward_terms"]
            stepped = ~resetting
            total = sum(v for k, v in terms.items() if not k.startswith("_"))  # "_k": masks
            np.testing.assert_allclose(reward[stepped], total[stepped], atol=1e-12)
            np.testing.assert_array_equal(reward[resetting], 0.0)
            resetting = terminated | truncated
            ended += int(resetting.sum())
        assert ended == N_ENVS  # each sub-env's 10-step episode ended once
    finally:
        envs.close()


@pytest.mark.parametrize("mode", ["sync", "async"])
def test_make_vec_runs_v1_for_200_steps(mode: str) -> None:
    # The robots issue's check: 200 steps of two SPL/ActiveVision-v1 envs (geometric mode: the
    # default vision + sonar robot front end emulated), 5-second episodes.
    envs = gym.make_vec(
        "SPL/ActiveVision-v1",
        num_envs=N_ENVS,
        vectorization_mode=mode,
        camera_mode="geometric",
        frontend="colour",
        episode_s=5.0,
    )
    try:
        envs.action_space.seed(0)
        obs, _ = envs.reset(seed=[3, 4])
        ended = 0
        for _ in range(200):
            obs, reward, terminated, truncated, _ = envs.step(envs.action_space.sample())
            assert envs.observation_space.contains(obs) and np.all(np.isfinite(reward))
            ended += int((terminated | truncated).sum())
        # 50-step episodes and a reset step after each (next-step autoreset): ends at 50, 101, 152
        assert ended == 3 * N_ENVS
    finally:
        envs.close()


def make_fns(env_id: str) -> list[Callable[[], gym.Env]]:
    return [lambda: gym.make(env_id, **fast(env_id)) for _ in range(N_ENVS)]


@pytest.mark.parametrize("vec", ["dummy", "subproc"])
@pytest.mark.parametrize("env_id", ENV_IDS)
def test_stable_baselines3_vec_envs(env_id: str, vec: str) -> None:
    from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv

    envs = (
        DummyVecEnv(make_fns(env_id))
        if vec == "dummy"
        else SubprocVecEnv(make_fns(env_id), start_method="fork")
    )
    try:
        envs.seed(3)
        obs = envs.reset()
        space = envs.observation_space
        for key, sub in space.spaces.items():
            assert obs[key].shape == (N_ENVS, *sub.shape)
        dones_seen = 0
        for _ in range(STEPS):
            actions = np.stack([envs.action_space.sample() for _ in range(N_ENVS)])
            obs, rewards, dones, infos = envs.step(actions)
            assert rewards.shape == (N_ENVS,) and np.all(np.isfinite(rewards))
            assert len(infos) == N_ENVS
            for k, info in enumerate(infos):
                assert rewards[k] == pytest.approx(sum(info["reward_terms"].values()))
                assert info["perception"]["pose"].shape == (3,)
                if dones[k]:
                    dones_seen += 1
                    assert info["TimeLimit.truncated"]
                    terminal = info["terminal_observation"]
                    assert set(terminal) == set(space.spaces)
        assert dones_seen == N_ENVS  # each sub-env's 10-step episode ended once
    finally:
        envs.close()
