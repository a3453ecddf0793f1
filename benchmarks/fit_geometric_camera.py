"""Fit the geometric camera mode's noise to the rendered colour-filter pipeline.

    python benchmarks/fit_geometric_camera.py --episodes 2

Runs ``SPL/ActiveVision-v0`` with rendered frames (default lighting, patrol walk) under three
head policies (fixed, scan, uniformly random targets), so that slow and fast heads are both
represented. For every frame it asks the geometric camera which poles are fully visible
(projection and ray casts, no noise) and compares with what the rendered colour filter found
(a detection matches when its id agrees and its range is within 25 % of the truth):

- ``recall_by_smear``: detected / visible against the smear, the motion-blur length over the
  pole's width in pixels (blur is what loses poles: with a still head recall is about 1);
- ``pixel_std_v_px`` / ``pixel_std_u_px``: the band-centre row / column noise for which the
  geometric mode's range / bearing errors, over the same detected poles and through the same
  measurement model, have the RMS of the rendered pipeline's.

Writes ``benchmarks/results/geometric_camera.json``; ``GeometricCameraConfig``'s defaults cite it.
"""

from __future__ import annotations

import argparse
import itertools
import json
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

import spl_env  # noqa: F401  (registers the env ids)
from agents.baselines import FixedHead, HeadScan
from perception.geometry import wrap_angle
from perception.metrics import landmark_range_bearing
from perception.providers.poles import ColourPoleSightings
from perception.representations import POLE_SIGHTINGS
from spl_env.envs.core import SplEnv
from spl_env.sensors.camera import blur_length_px
from spl_env.sensors.emulation.poles import GeometricPoleCamera, smear

SMEAR_BOUNDS = (0.25, 0.5, 1.0, 2.0, 4.0, 1000.0)
SIGMA_GRID_PX = np.round(np.arange(0.0, 2.01, 0.05), 2)
MATCH_FRACTION = 0.25


def _policies(env: gym.Env, rng: np.random.Generator) -> dict[str, Any]:
    config = env.get_wrapper_attr("config")
    return {
        "fixed": FixedHead.from_config(config).predict,
        "scan": HeadScan.from_config(config).predict,
        "random": lambda obs, **_: (rng.uniform(-1, 1, size=2).astype(np.float32), None),
    }


def collect(episodes: int, seconds: float, seed: int) -> dict[str, list]:
    """Per visible pole: smear, detection, rendered errors, and what the geometric model needs."""
    env = gym.make("SPL/ActiveVision-v0", episode_s=seconds, frontend="colour")
    core = env.unwrapped
    if not isinstance(core, SplEnv):
        raise TypeError(f"the fit needs an SplEnv, got {type(core).__name__}")
    sightings = core.pipeline.provider(POLE_SIGHTINGS)
    if not isinstance(sightings, ColourPoleSightings):
        raise TypeError(f"the fit needs the colour front end, got {type(sightings).__name__}")
    camera = core.config.sensors.camera
    geometric = GeometricPoleCamera.for_scene(
        core.scene, core.config.sensors.geometric_camera, camera.model
    )
    ours = core.robots[0]
    rows: dict[str, list] = {"smear": [], "detected": [], "err": [], "geometry": [], "policy": []}
    for name, predict in _policies(env, np.random.default_rng(seed)).items():
        for k in range(episodes):
            obs, info = env.reset(seed=seed + k)
            done, step = False, 0
            while not done:
                action, _ = predict(obs, episode_start=np.array([step == 0]))
                obs, _, terminated, truncated, info = env.step(action)
                done, step = terminated or truncated, step + 1
                gt = info["ground_truth"]
                truth = landmark_range_bearing(
                    gt["robot_pose"], gt["landmark_ids"], gt["landmarks"]
                )
                position, rotation = ours.camera_pose_world()
                visible = geometric.visible(core.world, position, rotation)
                # the camera's turn rate this step, which the env's motion blur used
                blur = blur_length_px(
                    core.camera_yaw_rate_rps, camera.exposure_time_s, camera.model.fx
                )
                seen = info["perception"]
                detected = {
                    int(i): (float(rb[0]), float(rb[1]))
                    for i, rb, ok in zip(
                        seen["landmark_ids"], seen["sightings"], seen["sighted"], strict=True
                    )
                    if ok
                }
                for band, s in zip(visible, smear(visible, blur), strict=True):
                    true_range, true_bearing = truth[band.landmark_id]
                    hit = detected.get(band.landmark_id)
                    ok = hit is not None and abs(hit[0] - true_range) <= MATCH_FRACTION * true_range
                    rows["smear"].append(float(s))
                    rows["detected"].append(ok)
                    rows["policy"].append(name)
                    rows["err"].append(
                        (hit[0] - true_range, float(wrap_angle(hit[1] - true_bearing)))
                        if ok and hit is not None
                        else (np.nan, np.nan)
                    )
                    rows["geometry"].append(
                        (band, core.sensor_frame.camera_state, true_range, true_bearing)
                    )
    rows["detector"] = [sightings.detector]
    env.close()
    return rows


def geometric_rms(
    rows: dict[str, list], sigma_u: float, sigma_v: float, seed: int
) -> tuple[float, float]:
    """RMS range and bearing error of the geometric mode over the rendered detections' poles,
    with band-centre column noise ``sigma_u`` and row noise ``sigma_v`` (px)."""
    rng = np.random.default_rng(seed)
    detector = rows["detector"][0]
    err_r, err_b = [], []
    for (band, state, true_range, true_bearing), ok in zip(
        rows["geometry"], rows["detected"], strict=True
    ):
        if not ok:
            continue
        noise = rng.normal(0.0, 1.0, size=(2, 2)) * np.array([sigma_u, sigma_v])
        obs = detector.observe_band_centres(
            band.landmark_id, band.upper + noise[0], band.lower + noise[1], band.box, state
        )
        if obs is not None:
            err_r.append(obs.range_m - true_range)
            err_b.append(float(wrap_angle(obs.bearing_rad - true_bearing)))
    return float(np.sqrt(np.mean(np.square(err_r)))), float(np.sqrt(np.mean(np.square(err_b))))


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--episodes", type=int, default=2, help="per head policy")
    parser.add_argument("--seconds", type=float, default=30.0)
    parser.add_argument("--seed", type=int, default=500)
    parser.add_argument(
        "--out", type=Path, default=Path("benchmarks/results/geometric_camera.json")
    )
    args = parser.parse_args()
    rows = collect(args.episodes, args.seconds, args.seed)
    smears = np.array(rows["smear"])
    detected = np.array(rows["detected"])
    errors = np.array(rows["err"])[detected]
    rendered = tuple(float(np.sqrt(np.mean(errors[:, i] ** 2))) for i in range(2))
    # rows set the range (vertical band spacing), columns the bearing: fit each on its own
    range_fit = {float(s): geometric_rms(rows, 0.0, float(s), args.seed)[0] for s in SIGMA_GRID_PX}
    sigma_v = min(range_fit, key=lambda s: abs(range_fit[s] - rendered[0]))
    bearing_fit = {
        float(s): geometric_rms(rows, float(s), sigma_v, args.seed)[1] for s in SIGMA_GRID_PX
    }
    sigma_u = min(bearing_fit, key=lambda s: abs(bearing_fit[s] - rendered[1]))
    at_fit = geometric_rms(rows, sigma_u, sigma_v, args.seed)
    table = []
    for lo, hi in itertools.pairwise((0.0, *SMEAR_BOUNDS)):
        inside = (smears >= lo) & (smears < hi) if lo > 0 else smears < hi
        table.append(
            {
                "smear_below": hi,
                "visible": int(inside.sum()),
                "recall": float(detected[inside].mean()) if inside.any() else None,
            }
        )
    policies = np.array(rows["policy"])
    result = {
        "setting": {
            "episodes_per_policy": args.episodes,
            "seconds": args.seconds,
            "seed": args.seed,
            "policies": ["fixed", "scan", "random"],
            "lighting": "default",
            "match_fraction": MATCH_FRACTION,
        },
        "visible_poles": len(smears),
        "recall": float(detected.mean()),
        "recall_by_policy": {p: float(detected[policies == p].mean()) for p in set(rows["policy"])},
        "recall_by_smear": table,
        "rendered_rms": {"range_m": rendered[0], "bearing_rad": rendered[1]},
        "fitted_pixel_std_u_px": sigma_u,
        "fitted_pixel_std_v_px": sigma_v,
        "geometric_rms_at_fit": {"range_m": at_fit[0], "bearing_rad": at_fit[1]},
        "grid": {"range_rms_by_sigma_v": range_fit, "bearing_rms_by_sigma_u": bearing_fit},
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=2))
    print(json.dumps({k: v for k, v in result.items() if k != "grid"}, indent=2))


if __name__ == "__main__":
    main()
