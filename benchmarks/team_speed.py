"""Steps per second of ``spl_env.team_v0`` (every robot perceiving) and where a step's time goes.

    python benchmarks/team_speed.py --steps 400 --out benchmarks/results/team_speed.json

One process, one env, the geometric camera mode (``camera_mode="geometric",
frontend="colour"``, the training mode), random actions from a seeded generator; episodes that
end are reset (not timed). For each setting: whole ``env.step`` calls timed by the wall clock
(``steps_per_second``) and by the process's CPU time (``steps_per_cpu_second``: what a core of
its own would give, where the machine is shared), the parts of a step from ``info["timing"]``
(physics; render = the emulators, sensors, perception summed over the players; "other" is the
rest: commands, observations, rewards, info) and the first and later ``reset()`` wall times.
Settings: 2 v 2 with the full and the light ``info`` (the target: >= 100 steps/s for 2 v 2),
1 v 1 and 3 v 3 with the full ``info``, and 2 v 2 without poles (``spl_env.NO_POLES_KWARGS``:
each robot localises from the field's features).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time
from pathlib import Path
from typing import Any

import numpy as np

from spl_env import NO_POLES_KWARGS, team_v0

PARTS = ("physics", "render", "sensors", "perception")
GEOMETRIC = {"camera_mode": "geometric", "frontend": "colour"}


def measure(steps: int, resets: int, seed: int, overrides: dict[str, Any]) -> dict[str, Any]:
    """Time the first reset, ``steps`` env steps after it, then ``resets`` later resets."""
    env = team_v0.parallel_env(info_timing=True, **GEOMETRIC, **overrides)
    rng = np.random.default_rng(seed)
    t0 = time.perf_counter()
    env.reset(seed=seed)
    first_reset_s = time.perf_counter() - t0
    totals = dict.fromkeys(PARTS, 0.0)
    wall, cpu, episodes = 0.0, 0.0, 0
    for _ in range(steps):
        actions = {a: rng.uniform(-1, 1, size=5).astype(np.float32) for a in env.agents}
        w0, c0 = time.perf_counter(), time.process_time()
        *_, infos = env.step(actions)
        wall += time.perf_counter() - w0
        cpu += time.process_time() - c0
        timing = next(iter(infos.values()))["timing"]
        for part in PARTS:
            totals[part] += timing[part]
        if not env.agents:
            env.reset()
            episodes += 1
    later = []
    for k in range(resets):
        t0 = time.perf_counter()
        env.reset(seed=seed + 1 + k)
        later.append(time.perf_counter() - t0)
    env.close()
    shares = {part: totals[part] / wall for part in PARTS}
    shares["other"] = 1.0 - sum(shares.values())
    return {
        "overrides": overrides,
        "agents": len(env.possible_agents),
        "steps": steps,
        "episodes_ended": episodes,
        "steps_per_second": steps / wall,
        "steps_per_cpu_second": steps / cpu,
        "mean_step_ms": 1000 * wall / steps,
        "share": shares,
        "mean_ms": {part: 1000 * totals[part] / steps for part in PARTS},
        "reset_ms": {"first": 1000 * first_reset_s, "later_mean": 1000 * float(np.mean(later))},
    }


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--steps", type=int, default=400)
    parser.add_argument("--resets", type=int, default=5, help="later resets timed")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=Path("benchmarks/results/team_speed.json"))
    args = parser.parse_args()
    settings: tuple[dict[str, Any], ...] = (
        {"players_per_side": 2},
        {"players_per_side": 2, "info_level": "light"},
        {"players_per_side": 1},
        {"players_per_side": 3},
        {"players_per_side": 2, **NO_POLES_KWARGS},
    )
    runs = [measure(args.steps, args.resets, args.seed, o) for o in settings]
    result = {
        "machine": {
            "cpu_count": os.cpu_count(),
            "load_average_1min": os.getloadavg()[0],
            "python": platform.python_version(),
        },
        "camera": GEOMETRIC,
        "runs": runs,
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=2))
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
