"""The field features a camera could see from a known pose: the map's features inside the image,
as :class:`~perception.field.features.FieldFeature` s in the robot frame, with Gaussian noise.

The oracle provider of field features (truth plus configured noise) and the sensor model's
benchmark on ideal detections read them. A ground point is in view when it projects inside the
image (``margin_px`` from its border) within ``max_range_m`` of the robot; robots and other
bodies hide nothing here. A line or field edge is seen as the longest stretch of it in view
(sampled every ``sample_m``) when that stretch is ``min_line_m`` long or more; a junction, a
mark or a post (its foot) when its point is in view; the centre circle when a
``min_circle_fraction`` of its rim is, with its direction when an X junction is in view too.

Noise: each point moves by an isotropic Gaussian of standard deviation
``point_std_m + point_std_per_m * d`` at distance ``d`` (m) from the robot, its reported
covariance; a direction by ``direction_std_rad``. Not fitted to a detector: a configuration.
Without a generator the features are exact (no noise), with the same covariances.

:func:`detected_features` (:func:`detect` per feature) turns exact features into what the
rendered detector (:mod:`perception.vision.field_features`) would report of them by a
:class:`DetectorModel` (``FeatureViewConfig.detector``, fitted by
``benchmarks/fit_geometric_field_features.py``): each is found with its kind's recall in its
range band and moved by its kind's noise. The geometric camera mode's emulator
(:mod:`spl_env.sensors.emulation.field`) applies it, after the camera's sway; neither
:func:`visible_features` nor the oracle provider does, and their noise is as above.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np
from numpy.typing import NDArray

from perception.field.features import (
    DIRECTED_KINDS,
    FEATURE_KINDS,
    SEGMENT_KINDS,
    FieldFeature,
    feature_distance,
)
from perception.field.field_map import FieldMap, MapFeature
from perception.geometry import FloatArray, project_points
from perception.types import CameraModel, CameraState
from perception.validation import (
    InvalidTypeError,
    check_in_interval,
    check_nested_configs,
    check_positive,
    finite_vector,
)

# the kinds that may carry a direction (the centre circle's only when the halfway line is seen)
DIRECTION_KINDS: tuple[str, ...] = tuple(
    k for k in FEATURE_KINDS if k in DIRECTED_KINDS or k == "centre_circle"
)

_EYE2 = np.eye(2)  # isotropic covariances: each point's variance times this (read-only)
_EYE2.flags.writeable = False
OCCLUSION_EVERY = 5  # visible_features asks its ``occluded`` about every this many samples

# DetectorModel's defaults: fitted by benchmarks/fit_geometric_field_features.py on 3000
# rendered frames of NoPoles patrols (tuning seeds 0-4, 30 s each under the head scan and under
# random head targets), benchmarks/results/geometric_field_features.json ("model"), against the
# features in view as the emulator judges them (hidden where a body stands in front, a post only
# with its cut height in the image; refitted so in stop 40). With the camera's sway taken out
# (the emulator adds it exactly), the detector errs by a few mm (median 2-5 mm) on lines,
# corners, T junctions and penalty marks, 1.5-2 cm on the centre circle, its crossings and the
# goal posts; with it, medians of 3-9 cm. Emulated at the fit's frames, the recall is within a
# few points of the detector's per kind and band (the JSON's "at_fit").
_FITTED_BANDS_M = (1.0, 2.0, 3.0, 4.0, 6.0, 8.0)
_FITTED_RECALL: dict[str, tuple[float, ...]] = {
    "line": (0.931, 0.964, 0.94, 0.846, 0.457, 0.017),
    "field_edge": (1.0, 1.0, 0.972, 0.954, 0.928, 0.71),
    "corner": (0.654, 0.665, 0.605, 0.493, 0.109, 0.0),
    "t_junction": (0.545, 0.545, 0.709, 0.628, 0.117, 0.0),
    "x_junction": (0.773, 0.888, 0.878, 0.632, 0.0, 0.0),
    "centre_circle": (1.0, 0.987, 0.934, 0.921, 0.0, 0.0),
    "penalty_mark": (0.544, 0.538, 0.93, 0.451, 0.0, 0.0),
    "goal_post": (0.673, 0.673, 0.394, 0.238, 0.363, 0.016),
}
# (a m, b per m): the noise's std a + b * range
_FITTED_POINT_STD_M: dict[str, tuple[float, float]] = {
    "line": (0.0001, 0.0024),
    "field_edge": (0.0001, 0.0066),
    "corner": (0.0001, 0.0021),
    "t_junction": (0.0001, 0.0015),
    "x_junction": (0.0144, 0.0113),
    "centre_circle": (0.009, 0.0198),
    "penalty_mark": (0.0001, 0.0019),
    "goal_post": (0.0349, 0.0034),
}
_FITTED_DIRECTION_STD_RAD: dict[str, float] = {
    "corner": 0.03,
    "t_junction": 0.0028,
    "x_junction": 0.0012,
    "centre_circle": 0.0012,
}
_FITTED_REPORTED_DIRECTION_STD_RAD: dict[str, float] = {
    "corner": 0.0466,
    "t_junction": 0.045,
    "x_junction": 0.0245,
    "centre_circle": 0.0249,
}


@dataclass(frozen=True, kw_only=True)
class DetectorModel:
    """What the rendered field-feature detector misses and how far off it is, per feature kind
    (:func:`detected_features`); the defaults are fitted (module comment above them).

    ``bands_m``: the upper edges (m, > 0, increasing) of the range bands; nothing beyond the
    last is seen. ``recall``: every kind -> the chance (in [0, 1]) that a feature in view in
    each band is found (one per band). ``point_std_m``: every kind -> ``(a, b)``, each point's
    noise standard deviation per axis ``a + b * d`` at its distance ``d`` (m; a > 0, b >= 0).
    ``direction_std_rad``: each kind that may carry a direction (:data:`DIRECTION_KINDS`) ->
    its noise (> 0); ``reported_direction_std_rad``: -> the standard deviation the detector
    reports with it (its information's equivalent: ``1 / sqrt(mean(1 / std**2))``), which the
    emulator reports too.
    """

    bands_m: tuple[float, ...] = _FITTED_BANDS_M
    recall: Mapping[str, tuple[float, ...]] = field(default_factory=lambda: dict(_FITTED_RECALL))
    point_std_m: Mapping[str, tuple[float, float]] = field(
        default_factory=lambda: dict(_FITTED_POINT_STD_M)
    )
    direction_std_rad: Mapping[str, float] = field(
        default_factory=lambda: dict(_FITTED_DIRECTION_STD_RAD)
    )
    reported_direction_std_rad: Mapping[str, float] = field(
        default_factory=lambda: dict(_FITTED_REPORTED_DIRECTION_STD_RAD)
    )

    def __post_init__(self) -> None:
        owner = "DetectorModel"
        bands = _numbers(owner, "bands_m", self.bands_m)
        if not bands:
            raise ValueError(f"{owner}.bands_m must hold at least one band edge, got ()")
        for k, edge in enumerate(bands):
            check_positive(owner, f"bands_m[{k}]", edge)
        if any(b <= a for a, b in itertools.pairwise(bands)):
            raise ValueError(f"{owner}.bands_m must increase, got {bands!r}")
        recall = _per_kind(owner, "recall", self.recall, FEATURE_KINDS)
        for kind, values in recall.items():
            name = f"recall[{kind!r}]"
            values = _numbers(owner, name, values)
            if len(values) != len(bands):
                raise ValueError(
                    f"{owner}.{name} must hold one recall per band ({len(bands)}), "
                    f"got {len(values)}"
                )
            for k, value in enumerate(values):
                check_in_interval(
                    owner, f"{name}[{k}]", value, 0.0, 1.0, low_inclusive=True, high_inclusive=True
                )
            recall[kind] = values
        noise = _per_kind(owner, "point_std_m", self.point_std_m, FEATURE_KINDS)
        for kind, pair in noise.items():
            name = f"point_std_m[{kind!r}]"
            pair = _numbers(owner, name, pair)
            if len(pair) != 2:
                raise ValueError(f"{owner}.{name} must be (a, b), got {pair!r}")
            check_positive(owner, f"{name}[0]", pair[0])
            check_positive(owner, f"{name}[1]", pair[1], allow_zero=True)
            noise[kind] = (pair[0], pair[1])
        directions = {}
        for name in ("direction_std_rad", "reported_direction_std_rad"):
            stds = _per_kind(owner, name, getattr(self, name), DIRECTION_KINDS)
            for kind, std in stds.items():
                check_positive(owner, f"{name}[{kind!r}]", std)
            directions[name] = stds
        object.__setattr__(self, "bands_m", bands)
        object.__setattr__(self, "recall", recall)
        object.__setattr__(self, "point_std_m", noise)
        for name, stds in directions.items():
            object.__setattr__(self, name, stds)

    def __hash__(self) -> int:
        """A hash of the values (the mappings are dicts, which do not hash): configs holding a
        model stay hashable, as every env config is."""
        mappings = ("recall", "point_std_m", "direction_std_rad", "reported_direction_std_rad")
        return hash((self.bands_m, *(tuple(getattr(self, name).items()) for name in mappings)))

    @property
    def max_range_m(self) -> float:
        """How far the detector sees anything (m): the last band's edge."""
        return self.bands_m[-1]

    def band(self, distance_m: float) -> int:
        """The index of the band ``distance_m`` falls in (``len(bands_m)`` beyond the last)."""
        return int(np.searchsorted(self.bands_m, distance_m, side="left"))

    def recall_at(self, kind: str, distance_m: float) -> float:
        """The chance a ``kind`` in view at ``distance_m`` is found (0 beyond the bands)."""
        band = self.band(distance_m)
        return self.recall[kind][band] if band < len(self.bands_m) else 0.0

    def std_at(self, kind: str, distance_m: FloatArray) -> FloatArray:
        """The noise standard deviation per axis (m) of ``kind``'s points at ``distance_m``."""
        a, b = self.point_std_m[kind]
        return a + b * np.asarray(distance_m, dtype=np.float64)


def _numbers(owner: str, name: str, values: object) -> tuple[float, ...]:
    """``values`` as a tuple of floats, or InvalidTypeError naming ``owner.name``."""
    if not isinstance(values, tuple | list):
        raise InvalidTypeError(
            f"{owner}.{name} must be a tuple of numbers, got {type(values).__name__}"
        )
    for k, value in enumerate(values):
        if isinstance(value, bool) or not isinstance(value, int | float | np.integer | np.floating):
            raise InvalidTypeError(
                f"{owner}.{name}[{k}] must be a real number, got {type(value).__name__} {value!r}"
            )
    return tuple(float(v) for v in values)


def _per_kind(owner: str, name: str, mapping: object, kinds: Iterable[str]) -> dict[str, object]:
    """``mapping`` as a dict with exactly the keys ``kinds``, or ValueError naming the field."""
    if not isinstance(mapping, Mapping):
        raise InvalidTypeError(
            f"{owner}.{name} must be a mapping kind -> value, got {type(mapping).__name__}"
        )
    expected = set(kinds)
    missing, extra = expected - set(mapping), set(mapping) - expected
    if missing or extra:
        raise ValueError(
            f"{owner}.{name} must have one entry per kind {tuple(kinds)}: "
            f"missing {sorted(missing)}, unknown {sorted(map(str, extra))}"
        )
    return {kind: mapping[kind] for kind in kinds}


@dataclass(frozen=True, kw_only=True)
class FeatureViewConfig:
    """Settings of :func:`visible_features` (module docstring; m, px, rad; all > 0 but
    ``margin_px`` >= 0; ``min_circle_fraction`` in (0, 1]), and ``detector``, the model of
    the rendered detector that the geometric camera mode's emulator applies
    (:func:`detected_features`; its range, the last band's edge, replaces ``max_range_m``
    there, and its noise the ``*_std_*`` here, which are the oracle's)."""

    max_range_m: float = 4.0
    min_line_m: float = 0.3
    sample_m: float = 0.02
    margin_px: float = 2.0
    min_circle_fraction: float = 0.25
    # a goal post counts as in view when its foot is; with this set (m), only when the post
    # at this height above its foot shows in the image too (the detector needs that much of it)
    post_seen_height_m: float | None = None
    point_std_m: float = 0.02
    point_std_per_m: float = 0.02
    direction_std_rad: float = 0.03
    detector: DetectorModel = field(default_factory=DetectorModel)

    def __post_init__(self) -> None:
        check_nested_configs(self)
        owner = "FeatureViewConfig"
        for name in (
            "max_range_m",
            "min_line_m",
            "sample_m",
            "point_std_m",
            "point_std_per_m",
            "direction_std_rad",
        ):
            check_positive(owner, name, getattr(self, name))
        check_positive(owner, "margin_px", self.margin_px, allow_zero=True)
        check_positive(
            owner, "min_circle_fraction", self.min_circle_fraction, upper=1.0, upper_inclusive=True
        )
        if self.post_seen_height_m is not None:
            check_positive(owner, "post_seen_height_m", self.post_seen_height_m)


def visible_features(
    field_map: FieldMap,
    pose: FloatArray,
    camera: CameraModel,
    state: CameraState,
    config: FeatureViewConfig,
    rng: np.random.Generator | None = None,
    occluded: Callable[[FloatArray], NDArray[np.bool_]] | None = None,
) -> tuple[FieldFeature, ...]:
    """The features of ``field_map`` in view of ``camera`` at ``state`` on a robot at ``pose``
    (3,) (m, m, rad, field frame), in map order; noisy when ``rng`` is given (module
    docstring), else exact with the same covariances. Every tested ground point of the map is
    projected at once (:func:`_samples`). ``occluded``, when given, says which field-frame
    ground points (N, 2) something stands in front of (N,) bool: those are not seen (a robot,
    the ball); a goal post is then judged by its foot."""
    robot = finite_vector(pose, "pose", 3)
    view = _View(robot, camera, state, config)
    samples = _samples(field_map, config.sample_m)
    seen = view.sees(samples.points)
    if occluded is not None and seen.any():
        seen &= ~_occluded_samples(samples, seen, occluded)
    any_seen = np.logical_or.reduceat(seen, samples.starts)  # per map feature
    found = []
    for feature, part, in_view in zip(field_map.features, samples.parts, any_seen, strict=True):
        if not in_view:  # most of the map, from any pose
            continue
        if feature.kind in SEGMENT_KINDS:
            stretch = _longest_stretch(samples.points[part], seen[part], config.min_line_m)
            if stretch is not None:
                found.append(view.feature(feature, stretch, rng))
        elif feature.kind == "centre_circle":
            if seen[part].mean() < config.min_circle_fraction:
                continue
            # its direction when an X junction (where the halfway line crosses it) is in view
            directed = any(seen[samples.parts[k].start] for k in samples.crossings)
            if not directed:
                feature = MapFeature("centre_circle", feature.points, feature.name)
            found.append(view.feature(feature, feature.points, rng))
        elif seen[part.start] and (feature.kind != "goal_post" or view.shows_post(feature)):
            found.append(view.feature(feature, feature.points, rng))
    return tuple(found)


def _occluded_samples(
    samples: _Samples, seen: NDArray[np.bool_], occluded: Callable[[FloatArray], NDArray[np.bool_]]
) -> NDArray[np.bool_]:
    """(N,) which of the ``seen`` samples ``occluded`` hides, asking it about every
    ``OCCLUSION_EVERY``-th sample and the first of each map feature and of each run of seen
    samples; the others take the answer of the nearest asked sample before them (in their own
    feature and run: about 10 cm apart at most)."""
    index = np.arange(len(seen))
    first = np.zeros(len(seen), dtype=bool)
    first[samples.starts] = True
    first[1:] |= ~seen[:-1]
    asked = seen & (first | (index % OCCLUSION_EVERY == 0))
    answer = np.zeros(len(seen), dtype=bool)
    answer[asked] = np.asarray(occluded(samples.points[asked]), dtype=bool)
    nearest = np.maximum.accumulate(np.where(asked, index, 0))
    return seen & answer[nearest]


@dataclass(frozen=True, eq=False)
class _Samples:
    """The ground points (field frame) :func:`visible_features` tests on one map, stacked:
    ``points`` (N, 2); ``parts``, per map feature in map order, the slice of ``points`` that
    is its own (a segment's points every ``sample_m`` from end to end, the centre circle's 180
    rim points, a point feature's point), and ``starts`` (F,) their first indices;
    ``crossings``, the indices of the map's X junctions."""

    points: FloatArray
    parts: tuple[slice, ...]
    starts: NDArray[np.intp]
    crossings: tuple[int, ...]


@lru_cache(maxsize=8)
def _samples(field_map: FieldMap, sample_m: float) -> _Samples:
    """The :class:`_Samples` of ``field_map`` (kept for the last few maps, by identity, and
    sample spacings ``sample_m`` (m): the map does not change)."""
    chunks: list[FloatArray] = []
    for feature in field_map.features:
        if feature.kind in SEGMENT_KINDS:
            a, b = feature.points
            n = max(2, math.ceil(float(np.linalg.norm(b - a)) / sample_m) + 1)
            chunks.append(a + np.linspace(0.0, 1.0, n)[:, None] * (b - a))
        elif feature.kind == "centre_circle":
            radius = field_map.dims.centre_circle_diameter_m / 2
            angles = np.linspace(0.0, 2 * math.pi, 180, endpoint=False)
            rim = radius * np.column_stack([np.cos(angles), np.sin(angles)])
            chunks.append(feature.points[0] + rim)
        else:
            chunks.append(feature.points[:1])
    # no part is empty (a segment has 2 samples or more, the circle 180, a point 1): the
    # reduceat over ``starts`` in visible_features counts on it
    ends = np.cumsum([0, *(len(c) for c in chunks)])
    points = np.concatenate(chunks)
    points.flags.writeable = False
    return _Samples(
        points=points,
        parts=tuple(slice(int(a), int(b)) for a, b in itertools.pairwise(ends)),
        starts=np.asarray(ends[:-1], dtype=np.intp),
        crossings=tuple(k for k, f in enumerate(field_map.features) if f.kind == "x_junction"),
    )


def _longest_stretch(
    samples: FloatArray, seen: NDArray[np.bool_], min_line_m: float
) -> FloatArray | None:
    """The ends (2, 2) (field frame) of the longest run of a segment's ``samples`` (N, 2)
    in view (``seen`` (N,), at least one True), the first of equals, or None when it is
    shorter than ``min_line_m`` (or a single sample)."""
    padded = np.zeros(len(seen) + 2, dtype=np.int8)
    padded[1:-1] = seen
    step = np.diff(padded)
    starts, stops = np.flatnonzero(step == 1), np.flatnonzero(step == -1)
    best = int(np.argmax(stops - starts))  # the first of the longest runs
    if stops[best] - starts[best] < 2:
        return None
    ends = samples[[starts[best], stops[best] - 1]]
    if float(np.linalg.norm(ends[1] - ends[0])) < min_line_m:
        return None
    return ends


class _View:
    """One camera pose's visibility test and noise."""

    def __init__(
        self, pose: FloatArray, camera: CameraModel, state: CameraState, config: FeatureViewConfig
    ) -> None:
        self.pose, self.camera, self.state, self.config = pose, camera, state, config
        c, s = math.cos(pose[2]), math.sin(pose[2])
        self.to_robot = np.array([[c, -s], [s, c]])  # rows: field -> robot via points @ this
        self.rotation = state.rotation()

    def robot_points(self, points: FloatArray) -> FloatArray:
        """Field-frame ``points`` (N, 2) in the robot frame."""
        return (points - self.pose[:2]) @ self.to_robot

    def sees(self, points: FloatArray) -> NDArray[np.bool_]:
        """Which field-frame ground ``points`` (N, 2) are in view (N,) bool."""
        robot = self.robot_points(np.atleast_2d(points))
        seen = np.hypot(robot[:, 0], robot[:, 1]) <= self.config.max_range_m
        near = robot[seen]  # only these are projected: most of the map is out of range
        seen[seen] = self._in_image(np.column_stack([near, np.zeros(len(near))]))
        return seen

    def shows_post(self, post: MapFeature) -> bool:
        """Whether the goal ``post`` at ``post_seen_height_m`` above its foot (when set) lies
        in the image, as its foot does (the caller has checked that)."""
        height = self.config.post_seen_height_m
        if height is None:
            return True
        foot = self.robot_points(post.points[:1])
        return bool(self._in_image(np.array([[foot[0, 0], foot[0, 1], height]]))[0])

    def _in_image(self, points: FloatArray) -> NDArray[np.bool_]:
        """Which robot-frame ``points`` (N, 3) project in front of the camera and inside the
        image, ``margin_px`` clear of its sides (N,) bool."""
        cam = self.camera
        in_camera = (points - self.state.position) @ self.rotation
        uv, front = project_points(in_camera, cam.fx, cam.fy, cam.cx, cam.cy)
        m = self.config.margin_px
        with np.errstate(invalid="ignore"):
            return np.asarray(
                front
                & (uv[:, 0] >= m)
                & (uv[:, 0] <= cam.width - 1 - m)
                & (uv[:, 1] >= m)
                & (uv[:, 1] <= cam.height - 1 - m),
                dtype=bool,
            )

    def feature(
        self, feature: MapFeature, points: FloatArray, rng: np.random.Generator | None
    ) -> FieldFeature:
        """``feature`` seen at the field-frame ``points``, in the robot frame with noise."""
        cfg = self.config
        robot = self.robot_points(points)
        std = cfg.point_std_m + cfg.point_std_per_m * np.hypot(robot[:, 0], robot[:, 1])
        direction = None if feature.direction is None else feature.direction - self.pose[2]
        if rng is not None:
            robot = robot + rng.normal(0.0, 1.0, robot.shape) * std[:, None]
            if direction is not None:
                direction += float(rng.normal(0.0, cfg.direction_std_rad))
        cov = (std**2)[:, None, None] * _EYE2
        direction_std = math.nan if direction is None else cfg.direction_std_rad
        # the map's own feature, placed: valid by construction (a finite point set, std > 0)
        return FieldFeature.trusted(feature.kind, robot, cov, direction, direction_std)


def detected_features(
    features: Iterable[FieldFeature], model: DetectorModel, rng: np.random.Generator
) -> tuple[FieldFeature, ...]:
    """What the detector would report of the exact ``features`` (robot frame), by ``model``
    (:func:`detect` each, in order): each reported with the covariance and direction standard
    deviation of its noise; no false detections are added."""
    out = []
    for f in features:
        found = detect(f.kind, f.points, f.direction, model, rng)
        if found is None:
            continue
        points, direction = found
        std = model.std_at(f.kind, np.hypot(f.points[:, 0], f.points[:, 1]))
        cov = (std**2)[:, None, None] * _EYE2
        if direction is None:
            out.append(FieldFeature(f.kind, points, cov))
        else:
            out.append(
                FieldFeature(f.kind, points, cov, direction, model.direction_std_rad[f.kind])
            )
    return tuple(out)


def detect(
    kind: str,
    points: FloatArray,
    direction: float | None,
    model: DetectorModel,
    rng: np.random.Generator,
) -> tuple[FloatArray, float | None] | None:
    """One exact feature of ``kind`` at ``points`` (P, 2) (robot frame) with ``direction`` as
    the detector would find it by ``model``, or None when it misses it: found with its kind's
    recall at its distance (:func:`feature_distance`; nothing beyond the last band), each point
    then moved by an isotropic Gaussian of its kind's ``a + b * d`` at that point's distance
    ``d``, the direction by its kind's direction noise. Draws, in order: a uniform, then (if
    found) the points' normals, then the direction's."""
    if rng.uniform() >= model.recall_at(kind, feature_distance(kind, points)):
        return None
    std = model.std_at(kind, np.hypot(points[:, 0], points[:, 1]))
    noisy = points + rng.normal(0.0, 1.0, points.shape) * std[:, None]
    if direction is None:
        return noisy, None
    return noisy, direction + float(rng.normal(0.0, model.direction_std_rad[kind]))
