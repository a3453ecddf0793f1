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

from agents.rllib import require_ray

require_ray()

from agents.rllib.envs import STRIKER_ENV  # noqa: E402  (needs ray)
from agents.rllib.training import (  # noqa: E402  (needs ray)
    example_config,
    example_parser,
    parse_example_args,
    run_example,
)


def main(argv: list[str] | None = None) -> None:
    parser = example_parser(__doc__.split("\n")[0])
    args = parse_example_args(parser, argv, STRIKER_ENV)
    run_example(example_config(STRIKER_ENV, args), args)


if __name__ == "__main__":
    main()
