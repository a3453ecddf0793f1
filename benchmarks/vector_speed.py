"""Reset time and vector-env throughput of an SPL env id.

    python benchmarks/vector_speed.py --out benchmarks/results/vector_speed.json

- ``reset``: mean wall time of ``env.reset()`` after the first one, in the rendered camera mode
  (the default front end): what each new episode costs.
- ``vector``: steps per second (summed over the envs) of SB3's ``DummyVecEnv`` with one env and
  ``SubprocVecEnv`` with one and two workers, random actions, in the geometric camera mode;
  ``--set key=value`` passes env overrides (e.g. ``--set info_level=light``).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv

import spl_env  # noqa: F401  (registers the env ids)
from agents.evaluate import add_overrides_argument, parse_overrides


def reset_seconds(env_id: str, resets: int, overrides: dict[str, Any]) -> dict[str, float]:
    """First and mean later ``reset()`` wall time (s) of one env."""
    env = gym.make(env_id, **overrides)
    times = []
    for seed in range(resets + 1):
        t0 = time.perf_counter()
        env.reset(seed=seed)
        times.append(time.perf_counter() - t0)
    env.close()
    return {"first_s": times[0], "later_mean_s": float(np.mean(times[1:]))}


def _maker(env_id: str, overrides: dict[str, Any]) -> Any:
    return lambda: gym.make(env_id, **overrides)


WARMUP_STEPS = 20  # vector steps before the timing starts


def vector_steps_per_second(
    env_id: str, kind: str, n_envs: int, steps: int, overrides: dict[str, Any]
) -> float:
    """Env steps per second (all workers together) of a ``kind`` SB3 vector env."""
    makers = [_maker(env_id, overrides) for _ in range(n_envs)]
    vec = DummyVecEnv(makers) if kind == "dummy" else SubprocVecEnv(makers, start_method="fork")
    vec.seed(0)
    vec.reset()
    rng = np.random.default_rng(0)
    actions = rng.uniform(-1.0, 1.0, size=(steps, n_envs, *vec.action_space.shape))
    for a in actions[:WARMUP_STEPS]:
        vec.step(a.astype(np.float32))
    t0 = time.perf_counter()
    for a in actions[WARMUP_STEPS:]:
        vec.step(a.astype(np.float32))
    elapsed = time.perf_counter() - t0
    vec.close()
    return n_envs * (steps - WARMUP_STEPS) / elapsed


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--env", default="SPL/ActiveVision-v0")
    parser.add_argument("--steps", type=int, default=1000, help="vector steps, warm-up included")
    parser.add_argument("--resets", type=int, default=5)
    add_overrides_argument(parser)
    parser.add_argument("--out", type=Path, default=Path("benchmarks/results/vector_speed.json"))
    args = parser.parse_args()
    if args.steps <= WARMUP_STEPS:
        parser.error(f"--steps must exceed the {WARMUP_STEPS} warm-up steps, got {args.steps}")
    if args.resets < 1:
        parser.error(f"--resets must be >= 1, got {args.resets}")
    extra = parse_overrides(args.set)
    geometric = {"camera_mode": "geometric", "frontend": "colour", **extra}
    runs = {
        kind_n: vector_steps_per_second(args.env, kind_n[0], kind_n[1], args.steps, geometric)
        for kind_n in (("dummy", 1), ("subproc", 1), ("subproc", 2))
    }
    vector = {f"{kind}_x{n}_steps_per_second": v for (kind, n), v in runs.items()}
    vector["subproc_x2_over_x1"] = runs[("subproc", 2)] / runs[("subproc", 1)]
    result = {
        "machine": {"cpu_count": os.cpu_count(), "python": platform.python_version()},
        "env_id": args.env,
        "overrides": extra,
        "reset_rendered": reset_seconds(args.env, args.resets, extra),
        "vector_geometric": vector,
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=2))
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
