"""Train PPO with Ray RLlib on ``SPL/Striker-v0``, on this machine or on a Ray cluster.

    python examples/rllib_striker.py --iterations 20 --env-runners 2
    python examples/rllib_striker.py --iterations 200 --env-runners 63 --address auto

The env is the fast geometric camera mode with its observation flattened
(:func:`agents.rllib.envs.make_striker_env`). Each iteration the env runners sample ``--batch``
env steps in parallel, then the learner (in this process) runs PPO on them. ``--address`` (or
``RAY_ADDRESS``) points at a running cluster (``ray start --head`` on one node, ``ray start
--address=<head>:6379`` on the others; ``auto`` when this node is part of it).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from agents.rllib.envs import STRIKER_ENV
from agents.rllib.training import init_ray, ppo_config, train


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--iterations", type=int, default=20)
    parser.add_argument("--env-runners", type=int, default=1, help="parallel sampling processes")
    parser.add_argument("--address", default=None, help="Ray cluster address (default: local)")
    parser.add_argument("--episode-s", type=float, default=60.0)
    parser.add_argument("--batch", type=int, default=4000, help="env steps per iteration")
    parser.add_argument("--minibatch", type=int, default=500)
    parser.add_argument("--epochs", type=int, default=10)
    parser.add_argument("--lr", type=float, default=3e-4)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=None, help="checkpoint folder")
    args = parser.parse_args(argv)
    init_ray(args.address, args.env_runners)
    config = ppo_config(
        STRIKER_ENV,
        {"episode_s": args.episode_s},
        args.env_runners,
        args.batch,
        args.minibatch,
        args.epochs,
        args.lr,
        args.seed,
    )
    algo = config.build_algo()
    try:
        train(algo, args.iterations, args.out)
    finally:
        algo.stop()


if __name__ == "__main__":
    main()
