"""Where a rendered step's perception time goes: milliseconds per step of each main part.

What: ``--env`` (``SPL/ActiveVision-NoPoles-v1`` by default) with its defaults (rendered
camera), the head on the ``scan`` baseline, ``--steps`` steps from ``reset(seed=--seed)`` (a
new episode, unseeded, where one ends). Each function of :data:`PARTS` is wrapped with a
timer for the run (the functions themselves are untouched; a wrapper adds about a
microsecond per call); parts nest (a detector's time includes its line finder's), so they do
not add up. Also the env's own ``step_times`` (physics, render, sensors, perception).

    python benchmarks/perception_profile.py                    # ~20 s on one core
    python benchmarks/perception_profile.py --env SPL/ActiveVision-v1 --steps 600

Writes ``perception_profile_<env>.json`` to ``--out`` (``benchmarks/results``). A change's
effect is best read side by side (``benchmarks/side_by_side.py --pin``): this machine's speed
moves by tens of per cent from one run to the next.
"""

from __future__ import annotations

import argparse
import functools
import importlib
import json
import sys
import time
from collections import defaultdict
from collections.abc import Callable
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import torch

import spl_env  # noqa: F401  (registers the env ids)
from agents.evaluate import load_policy

RESULTS = Path("benchmarks/results")

# (module, attribute path) of each timed part
PARTS: tuple[tuple[str, str], ...] = (
    ("perception.pipeline", "PerceptionPipeline.step"),
    ("perception.vision.field_features", "detect_field_features"),
    ("perception.vision.field_features", "_Frame.__init__"),
    ("perception.vision.field_features", "_Frame.segments"),
    ("perception.vision.field_geometry", "image_lines"),
    ("perception.vision.field_features", "line_runs"),
    ("perception.vision.field_features", "curvature"),
    ("perception.vision.field_geometry", "find_circle"),
    ("perception.vision.field_geometry", "merge_segments"),
    ("perception.vision.field_geometry", "find_junctions"),
    ("perception.vision.field_features", "_field_edges"),
    ("perception.vision.field_features", "_marks"),
    ("perception.vision.field_features", "_posts"),
    ("perception.vision.robots", "RobotDetector.detect"),
    ("perception.vision.robots", "RobotDetector._colours"),
    ("perception.vision.robots", "RobotDetector._boundary"),
    ("perception.vision.robots", "RobotDetector._groups"),
    ("perception.vision.robots", "RobotDetector._examine"),
    ("perception.vision.cnn_detector", "CnnPoleDetector.detect_objects"),
    ("perception.field.sensor_model", "observe_pose"),
    ("perception.providers.field", "FieldFeaturePose.update"),
    ("perception.providers.field_end", "NaturalLandmarkFieldEnd.update"),
    ("perception.tracking.sonar_filter", "SonarFilter.update"),
    ("perception.tracking.robot_tracker", "RobotTracker.update"),
)


def install_timers(parts: tuple[tuple[str, str], ...]) -> dict[str, float]:
    """Wrap each part with a timer; return the dict its seconds accumulate in (by name).
    A plain function is rebound wherever a loaded module imported it by name; a part that
    does not exist (another version of the code) is left out with a note on stderr."""
    total: dict[str, float] = defaultdict(float)
    for module_name, path in parts:
        owner: Any = importlib.import_module(module_name)
        *outer, name = path.split(".")
        try:
            for attribute in outer:
                owner = getattr(owner, attribute)
            original = getattr(owner, name)
        except AttributeError:
            print(f"no {module_name}.{path}: not timed", file=sys.stderr)
            continue
        timed = _timed(original, path, total)
        setattr(owner, name, timed)
        if not outer:  # a function: also where it was imported by name
            for module in list(sys.modules.values()):
                if module is not None and getattr(module, name, None) is original:
                    setattr(module, name, timed)
    return total


def _timed(function: Callable[..., Any], name: str, total: dict[str, float]) -> Any:
    @functools.wraps(function)
    def timed(*args: Any, **kwargs: Any) -> Any:
        start = time.perf_counter()
        try:
            return function(*args, **kwargs)
        finally:
            total[name] += time.perf_counter() - start

    return timed


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--env", default="SPL/ActiveVision-NoPoles-v1")
    parser.add_argument("--steps", type=int, default=300)
    parser.add_argument("--seed", type=int, default=100)
    parser.add_argument("--out", type=Path, default=RESULTS)
    args = parser.parse_args()
    torch.set_num_threads(1)
    total = install_timers(PARTS)
    env = gym.make(args.env)
    policy = load_policy("scan", env.get_wrapper_attr("config"))
    obs, _ = env.reset(seed=args.seed)
    total.clear()  # the reset's work is not a step's
    core: Any = env.unwrapped  # the env core, with its step_times
    step_times: dict[str, float] = defaultdict(float)
    for _ in range(args.steps):
        obs, _, terminated, truncated, _ = env.step(policy.predict(obs)[0])
        for part, seconds in core.step_times.items():
            step_times[part] += seconds
        if terminated or truncated:
            obs, _ = env.reset()
    env.close()
    per_step = {k: 1000.0 * v / args.steps for k, v in step_times.items()}
    parts = {k: 1000.0 * v / args.steps for k, v in sorted(total.items(), key=lambda kv: -kv[1])}
    report = {
        "env_id": args.env,
        "steps": args.steps,
        "seed": args.seed,
        "step_ms": per_step,
        "parts_ms": parts,
        "perception_over_render": per_step.get("perception", np.nan)
        / per_step.get("render", np.nan),
    }
    args.out.mkdir(parents=True, exist_ok=True)
    name = "perception_profile_" + args.env.replace("/", "_") + ".json"
    (args.out / name).write_text(json.dumps(report, indent=1))
    print(", ".join(f"{k} {v:.2f} ms" for k, v in per_step.items()))
    for part, ms in parts.items():
        print(f"{ms:8.2f} ms  {part}")


if __name__ == "__main__":
    main()
