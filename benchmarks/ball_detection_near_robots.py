"""How often the CNN finds a ball in view while playing, by its range and how near a robot stands.

What: ``--episodes`` episodes of ``--env`` (``SPL/Goalie-v0``, rendered) from
``reset(seed=--seed + k)``, played by ``--player`` (its scripted player). At every step where
the true ball lies in the top camera's view as the ball filter judges it
(:func:`perception.vision.cnn_ball.ball_in_view` with the frame's camera state and
``BallFilterConfig.view_margin``; occlusion is not known to the filter, so not judged here
either) and ``MIN_RANGE_M`` or more from our robot, the step counts as *seen* when one of the
pipeline's ball sightings of that step lies within ``OF_BALL_M`` plus ``OF_BALL_FRACTION`` of the
true range of the true ball. Counted per range band and per band of the distance from the ball
to the nearest other robot (centre to centre): the ball filter's ``detection_chance`` is the
chance in the open, and a robot's feet beside the ball (the goalie's kicker walking up to it)
make the CNN miss it far more often, frame after frame.

    python benchmarks/ball_detection_near_robots.py                       # goalie, seeds 0-15
    python benchmarks/ball_detection_near_robots.py --env SPL/Striker-v0 --player centre_kick

Writes ``ball_detection_near_robots.json`` (``--name``) to ``--out`` (``benchmarks/results``).
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path
from typing import Any

import numpy as np
import torch
from ball_flatness import (  # benchmarks/ is the script's folder
    episodes_parser,
    made_env,
    written_result,
)

import spl_env  # noqa: F401  (registers the env ids)
from agents.evaluate import load_policy, played_steps
from perception.geometry import invert, transform_points
from perception.representations import BALL_SIGHTINGS
from perception.types import BallSighting
from perception.vision.cnn_ball import ball_in_view

RESULTS = Path("benchmarks/results")
MIN_RANGE_M = 0.6  # nearer, the top camera loses the ball at the image's bottom
OF_BALL_M = 0.3  # a sighting this near the true ball, plus ...
OF_BALL_FRACTION = 0.1  # ... this share of its range, is of the ball
RANGE_BANDS_M = (MIN_RANGE_M, 1.0, 2.0, 3.0, 5.0)
ROBOT_BANDS_M = (0.0, 0.3, 0.5, 0.75, 1.0, math.inf)  # ball to the nearest other robot


def band(value: float, edges: tuple[float, ...]) -> int | None:
    """The index of the band ``[edges[k], edges[k + 1])`` holding ``value``, None outside."""
    for k in range(len(edges) - 1):
        if edges[k] <= value < edges[k + 1]:
            return k
    return None


def sighting_point(sighting: BallSighting) -> np.ndarray:
    """Where ``sighting`` places the ball (2,) (m, robot frame)."""
    return sighting.range_m * np.array(
        [math.cos(sighting.bearing_rad), math.sin(sighting.bearing_rad)]
    )


def record(args: argparse.Namespace) -> np.ndarray:
    """Counts (range bands, robot bands, 2): steps with the ball in view, and those seen."""
    env, core = made_env(args)
    camera = core.config.sensors.camera.model
    radius = core.config.perception.cnn_ball.radius_m
    margin = core.config.perception.ball_filter.view_margin
    policy = load_policy(args.player, env.get_wrapper_attr("config"))
    counts = np.zeros((len(RANGE_BANDS_M) - 1, len(ROBOT_BANDS_M) - 1, 2), dtype=int)
    for seed in range(args.seed, args.seed + args.episodes):
        for _ in played_steps(env, policy, seed):
            truth, frame = core.world_state, core.sensor_frame
            ball = transform_points(invert(truth.robot_pose), truth.ball)[0]  # robot frame
            true_range = float(np.hypot(*ball))
            row = band(true_range, RANGE_BANDS_M)
            if row is None or frame.camera_state is None:
                continue
            if not ball_in_view(ball, camera, frame.camera_state, radius, margin):
                continue
            others = np.delete(truth.poses[:, :2], truth.agent, axis=0)
            nearest = float(np.min(np.hypot(*(others - truth.ball).T))) if len(others) else math.inf
            column = band(nearest, ROBOT_BANDS_M)
            if column is None:  # the bands start at 0 and the last is open
                raise RuntimeError(f"no robot band holds {nearest} m")
            tolerance = OF_BALL_M + OF_BALL_FRACTION * true_range
            sightings = core.perception_output[BALL_SIGHTINGS]
            seen = any(math.dist(sighting_point(s), ball) <= tolerance for s in sightings)
            counts[row, column, 0] += 1
            counts[row, column, 1] += seen
    env.close()
    return counts


def summary(counts: np.ndarray) -> list[dict[str, Any]]:
    """One row per (range band, robot band) with steps in view and the share seen."""
    rows = []
    for i in range(counts.shape[0]):
        for j in range(counts.shape[1]):
            in_view, seen = (int(v) for v in counts[i, j])
            rows.append(
                {
                    "range_m": list(RANGE_BANDS_M[i : i + 2]),
                    "nearest_robot_m": [ROBOT_BANDS_M[j], ROBOT_BANDS_M[j + 1]],
                    "in_view": in_view,
                    "seen": seen,
                    "chance": seen / in_view if in_view else None,
                }
            )
    return rows


def main() -> None:
    parser = episodes_parser(
        __doc__, "ball_detection_near_robots", env="SPL/Goalie-v0", player="goalie"
    )
    args = parser.parse_args()
    torch.set_num_threads(1)
    start = time.perf_counter()
    counts = record(args)
    by_robot = counts.sum(axis=0)
    measured = {
        "bands": summary(counts),
        "by_nearest_robot": [
            {
                "nearest_robot_m": [ROBOT_BANDS_M[j], ROBOT_BANDS_M[j + 1]],
                "in_view": int(by_robot[j, 0]),
                "seen": int(by_robot[j, 1]),
                "chance": float(by_robot[j, 1] / by_robot[j, 0]) if by_robot[j, 0] else None,
            }
            for j in range(by_robot.shape[0])
        ],
    }
    result = written_result(args, args.player, measured, start)
    for row in result["by_nearest_robot"]:
        print(row)


if __name__ == "__main__":
    main()
