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

from agents.rllib import require_ray

require_ray()

from agents.rllib.envs import TEAM_ENV  # noqa: E402  (needs ray)
from agents.rllib.training import (  # noqa: E402  (needs ray)
    example_config,
    example_parser,
    parse_example_args,
    run_example,
    with_team_policies,
)


def main(argv: list[str] | None = None) -> None:
    parser = example_parser(__doc__.split("\n")[0])
    parser.add_argument(
        "--policies",
        choices=("team", "shared"),
        default="team",
        help="one policy per team, or one shared by both (red's view is mirrored)",
    )
    args = parse_example_args(parser, argv, TEAM_ENV)
    run_example(with_team_policies(example_config(TEAM_ENV, args), args.policies), args)


if __name__ == "__main__":
    main()
