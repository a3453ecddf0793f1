"""Run the head-scan baseline once with each pole front end and compare the SLAM errors.

    python examples/compare_front_ends.py --episode-s 30 --seed 0

Each front end gets the same seed, so the robot walks the same path under the same lighting;
only the perception differs.
"""

from __future__ import annotations

import argparse

import gymnasium as gym

import spl_env  # noqa: F401  (registers the env ids)
from agents.evaluate import episode_metrics, load_policy, run_episode


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--episode-s", type=float, default=30.0, help="episode length (s)")
    parser.add_argument("--seed", type=int, default=0, help="the episode's reset seed (>= 0)")
    args = parser.parse_args(argv)
    if args.seed < 0:
        parser.error(f"--seed must be >= 0, got {args.seed}")
    for frontend in ("colour", "cnn"):
        try:
            env = gym.make(
                "SPL/ActiveVision-v0",
                episode_s=args.episode_s,
                randomise_lighting=True,
                frontend=frontend,
            )
        except ValueError as refused:  # the episode length
            parser.error(str(refused))
        policy = load_policy("scan", env.get_wrapper_attr("config"))
        metrics = episode_metrics(run_episode(env, policy, seed=args.seed))
        env.close()
        landmark = metrics["mean_landmark_error_m"]
        print(
            f"{frontend:6s} robot {metrics['mean_position_error_m']:.3f} m, "
            f"landmarks {'-' if landmark is None else f'{landmark:.3f} m'}, "
            f"odometry alone {metrics['mean_odometry_error_m']:.3f} m"
        )


if __name__ == "__main__":
    main()
