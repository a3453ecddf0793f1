"""Train multi-agent PPO with Ray RLlib on the team env, a policy per team or one shared.

    python examples/rllib_team.py --iterations 20 --policies team --env-runners 2
    python examples/rllib_team.py --iterations 200 --policies shared --env-runners 63 --address auto

The team env (``spl_env.team_v0.parallel_env``, a PettingZoo ``ParallelEnv``: robots ``blue_0``,
``red_0``, ...) runs in the fast geometric camera mode, wrapped by RLlib's
``ParallelPettingZooEnv`` with each robot's observation flattened
(:func:`agents.rllib.envs.make_team_env`). ``--policies team`` trains a ``blue`` and a ``red``
policy, each robot mapped to its team's; ``--policies shared`` trains one policy on every robot.
``--address`` as in ``examples/rllib_striker.py``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from agents.rllib.envs import TEAM_ENV
from agents.rllib.training import init_ray, ppo_config, train, with_team_policies


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--iterations", type=int, default=20)
    parser.add_argument("--policies", choices=("team", "shared"), default="team")
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
        TEAM_ENV,
        {"episode_s": args.episode_s},
        args.env_runners,
        args.batch,
        args.minibatch,
        args.epochs,
        args.lr,
        args.seed,
    )
    algo = with_team_policies(config, args.policies).build_algo()
    try:
        train(algo, args.iterations, args.out)
    finally:
        algo.stop()


if __name__ == "__main__":
    main()
