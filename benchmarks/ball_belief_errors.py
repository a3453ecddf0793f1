"""Where the believed ball's error comes from, step by step, in a soccer env.

What: ``--episodes`` episodes of ``--env`` (``SPL/Striker-v0``, rendered by default) from
``reset(seed=--seed + k)``, played by ``--player`` (the centre-kicking striker). At every step
where a ball is believed and the true ball lies within ``NEAR_M`` of our robot, the error of
the believed ball relative to the robot (the filter's own estimate, free of the pose's error)
is put in one class:

- ``far_off``: more than ``FAR_OFF_M`` off (a belief started or restarted at a false
  sighting, or one that rolled far from the ball);
- ``phantom_motion``: the ball lies still (slower than ``STILL_MPS``) but the belief rolls
  (faster than ``PHANTOM_MPS``: a sighting taken for a kick);
- ``ball_moving``: the ball rolls;
- ``rest``: the rest.

Reports per class the steps, the error's sum and its share of the whole, and the mean; the
whole's mean, median and 95th percentile, with the field-frame error beside it; and how many
steps with the true ball within ``NEAR_M`` had no ball believed (``unbelieved``: a later
start lowers the error above and shows here).

    python benchmarks/ball_belief_errors.py                  # tuning seeds 0-15, ~6 min
    python benchmarks/ball_belief_errors.py --set perception.ball_filter.start_confirm_s=null \
        --set perception.cnn_ball.camera_tilt_std_rad=0 --name ball_belief_errors_before

Writes ``ball_belief_errors.json`` (``--name``) to ``--out`` (``benchmarks/results``).
"""

from __future__ import annotations

import json
import time
from collections import defaultdict
from pathlib import Path

import gymnasium as gym
import numpy as np
import torch
from ball_flatness import episodes_parser, written_result  # benchmarks/ is the script's folder

import spl_env  # noqa: F401  (registers the env ids)
from agents.evaluate import load_policy, parse_overrides, played_steps
from perception.geometry import invert, transform_points

RESULTS = Path("benchmarks/results")
NEAR_M = 3.0  # the error counts while the true ball lies this near our robot
FAR_OFF_M = 1.0
STILL_MPS = 0.05
PHANTOM_MPS = 0.3
CLASSES = ("far_off", "phantom_motion", "ball_moving", "rest")


def error_class(error_m: float, true_speed: float, believed_speed: float) -> str:
    """The class (module doc) of one step's relative error."""
    if error_m > FAR_OFF_M:
        return "far_off"
    if true_speed < STILL_MPS and believed_speed > PHANTOM_MPS:
        return "phantom_motion"
    if true_speed >= STILL_MPS:
        return "ball_moving"
    return "rest"


def main() -> None:
    args = episodes_parser(__doc__, "ball_belief_errors", player="centre_kick").parse_args()
    torch.set_num_threads(1)
    start = time.perf_counter()
    env = gym.make(args.env, **parse_overrides(args.set))
    policy = load_policy(args.player, env.get_wrapper_attr("config"))
    errors: dict[str, list[float]] = defaultdict(list)
    relative, field = [], []
    unbelieved = 0
    for seed in range(args.seed, args.seed + args.episodes):
        for _, info in played_steps(env, policy, seed):
            truth, belief = info["ground_truth"], info["perception"]
            ball = transform_points(invert(truth["robot_pose"]), truth["ball"])[0]  # robot frame
            if np.hypot(*ball) >= NEAR_M:
                continue
            if not belief["ball_known"]:
                unbelieved += 1
                continue
            error = float(np.hypot(*(ball - belief["ball_relative"])))
            kind = error_class(
                error,
                float(np.hypot(*truth["ball_velocity"])),
                float(np.hypot(*belief["ball_velocity"])),
            )
            errors[kind].append(error)
            relative.append(error)
            field.append(float(np.hypot(*(truth["ball"] - belief["ball"]))))
    env.close()
    total = sum(relative)
    measured = {
        "steps": len(relative),
        "relative_error_m": {  # None where no step counted (no ball believed near)
            "mean": float(np.mean(relative)) if relative else None,
            "median": float(np.median(relative)) if relative else None,
            "p95": float(np.percentile(relative, 95)) if relative else None,
        },
        "field_error_mean_m": float(np.mean(field)) if field else None,
        "unbelieved_steps": unbelieved,
        "unbelieved_share": unbelieved / max(unbelieved + len(relative), 1),
        "classes": {
            kind: {
                "steps": len(errors[kind]),
                "error_sum_m": float(sum(errors[kind])),
                "share": float(sum(errors[kind]) / total) if total > 0 else 0.0,
                "mean_m": float(np.mean(errors[kind])) if errors[kind] else None,
            }
            for kind in CLASSES
        },
    }
    result = written_result(args, args.player, measured, start)
    keys = ("relative_error_m", "field_error_mean_m", "unbelieved_share")
    print(json.dumps({k: result[k] for k in keys}))
    for kind, c in result["classes"].items():
        share = f"{c['share']:.0%}"
        print(f"{kind:15s} steps {c['steps']:5d} error sum {c['error_sum_m']:7.1f} m ({share})")


if __name__ == "__main__":
    main()
