"""Pose algebra and camera geometry against closed forms (no pybullet)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from perception.geometry import (
    camera_rotation,
    compose,
    invert,
    pixel_rays,
    project_points,
    range_bearing,
    ray_ground_intersection,
    relative,
    transform_points,
    wrap_angle,
    wrap_scalar,
)
from perception.types import CameraModel, CameraState

coord = st.floats(-10, 10, allow_nan=False)
angle = st.floats(-math.pi, math.pi, allow_nan=False)
poses = st.tuples(coord, coord, angle).map(np.array)


def test_wrap_angle_range_and_values() -> None:
    assert wrap_angle(3 * math.pi / 2) == pytest.approx(-math.pi / 2)
    assert wrap_angle(-3 * math.pi / 2) == pytest.approx(math.pi / 2)
    assert wrap_angle(math.pi) == pytest.approx(-math.pi)
    many = wrap_angle(np.linspace(-50, 50, 1001))
    assert np.all(many >= -math.pi) and np.all(many < math.pi)
    # a hair below -pi: the float remainder rounds up to 2 pi, yet the result stays below pi
    below = np.nextafter(-math.pi, -4.0)
    assert wrap_angle(below) == -math.pi and wrap_scalar(below) == -math.pi
    assert np.isnan(wrap_angle(math.nan)) and math.isnan(wrap_scalar(math.nan))


def test_wrap_scalar_is_wrap_angle_to_the_last_bit() -> None:
    rng = np.random.default_rng(0)
    angles = np.concatenate(
        [
            rng.normal(0.0, 4.0, 20000),
            rng.uniform(-1e3, 1e3, 2000),
            np.arange(-20, 21) * math.pi / 2,
            [0.0, -0.0, np.nextafter(math.pi, 0.0), np.nextafter(-math.pi, 0.0), 1e-300],
            [np.nextafter(-math.pi, -4.0), np.nextafter(-3 * math.pi, -10.0)],
        ]
    )
    scalar = np.array([wrap_scalar(a) for a in angles])  # numpy scalars ...
    assert scalar.view(np.int64).tolist() == wrap_angle(angles).view(np.int64).tolist()
    assert [wrap_scalar(float(a)) for a in angles[:100]] == scalar[:100].tolist()  # ... floats
    assert isinstance(wrap_scalar(np.float64(4.0)), float)


def test_compose_known_case() -> None:
    # a robot at (1, 2) facing +y steps 1 m forward and 0.5 m left: ends at (0.5, 3)
    np.testing.assert_allclose(
        compose([1, 2, math.pi / 2], [1, 0.5, 0.1]), [0.5, 3.0, math.pi / 2 + 0.1], atol=1e-12
    )


@given(poses, poses)
def test_relative_inverts_compose(a: np.ndarray, b: np.ndarray) -> None:
    c = compose(a, b)
    back = relative(a, c)
    np.testing.assert_allclose(back[:2], b[:2], atol=1e-9)
    assert abs(wrap_angle(back[2] - b[2])) < 1e-9


@given(poses)
def test_invert_gives_identity(a: np.ndarray) -> None:
    np.testing.assert_allclose(compose(a, invert(a)), [0.0, 0.0, 0.0], atol=1e-9)


def test_transform_points_matches_compose() -> None:
    pose = np.array([0.3, -1.2, 2.0])
    pts = np.array([[1.0, 0.0], [0.0, 2.0], [-1.0, 0.5]])
    expected = np.array([compose(pose, [x, y, 0.0])[:2] for x, y in pts])
    np.testing.assert_allclose(transform_points(pose, pts), expected, atol=1e-12)


def test_range_bearing_eq_2_11() -> None:
    rb = range_bearing([1.0, 1.0, math.pi / 2], [[1.0, 3.0], [0.0, 1.0]])
    np.testing.assert_allclose(rb, [[2.0, 0.0], [1.0, math.pi / 2]], atol=1e-12)


def test_camera_rotation_directions() -> None:
    # positive pitch looks down, positive yaw looks left
    assert camera_rotation(0.0, 0.3)[:, 0] @ [0, 0, 1] == pytest.approx(-math.sin(0.3))
    assert camera_rotation(0.4, 0.0)[:, 0] @ [0, 1, 0] == pytest.approx(math.sin(0.4))
    r = camera_rotation(0.7, -0.2, 0.05, 0.02)
    np.testing.assert_allclose(r @ r.T, np.eye(3), atol=1e-12)


def test_pixel_ray_round_trip() -> None:
    m = CameraModel(width=320, height=240, hfov_deg=56.3)
    uv = np.array([[0.0, 0.0], [160.0, 120.0], [300.5, 17.25]])
    rays = pixel_rays(uv, m.fx, m.fy, m.cx, m.cy)
    back, front = project_points(rays * 3.7, m.fx, m.fy, m.cx, m.cy)
    assert front.all()
    np.testing.assert_allclose(back, uv, atol=1e-9)


def test_image_edge_is_half_fov() -> None:
    m = CameraModel(width=320, height=240, hfov_deg=56.3)
    ray = pixel_rays([[0.0, m.cy]], m.fx, m.fy, m.cx, m.cy)[0]
    assert math.degrees(math.atan2(ray[1], ray[0])) == pytest.approx(56.3 / 2)
    assert m.vfov_deg == pytest.approx(
        2 * math.degrees(math.atan(0.75 * math.tan(math.radians(28.15))))
    )


def test_ground_projection_of_pitched_camera() -> None:
    # camera 0.5 m high pitched down 30°: the image centre hits the ground 0.5 / tan 30° ahead
    m = CameraModel()
    state = CameraState(
        position=np.array([0.0, 0.0, 0.5]), head_yaw=0.0, head_pitch=math.radians(30)
    )
    ray = state.rotation() @ pixel_rays([[m.cx, m.cy]], m.fx, m.fy, m.cx, m.cy)[0]
    xy, hit = ray_ground_intersection(state.position, ray[None, :])
    assert hit[0]
    np.testing.assert_allclose(xy[0], [0.5 / math.tan(math.radians(30)), 0.0], atol=1e-12)
    _, up_hit = ray_ground_intersection(state.position, np.array([[1.0, 0.0, 0.1]]))
    assert not up_hit[0]


@pytest.mark.parametrize("kwargs", [{"width": 8}, {"hfov_deg": 200.0}, {"height": 240.0}])
def test_camera_model_rejects_bad_values(kwargs: dict) -> None:
    with pytest.raises(ValueError, match=next(iter(kwargs))):
        CameraModel(**kwargs)


def test_camera_state_rotation_is_computed_once_read_only_and_equal_per_state() -> None:
    state = CameraState(position=np.array([0.0, 0.0, 0.5]), head_yaw=0.3, head_pitch=0.2, tilt=0.1)
    rotation = state.rotation()
    np.testing.assert_array_equal(rotation, camera_rotation(0.3, 0.2 + 0.1))
    assert state.rotation() is rotation
    with pytest.raises(ValueError):
        rotation[0, 0] = 1.0
    turned = dataclasses.replace(state, head_yaw=-0.3)  # a new state: its own rotation
    np.testing.assert_array_equal(turned.rotation(), camera_rotation(-0.3, 0.2 + 0.1))
    assert "_rotation" not in repr(turned)  # the cache is no field
