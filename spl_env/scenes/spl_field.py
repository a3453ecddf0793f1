"""The SPL field scene: the static world built from primitive shapes, and its ground truth.

Carpet (the world's painted floor) with painted lines (one mesh), two goals, the six landmark
poles of seed 000, a ball, and boards with textured posters around the field for realistic
clutter.
:class:`SplFieldScene` builds it once per env and answers what is where: the poles (landmark
ids and positions), the obstacles robots walk around, the ball's body.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field
from importlib import resources

import numpy as np

from perception.geometry import FloatArray
from perception.types import PoleCode, PoleGeometry
from perception.validation import (
    check_bool,
    check_choice,
    check_in_interval,
    check_int,
    check_nested_configs,
    check_positive,
)
from spl_env.field import FieldDimensions, PoleLayout
from spl_env.scenes.spectators import Spectators
from spl_env.sim.world import BulletWorld, TriangleMesh, VisualPart

CARPET_RGBA = (0.16, 0.48, 0.18, 1.0)
LINE_RGBA = (0.95, 0.95, 0.95, 1.0)
GOAL_RGBA = (0.97, 0.97, 0.97, 1.0)
NET_RGBA = (0.55, 0.55, 0.58, 1.0)
BALL_RGBA = (0.92, 0.92, 0.92, 1.0)
BOARD_RGBA = (0.75, 0.72, 0.68, 1.0)
POLE_BAND_RGBA: dict[str, tuple[float, float, float, float]] = {
    "pink": (1.0, 0.32, 0.68, 1.0),
    "yellow": (0.98, 0.86, 0.08, 1.0),
    "blue": (0.08, 0.30, 0.95, 1.0),
    "green": (0.0, 0.82, 0.52, 1.0),
}
# the poster sets of spl_env/assets/make_posters.py: "classic" (the default since the start;
# drawn with replacement, 12 for 20 panels) and "textured" (upright structure along every row:
# natural landmarks on the horizon; 40, drawn without replacement: every panel its own, so that
# the field's two ends look different, as a real hall's do)
POSTER_SETS = {
    "classic": tuple(f"poster_{i:02d}.png" for i in range(12)),
    "textured": tuple(f"textured_{i:02d}.png" for i in range(40)),
}
DISTINCT_POSTERS = {"classic": False, "textured": True}
LINE_THICKNESS_M = 0.002  # painted lines lie this high above the carpet


@dataclass(frozen=True, kw_only=True)
class SceneConfig:
    """What the scene contains."""

    dimensions: FieldDimensions = field(default_factory=FieldDimensions)
    poles: PoleLayout = field(default_factory=PoleLayout)
    poles_enabled: bool = True
    boards_enabled: bool = True
    board_distance_m: float = 0.6  # from the carpet's edge to the boards
    board_height_m: float = 1.2
    board_panel_width_m: float = 2.0  # each panel carries one poster
    ball_mass_kg: float = 0.044  # SPL ball mass
    ball_rolling_friction: float = 0.0015
    scene_seed: int = 0  # picks the posters when the world is built
    poster_set: str = "classic"  # one of POSTER_SETS
    # People walking between the carpet and the boards (spl_env.scenes.spectators); 0: none
    spectators: int = 0
    spectator_speed_mps: float = 1.0
    # The painted lines are cut into pieces no longer than this (m) for the tiny renderer,
    # which scans each triangle's screen bounding box: short pieces waste less of that scan on
    # long thin lines seen aslant; the pixels do not change.
    line_piece_m: float = 0.5

    def __post_init__(self) -> None:
        check_nested_configs(self)
        owner = "SceneConfig"
        check_bool(owner, "poles_enabled", self.poles_enabled)
        check_bool(owner, "boards_enabled", self.boards_enabled)
        for name in ("board_distance_m", "board_height_m", "board_panel_width_m", "ball_mass_kg"):
            check_positive(owner, name, getattr(self, name))
        check_in_interval(
            owner, "ball_rolling_friction", self.ball_rolling_friction, 0.0, 1.0, low_inclusive=True
        )
        check_int(owner, "scene_seed", self.scene_seed, 0)
        check_choice(owner, "poster_set", self.poster_set, tuple(POSTER_SETS))
        check_int(owner, "spectators", self.spectators, 0)
        check_positive(owner, "spectator_speed_mps", self.spectator_speed_mps, upper=3.0)
        check_positive(owner, "line_piece_m", self.line_piece_m, upper=20.0)
        carpet_l = self.dimensions.carpet_size_m[0]
        r = self.poles.geometry.radius_m
        if self.poles.offset_outside_m + r > self.dimensions.border_strip_m:
            raise ValueError(
                "SceneConfig.poles.offset_outside_m + pole radius must fit in the border strip "
                f"({self.dimensions.border_strip_m} m), got {self.poles.offset_outside_m} + {r}"
            )
        if any(abs(x) + r > carpet_l / 2 for x in self.poles.x_positions_m):
            raise ValueError(
                f"SceneConfig.poles.x_positions_m must lie on the carpet (|x| + radius <= "
                f"{carpet_l / 2} m), got {self.poles.x_positions_m}"
            )


@dataclass(frozen=True)
class SceneBodies:
    """Names of the bodies :func:`build_scene` created, by role."""

    poles: dict[int, str]  # landmark id -> body name
    goal_posts: tuple[str, ...]
    ball: str
    posters: dict[str, str]  # board panel body name -> its poster's file name


def build_scene(world: BulletWorld, config: SceneConfig, rng: np.random.Generator) -> SceneBodies:
    """Create every static body and the ball; ``rng`` picks the posters for the boards.

    The carpet is the world's painted floor (:class:`spl_env.sim.world.PaintedFloor`): the
    renderer leaves it out and each frame gets its one colour where nothing else is seen. The
    tiny renderer draws the other bodies in the order they were made, shading every pixel that
    passes the depth test: what stands on the ground comes before the lines on it, so that a
    line is not shaded where a goal or a pole covers it.
    """
    dims = config.dimensions
    posts = _add_goals(world, dims)
    poles: dict[int, str] = {}
    if config.poles_enabled:
        positions = config.poles.positions(dims)
        for code, xy in zip(config.poles.codes(), positions, strict=True):
            name = f"pole_{code.landmark_id}"
            world.add_static(
                name, _pole_parts(code, config.poles.geometry), base_position=(xy[0], xy[1], 0.0)
            )
            poles[code.landmark_id] = name
    posters = _add_boards(world, config, rng) if config.boards_enabled else {}
    world.add_static_mesh("field_lines_0", _line_mesh(dims, config.line_piece_m), LINE_RGBA)
    half = (dims.carpet_size_m[0] / 2, dims.carpet_size_m[1] / 2)
    # the ball rolls on (and rays hit) a 2 cm slab; the camera sees its top face, painted
    slab = VisualPart(shape="box", size=(*half, 0.01), position=(0, 0, -0.01), rgba=CARPET_RGBA)
    world.add_painted_floor("carpet", half, CARPET_RGBA, collision=[slab])
    radius = dims.ball_diameter_m / 2
    world.add_sphere(
        "ball",
        radius_m=radius,
        mass_kg=config.ball_mass_kg,
        position=(0.0, 0.0, radius),
        rgba=BALL_RGBA,
        rolling_friction=config.ball_rolling_friction,
        restitution=0.3,
    )
    return SceneBodies(poles=poles, goal_posts=posts, ball="ball", posters=posters)


def _quads(corners: FloatArray, normals: FloatArray) -> TriangleMesh:
    """Flat quads: ``corners`` (Q, 4, 3) counter-clockwise seen from the side their unit
    ``normals`` (Q, 3) point to, each quad two triangles."""
    q = len(corners)
    base = 4 * np.arange(q)[:, None]
    return TriangleMesh(
        vertices=corners.reshape(-1, 3),
        triangles=np.concatenate([base + np.array([0, 1, 2]), base + np.array([0, 2, 3])]),
        normals=np.repeat(normals, 4, axis=0),
    )


def _lift(points: FloatArray, z: float) -> FloatArray:
    """Points (..., 2) at height ``z`` (m): (..., 3)."""
    return np.concatenate([points, np.full((*points.shape[:-1], 1), z)], axis=-1)


def _slab(pieces: FloatArray, height: float) -> TriangleMesh:
    """A painted stripe as the box it was: ``pieces`` (Q, 4, 2) its consecutive pieces, corners
    ``(a - s, b - s, b + s, a + s)`` from piece start ``a`` to end ``b``, ``s`` half its width
    to the left; top faces at ``height`` (m), the long sides of every piece and the two ends,
    from the carpet (z = 0) up: 2 mm faces that thicken a line seen aslant from afar."""
    low, high = _lift(pieces, 0.0), _lift(pieces, height)
    ab = pieces[0, 1] - pieces[0, 0]
    along = _lift(ab / np.linalg.norm(ab), 0.0)
    left = np.array([-along[1], along[0], 0.0])
    faces = [
        (high, np.array([0.0, 0.0, 1.0])),
        (np.stack([low[:, 0], low[:, 1], high[:, 1], high[:, 0]], axis=1), -left),
        (np.stack([low[:, 2], low[:, 3], high[:, 3], high[:, 2]], axis=1), left),
        (np.stack([low[:1, 3], low[:1, 0], high[:1, 0], high[:1, 3]], axis=1), -along),
        (np.stack([low[-1:, 1], low[-1:, 2], high[-1:, 2], high[-1:, 1]], axis=1), along),
    ]
    return TriangleMesh.concatenate(
        [_quads(corners, np.tile(normal, (len(corners), 1))) for corners, normal in faces]
    )


def _stripe(ends: FloatArray, width: float, piece: float) -> FloatArray:
    """Pieces (Q, 4, 2) of a painted stripe between ``ends`` (4,) ``(x0, y0, x1, y1)`` (m),
    ``width`` wide and reaching ``width / 2`` beyond both ends, Q of them no longer than
    ``piece`` (m); corners as :func:`_slab` takes them."""
    start, end = np.asarray(ends[:2], dtype=float), np.asarray(ends[2:], dtype=float)
    length = float(np.linalg.norm(end - start)) + width
    along = (end - start) / max(float(np.linalg.norm(end - start)), 1e-12)
    side = np.array([-along[1], along[0]]) * width / 2
    cuts = np.linspace(-length / 2, length / 2, max(1, math.ceil(length / piece)) + 1)
    a = (start + end) / 2 + cuts[:-1, None] * along
    b = (start + end) / 2 + cuts[1:, None] * along
    return np.stack([a - side, b - side, b + side, a + side], axis=1)


def _line_mesh(dims: FieldDimensions, piece: float, circle_segments: int = 32) -> TriangleMesh:
    """All painted markings (straight lines, centre circle, centre and penalty marks) as slabs
    on the carpet, long stripes cut into pieces no longer than ``piece`` (m)."""
    w = dims.line_width_m
    stripes = [_stripe(segment, width=w, piece=piece) for segment in dims.line_segments()]
    r = dims.centre_circle_diameter_m / 2
    angles = np.linspace(0.0, 2 * math.pi, circle_segments + 1)
    for a0, a1 in itertools.pairwise(angles):
        ends = (r * math.cos(a0), r * math.sin(a0), r * math.cos(a1), r * math.sin(a1))
        stripes.append(_stripe(np.array(ends), width=w, piece=piece))
    mark = dims.penalty_mark_diameter_m / 2
    square = np.array([(-mark, -mark), (mark, -mark), (mark, mark), (-mark, mark)])
    for x, y in (*dims.penalty_marks(), (0.0, 0.0)):
        stripes.append((square + np.array([x, y]))[None])
    return TriangleMesh.concatenate([_slab(pieces, LINE_THICKNESS_M) for pieces in stripes])


def _add_goals(world: BulletWorld, dims: FieldDimensions) -> tuple[str, ...]:
    """Two goals: white posts and crossbar, grey back frame; returns the post body names."""
    r = dims.goal_post_diameter_m / 2
    h = dims.goal_height_m
    names = []
    for i, (x, y) in enumerate(dims.goal_posts()):
        name = f"goal_post_{i}"
        world.add_static(
            name,
            [VisualPart(shape="cylinder", size=(r, h), position=(0.0, 0.0, h / 2), rgba=GOAL_RGBA)],
            base_position=(x, y, 0.0),
        )
        names.append(name)
    for side in (-1.0, 1.0):
        x_post = side * (dims.half_length_m + r)
        x_back = side * (dims.half_length_m + dims.goal_depth_m)
        half_w = dims.goal_inner_width_m / 2 + 2 * r
        world.add_static(
            f"goal_frame_{int(side > 0)}",
            [
                VisualPart(
                    shape="box", size=(r, half_w, r), position=(x_post, 0.0, h - r), rgba=GOAL_RGBA
                ),
                VisualPart(
                    shape="box",
                    size=(0.01, half_w, h / 2),
                    position=(x_back, 0.0, h / 2),
                    rgba=NET_RGBA,
                ),
                VisualPart(
                    shape="box",
                    size=(dims.goal_depth_m / 2, 0.01, h / 2),
                    position=((x_post + x_back) / 2, half_w, h / 2),
                    rgba=NET_RGBA,
                ),
                VisualPart(
                    shape="box",
                    size=(dims.goal_depth_m / 2, 0.01, h / 2),
                    position=((x_post + x_back) / 2, -half_w, h / 2),
                    rgba=NET_RGBA,
                ),
            ],
        )
    return tuple(names)


def _pole_parts(code: PoleCode, geometry: PoleGeometry) -> list[VisualPart]:
    """White base and two coloured bands of a landmark pole, standing on the carpet."""
    r, base, band = geometry.radius_m, geometry.base_top_m, geometry.band_height_m
    return [
        VisualPart(shape="cylinder", size=(r, base), position=(0.0, 0.0, base / 2), rgba=LINE_RGBA),
        VisualPart(
            shape="cylinder",
            size=(r, band),
            position=(0.0, 0.0, geometry.lower_centre_m),
            rgba=POLE_BAND_RGBA[code.bottom],
        ),
        VisualPart(
            shape="cylinder",
            size=(r, band),
            position=(0.0, 0.0, geometry.upper_centre_m),
            rgba=POLE_BAND_RGBA[code.top],
        ),
    ]


# PyBullet's textured box (examples/OpenGLWindow/ShapeData.h, cube_vertices_textured and
# cube_indices): per face normal, its corners (unit box) with their texture coordinates, and
# its two triangles; each face shows its own quarter-by-quarter part of the texture
_BOX_FACES: dict[tuple[int, int], tuple[FloatArray, FloatArray, list[list[int]]]] = {
    (0, -1): (
        np.array([(-1, -1, -1), (-1, -1, 1), (1, -1, 1), (1, -1, -1)], dtype=float),
        np.array([(0.25, 0.5), (0.25, 0.25), (0.5, 0.25), (0.5, 0.5)]),
        [[2, 1, 0], [3, 2, 0]],
    ),
    (0, 1): (
        np.array([(-1, 1, -1), (-1, 1, 1), (1, 1, 1), (1, 1, -1)], dtype=float),
        np.array([(0.0, 0.0), (0.0, 0.25), (0.25, 0.25), (0.25, 0.0)]),
        [[0, 1, 2], [0, 2, 3]],
    ),
    (-1, 0): (
        np.array([(-1, -1, -1), (-1, 1, -1), (-1, 1, 1), (-1, -1, 1)], dtype=float),
        np.array([(0.5, 0.0), (0.75, 0.0), (0.75, 0.25), (0.5, 0.25)]),
        [[2, 1, 0], [3, 2, 0]],
    ),
    (1, 0): (
        np.array([(1, -1, -1), (1, 1, -1), (1, 1, 1), (1, -1, 1)], dtype=float),
        np.array([(0.25, 0.5), (0.25, 0.25), (0.0, 0.25), (0.0, 0.5)]),
        [[0, 1, 2], [0, 2, 3]],
    ),
}


def _board_face(box: VisualPart, facing: tuple[float, float]) -> TriangleMesh:
    """The one face of the box ``box`` a camera inside the boards sees: the side whose normal
    is the horizontal axis nearest ``facing`` (2,), textured as PyBullet textures that face
    of a box (the rest are hidden: back and top face away, the ends touch the next board)."""
    axis = int(abs(facing[1]) > abs(facing[0]))
    sign = int(math.copysign(1.0, facing[axis]))
    corners, uvs, triangles = _BOX_FACES[(sign, 0) if axis == 0 else (0, sign)]
    normal = np.zeros(3)
    normal[axis] = sign
    return TriangleMesh(
        vertices=corners * np.array(box.size) + np.array(box.position),
        triangles=np.array(triangles),
        normals=np.tile(normal, (4, 1)),
        uvs=uvs,
    )


def _add_boards(
    world: BulletWorld, config: SceneConfig, rng: np.random.Generator
) -> dict[str, str]:
    """Boards around the carpet, one poster texture of ``config.poster_set`` per panel, chosen
    by ``rng``; returns each panel's poster file name by body name."""
    carpet_l, carpet_w = config.dimensions.carpet_size_m
    hx = carpet_l / 2 + config.board_distance_m
    hy = carpet_w / 2 + config.board_distance_m
    h = config.board_height_m
    poster_dir = resources.files("spl_env") / "assets" / "posters"
    files = POSTER_SETS[config.poster_set]
    order = rng.permutation(len(files)) if DISTINCT_POSTERS[config.poster_set] else None
    panel = 0
    posters: dict[str, str] = {}
    for along_x, fixed, span in (
        (True, hy, hx),
        (True, -hy, hx),
        (False, hx, hy),
        (False, -hx, hy),
    ):
        n = max(1, round(2 * span / config.board_panel_width_m))
        width = 2 * span / n
        for k in range(n):
            centre = -span + (k + 0.5) * width
            x, y = (centre, fixed) if along_x else (fixed, centre)
            size = (width / 2, 0.02, h / 2) if along_x else (0.02, width / 2, h / 2)
            name = f"board_{panel}"
            board = VisualPart(shape="box", size=size, position=(0, 0, h / 2), rgba=BOARD_RGBA)
            world.add_static_mesh(
                name,
                _board_face(board, facing=(0.0, -y) if along_x else (-x, 0.0)),
                BOARD_RGBA,
                collision=[board],
                base_position=(x, y, 0.0),
            )
            if order is not None:
                poster = files[int(order[panel % len(files)])]
            else:
                poster = files[int(rng.integers(len(files)))]
            world.set_texture(name, str(poster_dir / poster))
            posters[name] = poster
            panel += 1
    return posters


class SplFieldScene:
    """The SPL field in ``world``, built once from ``config``, with its ground truth.

    The posters are drawn from ``poster_rng``, by default a generator seeded with
    ``config.scene_seed`` (the dataset generator and benchmarks pass their own, so that one
    seeded stream draws the posters and then every frame). ``codes`` (L,) are the poles' colour
    codes, ``landmark_ids`` (L,) and ``landmarks`` (L, 2) their ids and field positions (m);
    ``obstacles`` (K, 3) the goal posts and poles as ``(x, y, radius)`` circles (m) that robots
    walk around; ``bodies`` names the bodies; ``spectators`` the people walking outside the
    carpet (``config.spectators`` of them; their shirts drawn from ``poster_rng`` after the
    posters).
    """

    def __init__(
        self,
        world: BulletWorld,
        config: SceneConfig,
        poster_rng: np.random.Generator | None = None,
    ) -> None:
        self.config = config
        self.world = world
        if poster_rng is None:
            poster_rng = np.random.default_rng(config.scene_seed)
        self.bodies = build_scene(world, config, poster_rng)
        self.spectators = Spectators(
            world,
            config.spectators,
            config.dimensions.carpet_size_m,
            lane_m=config.board_distance_m / 2,
            speed_mps=config.spectator_speed_mps,
            rng=poster_rng,
        )
        self.codes: tuple[PoleCode, ...] = config.poles.codes() if config.poles_enabled else ()
        positions = config.poles.positions(config.dimensions)
        self.landmark_ids = np.array([c.landmark_id for c in self.codes], dtype=np.int64)
        self.landmarks = positions[self.landmark_ids] if self.codes else np.zeros((0, 2))
        dims, pole_radius = config.dimensions, config.poles.geometry.radius_m
        post_radius = dims.goal_post_diameter_m / 2
        self.obstacles = np.array(
            [(*world.position(n)[:2], post_radius) for n in self.bodies.goal_posts]
            + [(*world.position(n)[:2], pole_radius) for n in self.bodies.poles.values()]
        ).reshape(-1, 3)

    @property
    def dimensions(self) -> FieldDimensions:
        """The field's dimensions."""
        return self.config.dimensions

    def goal_post_body_ids(self) -> tuple[int, ...]:
        """The PyBullet bodies of the four goal posts."""
        return tuple(self.world.body(name) for name in self.bodies.goal_posts)

    def pole_body_ids(self) -> tuple[int, ...]:
        """PyBullet body ids (L,) of the poles, in the order of ``landmark_ids``."""
        return tuple(self.world.body(self.bodies.poles[int(i)]) for i in self.landmark_ids)

    def place_ball(self, xy: FloatArray, velocity: FloatArray | None = None) -> None:
        """Put the ball on the ground at ``xy`` (2,) (m) rolling at ``velocity`` (2,) (m/s)."""
        radius = self.config.dimensions.ball_diameter_m / 2
        self.world.set_pose(self.bodies.ball, (xy[0], xy[1], radius), 0.0)
        vx, vy = (0.0, 0.0) if velocity is None else (float(velocity[0]), float(velocity[1]))
        self.world.set_velocity(self.bodies.ball, (vx, vy, 0.0))

    def ball_state(self) -> tuple[FloatArray, FloatArray]:
        """The ball's position (2,) (m) and velocity (2,) (m/s), field frame."""
        return (
            self.world.position(self.bodies.ball)[:2],
            self.world.velocity(self.bodies.ball)[:2],
        )
