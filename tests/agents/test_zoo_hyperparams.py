"""The RL Baselines3 Zoo hyperparameters ``agents/configs/zoo/ppo.yml``: an entry per env id whose
env_kwargs build the env, and a short real ``rl_zoo3.train`` run from it."""

from __future__ import annotations

import importlib
import importlib.resources
import re
import subprocess
import sys
from pathlib import Path
from typing import Any

import gymnasium as gym
import pytest

import spl_env
from agents.head_options import HeadOptions

pytest.importorskip("rl_zoo3")
yaml = pytest.importorskip("yaml")

CONF = importlib.resources.files("agents") / "configs" / "zoo" / "ppo.yml"


@pytest.fixture(scope="module")
def hyperparams() -> dict[str, Any]:
    loaded = yaml.safe_load(CONF.read_text())
    assert isinstance(loaded, dict)
    return loaded


def test_every_env_id_has_an_entry(hyperparams: dict[str, Any]) -> None:
    assert set(spl_env.ENV_IDS) <= set(hyperparams)
    assert set(hyperparams) - set(spl_env.ENV_IDS) == {"default_head"}  # the YAML anchor
    for env_id in spl_env.ENV_IDS:
        entry = hyperparams[env_id]
        assert entry["policy"] == "MultiInputPolicy"
        assert entry["n_steps"] % entry["batch_size"] == 0
        assert isinstance(entry["env_kwargs"], dict)


@pytest.mark.parametrize("env_id", spl_env.ENV_IDS)
def test_env_kwargs_build_the_env(hyperparams: dict[str, Any], env_id: str) -> None:
    env_kwargs = hyperparams[env_id]["env_kwargs"]
    env = gym.make(env_id, **env_kwargs)  # unknown config keys raise TypeError
    if "env_wrapper" in hyperparams[env_id]:
        module, _, name = hyperparams[env_id]["env_wrapper"].rpartition(".")
        env = getattr(importlib.import_module(module), name)(env)
    try:
        config = env.get_wrapper_attr("config")
        for key, value in env_kwargs.items():
            if "." in key:
                node = config
                for part in key.split("."):
                    node = getattr(node, part)
                assert node == value, key
        obs, _ = env.reset(seed=0)
        assert env.observation_space.contains(obs)
        env.action_space.seed(0)
        obs, reward, terminated, truncated, _ = env.step(env.action_space.sample())
        assert env.observation_space.contains(obs)
        assert isinstance(float(reward), float)
        # a striker options step runs from one kick to the next: it may end the episode
        if not hyperparams[env_id].get("env_wrapper", "").endswith("StrikerOptions"):
            assert not terminated and not truncated
    finally:
        env.close()


def test_rl_zoo3_trains_and_saves_a_model(tmp_path: Path) -> None:
    command = [
        sys.executable,
        "-m",
        "rl_zoo3.train",
        "--algo",
        "ppo",
        "--env",
        "SPL/LookAround-v0",
        "--gym-packages",
        "spl_env",
        "--conf-file",
        str(CONF),
        "-n",
        "256",
        "--log-folder",
        str(tmp_path),
        "--seed",
        "0",
        "--eval-freq",
        "-1",
        "--hyperparams",
        "n_envs:1",
        "n_steps:128",
        "batch_size:64",
        "n_epochs:1",
        "--vec-env",
        "dummy",
    ]
    done = subprocess.run(command, capture_output=True, text=True, timeout=300, check=False)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    assert re.search(r"total_timesteps\s*\|\s*256\b", done.stdout), done.stdout[-3000:]
    zips = list(tmp_path.glob("**/*.zip"))
    assert len(zips) == 1, zips
    # rl_zoo3 turns the "/" of the id into "-" in its folder and file names
    assert zips[0].name == "SPL-LookAround-v0.zip"
    ppo = pytest.importorskip("stable_baselines3").PPO
    model = ppo.load(zips[0], device="cpu")
    env = HeadOptions(gym.make("SPL/LookAround-v0", camera_mode="geometric", frontend="colour"))
    assert model.action_space == env.action_space  # trained on the options
    obs, _ = env.reset(seed=0)
    action, _ = model.predict(obs, deterministic=True)
    assert env.action_space.contains(action)
    env.close()


@pytest.mark.parametrize(
    "env_id", ["SPL/ActiveVision-v1", "SPL/Striker-v0", "SPL/PenaltyShootout-v0"]
)
def test_zoo_entries_repeat_the_shipped_training_configs(
    hyperparams: dict[str, Any], env_id: str
) -> None:
    """The Zoo trains what ``agents.train`` trained the shipped policies with."""
    from agents.train import OPTIONS, default_config_path, load_config

    entry, config = hyperparams[env_id], load_config(default_config_path(env_id))
    module, _, name = entry["env_wrapper"].rpartition(".")
    assert getattr(importlib.import_module(module), name) is OPTIONS[config["options"]]
    assert entry["n_envs"] == config["n_envs"]
    for key, value in config["ppo"].items():
        if key == "policy_kwargs":
            assert entry[key] == f"dict(net_arch={value['net_arch']})"
        else:
            assert entry[key] == value, key
    assert entry["env_kwargs"] == {**config["env_kwargs"], "info_level": "light"}
