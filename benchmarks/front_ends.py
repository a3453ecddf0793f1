"""Both pole front ends of seed 000, colour filter (§3.3) and CNN (§3.4), on the same frames.

``--protocol random``: the protocol of ``benchmarks/colour_filter_accuracy.py`` (its
:class:`Bench`, truth and scoring) under randomised lighting on held-out scenes: precision and
recall within 5 m and at any range, range and bearing errors with their NEES, and the time per
frame on one thread (the CNN's: network, decoding, range and bearing); and the CNN's precision
and recall at each score threshold of ``--thresholds`` (``cnn_sweep``). Writes
``benchmarks/results/front_ends_random.json``.

``--protocol walking``: the analogue of seed 000's Table 4.2: 150 random frames from our robot
walking a patrol (random waypoints) with the classic head scan, among four scripted robots,
with lighting randomised per episode (``SPL/ActiveVision-v0`` itself, its frames read by both
detectors). Per front end: true and false positives, false negatives, images with no pole in
view and no detection (true negatives), precision and recall (any range, as the seed), the
localisation error (px) of the detection's box centre against the truth's and the mean IoU of
the boxes.
The truth box of a CNN detection is the pole's label box (all its seen pixels); the colour
filter only boxes the two colour bands, so its truth box is the label box above the white base.
Also the error (px) of the pole centre (the junction of the bands, the seed's reference point)
and, for the CNN's other classes, indicative per-class counts (a detection matches an unmatched
labelled object of its class with IoU >= 0.5; misses count objects of ``MIN_VIEW_PX`` pixels or
more). Writes
``front_ends_walking.json`` (summary), ``front_ends_walking_predictions.json`` (per image:
truth and both front ends' detections) and ``front_ends_walking.md`` (the table).

Usage::

    python benchmarks/front_ends.py --protocol random --scenes 10 --frames-per-scene 200
    python benchmarks/front_ends.py --protocol walking --episodes 3 --images 150
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import os
import time
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import torch
from colour_filter_accuracy import MIN_VIEW_PX, NEAR_M, Bench, is_true_positive, pole_truth, score

import spl_env  # noqa: F401  (registers the env ids)
from agents.baselines import HeadScan
from perception.geometry import FloatArray, project_points
from perception.types import LandmarkObservation
from perception.vision import (
    CnnDetectorConfig,
    CnnPoleDetector,
    ColourFilterConfig,
    ColourPoleDetector,
)
from perception.vision.cnn_detector import box_iou, pole_class_name
from spl_env.envs.core import SplEnv
from spl_env.sensors.camera import EpisodeLighting, LightingRandomisation

RESULTS = Path("benchmarks/results")
FRONT_ENDS = ("colour_filter", "cnn")
IOU_MATCH = 0.5  # other classes: a detection with this IoU matches a labelled object
CONTROL_DT_S = 0.1  # walking: one control step = one camera frame (as the envs)


def run_random(
    seed: int,
    scenes: int,
    frames_per_scene: int,
    cnn_config: CnnDetectorConfig,
    thresholds: tuple[float, ...] = (),
) -> dict:
    """Both front ends on the colour-filter benchmark's randomised-lighting frames; the CNN
    also at each of ``thresholds`` (``cnn_sweep``).

    The CNN runs once at the lowest threshold; a higher threshold's sightings are those scoring
    at least it, which is exactly what a run at that threshold gives (sightings are taken best
    score first, and a lower score never displaces a higher one).
    """
    benches = [Bench(1000 * seed + k) for k in range(scenes)]
    bench0 = benches[0]
    layout = bench0.scene.poles
    lowest = min((cnn_config.score_threshold, *thresholds))
    cnn = CnnPoleDetector(
        dataclasses.replace(cnn_config, score_threshold=lowest),
        bench0.camera.config.model,
        bench0.codes,
        layout.geometry,
    )
    frames: dict[str, list] = {name: [] for name in FRONT_ENDS}
    times: dict[str, list[float]] = {name: [] for name in FRONT_ENDS}
    for bench in benches:
        for _ in range(frames_per_scene):
            lighting = EpisodeLighting.sample(LightingRandomisation(), bench.rng)
            image, labels = bench.random_frame(lighting)
            state = bench.robot.camera_state()
            truth = bench.truth(labels)
            for name, detector in (("colour_filter", bench.detector), ("cnn", cnn)):
                start = time.perf_counter()
                detections = detector.detect(image, state)
                times[name].append(time.perf_counter() - start)
                frames[name].append((detections, truth))
        bench.world.close()

    lowest_frames = frames["cnn"]

    def above(threshold: float) -> list:
        return [([o for o in d if o.score >= threshold], t) for d, t in lowest_frames]

    frames["cnn"] = above(cnn_config.score_threshold)
    result: dict[str, Any] = {
        name: {
            "frames": len(frames[name]),
            "within_5m": score(frames[name], NEAR_M),
            "any_range": score(frames[name], math.inf),
            "ms_per_frame_mean": 1e3 * float(np.mean(times[name])),
            "ms_per_frame_p95": 1e3 * float(np.percentile(times[name], 95)),
        }
        for name in FRONT_ENDS
    }
    result["cnn_sweep"] = {
        f"{t:g}": {
            "within_5m": score(above(t), NEAR_M)["overall"],
            "any_range": score(above(t), math.inf)["overall"],
        }
        for t in thresholds
    }
    return result


# ----- walking protocol --------------------------------------------------------------------------
def _box(mask: np.ndarray) -> list[float] | None:
    """Pixel-edge box ``[u0, v0, u1, v1]`` of a (H, W) mask, None if empty."""
    rows, cols = np.nonzero(mask)
    if len(rows) == 0:
        return None
    return [cols.min() - 0.5, rows.min() - 0.5, cols.max() + 0.5, rows.max() + 0.5]


def _centre(box: FloatArray | list[float]) -> FloatArray:
    return np.array([(box[0] + box[2]) / 2, (box[1] + box[3]) / 2])


def _project(core: SplEnv, point: FloatArray) -> FloatArray:
    """Pixel (2,) of a field point (3,) in our robot's true camera frame now (NaN if behind)."""
    position, rotation = core.robots[0].camera_pose_world()
    m = core.config.sensors.camera.model
    uv, _ = project_points(((point - position) @ rotation)[None], m.fx, m.fy, m.cx, m.cy)
    return uv[0]


def walking_truth(core: SplEnv, labels: np.ndarray) -> dict[str, Any]:
    """Per pole: range, bearing, in view, visible, label box, band box and junction pixel; and
    the label boxes of the other classes' objects."""
    scene, robot, model = core.scene, core.robots[0], core.config.sensors.camera.model
    geometry = scene.config.poles.geometry
    positions = scene.config.poles.positions(scene.dimensions)
    bodies = {i: core.world.body(name) for i, name in scene.bodies.poles.items()}
    truth = pole_truth(labels, robot, bodies, positions, model, geometry)
    position, _ = robot.camera_pose_world()
    poles: dict[int, dict[str, Any]] = {}
    for i, t in truth.items():
        xy = positions[i]
        towards = (xy - position[:2]) / np.linalg.norm(xy - position[:2])
        near = xy - geometry.radius_m * towards
        base_row = _project(core, np.array([*near, geometry.base_top_m]))[1]
        junction = _project(core, np.array([*xy, geometry.base_top_m + geometry.band_height_m]))
        mask = labels == bodies[i]
        rows = np.arange(labels.shape[0])[:, None]
        poles[i] = {
            **t,
            "box": _box(mask),
            "band_box": _box(mask & (rows < base_row)) if np.isfinite(base_row) else None,
            "junction": junction.tolist(),
        }
    others: list[dict[str, Any]] = []
    for name, bodies_of in (
        ("goal_post", scene.bodies.goal_posts),
        ("ball", (scene.bodies.ball,)),
        ("robot", tuple(o.name for o in core.robots[1:])),
    ):
        for body_name in bodies_of:
            mask = labels == core.world.body(body_name)
            box = _box(mask)
            if box is not None:
                others.append({"class": name, "box": box, "pixels": int(mask.sum())})
    return {"poles": poles, "objects": others}


def _observation_json(obs: LandmarkObservation) -> dict[str, Any]:
    return {
        "landmark_id": obs.landmark_id,
        "box": obs.box.tolist(),
        "pixel": obs.pixel.tolist(),
        "score": obs.score,
        "range_m": obs.range_m,
        "bearing_rad": obs.bearing_rad,
        "cov": obs.cov.tolist(),
    }


def run_walking(
    seed: int, episodes: int, steps: int, images: int, cnn_config: CnnDetectorConfig
) -> tuple[dict, list[dict]]:
    """Table 4.2 analogue: summary and per-image records over ``images`` random walking frames.

    Each episode is ``SPL/ActiveVision-v0`` (patrol, randomised lighting, posters drawn from
    ``1000 seed + episode``) driven by the head scan; both detectors read the env's frames.
    """
    rng = np.random.default_rng(seed)
    picked = set(rng.choice(episodes * steps, size=images, replace=False).tolist())
    records: list[dict] = []
    for episode in range(episodes):
        env = gym.make(
            "SPL/ActiveVision-v0",
            frontend="colour",
            randomise_lighting=True,
            episode_s=steps * CONTROL_DT_S,
            **{"scene.scene_seed": 1000 * seed + episode, "control_dt_s": CONTROL_DT_S},
        )
        core = env.unwrapped
        assert isinstance(core, SplEnv)
        codes, geometry = core.scene.codes, core.config.scene.poles.geometry
        model = core.config.sensors.camera.model
        cnn = CnnPoleDetector(cnn_config, model, codes, geometry)
        colour = ColourPoleDetector(ColourFilterConfig(), model, codes, geometry)
        landmark_of = {pole_class_name(c): c.landmark_id for c in codes}
        policy = HeadScan.from_config(core.config)
        obs, _ = env.reset(seed=1000 * seed + episode)
        for step in range(steps):
            action, _ = policy.predict(obs, episode_start=np.array([step == 0]))
            obs, *_ = env.step(action)
            frame = core.sensor_frame
            if episode * steps + step not in picked or frame.image is None:
                continue
            assert frame.camera_state is not None  # the rig always reports it
            detections = cnn.detect_objects(frame.image)
            records.append(
                {
                    "episode": episode,
                    "step": step,
                    "truth": walking_truth(core, core.rig.camera_view(core.world)[1]),
                    "colour_filter": [
                        _observation_json(o) for o in colour.detect(frame.image, frame.camera_state)
                    ],
                    "cnn": [
                        _observation_json(o)
                        for o in cnn.observations(detections, frame.camera_state, frame.image)
                    ],
                    "cnn_objects": [
                        {
                            "class": d.class_name,
                            "box": d.box.tolist(),
                            "keypoint": d.keypoint.tolist(),
                            "score": d.score,
                            "landmark_id": landmark_of.get(d.class_name),
                        }
                        for d in detections
                    ],
                }
            )
        env.close()
    return summarise_walking(records), records


def _observations(items: list[dict]) -> list[LandmarkObservation]:
    return [
        LandmarkObservation(
            landmark_id=d["landmark_id"],
            range_m=d["range_m"],
            bearing_rad=d["bearing_rad"],
            cov=np.array(d["cov"]),
            pixel=np.array(d["pixel"]),
            box=np.array(d["box"]),
            score=d["score"],
        )
        for d in items
    ]


def summarise_walking(records: list[dict]) -> dict:
    """Table 4.2 figures per front end, and the CNN's other classes."""
    out: dict[str, Any] = {"images": len(records)}
    for name in FRONT_ENDS:
        frames = []
        centre_errors, junction_errors, ious = [], [], []
        true_negatives = 0
        for record in records:
            poles = {int(i): t for i, t in record["truth"]["poles"].items()}
            sightings = _observations(record[name])
            frames.append((sightings, poles))
            if not sightings and not any(t["in_view"] for t in poles.values()):
                true_negatives += 1
            keypoints = {
                o["landmark_id"]: o["keypoint"]
                for o in reversed(record["cnn_objects"])  # best score last: it wins
                if o["landmark_id"] is not None
            }
            for obs in sightings:
                t = poles[obs.landmark_id]
                ref = t["box"] if name == "cnn" else t["band_box"]
                if not is_true_positive(obs, t) or ref is None:
                    continue
                centre_errors.append(float(np.linalg.norm(_centre(obs.box) - _centre(ref))))
                ious.append(box_iou(obs.box, np.asarray(ref)))
                point = keypoints[obs.landmark_id] if name == "cnn" else obs.pixel
                junction_errors.append(float(np.linalg.norm(np.asarray(point) - t["junction"])))
        any_range = score(frames, math.inf)
        out[name] = {
            **{k: any_range["overall"][k] for k in ("tp", "fp", "fn", "precision", "recall")},
            "true_negative_images": true_negatives,
            "within_5m": score(frames, NEAR_M)["overall"],
            "localisation_error_px": float(np.mean(centre_errors)) if centre_errors else None,
            "junction_error_px": float(np.mean(junction_errors)) if junction_errors else None,
            "mean_iou": float(np.mean(ious)) if ious else None,
            "mean_abs_range_error_m": any_range["mean_abs_range_error_m"],
            "mean_abs_bearing_error_deg": any_range["mean_abs_bearing_error_deg"],
        }
    out["cnn_other_classes"] = _other_classes(records)
    return out


def _other_classes(records: list[dict]) -> dict[str, dict[str, int | float | None]]:
    """Per non-pole class: greedy IoU matches of CNN detections to labelled objects."""
    counts: dict[str, dict[str, int]] = {}
    for record in records:
        truth = record["truth"]["objects"]
        used = [False] * len(truth)
        for det in record["cnn_objects"]:
            if det["landmark_id"] is not None:
                continue
            c = counts.setdefault(det["class"], {"tp": 0, "fp": 0, "fn": 0})
            best, best_iou = -1, IOU_MATCH
            for j, obj in enumerate(truth):
                overlap = box_iou(np.asarray(det["box"]), np.asarray(obj["box"]))
                if obj["class"] == det["class"] and not used[j] and overlap >= best_iou:
                    best, best_iou = j, overlap
            if best >= 0:
                used[best] = True
                c["tp"] += 1
            else:
                c["fp"] += 1
        for j, obj in enumerate(truth):
            if not used[j] and obj["pixels"] >= MIN_VIEW_PX:
                counts.setdefault(obj["class"], {"tp": 0, "fp": 0, "fn": 0})["fn"] += 1
    return {
        name: {
            **c,
            "precision": c["tp"] / (c["tp"] + c["fp"]) if c["tp"] + c["fp"] else None,
            "recall": c["tp"] / (c["tp"] + c["fn"]) if c["tp"] + c["fn"] else None,
        }
        for name, c in sorted(counts.items())
    }


def markdown(summary: dict) -> str:
    """Seed 000 Table 4.2 analogue as a markdown table."""

    def fmt(value: float | None, spec: str) -> str:
        return "n/a" if value is None else format(value, spec)

    lines = [
        f"Front ends on {summary['images']} random frames of a walking robot (patrol, head scan, "
        "randomised lighting); any range.",
        "",
        "| front end | TP | FP | FN | TN images | precision | recall | localisation error (px) "
        "| junction error (px) | mean IoU |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    labels = {"colour_filter": "colour filter (boxes: bands)", "cnn": "CNN (boxes: whole pole)"}
    for name in FRONT_ENDS:
        s = summary[name]
        lines.append(
            f"| {labels[name]} | {s['tp']} | {s['fp']} | {s['fn']} | {s['true_negative_images']} "
            f"| {fmt(s['precision'], '.1%')} | {fmt(s['recall'], '.1%')} "
            f"| {fmt(s['localisation_error_px'], '.2f')} | {fmt(s['junction_error_px'], '.2f')} "
            f"| {fmt(s['mean_iou'], '.3f')} |"
        )
    lines += [
        "| seed 000 colour filter (Nao) | | | | | 97.4% | 65.8% | 8.20 | | |",
        "| seed 000 YOLOv8s (Nao) | 117 | 9 | 2 | 54 | 92.9% | 98.3% | | | 0.871 |",
        "| seed 000 YOLOv8m (Nao) | 119 | 7 | 1 | 51 | 94.4% | 99.2% | | | 0.878 |",
    ]
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--protocol", choices=("random", "walking"), required=True)
    parser.add_argument("--seed", type=int, default=1, help="held-out scene and episode seeds")
    parser.add_argument("--scenes", type=int, default=10, help="random: poster draws")
    parser.add_argument("--frames-per-scene", type=int, default=200, help="random: per scene")
    parser.add_argument("--episodes", type=int, default=3, help="walking: episodes")
    parser.add_argument("--steps", type=int, default=600, help="walking: steps per episode")
    parser.add_argument("--images", type=int, default=150, help="walking: frames evaluated")
    parser.add_argument("--score-threshold", type=float, default=CnnDetectorConfig.score_threshold)
    parser.add_argument(
        "--thresholds", type=float, nargs="*", default=[0.3, 0.4, 0.5, 0.6, 0.7, 0.8]
    )
    parser.add_argument("--weights", type=Path, default=None, help="CNN weights (the packaged)")
    parser.add_argument("--out", type=Path, default=RESULTS)
    args = parser.parse_args()
    torch.set_num_threads(1)
    cnn_config = CnnDetectorConfig(score_threshold=args.score_threshold)
    if args.weights is not None:
        cnn_config = dataclasses.replace(cnn_config, weights=args.weights)
    setting = {
        "protocol": args.protocol,
        "seed": args.seed,
        "cpu_count": os.cpu_count(),
        "torch_threads": torch.get_num_threads(),
        "cnn_score_threshold": args.score_threshold,
        "cnn_weights": cnn_config.weights.name,
    }
    args.out.mkdir(parents=True, exist_ok=True)
    if args.protocol == "random":
        setting |= {"scenes": args.scenes, "frames_per_scene": args.frames_per_scene}
        result = {
            "setting": setting,
            **run_random(
                args.seed, args.scenes, args.frames_per_scene, cnn_config, tuple(args.thresholds)
            ),
        }
        (args.out / "front_ends_random.json").write_text(json.dumps(result, indent=2) + "\n")
        print(json.dumps(result, indent=2))
        return
    setting |= {"episodes": args.episodes, "steps": args.steps}
    summary, records = run_walking(args.seed, args.episodes, args.steps, args.images, cnn_config)
    (args.out / "front_ends_walking.json").write_text(
        json.dumps({"setting": setting, **summary}, indent=2) + "\n"
    )
    (args.out / "front_ends_walking_predictions.json").write_text(json.dumps(records) + "\n")
    table = markdown(summary)
    (args.out / "front_ends_walking.md").write_text(table)
    print(json.dumps(summary, indent=2))
    print(table)


if __name__ == "__main__":
    main()
