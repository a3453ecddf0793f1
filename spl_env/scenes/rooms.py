"""Walled rooms with circular objects, for seed 001's circle mapping: the shared scene builder.

A :class:`RoomLayout` is a rectangle of walls centred on the origin, the circular objects
standing in it (:class:`SceneObject`: columns, plant pots, tree trunks) and the closed route a
robot drives (waypoints visited in order, then again from the first: seed 001 Fig. 5.3's graph).
:class:`RoomScene` builds a layout in a :class:`~spl_env.sim.world.BulletWorld` and answers
what is where. The layouts themselves are :data:`spl_env.scenes.office.OFFICE` and
:data:`spl_env.scenes.backyard.BACKYARD`.

Frames and units: the field frame has its origin at the room's centre, x along its length,
y along its width, z up, all in m; angles in rad, counter-clockwise from +x.

Objects are vertical prisms over their plan-view outline (:meth:`SceneObject.outline` with
:data:`BUILD_OUTLINE_VERTICES` vertices on the circle), built as static triangle meshes
(:meth:`~spl_env.sim.world.BulletWorld.add_static_prism`): rays hit their faces exactly, so a
horizontal ray meets a round object within ``R (1 - cos(π / 256))`` (0.05 mm for R = 0.6 m) of
the true circle, away from grazing incidence. PyBullet's cylinder primitive, ray cast by a
convex cast, was off by up to 0.5 mm head-on and 6 mm near grazing, too coarse for a laser
whose circle fits seed 001 scores in cm. Ground truth of an object is its circle ``(x, y, R)``;
for a trunk with a flat side, the circle of its round part.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from perception.geometry import FloatArray
from perception.validation import (
    InvalidTypeError,
    check_choice,
    check_finite,
    check_in_interval,
    check_int,
    check_positive,
    finite_vector,
)
from spl_env.sim.world import BulletWorld, VisualPart

OBJECT_KINDS = ("column", "plant", "tree")
ROUTE_CLEARANCE_M = 0.45  # robot body radius 0.25 m + 0.2 m margin, from objects and walls
MIN_HEIGHT_M = 0.5  # objects and walls stand above the laser (0.30 m) and sonars (0.21 m)
BUILD_OUTLINE_VERTICES = 256  # vertices of a full circle when an object is built
WALLS_BODY = "walls"
WALL_RGBA = (0.86, 0.84, 0.80, 1.0)
OBJECT_RGBA = (0.78, 0.78, 0.76, 1.0)


@dataclass(frozen=True, kw_only=True)
class SceneObject:
    """A standing circular object: a column, a plant pot or a tree trunk, in the field frame.

    Its plan view is the circle of centre ``(x_m, y_m)`` and radius ``radius_m`` (m), or, with
    ``flat_side_m`` = d (0 < d < R), that circle cut by a chord at distance d from the centre
    whose outward normal points along ``flat_side_direction_rad`` (rad, field frame): a trunk
    with a flat side, whose straight part is ``2 sqrt(R² - d²)`` long. It stands from the
    ground to ``height_m`` (m, > 0.5). ``rgba`` in [0, 1]. ``kind`` is one of
    :data:`OBJECT_KINDS`; ``name`` becomes its body name.
    """

    name: str
    kind: str
    x_m: float
    y_m: float
    radius_m: float
    height_m: float
    flat_side_m: float | None = None
    flat_side_direction_rad: float = 0.0
    rgba: tuple[float, float, float, float] = OBJECT_RGBA

    def __post_init__(self) -> None:
        owner = "SceneObject"
        _check_name(owner, "name", self.name)
        check_choice(owner, "kind", self.kind, OBJECT_KINDS)
        check_finite(owner, "x_m", self.x_m)
        check_finite(owner, "y_m", self.y_m)
        check_positive(owner, "radius_m", self.radius_m)
        check_in_interval(owner, "height_m", self.height_m, MIN_HEIGHT_M, math.inf)
        if self.flat_side_m is not None:
            check_in_interval(owner, "flat_side_m", self.flat_side_m, 0.0, self.radius_m)
        check_finite(owner, "flat_side_direction_rad", self.flat_side_direction_rad)
        _check_rgba(owner, "rgba", self.rgba)

    @property
    def circle(self) -> FloatArray:
        """The ground truth (3,): centre x, y and radius R (m), field frame."""
        return np.array([self.x_m, self.y_m, self.radius_m], dtype=np.float64)

    def outline(self, n: int = 96) -> FloatArray:
        """The plan-view outline (M, 2) (m, field frame), counter-clockwise, not closed.

        A round object: ``n`` vertices on the circle, the first at angle 0. A flat-sided one:
        the arc from one end of the chord round to the other, its vertices on the circle at
        the spacing of an ``n``-gon (at least 2 segments), then back along the chord (the
        closing edge from the last vertex to the first).
        """
        check_int("SceneObject.outline", "n", n, 8)
        centre = np.array([self.x_m, self.y_m])
        r = self.radius_m
        if self.flat_side_m is None:
            angles = 2 * math.pi * np.arange(n) / n
        else:
            half = math.acos(self.flat_side_m / r)  # half the angle the chord subtends
            arc = 2 * math.pi - 2 * half
            segments = max(2, math.ceil(n * arc / (2 * math.pi)))
            angles = self.flat_side_direction_rad + half + arc * np.arange(segments + 1) / segments
        return centre + r * np.column_stack([np.cos(angles), np.sin(angles)])


@dataclass(frozen=True, kw_only=True)
class RoomLayout:
    """A walled rectangle with its objects and the route a robot drives through it.

    ``half_size_m`` (2,): the inner half length (x) and half width (y) of the walled area (m),
    centred on the origin; walls ``wall_height_m`` high (> 0.5) and ``wall_thickness_m`` thick
    stand outside it. ``objects``: at least one, unique names (not ``"walls"``), each inside
    the walls, none touching another. ``waypoints`` (W >= 2) are field-frame points (m),
    visited in order and then again from the first; ``start_pose`` is the robot's start
    ``(x, y, θ)`` (m, m, rad), from which it drives to the first waypoint. Every waypoint, the
    start, and each straight leg between them (last -> first and start -> first included) stay
    :data:`ROUTE_CLEARANCE_M` from every object's circle and every wall.
    """

    name: str
    half_size_m: tuple[float, float]
    wall_height_m: float = 1.0
    wall_thickness_m: float = 0.1
    objects: tuple[SceneObject, ...]
    waypoints: tuple[tuple[float, float], ...]
    start_pose: tuple[float, float, float]

    def __post_init__(self) -> None:
        owner = "RoomLayout"
        _check_name(owner, "name", self.name)
        half = finite_vector(self.half_size_m, f"{owner}.half_size_m", 2)
        if not (half > 0).all():
            raise ValueError(f"{owner}.half_size_m must be > 0, got {self.half_size_m!r}")
        check_in_interval(owner, "wall_height_m", self.wall_height_m, MIN_HEIGHT_M, math.inf)
        check_positive(owner, "wall_thickness_m", self.wall_thickness_m)
        self._check_objects(half)
        if not isinstance(self.waypoints, tuple) or len(self.waypoints) < 2:
            raise ValueError(
                f"{owner}.waypoints must be a tuple of at least 2 points, got {self.waypoints!r}"
            )
        points = [
            finite_vector(w, f"{owner}.waypoints[{i}]", 2) for i, w in enumerate(self.waypoints)
        ]
        start = finite_vector(self.start_pose, f"{owner}.start_pose", 3)
        for i, point in enumerate(points):
            self._check_clearance(f"waypoints[{i}]", point, point, half)
        self._check_clearance("start_pose", start[:2], start[:2], half)
        for i, point in enumerate(points):
            following = points[(i + 1) % len(points)]
            if np.array_equal(point, following):
                raise ValueError(
                    f"{owner}.waypoints[{i}] and the next waypoint must differ, got {point}"
                )
            self._check_clearance(f"waypoints leg {i} -> next", point, following, half)
        self._check_clearance("start_pose leg -> waypoints[0]", start[:2], points[0], half)

    def _check_objects(self, half: FloatArray) -> None:
        owner = "RoomLayout.objects"
        if not isinstance(self.objects, tuple) or len(self.objects) < 1:
            raise ValueError(
                f"{owner} must be a tuple of at least 1 SceneObject, got {self.objects!r}"
            )
        names: set[str] = set()
        for i, obj in enumerate(self.objects):
            if not isinstance(obj, SceneObject):
                raise InvalidTypeError(
                    f"{owner}[{i}] must be a SceneObject, got {type(obj).__name__}"
                )
            if obj.name in names or obj.name == WALLS_BODY:
                raise ValueError(
                    f"{owner}[{i}].name must be unique and not {WALLS_BODY!r}, got {obj.name!r}"
                )
            names.add(obj.name)
            gap = float((half - np.abs(obj.circle[:2]) - obj.radius_m).min())
            if gap <= 0.0:
                raise ValueError(
                    f"{owner}[{i}] ({obj.name}) must lie inside the walls (|x| + R < "
                    f"{half[0]}, |y| + R < {half[1]}), got circle {obj.circle.tolist()}"
                )
        circles = self.circles
        for i in range(len(circles)):
            for j in range(i):
                gap = math.dist(circles[i, :2], circles[j, :2]) - circles[i, 2] - circles[j, 2]
                if gap <= 0.0:
                    raise ValueError(
                        f"{owner}[{i}] ({self.objects[i].name}) must not overlap "
                        f"{owner}[{j}] ({self.objects[j].name}), got a gap of {gap:.3f} m"
                    )

    def _check_clearance(self, what: str, a: FloatArray, b: FloatArray, half: FloatArray) -> None:
        """Raise unless the segment a-b (points (2,), m) keeps the route clearance."""
        # the room is convex: a segment keeps its clearance from the walls if its ends do
        wall = float(min((half - np.abs(a)).min(), (half - np.abs(b)).min()))
        if wall < ROUTE_CLEARANCE_M:
            raise ValueError(
                f"RoomLayout.{what} must stay at least {ROUTE_CLEARANCE_M} m from every wall, "
                f"got {wall:.3f} m ({a.tolist()} to {b.tolist()})"
            )
        for obj in self.objects:
            gap = _segment_point_distance(a, b, obj.circle[:2]) - obj.radius_m
            if gap < ROUTE_CLEARANCE_M:
                raise ValueError(
                    f"RoomLayout.{what} must stay at least {ROUTE_CLEARANCE_M} m from every "
                    f"object, got {gap:.3f} m from {obj.name} ({a.tolist()} to {b.tolist()})"
                )

    @property
    def circles(self) -> FloatArray:
        """Every object's circle (K, 3): x, y, R (m, field frame), in layout order."""
        return np.array([obj.circle for obj in self.objects], dtype=np.float64).reshape(-1, 3)

    def route(self) -> FloatArray:
        """The waypoints (W, 2) (m, field frame), in order."""
        return np.array(self.waypoints, dtype=np.float64).reshape(-1, 2)

    def lap_length_m(self) -> float:
        """Length (m) of one lap of the closed route, last waypoint back to the first included."""
        route = self.route()
        return float(np.linalg.norm(np.roll(route, -1, axis=0) - route, axis=1).sum())


class RoomScene:
    """A :class:`RoomLayout` built in a :class:`BulletWorld`, and its ground truth.

    The walls are one static compound body named ``"walls"`` (four boxes, the ones along x
    covering the corners); each object is a static prism named after it
    (:meth:`BulletWorld.add_static_prism` over :meth:`SceneObject.outline` with
    :data:`BUILD_OUTLINE_VERTICES`), round ones included: see the module docstring.
    """

    def __init__(self, world: BulletWorld, layout: RoomLayout) -> None:
        if not isinstance(layout, RoomLayout):
            raise InvalidTypeError(
                f"RoomScene.layout must be a RoomLayout, got {type(layout).__name__}"
            )
        self.world = world
        self.layout = layout
        hx, hy = (float(v) for v in layout.half_size_m)
        t, h = layout.wall_thickness_m, layout.wall_height_m
        world.add_static(
            WALLS_BODY,
            [
                VisualPart(
                    shape="box",
                    size=(hx + t, t / 2, h / 2),
                    position=(0.0, y, h / 2),
                    rgba=WALL_RGBA,
                )
                for y in (-(hy + t / 2), hy + t / 2)
            ]
            + [
                VisualPart(
                    shape="box", size=(t / 2, hy, h / 2), position=(x, 0.0, h / 2), rgba=WALL_RGBA
                )
                for x in (-(hx + t / 2), hx + t / 2)
            ],
        )
        for obj in layout.objects:
            world.add_static_prism(
                obj.name, obj.outline(BUILD_OUTLINE_VERTICES), obj.height_m, obj.rgba
            )

    @property
    def obstacles(self) -> FloatArray:
        """Ground-truth circles (K, 3): x, y, R (m, field frame), = ``layout.circles``."""
        return self.layout.circles

    @property
    def half_size_m(self) -> tuple[float, float]:
        """Inner half length (x) and half width (y) of the walled area (m)."""
        return (float(self.layout.half_size_m[0]), float(self.layout.half_size_m[1]))

    def wall_segments(self) -> FloatArray:
        """The walls' inner faces (4, 2, 2) as segments [[x0, y0], [x1, y1]] (m, field frame):
        south, east, north, west, running counter-clockwise round the room."""
        hx, hy = self.half_size_m
        corners = np.array([[-hx, -hy], [hx, -hy], [hx, hy], [-hx, hy]])
        return np.stack([corners, np.roll(corners, -1, axis=0)], axis=1)


def _segment_point_distance(a: FloatArray, b: FloatArray, point: FloatArray) -> float:
    """Distance (m) from ``point`` (2,) to the segment a-b (2,), a single point when a = b."""
    ab = b - a
    length2 = float(ab @ ab)
    t = 0.0 if length2 == 0.0 else min(1.0, max(0.0, float((point - a) @ ab) / length2))
    return float(np.linalg.norm(a + t * ab - point))


def _check_name(owner: str, name: str, value: object) -> None:
    if not isinstance(value, str):
        raise InvalidTypeError(f"{owner}.{name} must be a str, got {type(value).__name__}")
    if not value:
        raise ValueError(f"{owner}.{name} must be a non-empty str, got {value!r}")


def _check_rgba(owner: str, name: str, value: object) -> None:
    rgba = finite_vector(value, f"{owner}.{name}", 4)  # type: ignore[arg-type]
    if not ((rgba >= 0.0) & (rgba <= 1.0)).all():
        raise ValueError(f"{owner}.{name} must be 4 numbers in [0, 1], got {value!r}")
