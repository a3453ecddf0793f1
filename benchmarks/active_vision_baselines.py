"""SLAM against odometry alone on ``SPL/ActiveVision-v0`` for each scripted head policy.

    python benchmarks/active_vision_baselines.py --episodes 5

Every policy runs the same seeds (one-minute episodes, default config), on the patrol walk and
on seed 000's square walk. Reported per setting: the mean over episodes of each episode's mean
SLAM position error, odometry-only error, pose NEES, landmark error, return and wall-clock time
per step (:func:`agents.evaluate.episode_metrics`).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import gymnasium as gym

import spl_env  # noqa: F401  (registers the env ids)
from agents.baselines import BASELINES
from agents.evaluate import episode_metrics, load_policy, run_episode, summarise


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--episodes", type=int, default=5)
    parser.add_argument("--seed", type=int, default=100)
    parser.add_argument("--episode-s", type=float, default=60.0, help="episode length (s)")
    parser.add_argument(
        "--out", type=Path, default=Path("benchmarks/results/active_vision_baselines.json")
    )
    args = parser.parse_args()
    results = []
    for behaviour in ("patrol", "square"):
        env = gym.make("SPL/ActiveVision-v0", body_behaviour=behaviour, episode_s=args.episode_s)
        for name in BASELINES:
            policy = load_policy(name, env.get_wrapper_attr("config"))
            episodes = [
                episode_metrics(run_episode(env, policy, seed=args.seed + k))
                for k in range(args.episodes)
            ]
            row = {
                "body_behaviour": behaviour,
                "policy": name,
                "mean": summarise(episodes),
                "episodes": episodes,
            }
            results.append(row)
            print(json.dumps({k: row[k] for k in ("body_behaviour", "policy", "mean")}))
        env.close()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(
        json.dumps(
            {
                "episodes": args.episodes,
                "seed": args.seed,
                "episode_s": args.episode_s,
                "results": results,
            },
            indent=2,
        )
    )


if __name__ == "__main__":
    main()
