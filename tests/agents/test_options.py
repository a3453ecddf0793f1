"""The options wrapper's bookkeeping on a counting env: rewards summed exactly once, choices
asked only where they matter, ends and bad actions handled."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from gymnasium import spaces

from agents.options import OptionPolicy, OptionsWrapper


class CountingEnv(gym.Env):
    """Step t pays reward 2**t (every sum of distinct steps is unique) and ends at ``length``;
    the observation is the step count; it records the actions it got."""

    def __init__(self, length: int) -> None:
        self.length = length
        self.observation_space = spaces.Dict({"t": spaces.Box(0, 100, (1,), np.float32)})
        self.action_space = spaces.Box(-10, 10, (1,), np.float32)
        self.actions: list[float] = []
        self.t = 0

    def reset(self, *, seed: int | None = None, options: Any = None) -> tuple[Any, dict]:
        super().reset(seed=seed)
        self.t, self.actions = 0, []
        return {"t": np.array([0.0], np.float32)}, {"t": 0}

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict]:
        self.actions.append(float(action[0]))
        reward = float(2**self.t)
        self.t += 1
        obs = {"t": np.array([self.t], np.float32)}
        return obs, reward, self.t >= self.length, False, {"t": self.t}


class EveryThird:
    """Three options; a choice only at steps 2, 5, 8, ...; option k acts k, the choice-free
    action is -1; the policy sees ``t`` and ``double_t``."""

    n_options = 3

    def reset(self) -> None:
        pass

    def observation_space(self, space: spaces.Dict) -> spaces.Dict:
        return spaces.Dict({**space.spaces, "double_t": space["t"]})

    def observe(self, obs: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        return {**obs, "double_t": 2 * obs["t"]}

    def needs_choice(self, obs: dict[str, np.ndarray]) -> bool:
        return int(obs["t"][0]) % 3 == 2

    def option_action(self, option: int, obs: dict[str, np.ndarray]) -> np.ndarray:
        choice = self.needs_choice(obs)
        return np.array([option if choice else -1.0], np.float32)


@pytest.mark.parametrize("length", [1, 2, 3, 5, 7, 9])
def test_every_reward_counts_once_and_choices_come_where_needed(length: int) -> None:
    env = CountingEnv(length)
    wrapped = OptionsWrapper(env, EveryThird())
    obs, _ = wrapped.reset(seed=0)
    total, steps, done = 0.0, 0, False
    while not done:
        assert obs["double_t"][0] == 2 * obs["t"][0]
        _, reward, terminated, truncated, _ = wrapped.step(np.int64(1))
        total, steps, done = total + reward, steps + 1, terminated or truncated
    assert total == 2**length - 1  # 1 + 2 + ... + 2**(length - 1): each step exactly once
    choices = len(range(2, length, 3))  # the steps where a choice was asked
    assert steps == max(choices, 1)  # an episode that ends before any choice: one step
    assert env.actions == [1.0 if t % 3 == 2 else -1.0 for t in range(length)]
    with pytest.raises(RuntimeError, match="call reset"):
        wrapped.step(0)


@pytest.mark.parametrize(
    ("action", "error", "match"),
    [
        (2.7, TypeError, "one integer option index"),
        (np.array([1, 2]), TypeError, "one integer option index"),
        (3, ValueError, r"option \(the action\) must be in \[0, 3\), got 3"),
        (-1, ValueError, r"must be in \[0, 3\), got -1"),
    ],
)
def test_bad_actions_are_refused(action: Any, error: type, match: str) -> None:
    wrapped = OptionsWrapper(CountingEnv(9), EveryThird())
    wrapped.reset(seed=0)
    with pytest.raises(error, match=match):
        wrapped.step(action)


class RecordingModel:
    def __init__(self, option: int) -> None:
        self.option = option
        self.seen: list[dict[str, np.ndarray]] = []

    def predict(self, obs: Any, deterministic: bool = True) -> tuple[np.ndarray, None]:
        self.seen.append(obs)
        return np.array(self.option), None


def test_option_policy_asks_the_model_only_at_choices_with_what_it_trained_on() -> None:
    model = RecordingModel(2)
    policy = OptionPolicy(model, EveryThird())
    actions = [float(policy.predict({"t": np.array([t], np.float32)})[0][0]) for t in range(6)]
    assert actions == [-1.0, -1.0, 2.0, -1.0, -1.0, 2.0]
    assert [float(o["double_t"][0]) for o in model.seen] == [4.0, 10.0]
