"""What the RLlib examples share: connecting to Ray, the PPO config, the team policies, the loop.

Ray runs on this machine unless an address is given (``--address`` or ``RAY_ADDRESS``): then the
same script drives a cluster started with ``ray start --head`` (every node needs this package
installed, as the env runners build the envs where they run).
"""

from __future__ import annotations

import argparse
import math
import os
import time
from collections.abc import Hashable
from pathlib import Path
from typing import Any, Literal

import ray
from ray.rllib.algorithms.algorithm import Algorithm
from ray.rllib.algorithms.ppo import PPOConfig
from ray.rllib.core.rl_module.multi_rl_module import MultiRLModuleSpec
from ray.rllib.core.rl_module.rl_module import RLModuleSpec
from ray.rllib.utils.metrics import (
    ENV_RUNNER_RESULTS,
    EPISODE_MODULE_RETURN_MEAN,
    EPISODE_RETURN_MEAN,
    NUM_ENV_STEPS_SAMPLED,
    NUM_EPISODES,
)

from agents.rllib.envs import (
    STRIKER_ENV,
    TEAM_ENV,
    make_striker_env,
    make_team_env,
    register_envs,
)

TEAMS: tuple[str, ...] = ("blue", "red")
SHARED_POLICY = "shared"
PolicyMode = Literal["team", "shared"]


def init_ray(address: str | None, env_runners: int) -> None:
    """Connect to the Ray cluster at ``address`` (or ``RAY_ADDRESS``; ``"auto"``: the one that
    ``ray start`` runs on this machine), else start a new Ray here; then register the envs.

    A local Ray gets at least ``env_runners + 1`` logical CPUs (one per env runner, one for the
    driver and its learner), so that the runners start on a machine with fewer cores, which they
    then share. Ray already up (e.g. in the tests) is used as it is.
    """
    if not ray.is_initialized():
        address = address or os.environ.get("RAY_ADDRESS")
        if address is None:
            cpus = max(os.cpu_count() or 1, env_runners + 1)
            ray.init(address="local", num_cpus=cpus, include_dashboard=False)
        else:
            ray.init(address=address)
    register_envs()


def ppo_config(
    env: str,
    env_config: dict[str, Any],
    env_runners: int,
    batch: int,
    minibatch: int,
    epochs: int,
    lr: float,
    seed: int,
) -> PPOConfig:
    """PPO on the new API stack: ``env_runners`` remote samplers (each one env), the learner in the
    driver process; ``batch`` env steps per training iteration (in the team env each one is a
    step of every robot), SGD on ``minibatch``-step minibatches for ``epochs`` passes at learning
    rate ``lr``. The default model, an MLP (256, 256) with tanh, sees the flattened observation.
    """
    return (
        PPOConfig()
        .environment(env, env_config=env_config)
        .env_runners(num_env_runners=env_runners)
        .learners(num_learners=0)
        .training(
            train_batch_size_per_learner=batch, minibatch_size=minibatch, num_epochs=epochs, lr=lr
        )
        .debugging(seed=seed)
    )


def team_policy(agent_id: Hashable, *args: Any, **kwargs: Any) -> str:
    """Policy mapping for one policy per team: ``"blue_0"`` -> ``"blue"``."""
    return str(agent_id).split("_")[0]


def shared_policy(agent_id: Hashable, *args: Any, **kwargs: Any) -> str:
    """Policy mapping for one policy that every robot of both teams runs."""
    return SHARED_POLICY


def with_team_policies(config: PPOConfig, mode: PolicyMode) -> PPOConfig:
    """``config`` made multi-agent: a policy per team in :data:`TEAMS` (``"team"``: each team
    trains its own, against the other one as it learns) or one :data:`SHARED_POLICY` (the
    ``"shared"`` mode: both teams' experience trains it, self-play)."""
    policies = set(TEAMS) if mode == "team" else {SHARED_POLICY}
    mapping = team_policy if mode == "team" else shared_policy
    specs = {policy: RLModuleSpec() for policy in sorted(policies)}
    return config.multi_agent(policies=policies, policy_mapping_fn=mapping).rl_module(
        rl_module_spec=MultiRLModuleSpec(rl_module_specs=specs)
    )


def summary(iteration: int, result: dict[str, Any], seconds: float) -> str:
    """One line on a training iteration: env steps sampled, episodes finished, the mean episode
    return over the recent episodes (summed over agents in the team env; per policy too where
    there are several) and the wall time."""
    runners = result.get(ENV_RUNNER_RESULTS, {})
    line = (
        f"iteration {iteration}: {int(runners.get(NUM_ENV_STEPS_SAMPLED, 0))} env steps, "
        f"{int(runners.get(NUM_EPISODES, 0))} episodes, "
        f"return {float(runners.get(EPISODE_RETURN_MEAN, math.nan)):.2f}"
    )
    per_module = runners.get(EPISODE_MODULE_RETURN_MEAN, {})
    if len(per_module) > 1:
        line += " (" + ", ".join(f"{m} {float(r):.2f}" for m, r in sorted(per_module.items())) + ")"
    return line + f", {seconds:.1f} s"


def train(algo: Algorithm, iterations: int, out: Path | None) -> list[dict[str, Any]]:
    """Run ``iterations`` training iterations, printing :func:`summary` lines; save a checkpoint
    to ``out`` (``Algorithm.from_checkpoint`` restores it) when given. Returns the results."""
    results = []
    for iteration in range(1, iterations + 1):
        start = time.perf_counter()
        result = algo.train()
        print(summary(iteration, result, time.perf_counter() - start), flush=True)
        results.append(result)
    if out is not None:
        algo.save_to_path(out.resolve())
        print(f"checkpoint: {out}")
    return results


def example_parser(description: str) -> argparse.ArgumentParser:
    """The examples' shared command line: iterations, env runners, the cluster's address, the
    episode length, PPO's batch, minibatch, epochs and learning rate, the seed and a
    checkpoint folder."""
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("--iterations", type=int, default=20, help="training iterations (>= 1)")
    parser.add_argument(
        "--env-runners", type=int, default=1, help="parallel sampling processes (>= 0)"
    )
    parser.add_argument("--address", default=None, help="Ray cluster address (default: local)")
    parser.add_argument("--episode-s", type=float, default=60.0, help="episode length (s)")
    parser.add_argument("--batch", type=int, default=4000, help="env steps per iteration (>= 1)")
    parser.add_argument(
        "--minibatch", type=int, default=500, help="PPO minibatch (env steps, <= --batch)"
    )
    parser.add_argument("--epochs", type=int, default=10, help="PPO epochs per batch (>= 1)")
    parser.add_argument("--lr", type=float, default=3e-4, help="learning rate (> 0)")
    parser.add_argument("--seed", type=int, default=0, help="the envs' and PPO's seed (>= 0)")
    parser.add_argument("--out", type=Path, default=None, help="checkpoint folder")
    return parser


EXAMPLE_ENVS = {STRIKER_ENV: make_striker_env, TEAM_ENV: make_team_env}


def parse_example_args(
    parser: argparse.ArgumentParser, argv: list[str] | None, env: str
) -> argparse.Namespace:
    """The arguments of :func:`example_parser`'s ``parser``, checked before Ray starts:
    ``parser.error`` for a count below its least, a minibatch larger than the batch, a
    learning rate that is not finite and > 0, or an episode length the env ``env`` (one of
    :data:`EXAMPLE_ENVS`, made once here) refuses; otherwise an env runner would only report
    it among hundreds of lines of its own log."""
    args = parser.parse_args(argv)
    for name, least in (("iterations", 1), ("batch", 1), ("minibatch", 1), ("epochs", 1)):
        if getattr(args, name) < least:
            parser.error(f"--{name} must be >= {least}, got {getattr(args, name)}")
    for name in ("env_runners", "seed"):
        if getattr(args, name) < 0:
            parser.error(f"--{name.replace('_', '-')} must be >= 0, got {getattr(args, name)}")
    if args.minibatch > args.batch:
        parser.error(f"--minibatch must be <= --batch ({args.batch}), got {args.minibatch}")
    if not (math.isfinite(args.lr) and args.lr > 0):
        parser.error(f"--lr must be finite and > 0, got {args.lr}")
    try:
        EXAMPLE_ENVS[env]({"episode_s": args.episode_s}).close()
    except ValueError as error:
        parser.error(str(error))
    return args


def example_config(env: str, args: argparse.Namespace) -> PPOConfig:
    """Ray started (:func:`init_ray`) and PPO configured (:func:`ppo_config`) on the registered
    env ``env`` as an example's parsed ``args`` (:func:`example_parser`) say."""
    init_ray(args.address, args.env_runners)
    return ppo_config(
        env,
        {"episode_s": args.episode_s},
        args.env_runners,
        args.batch,
        args.minibatch,
        args.epochs,
        args.lr,
        args.seed,
    )


def run_example(config: PPOConfig, args: argparse.Namespace) -> None:
    """Build the algorithm of ``config``, train ``args.iterations`` iterations (:func:`train`,
    checkpoint to ``args.out``) and stop it."""
    algo = config.build_algo()
    try:
        train(algo, args.iterations, args.out)
    finally:
        algo.stop()
