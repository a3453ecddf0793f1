"""How far the CNN's ball sightings are off while the robot walks: the fit of the camera's tilt std.

What: ``--episodes`` episodes of ``--env`` (``SPL/Striker-v0``, rendered: pixels and the CNN)
from ``reset(seed=--seed + k)``, played by the centre-kicking striker. After every step each
camera's frame (the top one, and the bottom one read at the pipeline's ``bottom_downscale``)
goes through the CNN again and :func:`perception.vision.cnn_ball.ball_sightings` as the env
runs it; a sighting within ``OF_BALL_M`` plus ``OF_BALL_FRACTION`` of the true range of the
true ball (robot frame) is of the ball, and its range and bearing errors are kept with two parts
of its variance worked out here: the pixel noise's (``CnnBallConfig.pixel_std``) and that of
one radian of camera pitch (``fy`` pixels on ``v``), both through
:func:`perception.vision.ground_point.range_bearing_cov`. The tilt std is the maximum-likelihood
fit to the range errors of the top camera's sightings from 0.6 m (where the bottom camera
takes over) to ``--max-range`` while our robot walks (the sway grows with the walking speed;
the bottom camera's sightings at the feet move by millimetres). Reports the fit, and per
camera, walking or standing, and range band: the count, the range error's mean and std, the
model's std without and with the tilt, and the mean normalised squared range and bearing
errors (NEES, 1 when the model is right).

    python benchmarks/ball_sighting_noise.py              # tuning seeds 0-15, ~8 min

Writes ``ball_sighting_noise.json`` (``--name``) to ``--out`` (``benchmarks/results``).
"""

from __future__ import annotations

import argparse
import math
import time
from collections import defaultdict
from pathlib import Path
from typing import Any

import numpy as np
import torch
from ball_flatness import (
    camera_frames,
    camera_sightings,
    episodes_parser,
    made_env,
    written_result,
)  # benchmarks/ is the script's folder

import spl_env  # noqa: F401  (registers the env ids)
from agents.evaluate import load_policy, played_steps
from perception.geometry import invert, transform_points
from perception.types import CameraModel, CameraState
from perception.vision.cnn_ball import CnnBallConfig
from perception.vision.ground_point import range_bearing_cov

RESULTS = Path("benchmarks/results")
OF_BALL_M = 0.5  # a sighting this near the true ball, plus ...
OF_BALL_FRACTION = 0.1  # ... this share of its range, is of the ball
WALKING_MPS = 0.02  # our robot walks when its body moves this fast
BANDS_M = (0.0, 0.6, 1.0, 2.0, 3.0, 4.0, 6.0)
TILTS_RAD = tuple(np.round(np.arange(0.0, 0.02001, 0.0005), 4).tolist())  # the fit's grid


def variance_parts(
    box: np.ndarray, camera: CameraModel, state: CameraState, config: CnnBallConfig, downscale: int
) -> tuple[np.ndarray, np.ndarray] | None:
    """(range, bearing) variances (2,) of a ball box (4,) from the pixel noise alone, and per
    radian squared of camera pitch; None at the horizon."""
    centre = np.array([(box[0] + box[2]) / 2, (box[1] + box[3]) / 2 + config.row_offset_px])
    std = config.pixel_std(box, downscale)
    pixel = range_bearing_cov(centre, camera, state, std, config.radius_m)
    tilt = range_bearing_cov(centre, camera, state, (0.0, camera.fy), config.radius_m)
    if pixel is None or tilt is None:
        return None
    return np.diag(pixel).copy(), np.diag(tilt).copy()


def record(args: argparse.Namespace) -> list[dict[str, Any]]:
    """One row per sighting of the ball: camera, walking, true range, errors, variance parts."""
    env, core = made_env(args)
    pipeline = core.config.perception
    config = pipeline.cnn_ball
    detector = core.perception_context.cnn_detector(pipeline.cnn)
    camera = core.config.sensors.camera.model
    policy = load_policy("centre_kick", env.get_wrapper_attr("config"))
    rows: list[dict[str, Any]] = []
    for seed in range(args.seed, args.seed + args.episodes):
        for _ in played_steps(env, policy, seed):
            truth = core.world_state
            ball = transform_points(invert(truth.robot_pose), truth.ball)[0]  # robot frame
            true_range, true_bearing = float(np.hypot(*ball)), math.atan2(ball[1], ball[0])
            walking = bool(np.hypot(*core.robots[0].velocity[:2]) > WALKING_MPS)
            for name, image, state, downscale in camera_frames(core):
                found = camera_sightings(detector, image, state, core, config, downscale)
                for sighting in found:
                    seen = sighting.range_m * np.array(
                        [math.cos(sighting.bearing_rad), math.sin(sighting.bearing_rad)]
                    )
                    if math.dist(seen, ball) > OF_BALL_M + OF_BALL_FRACTION * true_range:
                        continue
                    parts = variance_parts(sighting.box, camera, state, config, downscale)
                    if parts is None:
                        continue
                    rows.append(
                        {
                            "camera": name,
                            "walking": walking,
                            "range_m": true_range,
                            "range_error_m": sighting.range_m - true_range,
                            "bearing_error_rad": math.remainder(
                                sighting.bearing_rad - true_bearing, math.tau
                            ),
                            "pixel_var": parts[0].tolist(),
                            "tilt_var_per_rad2": parts[1].tolist(),
                        }
                    )
    env.close()
    return rows


def fit_tilt(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """The maximum-likelihood tilt std over ``TILTS_RAD`` for the range errors of ``rows``,
    with the mean negative log-likelihood at each grid point."""
    errors = np.array([r["range_error_m"] for r in rows])
    pixel = np.array([r["pixel_var"][0] for r in rows])
    per_rad2 = np.array([r["tilt_var_per_rad2"][0] for r in rows])
    nll = []
    for tilt in TILTS_RAD:
        var = pixel + tilt**2 * per_rad2
        nll.append(float(0.5 * np.mean(np.log(2 * math.pi * var) + errors**2 / var)))
    best = TILTS_RAD[int(np.argmin(nll))]
    return {
        "tilt_std_rad": best,
        "count": len(rows),
        "mean_nll": dict(zip(TILTS_RAD, nll, strict=True)),
    }


def band_summary(rows: list[dict[str, Any]], tilt: float) -> dict[str, Any]:
    """Count, range error mean and std, model range std without and with ``tilt``, NEES."""
    errors = np.array([r["range_error_m"] for r in rows])
    bearing = np.array([r["bearing_error_rad"] for r in rows])
    pixel = np.array([r["pixel_var"] for r in rows])
    per_rad2 = np.array([r["tilt_var_per_rad2"] for r in rows])
    with_tilt = pixel + tilt**2 * per_rad2
    return {
        "count": len(rows),
        "range_error_mean_m": float(errors.mean()),
        "range_error_std_m": float(errors.std()),
        "model_range_std_m": float(np.sqrt(pixel[:, 0].mean())),
        "model_range_std_with_tilt_m": float(np.sqrt(with_tilt[:, 0].mean())),
        "range_nees": float(np.mean(errors**2 / pixel[:, 0])),
        "range_nees_with_tilt": float(np.mean(errors**2 / with_tilt[:, 0])),
        "bearing_nees": float(np.mean(bearing**2 / pixel[:, 1])),
    }


def main() -> None:
    parser = episodes_parser(__doc__, "ball_sighting_noise")
    parser.add_argument("--max-range", type=float, default=5.0, help="the fit's sightings (m)")
    args = parser.parse_args()
    torch.set_num_threads(1)
    start = time.perf_counter()
    rows = record(args)
    fitted = fit_tilt(
        [
            r
            for r in rows
            if r["camera"] == "top" and r["walking"] and 0.6 <= r["range_m"] < args.max_range
        ]
    )
    tilt = fitted["tilt_std_rad"]
    groups: dict[str, list[dict[str, Any]]] = defaultdict(list)
    for r in rows:
        band = int(np.searchsorted(BANDS_M, r["range_m"], side="right")) - 1
        lo = BANDS_M[band]
        span = f"{lo:g}-{BANDS_M[band + 1]:g} m" if band + 1 < len(BANDS_M) else f"{lo:g}+ m"
        motion = "walking" if r["walking"] else "standing"
        groups[f"{r['camera']}/{motion}/{span}"].append(r)
    measured = {
        "fit": fitted,
        "bands": {k: band_summary(v, tilt) for k, v in sorted(groups.items())},
    }
    result = written_result(args, "centre_kick", measured, start)
    print(f"tilt std {tilt} rad from {fitted['count']} sightings")
    for key, summary in result["bands"].items():
        print(
            f"{key:28s} n={summary['count']:5d} range err {summary['range_error_mean_m']:+.3f}"
            f" ± {summary['range_error_std_m']:.3f} m, model {summary['model_range_std_m']:.3f}"
            f" / {summary['model_range_std_with_tilt_m']:.3f}, NEES {summary['range_nees']:.2f}"
            f" / {summary['range_nees_with_tilt']:.2f}, bearing NEES {summary['bearing_nees']:.2f}"
        )


if __name__ == "__main__":
    main()
