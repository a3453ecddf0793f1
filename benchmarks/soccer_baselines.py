"""The scripted players of the soccer envs: how often they score (or save), and how well the
ball is tracked meanwhile.

What: ``SPL/PenaltyShootout-v0`` with the centre-kicking and the goalie-aware striker,
``SPL/Striker-v0`` with both, ``SPL/Goalie-v0`` with the scripted goalie
(:mod:`agents.soccer_baselines`), each over ``--episodes`` episodes of the held-out seeds
``--seed`` .. (100 on: no parameter of the players or the ball filter was set on them), in the
``--mode`` camera mode (``rendered``: pixels, the CNN; ``geometric``: the emulated sightings).
Per player: the share of episodes ending in a goal (for the goalie: without one) with its
Wilson 95 % interval, the mean return, and the ball estimate's position error while the true
ball lies within 3 m of our robot (mean, median, 95th percentile; frames after the ball was
first seen), on the field (the believed pose's error included) and relative to the robot (the
egocentric filter's own); and the env steps per second.

    python benchmarks/soccer_baselines.py --mode geometric --episodes 100
    python benchmarks/soccer_baselines.py --mode rendered --episodes 30

Writes ``soccer_baselines_<mode>.json`` and ``.md`` to ``--out`` (``benchmarks/results``).
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
from agents.soccer_baselines import SOCCER_BASELINES

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


def run(env_id: str, player: str, args: argparse.Namespace) -> dict[str, Any]:
    """``args.episodes`` episodes of ``player`` in ``env_id``: outcomes and ball errors."""
    kwargs: dict[str, Any] = {}
    if args.mode == "geometric":
        kwargs = {"camera_mode": "geometric", "frontend": "colour"}
    env = gym.make(env_id, **kwargs)
    policy = SOCCER_BASELINES[player].from_config(env.unwrapped.config)  # type: ignore[attr-defined]
    successes, returns, errors, relative_errors, steps = 0, [], [], [], 0
    start = time.perf_counter()
    for seed in range(args.seed, args.seed + args.episodes):
        obs, info = env.reset(seed=seed)
        policy.reset()
        done, episode_return = False, 0.0
        while not done:
            action, _ = policy.predict(obs)
            obs, reward, terminated, truncated, info = env.step(action)
            done, episode_return = terminated or truncated, episode_return + float(reward)
            steps += 1
            truth, belief = info["ground_truth"], info["perception"]
            near = np.hypot(*(truth["ball"] - truth["robot_pose"][:2])) < NEAR_M
            if belief["ball_known"] and near:
                errors.append(float(np.hypot(*(truth["ball"] - belief["ball"]))))
                x, y, theta = truth["robot_pose"]
                c, s = math.cos(theta), math.sin(theta)
                dx, dy = truth["ball"][0] - x, truth["ball"][1] - y
                relative = np.array([c * dx + s * dy, -s * dx + c * dy])
                relative_errors.append(float(np.hypot(*(relative - belief["ball_relative"]))))
        goal = info["reward_terms"]["goal"]
        successes += goal > 0 if player != "goalie" else goal == 0
        returns.append(episode_return)
    seconds = time.perf_counter() - start
    env.close()
    low, high = wilson(successes, args.episodes)
    return {
        "env": env_id,
        "player": player,
        "episodes": args.episodes,
        "success": successes / args.episodes,
        "success_ci95": [low, high],
        "mean_return": float(np.mean(returns)),
        "ball_error_m": error_stats(errors),
        "ball_relative_error_m": error_stats(relative_errors),
        "steps_per_s": steps / seconds,
    }


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
        f"Scripted soccer players, {args.mode} camera, seeds {args.seed}-"
        f"{args.seed + args.episodes - 1} (held out)",
        "",
        "| env | player | success (95 % CI) | mean return | ball error near (m): mean / median"
        " / p95 | the same relative to the robot | steps/s |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in results:
        e, q = r["ball_error_m"], r["ball_relative_error_m"]
        lines.append(
            f"| {r['env']} | {r['player']} | {r['success']:.0%} ({r['success_ci95'][0]:.0%}-"
            f"{r['success_ci95'][1]:.0%}) | {r['mean_return']:.2f} | {e['mean']:.3f} / "
            f"{e['median']:.3f} / {e['p95']:.3f} | {q['mean']:.3f} / {q['median']:.3f} / "
            f"{q['p95']:.3f} | {r['steps_per_s']:.0f} |"
        )
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--mode", choices=("rendered", "geometric"), default="geometric")
    parser.add_argument("--episodes", type=int, default=100)
    parser.add_argument("--seed", type=int, default=100)
    parser.add_argument("--envs", nargs="*", default=None, help="only these env ids")
    parser.add_argument("--out", type=Path, default=RESULTS)
    args = parser.parse_args()
    torch.set_num_threads(1)
    runs = [r for r in RUNS if args.envs is None or r[0] in args.envs]
    results = [run(env_id, player, args) for env_id, player in runs]
    args.out.mkdir(parents=True, exist_ok=True)
    stem = f"soccer_baselines_{args.mode}"
    (args.out / f"{stem}.json").write_text(
        json.dumps({"mode": args.mode, "seed": args.seed, "results": results}, indent=1)
    )
    (args.out / f"{stem}.md").write_text(markdown(results, args))
    print(markdown(results, args))


if __name__ == "__main__":
    main()
