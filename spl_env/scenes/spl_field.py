"""The SPL field scene: the static world built from primitive shapes, and its ground truth.

Carpet with painted lines (one compound body), two goals, the six landmark poles of seed 000,
a ball, and boards with textured posters around the field for realistic clutter.
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
from perception.validation import check_choice, check_in_interval, check_int, check_positive
from spl_env.field import FieldDimensions, PoleLayout
from spl_env.scenes.spectators import Spectators
from spl_env.sim.world import MAX_PARTS_PER_BODY, BulletWorld, VisualPart

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
LINE_THICKNESS_M = 0.002  # painted-line boxes stand this proud of the carpet


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

    def __post_init__(self) -> None:
        owner = "SceneConfig"
        for name in ("board_distance_m", "board_height_m", "board_panel_width_m", "ball_mass_kg"):
            check_positive(owner, name, getattr(self, name))
        check_in_interval(
            owner, "ball_rolling_friction", self.ball_rolling_friction, 0.0, 1.0, low_inclusive=True
        )
        check_int(owner, "scene_seed", self.scene_seed, 0)
        check_choice(owner, "poster_set", self.poster_set, tuple(POSTER_SETS))
        check_int(owner, "spectators", self.spectators, 0)
        check_positive(owner, "spectator_speed_mps", self.spectator_speed_mps, upper=3.0)
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
    """Create every static body and the ball; ``rng`` picks the posters for the boards."""
    dims = config.dimensions
    carpet_l, carpet_w = dims.carpet_size_m
    world.add_static(
        "carpet",
        [
            VisualPart(
                shape="box",
                size=(carpet_l / 2, carpet_w / 2, 0.01),
                position=(0.0, 0.0, -0.01),
                rgba=CARPET_RGBA,
            )
        ],
    )
    lines = _line_parts(dims)
    for k in range(0, len(lines), MAX_PARTS_PER_BODY):
        world.add_static(
            f"field_lines_{k // MAX_PARTS_PER_BODY}",
            lines[k : k + MAX_PARTS_PER_BODY],
            collide=False,
        )
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


def _flat_box(x0: float, y0: float, x1: float, y1: float, width: float) -> VisualPart:
    """A painted stripe from (x0, y0) to (x1, y1), ``width`` wide, lying on the carpet."""
    length = math.hypot(x1 - x0, y1 - y0) + width
    return VisualPart(
        shape="box",
        size=(length / 2, width / 2, LINE_THICKNESS_M / 2),
        position=((x0 + x1) / 2, (y0 + y1) / 2, LINE_THICKNESS_M / 2),
        rgba=LINE_RGBA,
        yaw=math.atan2(y1 - y0, x1 - x0),
    )


def _line_parts(dims: FieldDimensions, circle_segments: int = 32) -> list[VisualPart]:
    """All painted markings: straight lines, centre circle, centre mark and penalty marks."""
    w = dims.line_width_m
    parts = [_flat_box(x0, y0, x1, y1, width=w) for x0, y0, x1, y1 in dims.line_segments()]
    r = dims.centre_circle_diameter_m / 2
    angles = np.linspace(0.0, 2 * math.pi, circle_segments + 1)
    for a0, a1 in itertools.pairwise(angles):
        parts.append(
            _flat_box(
                r * math.cos(a0), r * math.sin(a0), r * math.cos(a1), r * math.sin(a1), width=w
            )
        )
    mark = dims.penalty_mark_diameter_m / 2
    for x, y in (*dims.penalty_marks(), (0.0, 0.0)):
        parts.append(
            VisualPart(
                shape="box",
                size=(mark, mark, LINE_THICKNESS_M / 2),
                position=(x, y, LINE_THICKNESS_M / 2),
                rgba=LINE_RGBA,
            )
        )
    return parts


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
            world.add_static(
                name,
                [VisualPart(shape="box", size=size, position=(0.0, 0.0, h / 2), rgba=BOARD_RGBA)],
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
