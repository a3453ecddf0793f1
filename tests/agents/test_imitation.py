"""Behaviour cloning warm start: discounted returns by hand, config checks, the recorded teacher
episodes against an independent replay, and a PPO policy fitted to a scanning teacher."""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np
import pytest

import spl_env  # noqa: F401  (registers the ids)
from agents.baselines import FixedHead
from agents.imitation import (
    Demonstrations,
    WarmStartConfig,
    discounted_returns,
    imitate,
    record_teacher,
)

ENV_ID = "SPL/LookAround-v0"
ENV_KWARGS: dict[str, Any] = {"camera_mode": "geometric", "frontend": "colour", "episode_s": 2.0}


def test_discounted_returns_of_three_steps() -> None:
    returns = discounted_returns(np.array([1.0, 2.0, 4.0]), 0.5)
    # G2 = 4, G1 = 2 + 0.5 * 4 = 4, G0 = 1 + 0.5 * 4 = 3
    np.testing.assert_allclose(returns, [3.0, 4.0, 4.0])
    np.testing.assert_allclose(discounted_returns(np.array([1.0, 2.0, 4.0]), 0.0), [1, 2, 4])
    assert discounted_returns(np.array([]), 0.9).shape == (0,)


@pytest.mark.parametrize(
    "kwargs, field",
    [
        ({"teacher": "random"}, "teacher"),
        ({"episodes": 0}, "episodes"),
        ({"episodes": 2.0}, "episodes"),
        ({"epochs": 0}, "epochs"),
        ({"batch_size": -1}, "batch_size"),
        ({"learning_rate": -1e-3}, "learning_rate"),
        ({"learning_rate": 0.0}, "learning_rate"),
        ({"learning_rate": math.nan}, "learning_rate"),
        ({"value_weight": -0.5}, "value_weight"),
    ],
)
def test_warm_start_config_refuses_bad_fields(kwargs: dict[str, Any], field: str) -> None:
    with pytest.raises((ValueError, TypeError), match=rf"WarmStartConfig\.{field}\b"):
        WarmStartConfig(**kwargs)


def test_warm_start_config_accepts_zero_value_weight() -> None:
    assert WarmStartConfig(teacher="scan", value_weight=0.0).value_weight == 0.0


def test_value_targets_stop_short_of_the_time_limit() -> None:
    env = gym.make(ENV_ID, **ENV_KWARGS)
    demos = record_teacher(env, WarmStartConfig(teacher="fixed", episodes=1, epochs=1), 0.5, 0)
    env.close()
    # γ = 0.5: the 3 / (1 - γ) = 6 steps before the limit are no value targets
    np.testing.assert_array_equal(demos.value_mask, [True] * 14 + [False] * 6)


def test_record_teacher_matches_an_independent_replay() -> None:
    env = gym.make(ENV_ID, **ENV_KWARGS)
    gamma, seed = 0.9, 3
    demos = record_teacher(env, WarmStartConfig(teacher="fixed", episodes=2, epochs=1), gamma, seed)
    config = env.get_wrapper_attr("config")
    env.close()
    assert demos.actions.shape == (40, 2) and demos.actions.dtype == np.float32
    assert demos.returns.shape == (40,)
    assert all(v.shape[0] == 40 for v in demos.observations.values())
    fixed = FixedHead.from_config(config).look(0.0, 0.0)
    np.testing.assert_array_equal(demos.actions, np.tile(fixed, (40, 1)))
    # each 20-step episode ends at its time limit: the last 3 / (1 - 0.9) = 30 steps' returns
    # (all of them) miss what follows, and no value target is kept
    assert not demos.value_mask.any()

    replay = gym.make(ENV_ID, **ENV_KWARGS)
    for episode in range(2):
        obs, _ = replay.reset(seed=seed + episode)
        rewards, done, t = [], False, 0
        while not done:
            for key, value in obs.items():
                np.testing.assert_array_equal(demos.observations[key][20 * episode + t], value)
            obs, reward, terminated, truncated, _ = replay.step(fixed)
            rewards.append(float(reward))
            done, t = terminated or truncated, t + 1
        assert t == 20
        expected = sum(gamma**k * r for k, r in enumerate(rewards))
        assert demos.returns[20 * episode] == pytest.approx(expected, rel=1e-5)
        assert demos.returns[20 * episode + 19] == pytest.approx(rewards[-1], rel=1e-5)
    replay.close()
    # the observations change over an episode (not one array stored 20 times)
    assert len(np.unique(demos.observations["time_fraction"][:20])) == 20


@pytest.fixture(scope="module")
def scan_demos() -> tuple[gym.Env, Demonstrations]:
    env = gym.make(ENV_ID, **ENV_KWARGS)
    demos = record_teacher(env, WarmStartConfig(teacher="scan", episodes=2, epochs=1), 0.95, 0)
    return env, demos


def test_imitate_fits_ppo_to_the_scanning_teacher(
    scan_demos: tuple[gym.Env, Demonstrations],
) -> None:
    ppo = pytest.importorskip("stable_baselines3").PPO
    env, demos = scan_demos
    model = ppo(
        "MultiInputPolicy",
        env,
        policy_kwargs={"log_std_init": -2.0},
        n_steps=64,
        batch_size=32,
        seed=0,
        device="cpu",
    )
    before, _ = model.predict(demos.observations, deterministic=True)
    assert np.abs(before - demos.actions).mean() > 0.1  # the untrained policy does not scan
    losses = imitate(model, demos, WarmStartConfig(teacher="scan", episodes=2, epochs=200), 0)
    env.close()
    assert len(losses) == 200 and losses[-1] < losses[0]
    after, _ = model.predict(demos.observations, deterministic=True)
    assert np.abs(after - demos.actions).mean() < 0.1
    assert not model.policy.training  # left in evaluation mode
