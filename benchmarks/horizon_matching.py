"""Natural landmark recognition by 1D SURF matching on a turn in place (seed 004 Table 2, Fig. 13).

The seed's classification experiment (§3.3): the robot turns in place at one spot, capturing
88 images about 4 degrees apart; a pair of images *matches* when their headings differ by less
than 20 degrees (at least 58 % of each horizon overlaps), otherwise it does not. Every pair gets
a recognition score and the score's power to separate matches from non-matches is the area
under the ROC curve (AUC). Here our robot stands at the centre of the SPL field scene
(``spl_env.scenes.spl_field``), head level (yaw = pitch = 0), no gait sway, no other robots,
and is turned to headings ``0, 4, ..., 348`` deg (``--images``, ``--step-deg``); the heading
difference of a pair is taken round the circle (images 0 and 87 are 12 deg apart). Frames have
the camera's default sensor noise (std 2 levels).

Methods (each pair scored once: the later image is the test, the earlier the stored image):

- ``1D SURF, NN``: :func:`perception.landmarks.horizon_features.horizon_features` (default
  :class:`~perception.landmarks.horizon_features.HorizonFeatureConfig`) on each frame, score
  :attr:`perception.landmarks.matching.Matches.score` of
  :func:`~perception.landmarks.matching.match_features` with the default ``MatchingConfig``
  (0.7 ratio test; the sum of inverse descriptor distances);
- ``1D SURF, NN + RANSAC``: the score of :func:`~perception.landmarks.matching.ransac_line`
  (default ``RansacConfig``) on those matches, one generator seeded with ``--seed`` drawn in
  pair order;
- ``ORB, NN`` and ``SIFT, NN``: 2-D features in SURF's row (SURF itself is non-free, absent
  from opencv-python-headless): ``cv2.ORB.create()`` / ``cv2.SIFT.create()`` with default
  settings on the whole grey image, brute-force matcher (Hamming / L2), the same 0.7 ratio
  test, score = sum of ``1 / max(distance, 1)`` over the ratio matches (``auc_count`` in the
  JSON: the number of ratio matches as the score instead).

AUC is the Mann-Whitney statistic ``P(score_match > score_nonmatch) + P(equal) / 2``. Also
reported: the true-positive rate at 5 % false positives (the seed's operating point, Fig. 13),
the ROC curve on a grid of false-positive rates, the headings whose matched pairs all fail that
threshold, and the non-matches by kind: *overlap* (headings 20 deg to the camera's field of
view apart: the views still share part of the horizon), *look-alike* (no overlap but a poster
in both views: the boards carry 12 poster textures on 20 panels, so posters repeat) and
*distinct*, with each kind's false-positive rate at that threshold and the kinds of the 20
highest-scoring non-matches. The posters on the panels are the scene's record
(:attr:`spl_env.scenes.spl_field.SceneBodies.posters`), the posters in view from the
renderer's body labels on the horizon row. Per poster texture: its contrast along and across
the rows and the 1D SURF features of the views that show it. ``--posters`` picks the poster
set (``classic``, the default scenes', or ``textured``, built with upright structure for the
horizon; :mod:`spl_env.assets.make_posters`).

Costs (one thread, ``cv2.setNumThreads(1)``): extraction ms per image, the mean over
``--repeats`` timed passes over all images after one warm-up pass (also the median, and the
mean over the images of each one's fastest call, steadier on a busy machine); ``1D SURF``
counts the whole of ``horizon_features`` on the RGB frame (grey conversion, band, extraction,
bearings), ``extract only`` just :func:`perception.landmarks.surf1d.extract_features` on the
band; the 2-D features count grey conversion plus ``detectAndCompute``. Matching ms per pair is the
mean over all pairs (``NN + RANSAC``: NN matching plus RANSAC).

Scenes (``--seed`` S): posters drawn with scene seed S; a second draw (S + 1); S with the
landmark poles; S with one episode of randomised lighting
(:meth:`spl_env.sensors.camera.EpisodeLighting.sample` with generator S: fixed over the turn);
and a control without boards (only the goals, the field and the white background on the
horizon). Writes ``horizon_matching.json`` and ``horizon_matching.md`` under ``--out``
(``horizon_matching_textured.*`` with ``--posters textured``); the default run takes 80-130 s
on 2 shared CPU cores (under a load of 4-5)::

    python benchmarks/horizon_matching.py
    python benchmarks/horizon_matching.py --posters textured
    python benchmarks/horizon_matching.py --seed 3 --out /tmp/horizon_matching
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import time
from collections.abc import Callable
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

import cv2
import numpy as np
from numpy.typing import NDArray

from perception.landmarks.horizon import horizon_band
from perception.landmarks.horizon_features import (
    HorizonFeatureConfig,
    HorizonFeatures,
    horizon_features,
)
from perception.landmarks.matching import (
    MatchingConfig,
    RansacConfig,
    match_features,
    ransac_line,
)
from perception.landmarks.surf1d import extract_features
from perception.types import CameraModel, CameraState
from spl_env.robots.nao import NaoRobot, RobotConfig
from spl_env.scenes.spl_field import POSTER_SETS, SceneConfig, SplFieldScene
from spl_env.sensors.camera import Camera, CameraConfig, EpisodeLighting, LightingRandomisation
from spl_env.sim.world import BulletWorld

RESULTS = Path("benchmarks/results")
RATIO = 0.7  # seed 004 §3.2 (Lowe): nearest / second-nearest distance
DISTANCE_FLOOR_2D = 1.0  # inverse-distance floor of the 2-D descriptors (Hamming, L2 units)
FPR_OPERATING = 0.05  # seed Fig. 13: 70 % true positives at 5 % false positives
MIN_POSTER_COLUMNS = 20  # a poster counts as in view with this many horizon columns
TOP_FALSE_POSITIVES = 20
SEED_TABLE = {  # seed 004 Table 2 (Core 2 Duo 2.4 GHz, OpenSURF, 640 x 480)
    "1D SURF, NN": {"auc": 88.0, "features": 59.2, "extract_ms": 0.158, "match_ms": 0.069},
    "1D SURF, NN + RANSAC": {"auc": 89.6, "features": 59.2, "extract_ms": 0.158, "match_ms": 0.076},
    "SURF, NN": {"auc": 98.8, "features": 429, "extract_ms": 222.3, "match_ms": 19.1},
}
METHODS = ("1D SURF, NN", "1D SURF, NN + RANSAC", "ORB, NN", "SIFT, NN")

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class Variant:
    """One scene of the experiment."""

    name: str
    scene: SceneConfig
    random_lighting: bool = False


@dataclass
class Frame:
    """One captured image of the turn."""

    heading_deg: float
    image: NDArray[np.uint8]
    labels: NDArray[np.int32]
    state: CameraState


class Turn:
    """A world with the scene of ``variant`` and our robot; renders it at a heading."""

    def __init__(self, variant: Variant, seed: int) -> None:
        self.world = BulletWorld(time_step_s=0.01)
        self.scene = SplFieldScene(self.world, variant.scene)
        self.robot = NaoRobot(self.world, "self", team=0, config=RobotConfig())
        self.camera = Camera(CameraConfig())
        self.scene.place_ball(np.array([3.0, 2.5]))  # away from the robot's feet
        self.lighting = (
            EpisodeLighting.sample(LightingRandomisation(), np.random.default_rng(seed))
            if variant.random_lighting
            else EpisodeLighting.default()
        )
        self.posters = panel_posters(self.world, self.scene)

    def capture(self, heading_deg: float, rng: np.random.Generator) -> Frame:
        """The frame at ``heading_deg`` (robot at the centre spot, head level, standing)."""
        self.robot.place(np.array([0.0, 0.0, math.radians(heading_deg)]), head=np.zeros(2))
        position, rotation = self.robot.camera_pose_world()
        image, labels = self.camera.render(self.world, position, rotation, self.lighting, rng)
        return Frame(heading_deg, image, labels, self.robot.camera_state())

    def close(self) -> None:
        self.world.close()


def panel_posters(world: BulletWorld, scene: SplFieldScene) -> dict[int, int]:
    """Body id -> index in the scene's poster set of every board panel's poster."""
    files = POSTER_SETS[scene.config.poster_set]
    return {world.body(name): files.index(file) for name, file in scene.bodies.posters.items()}


def posters_in_view(
    frame: Frame, camera: CameraModel, config: HorizonFeatureConfig, posters: dict[int, int]
) -> list[int]:
    """Posters covering at least ``MIN_POSTER_COLUMNS`` columns of the horizon row."""
    gray = cv2.cvtColor(frame.image, cv2.COLOR_RGB2GRAY)
    band = horizon_band(gray, camera, frame.state, config.horizon)
    columns = np.arange(camera.width)
    rows = np.clip(np.rint(np.interp(columns, band.columns, band.rows)), 0, camera.height - 1)
    seen = frame.labels[rows.astype(np.int64), columns]
    counts: dict[int, int] = {}
    for body, n in zip(*np.unique(seen, return_counts=True), strict=True):
        if int(body) in posters:
            counts[posters[int(body)]] = counts.get(posters[int(body)], 0) + int(n)
    return sorted(p for p, n in counts.items() if n >= MIN_POSTER_COLUMNS)


def ratio_matches(
    matcher: cv2.DescriptorMatcher, test: NDArray[Any] | None, stored: NDArray[Any] | None
) -> FloatArray:
    """Descriptor distances of the ratio-test NN matches of ``test`` to ``stored`` (a test
    feature with a single stored candidate passes, as in ``match_features``)."""
    if test is None or stored is None or len(test) == 0 or len(stored) == 0:
        return np.zeros(0)
    distances = []
    for pair in matcher.knnMatch(test, stored, k=2):
        if len(pair) == 1 or (len(pair) == 2 and pair[0].distance < RATIO * pair[1].distance):
            distances.append(pair[0].distance)
    return np.asarray(distances, dtype=np.float64)


def auc(positive: FloatArray, negative: FloatArray) -> float:
    """Mann-Whitney AUC: P(positive > negative) + P(equal) / 2."""
    greater = (positive[:, None] > negative[None, :]).mean()
    equal = (positive[:, None] == negative[None, :]).mean()
    return float(greater + 0.5 * equal)


def roc(positive: FloatArray, negative: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """ROC points (fpr, tpr) of the rule ``score >= threshold`` at every distinct score,
    highest threshold first, with the thresholds."""
    thresholds = np.unique(np.concatenate([positive, negative]))[::-1]
    tpr = (positive[None, :] >= thresholds[:, None]).mean(axis=1)
    fpr = (negative[None, :] >= thresholds[:, None]).mean(axis=1)
    return fpr, tpr, thresholds


def operating_point(positive: FloatArray, negative: FloatArray) -> tuple[float, float]:
    """The highest true-positive rate with at most ``FPR_OPERATING`` false positives, and its
    threshold (inf: no threshold does)."""
    fpr, tpr, thresholds = roc(positive, negative)
    ok = fpr <= FPR_OPERATING
    if not ok.any():
        return 0.0, math.inf
    best = int(np.argmax(np.where(ok, tpr, -1.0)))
    return float(tpr[best]), float(thresholds[best])


def roc_grid(positive: FloatArray, negative: FloatArray) -> list[float]:
    """True-positive rate at false-positive rates 0, 0.02, ..., 1 (the best with at most
    that rate)."""
    fpr, tpr, _ = roc(positive, negative)
    return [
        round(float(tpr[fpr <= g].max()) if (fpr <= g).any() else 0.0, 4)
        for g in np.linspace(0.0, 1.0, 51)
    ]


def extraction_times(
    inputs: list[Any], extract: Callable[[Any], Any], repeats: int
) -> dict[str, float]:
    """Mean and median ms per call of ``extract`` over ``repeats`` passes over ``inputs``
    after a warm-up pass, and ``best``: the mean over the inputs of each one's fastest call
    (the least disturbed by other processes on a shared machine)."""
    for item in inputs:
        extract(item)
    times = np.zeros((repeats, len(inputs)))
    for r in range(repeats):
        for k, item in enumerate(inputs):
            start = time.perf_counter()
            extract(item)
            times[r, k] = time.perf_counter() - start
    return {
        "mean": round(1000.0 * float(times.mean()), 4),
        "median": round(1000.0 * float(np.median(times)), 4),
        "best": round(1000.0 * float(times.min(axis=0).mean()), 4),
    }


def run_variant(variant: Variant, args: argparse.Namespace) -> dict[str, Any]:
    """The classification experiment on one scene."""
    started = time.perf_counter()
    turn = Turn(variant, args.seed)
    noise = np.random.default_rng(args.seed)
    frames = [turn.capture(k * args.step_deg, noise) for k in range(args.images)]
    camera = turn.camera.config.model
    config = HorizonFeatureConfig()
    in_view = [posters_in_view(frame, camera, config, turn.posters) for frame in frames]
    turn.close()
    images = [frame.image for frame in frames]
    state = frames[0].state  # the same at every heading: head level, standing

    # Features.
    surf1d: list[HorizonFeatures] = [
        horizon_features(image, camera, state, config) for image in images
    ]
    orb, sift = cv2.ORB.create(), cv2.SIFT.create()
    grey = [cv2.cvtColor(image, cv2.COLOR_RGB2GRAY) for image in images]
    orb_features = [orb.detectAndCompute(g, None) for g in grey]
    sift_features = [sift.detectAndCompute(g, None) for g in grey]
    bands = [horizon_band(g, camera, state, config.horizon) for g in grey]

    extract_ms = {
        "1D SURF": extraction_times(
            images, lambda image: horizon_features(image, camera, state, config), args.repeats
        ),
        "1D SURF extract only": extraction_times(
            bands,
            lambda band: extract_features(band.signal, config.surf, band.columns),
            args.repeats,
        ),
        "ORB": extraction_times(
            images,
            lambda image: orb.detectAndCompute(cv2.cvtColor(image, cv2.COLOR_RGB2GRAY), None),
            args.repeats,
        ),
        "SIFT": extraction_times(
            images,
            lambda image: sift.detectAndCompute(cv2.cvtColor(image, cv2.COLOR_RGB2GRAY), None),
            args.repeats,
        ),
    }

    # Pairs.
    n = len(frames)
    pairs = [(i, j) for i in range(n) for j in range(i + 1, n)]
    difference = np.array(
        [
            abs((frames[j].heading_deg - frames[i].heading_deg + 180.0) % 360.0 - 180.0)
            for i, j in pairs
        ]
    )
    match = difference < args.match_deg
    if match.all() or not match.any():
        raise SystemExit(
            f"--images {n} --step-deg {args.step_deg} --match-deg {args.match_deg}: every pair "
            "is one kind; an ROC needs matches and non-matches"
        )
    matching, ransac = MatchingConfig(), RansacConfig()
    ransac_rng = np.random.default_rng(args.seed)
    hamming, l2 = cv2.BFMatcher(cv2.NORM_HAMMING), cv2.BFMatcher(cv2.NORM_L2)
    scores = {method: np.zeros(len(pairs)) for method in METHODS}
    counts = {method: np.zeros(len(pairs)) for method in METHODS}
    seconds = {method: 0.0 for method in METHODS}
    for p, (i, j) in enumerate(pairs):
        test, stored = surf1d[j].features, surf1d[i].features
        t0 = time.perf_counter()
        nn = match_features(test, stored, matching)
        t1 = time.perf_counter()
        fit = ransac_line(nn, ransac, ransac_rng)
        t_nn, t_ransac = t1 - t0, time.perf_counter() - t1
        scores["1D SURF, NN"][p], counts["1D SURF, NN"][p] = nn.score, len(nn)
        scores["1D SURF, NN + RANSAC"][p] = fit.score
        counts["1D SURF, NN + RANSAC"][p] = int(fit.inliers.sum())
        seconds["1D SURF, NN"] += t_nn
        seconds["1D SURF, NN + RANSAC"] += t_nn + t_ransac
        for method, features, matcher in (
            ("ORB, NN", orb_features, hamming),
            ("SIFT, NN", sift_features, l2),
        ):
            t0 = time.perf_counter()
            d = ratio_matches(matcher, features[j][1], features[i][1])
            t = time.perf_counter() - t0
            scores[method][p] = float((1.0 / np.maximum(d, DISTANCE_FLOOR_2D)).sum())
            counts[method][p] = len(d)
            seconds[method] += t

    # Diagnostics: what the non-matches have in common, headings that fail.
    share = np.array([bool(set(in_view[i]) & set(in_view[j])) for i, j in pairs])
    overlap = difference < camera.hfov_deg  # the two views still overlap
    kinds = {
        "overlap": ~match & overlap,
        "lookalike": ~match & ~overlap & share,
        "distinct": ~match & ~overlap & ~share,
    }
    kind_of = np.where(overlap, "overlap", np.where(share, "lookalike", "distinct"))
    n_features = {
        "1D SURF": np.array([len(f) for f in surf1d]),
        "ORB": np.array([len(kp) for kp, _ in orb_features]),
        "SIFT": np.array([len(kp) for kp, _ in sift_features]),
    }
    methods: dict[str, Any] = {}
    for method in METHODS:
        s, c = scores[method], counts[method]
        positive, negative = s[match], s[~match]
        tpr, threshold = operating_point(positive, negative)
        recalled = s >= threshold
        first, second = np.array(pairs).T
        found = np.zeros(n, dtype=bool)
        np.logical_or.at(found, first, match & recalled)
        np.logical_or.at(found, second, match & recalled)
        failing = np.flatnonzero(~found).tolist()
        top = np.flatnonzero(~match)[np.argsort(-s[~match], kind="stable")][:TOP_FALSE_POSITIVES]
        feature_kind = method.split(",")[0]
        methods[method] = {
            "auc": round(100.0 * auc(positive, negative), 2),
            "auc_count": round(100.0 * auc(c[match], c[~match]), 2),
            "features_per_image": {
                "mean": round(float(n_features[feature_kind].mean()), 1),
                "min": int(n_features[feature_kind].min()),
                "max": int(n_features[feature_kind].max()),
            },
            "extract_ms": extract_ms[feature_kind]["mean"],
            "extract_ms_median": extract_ms[feature_kind]["median"],
            "extract_ms_best": extract_ms[feature_kind]["best"],
            "match_ms_per_pair": round(1000.0 * seconds[method] / len(pairs), 4),
            "score_match_median": round(float(np.median(positive)), 2),
            "score_nonmatch_median": round(float(np.median(negative)), 2),
            "score_nonmatch_p95": round(float(np.percentile(negative, 95)), 2),
            "tpr_at_5pct_fpr": round(tpr, 4),
            "threshold_at_5pct_fpr": round(threshold, 3),
            "headings_all_matches_missed_deg": [frames[k].heading_deg for k in failing],
            "auc_vs_nonoverlapping": round(100.0 * auc(positive, s[~match & ~overlap]), 2),
            "fpr_at_threshold_by_kind": {
                kind: round(float(recalled[mask].mean()), 4) if mask.any() else None
                for kind, mask in kinds.items()
            },
            "top_nonmatches": [
                {
                    "headings_deg": [
                        frames[pairs[p][0]].heading_deg,
                        frames[pairs[p][1]].heading_deg,
                    ],
                    "score": round(float(s[p]), 2),
                    "kind": str(kind_of[p]),
                }
                for p in top
            ],
            "tpr_at_fpr_grid": roc_grid(positive, negative),
        }
    return {
        "scene": {
            "scene_seed": variant.scene.scene_seed,
            "poles_enabled": variant.scene.poles_enabled,
            "boards_enabled": variant.scene.boards_enabled,
            "random_lighting": variant.random_lighting,
            "lighting": {
                "exposure": round(turn.lighting.exposure, 3),
                "ambient": round(turn.lighting.lighting.ambient, 3),
                "diffuse": round(turn.lighting.lighting.diffuse, 3),
                "window_strength": round(turn.lighting.window_strength, 3),
            },
            "posters_on_panels": list(turn.posters.values()),
        },
        "pairs": {
            "match": int(match.sum()),
            "nonmatch": int((~match).sum()),
            **{f"nonmatch_{kind}": int(mask.sum()) for kind, mask in kinds.items()},
        },
        "extract_ms_1d_surf_extract_only": extract_ms["1D SURF extract only"],
        "features_per_heading_1d_surf": n_features["1D SURF"].tolist(),
        "posters_in_view_per_heading": in_view,
        "methods": methods,
        "seconds": round(time.perf_counter() - started, 1),
    }


def poster_texture(scenes: dict[str, Any], poster_set: str) -> list[dict[str, Any]]:
    """Per poster texture: mean absolute grey difference between neighbouring texels along
    the rows (``column_contrast``: structure 1D SURF can see on a level horizon) and down the
    columns (``row_contrast``), and the mean 1D SURF features per image over the headings of
    the board scenes whose horizon shows the poster."""
    folder = resources.files("spl_env") / "assets" / "posters"
    files = POSTER_SETS[poster_set]
    seen: dict[int, list[int]] = {k: [] for k in range(len(files))}
    for result in scenes.values():
        in_view = result["posters_in_view_per_heading"]
        for count, posters in zip(result["features_per_heading_1d_surf"], in_view, strict=True):
            for poster in posters:
                seen[poster].append(count)
    table = []
    for k, name in enumerate(files):
        with resources.as_file(folder / name) as path:
            grey = np.asarray(cv2.imread(str(path), cv2.IMREAD_GRAYSCALE), dtype=np.float64)
        table.append(
            {
                "poster": k,
                "column_contrast": round(float(np.abs(np.diff(grey, axis=1)).mean()), 2),
                "row_contrast": round(float(np.abs(np.diff(grey, axis=0)).mean()), 2),
                "headings_in_view": len(seen[k]),
                "features_1d_surf_when_in_view": (
                    round(float(np.mean(seen[k])), 1) if seen[k] else None
                ),
            }
        )
    return table


def machine() -> str:
    """The CPU's model name (Linux) or the platform's, and the OpenCV version."""
    name = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as cpuinfo:
            for line in cpuinfo:
                if line.startswith("model name"):
                    name = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return f"{name}, {os.cpu_count()} CPUs, opencv {cv2.__version__}"


def variants(seed: int, poster_set: str) -> list[Variant]:
    """The scenes of the run (module docstring)."""

    def scene(scene_seed: int, poles: bool = False, boards: bool = True) -> SceneConfig:
        return SceneConfig(
            scene_seed=scene_seed,
            poster_set=poster_set,
            poles_enabled=poles,
            boards_enabled=boards,
        )

    plain = scene(seed)
    return [
        Variant(f"posters seed {seed}", plain),
        Variant(f"posters seed {seed + 1}", scene(seed + 1)),
        Variant(f"posters seed {seed}, poles", scene(seed, poles=True)),
        Variant(f"posters seed {seed}, random lighting", plain, random_lighting=True),
        Variant("no boards (control)", scene(0, boards=False)),
    ]


def markdown(report: dict[str, Any]) -> str:
    """The tables of ``report``."""
    lines = [
        "# 1D SURF natural landmark recognition on a turn in place (seed 004 Table 2, Fig. 13)",
        "",
        f"Ours: {report['poster_set']} posters; {report['images']} images "
        f"{report['step_deg']} deg apart at the field centre, "
        f"head level; match: headings < {report['match_deg']} deg apart (round the circle). "
        f"{report['pairs']['match']} matched and {report['pairs']['nonmatch']} unmatched pairs "
        "(seed: 480 and 2,065). Score: sum of inverse descriptor distances of the 0.7-ratio "
        "NN matches (RANSAC: of its inliers). Times: one thread on "
        f"{report['machine']}; seed: 2.4 GHz Core 2 Duo, SURF = OpenSURF at 640 x 480 (ours "
        "320 x 240). `TPR@5%`: true positives at 5 % false positives (seed: 70 % for NN + "
        f"RANSAC). Run time {report['seconds']} s.",
        "",
        "| Method | AUC seed | AUC | AUC (count score) | TPR@5% | features / image "
        "(min-max) | seed features | extraction ms mean (median, best) | seed ms | matching ms / "
        "pair "
        "| seed ms |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for name, result in report["scenes"].items():
        lines.append(f"| **{name}** | | | | | | | | | | |")
        for method, m in result["methods"].items():
            seed_row = SEED_TABLE.get(method) or SEED_TABLE["SURF, NN"]
            f = m["features_per_image"]
            lines.append(
                f"| {method} | {seed_row['auc']} % | {m['auc']:.1f} % | {m['auc_count']:.1f} % | "
                f"{100 * m['tpr_at_5pct_fpr']:.0f} % | {f['mean']} ({f['min']}-{f['max']}) | "
                f"{seed_row['features']} | {m['extract_ms']:.3f} ({m['extract_ms_median']:.3f}, "
                f"{m['extract_ms_best']:.3f}) | "
                f"{seed_row['extract_ms']} | "
                f"{m['match_ms_per_pair']:.3f} | {seed_row['match_ms']} |"
            )
    lines += [
        "",
        "SURF's seed row is shown against both ORB and SIFT. Extraction: mean and median over "
        "all calls, and best (the mean over the images of each one's fastest call: the least "
        "disturbed by other processes on a shared machine); 1D SURF is the whole "
        "`horizon_features` call on the RGB frame, `extract only` just `extract_features` on "
        "the band. Non-matches by kind: *overlap* "
        "(headings 20 deg to the camera's field of view apart: the views still share part of "
        "the horizon), *look-alike* (no overlap, but a poster in both views, on different "
        "panels), *distinct* (neither). Per scene, for 1D SURF NN + RANSAC: AUC against the "
        "non-overlapping non-matches only, the false-positive rate of each kind at the 5 % "
        "threshold, the kinds of the 20 highest-scoring non-matches, and the headings none of "
        "whose matches pass that threshold:",
        "",
        "| Scene | extract only ms (mean / median / best) | AUC vs non-overlapping | FPR overlap / "
        "look-alike / distinct | top 20 overlap / look-alike / distinct | headings missed "
        "(deg) |",
        "|---|---|---|---|---|---|",
    ]
    for name, result in report["scenes"].items():
        ransac = result["methods"]["1D SURF, NN + RANSAC"]
        top = [t["kind"] for t in ransac["top_nonmatches"]]
        fpr = ransac["fpr_at_threshold_by_kind"]
        rates = " / ".join(
            "-" if fpr[k] is None else f"{100 * fpr[k]:.1f} %"
            for k in ("overlap", "lookalike", "distinct")
        )
        only = result["extract_ms_1d_surf_extract_only"]
        missed = ransac["headings_all_matches_missed_deg"]
        lines.append(
            f"| {name} | {only['mean']:.3f} / {only['median']:.3f} / {only['best']:.3f} | "
            f"{ransac['auc_vs_nonoverlapping']:.1f} % | {rates} | "
            f"{top.count('overlap')} / {top.count('lookalike')} / {top.count('distinct')} | "
            f"{', '.join(f'{h:g}' for h in missed) or '-'} |"
        )
    lines += [
        "",
        "Non-match pairs per kind (overlap / look-alike / distinct): "
        + "; ".join(
            f"{name}: {r['pairs']['nonmatch_overlap']} / {r['pairs']['nonmatch_lookalike']} / "
            f"{r['pairs']['nonmatch_distinct']}"
            for name, r in report["scenes"].items()
        )
        + ".",
        "",
        "Posters: mean absolute grey step between neighbouring texels along the rows (column "
        "contrast: what a level horizon band sees) and down the columns (row contrast), and the "
        "mean 1D SURF features per image over the headings (all board scenes) that show the "
        "poster on the horizon:",
        "",
        "| Poster | column contrast | row contrast | headings in view | 1D SURF features |",
        "|---|---|---|---|---|",
        *(
            f"| {t['poster']:02d} | {t['column_contrast']} | {t['row_contrast']} | "
            f"{t['headings_in_view']} | {t['features_1d_surf_when_in_view']} |"
            for t in report["posters"]
        ),
    ]
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=RESULTS, help="results folder")
    parser.add_argument("--seed", type=int, default=0, help="scene (poster) seed")
    parser.add_argument("--images", type=int, default=88)
    parser.add_argument("--step-deg", type=float, default=4.0)
    parser.add_argument("--match-deg", type=float, default=20.0)
    parser.add_argument("--repeats", type=int, default=5, help="timed extraction passes")
    parser.add_argument("--posters", default="classic", choices=tuple(POSTER_SETS))
    args = parser.parse_args()
    cv2.setNumThreads(1)
    started = time.perf_counter()
    scenes: dict[str, Any] = {}
    for variant in variants(args.seed, args.posters):
        scenes[variant.name] = run_variant(variant, args)
        summary = {m: r["auc"] for m, r in scenes[variant.name]["methods"].items()}
        print(variant.name, summary, f"{scenes[variant.name]['seconds']} s", flush=True)
    first = next(iter(scenes.values()))
    report = {
        "images": args.images,
        "step_deg": args.step_deg,
        "match_deg": args.match_deg,
        "seed": args.seed,
        "repeats": args.repeats,
        "pairs": {k: first["pairs"][k] for k in ("match", "nonmatch")},
        "seed_table_2": SEED_TABLE,
        "machine": machine(),
        "scenes": scenes,
        "poster_set": args.posters,
        "posters": poster_texture(scenes, args.posters),
        "seconds": round(time.perf_counter() - started, 1),
    }
    args.out.mkdir(parents=True, exist_ok=True)
    stem = "horizon_matching" + ("" if args.posters == "classic" else f"_{args.posters}")
    (args.out / f"{stem}.json").write_text(json.dumps(report, indent=1))
    (args.out / f"{stem}.md").write_text(markdown(report))
    print(markdown(report))


if __name__ == "__main__":
    main()
