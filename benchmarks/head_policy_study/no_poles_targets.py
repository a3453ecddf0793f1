"""Study run: how much where the head looks matters on a field without poles.

    python -m benchmarks.head_policy_study.no_poles_targets --episodes 10   # about 8 min

Scripted head policies on ``SPL/ActiveVision-NoPoles-v1`` in the geometric mode (the fitted
field-feature emulator; the robot localises from the field's lines, the unified sensor
model), one-minute patrols on the tuning seeds ``--seed`` .. (0-9 by default): the head scan
(:class:`agents.baselines.HeadScan`) at its default 90° amplitude and 4 s period and at other
amplitudes and periods, and a head that looks, at level pitch, at the nearest reachable one of
a set of field points where the believed pose puts them (scanning when none is reachable): the
centre circle's centre, the goals' centres, or those and the penalty marks (the field's
distinctive features). Before a learned no-poles head policy is trained, this says how much
room its choice has: the mean and 95 % t-interval over episodes of each episode's mean
position error, written to ``--out`` (JSON).
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import gymnasium as gym
import numpy as np

import spl_env  # noqa: F401  (registers the env ids)
from agents.baselines import HeadScan, LookAtStalest
from agents.evaluate import episode_metrics, run_episode
from benchmarks.head_policies import interval
from spl_env.config import EnvConfig

ENV_ID = "SPL/ActiveVision-NoPoles-v1"
# field points (m, field frame) of each look-at policy
TARGETS: dict[str, tuple[tuple[float, float], ...]] = {
    "look_at_centre": ((0.0, 0.0),),
    "look_at_goals": ((4.5, 0.0), (-4.5, 0.0)),
    "look_at_distinctive": ((0.0, 0.0), (4.5, 0.0), (-4.5, 0.0), (3.2, 0.0), (-3.2, 0.0)),
}
# (amplitude deg, period s) of each scan
SCANS: dict[str, tuple[float, float]] = {
    "scan": (90.0, 4.0),
    "scan_amplitude_60": (60.0, 4.0),
    "scan_amplitude_119": (119.0, 4.0),
    "scan_period_2": (90.0, 2.0),
    "scan_period_8": (90.0, 8.0),
}


class LookAtPoint(HeadScan):
    """Look at the nearest of ``targets`` (field frame) within the head's reach where the
    believed pose (``self_pose_field``) puts it, at level pitch; the scan step otherwise."""

    def __init__(self, config: EnvConfig, targets: tuple[tuple[float, float], ...]) -> None:
        super().__init__(config.robot, config.control_dt_s)
        self.targets = targets
        length, width = config.scene.dimensions.carpet_size_m
        self.half_carpet_m = (length / 2, width / 2)

    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        x_scaled, y_scaled, cos_t, sin_t = (float(v) for v in obs["self_pose_field"])
        x, y = x_scaled * self.half_carpet_m[0], y_scaled * self.half_carpet_m[1]
        heading = math.atan2(sin_t, cos_t)
        reach = self.robot.head_yaw_limit_rad + LookAtStalest.reach_margin_rad
        best: tuple[float, float] | None = None  # (distance, bearing)
        for tx, ty in self.targets:
            bearing = math.remainder(math.atan2(ty - y, tx - x) - heading, math.tau)
            distance = math.hypot(tx - x, ty - y)
            if abs(bearing) <= reach and (best is None or distance < best[0]):
                best = (distance, bearing)
        if best is None:
            return super().act(obs)
        return self.look(best[1], 0.0)


def policy_for(name: str, config: EnvConfig) -> HeadScan:
    """The scripted policy ``name`` (a key of :data:`SCANS` or :data:`TARGETS`)."""
    if name in TARGETS:
        return LookAtPoint(config, TARGETS[name])
    scan = HeadScan(config.robot, config.control_dt_s)
    amplitude_deg, scan.period_s = SCANS[name]
    scan.amplitude_rad = math.radians(amplitude_deg)
    return scan


def position_error(env: gym.Env, policy: HeadScan, seed: int) -> float:
    """The mean position error (m) of one episode of ``policy`` from ``reset(seed=seed)``."""
    error = episode_metrics(run_episode(env, policy, seed))["mean_position_error_m"]
    if error is None:  # a patrol believes a pose every step
        raise RuntimeError(f"seed {seed}: the episode has no position error")
    return error


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--episodes", type=int, default=10)
    parser.add_argument(
        "--out", type=Path, default=Path("benchmarks/results/head_policy_study_no_poles.json")
    )
    args = parser.parse_args()
    env = gym.make(ENV_ID, camera_mode="geometric")
    config = env.get_wrapper_attr("config")
    seeds = list(range(args.seed, args.seed + args.episodes))
    report: dict[str, object] = {"env_id": ENV_ID, "mode": "geometric", "seeds": seeds}
    for name in (*SCANS, *TARGETS):
        policy = policy_for(name, config)
        errors = [position_error(env, policy, seed) for seed in seeds]
        report[name] = {"mean_position_error_m": interval(errors), "episodes": errors}
        print(f"{name:22s} {np.mean(errors):.4f} m")
    env.close()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(report, indent=1))


if __name__ == "__main__":
    main()
