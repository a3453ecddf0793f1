"""Our own body's silhouettes in our camera's image, against the pinhole's closed form."""

from __future__ import annotations

import math

import numpy as np
import pytest

from perception.types import CameraModel, CameraState
from perception.validation import InvalidTypeError
from perception.vision.body_contour import (
    BodyBox,
    BodyContourConfig,
    body_silhouettes,
    on_body,
)

CAMERA = CameraModel()
LEVEL = CameraState(position=np.array([0.0, 0.0, 0.5]), head_yaw=0.0, head_pitch=0.0)


def one_box(
    centre: tuple[float, float, float], half: tuple[float, float, float]
) -> BodyContourConfig:
    return BodyContourConfig(boxes=(BodyBox(centre, half),))


def test_a_box_ahead_projects_to_its_near_face() -> None:
    """A box ahead of a level camera: its silhouette is its near face, whose corners the
    pinhole puts at ``c -/+ f * half / depth`` (the far face lies inside it)."""
    silhouettes = body_silhouettes(one_box((2.0, 0.1, 0.45), (0.1, 0.2, 0.1)), CAMERA, LEVEL)
    assert len(silhouettes) == 1
    (u, v) = silhouettes[0].T
    depth = 1.9
    expected_u = (CAMERA.cx - CAMERA.fx * 0.3 / depth, CAMERA.cx - CAMERA.fx * -0.1 / depth)
    expected_v = (CAMERA.cy - CAMERA.fy * 0.05 / depth, CAMERA.cy - CAMERA.fy * -0.15 / depth)
    np.testing.assert_allclose((u.min(), u.max()), expected_u, atol=1e-3)
    np.testing.assert_allclose((v.min(), v.max()), expected_v, atol=1e-3)


def test_a_box_behind_the_camera_has_no_silhouette() -> None:
    assert body_silhouettes(one_box((-1.0, 0.0, 0.5), (0.1, 0.1, 0.1)), CAMERA, LEVEL) == []


def test_a_box_reaching_behind_the_camera_is_clipped_and_covers_the_image_bottom() -> None:
    """A slab under a level camera, from behind it to 1.5 m ahead: clipped at the near plane,
    its silhouette reaches far below the image; the bottom row's ray meets the slab's top
    (0.35 m down) 0.35 fy / (h / 2) m ahead, inside it, so the bottom row is on it, and the
    horizon is not."""
    config = one_box((0.5, 0.0, 0.1), (1.0, 1.0, 0.05))
    silhouettes = body_silhouettes(config, CAMERA, LEVEL)
    assert len(silhouettes) == 1
    assert silhouettes[0][:, 1].max() > 10 * CAMERA.height
    assert 0.35 * CAMERA.fy / (CAMERA.height / 2) < 1.5
    assert on_body(np.array([CAMERA.cx, CAMERA.height - 1.0]), silhouettes, 0.0)
    assert not on_body(np.array([CAMERA.cx, CAMERA.cy]), silhouettes, 0.0)


def test_a_point_counts_as_on_the_body_within_the_margin_only() -> None:
    silhouettes = body_silhouettes(one_box((2.0, 0.0, 0.5), (0.1, 0.2, 0.2)), CAMERA, LEVEL)
    right_edge = CAMERA.cx + CAMERA.fx * 0.2 / 1.9
    assert on_body(np.array([CAMERA.cx, CAMERA.cy]), silhouettes, 0.0)
    assert on_body(np.array([right_edge + 1.5, CAMERA.cy]), silhouettes, 2.0)
    assert not on_body(np.array([right_edge + 2.5, CAMERA.cy]), silhouettes, 2.0)


def test_the_nao_sees_its_shoulder_only_with_the_head_turned_and_down() -> None:
    """The Nao's top camera looking ahead sees none of its body; turned to the right limit and
    pitched down, its right arm fills the image's lower part."""
    ahead = CameraState(position=np.array([0.059, 0.0, 0.52]), head_yaw=0.0, head_pitch=0.3)
    config = BodyContourConfig()
    rows, columns = np.mgrid[0 : CAMERA.height : 4, 0 : CAMERA.width : 4]
    grid = np.column_stack([columns.ravel(), rows.ravel()]).astype(float)
    looking_ahead = body_silhouettes(config, CAMERA, ahead)
    assert looking_ahead  # the body lies in front of the camera's plane, below the image
    assert not any(on_body(p, looking_ahead, 0.0) for p in grid)
    yaw = -1.55
    turned = CameraState(
        position=np.array([0.059 * math.cos(yaw), 0.059 * math.sin(yaw), 0.49]),
        head_yaw=yaw,
        head_pitch=0.46,
    )
    silhouettes = body_silhouettes(config, CAMERA, turned)
    assert on_body(np.array([CAMERA.cx, CAMERA.height - 10.0]), silhouettes, 0.0)
    assert not on_body(np.array([CAMERA.cx, 10.0]), silhouettes, 0.0)


@pytest.mark.parametrize(
    ("centre", "half"),
    [
        ((0.0, 0.0), (0.1, 0.1, 0.1)),
        ((0.0, 0.0, math.nan), (0.1, 0.1, 0.1)),
        ((0, 0, 0), (0.1, 0.0, 0.1)),
    ],
)
def test_bad_boxes_are_refused(centre: tuple[float, ...], half: tuple[float, ...]) -> None:
    with pytest.raises(ValueError, match="BodyBox"):
        BodyBox(centre, half)  # type: ignore[arg-type]


def test_boxes_of_numpy_numbers_are_accepted_and_of_other_types_refused() -> None:
    box = BodyBox((np.float64(0.1), np.float32(0.0), 1), (0.1, 0.1, np.float64(0.2)))
    assert box.corners().shape == (8, 3)
    with pytest.raises(InvalidTypeError, match=r"BodyBox\.centre_m"):
        BodyBox([0.0, 0.0, 0.0], (0.1, 0.1, 0.1))  # type: ignore[arg-type]
    with pytest.raises(InvalidTypeError, match=r"BodyBox\.half_extents_m"):
        BodyBox((0.0, 0.0, 0.0), (0.1, "0.1", 0.1))  # type: ignore[arg-type]


def test_bad_contour_configs_are_refused() -> None:
    with pytest.raises(InvalidTypeError, match="boxes"):
        BodyContourConfig(boxes=[BodyBox((0.0, 0.0, 0.0), (0.1, 0.1, 0.1))])  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="margin_px"):
        BodyContourConfig(margin_px=-1.0)
