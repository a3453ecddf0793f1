"""Seed 004 Table 4's experiment: kidnaps after a walk on to the field; does the robot end on the
correct end of the (symmetric) field, and how far off?

What: ``SPL/ActiveVision-NoPoles-v1`` (rendered camera, field features, the pose filter, the
textured posters) with natural landmarks (``perception.field_end="bag_of_words"``, the
walk-on's length ``--walk-on`` s) and visual heading odometry, walking seed 000's square (2 m)
with the head on the ``scan`` baseline among four other robots. After the walk on, every
``--interval`` s the robot is kidnapped: put down at a free pose with any heading, unknown to
perception (:meth:`spl_env.robots.nao.NaoRobot.place`). At the end of each interval: the
position error of the believed pose, and whether it lies on the correct end, nearer the true
pose than its twin through the centre spot (the field's symmetry), and how many of the
recogniser's observations of the end the camera faces were right and wrong (against the true
camera heading) after the walk-on, and likewise of the side board it faces
(``side_observation``). The same episodes beside it with views of the goal areas only
(``perception.natural_landmarks.side_boards=False``), with those filled on the walk-on alone,
as in the seed (``side_boards=False`` and ``learn_in_play=False``; by default views are
stored in play too), and without natural landmarks (``field_end="none"``): the field features
alone relocalise on the truth or its twin. Seeds 0-4 are for tuning; 100 and up are held
out.

Per kidnap the JSON also holds what the walk-on stored (views facing each goal), the views
stored in play so far (``learned``) and the interval's trace: each field-end observation
(time, end, right?, net votes) and each relocalisation or half turn of the pose filter (time,
on the correct end after it?). ``--variant`` runs one localisation only.

Seeds ``--seed`` .. ``--seed + --episodes - 1`` (100-101 by default: held out), ``--kidnaps``
per episode (the seed: 10 kidnaps).

    python benchmarks/kidnaps.py                  # ~20 min on one core
    python benchmarks/kidnaps.py --episodes 1 --kidnaps 3
    python benchmarks/kidnaps.py --seed 0 --set perception.natural_landmarks.walk_on_s=30
    python benchmarks/kidnaps.py --seed 0 --episodes 5 --variant "natural landmarks"

Writes ``kidnaps.json`` and ``.md`` to ``--out`` (``benchmarks/results``).
"""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import torch

import spl_env  # noqa: F401  (registers the env ids)
from agents.evaluate import add_overrides_argument, load_policy, parse_overrides
from perception.landmarks.field_end import AWAY, HOME
from perception.providers.field import FieldFeaturePose
from perception.representations import FIELD_END, SELF_POSE
from spl_env.envs.core import SplEnv

RESULTS = Path("benchmarks/results")
VARIANTS: dict[str, dict[str, Any]] = {  # env overrides of each localisation
    "natural landmarks": {"perception.field_end": "bag_of_words"},
    "goal areas only": {
        "perception.field_end": "bag_of_words",
        "perception.natural_landmarks.side_boards": False,
    },
    "walk-on views only": {  # the seed's
        "perception.field_end": "bag_of_words",
        "perception.natural_landmarks.learn_in_play": False,
        "perception.natural_landmarks.side_boards": False,
    },
    "field features alone": {"perception.field_end": "none"},
}


def episode(variant: dict[str, Any], seed: int, args: argparse.Namespace) -> list[dict[str, Any]]:
    """One episode's kidnaps: per kidnap the position error (m), whether the end is right, and
    the interval's trace (:func:`_trace_step`)."""
    steps_per_s = 10  # control steps of 0.1 s
    total_s = args.walk_on + args.kidnaps * args.interval
    env = gym.make(
        "SPL/ActiveVision-NoPoles-v1",
        episode_s=total_s + 1.0,
        body_behaviour="square",
        square_side_m=2.0,
        **{
            **variant,
            "perception.natural_landmarks.walk_on_s": args.walk_on,
            "perception.odometry": "visual",
            **args.set,
        },
    )
    core = env.unwrapped
    if not isinstance(core, SplEnv):
        raise TypeError(f"kidnaps need an SplEnv, got {type(core).__name__}")
    pose_provider = core.pipeline.provider(SELF_POSE)
    if not isinstance(pose_provider, FieldFeaturePose):
        raise TypeError(f"kidnaps need the field-feature pose, got {type(pose_provider).__name__}")
    policy = load_policy("scan", env.get_wrapper_attr("config"))
    rng = np.random.default_rng([seed, 7])  # the kidnaps' own draws
    obs, info = env.reset(seed=seed)
    results = []
    kidnap_steps = {
        int((args.walk_on + k * args.interval) * steps_per_s) for k in range(args.kidnaps)
    }
    end_steps = {s + int(args.interval * steps_per_s) for s in kidnap_steps}
    seen = {"right": 0, "wrong": 0}  # field-end observations against the true facing
    sides = {"right": 0, "wrong": 0}  # side-board observations likewise
    trace: list[list[Any]] = []  # since the last kidnap (_trace_step)
    counts = (0, 0)  # the pose provider's relocalisations and half turns so far
    database: dict[str, int] = {}
    for step in range(1, int(total_s * steps_per_s) + 1):
        action, _ = policy.predict(obs, deterministic=True)
        obs, _, _, _, info = env.step(action)
        if step == int(args.walk_on * steps_per_s):
            database = _database_labels(core)
        counts = _trace_step(
            core, pose_provider, info, (seen, sides), trace, counts, step / steps_per_s
        )
        if step in end_steps:
            truth = info["ground_truth"]["robot_pose"]
            belief = info["perception"]["pose"]
            error = float(np.hypot(*(belief[:2] - truth[:2])))
            twin = float(np.hypot(*(belief[:2] + truth[:2])))
            results.append(
                {
                    "error_m": error,
                    "twin_error_m": twin,
                    "correct_end": bool(error < twin),
                    "end_observations": dict(seen),  # since the last kidnap
                    "side_observations": dict(sides),
                    "database": database,
                    "learned": getattr(core.pipeline.provider(FIELD_END), "learned", 0),
                    "trace": trace,
                }
            )
            seen = {"right": 0, "wrong": 0}
            sides = {"right": 0, "wrong": 0}
            trace = []
        if step in kidnap_steps:
            others = core.robots[1:]
            core.robots[0].place(core.placement.free_pose(rng, others))
    env.close()
    return results


def _database_labels(core: SplEnv) -> dict[str, int]:
    """How many walk-on images the recogniser stored facing each goal (empty without one)."""
    provider = core.pipeline.provider(FIELD_END)
    recogniser = getattr(provider, "_recogniser", None)
    if recogniser is None:
        return {}
    database = recogniser.database
    return {"away": database.count(AWAY), "home": database.count(HOME)}


def _trace_step(
    core: SplEnv,
    pose_provider: FieldFeaturePose,
    info: dict[str, Any],
    seen: tuple[dict[str, int], dict[str, int]],
    trace: list[list[Any]],
    counts: tuple[int, int],
    time_s: float,
) -> tuple[int, int]:
    """Count this step's field-end and side-board observations in ``seen`` (against the true
    camera heading) and append to ``trace`` ``[time (s), event, right]``: event
    ``"obs+1"``/``"obs-1"`` (an away / home observation; right: it is the end the camera
    faces, with its net votes), ``"side+1"``/``"side-1"`` (the +y / -y board), ``"reloc"`` or
    ``"turn"`` (the pose provider relocalised or turned through the centre spot; right: the
    pose is now on the correct end). Returns the provider's counts."""
    belief = core.perception_output.get(FIELD_END)
    truth = info["ground_truth"]["robot_pose"]
    camera = truth[2] + info["ground_truth"]["head"][0]
    facing = (AWAY if math.cos(camera) > 0 else HOME, 1 if math.sin(camera) > 0 else -1)
    observed = (getattr(belief, "observation", 0), getattr(belief, "side_observation", 0))
    for name, observation, faced, tally in zip(
        ("obs", "side"), observed, facing, seen, strict=True
    ):
        if observation:
            right = observation == faced
            tally["right" if right else "wrong"] += 1
            entry = [round(time_s, 1), f"{name}{observation:+d}", right]
            trace.append(entry + ([getattr(belief, "votes", 0)] if name == "obs" else []))
    now = (pose_provider.relocalisations, pose_provider.half_turns)
    for event, before, after in zip(("reloc", "turn"), counts, now, strict=True):
        if after != before:
            pose = pose_provider.filter.pose
            correct = np.hypot(*(pose[:2] - truth[:2])) < np.hypot(*(pose[:2] + truth[:2]))
            trace.append([round(time_s, 1), event, bool(correct)])
    return now


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--episodes", type=int, default=2)
    parser.add_argument("--seed", type=int, default=100)
    parser.add_argument("--kidnaps", type=int, default=10)
    parser.add_argument("--walk-on", type=float, default=45.0, help="walk-on (s)")
    parser.add_argument("--interval", type=float, default=20.0, help="kidnap to kidnap (s)")
    parser.add_argument("--out", type=Path, default=RESULTS)
    parser.add_argument(
        "--variant",
        choices=list(VARIANTS),
        action="append",
        help="run only these localisation variants (default: all)",
    )
    add_overrides_argument(parser)
    args = parser.parse_args()
    args.set = parse_overrides(args.set)
    torch.set_num_threads(1)
    t0 = time.perf_counter()
    rows: dict[str, Any] = {}
    for name, variant in VARIANTS.items():
        if args.variant and name not in args.variant:
            continue
        kidnaps = []
        for k in range(args.episodes):
            result = episode(variant, args.seed + k, args)
            print(name, args.seed + k, json.dumps(result), flush=True)
            kidnaps += result
        rows[name] = summary(kidnaps, args.kidnaps)
    report = {
        "seeds": [args.seed, args.seed + args.episodes - 1],
        "walk_on_s": args.walk_on,
        "interval_s": args.interval,
        "overrides": args.set,
        "variants": rows,
        "seconds": time.perf_counter() - t0,
    }
    print(write_report(report, args.out))


def summary(kidnaps: list[dict[str, Any]], per_episode: int) -> dict[str, Any]:
    """One variant's row: its ``kidnaps`` (each episode's ``per_episode`` in turn) counted."""
    correct = [r for r in kidnaps if r["correct_end"]]
    none = {"right": 0, "wrong": 0}  # a run from before side-board views were counted
    observations, sides = (
        {v: sum(r.get(key, none)[v] for r in kidnaps) for v in ("right", "wrong")}
        for key in ("end_observations", "side_observations")
    )
    counted_sides = all("side_observations" in r for r in kidnaps)
    return {
        "end_observations": observations,
        "side_observations": sides if counted_sides else None,
        "kidnaps": len(kidnaps),
        "correct_end": len(correct),
        "mean_error_correct_end_m": float(np.mean([r["error_m"] for r in correct]))
        if correct
        else math.nan,
        "median_error_m": float(np.median([r["error_m"] for r in kidnaps])),
        "silent_intervals": sum(
            1
            for r in kidnaps
            if not any(r["end_observations"].values())
            and not any(r.get("side_observations", none).values())
        ),
        "stored": [kidnaps[k]["database"] for k in range(0, len(kidnaps), per_episode)],
        "all": kidnaps,
    }


def write_report(report: dict[str, Any], out: Path) -> str:
    """Write ``report`` to ``out`` as ``kidnaps.json`` and ``kidnaps.md``; the table."""
    out.mkdir(parents=True, exist_ok=True)
    (out / "kidnaps.json").write_text(json.dumps(report, indent=1))
    first, last = report["seeds"]
    lines = [
        f"Kidnaps after a {report['walk_on_s']:.0f} s walk-on, one every "
        f"{report['interval_s']:.0f} s, seeds {first}-{last} (seed 004 Table 4)",
        "",
        "| localisation | correct end | mean error on the correct end (m) | median error (m) "
        "| field-end observations right / wrong | side-board observations right / wrong "
        "| intervals without either | walk-on views of the goal areas (away + home, per "
        "episode) |",
        "|---|---|---|---|---|---|---|---|",
        *(
            f"| {name} | {r['correct_end']} of {r['kidnaps']} | "
            f"{r['mean_error_correct_end_m']:.3f} | {r['median_error_m']:.3f} | "
            f"{r['end_observations']['right']} / {r['end_observations']['wrong']} | "
            + (
                f"{r['side_observations']['right']} / {r['side_observations']['wrong']} | "
                if r.get("side_observations")
                else "not counted | "
            )
            + f"{r['silent_intervals']} | "
            + ", ".join(f"{d['away']}+{d['home']}" if d else "-" for d in r["stored"])
            + " |"
            for name, r in report["variants"].items()
        ),
        "",
        f"Run time {report['seconds']:.0f} s.",
    ]
    (out / "kidnaps.md").write_text("\n".join(lines) + "\n")
    return "\n".join(lines)


if __name__ == "__main__":
    main()
