"""Scripted baselines against their definitions; PPO runs on the env; the CLIs write their files."""

from __future__ import annotations

import json
import math
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

from agents.baselines import FixedHead, HeadScan, LookAtStalest, head_action
from agents.evaluate import main as evaluate_main
from agents.evaluate import parse_overrides
from agents.train import default_config_path, load_config, train
from spl_env.config import EnvConfig
from spl_env.envs.active_vision import ActiveVisionEnv

CONFIG = EnvConfig()
ROBOT = CONFIG.sim.robot


def _obs(n: int = 6) -> dict[str, np.ndarray]:
    return {
        "landmarks_mask": np.zeros(n, np.float32),
        "landmarks_since_seen": np.ones(n, np.float32),
        "landmarks_cos_bearing": np.zeros(n, np.float32),
        "landmarks_sin_bearing": np.zeros(n, np.float32),
    }


@pytest.mark.parametrize("yaw_deg, pitch_deg", [(0, 0), (30, -10), (-119.5, 29.5), (90, -38.5)])
def test_head_action_inverts_the_envs_action_scaling(yaw_deg: float, pitch_deg: float) -> None:
    env = ActiveVisionEnv(episode_s=1.0)
    target = env._head_target(head_action(ROBOT, math.radians(yaw_deg), math.radians(pitch_deg)))
    env.close()
    np.testing.assert_allclose(np.degrees(target), [yaw_deg, pitch_deg], atol=1e-4)


def test_head_scan_is_the_sinusoid() -> None:
    policy = HeadScan.from_config(CONFIG)
    for k in range(40):
        action, _ = policy.predict(_obs(), episode_start=np.array([k == 0]))
        expected = (
            math.radians(90) * math.sin(2 * math.pi * 0.1 * k / 4.0) / ROBOT.head_yaw_limit_rad
        )
        assert action[0] == pytest.approx(expected, abs=1e-6)
        assert action[1] == pytest.approx(head_action(ROBOT, 0.0, 0.0)[1])
    first, _ = policy.predict(_obs(), episode_start=np.array([True]))  # a new episode restarts it
    assert first[0] == pytest.approx(0.0)


def test_look_at_stalest_points_at_least_recent_pole() -> None:
    obs = _obs()
    obs["landmarks_mask"][[1, 4]] = 1.0
    obs["landmarks_since_seen"][[1, 4]] = [0.2, 0.7]
    bearing = math.radians(30.0)
    obs["landmarks_cos_bearing"][4] = math.cos(bearing)
    obs["landmarks_sin_bearing"][4] = math.sin(bearing)
    action, _ = LookAtStalest.from_config(CONFIG).predict(obs)
    assert action[0] == pytest.approx(30.0 / 119.5, abs=1e-6)
    # a staler pole right behind the robot is out of the head's reach and is skipped
    obs["landmarks_mask"][5] = 1.0
    obs["landmarks_since_seen"][5] = 0.9
    obs["landmarks_cos_bearing"][5] = -1.0
    action, _ = LookAtStalest.from_config(CONFIG).predict(obs)
    assert action[0] == pytest.approx(30.0 / 119.5, abs=1e-6)


def test_fixed_head_and_override_parsing() -> None:
    assert FixedHead.from_config(CONFIG).predict(_obs())[0][0] == 0.0
    with pytest.raises(ValueError, match="key=value"):
        parse_overrides(["episode_s"])
    assert parse_overrides(["episode_s=3", "body_behaviour=square"]) == {
        "episode_s": 3,
        "body_behaviour": "square",
    }


def test_ppo_learn_2048_steps_smoke(tmp_path: Path) -> None:
    config = load_config(default_config_path("SPL/ActiveVision-v0"))
    config["env_kwargs"] = {"episode_s": 20.0}
    config["ppo"] = {**config["ppo"], "n_steps": 1024, "n_epochs": 1}
    path = train("SPL/ActiveVision-v0", config, 2048, tmp_path / "run", seed=0)
    saved = json.loads((tmp_path / "run" / "config.json").read_text())
    assert saved["timesteps"] == 2048
    from stable_baselines3 import PPO

    model = PPO.load(path, device="cpu")
    assert model.num_timesteps == 2048
    env = gym.make("SPL/ActiveVision-v0", episode_s=1.0)
    obs, _ = env.reset(seed=0)
    action, _ = model.predict(obs, deterministic=True)
    assert env.action_space.contains(action)
    env.close()


def test_evaluate_writes_metrics_and_plot(tmp_path: Path) -> None:
    evaluate_main(
        ["--policy", "scan", "--episodes", "1", "--out", str(tmp_path), "--set", "episode_s=3"]
    )
    result = json.loads((tmp_path / "metrics.json").read_text())
    episode = result["episodes"][0]
    assert episode["steps"] == 30
    assert result["mean"]["mean_position_error_m"] == episode["mean_position_error_m"]
    assert (tmp_path / "trajectory.png").stat().st_size > 0
    with pytest.raises(ValueError, match="policy"):
        evaluate_main(["--policy", "nonsense", "--episodes", "1", "--out", str(tmp_path)])
