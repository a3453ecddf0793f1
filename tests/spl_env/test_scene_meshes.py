"""The scene's cheaper parts (the carpet as the painted floor, the lines as one mesh of slabs,
the boards' faces) render what the primitive boxes they replace rendered; bad meshes and a
second painted floor are rejected."""

from __future__ import annotations

import math
from collections.abc import Iterator
from importlib import resources

import numpy as np
import pytest

from spl_env.field import FieldDimensions
from spl_env.scenes.spl_field import (
    BOARD_RGBA,
    CARPET_RGBA,
    LINE_RGBA,
    LINE_THICKNESS_M,
    _board_face,
    _line_mesh,
)
from spl_env.sensors.camera import Camera, CameraConfig, EpisodeLighting, LightingRandomisation
from spl_env.sim.world import MAX_PARTS_PER_BODY, BulletWorld, TriangleMesh, VisualPart

DIMS = FieldDimensions()
POSTER = str(resources.files("spl_env") / "assets" / "posters" / "textured_00.png")
# one board (base x, y; half extents) along each side, meeting at the corners as the panels
# of spl_field do (an end face shows only where no next board hides it)
BOARDS = (
    ((0.0, 4.3), (5.8, 0.02, 0.6)),
    ((0.0, -4.3), (5.8, 0.02, 0.6)),
    ((5.8, 0.0), (0.02, 4.3, 0.6)),
    ((-5.8, 0.0), (0.02, 4.3, 0.6)),
)


def _box_lines() -> list[VisualPart]:
    """The painted lines as the 2 mm boxes the scene used to build (straight lines and marks)."""
    mark = DIMS.penalty_mark_diameter_m / 2
    parts = [
        VisualPart(
            shape="box",
            size=(mark, mark, LINE_THICKNESS_M / 2),
            position=(x, y, LINE_THICKNESS_M / 2),
            rgba=LINE_RGBA,
        )
        for x, y in (*DIMS.penalty_marks(), (0.0, 0.0))
    ]
    w = DIMS.line_width_m
    for x0, y0, x1, y1 in DIMS.line_segments():
        length = math.hypot(x1 - x0, y1 - y0) + w
        parts.append(
            VisualPart(
                shape="box",
                size=(length / 2, w / 2, LINE_THICKNESS_M / 2),
                position=((x0 + x1) / 2, (y0 + y1) / 2, LINE_THICKNESS_M / 2),
                rgba=LINE_RGBA,
                yaw=math.atan2(y1 - y0, x1 - x0),
            )
        )
    return parts


def _boxes_world() -> BulletWorld:
    """Carpet, straight lines and boards as primitive boxes."""
    world = BulletWorld(time_step_s=0.01)
    carpet_l, carpet_w = DIMS.carpet_size_m
    carpet = VisualPart(
        shape="box",
        size=(carpet_l / 2, carpet_w / 2, 0.01),
        position=(0, 0, -0.01),
        rgba=CARPET_RGBA,
    )
    world.add_static("carpet", [carpet])
    lines = _box_lines()
    for k in range(0, len(lines), MAX_PARTS_PER_BODY):
        world.add_static(f"lines_{k}", lines[k : k + MAX_PARTS_PER_BODY], collide=False)
    for k, (xy, size) in enumerate(BOARDS):
        board = VisualPart(shape="box", size=size, position=(0, 0, 0.6), rgba=BOARD_RGBA)
        world.add_static(f"board_{k}", [board], base_position=(*xy, 0.0))
        world.set_texture(f"board_{k}", POSTER)
    return world


def _meshes_world() -> BulletWorld:
    """The same as the scene builds it: the painted floor, line slabs in pieces, board faces."""
    world = BulletWorld(time_step_s=0.01)
    for k, (xy, size) in enumerate(BOARDS):
        board = VisualPart(shape="box", size=size, position=(0, 0, 0.6), rgba=BOARD_RGBA)
        facing = (0.0, -xy[1]) if size[1] < 0.1 else (-xy[0], 0.0)
        world.add_static_mesh(
            f"board_{k}", _board_face(board, facing), BOARD_RGBA, base_position=(*xy, 0.0)
        )
        world.set_texture(f"board_{k}", POSTER)
    lines = _line_mesh(DIMS, piece=0.5, circle_segments=0)
    world.add_static_mesh("lines", lines, LINE_RGBA)
    half = (DIMS.carpet_size_m[0] / 2, DIMS.carpet_size_m[1] / 2)
    slab = VisualPart(shape="box", size=(*half, 0.01), position=(0, 0, -0.01), rgba=CARPET_RGBA)
    world.add_painted_floor("carpet", half, CARPET_RGBA, collision=[slab])
    return world


@pytest.fixture(scope="module")
def worlds() -> Iterator[tuple[BulletWorld, BulletWorld]]:
    boxes, meshes = _boxes_world(), _meshes_world()
    yield boxes, meshes
    boxes.close()
    meshes.close()


@pytest.mark.parametrize("lighting_seed", [None, 3])
@pytest.mark.parametrize(
    ("x", "y", "yaw_deg", "pitch_deg"),
    [
        (0.0, 0.0, 0.0, 0.0),  # the centre, looking at a goal's lines and the far boards
        (-3.0, 1.5, 35.0, 20.0),  # lines aslant and near
        (3.5, -2.5, -120.0, 5.0),  # a corner of the field, lines far and grazing
        (1.0, 2.8, 90.0, -15.0),  # close to the touchline, looking at the boards
    ],
)
def test_meshes_render_what_the_boxes_rendered(
    worlds, x, y, yaw_deg, pitch_deg, lighting_seed
) -> None:
    """Pixel for pixel and label for label, under even and randomised lighting, from the
    camera height of a Nao: where the mesh's side faces matter (a 2 mm line side thickens a far
    line), where the boards' texture shows, where the carpet ends; but for a raster tie or two
    on the carpet's outer edge (a pixel centre on it may round either way)."""
    yaw, pitch = math.radians(yaw_deg), math.radians(pitch_deg)
    forward = np.array(
        [math.cos(pitch) * math.cos(yaw), math.cos(pitch) * math.sin(yaw), -math.sin(pitch)]
    )
    left = np.array([-math.sin(yaw), math.cos(yaw), 0.0])
    rotation = np.column_stack([forward, left, np.cross(forward, left)])
    position = np.array([x, y, 0.52])
    camera = Camera(CameraConfig(noise_std=0.0))
    lighting = (
        EpisodeLighting.default()
        if lighting_seed is None
        else EpisodeLighting.sample(LightingRandomisation(), np.random.default_rng(lighting_seed))
    )
    frames = [
        camera.render(w, position, rotation, lighting, np.random.default_rng(0)) for w in worlds
    ]
    (image, labels), (new_image, new_labels) = frames
    names = [{v: k for k, v in w._bodies.items()} for w in worlds]
    assert (labels != -1).sum() > 10_000, "the frame should see the scene"
    assert (image != new_image).any(axis=2).sum() <= 2
    kinds = [
        np.vectorize(lambda i, n=n: n.get(int(i), "")[:5])(lab)
        for n, lab in zip(names, (labels, new_labels), strict=True)
    ]
    assert (kinds[0] != kinds[1]).sum() <= 2


def test_lines_are_cut_into_the_pieces_asked_for() -> None:
    lines = _line_mesh(DIMS, piece=0.5)
    assert lines.vertices[:, 2].max() == pytest.approx(LINE_THICKNESS_M)
    # every top quad's diagonal: at most the piece length and the line width
    tops = lines.vertices.reshape(-1, 4, 3)[
        np.all(lines.normals.reshape(-1, 4, 3)[:, :, 2] == 1, 1)
    ]
    diagonals = np.linalg.norm(tops[:, 2] - tops[:, 0], axis=1)
    assert diagonals.max() <= math.hypot(0.5, DIMS.line_width_m) + 1e-9


def test_bad_meshes_rejected() -> None:
    vertices = np.zeros((3, 3))
    normals = np.tile([0.0, 0.0, 1.0], (3, 1))
    triangle = np.array([[0, 1, 2]])
    with pytest.raises(ValueError, match="vertices"):
        TriangleMesh(vertices=np.zeros((3, 2)), triangles=triangle, normals=normals)
    with pytest.raises(ValueError, match="normals"):
        TriangleMesh(vertices=vertices, triangles=triangle, normals=2 * normals)
    with pytest.raises(ValueError, match="triangles"):
        TriangleMesh(vertices=vertices, triangles=np.array([[0, 1, 3]]), normals=normals)
    with pytest.raises(ValueError, match="uvs"):
        TriangleMesh(
            vertices=vertices, triangles=triangle, normals=normals, uvs=np.ones((3, 2)) * 2
        )
    textured = TriangleMesh(
        vertices=vertices, triangles=triangle, normals=normals, uvs=np.zeros((3, 2))
    )
    with pytest.raises(ValueError, match="untextured"):
        TriangleMesh.concatenate([textured, textured])


def test_one_painted_floor_per_world() -> None:
    world, other = BulletWorld(time_step_s=0.01), BulletWorld(time_step_s=0.01)
    try:
        slab = VisualPart(
            shape="box", size=(1.0, 1.0, 0.01), position=(0, 0, -0.01), rgba=LINE_RGBA
        )
        world.add_painted_floor("floor", (1.0, 1.0), LINE_RGBA, collision=[slab])
        with pytest.raises(ValueError, match="painted floor already"):
            world.add_painted_floor("again", (1.0, 1.0), LINE_RGBA, collision=[slab])
        with pytest.raises(ValueError, match="half_extents"):
            other.add_painted_floor("flat", (0.0, 1.0), LINE_RGBA, collision=[slab])
    finally:
        world.close()
        other.close()
