"""The scripted players of the soccer envs: how often they score (or save), and how well the
ball is tracked meanwhile.

What: ``SPL/PenaltyShootout-v0`` with the centre-kicking and the goalie-aware striker,
``SPL/Striker-v0`` with both, ``SPL/Goalie-v0`` with the scripted goalie
(:mod:`agents.soccer_baselines`), each over ``--episodes`` episodes of the held-out seeds
``--seed`` .. (100 on: no parameter of the players or the ball filter was set on them), in the
``--mode`` camera mode (``rendered``: pixels, the CNN; ``geometric``: the emulated sightings).
Per player: the share of episodes ending in a goal (for the goalie: without one) with its
Wilson 95 % interval, the mean return, and the ball estimate's position error while the true
ball lies within 3 m of our robot (mean, median, 95th percentile; frames in which a ball is
believed: seen, and not lost since), on the field (the believed pose's error included) and
relative to the robot (the egocentric filter's own), with the share of those frames in which a
ball is believed; the believed pose's position and heading error over every frame (mean,
median, 95th percentile); and the env steps per second.

    python benchmarks/soccer_baselines.py --mode geometric --episodes 100
    python benchmarks/soccer_baselines.py --mode rendered --episodes 30

Writes ``<name>_<mode>.json`` (with each episode's outcome, 1 = success, for paired
comparisons) and ``.md`` to ``--out`` (``benchmarks/results``; ``--name`` defaults to
``soccer_baselines``). ``--players`` replaces the scripted table by any players of
``agents.evaluate``'s ``--policy`` (learned strikers included):

    python benchmarks/soccer_baselines.py --mode geometric --envs SPL/Striker-v0 \
        --players centre_kick goalie_aware runs/striker_s0/model.zip runs/striker_s1/model.zip \
        --group learned=runs/striker_s --paired-with centre_kick --name striker_policies

``--envs`` takes the ``-NoPoles-`` ids too (their pole env's players; the robot localises
from the field's lines, with no pole on the field).
``--set KEY=VALUE`` passes env overrides (``agents.evaluate``'s), e.g.
``self_pose=field_features`` to localise from the field's lines instead of the poles.
``--group NAME=PREFIX`` pools the players whose spec starts with PREFIX (one recipe's training
seeds): the success share over all their episodes (Wilson interval) and the t-interval over
the seeds' shares; ``--paired-with PLAYER`` gives each player's success share minus that one's
on the same episodes, with the t-interval of the per-episode differences;
``--paired-with-run PATH`` the same against each (env, player) of an earlier run's JSON on
the same seeds (another setting, e.g. the self pose, on the same episodes)::

    python benchmarks/soccer_baselines.py --envs SPL/Striker-v0 --name striker_slam_poles
    python benchmarks/soccer_baselines.py --envs SPL/Striker-v0 \
        --set self_pose=ekf_slam_field_features --name striker_slam_field \
        --paired-with-run benchmarks/results/striker_slam_poles_geometric.json
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
from scipy import stats

import spl_env  # registers the env ids
from agents.evaluate import add_overrides_argument, load_policy, parse_overrides, played_steps

RESULTS = Path("benchmarks/results")
RUNS = (
    ("SPL/PenaltyShootout-v0", "centre_kick"),
    ("SPL/PenaltyShootout-v0", "goalie_aware"),
    ("SPL/Striker-v0", "centre_kick"),
    ("SPL/Striker-v0", "goalie_aware"),
    ("SPL/Goalie-v0", "goalie"),
)
NEAR_M = 3.0  # the ball error counts while the ball lies this near our robot


def wilson(successes: int, n: int, z: float = 1.96) -> tuple[float, float]:
    """Wilson score interval (95 % at z = 1.96) of a success share."""
    if n == 0:
        return (0.0, 1.0)
    p = successes / n
    centre = (p + z**2 / (2 * n)) / (1 + z**2 / n)
    half = z * math.sqrt(p * (1 - p) / n + z**2 / (4 * n**2)) / (1 + z**2 / n)
    return (centre - half, centre + half)


def env_kwargs(mode: str, overrides: list[str]) -> dict[str, Any]:
    """The env kwargs of camera ``mode`` (``rendered``, the default env; ``geometric``, with the
    colour front end it emulates) and the ``KEY=VALUE`` ``overrides`` (``--set``)."""
    kwargs: dict[str, Any] = parse_overrides(overrides)
    if mode == "geometric":
        kwargs = {"camera_mode": "geometric", "frontend": "colour", **kwargs}
    return kwargs


def run(env_id: str, player: str, args: argparse.Namespace) -> dict[str, Any]:
    """``args.episodes`` episodes of ``player`` in ``env_id``: outcomes and ball errors."""
    env = gym.make(env_id, **env_kwargs(args.mode, args.set))
    policy = load_policy(player, env.get_wrapper_attr("config"))
    outcomes, returns, errors, relative_errors, steps, near_frames = [], [], [], [], 0, 0
    position_errors, heading_errors = [], []
    start = time.perf_counter()
    for seed in range(args.seed, args.seed + args.episodes):
        episode_return = 0.0
        for reward, info in played_steps(env, policy, seed):
            episode_return += reward
            steps += 1
            truth, belief = info["ground_truth"], info["perception"]
            offset = belief["pose"] - truth["robot_pose"]
            position_errors.append(float(np.hypot(offset[0], offset[1])))
            heading_errors.append(abs(math.remainder(float(offset[2]), math.tau)))
            near = np.hypot(*(truth["ball"] - truth["robot_pose"][:2])) < NEAR_M
            near_frames += int(near)
            if belief["ball_known"] and near:
                errors.append(float(np.hypot(*(truth["ball"] - belief["ball"]))))
                x, y, theta = truth["robot_pose"]
                c, s = math.cos(theta), math.sin(theta)
                dx, dy = truth["ball"][0] - x, truth["ball"][1] - y
                relative = np.array([c * dx + s * dy, -s * dx + c * dy])
                relative_errors.append(float(np.hypot(*(relative - belief["ball_relative"]))))
        goal = info["reward_terms"]["goal"]
        keeping = spl_env.pole_env_id(env_id) == "SPL/Goalie-v0"  # a save is no goal
        outcomes.append(int(goal == 0 if keeping else goal > 0))
        returns.append(episode_return)
    seconds = time.perf_counter() - start
    env.close()
    successes = sum(outcomes)
    low, high = wilson(successes, args.episodes)
    return {
        "env": env_id,
        "player": player,
        "episodes": args.episodes,
        "success": successes / args.episodes,
        "success_ci95": [low, high],
        "outcomes": outcomes,
        "mean_return": float(np.mean(returns)),
        "ball_error_m": error_stats(errors),
        "ball_relative_error_m": error_stats(relative_errors),
        "ball_believed_near": len(errors) / max(near_frames, 1),
        "pose_error_m": error_stats(position_errors),
        "heading_error_rad": error_stats(heading_errors),
        "steps_per_s": steps / seconds,
    }


def t_interval(values: list[float]) -> list[float]:
    """Mean's 95 % Student-t interval of ``values`` (at least 2)."""
    x = np.asarray(values, dtype=float)
    half = float(stats.t.ppf(0.975, len(x) - 1) * np.std(x, ddof=1) / np.sqrt(len(x)))
    return [float(np.mean(x)) - half, float(np.mean(x)) + half]


def group_summary(name: str, members: list[dict[str, Any]]) -> dict[str, Any]:
    """A recipe trained with several seeds (``members``, results of :func:`run` on the same
    episodes): the pooled success share with its Wilson interval over all episodes, and the
    t-interval over the members' shares (the training seed's spread)."""
    outcomes = [o for m in members for o in m["outcomes"]]
    shares = [m["success"] for m in members]
    return {
        "group": name,
        "members": [m["player"] for m in members],
        "success": float(np.mean(outcomes)),
        "success_ci95": list(wilson(sum(outcomes), len(outcomes))),
        "seed_shares": shares,
        "seed_shares_ci95": t_interval(shares),
    }


def paired_difference(result: dict[str, Any], reference: dict[str, Any]) -> dict[str, Any]:
    """``result``'s success share minus ``reference``'s on the same episodes, with the 95 %
    t-interval of the per-episode differences (each -1, 0 or 1)."""
    diff = np.subtract(result["outcomes"], reference["outcomes"]).astype(float)
    interval = t_interval(list(diff)) if np.any(diff != diff[0]) else [diff[0], diff[0]]
    return {"minus": reference["player"], "difference": float(diff.mean()), "ci95": interval}


def earlier_run(path: Path, args: argparse.Namespace) -> dict[tuple[str, str], dict[str, Any]]:
    """The results of an earlier run's JSON by (env, player); ValueError unless it played the
    same camera mode, seeds and number of episodes as ``args``."""
    earlier = json.loads(path.read_text())
    if earlier["mode"] != args.mode or earlier["seed"] != args.seed:
        raise ValueError(
            f"--paired-with-run {path} played mode {earlier['mode']!r} from seed "
            f"{earlier['seed']}, this run {args.mode!r} from {args.seed}"
        )
    results = {(r["env"], r["player"]): r for r in earlier["results"]}
    if any(r["episodes"] != args.episodes for r in results.values()):
        raise ValueError(f"--paired-with-run {path} played other than {args.episodes} episodes")
    return results


def error_stats(errors: list[float]) -> dict[str, Any]:
    """Frames, mean, median and 95th percentile (m) of ``errors``."""
    return {
        "frames": len(errors),
        "mean": float(np.mean(errors)) if errors else None,
        "median": float(np.median(errors)) if errors else None,
        "p95": float(np.percentile(errors, 95)) if errors else None,
    }


def markdown(results: list[dict[str, Any]], args: argparse.Namespace) -> str:
    """The results as a markdown table."""
    lines = [
        f"Soccer players, {args.mode} camera, seeds {args.seed}-"
        f"{args.seed + args.episodes - 1}" + (f", {' '.join(args.set)}" if args.set else ""),
        "",
        "| env | player | success (95 % CI) | mean return | ball error near (m): mean / median"
        " / p95 | the same relative to the robot | ball believed while near | pose error (m)"
        " / heading error (°): mean | steps/s |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in results:
        e, q = r["ball_error_m"], r["ball_relative_error_m"]
        pose, heading = r["pose_error_m"]["mean"], math.degrees(r["heading_error_rad"]["mean"])
        lines.append(
            f"| {r['env']} | {r['player']} | {r['success']:.0%} ({r['success_ci95'][0]:.0%}-"
            f"{r['success_ci95'][1]:.0%}) | {r['mean_return']:.2f} | {e['mean']:.3f} / "
            f"{e['median']:.3f} / {e['p95']:.3f} | {q['mean']:.3f} / {q['median']:.3f} / "
            f"{q['p95']:.3f} | {r['ball_believed_near']:.0%} | {pose:.3f} / {heading:.1f} | "
            f"{r['steps_per_s']:.0f} |"
        )
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--mode", choices=("rendered", "geometric"), default="geometric")
    parser.add_argument("--episodes", type=int, default=100)
    parser.add_argument("--seed", type=int, default=100)
    parser.add_argument("--envs", nargs="*", default=None, help="only these env ids")
    parser.add_argument(
        "--players",
        nargs="*",
        default=None,
        help="instead of the scripted table: these players (agents.evaluate's --policy: a "
        "scripted name, pretrained:<name> or a model .zip) in each of --envs",
    )
    parser.add_argument(
        "--group",
        nargs="*",
        default=[],
        metavar="NAME=PREFIX",
        help="pool the players whose spec starts with PREFIX (one recipe, several training "
        "seeds) under NAME",
    )
    parser.add_argument(
        "--paired-with",
        default=None,
        metavar="PLAYER",
        help="also each player's success share minus this one's, paired on the episodes",
    )
    parser.add_argument(
        "--paired-with-run",
        type=Path,
        default=None,
        metavar="PATH",
        help="also each (env, player)'s success share minus the same one's in this earlier "
        "run's JSON (same --seed and --episodes), paired on the episodes",
    )
    add_overrides_argument(parser)
    parser.add_argument("--name", default="soccer_baselines", help="output file stem")
    parser.add_argument("--out", type=Path, default=RESULTS)
    args = parser.parse_args()
    if args.players is not None and not args.envs:
        parser.error("--players needs --envs")
    torch.set_num_threads(1)
    if args.players is None:  # a no-poles id plays its pole env's players
        envs = [e for e, _ in RUNS] if args.envs is None else args.envs
        runs = [
            (env_id, player)
            for env_id in dict.fromkeys(envs)
            for base, player in RUNS
            if base == spl_env.pole_env_id(env_id)
        ]
    else:
        runs = [(env_id, player) for env_id in args.envs for player in args.players]
    for pair in args.group:
        name, sep, prefix = pair.partition("=")
        matched = sum(player.startswith(prefix) for _, player in runs if prefix)
        if not (sep and name and prefix) or matched < 2 * len({e for e, _ in runs}):
            parser.error(f"--group takes NAME=PREFIX matching >= 2 players, got {pair!r}")
    if args.paired_with is not None and args.paired_with not in {p for _, p in runs}:
        parser.error(f"--paired-with {args.paired_with!r} is not one of the players")
    earlier = {} if args.paired_with_run is None else earlier_run(args.paired_with_run, args)
    results = [run(env_id, player, args) for env_id, player in runs]
    groups, paired = [], []
    for env_id in dict.fromkeys(env_id for env_id, _ in runs):
        played = [r for r in results if r["env"] == env_id]
        for pair in args.group:
            name, _, prefix = pair.partition("=")
            members = [r for r in played if r["player"].startswith(prefix)]
            if len(members) >= 2:
                groups.append({"env": env_id, **group_summary(name, members)})
        reference = [r for r in played if r["player"] == args.paired_with]
        paired += [
            {"env": env_id, "player": r["player"], **paired_difference(r, reference[0])}
            for r in played
            if reference and r is not reference[0]
        ]
    paired_runs = [
        {
            "env": r["env"],
            "player": r["player"],
            **paired_difference(r, earlier[(r["env"], r["player"])]),
            "minus": str(args.paired_with_run),
        }
        for r in results
        if (r["env"], r["player"]) in earlier
    ]
    args.out.mkdir(parents=True, exist_ok=True)
    stem = f"{args.name}_{args.mode}"
    (args.out / f"{stem}.json").write_text(
        json.dumps(
            {
                "mode": args.mode,
                "seed": args.seed,
                "set": args.set,
                "results": results,
                "groups": groups,
                "paired": paired,
                "paired_with_run": paired_runs,
            },
            indent=1,
        )
    )
    print(
        json.dumps({"groups": groups, "paired": paired, "paired_with_run": paired_runs}, indent=1)
    )
    (args.out / f"{stem}.md").write_text(markdown(results, args))
    print(markdown(results, args))


if __name__ == "__main__":
    main()
