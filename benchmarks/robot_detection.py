"""Precision, recall, range/bearing errors and cost of three robot-detection front ends.

Measures, on the same rendered walking frames, the three robot-sighting front ends of
:data:`perception.pipeline.PROVIDERS` (``robot_sightings``), with the configurations of
``PipelineConfig()``'s defaults (``vision_robots``, ``sonar_filter``, ``cnn_robots``, ``cnn``):

- ``vision``: :class:`perception.vision.robots.RobotDetector` alone (seed 004 §6.2 without the
  sonar check), every sighting kept, team-coloured or not (the ``vision_only`` provider);
- ``vision_sonar``: seed 004's complete Algorithm 2 (the ``vision`` provider): the detector's
  sightings through :func:`perception.tracking.sonar_filter.confirm_with_sonar` against the
  observations of a :class:`~perception.tracking.sonar_filter.SonarFilter` that is reset at each
  episode's start and updated with the env's sonar reading (``sensor_frame.sonar``) on every env
  step, the reset's included, kept frame or not (it is a rolling window over steps). A sighting
  the sonar confirms takes the sonar's range; one with neither team colour nor confirmation is
  dropped;
- ``cnn``: the packaged CNN's ``robot`` class: ``robot_sightings`` on the CNN detector's
  ``detect_objects`` (the ``cnn`` provider, the pipeline's default); no team.

The frames: ``SPL/ActiveVision-v0``, our robot walks its scripted patrol among four other robots
(two per team) that walk about. The head follows a scripted policy that looks at one of the other
robots (switching every 2 s, with a random offset of up to ±15° in yaw and a random pitch), so that
most frames show robots; every ``--stride``-th step is kept. The image is the env's own rendered
frame (sensor noise, motion blur, gait sway the camera state does not report), under default
lighting and under randomised lighting (``--lighting``). The figures are given over all frames
and, under ``sharp_frames``, over those without motion blur.

Ground truth per other robot, from ``env.unwrapped.world_state`` (range and bearing of its centre
from our robot) and the renderer's body-id labels (``env.unwrapped.rig.camera_view``):

- *visible*: at least ``MIN_VISIBLE_PX`` labelled pixels;
- *in view*: visible, its 3-D bounding box (a standing Nao, arms included) projects wholly inside
  the image (feet not cut off), and no nearer robot's projected box covers more than
  ``MAX_OCCLUDED_FRACTION`` of its own.

Each front end's detections are matched on their own. A detection is a true positive if it
matches a visible robot: greedily by bearing error, within ``MATCH_BEARING_DEG`` and
``MATCH_RANGE_FRACTION`` of the true range, or within ``MATCH_MIN_M`` sideways and in range (one
detection per robot); otherwise a false positive, classified by the body most labelled in its
box's lower half. Recall counts robots in view by their true range's band (0-1, 1-2, 2-3, 3-5 m
and the headline 0-3 m); precision counts detections in the band of their robot's true range and
in that of their measured range (a false positive: the latter only), also for the team-coloured
detections alone (``team_precision``; a detection of the wrong team counts as false). Robots
partly visible (visible, not in view) are "don't care": found or missed, they count in neither
recall nor, when found, as false positives. Per band also: the relative range error (median,
median absolute, 90th percentile, std and the robust std 1.4826 MAD) and the bearing error
(median absolute, 90th percentile, std) of the true positives, and for ``vision_sonar`` the share
sonar-confirmed and the range errors of confirmed and unconfirmed sightings apart.

Cost per frame (ms, one thread; torch is limited to one thread): ``vision`` the detector
(``RobotDetector.candidates``); ``vision_sonar`` the detector plus that step's filter update plus
the check; ``cnn`` the CNN's ``detect_objects`` (forward pass and decoding) plus
``robot_sightings``. Rendering and ground truth are not counted.

The JSON: ``vision``, ``vision_sonar`` and ``cnn`` each hold ``default_lighting`` and
``randomised_lighting`` summaries (``bands``, ``within_3m``, ``team``, ``false_positive_causes``,
``ms_per_frame``, ``sharp_frames``...); the top-level ``default_lighting`` and
``randomised_lighting`` repeat the ``vision`` ones (the layout before the other front ends were
added); ``acceptance`` checks vision + sonar within 3 m against recall and precision >= 0.95.

``emulator_fit`` (per lighting and pooled): the figures a fast geometric emulator of the
``vision`` provider (vision + sonar: truth through a detection chance and a noise model) is fitted
to, over robots in view: per band the recall, the shares of true positives with the right team,
no team and the wrong team, the share sonar-confirmed (of all, and of those the sonar can hear,
*audible*: the robot's centre lies in one of the sonar's cones, seen from the transducers, at a
distance within the sonar's range; the head turns, so many robots in view are not), the relative
range error (mean, std, robust std) of confirmed and of unconfirmed sightings (and of confirmed
ones in metres) and the bearing error; and the false positives per frame (by measured-range band,
with their team and confirmation shares). Fit it on the tuning seeds' output, not on the
reporting seeds'.

Seeds: the detector and this protocol were tuned on seeds 0-9; the published figures are on
seeds 100-109 (the default), under default and randomised lighting (``--lighting both``, the
default). Each run also writes a markdown table next to its JSON (``--out`` with ``.md``)::

    python benchmarks/robot_detection.py --seeds 0-9 \\
        --out benchmarks/results/robot_detection_tuning.json   # tuning: emulator_fit from here
    python benchmarks/robot_detection.py --seeds 100-109       # reporting (held out)
    python benchmarks/robot_detection.py --tables benchmarks/results/robot_detection.json

(the last only rewrites a result's markdown). Each run takes about 7 minutes on one core.
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
from numpy.typing import NDArray

import spl_env  # noqa: F401  (registers the envs)
from perception.geometry import FloatArray, range_bearing, wrap_angle
from perception.pipeline import PipelineConfig
from perception.providers.base import PerceptionContext
from perception.tracking.sonar_filter import SonarFilter, audible, confirm_with_sonar
from perception.types import RobotSighting
from perception.vision.cnn_robots import robot_sightings
from perception.vision.robots import RobotDetector
from spl_env.robots.nao import head_action
from spl_env.sensors.camera import CameraConfig, blur_length_px

FRONT_ENDS = ("vision", "vision_sonar", "cnn")
BANDS_M = ((0.0, 1.0), (1.0, 2.0), (2.0, 3.0), (3.0, 5.0))
NEAR_M = 3.0  # the headline figures: robots (and detections) within 3 m
NEAR = f"0-{NEAR_M:g}"
TARGET = 0.95  # the acceptance: recall and precision within 3 m with vision + sonar
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
    audible: bool = False  # its centre in a sonar cone and its distance in the sonar's range


@dataclass
class Detection:
    """One sighting in one frame, with its match."""

    range_m: float
    bearing_rad: float
    team: int | None
    box: list[float]
    sonar_confirmed: bool = False
    match: int | None = None  # index of the truth robot, None: false positive
    cause: str = ""  # for a false positive: the body most labelled under its box


@dataclass
class Frame:
    seed: int
    step: int
    truths: list[Truth] = field(default_factory=list)
    detections: dict[str, list[Detection]] = field(default_factory=dict)  # by front end
    # seconds of the parts: vision (detector), filter, check, cnn_net, cnn_sightings
    seconds: dict[str, float] = field(default_factory=dict)
    rejections: dict[str, int] = field(default_factory=dict)  # candidates rejected, by reason
    sonar_dropped: int = 0  # vision sightings without team and sonar confirmation
    blur_px: float = 0.0  # the frame's horizontal motion blur (px)

    def cost_s(self, front_end: str) -> float:
        """Seconds ``front_end`` spent on this frame."""
        parts = {
            "vision": ("vision",),
            "vision_sonar": ("vision", "filter", "check"),
            "cnn": ("cnn_net", "cnn_sightings"),
        }[front_end]
        return sum(self.seconds[p] for p in parts)


@dataclass
class FrontEnds:
    """The three front ends' parts, configured as ``PipelineConfig()``'s defaults."""

    config: PipelineConfig
    detector: RobotDetector
    cnn: Any = None  # perception.vision.cnn_detector.CnnPoleDetector, built with the first env

    @classmethod
    def build(cls) -> FrontEnds:
        config = PipelineConfig()
        return cls(config, RobotDetector(config.vision_robots, CameraConfig().model))

    def cnn_detector(self, env: Any) -> Any:
        if self.cnn is None:
            u = env.unwrapped
            context = PerceptionContext(
                u.config.sensors.camera.model, u.scene.codes, u.config.scene.poles.geometry
            )
            self.cnn = context.cnn_detector(self.config.cnn)
        return self.cnn


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


def wholly_in_view(env: Any) -> NDArray[np.bool_]:
    """(R,) whether each other robot's projected standing box (feet included) lies wholly
    inside our camera image and at most ``MAX_OCCLUDED_FRACTION`` of it is covered by a nearer
    robot's box: the geometric half of *in view* (module doc)."""
    u = env.unwrapped
    state = u.world_state
    model = u.config.sensors.camera.model
    eye, rotation = u.robots[0].camera_pose_world()
    ranges = range_bearing(state.robot_pose, state.robots[:, :2])[:, 0]
    boxes = [projected_box(eye, rotation, u.robots[k].pose, model) for k in state.others]
    out = np.zeros(len(boxes), dtype=bool)
    for k, (box, front) in enumerate(boxes):
        inside = front and box[0] >= 0 and box[2] <= model.width - 1 and box[3] <= model.height - 1
        if not inside:
            continue
        area = max((box[2] - box[0]) * (box[3] - box[1]), 1e-9)
        covered = 0.0
        for j, (other, other_front) in enumerate(boxes):
            if j == k or not other_front or ranges[j] >= ranges[k]:
                continue
            w = min(box[2], other[2]) - max(box[0], other[0])
            h = min(box[3], other[3]) - max(box[1], other[1])
            if w > 0 and h > 0:
                covered = max(covered, w * h / area)
        out[k] = covered <= MAX_OCCLUDED_FRACTION
    return out


def frame_truth(env: Any, labels: np.ndarray) -> list[Truth]:
    """The other robots of the current frame with their visibility."""
    u = env.unwrapped
    state = u.world_state
    others = [u.robots[k] for k in state.others]
    rb = range_bearing(state.robot_pose, state.robots[:, :2])
    geometric = wholly_in_view(env)
    out = []
    for k, robot in enumerate(others):
        pixels = int(np.count_nonzero(labels == u.world.body(robot.name)))
        out.append(
            Truth(
                range_m=float(rb[k, 0]),
                bearing_rad=float(rb[k, 1]),
                team=int(robot.team),
                pixels=pixels,
                in_view=bool(pixels >= MIN_VISIBLE_PX and geometric[k]),
                audible=audible(u.sensor_frame.sonar_model, float(rb[k, 0]), float(rb[k, 1])),
            )
        )
    return out


def match(
    detections: list[Detection], truths: list[Truth], labels: np.ndarray, names: dict[int, str]
) -> None:
    """Greedy matching of detections to visible robots; names the false positives' causes."""
    pairs = []
    for i, det in enumerate(detections):
        for k, truth in enumerate(truths):
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
        detections[i].match = k
        used_d.add(i)
        used_t.add(k)
    for det in detections:
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


def _detections(sightings: Any) -> list[Detection]:
    return [
        Detection(
            s.range_m, s.bearing_rad, s.team, [float(x) for x in s.box], bool(s.sonar_confirmed)
        )
        for s in sightings
    ]


def run_seed(seed: int, parts: FrontEnds, steps: int, stride: int, randomise: bool) -> list[Frame]:
    env = gym.make(
        "SPL/ActiveVision-v0",
        frontend="colour",
        backend="classic",
        randomise_lighting=randomise,
        episode_s=steps * 0.1 + 1.0,
    )
    u = env.unwrapped
    names = body_names(env)
    config = parts.config
    cnn = parts.cnn_detector(env)
    sonar = SonarFilter(config.sonar_filter)
    rng = np.random.default_rng(10_000 + seed)
    env.reset(seed=seed)
    sonar.reset()
    sonar.update(u.sensor_frame.time_s, u.sensor_frame.sonar)  # the pipeline sees it too
    n_others = len(u.world_state.others)
    frames = []
    target, offset = 0, np.zeros(2)
    switch_every = round(HEAD_SWITCH_S / u.config.control_dt_s)
    for step in range(steps):
        if step % switch_every == 0:
            target = int(rng.integers(n_others))
            offset = np.array([rng.uniform(-0.26, 0.26), rng.uniform(0.0, 0.4)])
        env.step(head_policy(env, rng, target, offset))
        data = u.sensor_frame
        assert data.sonar is not None and data.sonar_model is not None
        t0 = time.perf_counter()
        observations = sonar.update(data.time_s, data.sonar)
        filter_s = time.perf_counter() - t0
        if step % stride:
            continue
        assert data.image is not None and data.camera_state is not None
        assert data.camera is not None
        _, labels = u.rig.camera_view(u.world)
        t0 = time.perf_counter()
        candidates = parts.detector.candidates(data.image, data.camera_state)
        t1 = time.perf_counter()
        sightings: list[RobotSighting] = [c.sighting for c in candidates if c.sighting is not None]
        t2 = time.perf_counter()
        checked = confirm_with_sonar(sightings, observations, data.sonar_model, config.sonar_filter)
        t3 = time.perf_counter()
        objects = cnn.detect_objects(data.image)
        t4 = time.perf_counter()
        cnn_sightings = robot_sightings(objects, data.camera, data.camera_state, config.cnn_robots)
        t5 = time.perf_counter()
        frame = Frame(
            seed=seed,
            step=step,
            seconds={
                "vision": t1 - t0,
                "filter": filter_s,
                "check": t3 - t2,
                "cnn_net": t4 - t3,
                "cnn_sightings": t5 - t4,
            },
        )
        cam = u.config.sensors.camera
        frame.blur_px = blur_length_px(u.camera_yaw_rate_rps, cam.exposure_time_s, cam.model.fx)
        frame.rejections = dict(Counter(c.rejected for c in candidates if c.rejected))
        frame.sonar_dropped = len(sightings) - len(checked)
        frame.truths = frame_truth(env, labels)
        frame.detections = {
            "vision": _detections(sightings),
            "vision_sonar": _detections(checked),
            "cnn": _detections(cnn_sightings),
        }
        for detections in frame.detections.values():
            match(detections, frame.truths, labels, names)
        frames.append(frame)
    env.close()
    return frames


def band_of(range_m: float) -> str | None:
    for lo, hi in BANDS_M:
        if lo <= range_m < hi:
            return f"{lo:g}-{hi:g}"
    return None


def band_keys(range_m: float) -> list[str]:
    """The band of ``range_m`` and the headline band when within NEAR_M."""
    keys = [b] if (b := band_of(range_m)) else []
    return keys + ([NEAR] if range_m < NEAR_M else [])


BANDS = [f"{lo:g}-{hi:g}" for lo, hi in BANDS_M] + [NEAR]


def _ratio(num: int, den: int) -> float | None:
    return round(num / den, 4) if den else None


def _round(x: float, digits: int = 4) -> float:
    return round(float(x), digits)


def _robust_std(x: np.ndarray) -> float:
    return float(1.4826 * np.median(np.abs(x - np.median(x))))


def range_errors(rel: list[float]) -> dict[str, Any]:
    """Relative range errors: count, median, median absolute, p90 absolute, std, robust std."""
    e = np.asarray(rel, dtype=np.float64)
    if not len(e):
        return {"n": 0}
    return {
        "n": len(e),
        "median": _round(np.median(e)),
        "abs_median": _round(np.median(np.abs(e))),
        "abs_p90": _round(np.percentile(np.abs(e), 90)),
        "std": _round(e.std()),
        "robust_std": _round(_robust_std(e)),
    }


def summarise(frames: list[Frame], front_end: str) -> dict[str, Any]:
    """Precision / recall per band and within NEAR_M, errors, team accuracy, causes, cost."""
    rec = {b: [0, 0] for b in BANDS}  # found, in view
    prec = {b: [0, 0] for b in BANDS}  # true, reported (all sightings)
    prec_team = {b: [0, 0] for b in BANDS}  # team-coloured sightings only
    rec_team = {b: [0, 0] for b in BANDS}
    # per true positive: relative range error, bearing error (rad), sonar-confirmed
    errors: dict[str, list[tuple[float, float, bool]]] = {b: [] for b in BANDS}
    team_right = team_wrong = team_none = 0
    causes: Counter[str] = Counter()
    partial_found = partial = 0

    for frame in frames:
        detections = frame.detections[front_end]
        found = {d.match: d for d in detections if d.match is not None}
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
        for det in detections:
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
                        det.sonar_confirmed,
                    )
                )
            if det.team is None:
                team_none += 1
            elif det.team == truth_k.team:
                team_right += 1
            else:
                team_wrong += 1
    out: dict[str, Any] = {"bands": {}}
    for key in BANDS:
        e = np.array([x[:2] for x in errors[key]]).reshape(-1, 2)
        n = len(e)
        band: dict[str, Any] = {
            "in_view": rec[key][1],
            "recall": _ratio(*rec[key]),
            "recall_with_right_team": _ratio(*rec_team[key]),
            "detections": prec[key][1],
            "precision": _ratio(*prec[key]),
            "team_detections": prec_team[key][1],
            "team_precision": _ratio(*prec_team[key]),
            "range_rel_error_median": _round(np.median(e[:, 0])) if n else None,
            "range_rel_abs_error_median": _round(np.median(np.abs(e[:, 0]))) if n else None,
            "range_rel_abs_error_p90": _round(np.percentile(np.abs(e[:, 0]), 90)) if n else None,
            "range_rel_error_std": _round(e[:, 0].std()) if n else None,
            "range_rel_error_robust_std": _round(_robust_std(e[:, 0])) if n else None,
            "bearing_abs_error_median_deg": _round(np.degrees(np.median(np.abs(e[:, 1]))), 3)
            if n
            else None,
            "bearing_abs_error_p90_deg": _round(np.degrees(np.percentile(np.abs(e[:, 1]), 90)), 3)
            if n
            else None,
            "bearing_error_std_deg": _round(np.degrees(e[:, 1].std()), 3) if n else None,
        }
        if front_end == "vision_sonar":
            confirmed = [x[2] for x in errors[key]]
            band["share_confirmed"] = _ratio(sum(confirmed), n)
            band["range_rel_error_confirmed"] = range_errors([x[0] for x in errors[key] if x[2]])
            band["range_rel_error_unconfirmed"] = range_errors(
                [x[0] for x in errors[key] if not x[2]]
            )
        out["bands"][key] = band
    out["within_3m"] = {"recall": out["bands"][NEAR]["recall"]}
    out["within_3m"]["precision"] = out["bands"][NEAR]["precision"]
    team_total = team_right + team_wrong + team_none
    out["team"] = {
        "right": team_right,
        "wrong": team_wrong,
        "none": team_none,
        "right_share": _ratio(team_right, team_total),
        "right_of_team_given": _ratio(team_right, team_right + team_wrong),
    }
    out["false_positive_causes"] = dict(causes.most_common())
    out["partly_visible"] = {"robots": partial, "found": partial_found}
    rejections: Counter[str] = Counter()
    for frame in frames:
        if front_end != "cnn":
            rejections.update(frame.rejections)
        if front_end == "vision_sonar" and frame.sonar_dropped:
            rejections["no_team_no_sonar"] += frame.sonar_dropped
    out["rejected_candidates"] = dict(rejections.most_common())
    out["frames"] = len(frames)
    out["ms_per_frame"] = _cost(frames, front_end)
    return out


def _cost(frames: list[Frame], front_end: str) -> dict[str, Any]:
    """Mean and p95 cost per frame (ms), and the mean of each part."""
    seconds = np.array([f.cost_s(front_end) for f in frames])
    parts = {
        "vision": (),
        "vision_sonar": ("vision", "filter", "check"),
        "cnn": ("cnn_net", "cnn_sightings"),
    }[front_end]
    return {
        "mean": _round(1e3 * seconds.mean(), 3),
        "p95": _round(1e3 * np.percentile(seconds, 95), 3),
        **{f"{p}_mean": _round(1e3 * np.mean([f.seconds[p] for f in frames]), 3) for p in parts},
    }


def _sharp(frames: list[Frame], front_end: str) -> dict[str, Any]:
    """The band figures over the frames without motion blur."""
    sharp = [f for f in frames if f.blur_px == 0.0]
    return {"frames": len(sharp), "bands": summarise(sharp, front_end)["bands"]} if sharp else {}


def _error_stats(x: list[float]) -> dict[str, Any]:
    e = np.asarray(x, dtype=np.float64)
    if not len(e):
        return {"n": 0}
    return {
        "n": len(e),
        "mean": _round(e.mean()),
        "std": _round(e.std()),
        "robust_std": _round(_robust_std(e)),
    }


def emulator_fit(frames: list[Frame]) -> dict[str, Any]:
    """What a geometric emulator of ``vision_sonar`` needs, over robots in view (module doc)."""
    keys = [f"{lo:g}-{hi:g}" for lo, hi in BANDS_M] + ["all"]
    in_view = dict.fromkeys(keys, 0)
    tps: dict[str, list[tuple[Detection, Truth]]] = {k: [] for k in keys}
    fps: list[Detection] = []
    for frame in frames:
        detections = frame.detections["vision_sonar"]
        found = {d.match: d for d in detections if d.match is not None}
        for k, truth in enumerate(frame.truths):
            if not truth.in_view:
                continue
            for key in [b for b in (band_of(truth.range_m),) if b] + ["all"]:
                in_view[key] += 1
                if k in found:
                    tps[key].append((found[k], truth))
        fps += [d for d in detections if d.match is None]
    n_frames = max(len(frames), 1)
    bands: dict[str, Any] = {}
    for key in keys:
        hits = tps[key]
        n = len(hits)
        rel = [((d.range_m - t.range_m) / t.range_m, d.sonar_confirmed) for d, t in hits]
        heard = [(d, t) for d, t in hits if t.audible]
        bands[key] = {
            "in_view": in_view[key],
            "recall": _ratio(n, in_view[key]),
            "true_positives": n,
            "team_right": _ratio(sum(d.team == t.team for d, t in hits), n),
            "team_none": _ratio(sum(d.team is None for d, _ in hits), n),
            "team_wrong": _ratio(sum(d.team is not None and d.team != t.team for d, t in hits), n),
            "share_confirmed": _ratio(sum(d.sonar_confirmed for d, _ in hits), n),
            # confirmation hinges on the sonar hearing the robot at all (module doc: audible)
            "share_audible": _ratio(len(heard), n),
            "share_confirmed_audible": _ratio(sum(d.sonar_confirmed for d, _ in heard), len(heard)),
            "share_confirmed_inaudible": _ratio(
                sum(d.sonar_confirmed for d, t in hits if not t.audible), n - len(heard)
            ),
            "range_rel_error_confirmed": _error_stats([e for e, c in rel if c]),
            "range_error_confirmed_m": _error_stats(
                [d.range_m - t.range_m for d, t in hits if d.sonar_confirmed]
            ),
            "range_rel_error_unconfirmed": _error_stats([e for e, c in rel if not c]),
            "bearing_error_deg": _error_stats(
                [math.degrees(float(wrap_angle(d.bearing_rad - t.bearing_rad))) for d, t in hits]
            ),
        }
    by_band = Counter(band_of(d.range_m) or "beyond" for d in fps)
    return {
        "front_end": "vision_sonar",
        "frames": len(frames),
        "bands": bands,
        "false_positives": {
            "count": len(fps),
            "per_frame": _round(len(fps) / n_frames),
            "per_frame_by_measured_band": {
                b: _round(by_band[b] / n_frames) for b in [*keys[:-1], "beyond"]
            },
            "team_given": _ratio(sum(d.team is not None for d in fps), len(fps)),
            "share_confirmed": _ratio(sum(d.sonar_confirmed for d in fps), len(fps)),
        },
    }


def evaluate(
    parts: FrontEnds, seeds: list[int], steps: int, stride: int, randomise: bool
) -> list[Frame]:
    """The frames of ``seeds``, every front end's detections matched."""
    frames: list[Frame] = []
    for seed in seeds:
        frames += run_seed(seed, parts, steps, stride, randomise)
    return frames


def _fmt(x: float | None, pct: bool = True) -> str:
    if x is None:
        return "-"
    return f"{100 * x:.1f}" if pct else f"{x:.2f}"


def markdown(result: dict[str, Any]) -> str:
    """Tables of the result: headline, per band, cost, vision + sonar's confirmation, fit."""
    s = result["setting"]
    lines = [
        "# Robot detection: vision, vision + sonar, CNN",
        "",
        f"`benchmarks/robot_detection.py --seeds {s['seeds']}` ({s['episodes']} episodes x "
        f"{s['steps']} steps, every step k with k % {s['stride']} == 0 kept; robots in view as "
        "the module docstring defines). Percentages; range errors relative to the true range.",
        "",
    ]
    lightings = [k for k in ("default_lighting", "randomised_lighting") if k in result["vision"]]
    lines += [
        f"## Within {NEAR_M:g} m (target for vision + sonar: recall and precision >= "
        f"{100 * TARGET:.0f} %)",
        "",
        "| front end | lighting | in view | recall | detections | precision |",
        "|---|---|---:|---:|---:|---:|",
    ]
    for fe in FRONT_ENDS:
        for li in lightings:
            b = result[fe][li]["bands"][NEAR]
            lines.append(
                f"| {fe} | {li.split('_')[0]} | {b['in_view']} | {_fmt(b['recall'])} | "
                f"{b['detections']} | {_fmt(b['precision'])} |"
            )
    lines += [
        "",
        "## By range band",
        "",
        "| front end | lighting | band (m) | in view | recall | precision | team prec. | "
        "range abs err median | range err std | range err robust std | bearing err std (deg) |",
        "|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for fe in FRONT_ENDS:
        for li in lightings:
            for band in BANDS[:-1]:
                b = result[fe][li]["bands"][band]
                lines.append(
                    f"| {fe} | {li.split('_')[0]} | {band} | {b['in_view']} | "
                    f"{_fmt(b['recall'])} | {_fmt(b['precision'])} | "
                    f"{_fmt(b['team_precision'])} | {_fmt(b['range_rel_abs_error_median'])} | "
                    f"{_fmt(b['range_rel_error_std'])} | "
                    f"{_fmt(b['range_rel_error_robust_std'])} | "
                    f"{_fmt(b['bearing_error_std_deg'], pct=False)} |"
                )
    lines += [
        "",
        "## Cost per frame (ms, one thread)",
        "",
        "| front end | lighting | mean | p95 | parts (mean) |",
        "|---|---|---:|---:|---|",
    ]
    for fe in FRONT_ENDS:
        for li in lightings:
            c = result[fe][li]["ms_per_frame"]
            parts = ", ".join(f"{k[:-5]} {v:.2f}" for k, v in c.items() if k.endswith("_mean"))
            lines.append(
                f"| {fe} | {li.split('_')[0]} | {c['mean']:.2f} | {c['p95']:.2f} | {parts} |"
            )
    lines += [
        "",
        "## Team of the true positives",
        "",
        "| front end | lighting | right | wrong | none |",
        "|---|---|---:|---:|---:|",
    ]
    for fe in ("vision", "vision_sonar"):
        for li in lightings:
            t = result[fe][li]["team"]
            lines.append(
                f"| {fe} | {li.split('_')[0]} | {t['right']} | {t['wrong']} | {t['none']} |"
            )
    lines += [
        "",
        "## Vision + sonar: confirmed and unconfirmed sightings (relative range error)",
        "",
        "| lighting | band (m) | confirmed | conf. median | conf. abs median | conf. std | "
        "unconf. median | unconf. abs median | unconf. std |",
        "|---|---|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for li in lightings:
        for band in BANDS:
            b = result["vision_sonar"][li]["bands"][band]
            c, u = b["range_rel_error_confirmed"], b["range_rel_error_unconfirmed"]
            lines.append(
                f"| {li.split('_')[0]} | {band} | {_fmt(b['share_confirmed'])} | "
                f"{_fmt(c.get('median'))} | {_fmt(c.get('abs_median'))} | {_fmt(c.get('std'))} | "
                f"{_fmt(u.get('median'))} | {_fmt(u.get('abs_median'))} | {_fmt(u.get('std'))} |"
            )
    fit = result.get("emulator_fit", {}).get("pooled")
    if fit:
        lines += [
            "",
            "## Emulator fit (vision + sonar, robots in view, both lightings pooled)",
            "",
            "| band (m) | recall | team right | none | wrong | confirmed | audible | "
            "confirmed if audible | conf. range mean / std | unconf. range mean / std | "
            "bearing std (deg) |",
            "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
        ]
        for band, b in fit["bands"].items():
            conf, unconf = b["range_rel_error_confirmed"], b["range_rel_error_unconfirmed"]
            lines.append(
                f"| {band} | {_fmt(b['recall'])} | {_fmt(b['team_right'])} | "
                f"{_fmt(b['team_none'])} | {_fmt(b['team_wrong'])} | "
                f"{_fmt(b['share_confirmed'])} | {_fmt(b['share_audible'])} | "
                f"{_fmt(b['share_confirmed_audible'])} | "
                f"{_fmt(conf.get('mean'))} / {_fmt(conf.get('std'))} | "
                f"{_fmt(unconf.get('mean'))} / {_fmt(unconf.get('std'))} | "
                f"{_fmt(b['bearing_error_deg'].get('std'), pct=False)} |"
            )
        fp = fit["false_positives"]
        lines += ["", f"False positives per frame: {fp['per_frame']:.3f}."]
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seeds", default="100-109", help="episode seeds, e.g. 0-9 or 100-109")
    parser.add_argument("--steps", type=int, default=300, help="control steps per episode")
    parser.add_argument("--stride", type=int, default=3, help="keep every stride-th step")
    parser.add_argument("--lighting", choices=("default", "randomised", "both"), default="both")
    parser.add_argument("--out", type=Path, default=RESULTS / "robot_detection.json")
    parser.add_argument("--dump", type=Path, default=None, help="per-frame records (JSON)")
    parser.add_argument(
        "--tables", type=Path, default=None, help="only write the markdown of this result JSON"
    )
    args = parser.parse_args()
    if args.tables is not None:
        args.tables.with_suffix(".md").write_text(markdown(json.loads(args.tables.read_text())))
        return
    import torch

    torch.set_num_threads(1)
    parts = FrontEnds.build()
    seeds = parse_seeds(args.seeds)
    config = parts.config
    result: dict[str, Any] = {
        "setting": {
            "env": "SPL/ActiveVision-v0",
            "seeds": args.seeds,
            "episodes": len(seeds),
            "steps": args.steps,
            "stride": args.stride,
            "min_visible_px": MIN_VISIBLE_PX,
            "max_occluded_fraction": MAX_OCCLUDED_FRACTION,
            "match_bearing_deg": MATCH_BEARING_DEG,
            "match_range_fraction": MATCH_RANGE_FRACTION,
            "match_min_m": MATCH_MIN_M,
            "front_ends": list(FRONT_ENDS),
            "config": asdict(config.vision_robots),
            "sonar_filter": asdict(config.sonar_filter),
            "cnn_robots": asdict(config.cnn_robots),
            "cnn": {
                k: Path(v).name if k == "weights" else str(v)  # no host paths in the results
                for k, v in asdict(config.cnn).items()
            },
            "torch_threads": 1,
            "note": "default_lighting / randomised_lighting: the vision front end (as before "
            "the other front ends were added); every front end under its own key",
        }
    }
    for fe in FRONT_ENDS:
        result[fe] = {}
    dumps: dict[str, list[dict[str, Any]]] = {}
    all_frames: list[Frame] = []
    fits: dict[str, Any] = {}
    for lighting in ("default", "randomised"):
        if args.lighting not in (lighting, "both"):
            continue
        frames = evaluate(parts, seeds, args.steps, args.stride, lighting == "randomised")
        key = f"{lighting}_lighting"
        for fe in FRONT_ENDS:
            result[fe][key] = {**summarise(frames, fe), "sharp_frames": _sharp(frames, fe)}
        result[key] = result["vision"][key]
        fits[key] = emulator_fit(frames)
        all_frames += frames
        dumps[lighting] = [asdict(f) for f in frames]
    fits["pooled"] = emulator_fit(all_frames)
    result["acceptance"] = {
        key: {
            "recall": result["vision_sonar"][key]["within_3m"]["recall"],
            "precision": result["vision_sonar"][key]["within_3m"]["precision"],
            "met": all(
                (result["vision_sonar"][key]["within_3m"][m] or 0.0) >= TARGET
                for m in ("recall", "precision")
            ),
        }
        for key in result["vision_sonar"]
    }
    result["emulator_fit"] = {
        "note": "fit the emulator on the tuning seeds' (0-9) output; this run's seeds: "
        + args.seeds,
        **fits,
    }
    if args.out is not None:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(json.dumps(result, indent=1) + "\n")
        args.out.with_suffix(".md").write_text(markdown(result))
    if args.dump is not None:
        args.dump.write_text(json.dumps(dumps) + "\n")
    print(json.dumps({"acceptance": result["acceptance"]}, indent=1))
    print(markdown(result))


if __name__ == "__main__":
    main()
