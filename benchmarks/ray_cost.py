"""What a batch of ray casts costs on the SPL field, by batch size.

    python benchmarks/ray_cost.py --out benchmarks/results/ray_cost.json

Builds ``SPL/ActiveVision-v0`` (its world: field, goals, poles, boards, five robots), and times
``BulletWorld.ray_test`` (PyBullet's ``rayTestBatch`` and the conversion of its hits to arrays,
as the sonar casts them) on batches of horizontal rays at the sonar's height (0.3 m), each
2.55 m long (the sonar's range) from a random point on the carpet in a random direction, as
the sonar's 93 rays are cast every step. Per batch size: the mean time of ``--repeats`` calls
(µs); and the least-squares line through them, whose slope is the cost of one more ray (µs)
and whose intercept the cost of a call.
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
from spl_env.envs.core import SplEnv
from spl_env.sim.world import BulletWorld

SIZES = (1, 2, 8, 31, 93, 186)
HEIGHT_M = 0.3
LENGTH_M = 2.55


def batch_us(world: BulletWorld, size: int, repeats: int, rng: np.random.Generator) -> float:
    """Mean µs of one ``world.ray_test`` of ``size`` rays (drawn anew for each size)."""
    starts = np.column_stack(
        [rng.uniform(-4.5, 4.5, size), rng.uniform(-3.0, 3.0, size), np.full(size, HEIGHT_M)]
    )
    heading = rng.uniform(-np.pi, np.pi, size)
    ends = starts + LENGTH_M * np.column_stack([np.cos(heading), np.sin(heading), np.zeros(size)])
    t0 = time.perf_counter()
    for _ in range(repeats):
        world.ray_test(starts, ends)
    return 1e6 * (time.perf_counter() - t0) / repeats


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--repeats", type=int, default=2000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=Path("benchmarks/results/ray_cost.json"))
    args = parser.parse_args()
    env = gym.make("SPL/ActiveVision-v0", camera_mode="geometric", frontend="colour")
    core = env.unwrapped
    if not isinstance(core, SplEnv):
        raise TypeError(f"expected an SplEnv, got {type(core).__name__}")
    env.reset(seed=args.seed)
    rng = np.random.default_rng(args.seed)
    means = [batch_us(core.world, size, args.repeats, rng) for size in SIZES]
    env.close()
    slope, intercept = np.polyfit(SIZES, means, 1)
    result = {
        "machine": {
            "cpu_count": os.cpu_count(),
            "load_average_1min": os.getloadavg()[0],
            "python": platform.python_version(),
        },
        "rays": {"height_m": HEIGHT_M, "length_m": LENGTH_M},
        "repeats": args.repeats,
        "batch_us": dict(zip(map(str, SIZES), means, strict=True)),
        "us_per_ray": float(slope),
        "us_per_call": float(intercept),
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=2))
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
