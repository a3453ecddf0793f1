"""Field features: what a frame shows of the field's markings and goals (seed 004 §2.2).

One :class:`FieldFeature` per thing seen, in the robot frame (m, rad; x forward, y left), with
the covariance of each of its points. The kinds, and what ``points`` and ``direction`` hold:

==================  ======  ===============================================================
kind                points  direction (rad, robot frame)
==================  ======  ===============================================================
``line``            2       None: the two ends of the part of a straight line that was seen
``field_edge``      2       None: the two ends of a seen stretch of the carpet's edge
``corner``          1       the vertex of an L; along its bisector, into its opening
``t_junction``      1       the vertex of a T; along its stem, away from its bar
``x_junction``      1       where two lines cross; along one of them (known modulo pi)
``centre_circle``   1       its centre; along the halfway line through it (modulo pi) when
                            that was seen, else None
``penalty_mark``    1       None: the mark's centre
``goal_post``       1       None: where the post stands on the ground
==================  ======  ===============================================================

:class:`~perception.field.field_map.FieldMap` holds the same kinds in the field frame.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal, get_args

import numpy as np

from perception.geometry import FloatArray
from perception.validation import InvalidTypeError, check_covariance, check_finite, check_real

FeatureKind = Literal[
    "line",
    "field_edge",
    "corner",
    "t_junction",
    "x_junction",
    "centre_circle",
    "penalty_mark",
    "goal_post",
]
FEATURE_KINDS: tuple[FeatureKind, ...] = get_args(FeatureKind)
SEGMENT_KINDS: frozenset[str] = frozenset({"line", "field_edge"})  # two points, no direction
DIRECTED_KINDS: frozenset[str] = frozenset({"corner", "t_junction", "x_junction"})  # required
# directions known modulo pi: the line through an X junction or the centre circle
AXIAL_KINDS: frozenset[str] = frozenset({"x_junction", "centre_circle"})


def points_of(kind: str) -> int:
    """How many points a feature of ``kind`` has: 2 for segments, else 1."""
    return 2 if kind in SEGMENT_KINDS else 1


def check_direction(kind: str, direction: float | None, owner: str) -> None:
    """Raise unless ``direction`` suits ``kind`` (module table): a finite number for the
    directed kinds, None for segments, marks and posts, either for the centre circle."""
    if kind in DIRECTED_KINDS and direction is None:
        raise ValueError(f"{owner}.direction is required for a {kind}, got None")
    if kind in SEGMENT_KINDS | {"penalty_mark", "goal_post"} and direction is not None:
        raise ValueError(f"{owner}.direction must be None for a {kind}, got {direction!r}")
    if direction is not None:
        check_finite(owner, "direction", direction)


def check_kind(kind: object, owner: str) -> None:
    """Raise unless ``kind`` is one of :data:`FEATURE_KINDS`."""
    if not isinstance(kind, str):
        raise InvalidTypeError(f"{owner}.kind must be a str, got {type(kind).__name__}")
    if kind not in FEATURE_KINDS:
        raise ValueError(f"{owner}.kind must be one of {FEATURE_KINDS}, got {kind!r}")


def checked_points(points: object, kind: str, owner: str) -> FloatArray:
    """``points`` as a finite (P, 2) float array with P = :func:`points_of` (``kind``)."""
    size = points_of(kind)
    try:
        array = np.array(points, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise InvalidTypeError(f"{owner}.points must be numbers, got {points!r}") from error
    if array.shape != (size, 2):
        raise ValueError(
            f"{owner}.points must have shape ({size}, 2) for a {kind}, got {array.shape}"
        )
    if not np.isfinite(array).all():
        raise ValueError(f"{owner}.points must be finite, got {array.tolist()}")
    if kind in SEGMENT_KINDS and np.allclose(array[0], array[1]):
        raise ValueError(f"{owner}.points must be two distinct ends, got {array.tolist()}")
    return array


@dataclass(frozen=True, eq=False)
class FieldFeature:
    """One feature seen in a frame, in the robot frame (module docstring for each kind).

    ``points`` (P, 2) m; ``direction`` rad or None; ``cov`` (P, 2, 2) m², each point's
    covariance (symmetric positive definite); ``direction_std`` rad (> 0), the direction's
    standard deviation, NaN when ``direction`` is None. Bad fields raise ``ValueError``
    (``InvalidTypeError`` for a wrong type) naming ``FieldFeature.<field>``.
    """

    kind: FeatureKind
    points: FloatArray
    cov: FloatArray
    direction: float | None = None
    direction_std: float = math.nan

    def __post_init__(self) -> None:
        owner = "FieldFeature"
        check_kind(self.kind, owner)
        points = checked_points(self.points, self.kind, owner)
        try:
            cov = np.array(self.cov, dtype=np.float64)
        except (TypeError, ValueError) as error:
            raise InvalidTypeError(f"{owner}.cov must be numbers, got {self.cov!r}") from error
        if cov.shape != (len(points), 2, 2):
            raise ValueError(f"{owner}.cov must have shape ({len(points)}, 2, 2), got {cov.shape}")
        for i, block in enumerate(cov):
            check_covariance(block, f"{owner}.cov[{i}]", 2)
        check_direction(self.kind, self.direction, owner)
        check_real(owner, "direction_std", self.direction_std)
        if self.direction is None:
            if not math.isnan(self.direction_std):
                raise ValueError(
                    f"{owner}.direction_std must be NaN without a direction, "
                    f"got {self.direction_std!r}"
                )
        elif not (math.isfinite(self.direction_std) and self.direction_std > 0):
            raise ValueError(
                f"{owner}.direction_std must be finite and > 0 with a direction, "
                f"got {self.direction_std!r}"
            )
        object.__setattr__(self, "points", points)
        object.__setattr__(self, "cov", cov)
        if self.direction is not None:
            object.__setattr__(self, "direction", float(self.direction))

    @classmethod
    def trusted(
        cls,
        kind: FeatureKind,
        points: FloatArray,
        cov: FloatArray,
        direction: float | None = None,
        direction_std: float = math.nan,
    ) -> FieldFeature:
        """A feature from fields its caller built and knows valid (a detector's own finite
        (P, 2) ``points`` and covariances ``cov`` (P, 2, 2)), stored as construction would
        store them (float64 copies, ``direction`` as a float) without checking them again:
        the fast path of :mod:`perception.vision.field_features` and of the features placed
        from the map (:mod:`perception.field.visibility`, the geometric mode's emulator);
        other code constructs."""
        feature = object.__new__(cls)
        object.__setattr__(feature, "kind", kind)
        object.__setattr__(feature, "points", np.array(points, dtype=np.float64))
        object.__setattr__(feature, "cov", np.array(cov, dtype=np.float64))
        object.__setattr__(feature, "direction", None if direction is None else float(direction))
        object.__setattr__(feature, "direction_std", direction_std)
        return feature

    @property
    def distance_m(self) -> float:
        """Distance (m) from the robot origin to the feature's nearest point (a segment's
        nearest end, or its nearest point between them)."""
        return feature_distance(self.kind, self.points)


def feature_distance(kind: str, points: FloatArray) -> float:
    """The distance (m) from the robot origin to the nearest point of a feature of ``kind`` at
    ``points`` (P, 2), robot frame: a segment's nearest point between its ends, else its
    first point."""
    if kind not in SEGMENT_KINDS:
        return float(np.hypot(*points[0]))
    a, b = points
    t = float(np.clip(-(a @ (b - a)) / float((b - a) @ (b - a)), 0.0, 1.0))
    return float(np.hypot(*(a + t * (b - a))))
