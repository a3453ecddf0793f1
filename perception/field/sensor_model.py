"""The unified field-feature sensor model of seed 004 (§2.2): one pose from all of a frame's
field features at once, by an ICP over point pairs with hierarchical matching.

Given the features of a frame (:class:`~perception.field.features.FieldFeature`, robot frame),
the field map and a prior pose (the pose filter's), :func:`observe_pose` returns the pose that
places the features best on the map, with its information matrix, or None when the features
cannot be placed consistently.

**Pre-processing** (:func:`match_items`) makes features more distinctive by what is seen with
them in the same frame; the field edges are then dropped:

- two goal posts about a goal's width apart become one item, matched to the two posts of a
  goal in the same left-right order;
- two parallel lines become one item, matched to two parallel map lines as far apart;
- a T junction with a goal post beside it (within ``relation_range_m``) may only match a map T
  junction that has a map post where the seen post lies in the junction's own frame (within
  ``relation_tolerance_m``); a corner with a field edge may only match a map corner with a map
  edge as far away and as turned; a line parallel to a field edge may only match a map line as
  far from a map edge: the seed's sub-categories, found from the map rather than listed (the
  map's side of each relation worked out once per map).

**Hierarchical matching**, in the seed's order: two posts, parallel lines, corners, T junctions,
a single post, then (ours) penalty marks, the centre circle and X junctions, then single lines;
within a rank the nearest item first. Iteration k matches the first k items (at least one),
each placed in the field with the current pose to its nearest map candidate (Euclidean distance
of its points, directions weighted by ``direction_scale_m_per_rad``; a line's ends by their
distance to the map segment).

**Point pairs**: a post, a mark and a centre circle seen without direction give one pair; a
junction, a centre circle with direction and a line give two (a junction's vertex and a point
``junction_arm_m`` along its direction; a line's two ends, each paired with its foot on the
map line). A line's pairs count only across the line, the two-of-three constraint of eqs. 6-7
(the field's lines run along x or y), so a line never pins the pose along itself. Each pair
is weighted by the inverse distance of the feature from the robot (at least
``min_weight_distance_m``).

**Least squares step** (eqs. 1-5): with ``c`` the weighted centroid of the placed points
``p_i``, ``J = [[0, -1], [1, 0]]`` and a selection ``S_i`` of the counted components, the step
``(t_x, t_y, dtheta)`` minimises ``sum_i w_i |S_i (q_i - p_i - t - dtheta J (p_i - c))|^2``,
the seed's linearised rotation (``sin dtheta ~ dtheta``, ``cos dtheta ~ 1``) about the
centroid, solved from its normal equations in closed form (the minimum-norm step where a
direction is not constrained, which it leaves alone); the pose is then turned by ``dtheta``
about ``c`` exactly and moved by ``t``. The error ``e`` is the weighted mean of the squared
residuals (eq. 1). The iterations stop once every item is matched and ``e`` falls below
``converged_rms_m²`` or is no lower than in one of the two iterations before, or after
``max_iterations`` (the items matched by then make the observation). The iterations before
matched fewer items, whose error is mostly lower, so with three or more items this usually
stops after the first step that matches them all: noiseless features from a prior 0.2 rad off
end about 0.1 mm from the truth rather than converging further, far inside any detector's
noise (a review's simulation of 495 views: poses within 0.27 of their std, no acceptance
changed). A final RMS above ``accept_rms_m`` says the
features do not fit together (a false detection, or a prior so poor that the match is wrong)
and the observation is refused.

**Information**: first order at the final pose, from the features' covariances: each point
pair's counted components ``S_i (pos + Rot(theta) f_i)`` with ``f_i`` the point in the robot
frame and covariance ``S_i Rot C_i Rot^T S_i^T``; a direction contributes ``1 / std^2`` to the
heading. A junction's second point is not counted again (its vertex and direction are), the
errors of different features are taken as independent.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property, lru_cache
from typing import Literal

import numpy as np

from perception.field.features import AXIAL_KINDS, FEATURE_KINDS, FeatureKind, FieldFeature
from perception.field.field_map import FieldMap, MapFeature
from perception.field.pose_observation import PoseObservation
from perception.geometry import FloatArray, wrap_angle, wrap_scalar
from perception.validation import (
    InvalidTypeError,
    check_choice,
    check_int,
    check_positive,
    finite_vector,
)

_J = np.array([[0.0, -1.0], [1.0, 0.0]])  # a quarter turn: d Rot(a) / da at a = 0
_BOTH = np.ones(2)  # a point pair's mask: both components counted
_X_AXIS, _Y_AXIS = np.array([1.0, 0.0]), np.array([0.0, 1.0])  # the unit axes (read-only)
for _axis in (_BOTH, _X_AXIS, _Y_AXIS):
    _axis.flags.writeable = False
MatchOrder = Literal["seed", "candidates"]
MATCH_ORDERS: tuple[MatchOrder, ...] = ("seed", "candidates")
Starts = Literal["prior", "hypotheses"]
STARTS: tuple[Starts, ...] = ("prior", "hypotheses")
_SAME_FIT_M = 1e-4  # runs whose RMS errors differ by less fit equally well
PARALLEL_RAD = math.radians(10.0)  # two lines within this of each other are parallel

# rank of each item in the hierarchical matching (seed order, ours in between)
RANKS = {
    "two_posts": 0,
    "parallel_lines": 1,
    "corner": 2,
    "t_junction": 3,
    "goal_post": 4,
    "penalty_mark": 5,
    "centre_circle": 6,
    "x_junction": 6,
    "line": 7,
}


@dataclass(frozen=True, kw_only=True)
class SensorModelConfig:
    """Settings of :func:`observe_pose` (module docstring for each; all > 0).

    ``direction_scale_m_per_rad`` (m/rad): a direction difference's weight in the matching
    distance, the seed's "arbitrary scaling factor"; ``junction_arm_m`` (m); ``relation_range_m``
    (m) and ``relation_tolerance_m`` (m): pre-processing; ``min_weight_distance_m`` (m);
    ``max_iterations`` (int >= 1); ``converged_rms_m`` and ``accept_rms_m`` (m); ``order``:
    ``"seed"`` (the seed's ranks, :data:`RANKS`) or ``"candidates"`` (the items with the
    fewest map candidates left by the pre-processing first, the seed's ranks breaking ties:
    distinctiveness measured on this field rather than listed for the seed's); ``starts``:
    ``"prior"`` (the seed's: one ICP from the prior pose) or ``"hypotheses"`` (also one ICP
    from each pose that puts an item fixing the pose alone, a junction with its direction or
    two posts, on one of its candidates; the best fit wins, and of equal fits, the field's
    twins, the one nearest the prior: a hypothesis per candidate, as the field's repeated
    features ask for).
    """

    direction_scale_m_per_rad: float = 0.5
    junction_arm_m: float = 0.5
    relation_range_m: float = 2.5
    relation_tolerance_m: float = 0.3
    min_weight_distance_m: float = 0.3
    max_iterations: int = 30
    converged_rms_m: float = 1e-6
    accept_rms_m: float = 0.15
    order: MatchOrder = "seed"
    starts: Starts = "prior"

    def __post_init__(self) -> None:
        owner = "SensorModelConfig"
        for name in (
            "direction_scale_m_per_rad",
            "junction_arm_m",
            "relation_range_m",
            "relation_tolerance_m",
            "min_weight_distance_m",
            "converged_rms_m",
            "accept_rms_m",
        ):
            check_positive(owner, name, getattr(self, name))
        check_int(owner, "max_iterations", self.max_iterations, 1)
        check_choice(owner, "order", self.order, MATCH_ORDERS)
        check_choice(owner, "starts", self.starts, STARTS)


@dataclass(frozen=True, eq=False)
class MatchItem:
    """What is matched as one: ``kind`` (a feature kind, ``"two_posts"`` or
    ``"parallel_lines"``), its ``features`` (1 or 2, robot frame) and the map ``candidates``
    it may match, each a tuple of as many map features."""

    kind: str
    features: tuple[FieldFeature, ...]
    candidates: tuple[tuple[MapFeature, ...], ...]

    @cached_property
    def distances_m(self) -> tuple[float, ...]:
        """Its features' distances (m) from the robot, worked out once."""
        return tuple(f.distance_m for f in self.features)

    @property
    def distance_m(self) -> float:
        """The nearest of its features' distances from the robot (m)."""
        return min(self.distances_m)


@dataclass(frozen=True)
class SensorModelResult:
    """What :func:`observe_pose` found: ``observation`` (None when refused or nothing could be
    matched), the final ``pose`` (3,) and ``rms_error_m`` even when refused, ``iterations``
    run, and ``matches``: per matched item, the names of the map features it matched."""

    observation: PoseObservation | None
    pose: FloatArray
    rms_error_m: float
    iterations: int
    matches: tuple[tuple[str, ...], ...]


def observe_pose(
    features: Sequence[FieldFeature],
    prior_pose: FloatArray,
    field_map: FieldMap,
    config: SensorModelConfig,
) -> SensorModelResult:
    """The pose observation of one frame's ``features`` from ``prior_pose`` (3,) (m, m, rad,
    field frame) on ``field_map`` (module docstring)."""
    pose = finite_vector(prior_pose, "prior_pose", 3)
    if not isinstance(config, SensorModelConfig):
        raise InvalidTypeError(f"config must be a SensorModelConfig, got {type(config).__name__}")
    if not isinstance(field_map, FieldMap):
        raise InvalidTypeError(f"field_map must be a FieldMap, got {type(field_map).__name__}")
    items = match_items(features, field_map, config)
    if not items:
        return SensorModelResult(None, pose, math.inf, 0, ())
    starts = [pose]
    if config.starts == "hypotheses":
        fixing = [item for item in items if _fixes_pose(item)]
        starts += [_implied_pose(item, c, pose) for item in fixing for c in item.candidates]
    matcher = _Matcher(items, config)
    runs = [_icp(matcher, start, config) for start in starts]
    least = min(run.rms for run in runs)
    # of the runs that fit best (the field's twin poses fit exactly as well), the nearest
    best = min(
        (run for run in runs if run.rms <= least + _SAME_FIT_M),
        key=lambda run: _pose_distance(run.pose, pose, config),
    )
    matches = tuple(tuple(m.name for m in c) for c in best.chosen)
    iterations = sum(run.iterations for run in runs)
    if best.rms > config.accept_rms_m:
        return SensorModelResult(None, best.pose, best.rms, iterations, matches)
    matched = items[: len(best.chosen)]  # all, unless max_iterations stopped it first
    information = _information(matched, best.chosen, best.pose, config)
    features_used = sum(len(i.features) for i in matched)
    observation = PoseObservation(best.pose, information, best.rms, features_used)
    return SensorModelResult(observation, best.pose, best.rms, iterations, matches)


@dataclass(frozen=True)
class _Run:
    """One ICP run: its final ``pose``, ``rms`` error (m), ``iterations`` and the map
    features ``chosen`` for its items."""

    pose: FloatArray
    rms: float
    iterations: int
    chosen: list[tuple[MapFeature, ...]]


def _icp(matcher: _Matcher, start: FloatArray, config: SensorModelConfig) -> _Run:
    """The hierarchical ICP from ``start`` (module docstring) over the matcher's items."""
    pose = start
    errors: list[float] = []
    choice: tuple[int, ...] = ()
    count = len(matcher.items)
    for iteration in range(1, config.max_iterations + 1):
        included = min(iteration, count)
        choice = matcher.nearest(pose, included)
        pairs, turns = matcher.pairs(choice, pose)
        pose = _step(pose, pairs)
        if turns:  # the pairs at the new pose differ: made again
            pairs, _ = matcher.pairs(choice, pose)
        errors.append(_error(pose, pairs))
        if included == count and (
            errors[-1] < config.converged_rms_m**2
            or (len(errors) >= 3 and errors[-1] >= min(errors[-3], errors[-2]))
        ):
            break
    return _Run(pose, math.sqrt(errors[-1]), iteration, matcher.chosen(choice))


def _pose_distance(a: FloatArray, b: FloatArray, config: SensorModelConfig) -> float:
    """Position distance plus the heading difference in metres (``direction_scale``)."""
    heading = abs(wrap_scalar(a[2] - b[2]))
    return float(np.linalg.norm(a[:2] - b[:2])) + config.direction_scale_m_per_rad * heading


# ----- pre-processing ---------------------------------------------------------------------
def match_items(
    features: Sequence[FieldFeature], field_map: FieldMap, config: SensorModelConfig
) -> list[MatchItem]:
    """The features as match items in matching order (module docstring): pre-processed, the
    field edges dropped, sorted by ``config.order`` and then by distance."""
    if isinstance(features, FieldFeature) or not isinstance(features, Sequence):
        raise InvalidTypeError(
            f"features must be a sequence of FieldFeature, got {type(features).__name__}"
        )
    for i, f in enumerate(features):
        if not isinstance(f, FieldFeature):
            raise InvalidTypeError(f"features[{i}] must be a FieldFeature, got {type(f).__name__}")
    edges = [f for f in features if f.kind == "field_edge"]
    posts = [f for f in features if f.kind == "goal_post"]
    lines = _merged_lines([f for f in features if f.kind == "line"], config)
    features = [f for f in features if f.kind != "line"] + lines
    tables = _map_tables(field_map)
    items: list[MatchItem] = []
    paired_posts = _two_posts(posts, tables, field_map, config)
    items += paired_posts
    used = {id(f) for item in paired_posts for f in item.features}
    parallel = _parallel_lines(lines, tables, config)
    items += parallel
    used |= {id(f) for item in parallel for f in item.features}
    for f in features:
        if f.kind == "field_edge" or id(f) in used:
            continue
        candidates = tables.singles[f.kind]
        if f.kind == "t_junction":
            candidates = _related(f, posts, "goal_post", tables, config)
        elif f.kind == "corner" or f.kind == "line":
            candidates = _related(f, edges, "field_edge", tables, config)
        items.append(MatchItem(f.kind, (f,), candidates))
    if config.order == "candidates":
        return sorted(
            items, key=lambda item: (len(item.candidates), RANKS[item.kind], item.distance_m)
        )
    return sorted(items, key=lambda item: (RANKS[item.kind], item.distance_m))


@dataclass(frozen=True, eq=False)
class _MapTables:
    """What the pre-processing asks of one map, worked out once (:func:`_map_tables`).

    ``singles``: per kind, the map's features of that kind as one-feature candidates, in map
    order; ``relations``: per (kind, reference kind) of :data:`_RELATED`, the
    :func:`_relation` (C, M, 2) of each of the C map features of the kind to each of the M
    map references; ``goal_width_m`` (m); ``post_pairs``: the ordered pairs of map posts a
    goal's width apart; ``parallel_pairs``: the ordered pairs of parallel map lines, and
    ``parallel_gaps_m`` (K,) (m), their :func:`_line_gap` s.
    """

    singles: dict[str, tuple[tuple[MapFeature, ...], ...]]
    relations: dict[tuple[str, str], FloatArray]
    goal_width_m: float
    post_pairs: tuple[tuple[MapFeature, MapFeature], ...]
    parallel_pairs: tuple[tuple[MapFeature, MapFeature], ...]
    parallel_gaps_m: FloatArray


# (kind, reference kind): the relations that restrict a kind's candidates (module docstring)
_RELATED: tuple[tuple[FeatureKind, FeatureKind], ...] = (
    ("t_junction", "goal_post"),
    ("corner", "field_edge"),
    ("line", "field_edge"),
)


@lru_cache(maxsize=8)
def _map_tables(field_map: FieldMap) -> _MapTables:
    """The tables of ``field_map`` (kept for the last few maps, by identity): its features
    do not change, so the relations among them are worked out once, not per frame."""
    relations: dict[tuple[str, str], FloatArray] = {}
    for kind, reference_kind in _RELATED:
        features, references = field_map.of_kind(kind), field_map.of_kind(reference_kind)
        relations[kind, reference_kind] = np.array(
            [[_relation(f, r) for r in references] for f in features], dtype=np.float64
        ).reshape(len(features), len(references), 2)
    posts = field_map.of_kind("goal_post")
    goal_posts = field_map.dims.goal_posts()
    width = float(np.linalg.norm(goal_posts[1] - goal_posts[0]))
    lines = field_map.of_kind("line")
    parallel = [
        (a, b)
        for a, b in itertools.permutations(lines, 2)
        if _axial_difference(_segment_angle(a.points), _segment_angle(b.points)) < 1e-6
    ]
    return _MapTables(
        singles={kind: tuple((m,) for m in field_map.of_kind(kind)) for kind in FEATURE_KINDS},
        relations=relations,
        goal_width_m=width,
        post_pairs=tuple(
            (a, b)
            for a, b in itertools.permutations(posts, 2)
            if abs(float(np.linalg.norm(b.points[0] - a.points[0])) - width) < 1e-6
        ),
        parallel_pairs=tuple(parallel),
        parallel_gaps_m=np.array([_line_gap(a.points, b.points) for a, b in parallel]),
    )


def _segment_angle(points: FloatArray) -> float:
    d = points[1] - points[0]
    return math.atan2(d[1], d[0])


def _axial_difference(a: float, b: float) -> float:
    """|a - b| modulo pi, in [0, pi/2]."""
    return abs(wrap_scalar(2.0 * (a - b))) / 2.0


def _line_gap(a: FloatArray, b: FloatArray) -> float:
    """Distance (m) from the midpoint of segment ``b`` to the infinite line through ``a``."""
    d = (a[1] - a[0]) / np.linalg.norm(a[1] - a[0])
    offset = 0.5 * (b[0] + b[1]) - a[0]
    return abs(float(d[0] * offset[1] - d[1] * offset[0]))


def _two_posts(
    posts: list[FieldFeature], tables: _MapTables, field_map: FieldMap, config: SensorModelConfig
) -> list[MatchItem]:
    """The first pair of seen posts about a goal's width apart that some goal's posts fit with
    the robot on the carpet, as a two-posts item."""
    for a, b in itertools.combinations(posts, 2):
        gap = b.points[0] - a.points[0]
        if abs(float(np.linalg.norm(gap)) - tables.goal_width_m) > config.relation_tolerance_m:
            continue
        # both orders of a goal's posts fit the pair; the one that puts the robot off the
        # carpet (behind the goal) is no candidate
        candidates = tuple(
            (ma, mb)
            for ma, mb in tables.post_pairs
            if _on_carpet(_implied_origin(a, b, ma, mb), field_map)
        )
        if candidates:  # none: every order puts the robot off the carpet (noise, or it is)
            return [MatchItem("two_posts", (a, b), candidates)]
    return []


def _implied_origin(a: FieldFeature, b: FieldFeature, ma: MapFeature, mb: MapFeature) -> FloatArray:
    """Where the robot stands (2,) if the seen points ``a``, ``b`` are the map's ``ma``, ``mb``."""
    seen, mapped = b.points[0] - a.points[0], mb.points[0] - ma.points[0]
    turn = math.atan2(mapped[1], mapped[0]) - math.atan2(seen[1], seen[0])
    c, s = math.cos(turn), math.sin(turn)
    return ma.points[0] - np.array([[c, -s], [s, c]]) @ a.points[0]


def _on_carpet(point: FloatArray, field_map: FieldMap) -> bool:
    dims = field_map.dims
    return bool(
        abs(point[0]) <= dims.half_length_m + dims.border_strip_m
        and abs(point[1]) <= dims.half_width_m + dims.border_strip_m
    )


def _parallel_lines(
    lines: list[FieldFeature], tables: _MapTables, config: SensorModelConfig
) -> list[MatchItem]:
    """The first pair of seen parallel lines, with the map line pairs as far apart."""
    for a, b in itertools.combinations(lines, 2):
        if _axial_difference(_segment_angle(a.points), _segment_angle(b.points)) > PARALLEL_RAD:
            continue
        gap = _line_gap(a.points, b.points)
        if gap <= config.relation_tolerance_m:
            continue  # one line (or two collinear ones), not a parallel pair
        fits = np.abs(tables.parallel_gaps_m - gap) <= config.relation_tolerance_m
        candidates = tuple(
            pair for pair, fit in zip(tables.parallel_pairs, fits, strict=True) if fit
        )
        if candidates:
            return [MatchItem("parallel_lines", (a, b), candidates)]
    return []


def _merged_lines(lines: list[FieldFeature], config: SensorModelConfig) -> list[FieldFeature]:
    """``lines`` with collinear ones merged (within ``PARALLEL_RAD`` and with each one's middle
    within ``relation_tolerance_m`` of the other's line): the stretches of one line that the
    two cameras, or two pieces of one image, saw. A merged line spans the outermost ends."""
    merged = list(lines)
    joined = True
    while joined:
        joined = False
        for i, j in itertools.combinations(range(len(merged)), 2):
            a, b = merged[i], merged[j]
            collinear = (
                _axial_difference(_segment_angle(a.points), _segment_angle(b.points))
                <= PARALLEL_RAD
                and _line_gap(a.points, b.points) <= config.relation_tolerance_m
                and _line_gap(b.points, a.points) <= config.relation_tolerance_m
            )
            if collinear:
                merged[i] = _span(a, b)
                del merged[j]
                joined = True
                break
    return merged


def _span(a: FieldFeature, b: FieldFeature) -> FieldFeature:
    """The line through the outermost of ``a``'s and ``b``'s ends (with their covariances)."""
    ends = np.concatenate([a.points, b.points])
    covs = np.concatenate([a.cov, b.cov])
    along = a.points[1] - a.points[0]
    t = ends @ along
    first, last = int(np.argmin(t)), int(np.argmax(t))
    return FieldFeature("line", ends[[first, last]], covs[[first, last]])


def _local(point: FloatArray, origin: FloatArray, direction: float) -> FloatArray:
    """``point`` (2,) in the frame at ``origin`` (2,) turned by ``direction`` (rad)."""
    c, s = math.cos(direction), math.sin(direction)
    d = point - origin
    return np.array([c * d[0] + s * d[1], -s * d[0] + c * d[1]])


def _relation(feature: FieldFeature | MapFeature, other: FieldFeature | MapFeature) -> FloatArray:
    """How ``other`` lies relative to ``feature``: a post's position in a junction's frame
    (2,), or an edge's distance and direction from a corner or line (2,): (distance, angle)."""
    if other.kind == "goal_post":  # beside a T junction, which always has a direction
        return _local(other.points[0], feature.points[0], float(feature.direction or 0.0))
    anchor = 0.5 * (feature.points[0] + feature.points[-1])
    d = (other.points[1] - other.points[0]) / np.linalg.norm(other.points[1] - other.points[0])
    offset = anchor - other.points[0]
    distance = abs(float(d[0] * offset[1] - d[1] * offset[0]))
    base = feature.direction if feature.direction is not None else _segment_angle(feature.points)
    return np.array([distance, _axial_difference(math.atan2(d[1], d[0]), base)])


def _related(
    feature: FieldFeature,
    references: list[FieldFeature],
    reference_kind: FeatureKind,
    tables: _MapTables,
    config: SensorModelConfig,
) -> tuple[tuple[MapFeature, ...], ...]:
    """The map features of the feature's kind as its candidates, restricted to those with a
    map reference placed as each seen one is (the seen references within
    ``relation_range_m`` of the feature; lines need a parallel edge)."""
    candidates = tables.singles[feature.kind]
    near = [
        r
        for r in references
        if _reference_distance(feature, r) <= config.relation_range_m
        and (feature.kind != "line" or _relation(feature, r)[1] <= PARALLEL_RAD)
    ]
    if not near:
        return candidates
    scale = np.array([1.0, config.direction_scale_m_per_rad])
    if reference_kind == "goal_post":
        scale = np.ones(2)
    relations = tables.relations[feature.kind, reference_kind]  # (C, M, 2)
    fits = np.ones(len(candidates), dtype=bool)
    for r in near:
        gaps = (relations - _relation(feature, r)) * scale
        # the norm as np.linalg.norm takes it (a dot product), to the last bit
        fits &= (np.sqrt(np.vecdot(gaps, gaps)) <= config.relation_tolerance_m).any(axis=1)
    kept = tuple(c for c, fit in zip(candidates, fits, strict=True) if fit)
    return kept or candidates  # no map feature fits the relation: noise or a false detection


def _reference_distance(feature: FieldFeature, reference: FieldFeature) -> float:
    if reference.kind == "goal_post":
        return float(np.linalg.norm(reference.points[0] - feature.points[0]))
    return float(_relation(feature, reference)[0])


# ----- matching and point pairs -----------------------------------------------------------
def _place(pose: FloatArray, points: FloatArray) -> FloatArray:
    """Robot-frame ``points`` (N, 2) in the field frame from ``pose`` (3,)."""
    c, s = math.cos(pose[2]), math.sin(pose[2])
    return points @ np.array([[c, s], [-s, c]]) + pose[:2]


def _unit(angle: float) -> FloatArray:
    """The unit vector (2,) at ``angle`` (rad)."""
    return np.array([math.cos(angle), math.sin(angle)])


@dataclass(frozen=True)
class _Pairs:
    """N point pairs: the features' points ``robot`` (N, 2) (robot frame), their map targets
    ``q`` (N, 2) (field frame), the counted components ``mask`` (N, 2) (1 or 0) and the
    weights ``w`` (N,)."""

    robot: FloatArray
    q: FloatArray
    mask: FloatArray
    w: FloatArray


@dataclass(frozen=True)
class _PairLayout:
    """The point pairs of one choice of candidates before the pose is known: ``pairs`` with
    every axial arm at its map direction; per pair, ``flipped_q`` (N, 2), the arm's map
    point for the opposite direction (``q`` elsewhere), and ``seen_direction`` and
    ``map_direction`` (N,) (rad; NaN but for axial arms), which pick one of the two at a
    pose; ``turns``: whether any pair is an axial arm (the pairs depend on the pose)."""

    pairs: _Pairs
    flipped_q: FloatArray
    seen_direction: FloatArray
    map_direction: FloatArray
    turns: bool


class _Matcher:
    """One frame's items laid out once for the ICP's iterations (shared by its runs).

    Each item's candidate ``c`` has the slot ``item * width + c`` (``width``: the most
    candidates of an item). The matching costs (:meth:`nearest`) come in one pass over every
    (feature, candidate) row: a line's two ends' distances to the map segment (rows of
    ``line_slots`` (R,), the seen ends ``line_ends`` (R, 2, 2), the segments' ``starts``
    (R, 2), ``spans`` (R, 2) and ``span_sq`` (R,)); a point's distance plus its direction's
    difference times ``direction_scale_m_per_rad`` (rows of ``point_slots`` (Q,), the seen
    ``points`` (Q, 2) and ``directions`` (Q,) (NaN: none), the map ``targets`` (Q, 2) and
    ``target_directions`` (Q,), ``axial`` (Q,)), added to ``base_costs`` (0, or infinity for an
    empty slot). The point pairs of a choice of candidates are laid out once per choice
    (:meth:`pairs`).
    """

    def __init__(self, items: list[MatchItem], config: SensorModelConfig) -> None:
        self.items, self.config = items, config
        self.width = max(len(item.candidates) for item in items)
        self.base_costs = np.full(len(items) * self.width, math.inf)
        lines: list[tuple[int, FloatArray, FloatArray]] = []  # slot, seen ends, map segment
        points: list[tuple[int, FloatArray, float, FloatArray, float, bool]] = []
        for i, item in enumerate(items):
            self.base_costs[i * self.width : i * self.width + len(item.candidates)] = 0.0
            for k, feature in enumerate(item.features):
                for c, candidate in enumerate(item.candidates):
                    slot, target = i * self.width + c, candidate[k]
                    if feature.kind == "line":
                        lines.append((slot, feature.points, target.points))
                        continue
                    points.append(
                        (
                            slot,
                            feature.points[0],
                            _or_nan(feature.direction),
                            target.points[0],
                            _or_nan(target.direction),
                            feature.kind in AXIAL_KINDS,
                        )
                    )
        line_slots, line_ends, segments = zip(*lines, strict=True) if lines else ((), (), ())
        self.line_slots = np.array(line_slots, dtype=np.intp)
        self.line_ends = np.array(line_ends).reshape(-1, 2, 2)
        segment_points = np.array(segments).reshape(-1, 2, 2)
        self.starts = segment_points[:, 0]
        self.spans = segment_points[:, 1] - segment_points[:, 0]
        self.span_sq = self.spans[:, 0] * self.spans[:, 0] + self.spans[:, 1] * self.spans[:, 1]
        slots, seen, directions, targets, target_directions, axial = (
            zip(*points, strict=True) if points else ((), (), (), (), (), ())
        )
        self.point_slots = np.array(slots, dtype=np.intp)
        self.points = np.array(seen).reshape(-1, 2)
        self.directions = np.array(directions, dtype=np.float64)
        self.targets = np.array(targets).reshape(-1, 2)
        self.target_directions = np.array(target_directions, dtype=np.float64)
        self.axial = np.array(axial, dtype=bool)
        self._layouts: dict[tuple[int, ...], _PairLayout] = {}  # per choice
        self._slots: dict[tuple[int, int], _PairLayout] = {}  # per (item, candidate)

    def nearest(self, pose: FloatArray, count: int) -> tuple[int, ...]:
        """Per item of the first ``count``, the index of its candidate nearest the item placed
        from ``pose`` (the first of equals)."""
        costs = self.base_costs.copy()
        if len(self.line_slots):
            ends = _place(pose, self.line_ends.reshape(-1, 2)).reshape(-1, 2, 2)
            offsets = ends - self.starts[:, None]  # (R, 2 ends, 2)
            along = (
                offsets[..., 0] * self.spans[:, None, 0] + offsets[..., 1] * self.spans[:, None, 1]
            )
            t = np.clip(along / self.span_sq[:, None], 0.0, 1.0)
            gaps = ends - (self.starts[:, None] + t[..., None] * self.spans[:, None])
            distances = np.hypot(gaps[..., 0], gaps[..., 1])
            costs += np.bincount(
                self.line_slots, distances[:, 0] + distances[:, 1], minlength=len(costs)
            )
        if len(self.point_slots):
            placed = _place(pose, self.points)
            distances = np.hypot(
                placed[:, 0] - self.targets[:, 0], placed[:, 1] - self.targets[:, 1]
            )
            turn = self.directions + pose[2] - self.target_directions
            gap = np.where(self.axial, np.abs(wrap_angle(2.0 * turn)) / 2, np.abs(wrap_angle(turn)))
            # no direction on either side (NaN) adds nothing
            scaled = self.config.direction_scale_m_per_rad * np.where(np.isnan(gap), 0.0, gap)
            costs += np.bincount(self.point_slots, distances + scaled, minlength=len(costs))
        return tuple(np.argmin(costs.reshape(-1, self.width)[:count], axis=1).tolist())

    def chosen(self, choice: tuple[int, ...]) -> list[tuple[MapFeature, ...]]:
        """The map features of a ``choice`` of candidate indices (one per leading item)."""
        return [item.candidates[c] for item, c in zip(self.items, choice, strict=False)]

    def pairs(self, choice: tuple[int, ...], pose: FloatArray) -> tuple[_Pairs, bool]:
        """The point pairs (module docstring) of the first ``len(choice)`` items matched to
        their ``choice`` of candidates at ``pose``, and whether they depend on the pose."""
        layout = self._layouts.get(choice)
        if layout is None:
            layout = self._layouts[choice] = _joined(
                [self._slot_layout(i, c) for i, c in enumerate(choice)]
            )
        if not layout.turns:
            return layout.pairs, False
        # an axial arm goes to the map direction nearer the placed feature's
        turn = layout.seen_direction + pose[2] - layout.map_direction
        flip = np.abs(wrap_angle(turn)) > math.pi / 2  # False where NaN: no axial arm
        pairs = layout.pairs
        q = np.where(flip[:, None], layout.flipped_q, pairs.q)
        return _Pairs(pairs.robot, q, pairs.mask, pairs.w), True

    def _slot_layout(self, i: int, c: int) -> _PairLayout:
        """The point pairs of item ``i`` matched to its candidate ``c`` (made once)."""
        key = (i, c)
        if key in self._slots:
            return self._slots[key]
        item = self.items[i]
        # per pair: robot point, map point, the map point of the opposite direction, the seen
        # and map directions (NaN but for an axial arm), counted components, weight
        rows: list[tuple[FloatArray, FloatArray, FloatArray, float, float, FloatArray, float]]
        rows = []
        for feature, distance, target in zip(
            item.features, item.distances_m, item.candidates[c], strict=True
        ):
            weight = _weight(distance, self.config)
            q = target.points[0]
            if feature.kind == "line":
                # lines run along x or y: count only the component across the line (eqs.
                # 6-7), where an end's foot on the map line lies at the line's own coordinate
                across = _across(target)
                rows += [(end, q, q, math.nan, math.nan, across, weight) for end in feature.points]
                continue
            rows.append((feature.points[0], q, q, math.nan, math.nan, _BOTH, weight))
            if feature.direction is not None and target.direction is not None:
                arm = self.config.junction_arm_m
                end = feature.points[0] + arm * _unit(feature.direction)
                arm_q = q + arm * _unit(target.direction)
                if feature.kind in AXIAL_KINDS:
                    flipped = q + arm * _unit(target.direction + math.pi)
                    rows.append(
                        (end, arm_q, flipped, feature.direction, target.direction, _BOTH, weight)
                    )
                else:
                    rows.append((end, arm_q, arm_q, math.nan, math.nan, _BOTH, weight))
        robot, qs, flipped_q, seen, mapped, mask, w = zip(*rows, strict=True)
        seen_direction = np.array(seen, dtype=np.float64)
        layout = self._slots[key] = _PairLayout(
            _Pairs(np.array(robot), np.array(qs), np.array(mask), np.array(w)),
            np.array(flipped_q),
            seen_direction,
            np.array(mapped, dtype=np.float64),
            bool((~np.isnan(seen_direction)).any()),
        )
        return layout


def _joined(layouts: list[_PairLayout]) -> _PairLayout:
    """The pairs of several layouts, in order."""
    if len(layouts) == 1:
        return layouts[0]
    return _PairLayout(
        _Pairs(*(np.concatenate([getattr(x.pairs, f) for x in layouts]) for f in _PAIR_FIELDS)),
        np.concatenate([x.flipped_q for x in layouts]),
        np.concatenate([x.seen_direction for x in layouts]),
        np.concatenate([x.map_direction for x in layouts]),
        any(x.turns for x in layouts),
    )


_PAIR_FIELDS = ("robot", "q", "mask", "w")


def _or_nan(direction: float | None) -> float:
    """``direction`` (rad), NaN for none."""
    return math.nan if direction is None else direction


def _direction(feature: FieldFeature | MapFeature) -> float:
    """The direction of a feature known to have one."""
    if feature.direction is None:
        raise ValueError(f"a {feature.kind} without a direction cannot fix the pose")
    return feature.direction


def _fixes_pose(item: MatchItem) -> bool:
    """Whether the item alone fixes the pose: two posts, or one feature with a direction."""
    return item.kind == "two_posts" or (
        len(item.features) == 1 and item.kind != "line" and item.features[0].direction is not None
    )


def _implied_pose(
    item: MatchItem, candidate: tuple[MapFeature, ...], pose: FloatArray
) -> FloatArray:
    """The robot pose (3,) that puts a pose-fixing item exactly on ``candidate`` (an axial
    direction: the branch nearer ``pose``'s heading)."""
    seen = item.features
    if item.kind == "two_posts":
        a, b = seen[0].points[0], seen[1].points[0]
        ma, mb = candidate[0].points[0], candidate[1].points[0]
        heading = math.atan2(*(mb - ma)[::-1]) - math.atan2(*(b - a)[::-1])
        anchor, mapped = a, ma
    else:
        feature, target = seen[0], candidate[0]
        heading = _direction(target) - _direction(feature)
        if feature.kind in AXIAL_KINDS and abs(wrap_scalar(heading - pose[2])) > math.pi / 2:
            heading += math.pi
        anchor, mapped = feature.points[0], target.points[0]
    c, s = math.cos(heading), math.sin(heading)
    position = mapped - np.array([[c, -s], [s, c]]) @ anchor
    return np.array([position[0], position[1], wrap_scalar(heading)])


def _step(pose: FloatArray, pairs: _Pairs) -> FloatArray:
    """One least-squares step (module docstring): the new pose."""
    p = _place(pose, pairs.robot)
    w = pairs.w
    centre = (w[:, None] * p).sum(axis=0) / w.sum()
    levers = (p - centre) @ _J.T  # (N, 2): d (placed point) / d dtheta
    t_x, t_y, dtheta = _step_solution(w[:, None] * pairs.mask, levers, pairs.q - p)
    c, s = math.cos(dtheta), math.sin(dtheta)
    turned = centre + np.array([[c, -s], [s, c]]) @ (pose[:2] - centre) + np.array([t_x, t_y])
    return np.array([turned[0], turned[1], wrap_scalar(pose[2] + dtheta)])


def _step_solution(
    weights: FloatArray, levers: FloatArray, residuals: FloatArray
) -> tuple[float, float, float]:
    """``(t_x, t_y, dtheta)`` minimising ``sum_i,a weights[i, a] (residuals[i, a] - t_a -
    dtheta levers[i, a])^2`` (each (N, 2); a weight 0 leaves a component out; at least one
    weight > 0, else ValueError).

    The normal equations have the block form ``[[S_x, 0, L_x], [0, S_y, L_y], [L_x, L_y,
    L]]`` (per axis the weights' sum ``S_a`` and their moments of the levers ``L_a``):
    ``dtheta`` from its Schur complement, then each translation. The minimum-norm choice
    where nothing pins a parameter down: an axis without a counted component (lines along
    it only) gets no translation, and a turn whose Schur complement is under 1e-12 of the
    largest ``S_a`` (levers within a micrometre of each other: one point) none."""
    columns = np.stack([np.ones_like(levers), levers, residuals], axis=2)  # (N, 2, 3)
    moments = np.einsum("na,nai,naj->aij", weights, columns, columns)  # (2, 3, 3)
    axes = [row for row in moments[:, :2].tolist() if row[0][0] > 0.0]  # S_a, L_a, B_a; ...
    if not axes:
        raise ValueError("weights must hold at least one value > 0, got none")
    schur = sum(ll - lv * lv / w for (w, lv, _), (_, ll, _) in axes)
    dtheta = 0.0
    if schur > 1e-12 * max(w for (w, _, _), _ in axes):
        dtheta = sum(bl - lv * b / w for (w, lv, b), (_, _, bl) in axes) / schur
    shift = [(b - lv * dtheta) / w if w > 0.0 else 0.0 for w, lv, b in moments[:, 0].tolist()]
    return shift[0], shift[1], dtheta


def _error(pose: FloatArray, pairs: _Pairs) -> float:
    """Weighted mean squared residual (m²) of the point pairs placed from ``pose`` (eq. 1,
    counted components only)."""
    residual = pairs.mask * (pairs.q - _place(pose, pairs.robot))
    return float((pairs.w * (residual**2).sum(axis=1)).sum() / pairs.w.sum())


def _information(
    items: list[MatchItem],
    chosen: list[tuple[MapFeature, ...]],
    pose: FloatArray,
    config: SensorModelConfig,
) -> FloatArray:
    """The pose's information (3, 3) at ``pose``: the pseudo-inverse of the weighted least
    squares' covariance (module docstring)."""
    c, s = math.cos(pose[2]), math.sin(pose[2])
    turn = np.array([[c, -s], [s, c]])
    rows: list[FloatArray] = []  # per counted row: d (row's coordinate) / d pose
    weights: list[float] = []  # per row
    sources: list[dict[int, float]] = []  # per row: its error's coefficient per noise source
    noise: list[float] = []  # per independent noise source: its variance
    for item, targets in zip(items, chosen, strict=True):
        for feature, distance, target in zip(item.features, item.distances_m, targets, strict=True):
            w = _weight(distance, config)
            if feature.kind == "line":
                # per end, the component across the map line: its row (n, n . J Rot f) and its
                # variance (Rot^T n)^T C (Rot^T n), in floats
                n_x, n_y = _across(target).tolist()
                u_x, u_y = c * n_x + s * n_y, c * n_y - s * n_x  # Rot^T n
                for (f_x, f_y), ((c_xx, c_xy), (c_yx, c_yy)) in zip(
                    feature.points.tolist(), feature.cov.tolist(), strict=True
                ):
                    lever = -n_x * (s * f_x + c * f_y) + n_y * (c * f_x - s * f_y)
                    rows.append(np.array([n_x, n_y, lever]))
                    weights.append(w)
                    sources.append({len(noise): 1.0})
                    noise.append(u_x * u_x * c_xx + u_x * u_y * (c_xy + c_yx) + u_y * u_y * c_yy)
                continue
            # the vertex's error (two independent sources along the eigenvectors of its
            # field-frame covariance) and, for a directed feature, the direction's
            values, vectors = np.linalg.eigh(turn @ feature.cov[0] @ turn.T)
            vertex = len(noise)
            noise += [float(v) for v in values]
            points = [feature.points[0]]
            swing = np.zeros(2)
            if feature.direction is not None and target.direction is not None:
                arm = config.junction_arm_m * _unit(feature.direction)
                points.append(feature.points[0] + arm)
                swing = turn @ _J @ arm  # how the arm's point moves with the direction
                noise.append(feature.direction_std**2)
            for k, point in enumerate(points):
                A = np.hstack([np.eye(2), (_J @ turn @ point)[:, None]])
                for axis in (0, 1):
                    rows.append(A[axis])
                    weights.append(w)
                    source = {vertex: float(vectors[axis, 0]), vertex + 1: float(vectors[axis, 1])}
                    if k == 1:  # the arm's point: the direction's source, added after the vertex
                        source[vertex + 2] = float(swing[axis])
                    sources.append(source)
    A = np.array(rows)
    W = np.array(weights)  # the weight matrix's diagonal
    B = np.zeros((len(rows), len(noise)))
    for r, source in enumerate(sources):
        for k, value in source.items():
            B[r, k] = value
    # products with the diagonal weights and noise as the scalings of columns they are (in C
    # order, which sums them as the matrix products did, to the last bit)
    error_cov = (B * np.array(noise)) @ B.T
    normal = np.ascontiguousarray(A.T * W) @ A
    normal_inverse = _pseudo_inverse(normal)
    cov = ((((normal_inverse @ A.T) * W) @ error_cov) * W) @ A @ normal_inverse
    information = _pseudo_inverse(0.5 * (cov + cov.T))
    return 0.5 * (information + information.T)


def _pseudo_inverse(matrix: FloatArray) -> FloatArray:
    """The pseudo-inverse of a symmetric ``matrix`` (n, n): its eigenvalues of magnitude
    above 1e-10 of the largest inverted, the others (a direction without information) 0,
    as :func:`numpy.linalg.pinv` with ``rcond=1e-10, hermitian=True``."""
    values, vectors = np.linalg.eigh(matrix)
    magnitude = np.abs(values)
    kept = magnitude > 1e-10 * magnitude.max()
    inverse = np.divide(1.0, values, out=np.zeros_like(values), where=kept)
    inverted: FloatArray = (vectors * inverse) @ vectors.T
    return inverted


def _weight(distance_m: float, config: SensorModelConfig) -> float:
    """The weight of a feature's pairs: the inverse of its distance (m) from the robot."""
    return 1.0 / max(distance_m, config.min_weight_distance_m)


def _across(target: MapFeature) -> FloatArray:
    """The unit axis (2,) across a map line: y for a line along x, x for one along y."""
    along = target.points[1] - target.points[0]
    return _Y_AXIS if abs(along[0]) > abs(along[1]) else _X_AXIS
