"""agents.evaluate.played_steps against a hand-written loop on a small Gymnasium env."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np

from agents.evaluate import played_steps


class AlternatingPolicy:
    """Pushes left, right, left, ...; records the ``episode_start`` flags it was given."""

    def __init__(self) -> None:
        self.starts: list[bool] = []

    def predict(
        self, obs: Any, episode_start: np.ndarray | None = None, deterministic: bool = True
    ) -> tuple[int, None]:
        assert episode_start is not None and deterministic
        self.starts.append(bool(episode_start[0]))
        return len(self.starts) % 2, None


def test_played_steps_are_the_episode_step_by_step_until_it_ends() -> None:
    env = gym.make("CartPole-v1")
    policy = AlternatingPolicy()
    played = list(played_steps(env, policy, seed=3))
    env.reset(seed=3)
    expected, k, done = [], 0, False
    while not done:
        k += 1
        _, reward, terminated, truncated, info = env.step(k % 2)
        expected.append((float(reward), info))
        done = terminated or truncated
    assert played == expected and len(played) > 1
    assert policy.starts == [True] + [False] * (len(played) - 1)
