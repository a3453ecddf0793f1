"""Env steps per second and the share of each step spent in physics, render, sensors, perception.

    python benchmarks/env_speed.py --steps 300 --out benchmarks/results/env_speed.json

Runs ``SPL/ActiveVision-v0`` with random head actions, one env per setting (rendered, rendered
with randomised lighting, geometric) in one process, and times whole ``env.step`` calls; the
parts come from ``info["timing"]`` (the envs are made with ``info_timing=True``), and "other" is
the rest (observation, reward, info, Python overhead). The settings' envs step in turn, one
step each (the same actions; which goes first rotates), so that the load of other jobs on a
shared CPU falls on all of them alike: ``geometric_over_rendered`` (the geometric setting's
steps per second over the rendered one's) compares like with like. Also the wall time of the
first ``env.reset()`` (the first episode start, e.g. the CNN's first pass) and the mean of
``--resets`` later ones (what each new episode costs).

``--block N`` steps each env N steps in a row before the next takes its turn (default 1: one
step each, as above). Step by step, every geometric step follows a rendered one, which has
filled the CPU's caches with the frame's buffers, so the geometric env is measured slower than
it runs on its own, as in training. Blocks of 50 steps keep that out while the load of other
jobs still falls on every setting alike (which setting goes first rotates per block).

    python benchmarks/env_speed.py --block 50 --out benchmarks/results/env_speed_blocks.json
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

import spl_env  # noqa: F401  (registers the env ids)

PARTS = ("physics", "render", "sensors", "perception")


def _timed_reset(env: gym.Env, seed: int) -> float:
    """Seconds of one ``env.reset(seed=seed)``."""
    t0 = time.perf_counter()
    env.reset(seed=seed)
    return time.perf_counter() - t0


def measure(
    env_id: str,
    steps: int,
    resets: int,
    seed: int,
    settings: tuple[dict[str, Any], ...],
    block: int = 1,
) -> list[dict[str, Any]]:
    """Time the first reset of each setting's env, ``steps`` env steps after it (the settings
    in turn, ``block`` steps each), then ``resets`` later resets of each."""
    envs = [gym.make(env_id, info_timing=True, **o) for o in settings]
    actions = envs[0].action_space
    actions.seed(seed)
    first_reset_s = [_timed_reset(env, seed) for env in envs]
    totals = [dict.fromkeys(PARTS, 0.0) for _ in envs]
    step_s: list[list[float]] = [[] for _ in envs]
    for k0 in range(0, steps, block):
        block_actions = [actions.sample() for _ in range(min(block, steps - k0))]
        for i in np.roll(np.arange(len(envs)), k0 // block):
            for action in block_actions:
                t0 = time.perf_counter()
                *_, terminated, truncated, info = envs[i].step(action)
                step_s[i].append(time.perf_counter() - t0)
                for part in PARTS:
                    totals[i][part] += info["timing"][part]
                if terminated or truncated:
                    envs[i].reset()
    later_reset_s = [[_timed_reset(env, seed + 1 + k) for k in range(resets)] for env in envs]
    for env in envs:
        env.close()
    return [
        _summary(env_id, o, step_s[i], totals[i], first_reset_s[i], later_reset_s[i])
        for i, o in enumerate(settings)
    ]


def _summary(
    env_id: str,
    overrides: dict[str, Any],
    step_s: list[float],
    totals: dict[str, float],
    first_reset_s: float,
    later_reset_s: list[float],
) -> dict[str, Any]:
    """One setting's steps per second, step times (ms), reset times (ms) and parts' shares."""
    steps = len(step_s)
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
        "reset_ms": {
            "first": 1000 * first_reset_s,
            "later_mean": 1000 * float(np.mean(later_reset_s)) if later_reset_s else None,
            "later_resets": len(later_reset_s),
        },
        "share": shares,
        "mean_ms": {part: 1000 * totals[part] / steps for part in PARTS},
    }


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--env", default="SPL/ActiveVision-v0")
    parser.add_argument("--steps", type=int, default=300)
    parser.add_argument("--resets", type=int, default=5, help="later resets timed")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--block", type=int, default=1, help="steps per env per turn")
    parser.add_argument("--out", type=Path, default=Path("benchmarks/results/env_speed.json"))
    args = parser.parse_args()
    settings: tuple[dict[str, Any], ...] = (
        {},
        {"randomise_lighting": True},
        {"camera_mode": "geometric", "frontend": "colour"},
    )
    if args.block < 1:
        parser.error(f"--block must be at least 1, got {args.block}")
    runs = measure(args.env, args.steps, args.resets, args.seed, settings, args.block)
    result = {
        "machine": {"cpu_count": os.cpu_count(), "python": platform.python_version()},
        "block": args.block,
        "runs": runs,
        "geometric_over_rendered": runs[2]["steps_per_second"] / runs[0]["steps_per_second"],
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=2))
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
