"""Seed 004 §2.3's last experiment: one-minute patrols without poles against the same patrols
with them.

What: ``SPL/ActiveVision-v1`` (poles, CNN, gated EKF SLAM) and ``SPL/ActiveVision-NoPoles-v1``
(no poles; field features detected in the rendered image, the unified sensor model, the pose
filter), rendered camera, the patrol walk among four other robots, the head on the
``scan`` baseline (:class:`agents.baselines.HeadScan`), seeds ``--seed`` .. ``--seed +
--episodes - 1`` (100-104 by default: held out, no parameter was set on them). Per env: the
mean over episodes of each episode's mean position error, the odometry alone's, the pose
NEES (:func:`agents.evaluate.episode_metrics`), and the mean seconds per step of rendering
and of perception (everything from the frame to the pose), and their ratio.

    python benchmarks/no_poles_patrols.py            # ~6 min on one core
    python benchmarks/no_poles_patrols.py --episodes 2
    python benchmarks/no_poles_patrols.py --env SPL/ActiveVision-NoPoles-v1 \
        --set perception.odometry=visual --set perception.field_end=bag_of_words

Writes ``no_poles_patrols.json`` and ``.md`` to ``--out`` (``benchmarks/results``); with
``--set KEY=VALUE`` overrides (``gym.make`` keyword arguments, each env's; the value parsed as
JSON where it parses, else kept as a string) the files are named after them, e.g.
``no_poles_patrols_perception.odometry=visual.json``.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import torch

import spl_env  # noqa: F401  (registers the env ids)
from agents.evaluate import (
    add_overrides_argument,
    episode_metrics,
    load_policy,
    parse_overrides,
    run_episode,
    summarise,
)

ENV_IDS = ("SPL/ActiveVision-v1", "SPL/ActiveVision-NoPoles-v1")
RESULTS = Path("benchmarks/results")


def timed_episode(env: gym.Env, policy: Any, seed: int) -> tuple[dict[str, Any], dict[str, float]]:
    """One episode's metrics and its mean render and perception seconds per step."""
    parts: dict[str, list[float]] = {"render": [], "perception": []}
    step = env.unwrapped.step

    def step_and_time(action: np.ndarray) -> Any:
        result = step(action)
        times = env.unwrapped.step_times
        for part in parts:
            parts[part].append(float(times.get(part, 0.0)))
        return result

    env.unwrapped.step = step_and_time  # type: ignore[method-assign]
    try:
        metrics = episode_metrics(run_episode(env, policy, seed=seed))
    finally:
        del env.unwrapped.step
    return metrics, {part: float(np.mean(values)) for part, values in parts.items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--episodes", type=int, default=5)
    parser.add_argument("--seed", type=int, default=100)
    parser.add_argument("--episode-s", type=float, default=60.0)
    parser.add_argument("--out", type=Path, default=RESULTS)
    parser.add_argument("--env", action="append", choices=ENV_IDS, help="default: both")
    add_overrides_argument(parser)
    args = parser.parse_args()
    overrides = parse_overrides(args.set)
    torch.set_num_threads(1)
    t0 = time.perf_counter()
    rows = []
    for env_id in args.env or ENV_IDS:
        env = gym.make(env_id, episode_s=args.episode_s, **overrides)
        policy = load_policy("scan", env.get_wrapper_attr("config"))
        episodes, timings = [], []
        for k in range(args.episodes):
            metrics, timing = timed_episode(env, policy, args.seed + k)
            episodes.append(metrics)
            timings.append(timing)
            print(env_id, args.seed + k, json.dumps(metrics), json.dumps(timing), flush=True)
        env.close()
        render = float(np.mean([t["render"] for t in timings]))
        perception = float(np.mean([t["perception"] for t in timings]))
        rows.append(
            {
                "env_id": env_id,
                "mean": summarise(episodes),
                "render_ms": 1000 * render,
                "perception_ms": 1000 * perception,
                "perception_over_render": perception / render if render else None,
                "episodes": episodes,
            }
        )
    result = {
        "seeds": [args.seed + k for k in range(args.episodes)],
        "episode_s": args.episode_s,
        "policy": "scan",
        "overrides": overrides,
        "rows": rows,
        "seconds": time.perf_counter() - t0,
    }
    args.out.mkdir(parents=True, exist_ok=True)
    name = "_".join(["no_poles_patrols", *sorted(args.set)])
    (args.out / f"{name}.json").write_text(json.dumps(result, indent=1))
    (args.out / f"{name}.md").write_text(markdown(result))
    print(markdown(result))


def markdown(result: dict[str, Any]) -> str:
    """One row per env."""
    lines = [
        f"# One-minute patrols with and without poles (head scan, seeds {result['seeds']})",
        "",
        *([f"Overrides: {result['overrides']}", ""] if result["overrides"] else []),
        "| env | position error (m) | odometry alone (m) | pose NEES | render ms | "
        "perception ms | perception / render |",
        "|---|---|---|---|---|---|---|",
    ]
    for row in result["rows"]:
        mean = row["mean"]
        lines.append(
            f"| {row['env_id']} | {mean['mean_position_error_m']:.3f} | "
            f"{mean['mean_odometry_error_m']:.3f} | {mean['mean_pose_nees']:.2f} | "
            f"{row['render_ms']:.1f} | {row['perception_ms']:.1f} | "
            f"{row['perception_over_render']:.2f} |"
        )
    lines += ["", f"Run time {result['seconds']:.0f} s."]
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    main()
