"""Learned and scripted head policies on held-out seeds, with 95 % confidence intervals.

    python benchmarks/head_policies.py --mode rendered --episodes 20 \
        --policies scan look_at_stalest fixed greedy_information \
                   runs/av_seed0/model.zip runs/av_seed1/model.zip runs/av_seed2/model.zip

Every policy runs the same seeds (``--seed`` .. ``--seed + episodes - 1``; 100-119 by default,
which neither training nor the planner's tuning used) of ``--env`` (one-minute episodes). The
mode is ``rendered`` (the CNN front end on rendered frames, the env's default) or ``geometric``
(the colour filter's fitted emulation, where the policies train). Per policy: the mean over
episodes of each episode's mean position error, pose NEES, robot awareness (share of the robots
within 3 m tracked within 0.3 m) and return, each with a 95 % t-interval over episodes. Models
of one recipe trained with different seeds (folders ``runs/av_seed<k>``) form a group
(``--group NAME=runs/av_seed``: the models whose folder name starts so): its interval is the
t-interval over the S training seeds' means (S - 1 degrees of freedom; the training seed is the
larger source of spread, and all run the same evaluation seeds).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from scipy import stats

import spl_env  # noqa: F401  (registers the env ids)
from agents.evaluate import episode_metrics, load_policy, run_episode

METRICS = ("mean_position_error_m", "mean_pose_nees", "robot_awareness", "return")
MODES: dict[str, dict[str, Any]] = {
    "rendered": {},
    "geometric": {"camera_mode": "geometric", "frontend": "colour"},
}


def interval(values: list[float]) -> dict[str, float | int | None]:
    """Mean and 95 % Student-t interval of ``values`` (None bounds for fewer than 2)."""
    x = np.asarray(values, dtype=float)
    mean = float(np.mean(x))
    if len(x) < 2:
        return {"mean": mean, "low": None, "high": None, "n": len(x)}
    half = float(stats.t.ppf(0.975, len(x) - 1) * np.std(x, ddof=1) / np.sqrt(len(x)))
    return {"mean": mean, "low": mean - half, "high": mean + half, "n": len(x)}


def seed_values(episodes: list[dict[str, Any]], key: str) -> list[float]:
    """The values of ``key`` in the episodes that have it."""
    return [e[key] for e in episodes if e[key] is not None]


def summary(episodes: list[dict[str, Any]]) -> dict[str, Any]:
    """Each metric's interval over the episodes that have it."""
    return {
        key: interval(seed_values(episodes, key)) for key in METRICS if seed_values(episodes, key)
    }


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--env", default="SPL/ActiveVision-v1")
    parser.add_argument("--mode", choices=tuple(MODES), default="rendered")
    parser.add_argument("--episodes", type=int, default=20)
    parser.add_argument("--seed", type=int, default=100)
    parser.add_argument("--policies", nargs="+", required=True)
    parser.add_argument(
        "--group",
        nargs="*",
        default=[],
        metavar="NAME=PREFIX",
        help="pool the policies whose spec starts with PREFIX under NAME",
    )
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    if args.episodes < 1:
        parser.error(f"--episodes must be >= 1, got {args.episodes}")
    env = gym.make(args.env, **MODES[args.mode])
    config = env.get_wrapper_attr("config")
    per_policy: dict[str, list[dict[str, Any]]] = {}
    for spec in args.policies:
        policy = load_policy(spec, config)
        per_policy[spec] = [
            episode_metrics(run_episode(env, policy, seed=args.seed + k))
            for k in range(args.episodes)
        ]
        print(json.dumps({"policy": spec, **summary(per_policy[spec])}), flush=True)
    env.close()
    groups = {}
    for pair in args.group:
        name, sep, folder = pair.partition("=")
        if not (sep and name and folder):
            parser.error(f"--group takes NAME=FOLDER_PREFIX, got {pair!r}")
        members = [s for s in per_policy if Path(s).parent.name.startswith(Path(folder).name)]
        if len(members) < 2:
            parser.error(f"--group {pair!r} matches {len(members)} policies; it needs >= 2")
        groups[name] = {
            "members": members,
            **{
                key: interval([float(np.mean(seed_values(per_policy[s], key))) for s in members])
                for key in METRICS
                if all(seed_values(per_policy[s], key) for s in members)
            },
        }
        print(json.dumps({"group": name, **groups[name]}), flush=True)
    out = args.out or Path(f"benchmarks/results/head_policies_{args.mode}.json")
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(
        json.dumps(
            {
                "env": args.env,
                "mode": args.mode,
                "seeds": [args.seed, args.seed + args.episodes - 1],
                "policies": {s: summary(e) for s, e in per_policy.items()},
                "groups": groups,
                "episodes": per_policy,
            },
            indent=2,
        )
    )


if __name__ == "__main__":
    main()
