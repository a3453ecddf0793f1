"""The field map against the rule book's geometry, and the field feature type's checks."""

from __future__ import annotations

import math
from collections import Counter

import numpy as np
import pytest

from perception.field.dimensions import FieldDimensions
from perception.field.features import FieldFeature
from perception.field.field_map import FieldMap, shared_field_map
from perception.geometry import wrap_angle

FIELD = FieldMap()
DIMS = FieldDimensions()


def test_the_map_holds_the_2025_fields_features() -> None:
    counts = Counter(f.kind for f in FIELD.features)
    assert counts == {
        "line": 17,
        "field_edge": 4,
        "corner": 12,
        "t_junction": 10,
        "x_junction": 2,
        "centre_circle": 1,
        "penalty_mark": 2,
        "goal_post": 4,
    }
    assert len({f.name for f in FIELD.features}) == len(FIELD.features)


def test_one_shared_map_per_field_size_with_read_only_points() -> None:
    """Every env and player of a process gets the same map of a field size (the per-map
    caches of the sensor model and view test then serve them all), and nobody can move it."""
    assert shared_field_map(DIMS) is shared_field_map(FieldDimensions())
    smaller = FieldDimensions(length_m=7.5, width_m=5.0)
    assert shared_field_map(smaller) is not shared_field_map(DIMS)
    assert shared_field_map(smaller).dims == smaller
    points = shared_field_map(DIMS).features[0].points
    with pytest.raises(ValueError, match="read-only"):
        points[0, 0] = 1.0


def test_every_feature_has_its_half_turn_twin() -> None:
    for feature in FIELD.features:
        twin_points = -feature.points
        twins = [
            f
            for f in FIELD.of_kind(feature.kind)
            if {tuple(np.round(p, 9)) for p in f.points}
            == {tuple(np.round(p, 9)) for p in twin_points}
        ]
        assert len(twins) == 1, feature.name
        if feature.direction is not None:
            turned = feature.direction + math.pi
            gap = abs(float(wrap_angle(turned - twins[0].direction)))
            if feature.kind in ("x_junction", "centre_circle"):
                gap = min(gap, math.pi - gap)
            assert gap < 1e-9, feature.name


def test_junctions_lie_on_two_lines_and_point_into_the_painted_angle() -> None:
    lines = [f.points for f in FIELD.of_kind("line")]

    def on_line(point: np.ndarray, segment: np.ndarray) -> bool:
        a, b = segment
        t = (point - a) @ (b - a) / ((b - a) @ (b - a))
        return bool(-1e-9 <= t <= 1 + 1e-9 and np.linalg.norm(a + t * (b - a) - point) < 1e-9)

    for junction in FIELD.of_kind("corner") + FIELD.of_kind("t_junction"):
        vertex = junction.points[0]
        assert sum(on_line(vertex, s) for s in lines) == 2, junction.name
        # a step along the direction stays on a painted line (T: the stem) or inside the
        # corner's angle, between its arms (both arms' lines then lie beside it)
        step = vertex + 0.3 * np.array([math.cos(junction.direction), math.sin(junction.direction)])
        if junction.kind == "t_junction":
            assert any(on_line(step, s) for s in lines), junction.name
        else:
            assert abs(step[0]) <= DIMS.half_length_m and abs(step[1]) <= DIMS.half_width_m


def test_x_junctions_are_where_the_halfway_line_meets_the_centre_circle() -> None:
    r = DIMS.centre_circle_diameter_m / 2
    points = sorted(tuple(f.points[0]) for f in FIELD.of_kind("x_junction"))
    assert points == [(0.0, -r), (0.0, r)]


def test_edges_lie_a_border_strip_beyond_the_outer_lines() -> None:
    x = DIMS.half_length_m + DIMS.border_strip_m
    y = DIMS.half_width_m + DIMS.border_strip_m
    ends = {tuple(p) for f in FIELD.of_kind("field_edge") for p in f.points}
    assert ends == {(-x, -y), (x, -y), (-x, y), (x, y)}


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"kind": "pole"}, "kind"),
        ({"kind": 3}, "kind"),
        ({"points": [[0.0, 1.0]]}, "points"),  # a line needs two ends
        ({"points": [[0.0, 1.0], [0.0, 1.0]]}, "points"),
        ({"points": [[0.0, np.nan], [1.0, 1.0]]}, "points"),
        ({"cov": np.eye(2)}, "cov"),
        ({"cov": np.array([np.eye(2), -np.eye(2)])}, "cov"),
        ({"direction": 0.3}, "direction"),
        ({"direction_std": 0.1}, "direction_std"),
    ],
)
def test_bad_line_features_are_refused(kwargs: dict, message: str) -> None:
    fields = {
        "kind": "line",
        "points": [[1.0, 0.0], [2.0, 0.0]],
        "cov": np.array([np.eye(2), np.eye(2)]) * 1e-4,
    } | kwargs
    with pytest.raises((ValueError, TypeError), match=message):
        FieldFeature(**fields)


def test_directions_are_required_or_refused_by_kind() -> None:
    cov = np.eye(2)[None] * 1e-4
    with pytest.raises(ValueError, match="direction"):
        FieldFeature("corner", [[1.0, 0.0]], cov)
    with pytest.raises(ValueError, match="direction"):
        FieldFeature("goal_post", [[1.0, 0.0]], cov, 0.2, 0.1)
    with pytest.raises(ValueError, match="direction_std"):
        FieldFeature("corner", [[1.0, 0.0]], cov, 0.2)  # a direction needs its std
    circle = FieldFeature("centre_circle", [[1.0, 0.0]], cov)  # its direction is optional
    assert circle.direction is None


def test_a_trusted_feature_is_stored_as_a_constructed_one() -> None:
    points, cov = np.array([[1.0, 0.5]]), np.eye(2)[None] * 1e-4
    built = FieldFeature("corner", points, cov, np.float64(0.3), 0.1)
    trusted = FieldFeature.trusted("corner", points, cov, np.float64(0.3), 0.1)
    for name in ("kind", "direction", "direction_std"):
        assert getattr(trusted, name) == getattr(built, name)
        assert type(getattr(trusted, name)) is type(getattr(built, name))
    for name in ("points", "cov"):
        assert np.array_equal(getattr(trusted, name), getattr(built, name))
        assert getattr(trusted, name) is not locals()[name]  # a copy, as construction makes
    assert FieldFeature.trusted("goal_post", points, cov).direction is None


def test_a_lines_distance_is_to_its_nearest_point() -> None:
    line = FieldFeature("line", [[1.0, -2.0], [1.0, 2.0]], np.array([np.eye(2)] * 2) * 1e-4)
    assert line.distance_m == pytest.approx(1.0)
    post = FieldFeature("goal_post", [[3.0, 4.0]], np.eye(2)[None] * 1e-4)
    assert post.distance_m == pytest.approx(5.0)
