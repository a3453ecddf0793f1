"""Dead-reckoning drift of the default walk odometry on a one-minute Nao square walk.

Reproduces the setting of seed 000's Nao v6 dataset (odometry-only position error over a
one-minute square walk: mean 0.5039 m, std 0.2030 m): a Nao walking 0.15 m/s forward with 90°
turns in place at 0.5 rad/s, the side chosen so that one lap lasts 60 s. For every seed the
noisy increments are integrated from the true start pose and compared with the true poses.

Usage::

    python benchmarks/odometry_drift.py --seeds 50 --out benchmarks/results/odometry_drift.json
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
from pathlib import Path

import numpy as np

from perception.geometry import FloatArray, compose, wrap_angle
from spl_env.sensors.odometry import OdometryConfig, WalkOdometry
from spl_env.trajectories import increments, square_walk

SPEED_MPS = 0.15  # Nao forward walking speed
TURN_RATE_RPS = 0.5  # Nao turning speed in place
LAP_S = 60.0  # one lap of the square, as in seed 000's one-minute walk
SIDE_M = SPEED_MPS * (LAP_S - 4 * (0.5 * math.pi) / TURN_RATE_RPS) / 4  # about 1.78 m
SEED_000 = {"mean_position_error_m": 0.5039, "std_position_error_m": 0.2030}


def dead_reckon(start: FloatArray, deltas: FloatArray) -> FloatArray:
    """Integrate (N-1, 3) robot-frame increments from ``start`` (3,) into (N, 3) poses."""
    poses = [np.asarray(start, dtype=np.float64)]
    for delta in deltas:
        poses.append(compose(poses[-1], delta))
    return np.array(poses)


def run_seed(config: OdometryConfig, poses: FloatArray, seed: int) -> dict[str, float]:
    """Errors of one dead-reckoned walk over the true ``poses`` (N, 3) with odometry ``seed``."""
    odometry = WalkOdometry(config)
    odometry.reset(np.random.default_rng(seed))
    measured = np.array([odometry.measure(d) for d in increments(poses)])
    estimate = dead_reckon(poses[0], measured)
    position_error = np.linalg.norm(estimate[:, :2] - poses[:, :2], axis=1)
    return {
        "mean_position_error_m": float(position_error.mean()),
        "std_position_error_m": float(position_error.std()),
        "final_position_error_m": float(position_error[-1]),
        "final_heading_error_rad": float(abs(wrap_angle(estimate[-1, 2] - poses[-1, 2]))),
    }


def summarise(runs: list[dict[str, float]]) -> dict[str, dict[str, float]]:
    """Mean and std across seeds of every per-seed metric."""
    return {
        key: {
            "mean": float(np.mean([r[key] for r in runs])),
            "std": float(np.std([r[key] for r in runs])),
        }
        for key in runs[0]
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=50, help="number of odometry seeds")
    parser.add_argument("--dt", type=float, default=0.1, help="odometry period (s)")
    parser.add_argument("--out", type=Path, default=Path("benchmarks/results/odometry_drift.json"))
    args = parser.parse_args()
    if args.seeds < 1:
        parser.error(f"--seeds must be >= 1, got {args.seeds}")

    config = OdometryConfig()
    poses = square_walk(
        side_m=SIDE_M, speed_mps=SPEED_MPS, turn_rate_rps=TURN_RATE_RPS, dt_s=args.dt
    )
    runs = [run_seed(config, poses, seed) for seed in range(args.seeds)]
    result = {
        "walk": {
            "side_m": SIDE_M,
            "speed_mps": SPEED_MPS,
            "turn_rate_rps": TURN_RATE_RPS,
            "dt_s": args.dt,
            "duration_s": LAP_S,
        },
        "seeds": args.seeds,
        "odometry_config": dataclasses.asdict(config),
        "across_seeds": summarise(runs),
        "seed_000_reference": SEED_000,
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=2) + "\n")
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
