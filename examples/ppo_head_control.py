"""Train a PPO head-control policy with stable-baselines3, then compare it with the head scan.

    python examples/ppo_head_control.py --timesteps 4096 --episode-s 20

The env is the fast geometric camera mode (poles projected with the colour filter's fitted
noise instead of rendered), so a short run takes minutes on a laptop. The policy sees the
SLAM belief (pose, map, staleness, sonar) and picks head yaw and pitch targets; the reward is
minus the true position error minus half the position std.
"""

from __future__ import annotations

import argparse

import gymnasium as gym
import numpy as np
from stable_baselines3 import PPO

import spl_env  # noqa: F401  (registers the env ids)
from agents.evaluate import episode_metrics, load_policy, run_episode


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--timesteps", type=int, default=4096, help="PPO env steps (>= 1)")
    parser.add_argument("--episode-s", type=float, default=20.0, help="episode length (s)")
    parser.add_argument(
        "--eval-episodes", type=int, default=2, help="episodes per policy in the comparison (>= 1)"
    )
    parser.add_argument("--seed", type=int, default=0, help="PPO's seed")
    args = parser.parse_args(argv)
    for name in ("timesteps", "eval_episodes"):
        if getattr(args, name) < 1:
            parser.error(f"--{name.replace('_', '-')} must be >= 1, got {getattr(args, name)}")
    kwargs = {"camera_mode": "geometric", "frontend": "colour", "episode_s": args.episode_s}
    try:
        env = gym.make("SPL/ActiveVision-v0", **kwargs)
    except ValueError as refused:  # the episode length
        parser.error(str(refused))
    model = PPO("MultiInputPolicy", env, n_steps=512, batch_size=128, seed=args.seed, device="cpu")
    model.learn(total_timesteps=args.timesteps)
    scan = load_policy("scan", env.get_wrapper_attr("config"))
    for name, policy in (("ppo", model), ("head scan", scan)):
        errors = []
        for k in range(args.eval_episodes):
            error = episode_metrics(run_episode(env, policy, seed=1000 + k))[
                "mean_position_error_m"
            ]
            assert error is not None  # only the landmark error can be missing
            errors.append(error)
        print(f"{name:9s} mean SLAM position error {np.mean(errors):.3f} m")
    env.close()


if __name__ == "__main__":
    main()
