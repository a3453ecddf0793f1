"""RLlib's sampling throughput (env steps/s) with 1, 2, ... env runners, and the bare env's.

    python benchmarks/rllib_throughput.py --runners 1 2 --steps 1000 --rounds 3
    python benchmarks/rllib_throughput.py --env team --runners 1 2
    python benchmarks/rllib_throughput.py --envs-per-runner 4 --out /tmp/rllib_vector.json

For each runner count a local Ray gets ``runners + 1`` logical CPUs, PPO is built as the examples
build it (:func:`agents.rllib.training.ppo_config`; the env is the fast geometric camera mode,
observations flattened) and every env runner samples ``--steps`` env steps with the policy
(inference, connectors, env steps and resets) at once, ``--rounds`` times after a warm-up round;
the throughput is all runners' steps over the wall time of the round, the per-runner figure
each runner's steps over its own sampling time. The bare env's figure is the same env stepped
with random actions in this process, no Ray. No learning: this is the sampling side only (the
learner's update, in the driver, comes on top in training). The machine's load average goes
into the result, since other jobs share the cores.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np

from agents.rllib import require_ray

require_ray()

import ray  # noqa: E402  (after the check that it is installed)

from agents.rllib.envs import (  # noqa: E402  (needs ray)
    STRIKER_ENV,
    TEAM_ENV,
    make_striker_env,
    make_team_env,
)
from agents.rllib.training import init_ray, ppo_config, with_team_policies  # noqa: E402


def _sample(runner: Any, steps: int) -> tuple[int, float]:
    """(env steps, seconds) of one ``runner.sample`` of ``steps`` env steps (in the runner)."""
    start = time.perf_counter()
    episodes = runner.sample(num_timesteps=steps)
    return sum(len(episode) for episode in episodes), time.perf_counter() - start


def rllib_sampling(
    env: str, env_config: dict[str, Any], runners: int, envs: int, steps: int, rounds: int
) -> dict[str, Any]:
    """Sampling throughput of ``runners`` env runners, each stepping ``envs`` envs (one batched
    policy inference for all of them), on a fresh local Ray."""
    init_ray(None, runners)
    config = ppo_config(env, env_config, runners, 128, 64, 1, 3e-4, 0)
    config = config.env_runners(num_envs_per_env_runner=envs)
    if env == TEAM_ENV:
        config = with_team_policies(config, "team")
    algo = config.build_algo()
    group = algo.env_runner_group
    assert group is not None  # built with the algorithm
    sample = partial(_sample, steps=steps)
    group.foreach_env_runner(sample, local_env_runner=False)  # warm-up: first resets
    rates, per_runner = [], []
    for _ in range(rounds):
        start = time.perf_counter()
        done = group.foreach_env_runner(sample, local_env_runner=False)
        wall = time.perf_counter() - start
        rates.append(sum(n for n, _ in done) / wall)
        per_runner += [n / s for n, s in done]
    algo.stop()
    ray.shutdown()
    return {
        "env_runners": runners,
        "envs_per_runner": envs,
        "steps_per_runner_per_round": steps,
        "rounds": rounds,
        "steps_per_second": float(np.mean(rates)),
        "steps_per_second_rounds": rates,
        "per_runner_steps_per_second": float(np.mean(per_runner)),
    }


def bare_env(env: str, env_config: dict[str, Any], steps: int, seed: int) -> dict[str, Any]:
    """Env steps/s of the same (flattened) env with random actions, in this process."""
    if env == STRIKER_ENV:
        single = make_striker_env(env_config)
        single.action_space.seed(seed)
        single.reset(seed=seed)
        start = time.perf_counter()
        for _ in range(steps):
            *_, terminated, truncated, _ = single.step(single.action_space.sample())
            if terminated or truncated:
                single.reset()
        seconds = time.perf_counter() - start
        single.close()
    else:
        team = make_team_env(env_config)
        team.reset(seed=seed)
        start = time.perf_counter()
        for _ in range(steps):
            actions = {a: team.get_action_space(a).sample() for a in team.agents}
            *_, terminated, truncated, _ = team.step(actions)
            if terminated["__all__"] or truncated["__all__"]:
                team.reset()
        seconds = time.perf_counter() - start
        team.close()
    return {"steps": steps, "steps_per_second": steps / seconds}


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--env", choices=("striker", "team"), default="striker")
    parser.add_argument("--runners", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--envs-per-runner", type=int, default=1)
    parser.add_argument("--steps", type=int, default=1000, help="env steps per runner per round")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--episode-s", type=float, default=60.0)
    parser.add_argument("--out", type=Path, default=None, help="default: results/rllib_*.json")
    args = parser.parse_args()
    env = STRIKER_ENV if args.env == "striker" else TEAM_ENV
    env_config = {"episode_s": args.episode_s}
    name = "rllib_throughput" if args.env == "striker" else "rllib_throughput_team"
    out = args.out or Path(f"benchmarks/results/{name}.json")
    load_before = os.getloadavg()
    bare = bare_env(env, env_config, args.steps, seed=0)
    runs = [
        rllib_sampling(env, env_config, n, args.envs_per_runner, args.steps, args.rounds)
        for n in args.runners
    ]
    result = {
        "machine": {
            "cpu_count": os.cpu_count(),
            "python": platform.python_version(),
            "ray": ray.__version__,
            "load_average_1_5_15_min": {"before": load_before, "after": os.getloadavg()},
        },
        "env": args.env,
        "env_config": env_config,
        "bare_env": bare,
        "runs": runs,
    }
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(result, indent=2))
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
