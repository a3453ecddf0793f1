"""Room scenes (office, backyard) against independent plane geometry, and their validation."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterator

import numpy as np
import pytest

from spl_env.scenes.backyard import BACKYARD
from spl_env.scenes.office import OFFICE
from spl_env.scenes.rooms import RoomLayout, RoomScene, SceneObject
from spl_env.sim.world import BulletWorld

LASER_Z_M = 0.30
SONAR_Z_M = 0.21
CLEARANCE_M = 0.45
RAY_LENGTH_M = 30.0


def _column(name: str, x: float, y: float, r: float = 0.2) -> SceneObject:
    return SceneObject(name=name, kind="column", x_m=x, y_m=y, radius_m=r, height_m=1.0)


def _layout(**changes: object) -> RoomLayout:
    base: dict[str, object] = {
        "name": "test",
        "half_size_m": (3.0, 2.0),
        "objects": (_column("a", 0.0, 0.0), _column("b", 1.0, 0.0)),
        "waypoints": ((-2.0, -1.2), (2.0, -1.2), (2.0, 1.2), (-2.0, 1.2)),
        "start_pose": (-2.0, 1.2, 0.0),
    }
    base.update(changes)
    return RoomLayout(**base)  # type: ignore[arg-type]


# ----- validation ---------------------------------------------------------------------------
def test_valid_layout_builds() -> None:
    layout = _layout()
    np.testing.assert_array_equal(layout.circles, [[0.0, 0.0, 0.2], [1.0, 0.0, 0.2]])


@pytest.mark.parametrize(
    ("changes", "pattern"),
    [
        ({"objects": (_column("a", 0.0, 0.0), _column("b", 0.39, 0.0))}, r"objects\[1\].*overlap"),
        ({"objects": (_column("a", 0.0, 0.0), _column("a", 1.0, 0.0))}, r"objects\[1\]\.name"),
        ({"objects": (_column("walls", 0.0, 0.0),)}, r"objects\[0\]\.name"),
        ({"objects": ()}, r"RoomLayout\.objects"),
        ({"objects": (_column("a", 2.85, 0.0),)}, r"objects\[0\].*inside the walls"),
        ({"objects": (_column("a", 0.0, -1.85),)}, r"objects\[0\].*inside the walls"),
        ({"waypoints": ((-2.0, -1.2), (0.0, -0.6))}, r"waypoints\[1\].*from a"),
        ({"waypoints": ((-2.0, -1.2), (2.7, -1.2))}, r"waypoints\[1\].*wall"),
        ({"waypoints": ((-2.0, -0.3), (2.0, 0.5))}, r"waypoints leg 0"),
        ({"waypoints": ((-2.0, -1.2),)}, r"RoomLayout\.waypoints"),
        ({"waypoints": ((-2.0, -1.2), (-2.0, -1.2))}, r"waypoints\[0\]"),
        ({"start_pose": (0.5, 0.1, 0.0)}, r"RoomLayout\.start_pose"),
        ({"start_pose": (2.0, 1.2, 0.0)}, r"start_pose leg"),  # passes through both columns
        ({"start_pose": (0.0, 0.0)}, r"RoomLayout\.start_pose"),
        ({"half_size_m": (3.0, -2.0)}, r"RoomLayout\.half_size_m"),
        ({"wall_height_m": 0.4}, r"RoomLayout\.wall_height_m"),
    ],
)
def test_layout_rejects(changes: dict[str, object], pattern: str) -> None:
    with pytest.raises(ValueError, match=pattern):
        _layout(**changes)


@pytest.mark.parametrize(
    ("changes", "pattern"),
    [
        ({"flat_side_m": 0.2}, r"SceneObject\.flat_side_m.*got 0\.2"),  # d = R
        ({"flat_side_m": 0.0}, r"SceneObject\.flat_side_m"),
        ({"flat_side_m": -0.1}, r"SceneObject\.flat_side_m"),
        ({"flat_side_direction_rad": math.nan}, r"SceneObject\.flat_side_direction_rad"),
        ({"kind": "table"}, r"SceneObject\.kind"),
        ({"radius_m": 0.0}, r"SceneObject\.radius_m"),
        ({"height_m": 0.5}, r"SceneObject\.height_m"),
        ({"x_m": math.inf}, r"SceneObject\.x_m"),
        ({"rgba": (1.0, 0.0, 0.0, 2.0)}, r"SceneObject\.rgba"),
        ({"name": ""}, r"SceneObject\.name"),
    ],
)
def test_object_rejects(changes: dict[str, object], pattern: str) -> None:
    base: dict[str, object] = {
        "name": "t",
        "kind": "tree",
        "x_m": 0.0,
        "y_m": 0.0,
        "radius_m": 0.2,
        "height_m": 1.0,
    }
    base.update(changes)
    with pytest.raises(ValueError, match=pattern):
        SceneObject(**base)  # type: ignore[arg-type]


def test_object_rejects_wrong_types() -> None:
    with pytest.raises(TypeError, match=r"SceneObject\.name"):
        SceneObject(name=3, kind="tree", x_m=0.0, y_m=0.0, radius_m=0.2, height_m=1.0)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match=r"SceneObject\.radius_m"):
        SceneObject(name="t", kind="tree", x_m=0.0, y_m=0.0, radius_m="0.2", height_m=1.0)  # type: ignore[arg-type]


def test_outline_of_flat_sided_trunk() -> None:
    r, d, phi = 0.4, 0.25, 2.0
    obj = SceneObject(
        name="t",
        kind="tree",
        x_m=1.0,
        y_m=-2.0,
        radius_m=r,
        height_m=1.0,
        flat_side_m=d,
        flat_side_direction_rad=phi,
    )
    outline = obj.outline(720)
    rel = outline - [1.0, -2.0]
    np.testing.assert_allclose(np.hypot(rel[:, 0], rel[:, 1]), r, atol=1e-12)  # all on the circle
    normal = np.array([math.cos(phi), math.sin(phi)])
    assert (rel @ normal <= d + 1e-12).all()
    np.testing.assert_allclose(rel[[0, -1]] @ normal, d, atol=1e-12)  # chord ends
    x, y = outline[:, 0], outline[:, 1]
    area = 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))  # > 0: counter-clockwise
    cap = r * r * math.acos(d / r) - d * math.sqrt(r * r - d * d)  # the cut-off circular segment
    assert area == pytest.approx(math.pi * r * r - cap, rel=1e-4)
    round_outline = dataclasses.replace(obj, flat_side_m=None).outline(64)
    assert round_outline.shape == (64, 2)


# ----- geometry of the two layouts ----------------------------------------------------------
def _wall_gap(layout: RoomLayout, circle: np.ndarray) -> float:
    hx, hy = layout.half_size_m
    return float(min(hx - abs(circle[0]), hy - abs(circle[1])) - circle[2])


def test_office_holds_the_corner_cases() -> None:
    circles = OFFICE.circles
    kinds = [obj.kind for obj in OFFICE.objects]
    assert kinds.count("column") == 5 and kinds.count("plant") == 1
    columns = circles[[k == "column" for k in kinds]]
    gaps = [
        math.dist(a[:2], b[:2]) - a[2] - b[2]
        for i, a in enumerate(columns)
        for b in columns[i + 1 :]
    ]
    assert min(gaps) < 0.4
    assert columns[:, 2].max() >= 0.5
    plant = circles[kinds.index("plant")]
    assert 0.0 < _wall_gap(OFFICE, plant) <= 0.1


def test_backyard_trees_have_flat_sides() -> None:
    assert len(BACKYARD.objects) == 5
    directions = []
    for tree in BACKYARD.objects:
        assert tree.kind == "tree"
        assert tree.flat_side_m is not None and 0.0 < tree.flat_side_m < tree.radius_m
        assert 0.15 <= tree.radius_m <= 0.45
        directions.append(tree.flat_side_direction_rad % (2 * math.pi))
    assert len({round(d, 3) for d in directions}) == 5


@pytest.mark.parametrize("layout", [OFFICE, BACKYARD], ids=["office", "backyard"])
def test_route_keeps_clear_and_laps(layout: RoomLayout) -> None:
    route = np.array(layout.waypoints)
    assert 4 <= len(route) <= 8
    legs = [*zip(route, np.roll(route, -1, axis=0), strict=True)]
    legs.append((np.array(layout.start_pose[:2]), route[0]))
    lap = sum(math.dist(a, b) for a, b in legs[:-1])
    assert 25.0 <= lap <= 40.0
    samples = np.concatenate([a + np.linspace(0, 1, 400)[:, None] * (b - a) for a, b in legs])
    hx, hy = layout.half_size_m
    assert (hx - np.abs(samples[:, 0]) >= CLEARANCE_M).all()
    assert (hy - np.abs(samples[:, 1]) >= CLEARANCE_M).all()
    for x, y, r in layout.circles:
        assert (np.hypot(samples[:, 0] - x, samples[:, 1] - y) - r >= CLEARANCE_M - 1e-9).all()
    assert all(obj.height_m > 0.5 for obj in layout.objects) and layout.wall_height_m > 0.5


# ----- the built scenes against analytic ray casts ------------------------------------------
@pytest.fixture(scope="module", params=[OFFICE, BACKYARD], ids=["office", "backyard"])
def built(request: pytest.FixtureRequest) -> Iterator[tuple[BulletWorld, RoomScene]]:
    world = BulletWorld(time_step_s=0.01)
    scene = RoomScene(world, request.param)
    yield world, scene
    world.close()


def _ray_convex(o: np.ndarray, u: np.ndarray, obj: SceneObject) -> tuple[float, str, float]:
    """Entry distance of the ray o + t u (u unit) into the object's plan view (disk, cut by the
    half-plane (p - c) . n <= d for a flat side), the face it enters by, and the cosine of
    incidence there: (inf, "", 0) on a miss."""
    c = np.array([obj.x_m, obj.y_m])
    w = o - c
    b, q = float(w @ u), float(w @ w) - obj.radius_m**2
    disc = b * b - q
    if disc <= 0.0:
        return math.inf, "", 0.0
    t_in, t_out, face = -b - math.sqrt(disc), -b + math.sqrt(disc), "round"
    if obj.flat_side_m is not None:
        n = np.array([math.cos(obj.flat_side_direction_rad), math.sin(obj.flat_side_direction_rad)])
        un, wn = float(u @ n), float(w @ n)
        if un < 0.0:  # entering the half-plane at the chord's line
            t_plane = (obj.flat_side_m - wn) / un
            if t_plane > t_in:
                t_in, face = t_plane, "flat"
        elif un > 0.0:
            t_out = min(t_out, (obj.flat_side_m - wn) / un)
        elif wn > obj.flat_side_m:
            return math.inf, "", 0.0
    if t_in > t_out or t_in < 0.0:
        return math.inf, "", 0.0
    point = o + t_in * u
    cosine = -un if face == "flat" else abs(float((point - c) @ u)) / obj.radius_m
    return t_in, face, cosine


def _ray_walls(o: np.ndarray, u: np.ndarray, segments: np.ndarray) -> float:
    """Distance along the ray o + t u to the nearest wall segment (inner faces)."""
    best = math.inf
    for a, b in segments:
        e = b - a
        den = u[0] * e[1] - u[1] * e[0]
        if abs(den) < 1e-12:
            continue
        w = a - o
        t = (w[0] * e[1] - w[1] * e[0]) / den
        s = (w[0] * u[1] - w[1] * u[0]) / den
        if t > 0.0 and 0.0 <= s <= 1.0:
            best = min(best, t)
    return best


def _expected(
    o: np.ndarray, u: np.ndarray, layout: RoomLayout, segments: np.ndarray
) -> tuple[float, str, str, bool]:
    """Nearest hit: distance, body name, face, and whether it is safe to compare (no grazing
    incidence on the hit object, no near-miss of a nearer object)."""
    best = (_ray_walls(o, u, segments), "walls", "wall")
    safe = True
    hits = []
    for obj in layout.objects:
        t, face, cosine = _ray_convex(o, u, obj)
        hits.append((t, obj.name, face, cosine))
        c = np.array([obj.x_m, obj.y_m])
        along = float((c - o) @ u)
        miss = abs(float(u[0] * (c - o)[1] - u[1] * (c - o)[0])) / obj.radius_m
        if along > 0.0 and 0.9 < miss < 1.1 and along < best[0] + obj.radius_m:
            safe = False  # grazes this object's edge: the ray might just hit or just miss
    for t, name, face, cosine in hits:
        if t < best[0]:
            best = (t, name, face)
            safe = safe and cosine > 0.3
    return best[0], best[1], best[2], safe


def _route_points(layout: RoomLayout) -> np.ndarray:
    route = np.array(layout.waypoints)
    mids = 0.5 * (route + np.roll(route, -1, axis=0))
    return np.concatenate([route, mids])


def _cast(world: BulletWorld, origins: np.ndarray, dirs: np.ndarray, z: float):
    starts = np.column_stack([origins, np.full(len(origins), z)])
    ends = starts + RAY_LENGTH_M * np.column_stack([dirs, np.zeros(len(dirs))])
    fractions, ids = world.ray_test(starts, ends)
    return fractions * RAY_LENGTH_M, ids


def test_rays_hit_objects_and_walls_where_geometry_says(built) -> None:
    world, scene = built
    layout = scene.layout
    segments = scene.wall_segments()
    origins, dirs = [], []
    for o in _route_points(layout):
        for angle in np.linspace(-math.pi, math.pi, 36, endpoint=False):  # a coarse scan
            origins.append(o)
            dirs.append([math.cos(angle), math.sin(angle)])
        for obj in layout.objects:  # a fan across each object, and at its flat side's middle
            c = np.array([obj.x_m, obj.y_m])
            targets = [c + f * obj.radius_m * np.array([0.0, 1.0]) for f in (-0.6, 0.0, 0.6)]
            targets += [c + f * obj.radius_m * np.array([1.0, 0.0]) for f in (-0.6, 0.6)]
            if obj.flat_side_m is not None:
                phi = obj.flat_side_direction_rad
                n = np.array([math.cos(phi), math.sin(phi)])
                chord = math.sqrt(obj.radius_m**2 - obj.flat_side_m**2)
                for f in (-0.5, 0.0, 0.5):
                    targets.append(c + obj.flat_side_m * n + f * chord * np.array([-n[1], n[0]]))
            for target in targets:
                v = target - o
                origins.append(o)
                dirs.append(v / np.linalg.norm(v))
    origins_a, dirs_a = np.array(origins), np.array(dirs)
    names = {world.body(name): name for name in ["walls", *(ob.name for ob in layout.objects)]}
    faces_checked: dict[str, int] = {"wall": 0, "round": 0, "flat": 0}
    hit_names: set[str] = set()
    for z in (LASER_Z_M, SONAR_Z_M):
        distances, ids = _cast(world, origins_a, dirs_a, z)
        for o, u, dist, body in zip(origins_a, dirs_a, distances, ids, strict=True):
            t, name, face, safe = _expected(o, u, layout, segments)
            if not safe:
                continue
            assert names.get(int(body)) == name, (o, u, t, name)
            assert dist == pytest.approx(t, abs=1e-3), (o, u, name, face)
            faces_checked[face] += 1
            hit_names.add(name)
    assert hit_names == set(names.values())
    assert faces_checked["wall"] > 50 and faces_checked["round"] > 50
    if layout is BACKYARD:
        assert faces_checked["flat"] > 20


def test_every_object_is_seen_from_several_sides(built) -> None:
    """From points along the route, rays at each object's centre hit it from >= 3 octants."""
    world, scene = built
    layout = scene.layout
    route = np.array(layout.waypoints)
    points = np.concatenate(
        [
            a + np.linspace(0, 1, 20, endpoint=False)[:, None] * (b - a)
            for a, b in zip(route, np.roll(route, -1, axis=0), strict=True)
        ]
    )
    for obj in layout.objects:
        c = np.array([obj.x_m, obj.y_m])
        v = c - points
        dist = np.linalg.norm(v, axis=1)
        _, ids = _cast(world, points, v / dist[:, None], LASER_Z_M)
        seen = (ids == world.body(obj.name)) & (dist - obj.radius_m < 10.0)  # laser range
        bearings = np.arctan2(-v[seen, 1], -v[seen, 0])  # from the object to the robot
        octants = set(np.floor(bearings / (math.pi / 4)).astype(int).tolist())
        assert len(octants) >= 3, (obj.name, octants)


def test_pot_is_below_a_ray_above_it() -> None:
    world = BulletWorld(time_step_s=0.01)
    try:
        scene = RoomScene(world, OFFICE)
        plant = next(obj for obj in OFFICE.objects if obj.kind == "plant")
        start = np.array([[plant.x_m, 3.0, plant.height_m + 0.05]])
        distances, ids = _cast(world, start[:, :2], np.array([[0.0, 1.0]]), start[0, 2])
        assert ids[0] == world.body("walls")
        assert distances[0] == pytest.approx(scene.half_size_m[1] - 3.0, abs=1e-6)
        np.testing.assert_array_equal(scene.obstacles, OFFICE.circles)
        hx, hy = scene.half_size_m
        np.testing.assert_allclose(
            scene.wall_segments(),
            [
                [[-hx, -hy], [hx, -hy]],
                [[hx, -hy], [hx, hy]],
                [[hx, hy], [-hx, hy]],
                [[-hx, hy], [-hx, -hy]],
            ],
        )
    finally:
        world.close()


# ----- BulletWorld.add_static_prism ---------------------------------------------------------
def test_prism_is_concave_and_exact() -> None:
    world = BulletWorld(time_step_s=0.01)
    try:
        ell = np.array([[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2]], dtype=float)
        shifted = ell[::-1] + np.array([3.0, 0.0])  # clockwise
        body = world.add_static_prism("ell", shifted, 1.0, (1, 0, 0, 1))
        # into the notch (x in (4, 5), y in (1, 2)): hits the inner face x = 4 at y = 1.5
        starts = np.array([[5.5, 1.5, 0.3], [5.5, 0.5, 0.3], [4.5, 1.5, 1.2]])
        ends = np.array([[2.5, 1.5, 0.3], [2.5, 0.5, 0.3], [4.5, 1.5, 0.2]])
        fractions, ids = world.ray_test(starts, ends)
        lengths = np.linalg.norm(ends - starts, axis=1)
        np.testing.assert_allclose(fractions[:2] * lengths[:2], [1.5, 0.5], atol=1e-6)
        assert (ids[:2] == body).all()
        assert ids[2] == -1  # down through the notch: nothing
        world.add_static_prism("slab", ell, 0.4, (0, 0, 1, 1), base_z_m=0.2)
        f, i = world.ray_test(np.array([[0.5, 0.5, 1.0]]), np.array([[0.5, 0.5, 0.0]]))
        assert i[0] == world.body("slab") and f[0] == pytest.approx(0.4, abs=1e-6)  # top at 0.6
        bowtie = np.array([[0.0, 0.0], [3.0, 1.0], [3.0, 0.0], [0.0, 2.0]])
        with pytest.raises(ValueError, match=r"simple.*crosses"):
            world.add_static_prism("bowtie", bowtie, 1.0, (1, 1, 1, 1))
        with pytest.raises(ValueError, match="simple"):
            world.add_static_prism("line", np.array([[0, 0], [1, 1], [2, 2.0]]), 1.0, (1, 1, 1, 1))
        with pytest.raises(ValueError, match="height_m"):
            world.add_static_prism("flat", ell, 0.0, (1, 1, 1, 1))
    finally:
        world.close()
