"""Precision, recall, range/bearing errors and cost of the field-edge robot detector.

Runs :class:`perception.vision.robots.RobotDetector` (seed 004 §6.2, vision only: no sonar
confirmation) on rendered frames of ``SPL/ActiveVision-v0``: our robot walks its scripted patrol
among four other robots (two per team) that walk about. The head follows a scripted policy that
looks at one of the other robots (switching every 2 s, with a random offset of up to ±15° in yaw
and a random pitch), so that most frames show robots; every ``--stride``-th step is kept. The
image is the env's own rendered frame (sensor noise, motion blur, gait sway the camera state does
not report), under default lighting and under randomised lighting (``--lighting``). The figures
are given over all frames and, under ``sharp_frames``, over those without motion blur.

Ground truth per other robot, from ``env.unwrapped.world_state`` (range and bearing of its centre
from our robot) and the renderer's body-id labels (``env.unwrapped.rig.camera_view``):

- *visible*: at least ``MIN_VISIBLE_PX`` labelled pixels;
- *in view*: visible, its 3-D bounding box (a standing Nao, arms included) projects wholly inside
  the image (feet not cut off), and no nearer robot's projected box covers more than
  ``MAX_OCCLUDED_FRACTION`` of its own.

A detection is a true positive if it matches a visible robot: greedily by bearing error, within
``MATCH_BEARING_DEG`` and ``MATCH_RANGE_FRACTION`` of the true range, or within ``MATCH_MIN_M``
sideways and in range (one detection per robot); otherwise a false positive, classified by the
body most labelled in its box's lower half. Recall counts robots in view by their true range's
band; precision counts detections in the band of their robot's true range and in that of their
measured range (a false positive: the latter only), also for the team-coloured detections alone
(``team_precision``: what vision keeps without a sonar confirmation, Algorithm 2 lines 16-17;
a detection of the wrong team counts as false). Robots partly visible (visible, not in view) are
"don't care": found or missed, they count in neither recall nor, when found, as false positives.

Tuned on seeds 0-9 (``--seeds 0-9``); the published figures are on seeds 100-109 (the default),
under default and randomised lighting (``--lighting both``, the default)::

    python benchmarks/robot_detection.py --seeds 100-109
"""

from __future__ import annotations

import argparse
import json
import math
import time
from collections import Counter
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

import spl_env  # noqa: F401  (registers the envs)
from perception.geometry import FloatArray, range_bearing, wrap_angle
from perception.vision.robots import RobotDetector, RobotDetectorConfig
from spl_env.robots.nao import head_action
from spl_env.sensors.camera import CameraConfig, blur_length_px

BANDS_M = ((0.0, 1.0), (1.0, 2.0), (2.0, 3.0), (3.0, 5.0))
NEAR_M = 3.0  # the headline figures: robots (and detections) within 3 m
MIN_VISIBLE_PX = 30  # fewer labelled pixels: not visible
MAX_OCCLUDED_FRACTION = 0.3  # of a robot's projected box covered by nearer robots' boxes
MATCH_BEARING_DEG = 6.0
MATCH_RANGE_FRACTION = 0.3
MATCH_MIN_M = 0.2  # range and lateral errors up to this always match (a robot's body radius)
HEAD_SWITCH_S = 2.0
ROBOT_BOX = (0.06, 0.14, 0.54)  # half depth, half width (arms) and height (m) of a Nao
RESULTS = Path("benchmarks/results")


@dataclass
class Truth:
    """One other robot in one frame."""

    range_m: float
    bearing_rad: float
    team: int
    pixels: int
    in_view: bool


@dataclass
class Detection:
    """One sighting in one frame, with its match."""

    range_m: float
    bearing_rad: float
    team: int | None
    box: list[float]
    match: int | None = None  # index of the truth robot, None: false positive
    cause: str = ""  # for a false positive: the body most labelled under its box


@dataclass
class Frame:
    seed: int
    step: int
    truths: list[Truth] = field(default_factory=list)
    detections: list[Detection] = field(default_factory=list)
    seconds: float = 0.0
    rejections: dict[str, int] = field(default_factory=dict)  # candidates rejected, by reason
    blur_px: float = 0.0  # the frame's horizontal motion blur (px)


def parse_seeds(text: str) -> list[int]:
    """``"0-9"`` or ``"100,101,105-107"`` as a list of ints."""
    seeds: list[int] = []
    for part in text.split(","):
        if "-" in part:
            lo, hi = (int(x) for x in part.split("-"))
            seeds += list(range(lo, hi + 1))
        else:
            seeds.append(int(part))
    return seeds


def body_names(env: Any) -> dict[int, str]:
    """Body id -> category name (robot names, pole, goal_post, goal_frame, line, board...)."""
    u = env.unwrapped
    names: dict[int, str] = {-1: "sky", u.world.body("carpet"): "carpet"}
    for robot in u.robots:
        names[u.world.body(robot.name)] = robot.name
    for name in u.scene.bodies.poles.values():
        names[u.world.body(name)] = "pole"
    for name in u.scene.bodies.goal_posts:
        names[u.world.body(name)] = "goal_post"
    names[u.world.body(u.scene.bodies.ball)] = "ball"
    for prefix, label in (
        ("goal_frame_", "goal_frame"),
        ("field_lines_", "line"),
        ("board_", "board"),
    ):
        k = 0
        while True:
            try:
                names[u.world.body(f"{prefix}{k}")] = label
            except KeyError:
                break
            k += 1
    return names


def projected_box(
    eye: FloatArray, rotation: FloatArray, pose: FloatArray, model: Any
) -> tuple[FloatArray, bool]:
    """Image bounding box (4,) ``(u0, v0, u1, v1)`` of a Nao standing at ``pose`` and whether
    all its corners lie in front of the camera."""
    hx, hy, h = ROBOT_BOX
    c, s = math.cos(pose[2]), math.sin(pose[2])
    corners = np.array(
        [
            (pose[0] + c * x - s * y, pose[1] + s * x + c * y, z)
            for x in (-hx, hx)
            for y in (-hy, hy)
            for z in (0.0, h)
        ]
    )
    cam = (corners - eye) @ rotation
    front = bool((cam[:, 0] > 0.05).all())
    depth = np.maximum(cam[:, 0], 0.05)
    u = model.cx - model.fx * cam[:, 1] / depth
    v = model.cy - model.fy * cam[:, 2] / depth
    return np.array([u.min(), v.min(), u.max(), v.max()]), front


def frame_truth(env: Any, labels: np.ndarray) -> list[Truth]:
    """The other robots of the current frame with their visibility."""
    u = env.unwrapped
    state = u.world_state
    model = u.config.sensors.camera.model
    eye, rotation = u.robots[0].camera_pose_world()
    others = [u.robots[k] for k in state.others]
    rb = range_bearing(state.robot_pose, state.robots[:, :2])
    boxes = [projected_box(eye, rotation, r.pose, model) for r in others]
    out = []
    for k, robot in enumerate(others):
        pixels = int(np.count_nonzero(labels == u.world.body(robot.name)))
        box, front = boxes[k]
        inside = front and box[0] >= 0 and box[2] <= model.width - 1 and box[3] <= model.height - 1
        area = max((box[2] - box[0]) * (box[3] - box[1]), 1e-9)
        covered = 0.0
        for j, (other, other_front) in enumerate(boxes):
            if j == k or not other_front or rb[j, 0] >= rb[k, 0]:
                continue
            w = min(box[2], other[2]) - max(box[0], other[0])
            h = min(box[3], other[3]) - max(box[1], other[1])
            if w > 0 and h > 0:
                covered = max(covered, w * h / area)
        visible = pixels >= MIN_VISIBLE_PX
        out.append(
            Truth(
                range_m=float(rb[k, 0]),
                bearing_rad=float(rb[k, 1]),
                team=int(robot.team),
                pixels=pixels,
                in_view=bool(visible and inside and covered <= MAX_OCCLUDED_FRACTION),
            )
        )
    return out


def match(frame: Frame, labels: np.ndarray, names: dict[int, str]) -> None:
    """Greedy matching of detections to visible robots; names the false positives' causes."""
    pairs = []
    for i, det in enumerate(frame.detections):
        for k, truth in enumerate(frame.truths):
            if truth.pixels < MIN_VISIBLE_PX:
                continue
            db = abs(float(wrap_angle(det.bearing_rad - truth.bearing_rad)))
            dr = abs(det.range_m - truth.range_m)
            lateral = truth.range_m * math.sin(min(db, math.pi / 2))
            bearing_ok = db <= math.radians(MATCH_BEARING_DEG) or lateral <= MATCH_MIN_M
            if bearing_ok and dr <= max(MATCH_RANGE_FRACTION * truth.range_m, MATCH_MIN_M):
                pairs.append((db, i, k))
    used_d, used_t = set(), set()
    for _, i, k in sorted(pairs):
        if i in used_d or k in used_t:
            continue
        frame.detections[i].match = k
        used_d.add(i)
        used_t.add(k)
    for det in frame.detections:
        if det.match is None:
            u0, v0, u1, v1 = (round(x + 0.5) for x in det.box)
            window = labels[(v0 + v1) // 2 : max(v1, v0 + 1), u0 : max(u1, u0 + 1)]
            ids, counts = np.unique(window, return_counts=True)
            det.cause = names.get(int(ids[np.argmax(counts)]), "other") if len(ids) else "none"


def head_policy(env: Any, rng: np.random.Generator, target: int, offset: FloatArray) -> FloatArray:
    """Head action looking at other robot ``target`` (index among the others) plus ``offset``
    (yaw, pitch) rad."""
    u = env.unwrapped
    state = u.world_state
    rb = range_bearing(state.robot_pose, state.robots[target : target + 1, :2])[0]
    yaw = float(np.clip(rb[1] + offset[0], -2.0, 2.0))
    pitch = float(offset[1])
    return np.clip(head_action(u.config.robot, yaw, pitch), -1.0, 1.0).astype(np.float32)


def run_seed(
    seed: int, detector: RobotDetector, steps: int, stride: int, randomise: bool
) -> list[Frame]:
    env = gym.make(
        "SPL/ActiveVision-v0",
        frontend="colour",
        backend="classic",
        randomise_lighting=randomise,
        episode_s=steps * 0.1 + 1.0,
    )
    u = env.unwrapped
    names = body_names(env)
    rng = np.random.default_rng(10_000 + seed)
    env.reset(seed=seed)
    n_others = len(u.world_state.others)
    frames = []
    target, offset = 0, np.zeros(2)
    switch_every = round(HEAD_SWITCH_S / u.config.control_dt_s)
    for step in range(steps):
        if step % switch_every == 0:
            target = int(rng.integers(n_others))
            offset = np.array([rng.uniform(-0.26, 0.26), rng.uniform(0.0, 0.4)])
        env.step(head_policy(env, rng, target, offset))
        if step % stride:
            continue
        frame_data = u.sensor_frame
        assert frame_data.image is not None and frame_data.camera_state is not None
        _, labels = u.rig.camera_view(u.world)
        t0 = time.perf_counter()
        candidates = detector.candidates(frame_data.image, frame_data.camera_state)
        frame = Frame(seed=seed, step=step, seconds=time.perf_counter() - t0)
        cam = u.config.sensors.camera
        frame.blur_px = blur_length_px(u.camera_yaw_rate_rps, cam.exposure_time_s, cam.model.fx)
        sightings = [c.sighting for c in candidates if c.sighting is not None]
        frame.rejections = dict(Counter(c.rejected for c in candidates if c.rejected))
        frame.truths = frame_truth(env, labels)
        frame.detections = [
            Detection(s.range_m, s.bearing_rad, s.team, [float(x) for x in s.box])
            for s in sightings
        ]
        match(frame, labels, names)
        frames.append(frame)
    env.close()
    return frames


def band_of(range_m: float) -> str | None:
    for lo, hi in BANDS_M:
        if lo <= range_m < hi:
            return f"{lo:g}-{hi:g}"
    return None


def _ratio(num: int, den: int) -> float | None:
    return round(num / den, 4) if den else None


def summarise(frames: list[Frame]) -> dict[str, Any]:
    """Precision / recall per band and within NEAR_M, errors, team accuracy, causes, cost."""
    bands = [f"{lo:g}-{hi:g}" for lo, hi in BANDS_M] + [f"0-{NEAR_M:g}"]
    rec = {b: [0, 0] for b in bands}  # found, in view
    prec = {b: [0, 0] for b in bands}  # true, reported (all sightings)
    prec_team = {b: [0, 0] for b in bands}  # team-coloured sightings only
    rec_team = {b: [0, 0] for b in bands}
    errors: dict[str, list[tuple[float, float]]] = {b: [] for b in bands}
    team_right = team_wrong = team_none = 0
    causes: Counter[str] = Counter()
    partial_found = partial = 0

    def band_keys(r: float) -> list[str]:
        keys = [b] if (b := band_of(r)) else []
        return keys + ([f"0-{NEAR_M:g}"] if r < NEAR_M else [])

    for frame in frames:
        found = {d.match: d for d in frame.detections if d.match is not None}
        for k, truth in enumerate(frame.truths):
            if truth.in_view:
                for key in band_keys(truth.range_m):
                    rec[key][1] += 1
                    rec_team[key][1] += 1
                    if k in found:
                        rec[key][0] += 1
                        rec_team[key][0] += found[k].team == truth.team
            elif truth.pixels >= MIN_VISIBLE_PX:
                partial += 1
                partial_found += k in found
        for det in frame.detections:
            truth_k = frame.truths[det.match] if det.match is not None else None
            if truth_k is not None and not truth_k.in_view:
                continue  # a partly visible robot: don't care
            true_positive = truth_k is not None
            # precision by the band of the true range for hits and of the measured one else
            r = truth_k.range_m if truth_k is not None else det.range_m
            for key in band_keys(r) + [k for k in band_keys(det.range_m) if k not in band_keys(r)]:
                prec[key][1] += 1
                prec[key][0] += true_positive
                if det.team is not None:
                    prec_team[key][1] += 1
                    prec_team[key][0] += true_positive and det.team == truth_k.team  # type: ignore[union-attr]
            if truth_k is None:
                causes[det.cause] += 1
                continue
            for key in band_keys(truth_k.range_m):
                errors[key].append(
                    (
                        (det.range_m - truth_k.range_m) / truth_k.range_m,
                        float(wrap_angle(det.bearing_rad - truth_k.bearing_rad)),
                    )
                )
            if det.team is None:
                team_none += 1
            elif det.team == truth_k.team:
                team_right += 1
            else:
                team_wrong += 1
    out: dict[str, Any] = {"bands": {}}
    for key in bands:
        e = np.array(errors[key]).reshape(-1, 2)
        out["bands"][key] = {
            "in_view": rec[key][1],
            "recall": _ratio(*rec[key]),
            "recall_with_right_team": _ratio(*rec_team[key]),
            "detections": prec[key][1],
            "precision": _ratio(*prec[key]),
            "team_detections": prec_team[key][1],
            "team_precision": _ratio(*prec_team[key]),
            "range_rel_error_median": round(float(np.median(e[:, 0])), 4) if len(e) else None,
            "range_rel_abs_error_median": round(float(np.median(np.abs(e[:, 0]))), 4)
            if len(e)
            else None,
            "range_rel_abs_error_p90": round(float(np.percentile(np.abs(e[:, 0]), 90)), 4)
            if len(e)
            else None,
            "bearing_abs_error_median_deg": round(float(np.degrees(np.median(np.abs(e[:, 1])))), 3)
            if len(e)
            else None,
            "bearing_abs_error_p90_deg": round(
                float(np.degrees(np.percentile(np.abs(e[:, 1]), 90))), 3
            )
            if len(e)
            else None,
        }
    seconds = np.array([f.seconds for f in frames])
    out["team"] = {"right": team_right, "wrong": team_wrong, "none": team_none}
    out["false_positive_causes"] = dict(causes.most_common())
    out["partly_visible"] = {"robots": partial, "found": partial_found}
    rejections: Counter[str] = Counter()
    for frame in frames:
        rejections.update(frame.rejections)
    out["rejected_candidates"] = dict(rejections.most_common())
    out["frames"] = len(frames)
    out["ms_per_frame"] = {
        "mean": round(1e3 * float(seconds.mean()), 3),
        "p95": round(1e3 * float(np.percentile(seconds, 95)), 3),
    }
    return out


def _sharp(frames: list[Frame]) -> dict[str, Any]:
    """The band figures over the frames without motion blur."""
    sharp = [f for f in frames if f.blur_px == 0.0]
    return {"frames": len(sharp), "bands": summarise(sharp)["bands"]} if sharp else {}


def evaluate(
    detector: RobotDetector, seeds: list[int], steps: int, stride: int, randomise: bool
) -> tuple[dict[str, Any], list[Frame]]:
    """The summary over ``seeds`` (all frames, and the band figures of the sharp ones) and the
    frames."""
    frames: list[Frame] = []
    for seed in seeds:
        frames += run_seed(seed, detector, steps, stride, randomise)
    return {**summarise(frames), "sharp_frames": _sharp(frames)}, frames


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seeds", default="100-109", help="episode seeds, e.g. 0-9 or 100-109")
    parser.add_argument("--steps", type=int, default=300, help="control steps per episode")
    parser.add_argument("--stride", type=int, default=3, help="keep every stride-th step")
    parser.add_argument("--lighting", choices=("default", "randomised", "both"), default="both")
    parser.add_argument("--out", type=Path, default=RESULTS / "robot_detection.json")
    parser.add_argument("--dump", type=Path, default=None, help="per-frame records (JSON)")
    args = parser.parse_args()
    config = RobotDetectorConfig()
    detector = RobotDetector(config, CameraConfig().model)
    seeds = parse_seeds(args.seeds)
    result: dict[str, Any] = {
        "setting": {
            "env": "SPL/ActiveVision-v0",
            "seeds": args.seeds,
            "steps": args.steps,
            "stride": args.stride,
            "min_visible_px": MIN_VISIBLE_PX,
            "max_occluded_fraction": MAX_OCCLUDED_FRACTION,
            "match_bearing_deg": MATCH_BEARING_DEG,
            "match_range_fraction": MATCH_RANGE_FRACTION,
            "match_min_m": MATCH_MIN_M,
            "config": asdict(config),
        }
    }
    dumps: dict[str, list[dict[str, Any]]] = {}
    for lighting in ("default", "randomised"):
        if args.lighting in (lighting, "both"):
            summary, frames = evaluate(
                detector, seeds, args.steps, args.stride, lighting == "randomised"
            )
            result[f"{lighting}_lighting"] = summary
            dumps[lighting] = [asdict(f) for f in frames]
    if args.out is not None:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(json.dumps(result, indent=1) + "\n")
    if args.dump is not None:
        args.dump.write_text(json.dumps(dumps) + "\n")
    print(json.dumps({k: v for k, v in result.items() if k != "setting"}, indent=1))


if __name__ == "__main__":
    main()
