"""Precision, recall, errors and cost of field-feature detection on rendered frames.

Measures :func:`perception.vision.field_features.detect_field_features` with its default
:class:`~perception.vision.field_features.FieldFeatureConfig` on frames of the SPL field scene
(``spl_env.scenes.spl_field``, posters drawn with seed 0) rendered at random poses: our robot
standing still anywhere on the field (|x| < 4.8, |y| < 3.3 m, any heading), head yaw within
±1 rad and pitch 0.05-0.5 rad (no gait sway: the camera state is exact), with two other robots
and the ball placed at random on the field as clutter, the camera's sensor noise (std 2 levels)
and default lighting.

Truth comes from the field map (:class:`perception.field.field_map.FieldMap`) and the renderer's
body-id labels, not from the detector:

- a map **line** is *visible* where points sampled every 2 cm along it fall inside the image on
  pixels labelled as a painted line, within ``RANGE_M`` of the robot; it *should be found* when
  ``MIN_VISIBLE_M`` or more of it is visible;
- a **junction** (corner, T, X) should be found when its vertex and ``ARM_M`` of every arm
  (the map lines through it) are visible;
- the **centre circle** when a quarter of its circumference is visible; a **penalty mark**
  when its centre pixel is labelled painted line and clear of the image sides; a **goal post**
  when the pixels of its front 2 cm and ``POST_SEEN_M`` up are labelled as that post (the
  detector needs ``min_post_height_m`` of it in view);
- a **field edge** (the carpet's edge) when ``MIN_VISIBLE_M`` of it is visible: sampled
  points 2 cm inside the carpet fall on carpet pixels.

A detected line (or edge) is correct when both its ends (moved to the field frame with the true
pose) lie within ``tolerance`` of one map line (edge) segment: ``TOL_M`` plus ``TOL_SIGMA``
standard deviations of that end (its covariance's largest axis). A point feature is correct
within ``POINT_TOL_M`` (``FAR_POINT_TOL_M`` for goal posts), or ``TOL_SIGMA`` of its standard
deviations if more, of a map feature of its kind.
Recall: the share of those that should be found that a correct detection matches. Counts are
kept per kind and per kind and range band (``RANGE_BANDS_M``: a detection's distance from the
robot, a map feature's nearest point's). Errors: the
perpendicular distance of line ends to their map line, point distances, direction errors;
``nees`` the mean squared error over the variance along the error (a consistent covariance
gives about 1). Cost: milliseconds per frame of the detector alone (one thread).

``--row-offset`` (default 1, the pipeline's) tells the detector of the renderer's one-row
offset (``FieldFeatureConfig.row_offset_px``; 0: not told). Writes
``benchmarks/results/field_feature_detection.json`` (``--out``); 300 frames take about 10 s::

    python benchmarks/field_feature_detection.py --frames 300 --seed 100
    python benchmarks/field_feature_detection.py --frames 300 --seed 100 --row-offset 1 \
        --out benchmarks/results/field_feature_detection_row_offset.json
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import time
from collections import defaultdict
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from perception.field.features import FEATURE_KINDS, SEGMENT_KINDS, FeatureKind, FieldFeature
from perception.field.field_map import FieldMap, MapFeature
from perception.geometry import (
    FloatArray,
    invert,
    project_points,
    transform_points,
    wrap_angle,
)
from perception.types import CameraModel, CameraState
from perception.vision.field_features import FieldFeatureConfig, detect_field_features
from perception.vision.field_pixels import pixels_of
from spl_env.robots.nao import NaoRobot, RobotConfig
from spl_env.scenes.spl_field import SceneConfig, build_scene
from spl_env.sensors.camera import Camera, CameraConfig, EpisodeLighting
from spl_env.sim.world import BulletWorld

RANGE_M = 5.0
MIN_VISIBLE_M = 0.5
ARM_M = 0.3
TOL_M = 0.05
TOL_SIGMA = 3.0
POINT_TOL_M = 0.15
FAR_POINT_TOL_M = 0.3
STEP_M = 0.02
POST_SEEN_M = 0.5  # a post counts when in view from its foot to this height (m)
RESULTS = Path("benchmarks/results")


class Scene:
    """The field scene, our robot, two others and the ball; renders a frame at a pose."""

    def __init__(self) -> None:
        self.world = BulletWorld(time_step_s=0.01)
        self.bodies = build_scene(self.world, SceneConfig(), np.random.default_rng(0))
        self.robot = NaoRobot(self.world, "self", team=0, config=RobotConfig())
        self.others = [
            NaoRobot(self.world, f"other_{k}", team=k % 2, config=RobotConfig()) for k in range(2)
        ]
        self.camera = Camera(CameraConfig())
        self.carpet_id = self.world.body("carpet")
        self.line_ids = [
            self.world.body(f"field_lines_{k}") for k in range(8) if self._has(f"field_lines_{k}")
        ]
        self.post_ids = [self.world.body(name) for name in self.bodies.goal_posts]

    def _has(self, name: str) -> bool:
        try:
            self.world.body(name)
        except KeyError:
            return False
        return True

    def render(
        self, pose: FloatArray, head: FloatArray, rng: np.random.Generator
    ) -> tuple[np.ndarray, np.ndarray, CameraState]:
        """Image, labels and camera state with our robot at ``pose`` looking with ``head``."""
        self.robot.place(pose, head=head)
        position, rotation = self.robot.camera_pose_world()
        image, labels = self.camera.render(
            self.world, position, rotation, EpisodeLighting.default(), rng
        )
        return image, labels, self.robot.camera_state()

    def close(self) -> None:
        self.world.close()


def visible(
    points_field: FloatArray,
    pose: FloatArray,
    labels: np.ndarray,
    ids: list[int],
    camera: CameraModel,
    state: CameraState,
    margin_px: int = 2,
) -> np.ndarray:
    """(N,) whether field points are in view (inside the image by ``margin_px``, within
    ``RANGE_M``) on pixels labelled one of ``ids``."""
    robot = transform_points(invert(pose), points_field)
    uv = pixels_of(robot, camera, state)
    ok = np.isfinite(uv).all(axis=1) & (np.hypot(robot[:, 0], robot[:, 1]) <= RANGE_M)
    ok &= (uv[:, 0] >= margin_px) & (uv[:, 0] <= camera.width - 1 - margin_px)
    ok &= (uv[:, 1] >= margin_px) & (uv[:, 1] <= camera.height - 1 - margin_px)
    out = np.zeros(len(points_field), dtype=bool)
    rc = np.rint(uv[ok]).astype(int)
    out[ok] = np.isin(labels[rc[:, 1], rc[:, 0]], ids)
    return out


def samples(a: FloatArray, b: FloatArray) -> FloatArray:
    """Points every ``STEP_M`` from ``a`` to ``b`` (2,)."""
    n = max(int(np.hypot(*(b - a)) / STEP_M), 1) + 1
    return a + np.linspace(0, 1, n)[:, None] * (b - a)


def segment_distance(p: FloatArray, a: FloatArray, b: FloatArray) -> float:
    """Distance from ``p`` to the segment ``a``-``b``."""
    d = b - a
    t = float(np.clip((p - a) @ d / (d @ d), 0.0, 1.0))
    return float(np.hypot(*(p - a - t * d)))


def end_tolerance(cov: FloatArray) -> float:
    """``TOL_M`` plus ``TOL_SIGMA`` times the largest std of a (2, 2) covariance."""
    return TOL_M + TOL_SIGMA * math.sqrt(float(np.linalg.eigvalsh(cov).max()))


def match_segment(feature: FieldFeature, pose: FloatArray, targets: list[MapFeature]) -> int:
    """Index of the map segment both ends of ``feature`` lie near, or -1."""
    ends = transform_points(pose, feature.points)
    best, best_err = -1, math.inf
    for k, target in enumerate(targets):
        errs = [segment_distance(e, *target.points) for e in ends]
        near = all(err <= end_tolerance(c) for err, c in zip(errs, feature.cov, strict=True))
        if near and max(errs) < best_err:
            best, best_err = k, max(errs)
    return best


def nees(error: FloatArray, cov: FloatArray) -> float:
    """Normalised squared error of a (2,) error under a (2, 2) covariance."""
    return float(error @ np.linalg.solve(cov, error))


RANGE_BANDS_M = (2.0, 4.0)  # the counts are also kept per range band: < 2 m, 2-4 m, > 4 m


def _groups(kind: str, distance_m: float) -> tuple[str, str]:
    """The stats keys a count goes to: the kind's, and the kind's in its range band."""
    band = int(np.searchsorted(RANGE_BANDS_M, distance_m))
    names = ("< 2 m", "2-4 m", "> 4 m")
    return kind, f"{kind} {names[band]}"


def evaluate_frame(
    features: tuple[FieldFeature, ...],
    pose: FloatArray,
    labels: np.ndarray,
    scene: Scene,
    field: FieldMap,
    state: CameraState,
    stats: dict[str, Any],
) -> None:
    """Add one frame's matches and errors to ``stats`` (per kind lists and counters)."""
    cam = scene.camera.config.model
    segment_kinds: tuple[tuple[FeatureKind, list[int]], ...] = (
        ("line", scene.line_ids),
        ("field_edge", [scene.carpet_id]),
    )
    for kind, ids in segment_kinds:
        targets = list(field.of_kind(kind))
        found = set()
        for f in (f for f in features if f.kind == kind):
            k = match_segment(f, pose, targets)
            for group in _groups(kind, f.distance_m):
                stats[group]["detected"] += 1
                stats[group]["false"] += k < 0
            if k < 0:
                continue
            found.add(k)
            a, b = targets[k].points
            for end in transform_points(pose, f.points):
                stats[kind]["end_errors"].append(segment_distance(end, a, b))
        for k, target in enumerate(targets):
            pts = samples(*target.points)
            if kind == "field_edge":  # 2 cm inside the carpet
                inward = -np.sign(pts.mean(axis=0)) * (np.abs(pts.mean(axis=0)) > 1.0)
                pts = pts + STEP_M * inward
            if visible(pts, pose, labels, ids, cam, state).sum() * STEP_M >= MIN_VISIBLE_M:
                for group in _groups(kind, segment_distance(pose[:2], *target.points)):
                    stats[group]["should"] += 1
                    stats[group]["recalled"] += k in found
    lines = [t.points for t in field.of_kind("line")]
    for kind in (k for k in FEATURE_KINDS if k not in SEGMENT_KINDS):
        targets = list(field.of_kind(kind))
        tol = FAR_POINT_TOL_M if kind == "goal_post" else POINT_TOL_M
        found = set()
        for f in (f for f in features if f.kind == kind):
            p = transform_points(pose, f.points)[0]
            dists = [float(np.hypot(*(p - t.points[0]))) for t in targets]
            k = int(np.argmin(dists))
            wrong = dists[k] > max(
                tol, TOL_SIGMA * math.sqrt(float(np.linalg.eigvalsh(f.cov[0]).max()))
            )
            for group in _groups(kind, f.distance_m):
                stats[group]["detected"] += 1
                stats[group]["false"] += wrong
            if wrong:
                continue
            found.add(k)
            err = p - targets[k].points[0]
            # covariance to the field frame
            c, s = math.cos(pose[2]), math.sin(pose[2])
            rot = np.array([[c, -s], [s, c]])
            stats[kind]["errors"].append(dists[k])
            stats[kind]["nees"].append(nees(err, rot @ f.cov[0] @ rot.T))
            if f.direction is not None and targets[k].direction is not None:
                diff = wrap_angle(f.direction + pose[2] - targets[k].direction)
                if kind in ("x_junction", "centre_circle"):
                    diff = wrap_angle(2 * diff) / 2
                stats[kind]["direction_errors"].append(abs(float(diff)))
        for k, target in enumerate(targets):
            vertex = target.points[0]
            if kind == "centre_circle":
                ring = 0.75 * np.column_stack(
                    [np.cos(np.linspace(0, 2 * np.pi, 236)), np.sin(np.linspace(0, 2 * np.pi, 236))]
                )
                ok = visible(ring, pose, labels, scene.line_ids, cam, state).mean() >= 0.25
            elif kind == "goal_post":
                ok = _post_foot_visible(vertex, pose, labels, scene, cam, state)
            elif kind == "penalty_mark":
                ok = bool(visible(vertex[None], pose, labels, scene.line_ids, cam, state, 10)[0])
            else:
                arms = _arms(vertex, lines, field)
                ok = bool(visible(vertex[None], pose, labels, scene.line_ids, cam, state, 5)[0])
                for arm in arms:
                    pts = samples(vertex, vertex + ARM_M * arm)
                    ok &= visible(pts, pose, labels, scene.line_ids, cam, state).mean() >= 0.8
            if ok:
                for group in _groups(kind, float(np.hypot(*(vertex - pose[:2])))):
                    stats[group]["should"] += 1
                    stats[group]["recalled"] += k in found


def _post_foot_visible(
    post: FloatArray,
    pose: FloatArray,
    labels: np.ndarray,
    scene: Scene,
    cam: CameraModel,
    state: CameraState,
) -> bool:
    """Whether the front of a post (towards the robot) is seen on the post 2 cm up and
    ``POST_SEEN_M`` up (the detector needs that much of it in view)."""
    robot_xy = transform_points(invert(pose), post[None])[0]
    front = robot_xy - 0.05 * robot_xy / max(float(np.hypot(*robot_xy)), 1e-9)
    if np.hypot(*front) > RANGE_M:
        return False
    xyz = np.column_stack([np.tile(front, (2, 1)), [0.02, POST_SEEN_M]]) - state.position
    uv, ok = project_points(xyz @ state.rotation(), cam.fx, cam.fy, cam.cx, cam.cy)
    if not ok.all():
        return False
    u, v = np.rint(uv).astype(int).T
    if not ((u >= 4) & (u < cam.width - 4) & (v >= 4) & (v < cam.height - 4)).all():
        return False
    return bool(np.isin(labels[v, u], scene.post_ids).all())


def _arms(vertex: FloatArray, lines: list[FloatArray], field: FieldMap) -> list[FloatArray]:
    """Unit directions from ``vertex`` along the map lines (and circle) through it."""
    arms = []
    for a, b in lines:
        d = (b - a) / np.hypot(*(b - a))
        t = float((vertex - a) @ d)
        if segment_distance(vertex, a, b) > 1e-6:
            continue
        if t > 1e-6:
            arms.append(-d)
        if t < np.hypot(*(b - a)) - 1e-6:
            arms.append(d)
    if abs(abs(vertex[1]) - 0.75) < 1e-6 and abs(vertex[0]) < 1e-6:  # on the centre circle
        arms += [np.array([0.5, 0.0]), np.array([-0.5, 0.0])]  # tangents: half as far
    return arms


def random_frame(rng: np.random.Generator, scene: Scene) -> tuple[FloatArray, FloatArray]:
    """A random pose and head for our robot; the others and the ball placed as clutter."""
    pose = np.array([rng.uniform(-4.8, 4.8), rng.uniform(-3.3, 3.3), rng.uniform(-np.pi, np.pi)])
    head = np.array([rng.uniform(-1.0, 1.0), rng.uniform(0.05, 0.5)])
    for other in scene.others:
        other.place(
            np.array([rng.uniform(-4.5, 4.5), rng.uniform(-3, 3), rng.uniform(-np.pi, np.pi)])
        )
    return pose, head


def summary(stats: dict[str, Any]) -> dict[str, Any]:
    """Precision, recall and error statistics per kind."""
    out = {}
    for kind, s in stats.items():
        det, false = s["detected"], s["false"]
        entry = {
            "detected": det,
            "false": false,
            "precision": None if det == 0 else round(1 - false / det, 4),
            "should_find": s["should"],
            "recall": None if s["should"] == 0 else round(s["recalled"] / s["should"], 4),
        }
        for name in ("end_errors", "errors", "direction_errors", "nees"):
            values = np.asarray(s.get(name, []), dtype=np.float64)
            if len(values):
                entry[name] = {
                    "median": round(float(np.median(values)), 4),
                    "p90": round(float(np.percentile(values, 90)), 4),
                    "max": round(float(values.max()), 4),
                    "mean": round(float(values.mean()), 4),
                }
        out[kind] = entry
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=200)
    parser.add_argument("--seed", type=int, default=100)
    parser.add_argument("--out", type=Path, default=RESULTS / "field_feature_detection.json")
    parser.add_argument(
        "--row-offset", type=float, default=1.0, help="FieldFeatureConfig.row_offset_px"
    )
    args = parser.parse_args()
    cv2.setNumThreads(1)
    scene = Scene()
    field = FieldMap()
    config = FieldFeatureConfig(row_offset_px=args.row_offset)
    rng = np.random.default_rng(args.seed)

    def empty() -> dict[str, Any]:
        return {"detected": 0, "false": 0, "should": 0, "recalled": 0} | {
            k: [] for k in ("end_errors", "errors", "direction_errors", "nees")
        }

    stats: dict[str, Any] = defaultdict(empty)
    times = []
    for _ in range(args.frames):
        pose, head = random_frame(rng, scene)
        scene.world.set_pose("ball", (rng.uniform(-4.5, 4.5), rng.uniform(-3, 3), 0.05), 0.0)
        image, labels, state = scene.render(pose, head, rng)
        start = time.perf_counter()
        features = detect_field_features(image, scene.camera.config.model, state, config)
        times.append(time.perf_counter() - start)
        evaluate_frame(features, pose, labels, scene, field, state, stats)
    scene.close()
    report = {
        "frames": args.frames,
        "seed": args.seed,
        "config": dataclasses.asdict(config),
        "ms_per_frame": {
            "median": round(1000 * float(np.median(times)), 2),
            "p90": round(1000 * float(np.percentile(times, 90)), 2),
            "max": round(1000 * float(np.max(times)), 2),
        },
        "kinds": summary(stats),
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(report, indent=1))
    print(json.dumps({k: v for k, v in report.items() if k != "config"}, indent=1))


if __name__ == "__main__":
    main()
