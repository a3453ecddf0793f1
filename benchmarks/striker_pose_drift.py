"""How the striker's believed pose drifts between pole sightings, and what that does to its ball.

What: ``--episodes`` episodes of ``--env`` (``SPL/Striker-v0``) from ``reset(seed=--seed + k)``,
played by ``--player`` (the centre-kicking striker), with the env overrides given (``--set
camera_mode=geometric --set frontend=colour`` for the fast mode). At every step: the believed
pose's position and heading errors (``info["perception"]`` against ``info["ground_truth"]``),
the time since a pole was last sighted (``info["perception"]["sighted"]``; the known start
pose counts as one), whether our walk was blocked (the body stayed put while the walk engine,
and so the odometry, stepped), the heading's NEES (squared error over the believed variance;
1 for a consistent filter) and the position's (2 for a consistent one), and the ball's error on
the field while it lies within ``NEAR_M`` of our robot and is believed. Reported over all steps
and by band of the time since the last pole sighting; ``blocked_share_of_heading_change`` is the
share of the summed step-to-step change of the heading error that falls in blocked steps;
``blind_at_the_feet`` the steps whose frame showed neither a pole nor a field feature while the
head was pitched down to its stop (the ball at our feet), with the errors there and the longest
such run (a striker stuck at a ball pinned against the goalie looks down for many seconds); in
an env whose perception holds no field features, the steps with no pole and the head there.

    python benchmarks/striker_pose_drift.py --set camera_mode=geometric --set frontend=colour \\
        --episodes 100                                      # tuning seeds 0-99, ~1 min

Writes ``striker_pose_drift.json`` (``--name``) to ``--out`` (``benchmarks/results``).
"""

from __future__ import annotations

import itertools
import json
import math
import time
from typing import Any

import numpy as np
from ball_flatness import (  # benchmarks/ is the script's folder
    episodes_parser,
    made_env,
    written_result,
)

import spl_env  # noqa: F401  (registers the env ids)
from agents.evaluate import load_policy, played_steps

NEAR_M = 3.0  # the ball's error counts while it lies this near our robot (m), as the issue's
AGENT = 0  # our robot's row in the world state
GAP_BANDS_S = (0.0, 0.1, 1.0, 3.0, 6.0, math.inf)  # time since the last pole sighting (s)
PITCH_STOP_TOL_RAD = 0.02  # a head pitched this near its stop looks down at the feet


def main() -> None:
    parser = episodes_parser(__doc__, "striker_pose_drift", player="centre_kick")
    args = parser.parse_args()
    start = time.perf_counter()
    env, core = made_env(args)
    dt = core.config.control_dt_s
    pitch_stop = core.config.robot.head_pitch_max_rad
    policy = load_policy(args.player, env.get_wrapper_attr("config"))
    rows: list[tuple[float, ...]] = []  # per step: the columns summary() unpacks
    for seed in range(args.seed, args.seed + args.episodes):
        since = 0.0  # the start pose is known (the prior)
        for _, info in played_steps(env, policy, seed):
            truth, belief = info["ground_truth"], info["perception"]
            offset = belief["pose"] - truth["robot_pose"]
            heading = math.remainder(float(offset[2]), math.tau)
            cov = np.asarray(belief["pose_cov"])
            since = 0.0 if np.any(belief["sighted"]) else since + dt
            near = np.hypot(*(truth["ball"] - truth["robot_pose"][:2])) < NEAR_M
            ball = np.hypot(*(truth["ball"] - belief["ball"])) if belief["ball_known"] else None
            blind = (
                truth["head"][1] >= pitch_stop - PITCH_STOP_TOL_RAD
                and not np.any(belief["sighted"])
                and not belief.get("field_features_count", 0)
            )
            rows.append(
                (
                    seed,
                    float(np.hypot(offset[0], offset[1])),
                    heading,
                    heading**2 / cov[2, 2],
                    float(offset[:2] @ np.linalg.solve(cov[:2, :2], offset[:2])),
                    since,
                    float(core.world_state.blocked[AGENT]),
                    float(ball) if near and ball is not None else math.nan,
                    float(blind),
                )
            )
    env.close()
    result = written_result(args, args.player, summary(np.array(rows), dt), start)
    print(json.dumps(result, indent=1))


def summary(rows: np.ndarray, dt: float) -> dict[str, Any]:
    """Means over the steps ``rows`` (N, 9) and by band of the time since a pole sighting;
    ``dt`` the control step (s)."""
    seed, position, heading, heading_nees, position_nees, since, blocked, ball, blind = rows.T
    change = np.abs(np.diff(heading))[np.diff(seed) == 0]  # within episodes
    in_blocked = blocked[1:][np.diff(seed) == 0] > 0
    bands = {}
    for low, high in itertools.pairwise(GAP_BANDS_S):
        band = (since >= low) & (since < high)
        bands[f"{low:g}-{high:g} s"] = {
            "share_of_steps": float(band.mean()),
            "position_error_m": float(position[band].mean()) if band.any() else None,
            "heading_error_deg": float(np.degrees(np.abs(heading[band])).mean())
            if band.any()
            else None,
            "ball_error_m": float(np.nanmean(ball[band]))
            if np.isfinite(ball[band]).any()
            else None,
        }
    return {
        "steps": len(rows),
        "position_error_m": float(position.mean()),
        "heading_error_deg": float(np.degrees(np.abs(heading)).mean()),
        "heading_nees": float(heading_nees.mean()),
        "position_nees": float(position_nees.mean()),
        "ball_error_m": float(np.nanmean(ball)),
        "steps_with_a_pole_sighted": float((since == 0.0).mean()),
        "blocked_steps": float(blocked.mean()),
        "blocked_share_of_heading_change": float(change[in_blocked].sum() / change.sum()),
        "by_time_since_a_pole_sighting": bands,
        "blind_at_the_feet": blind_summary(seed, blind > 0, position, heading, ball, dt),
    }


def blind_summary(
    seed: np.ndarray,
    blind: np.ndarray,
    position: np.ndarray,
    heading: np.ndarray,
    ball: np.ndarray,
    dt: float,
) -> dict[str, Any]:
    """The share of the steps ``blind`` (N,) bool (module doc), the mean errors there, the
    longest run of them within an episode (s) and how many episodes hold a run of 5 s."""
    runs = _run_seeds(seed, blind)
    long_runs = {s for s, length in runs if length * dt >= 5.0}
    return {
        "share_of_steps": float(blind.mean()),
        "position_error_m": float(position[blind].mean()) if blind.any() else None,
        "heading_error_deg": float(np.degrees(np.abs(heading[blind])).mean())
        if blind.any()
        else None,
        "ball_error_m": float(np.nanmean(ball[blind])) if np.isfinite(ball[blind]).any() else None,
        "position_error_elsewhere_m": float(position[~blind].mean()) if (~blind).any() else None,
        "longest_run_s": max((length for _, length in runs), default=0) * dt,
        "episodes_with_a_5_s_run": len(long_runs),
    }


def _run_seeds(seed: np.ndarray, blind: np.ndarray) -> list[tuple[int, int]]:
    """(seed, length in steps) of each run of ``blind`` steps within an episode."""
    out = []
    for (s, is_blind), steps in itertools.groupby(zip(seed.tolist(), blind.tolist(), strict=True)):
        if is_blind:
            out.append((int(s), len(list(steps))))
    return out


if __name__ == "__main__":
    main()
