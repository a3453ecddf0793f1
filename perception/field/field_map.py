"""The map of the SPL field's features in the field frame (seed 004 §2.2, Fig. 1).

Built from :class:`~perception.field.dimensions.FieldDimensions`; kinds and conventions as in
:mod:`perception.field.features`. On the 2025 field:

- 17 straight ``line`` s (2 touch lines, 2 goal lines, the halfway line, and 3 lines each of
  the two penalty areas and two goal areas), each a whole segment;
- 4 ``field_edge`` s: the carpet's edges, ``border_strip_m`` beyond the outer lines;
- 12 ``corner`` s: the field's 4 and the 4 each of the penalty and goal areas' front corners;
- 10 ``t_junction`` s: the halfway line on the touch lines, the penalty and goal areas' side
  lines on the goal lines;
- 2 ``x_junction`` s: the halfway line crossing the centre circle;
- 1 ``centre_circle`` (its direction along the halfway line), 2 ``penalty_mark`` s and 4
  ``goal_post`` s.

The field is symmetric under a half turn about its centre, so every feature has a twin there
(the centre circle and the halfway line are their own): field features alone cannot tell the
two halves apart.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from perception.field.dimensions import FieldDimensions
from perception.field.features import (
    FeatureKind,
    check_direction,
    check_kind,
    checked_points,
)
from perception.geometry import FloatArray


@dataclass(frozen=True, eq=False)
class MapFeature:
    """One feature of the field map: ``kind``, ``points`` (P, 2) m in the field frame (a line's
    or edge's whole segment), ``direction`` (rad, field frame, or None) and a ``name`` that says
    which it is (e.g. ``"corner_penalty_area_+x_+y"``)."""

    kind: FeatureKind
    points: FloatArray
    name: str
    direction: float | None = None

    def __post_init__(self) -> None:
        check_kind(self.kind, "MapFeature")
        points = checked_points(self.points, self.kind, "MapFeature")
        points.flags.writeable = False  # maps are shared (shared_field_map)
        object.__setattr__(self, "points", points)
        check_direction(self.kind, self.direction, "MapFeature")


class FieldMap:
    """The field's features (module docstring), from ``dims`` (default: the 2025 rule book)."""

    def __init__(self, dims: FieldDimensions | None = None) -> None:
        if dims is None:
            dims = FieldDimensions()
        elif not isinstance(dims, FieldDimensions):
            raise TypeError(f"dims must be a FieldDimensions or None, got {type(dims).__name__}")
        self.dims = dims
        self.features: tuple[MapFeature, ...] = (
            *_lines(dims),
            *_edges(dims),
            *_corners(dims),
            *_t_junctions(dims),
            *_x_junctions(dims),
            _feature("centre_circle", [(0.0, 0.0)], "centre_circle", math.pi / 2),
            *(
                _feature("penalty_mark", [p], f"penalty_mark_{_sign(p[0])}x")
                for p in dims.penalty_marks()
            ),
            *(
                _feature("goal_post", [p], f"goal_post_{_sign(p[0])}x_{_sign(p[1])}y")
                for p in dims.goal_posts()
            ),
        )

    def of_kind(self, kind: FeatureKind) -> tuple[MapFeature, ...]:
        """The map's features of ``kind``, in map order."""
        check_kind(kind, "FieldMap.of_kind")
        return tuple(f for f in self.features if f.kind == kind)


@functools.cache
def shared_field_map(dims: FieldDimensions) -> FieldMap:
    """One :class:`FieldMap` of ``dims`` for every env and player of the process: a map never
    changes (its features' points are read-only), and what the sensor model and the view test
    work out from a map once, kept by the map's identity, then serves them all (a team of ten
    perceiving players, a vector of envs)."""
    return FieldMap(dims)


def _feature(
    kind: FeatureKind, points: ArrayLike, name: str, direction: float | None = None
) -> MapFeature:
    return MapFeature(kind, np.array(points, dtype=np.float64), name, direction)


def _sign(value: float) -> str:
    return "+" if value > 0 else "-"


def _lines(dims: FieldDimensions) -> list[MapFeature]:
    names = ["touch_line_-y", "touch_line_+y", "goal_line_-x", "goal_line_+x", "halfway_line"]
    for side in ("-", "+"):
        for area in ("penalty_area", "goal_area"):
            names += [f"{area}_{side}x_side_-y", f"{area}_{side}x_side_+y", f"{area}_{side}x_front"]
    return [
        _feature("line", np.reshape(segment, (2, 2)), name)
        for segment, name in zip(dims.line_segments(), names, strict=True)
    ]


def _edges(dims: FieldDimensions) -> list[MapFeature]:
    x = dims.half_length_m + dims.border_strip_m
    y = dims.half_width_m + dims.border_strip_m
    return [
        _feature("field_edge", [(-x, -y), (x, -y)], "field_edge_-y"),
        _feature("field_edge", [(-x, y), (x, y)], "field_edge_+y"),
        _feature("field_edge", [(-x, -y), (-x, y)], "field_edge_-x"),
        _feature("field_edge", [(x, -y), (x, y)], "field_edge_+x"),
    ]


def _bisector(arm_a: ArrayLike, arm_b: ArrayLike) -> float:
    """Direction (rad) halfway between two unit arm directions."""
    mid = np.asarray(arm_a, dtype=np.float64) + np.asarray(arm_b, dtype=np.float64)
    return math.atan2(mid[1], mid[0])


def _corners(dims: FieldDimensions) -> list[MapFeature]:
    hl, hw = dims.half_length_m, dims.half_width_m
    corners = []
    for sx in (-1.0, 1.0):
        for sy in (-1.0, 1.0):
            tag = f"{_sign(sx)}x_{_sign(sy)}y"
            # the field's corner: arms along the goal line and the touch line, inwards
            corners.append(
                _feature(
                    "corner",
                    [(sx * hl, sy * hw)],
                    f"corner_field_{tag}",
                    _bisector((-sx, 0), (0, -sy)),
                )
            )
            for area, depth, width in (
                ("penalty_area", dims.penalty_area_length_m, dims.penalty_area_width_m),
                ("goal_area", dims.goal_area_length_m, dims.goal_area_width_m),
            ):
                # the area's front corner: arms along its side line (to the goal line) and
                # along its front line (to the middle)
                vertex = (sx * (hl - depth), sy * width / 2)
                direction = _bisector((sx, 0), (0, -sy))
                corners.append(_feature("corner", [vertex], f"corner_{area}_{tag}", direction))
    return corners


def _t_junctions(dims: FieldDimensions) -> list[MapFeature]:
    hl, hw = dims.half_length_m, dims.half_width_m
    junctions = [
        _feature(
            "t_junction", [(0.0, sy * hw)], f"t_junction_halfway_{_sign(sy)}y", math.atan2(-sy, 0)
        )
        for sy in (-1.0, 1.0)
    ]
    for sx in (-1.0, 1.0):
        for area, width in (
            ("penalty_area", dims.penalty_area_width_m),
            ("goal_area", dims.goal_area_width_m),
        ):
            for sy in (-1.0, 1.0):
                junctions.append(
                    _feature(
                        "t_junction",
                        [(sx * hl, sy * width / 2)],
                        f"t_junction_{area}_{_sign(sx)}x_{_sign(sy)}y",
                        math.atan2(0.0, -sx),
                    )
                )
    return junctions


def _x_junctions(dims: FieldDimensions) -> list[MapFeature]:
    r = dims.centre_circle_diameter_m / 2
    return [
        _feature("x_junction", [(0.0, sy * r)], f"x_junction_{_sign(sy)}y", math.pi / 2)
        for sy in (-1.0, 1.0)
    ]
