"""Ray RLlib smoke (the ``ray`` extra): the examples train two tiny iterations without error, and
the team env's per-robot observations flatten. Skipped where ray is not installed."""

from __future__ import annotations

import importlib.util
import re
from collections.abc import Iterator
from pathlib import Path
from types import ModuleType
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from pettingzoo import ParallelEnv

ray = pytest.importorskip("ray")
pytestmark = pytest.mark.rllib

from agents.rllib.envs import FlattenObservations  # noqa: E402  (needs ray)

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
# two iterations of 128 env steps, episodes of 30 steps, one env runner
TINY = ["--iterations", "2", "--batch", "128", "--minibatch", "64", "--epochs", "1"]
TINY += ["--episode-s", "3.0", "--env-runners", "1"]


def load(name: str) -> ModuleType:
    spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module", autouse=True)
def local_ray() -> Iterator[None]:
    """One local Ray for the module: the driver and one env runner (2 logical CPUs)."""
    ray.init(address="local", num_cpus=2, include_dashboard=False, log_to_driver=False)
    yield
    ray.shutdown()


def iteration_lines(out: str) -> list[str]:
    return [line for line in out.splitlines() if line.startswith("iteration ")]


class TwoRobots(ParallelEnv[str, dict[str, np.ndarray], np.ndarray]):
    """A stand-in PettingZoo ParallelEnv: two robots observing a ``Dict`` of two boxes."""

    def __init__(self) -> None:
        self.metadata: dict[str, Any] = {}
        self.possible_agents = ["blue_0", "red_0"]
        self.agents: list[str] = []
        self.space = gym.spaces.Dict(
            {"b": gym.spaces.Box(-1, 1, (2, 2), np.float32), "a": gym.spaces.Box(0, 1, (1,))}
        )

    def observation_space(self, agent: str) -> gym.spaces.Dict:
        return self.space

    def action_space(self, agent: str) -> gym.spaces.Box:
        return gym.spaces.Box(-1, 1, (5,), np.float32)

    def observations(self) -> dict[str, dict[str, np.ndarray]]:
        return {a: {"a": np.ones(1), "b": np.full((2, 2), 0.5)} for a in self.agents}

    def reset(self, seed: int | None = None, options: dict[str, Any] | None = None) -> Any:
        self.agents = list(self.possible_agents)
        return self.observations(), {a: {} for a in self.agents}

    def step(self, actions: dict[str, np.ndarray]) -> Any:
        observations = self.observations()
        self.agents = []
        done = dict.fromkeys(observations, True)
        return observations, dict.fromkeys(observations, 0.0), done, done, {}


def test_flatten_observations() -> None:
    env = FlattenObservations(TwoRobots())
    assert env.observation_space("red_0") == gym.spaces.Box(
        np.array([0, -1, -1, -1, -1], np.float32), np.ones(5, np.float32), (5,), np.float32
    )
    observations, _ = env.reset(seed=0)
    assert env.agents == ["blue_0", "red_0"]
    for obs in observations.values():
        assert obs.dtype == np.float32
        np.testing.assert_array_equal(obs, [1, 0.5, 0.5, 0.5, 0.5])
    observations, *_ = env.step({a: np.zeros(5, np.float32) for a in env.agents})
    assert set(observations) == {"blue_0", "red_0"} and env.agents == []


def test_rllib_striker(capsys: pytest.CaptureFixture[str]) -> None:
    load("rllib_striker").main(TINY)
    lines = iteration_lines(capsys.readouterr().out)
    assert [line.split(":")[0] for line in lines] == ["iteration 1", "iteration 2"]
    assert all("128 env steps" in line for line in lines)


@pytest.mark.parametrize("policies", ["team", "shared"])
def test_rllib_team(policies: str, capsys: pytest.CaptureFixture[str]) -> None:
    pytest.importorskip("spl_env.team_v0")
    load("rllib_team").main([*TINY, "--policies", policies])
    lines = iteration_lines(capsys.readouterr().out)
    assert [line.split(":")[0] for line in lines] == ["iteration 1", "iteration 2"]
    if policies == "team":  # a return per team once an episode has ended
        assert all("blue" in line and "red" in line for line in lines if " 0 episodes" not in line)


@pytest.mark.parametrize(
    ("example", "change", "message"),
    [
        ("rllib_striker", ["--iterations", "0"], "--iterations must be >= 1, got 0"),
        ("rllib_striker", ["--batch", "0"], "--batch must be >= 1, got 0"),
        ("rllib_striker", ["--minibatch", "256"], r"--minibatch must be <= --batch \(128\)"),
        ("rllib_striker", ["--env-runners", "-1"], "--env-runners must be >= 0, got -1"),
        ("rllib_striker", ["--lr", "nan"], "--lr must be finite and > 0, got nan"),
        ("rllib_striker", ["--episode-s", "-1"], "episode_s must be finite and in"),
        ("rllib_team", ["--episode-s", "-1"], "episode_s must be finite and in"),
    ],
)
def test_bad_example_arguments_are_refused_before_ray_trains(
    example: str, change: list[str], message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit) as exit_info:
        load(example).main([*TINY, *change])  # a later flag wins over TINY's
    assert exit_info.value.code == 2
    assert re.search(message, capsys.readouterr().err)
