"""Env steps per second and the share of each step spent in physics, render, sensors, perception.

    python benchmarks/env_speed.py --steps 300 --out benchmarks/results/env_speed.json

Runs ``SPL/ActiveVision-v0`` with random head actions (one process, one env) and times whole
``env.step`` calls; the parts come from ``info["timing"]``, and "other" is the rest (observation,
reward, info, Python overhead).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time
from pathlib import Path

import gymnasium as gym
import numpy as np

import spl_env  # noqa: F401  (registers the env ids)

PARTS = ("physics", "render", "sensors", "perception")


def measure(env_id: str, steps: int, seed: int, overrides: dict[str, object]) -> dict[str, object]:
    """Time ``steps`` env steps after one warm-up episode start."""
    env = gym.make(env_id, **overrides)
    env.action_space.seed(seed)
    t_reset = time.perf_counter()
    env.reset(seed=seed)
    reset_s = time.perf_counter() - t_reset
    totals = dict.fromkeys(PARTS, 0.0)
    step_s = []
    for _ in range(steps):
        t0 = time.perf_counter()
        *_, terminated, truncated, info = env.step(env.action_space.sample())
        step_s.append(time.perf_counter() - t0)
        for part in PARTS:
            totals[part] += info["timing"][part]
        if terminated or truncated:
            env.reset()
    env.close()
    total = float(np.sum(step_s))
    shares = {part: totals[part] / total for part in PARTS}
    shares["other"] = 1.0 - sum(shares.values())
    return {
        "env_id": env_id,
        "overrides": overrides,
        "steps": steps,
        "steps_per_second": steps / total,
        "mean_step_ms": 1000 * total / steps,
        "p95_step_ms": 1000 * float(np.percentile(step_s, 95)),
        "reset_ms": 1000 * reset_s,
        "share": shares,
        "mean_ms": {part: 1000 * totals[part] / steps for part in PARTS},
    }


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--env", default="SPL/ActiveVision-v0")
    parser.add_argument("--steps", type=int, default=300)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=Path("benchmarks/results/env_speed.json"))
    args = parser.parse_args()
    runs = [
        measure(args.env, args.steps, args.seed, {}),
        measure(args.env, args.steps, args.seed, {"randomise_lighting": True}),
        measure(
            args.env, args.steps, args.seed, {"camera_mode": "geometric", "frontend": "colour"}
        ),
    ]
    result = {
        "machine": {"cpu_count": os.cpu_count(), "python": platform.python_version()},
        "runs": runs,
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=2))
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
