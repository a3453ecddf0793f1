"""Planar pose algebra and camera ray geometry.

Frames (right-handed, metres, radians):

- field frame: origin at the centre spot, x towards the opponent goal, y to the left, z up;
- robot frame: origin on the ground under the torso, x forward, y left, z up;
- camera frame: origin at the optical centre, x along the optical axis, y left, z up
  (so image column ``u`` grows towards -y and image row ``v`` grows towards -z).

A planar pose is an array ``(x, y, theta)``. Head angles follow the Nao convention: positive
yaw turns the head left, positive pitch tilts it down.

These are the inner loops' arithmetic, called thousands of times a frame: they trust their
inputs to be finite and of the shapes documented (a NaN comes out as a NaN). The public
boundaries check them instead: the configs, the providers' sensor frames, the filters'
``update`` methods and :class:`~perception.types.CameraState`.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]


def wrap_angle(angle: ArrayLike) -> FloatArray:
    """Wrap angles (rad, any shape) into [-pi, pi)."""
    a = np.asarray(angle, dtype=np.float64)
    wrapped = (a + np.pi) % (2.0 * np.pi) - np.pi
    # an angle a hair below -pi: the remainder rounds up to 2 pi, which would give +pi
    return wrapped - 2.0 * np.pi * (wrapped >= np.pi)  # (NaN stays NaN)


def wrap_scalar(angle: float) -> float:
    """:func:`wrap_angle` of one angle (rad) as a Python float, into [-pi, pi): the same
    arithmetic (Python's float remainder is NumPy's), without the array's overhead."""
    wrapped = (float(angle) + math.pi) % (2.0 * math.pi) - math.pi
    return wrapped - 2.0 * math.pi if wrapped >= math.pi else wrapped


def compose(a: ArrayLike, b: ArrayLike) -> FloatArray:
    """Pose composition ``a ⊕ b``: pose ``b`` given in the frame of ``a``, expressed in a's parent.

    Both are (3,) arrays ``(x, y, theta)``; returns (3,).
    """
    ax, ay, at = np.asarray(a, dtype=np.float64).tolist()
    bx, by, bt = np.asarray(b, dtype=np.float64).tolist()
    c, s = math.cos(at), math.sin(at)
    return np.array([ax + c * bx - s * by, ay + s * bx + c * by, wrap_scalar(at + bt)])


def invert(a: ArrayLike) -> FloatArray:
    """Inverse pose ``⊖a`` (3,), so that ``compose(a, invert(a))`` is the identity."""
    ax, ay, at = np.asarray(a, dtype=np.float64)
    c, s = np.cos(at), np.sin(at)
    return np.array([-c * ax - s * ay, s * ax - c * ay, float(wrap_angle(-at))])


def relative(a: ArrayLike, b: ArrayLike) -> FloatArray:
    """Pose of ``b`` in the frame of ``a`` (``⊖a ⊕ b``), both (3,) in a common frame."""
    return compose(invert(a), b)


def transform_points(pose: ArrayLike, points: ArrayLike) -> FloatArray:
    """Map (N, 2) points from the frame of ``pose`` into its parent frame; returns (N, 2)."""
    x, y, t = np.asarray(pose, dtype=np.float64)
    p = np.atleast_2d(np.asarray(points, dtype=np.float64))
    c, s = np.cos(t), np.sin(t)
    return np.column_stack([x + c * p[:, 0] - s * p[:, 1], y + s * p[:, 0] + c * p[:, 1]])


def range_bearing(pose: ArrayLike, points: ArrayLike) -> FloatArray:
    """Range (m) and bearing (rad, robot frame) from ``pose`` (3,) to (N, 2) field points.

    Returns (N, 2) columns ``(range, bearing)``: seed 000 eq. 2.11 without the noise term.
    """
    x, y, t = np.asarray(pose, dtype=np.float64)
    p = np.atleast_2d(np.asarray(points, dtype=np.float64))
    dx, dy = p[:, 0] - x, p[:, 1] - y
    return np.column_stack([np.hypot(dx, dy), wrap_angle(np.arctan2(dy, dx) - t)])


def rot_x(angle: float) -> FloatArray:
    """(3, 3) rotation about the x axis by ``angle`` (rad)."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rot_y(angle: float) -> FloatArray:
    """(3, 3) rotation about the y axis; a positive angle tips the x axis downwards."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rot_z(angle: float) -> FloatArray:
    """(3, 3) rotation about the z axis by ``angle`` (rad)."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def camera_rotation(
    head_yaw: float, head_pitch: float, body_roll: float = 0.0, body_pitch: float = 0.0
) -> FloatArray:
    """(3, 3) rotation of the camera frame in the robot frame.

    ``head_pitch`` includes the camera's fixed tilt; ``body_roll``/``body_pitch`` are the
    torso's sway (rad), composed as PyBullet's Euler angles (pitch after roll). The torso sways
    first, then the head yaws, then pitches.
    """
    return rot_y(body_pitch) @ rot_x(body_roll) @ rot_z(head_yaw) @ rot_y(head_pitch)


def pixel_rays(pixels: ArrayLike, fx: float, fy: float, cx: float, cy: float) -> FloatArray:
    """Unit rays (N, 3) in the camera frame through (N, 2) pixel coordinates ``(u, v)``."""
    uv = np.atleast_2d(np.asarray(pixels, dtype=np.float64))
    d = np.column_stack([np.ones(len(uv)), (cx - uv[:, 0]) / fx, (cy - uv[:, 1]) / fy])
    return d / np.linalg.norm(d, axis=1, keepdims=True)


def project_points(
    points_cam: ArrayLike, fx: float, fy: float, cx: float, cy: float
) -> tuple[FloatArray, NDArray[np.bool_]]:
    """Pinhole projection of (N, 3) camera-frame points to (N, 2) pixels ``(u, v)``.

    Returns the pixels and a (N,) mask of points in front of the camera (x > 0); pixels of
    points behind the camera are NaN.
    """
    p = np.atleast_2d(np.asarray(points_cam, dtype=np.float64))
    front = p[:, 0] > 1e-9
    depth = np.where(front, p[:, 0], np.nan)  # NaN behind: each of its pixels comes out NaN
    uv = np.empty((len(p), 2))
    uv[:, 0] = cx - fx * p[:, 1] / depth
    uv[:, 1] = cy - fy * p[:, 2] / depth
    return uv, front


def ray_ground_intersection(
    origin: ArrayLike, rays: ArrayLike, ground_z: float = 0.0
) -> tuple[FloatArray, NDArray[np.bool_]]:
    """Intersect (N, 3) rays from ``origin`` (3,) with the plane ``z = ground_z``.

    Returns (N, 2) xy points and a (N,) mask of rays that point down and hit the plane; the
    points of the others are NaN.
    """
    o = np.asarray(origin, dtype=np.float64)
    d = np.atleast_2d(np.asarray(rays, dtype=np.float64))
    hits = d[:, 2] < -1e-9
    xy = np.full((len(d), 2), np.nan)
    t = (ground_z - o[2]) / d[hits, 2]
    xy[hits] = o[:2] + t[:, None] * d[hits, :2]
    return xy, hits
