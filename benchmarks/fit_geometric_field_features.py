"""Fit the geometric camera mode's field features to the rendered field-feature detector.

    python benchmarks/fit_geometric_field_features.py      # ~4 min on one core

Runs ``SPL/ActiveVision-NoPoles-v1`` with rendered frames (default lighting, the patrol walk
among four other robots, the ``vision`` field-feature provider: the top camera) under two head
policies, the ``scan`` baseline (:class:`agents.baselines.HeadScan`, level pitch) and random
head targets (:class:`RandomTargets`, each held ``HOLD_S``), ``--episodes`` of ``--seconds``
each on seeds ``--seed`` .. ``--seed + --episodes - 1`` (tuning seeds, 0-4 by default; 100 and
up are kept for reporting). Every frame it compares what the detector found with the map's
features in view of the camera the joints report at the robot's true pose, exactly
(:func:`perception.field.visibility.visible_features` without noise, out to ``BANDS_M[-1]``),
as the emulator (:mod:`spl_env.sensors.emulation.field`) does:

- the rendered camera sways with the gait, which the joints do not report: the emulator
  reproduces that exactly (each point where the joints' camera places the pixel the true
  camera sees it at, :func:`~spl_env.sensors.emulation.field.reprojected`), so the errors
  fitted here are measured from the features so moved (and reported in all, from the exact
  ones, as ``median_abs_total_m``);
- a detection is matched to a map feature with the sway taken out (placed by the true camera)
  as ``benchmarks/field_feature_detection.py`` matches them (both ends of a line near one map
  line; a point within ``POINT_TOL_M``, ``FAR_POINT_TOL_M`` for posts, or ``TOL_SIGMA`` of its
  standard deviations), to a feature in view or else counted as a false detection (no map
  feature) or one outside the exact view.

Fits, per feature kind, the emulator's :class:`~perception.field.visibility.DetectorModel`
(``model`` in the JSON):

- ``recall``: of the features in view, the share the detector found, per range band
  (``BANDS_M``; the feature's nearest point's distance, as placed); a band with fewer than
  ``MIN_IN_BAND`` features in view is pooled with its neighbours (the nearer first), and one
  with no detection in it or farther gets 0;
- ``point_std_m``: the position error's standard deviation per axis, ``a + b * range``
  (maximum likelihood, zero-mean isotropic Gaussian; a line's ends by their distance across
  the line only: where a seen stretch ends along it is no measurement), refitted without the
  gross errors beyond ``OUTLIER_SIGMAS`` of the fit (their share is reported; the emulator
  makes none);
- ``direction_std_rad``: the direction error's RMS (axial kinds modulo pi), without the gross
  errors beyond ``OUTLIER_SIGMAS`` robust standard deviations;
- ``reported_direction_std_rad``: the direction standard deviation the detector reports, as
  the one with the same mean information (``1 / sqrt(mean(1 / std**2))``).

The detector's covariances need no fit: the emulator reports the detector's own covariance
model at each point. ``cov_scale`` (``std_scale`` for directions) checks that: the RMS of the
errors in all over the reported standard deviation along them, for the detector and, under
``at_fit``, for the emulator run with the fitted model at the same frames (with its recall and
noise, measured as the detector's).

Also reported, not emulated: false detections per frame, detections outside the exact view,
recall per head policy and with a still or a turning camera (motion blur), and the pieces a
found line or edge is detected in.

Writes ``geometric_field_features.json`` to ``--out`` (``benchmarks/results``);
``DetectorModel``'s defaults cite it.
"""

from __future__ import annotations

import argparse
import dataclasses
import itertools
import json
import math
import time
from collections import defaultdict
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from field_feature_detection import (
    FAR_POINT_TOL_M,
    POINT_TOL_M,
    TOL_SIGMA,
    match_segment,
    segment_distance,
)
from numpy.typing import NDArray
from scipy.optimize import minimize

import spl_env  # noqa: F401  (registers the env ids)
from agents.baselines import HeadScan
from perception.field.features import AXIAL_KINDS, FEATURE_KINDS, SEGMENT_KINDS, FieldFeature
from perception.field.field_map import FieldMap, MapFeature
from perception.field.visibility import (
    DIRECTION_KINDS,
    DetectorModel,
    FeatureViewConfig,
    visible_features,
)
from perception.geometry import FloatArray, transform_points, wrap_angle
from perception.pipeline import PipelineConfig
from perception.providers.field import VisionFieldFeatures
from perception.representations import FIELD_FEATURES
from perception.types import CameraModel, CameraState
from spl_env.envs.core import SplEnv
from spl_env.robots.nao import head_action
from spl_env.sensors.camera import blur_length_px
from spl_env.sensors.emulation.field import (
    CameraPose,
    GeometricFieldFeatures,
    joints_camera,
    occlusion,
    reprojected,
    true_camera,
)

BANDS_M = (1.0, 2.0, 3.0, 4.0, 6.0, 8.0)  # upper edges of the range bands (m)
MIN_IN_BAND = 20  # fewer features in view in a band: pooled with the neighbours
OUTLIER_SIGMAS = 5.0  # errors beyond this many fitted stds are gross, not noise
CUT_ROUNDS = 10  # refits without the gross errors, at most
HOLD_S = 1.0  # a random head target is held this long (s)
PITCH_MIN_RAD = -0.1  # random pitch from a little up to the joint's lowest (looking higher,
# the camera sees little but the far field's edge)
POLICIES = ("scan", "random")
# the features in view, as the emulator judges them: to the last band's edge, hidden where a
# body stands in front, a post only with the detector's cut-post height of it in the image
IN_VIEW = FeatureViewConfig(
    max_range_m=BANDS_M[-1],
    post_seen_height_m=PipelineConfig().field_detector.min_cut_post_height_m,
)


class RandomTargets:
    """Head targets uniform over the yaw joint's range and pitch from ``PITCH_MIN_RAD`` down
    to the joint's limit, each held ``HOLD_S``."""

    def __init__(self, env: gym.Env, rng: np.random.Generator) -> None:
        config = env.get_wrapper_attr("config")
        self.robot, self.hold = config.robot, max(1, round(HOLD_S / config.control_dt_s))
        self.rng, self.steps, self.action = rng, 0, np.zeros(2, dtype=np.float32)

    def predict(self, obs: Any, episode_start: Any = None) -> tuple[np.ndarray, None]:
        if self.steps % self.hold == 0:
            yaw = self.rng.uniform(-self.robot.head_yaw_limit_rad, self.robot.head_yaw_limit_rad)
            pitch = self.rng.uniform(PITCH_MIN_RAD, self.robot.head_pitch_max_rad)
            action = head_action(self.robot, yaw, pitch)
            self.action = np.clip(action, -1.0, 1.0).astype(np.float32)
        self.steps += 1
        return self.action, None


def map_index(feature: FieldFeature, pose: FloatArray, targets: tuple[MapFeature, ...]) -> int:
    """Which of ``targets`` (the map's features of its kind) an exact ``feature`` is."""
    field = transform_points(pose, feature.points)
    if feature.kind in SEGMENT_KINDS:
        errors = [max(segment_distance(p, *t.points) for p in field) for t in targets]
    else:
        errors = [float(np.hypot(*(field[0] - t.points[0]))) for t in targets]
    return int(np.argmin(errors))


def match_point(feature: FieldFeature, pose: FloatArray, targets: tuple[MapFeature, ...]) -> int:
    """The map feature a detected point feature matches, or -1: the nearest of ``targets``
    within ``POINT_TOL_M`` (``FAR_POINT_TOL_M`` for a post) or ``TOL_SIGMA`` of its standard
    deviations (``benchmarks/field_feature_detection.py``'s rule)."""
    p = transform_points(pose, feature.points)[0]
    dists = [float(np.hypot(*(p - t.points[0]))) for t in targets]
    k = int(np.argmin(dists))
    tol = FAR_POINT_TOL_M if feature.kind == "goal_post" else POINT_TOL_M
    sigma = math.sqrt(float(np.linalg.eigvalsh(feature.cov[0]).max()))
    return k if dists[k] <= max(tol, TOL_SIGMA * sigma) else -1


def match(feature: FieldFeature, pose: FloatArray, targets: tuple[MapFeature, ...]) -> int:
    """The map feature (index into ``targets``) a detection matches, or -1."""
    if feature.kind in SEGMENT_KINDS:
        return match_segment(feature, pose, list(targets))
    return match_point(feature, pose, targets)


def direction_error(kind: str, detected: float, truth: float) -> float:
    """Detected minus true direction (rad), modulo pi for the axial kinds."""
    diff = float(wrap_angle(detected - truth))
    return float(wrap_angle(2 * diff)) / 2 if kind in AXIAL_KINDS else diff


@dataclass(frozen=True)
class Frame:
    """One rendered frame: the robot's true pose, the joints' camera state, the true camera
    (robot frame), what the detector found, the head policy, the frame's motion blur, and the
    occlusion verdicts of the map's ground points asked about in it (field-frame point ->
    hidden), recorded while its world was live."""

    pose: FloatArray
    state: CameraState
    seen_by: CameraPose
    detected: tuple[FieldFeature, ...]
    policy: str
    blur_px: float
    hidden: dict[tuple[float, float], bool]

    def occluded(self, points: FloatArray) -> NDArray[np.bool_]:
        """The recorded verdicts of ``points`` (N, 2) (KeyError for one never asked)."""
        return np.array([self.hidden[(float(x), float(y))] for x, y in points], dtype=bool)


def compare(
    frame: Frame,
    detected: tuple[FieldFeature, ...],
    field_map: FieldMap,
    camera: CameraModel,
    rows: dict[str, list],
) -> None:
    """Add one frame's features in view (found or not), errors and unmatched detections to
    ``rows``. Detections are matched to the map as the true camera saw them (the sway taken
    out); errors are measured against the features in view as the joints' camera places them
    (the sway left in: the emulator adds it), and in all against the exact ones."""
    exact = visible_features(
        field_map, frame.pose, camera, frame.state, IN_VIEW, occluded=frame.occluded
    )
    placed_by = joints_camera(frame.state)
    targets = {kind: field_map.of_kind(kind) for kind in FEATURE_KINDS}
    truth = {}
    for t in exact:
        swayed = reprojected(t, frame.seen_by, placed_by, camera)
        if swayed is not None:
            truth[(t.kind, map_index(t, frame.pose, targets[t.kind]))] = (t, swayed)
    found: dict[tuple[str, int], list[FieldFeature]] = defaultdict(list)
    for f in detected:
        unswayed = reprojected(f, placed_by, frame.seen_by, camera)
        k = -1 if unswayed is None else match(unswayed, frame.pose, targets[f.kind])
        if k >= 0 and (f.kind, k) in truth:
            found[(f.kind, k)].append(f)
        else:
            status = "false" if k < 0 else "outside_view"
            rows["extra"].append({"kind": f.kind, "status": status, "range_m": f.distance_m})
    for key, (t, swayed) in truth.items():
        hits = found.get(key, [])
        rows["visible"].append(
            {
                "kind": t.kind,
                "range_m": swayed.distance_m,  # as the emulator, which sways it first, sees it
                "found": bool(hits),
                "pieces": len(hits),
                "policy": frame.policy,
                "blur_px": frame.blur_px,
            }
        )
        for f in hits[:1] if t.kind not in SEGMENT_KINDS else hits:
            _errors(f, swayed, t, rows)


def _errors(f: FieldFeature, swayed: FieldFeature, t: FieldFeature, rows: dict[str, list]) -> None:
    """The errors of detection ``f`` of the feature in view ``t`` (``swayed``: as the joints'
    camera places it): position and direction against ``swayed`` (the noise to fit), and
    normalised by the reported covariance against ``t`` (what the sensor model sees)."""
    if f.kind in SEGMENT_KINDS:
        for end, cov in zip(f.points, f.cov, strict=True):
            err, _ = _across(end, swayed.points)
            total, normal_t = _across(end, t.points)
            rows["errors"].append(
                {
                    "kind": f.kind,
                    "range_m": float(np.hypot(*end)),
                    "error": [err],
                    "total": [total],
                    "normalised": [total / math.sqrt(float(normal_t @ cov @ normal_t))],
                }
            )
        return
    err = f.points[0] - swayed.points[0]
    total = f.points[0] - t.points[0]
    rows["errors"].append(
        {
            "kind": f.kind,
            "range_m": float(np.hypot(*swayed.points[0])),
            "error": err.tolist(),
            "total": total.tolist(),
            # the total error over the reported std along each axis (x, y)
            "normalised": (total / np.sqrt(np.diag(f.cov[0]))).tolist(),
        }
    )
    if f.direction is not None and swayed.direction is not None and t.direction is not None:
        rows["directions"].append(
            {
                "kind": f.kind,
                "error": direction_error(f.kind, f.direction, swayed.direction),
                "total": direction_error(f.kind, f.direction, t.direction),
                "reported_std": f.direction_std,
            }
        )


def _across(point: FloatArray, segment: FloatArray) -> tuple[float, FloatArray]:
    """Signed distance of ``point`` from the line through ``segment`` (2, 2), and its normal."""
    a, b = segment
    along = (b - a) / np.hypot(*(b - a))
    normal = np.array([-along[1], along[0]])
    return float((point - a) @ normal), normal


def collect(episodes: int, seconds: float, seed: int) -> tuple[list[Frame], FieldMap, CameraModel]:
    """The rendered frames of every policy and episode, with the detector's features."""
    env = gym.make("SPL/ActiveVision-NoPoles-v1", episode_s=seconds)
    core = env.unwrapped
    if not isinstance(core, SplEnv):
        raise TypeError(f"the fit needs an SplEnv, got {type(core).__name__}")
    provider = core.pipeline.provider(FIELD_FEATURES)
    if type(provider) is not VisionFieldFeatures:
        raise TypeError(f"the fit needs the top camera's detector, got {type(provider).__name__}")
    camera = core.config.sensors.camera
    ours = core.robots[0]
    field_map = FieldMap(core.scene.dimensions)
    posts = core.scene.goal_post_body_ids()
    frames = []
    policies: dict[str, Any] = {
        "scan": HeadScan.from_config(core.config),
        "random": RandomTargets(env, np.random.default_rng(seed)),
    }
    for name, policy in policies.items():
        for k in range(episodes):
            obs, _ = env.reset(seed=seed + k)
            done, step = False, 0
            while not done:
                action, _ = policy.predict(obs, episode_start=np.array([step == 0]))
                obs, _, terminated, truncated, _ = env.step(action)
                done, step = terminated or truncated, step + 1
                state = core.sensor_frame.camera_state
                if state is None:
                    raise RuntimeError("the rendered frame holds no camera state")
                blur = blur_length_px(
                    core.camera_yaw_rate_rps, camera.exposure_time_s, camera.model.fx
                )
                hidden = RecordedOcclusion(
                    occlusion(core.world, ours.camera_pose_world()[0], posts)
                )
                visible_features(
                    field_map, ours.pose, camera.model, state, IN_VIEW, occluded=hidden
                )  # asks about every ground point the comparison and the emulator will
                frames.append(
                    Frame(
                        pose=ours.pose.copy(),
                        state=state,
                        seen_by=true_camera(ours, "top"),
                        detected=core.perception_output[FIELD_FEATURES],
                        policy=name,
                        blur_px=blur,
                        hidden=hidden.verdicts,
                    )
                )
    env.close()
    return frames, field_map, camera.model


class RecordedOcclusion:
    """``occluded`` that keeps each verdict it gives (``verdicts``: point -> hidden)."""

    def __init__(self, occluded: Callable[[FloatArray], NDArray[np.bool_]]) -> None:
        self._occluded = occluded
        self.verdicts: dict[tuple[float, float], bool] = {}

    def __call__(self, points: FloatArray) -> NDArray[np.bool_]:
        hidden = np.asarray(self._occluded(points), dtype=bool)
        for (x, y), h in zip(points.tolist(), hidden.tolist(), strict=True):
            self.verdicts[(x, y)] = h
        return hidden


def rows_of(
    frames: list[Frame],
    field_map: FieldMap,
    camera: CameraModel,
    emulator: GeometricFieldFeatures | None = None,
    seed: int = 0,
) -> dict[str, Any]:
    """The comparison rows of the detector's features in ``frames`` or, with ``emulator``,
    of the emulated ones at the same poses and cameras."""
    rows: dict[str, Any] = {"visible": [], "errors": [], "directions": [], "extra": []}
    rng = np.random.default_rng(seed)
    for frame in frames:
        detected = (
            frame.detected
            if emulator is None
            else emulator.emulate(frame.pose, frame.state, frame.seen_by, rng, frame.occluded)
        )
        compare(frame, detected, field_map, camera, rows)
    rows["frames"] = len(frames)
    return rows


def band_of(range_m: float) -> int:
    """The index of the range band ``range_m`` falls in (``len(BANDS_M)`` beyond them)."""
    return int(np.searchsorted(BANDS_M, range_m, side="left"))


def fit_recall(visible: list[dict[str, Any]]) -> dict[str, Any]:
    """Per band: features in view, found, the measured and the configured recall (module
    docstring)."""
    counts = np.zeros(len(BANDS_M), dtype=int)
    hits = np.zeros(len(BANDS_M), dtype=int)
    for v in visible:
        band = band_of(v["range_m"])
        if band < len(BANDS_M):
            counts[band] += 1
            hits[band] += v["found"]
    measured = [round(float(h / c), 3) if c else None for h, c in zip(hits, counts, strict=True)]
    configured = []
    for band in range(len(BANDS_M)):
        c, h, reach = counts[band], hits[band], 0
        while c < MIN_IN_BAND and reach < len(BANDS_M):
            reach += 1
            for other in (band - reach, band + reach):
                if 0 <= other < len(BANDS_M) and c < MIN_IN_BAND:
                    c, h = c + counts[other], h + hits[other]
        # where the detector found nothing that far or farther, it does not see that far
        configured.append(round(float(h / c), 3) if c and hits[band:].sum() else 0.0)
    return {
        "in_view": counts.tolist(),
        "found": hits.tolist(),
        "measured": measured,
        "configured": configured,
    }


def fit_noise(errors: list[dict[str, Any]]) -> dict[str, Any]:
    """``a + b * range`` for the per-axis std of the errors, by maximum likelihood, gross
    errors left out; the reported covariances' scale over the same (module docstring)."""
    e = [np.asarray(r["error"]) for r in errors]
    d = np.concatenate([np.full(len(x), r["range_m"]) for x, r in zip(e, errors, strict=True)])
    err = np.concatenate(e)
    total = np.concatenate([np.asarray(r["total"]) for r in errors])
    normalised = np.concatenate([np.asarray(r["normalised"]) for r in errors])
    # gross errors: beyond OUTLIER_SIGMAS of the fit (which grows with the range as the noise
    # does), refitted without them until none is left out anew
    keep = np.ones(len(err), dtype=bool)
    for _ in range(CUT_ROUNDS):
        a, b = _ml_std(d[keep], err[keep])
        again = np.abs(err) <= OUTLIER_SIGMAS * (a + b * d)
        if (again == keep).all():
            break
        keep = again
    return {
        "samples": len(err),
        "gross_share": round(float((~keep).mean()), 4),
        "a_m": round(a, 4),
        "b_per_m": round(b, 4),
        "rms_m": round(float(np.sqrt(np.mean(err[keep] ** 2))), 4),
        "median_abs_m": round(float(np.median(np.abs(err))), 4),
        "median_abs_total_m": round(float(np.median(np.abs(total))), 4),
        "cov_scale": round(float(np.sqrt(np.mean(normalised[keep] ** 2))), 3),
        "by_band": _band_rms(d[keep], err[keep], a, b),
    }


def _ml_std(d: FloatArray, err: FloatArray) -> tuple[float, float]:
    """(a, b) >= (1e-4, 0) maximising the likelihood of zero-mean ``err`` with std a + b d."""

    def nll(x: FloatArray) -> float:
        std = x[0] + x[1] * d
        return float(np.sum(np.log(std) + 0.5 * (err / std) ** 2))

    start = np.array([max(float(np.std(err)), 1e-3), 0.0])
    res = minimize(nll, start, bounds=[(1e-4, None), (0.0, None)], method="L-BFGS-B")
    return float(res.x[0]), float(res.x[1])


def _band_rms(d: FloatArray, err: FloatArray, a: float, b: float) -> list[dict[str, Any]]:
    """Per band: samples, the measured RMS and the fit's at the band's mean range."""
    out = []
    for lo, hi in itertools.pairwise((0.0, *BANDS_M)):
        inside = (d > lo) & (d <= hi)
        if inside.any():
            out.append(
                {
                    "band_m": [lo, hi],
                    "samples": int(inside.sum()),
                    "rms_m": round(float(np.sqrt(np.mean(err[inside] ** 2))), 4),
                    "fit_m": round(a + b * float(np.mean(d[inside])), 4),
                }
            )
    return out


def fit_direction(directions: list[dict[str, Any]]) -> dict[str, Any]:
    """The direction error's RMS (gross errors left out), the reported stds' information
    equivalent and the reports' scale over the errors in all."""
    err = np.array([r["error"] for r in directions])
    total = np.array([r["total"] for r in directions])
    reported = np.array([r["reported_std"] for r in directions])
    robust = max(1.4826 * float(np.median(np.abs(err))), 1e-3)
    keep = np.abs(err) <= OUTLIER_SIGMAS * robust
    return {
        "samples": len(err),
        "gross_share": round(float((~keep).mean()), 4),
        "std_rad": round(max(float(np.sqrt(np.mean(err[keep] ** 2))), 1e-4), 4),
        "median_abs_rad": round(float(np.median(np.abs(err))), 4),
        "reported_std_rad": round(float(1.0 / np.sqrt(np.mean(1.0 / reported**2))), 4),
        "std_scale": round(float(np.sqrt(np.mean((total[keep] / reported[keep]) ** 2))), 3),
    }


def summary(rows: dict[str, Any]) -> dict[str, Any]:
    """Per kind: the fit, and what it leaves out (module docstring)."""
    kinds: dict[str, Any] = {}
    frames = rows["frames"]
    for kind in FEATURE_KINDS:
        visible = [v for v in rows["visible"] if v["kind"] == kind]
        entry: dict[str, Any] = {"recall": fit_recall(visible)}
        errors = [r for r in rows["errors"] if r["kind"] == kind]
        if errors:
            entry["noise"] = fit_noise(errors)
        directions = [r for r in rows["directions"] if r["kind"] == kind]
        if directions:
            entry["direction"] = fit_direction(directions)
        extra = [x for x in rows["extra"] if x["kind"] == kind]
        for status in ("false", "outside_view"):
            count = sum(x["status"] == status for x in extra)
            entry[f"{status}_per_frame"] = round(count / frames, 4)
        entry["recall_by_policy"] = {
            p: _share([v["found"] for v in visible if v["policy"] == p]) for p in POLICIES
        }
        entry["recall_still_vs_turning"] = {
            "still": _share([v["found"] for v in visible if v["blur_px"] == 0.0]),
            "turning": _share([v["found"] for v in visible if v["blur_px"] > 0.0]),
        }
        if kind in SEGMENT_KINDS:
            pieces = [v["pieces"] for v in visible if v["found"]]
            entry["pieces_per_found"] = round(float(np.mean(pieces)), 3) if pieces else None
        kinds[kind] = entry
    return kinds


def _share(flags: list[bool]) -> float | None:
    return round(float(np.mean(flags)), 3) if flags else None


def model_of(kinds: dict[str, Any]) -> DetectorModel:
    """The emulator's detector model from the fit; a kind without errors to fit takes the
    median fit of the kinds with them."""
    noise = {
        k: (v["noise"]["a_m"], v["noise"]["b_per_m"]) for k, v in kinds.items() if "noise" in v
    }
    shared = tuple(float(np.median([n[i] for n in noise.values()])) for i in range(2))
    directions = {k: v["direction"] for k, v in kinds.items() if "direction" in v}

    def direction(kind: str, name: str) -> float:
        if kind in directions:
            return float(directions[kind][name])
        return float(np.median([d[name] for d in directions.values()]))

    return DetectorModel(
        bands_m=BANDS_M,
        recall={k: tuple(v["recall"]["configured"]) for k, v in kinds.items()},
        point_std_m={k: noise.get(k, (shared[0], shared[1])) for k in FEATURE_KINDS},
        direction_std_rad={k: direction(k, "std_rad") for k in DIRECTION_KINDS},
        reported_direction_std_rad={k: direction(k, "reported_std_rad") for k in DIRECTION_KINDS},
    )


def at_fit(kinds: dict[str, Any]) -> dict[str, Any]:
    """The figures to compare between the detector and the emulator at the fit."""
    out = {}
    for kind, entry in kinds.items():
        row: dict[str, Any] = {"recall": entry["recall"]["measured"]}
        if "noise" in entry:
            noise = entry["noise"]
            row |= {
                k: noise[k] for k in ("a_m", "b_per_m", "rms_m", "median_abs_total_m", "cov_scale")
            }
        if "direction" in entry:
            row |= {k: entry["direction"][k] for k in ("std_rad", "std_scale")}
        out[kind] = row
    return out


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--episodes", type=int, default=5, help="per head policy")
    parser.add_argument("--seconds", type=float, default=30.0)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=Path("benchmarks/results"))
    args = parser.parse_args()
    t0 = time.perf_counter()
    frames, field_map, camera = collect(args.episodes, args.seconds, args.seed)
    kinds = summary(rows_of(frames, field_map, camera))
    model = model_of(kinds)
    view = FeatureViewConfig(detector=model)
    detector = PipelineConfig().field_detector  # the covariance model the env's detector has
    emulator = GeometricFieldFeatures(field_map, camera, view, detector=detector)
    emulated = summary(rows_of(frames, field_map, camera, emulator, args.seed))
    result = {
        "setting": {
            "env_id": "SPL/ActiveVision-NoPoles-v1",
            "episodes_per_policy": args.episodes,
            "seconds": args.seconds,
            "seeds": [args.seed + k for k in range(args.episodes)],
            "policies": list(POLICIES),
            "hold_s": HOLD_S,
            "lighting": "default",
            "bands_m": list(BANDS_M),
            "min_in_band": MIN_IN_BAND,
            "outlier_sigmas": OUTLIER_SIGMAS,
        },
        "frames": len(frames),
        "model": dataclasses.asdict(model),
        "kinds": kinds,
        "at_fit": {"detector": at_fit(kinds), "emulator": at_fit(emulated)},
        "seconds": round(time.perf_counter() - t0, 1),
    }
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "geometric_field_features.json").write_text(json.dumps(result, indent=1))
    print(json.dumps({k: result[k] for k in ("frames", "model", "at_fit", "seconds")}, indent=1))


if __name__ == "__main__":
    main()
