"""Study run: head options plus one more, "follow the greedy planner", trained with PPO.

    python benchmarks/head_policy_study/planner_option.py --seed 0 --timesteps 60000

Trains on ``SPL/ActiveVision-v1`` in the geometric mode with the shipped recipe's PPO settings
(``agents/configs/SPL_ActiveVision-v1.json``), then evaluates deterministically on the tuning
seeds 0-5 and prints the mean position error, the return and how often the planner's option
was picked. The planner runs every step (its covariance tracking needs every observation);
its action is used only when picked.
"""

from __future__ import annotations

import argparse
import json
from typing import Any

import gymnasium as gym
import numpy as np
import torch
from gymnasium import spaces
from stable_baselines3 import PPO
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.vec_env import SubprocVecEnv

import spl_env  # noqa: F401  (registers the env ids)
from agents.baselines import GreedyInformation
from agents.head_options import HeadOptions
from agents.train import default_config_path, load_config


class PlannerOptions(HeadOptions):
    """:class:`HeadOptions` whose last option is the greedy planner's head action."""

    def __init__(self, env: gym.Env) -> None:
        super().__init__(env)
        self.planner = GreedyInformation.from_config(env.get_wrapper_attr("config"))
        self.action_space = spaces.Discrete(self.primitives.n_options + 1)

    def reset(self, **kwargs: Any) -> tuple[Any, dict[str, Any]]:
        obs, info = super().reset(**kwargs)
        self.planner.reset()
        return obs, info

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict[str, Any]]:
        if self._obs is None:
            raise RuntimeError("call reset() before step()")
        planned, _ = self.planner.predict(self._obs)
        if int(np.asarray(action).reshape(())) < self.primitives.n_options:
            return super().step(action)
        self.primitives.t_s += self.primitives.control_dt_s  # the scan's clock runs on
        obs, reward, terminated, truncated, info = self.env.step(planned)
        self._obs = obs
        return obs, float(reward), terminated, truncated, info


def make_env(env_kwargs: dict[str, Any]) -> gym.Env:
    return PlannerOptions(gym.make("SPL/ActiveVision-v1", **env_kwargs))


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--timesteps", type=int, default=60_000)
    args = parser.parse_args()
    config = load_config(default_config_path("SPL/ActiveVision-v1"))
    torch.set_num_threads(1)
    venv = make_vec_env(
        lambda: make_env({**config["env_kwargs"], "info_level": "light"}),
        n_envs=config["n_envs"],
        seed=args.seed,
        vec_env_cls=SubprocVecEnv,
    )
    model = PPO(config["policy"], venv, seed=args.seed, device="cpu", **config["ppo"])
    model.learn(args.timesteps)
    venv.close()
    env = make_env(config["env_kwargs"])
    errors, returns, picks = [], [], []
    for seed in range(6):
        obs, info = env.reset(seed=seed)
        done, total, episode_errors = False, 0.0, []
        while not done:
            option, _ = model.predict(obs, deterministic=True)
            picks.append(int(option))
            obs, reward, terminated, truncated, info = env.step(option)
            total += float(reward)
            truth, belief = info["ground_truth"]["robot_pose"], info["perception"]["pose"]
            episode_errors.append(float(np.hypot(*(truth[:2] - belief[:2]))))
            done = terminated or truncated
        errors.append(float(np.mean(episode_errors)))
        returns.append(total)
    planner = env.action_space.n - 1  # type: ignore[attr-defined]
    print(
        json.dumps(
            {
                "seed": args.seed,
                "timesteps": args.timesteps,
                "mean_position_error_m": float(np.mean(errors)),
                "per_episode_position_error_m": [round(e, 4) for e in errors],
                "return": float(np.mean(returns)),
                "planner_share": float(np.mean(np.array(picks) == planner)),
            }
        )
    )


if __name__ == "__main__":
    main()
