"""What a penalty striker could gain by choosing where to kick: every episode played once per aim.

Each episode of ``SPL/PenaltyShootout-v0`` (seeds ``--seed`` ..) is played once for each aim of
:data:`AIMS_M` (points on the goal line, by their y), at full strength, by the striker options of
:mod:`agents.striker_options` (the centre-kicking striker's approach; at the kick chance the
kick towards the aim). The approach does not depend on the aim, and the kick's noise is the
same draw in every replay of an episode, so the replays differ only by the aim: one row per
episode tells which aims would have scored. From the table:

- per aim, the share of episodes scored (Wilson 95 % interval);
- ``any aim``: the share of episodes where some aim scores (what a striker that knew the
  episode's errors could reach);
- rules that pick an aim from what the striker could know, applied to the same rows (the
  table's aim nearest to what the rule wants): the centre; the middle of the wider gap beside
  the goalie (:class:`agents.soccer_baselines.GoalieAwareStriker`'s rule) on the believed
  goalie (``kick_geometry``), and on the true one;
- lookup tables from the believed goalie's offset to the aim, fitted on the rows themselves
  (in sample, an upper bound; and left-one-out): what a learned chooser seeing that offset
  could reach at best, over all aims and over the striker options' three;
- where the centre kick's ball crosses the goal line (m off the aim) split into what the
  believed pose and ball at the kick explain (the kick angle computed on them and applied from
  the true pose: heading part, the believed ball's part) and the rest (the kick's own noise).

    python -m benchmarks.penalty_aims --seed 0 --episodes 100             # tuning seeds
    python -m benchmarks.penalty_aims --set self_pose=oracle --name penalty_aims_oracle_pose
    python -m benchmarks.penalty_aims --set self_pose=field_features \
        --name penalty_aims_field_features

Writes ``<name>_<mode>.json`` (with every row) and ``.md`` to ``--out``
(``benchmarks/results``); ``--rows`` summarises an earlier JSON's rows again without playing.
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import torch

import spl_env  # noqa: F401  (registers the env ids)
from agents.evaluate import add_overrides_argument
from agents.options import OptionsWrapper
from agents.soccer_baselines import GoalieAwareStriker, wider_gap_middle
from agents.striker_options import KICK_GEOMETRY, StrikerOptionsConfig, StrikerPrimitives
from benchmarks.soccer_baselines import RESULTS, env_kwargs, wilson
from perception.geometry import wrap_angle

ENV_ID = "SPL/PenaltyShootout-v0"
AIMS_M = (-0.6, -0.45, -0.3, -0.15, 0.0, 0.15, 0.3, 0.45, 0.6)
LINE_SLACK_M = 0.05  # a ball this near the goal line at the end reached it (not saved short)
LOOKUP_BINS = (2, 4, 8)  # bins of the believed goalie offset for the fitted lookups


def play_row(wrapped: OptionsWrapper, seed: int, n_aims: int) -> dict[str, Any]:
    """One episode (``seed``) replayed with each aim: outcomes and where the ball ended (2,);
    at the first kick chance the true and believed pose (3,), ball (2,), the true goalie (2,)
    and ``kick_geometry``."""
    row: dict[str, Any] = {"seed": seed, "scored": [], "final_ball": []}
    for aim in range(n_aims):
        obs, info = wrapped.reset(seed=seed)
        if aim == 0:
            truth, belief = info["ground_truth"], info["perception"]
            row.update(
                pose_true=truth["robot_pose"].tolist(),
                pose_belief=belief["pose"].tolist(),
                ball_true=truth["ball"].tolist(),
                ball_belief=belief["ball"].tolist(),
                goalie_true=truth["robots"][0][:2].tolist(),
                kick_geometry=obs[KICK_GEOMETRY].tolist(),
            )
        done, goals = False, 0.0
        while not done:
            obs, _, terminated, truncated, info = wrapped.step(aim)
            done, goals = terminated or truncated, goals + info["reward_terms"]["goal"]
        row["scored"].append(int(goals > 0))
        row["final_ball"].append(info["ground_truth"]["ball"].tolist())
    return row


def nearest_aim(y: float) -> int:
    """The index of the aim of :data:`AIMS_M` nearest to ``y`` (m)."""
    return int(np.argmin(np.abs(np.asarray(AIMS_M) - y)))


def gap_aim(goalie_y: float | None, post_m: float) -> float:
    """The goalie-aware striker's aim (m on the goal line) for a goalie at ``goalie_y`` (None:
    none tracked: the centre), inner posts at ``±post_m`` less a ball."""
    if goalie_y is None:
        return 0.0
    return wider_gap_middle(goalie_y, post_m, GoalieAwareStriker.goalie_half_width_m)


def rule_share(rows: list[dict[str, Any]], picks: list[int]) -> dict[str, Any]:
    """The share of ``rows`` scored when row k is played with aim ``picks[k]``."""
    scored = sum(row["scored"][pick] for row, pick in zip(rows, picks, strict=True))
    return {"success": scored / len(rows), "success_ci95": list(wilson(scored, len(rows)))}


def landing_split(rows: list[dict[str, Any]], goal_x: float) -> dict[str, float]:
    """For the centre kick, over the episodes whose ball reached the goal line (scored or
    wide, not saved short of it): the std (m) of where the believed pose and ball send the ball
    across the line (heading part: the believed heading's error; ball part: the believed
    ball's), of where it crossed, and of the rest (the kick's noise)."""
    centre = nearest_aim(0.0)
    reached = [row for row in rows if row["final_ball"][centre][0] >= goal_x - LINE_SLACK_M]
    heading, ball_part, explained, crossed = [], [], [], []
    for row in reached:
        pose, believed = np.array(row["pose_true"]), np.array(row["pose_belief"])
        ball, ball_b = np.array(row["ball_true"]), np.array(row["ball_belief"])
        distance = goal_x - ball[0]
        to_goal_b = math.atan2(-ball_b[1], goal_x - ball_b[0])
        to_goal = math.atan2(-ball[1], distance)
        direction = pose[2] + float(wrap_angle(to_goal_b - believed[2]))
        heading.append(float(wrap_angle(pose[2] - believed[2])) * distance)
        ball_part.append(float(wrap_angle(to_goal_b - to_goal)) * distance)
        explained.append(ball[1] + math.tan(direction) * distance)
        crossed.append(row["final_ball"][centre][1])
    return {
        "episodes": len(reached),
        "heading_part_std_m": float(np.std(heading)),
        "ball_part_std_m": float(np.std(ball_part)),
        "explained_std_m": float(np.std(explained)),
        "crossing_std_m": float(np.std(crossed)),
        "rest_std_m": float(np.std(np.subtract(crossed, explained))),
    }


def lookup_share(
    table: np.ndarray, offsets: np.ndarray, aims: list[int], bins: int, leave_one_out: bool
) -> float:
    """The share scored by a lookup table fitted on the rows themselves: ``offsets`` (E,) (the
    believed goalie's, m) cut into ``bins`` quantile bins, each bin's aim the one of ``aims``
    (indices into ``table`` (E, A) of outcomes) that scored most in it; ``leave_one_out``
    fits each row's bin without that row."""
    edges = np.quantile(offsets, np.linspace(0.0, 1.0, bins + 1)[1:-1])
    binned = np.digitize(offsets, edges)
    scored = 0
    for k in range(len(table)):
        same = binned == binned[k]
        if leave_one_out:
            same[k] = False
        best = aims[int(np.argmax(table[same][:, aims].sum(axis=0)))]
        scored += int(table[k, best])
    return scored / len(table)


def fitted_lookups(table: np.ndarray, believed: list[float | None]) -> dict[str, Any]:
    """What a chooser that sees the believed goalie's offset could reach at best: lookup
    tables (:func:`lookup_share`) over all aims and over the striker options' aims
    (:class:`agents.striker_options.StrikerOptionsConfig`), fitted on these rows (in
    sample: an upper bound) and left-one-out; an untracked goalie counts as offset 0."""
    offsets = np.array([0.0 if g is None else g for g in believed])
    every = list(range(table.shape[1]))
    options = [nearest_aim(aim) for aim in StrikerOptionsConfig().aims_m]
    return {
        "all_aims_in_sample": {
            b: lookup_share(table, offsets, every, b, False) for b in LOOKUP_BINS
        },
        "all_aims_leave_one_out": {
            b: lookup_share(table, offsets, every, b, True) for b in LOOKUP_BINS
        },
        "options_aims_in_sample": {
            b: lookup_share(table, offsets, options, b, False) for b in LOOKUP_BINS
        },
    }


def summarise(rows: list[dict[str, Any]], env: gym.Env) -> dict[str, Any]:
    """Per-aim shares, the any-aim share, the rules' shares and the centre kick's landing split
    (module doc)."""
    dims = env.get_wrapper_attr("config").scene.dimensions
    post = dims.goal_inner_width_m / 2 - dims.ball_diameter_m
    table = np.array([row["scored"] for row in rows])
    believed = [None if row["kick_geometry"][2] < 0.5 else row["kick_geometry"][4] for row in rows]
    true_goalie = [row["goalie_true"][1] for row in rows]
    rules = {
        "centre": [nearest_aim(0.0)] * len(rows),
        "gap_believed_goalie": [nearest_aim(gap_aim(g, post)) for g in believed],
        "gap_true_goalie": [nearest_aim(gap_aim(g, post)) for g in true_goalie],
    }
    any_aim = int(table.max(axis=1).sum())
    believed_error = [b - t for b, t in zip(believed, true_goalie, strict=True) if b is not None]
    return {
        "per_aim": [
            {
                "aim_m": aim,
                "success": float(table[:, k].mean()),
                "success_ci95": list(wilson(int(table[:, k].sum()), len(rows))),
            }
            for k, aim in enumerate(AIMS_M)
        ],
        "any_aim": {
            "success": any_aim / len(rows),
            "success_ci95": list(wilson(any_aim, len(rows))),
        },
        "rules": {name: rule_share(rows, picks) for name, picks in rules.items()},
        "goalie_tracked_share": float(np.mean([g is not None for g in believed])),
        "believed_goalie_y_error_std_m": float(np.std(believed_error)),
        "centre_kick_landing": landing_split(rows, dims.half_length_m),
        "lookups": fitted_lookups(table, believed),
    }


def markdown(summary: dict[str, Any], args: argparse.Namespace) -> str:
    """The summary as markdown tables."""
    last = args.seed + args.episodes - 1
    lines = [
        f"# Penalty aims, {args.mode} camera, seeds {args.seed}-{last}"
        + (f", {' '.join(args.set)}" if args.set else ""),
        "",
        "Every episode replayed with each aim (full strength, the same approach and kick noise).",
        "",
        "| aim (m) | " + " | ".join(f"{a:+.2f}" for a in AIMS_M) + " |",
        "|---|" + "---|" * len(AIMS_M),
        "| scored | " + " | ".join(f"{r['success']:.0%}" for r in summary["per_aim"]) + " |",
        "",
        "| who picks the aim | scored (95 % CI) |",
        "|---|---|",
    ]
    picks = {
        "centre": "always the centre",
        "gap_believed_goalie": "the wider gap beside the believed goalie",
        "gap_true_goalie": "the wider gap beside the true goalie",
    }
    for name, label in picks.items():
        r = summary["rules"][name]
        lo, hi = r["success_ci95"]
        lines.append(f"| {label} | {r['success']:.0%} ({lo:.0%}-{hi:.0%}) |")
    a = summary["any_aim"]
    lines.append(
        f"| some aim scores (knowing the episode's errors) | {a['success']:.0%} "
        f"({a['success_ci95'][0]:.0%}-{a['success_ci95'][1]:.0%}) |"
    )
    split, lookups = summary["centre_kick_landing"], summary["lookups"]

    def shares(values: dict[Any, float]) -> str:
        return " / ".join(f"{v:.0%}" for v in values.values())

    bins = " / ".join(str(b) for b in LOOKUP_BINS)
    lines += [
        "",
        f"Lookup tables on the believed goalie's offset ({bins} bins), fitted on these episodes: "
        f"best of all aims {shares(lookups['all_aims_in_sample'])} in sample, "
        f"{shares(lookups['all_aims_leave_one_out'])} left-one-out; best of the striker "
        f"options' aims {shares(lookups['options_aims_in_sample'])} in sample.",
    ]
    lines += [
        "",
        f"Goalie tracked at the kick chance: {summary['goalie_tracked_share']:.0%}; believed "
        f"goalie y error std {summary['believed_goalie_y_error_std_m']:.2f} m.",
        "",
        f"Centre kick, where the ball crosses the goal line ({split['episodes']} episodes "
        "reaching it; std over them, m): "
        f"crossing {split['crossing_std_m']:.2f}; explained by the believed pose and ball "
        f"{split['explained_std_m']:.2f} (heading part {split['heading_part_std_m']:.2f}, "
        f"ball part {split['ball_part_std_m']:.2f}); rest (the kick's noise) "
        f"{split['rest_std_m']:.2f}.",
    ]
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--mode", choices=("rendered", "geometric"), default="geometric")
    parser.add_argument("--episodes", type=int, default=100)
    parser.add_argument("--seed", type=int, default=0)
    add_overrides_argument(parser)
    parser.add_argument(
        "--rows",
        type=Path,
        default=None,
        help="summarise the rows of this earlier JSON again instead of playing (its seeds, "
        "mode and --set)",
    )
    parser.add_argument("--name", default="penalty_aims", help="output file stem")
    parser.add_argument("--out", type=Path, default=RESULTS)
    args = parser.parse_args()
    torch.set_num_threads(1)
    saved = json.loads(args.rows.read_text()) if args.rows is not None else None
    if saved is not None:
        args.mode, args.seed, args.set = saved["mode"], saved["seed"], saved["set"]
        args.episodes = len(saved["rows"])
    env = gym.make(ENV_ID, **env_kwargs(args.mode, args.set))
    if saved is not None:
        rows = saved["rows"]
    else:
        options = StrikerOptionsConfig(aims_m=AIMS_M, strengths=(1.0,))
        wrapped = OptionsWrapper(env, StrikerPrimitives(env.get_wrapper_attr("config"), options))
        rows = []
        for seed in range(args.seed, args.seed + args.episodes):
            rows.append(play_row(wrapped, seed, len(AIMS_M)))
            print(seed, rows[-1]["scored"], flush=True)
    summary = summarise(rows, env)
    env.close()
    args.out.mkdir(parents=True, exist_ok=True)
    stem = f"{args.name}_{args.mode}"
    result = {"mode": args.mode, "seed": args.seed, "set": args.set, "aims_m": AIMS_M}
    (args.out / f"{stem}.json").write_text(
        json.dumps({**result, **summary, "rows": rows}, indent=1)
    )
    (args.out / f"{stem}.md").write_text(markdown(summary, args))
    print(markdown(summary, args))


if __name__ == "__main__":
    main()
