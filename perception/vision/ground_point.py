"""Where a pixel lies on a horizontal plane: the robot front ends' monocular range (seed 004 §6.2).

A robot standing on the field is located by one pixel of its image whose height above the
ground is known: the base of its box (its feet, height 0) or, when the feet are cut off by the
image border, a part of known height on a standing robot. The ray through that pixel, turned
into the robot frame by the camera state (:meth:`perception.types.CameraState.rotation`, frames
of :mod:`perception.geometry`), meets the horizontal plane ``z = height_m`` at one point; its
range and bearing from the robot origin are the measurement.

``beyond_m`` moves that point further along its horizontal heading from the camera: the pixel
shows the surface nearest the camera, and an object's centre lies that far behind it.

The covariance propagates an isotropic (or per-axis) pixel noise through this map to first
order, by central differences as in :mod:`perception.vision.colour_filter`. The range's
sensitivity grows about with its square: a ground point seen at the image centre by a camera
``h`` above the ground at horizontal distance ``d`` moves by ``dd/dv = (d**2 + h**2) / (h * fy)``
per pixel row.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from perception.geometry import FloatArray, pixel_rays, wrap_angle
from perception.types import CameraModel, CameraState
from perception.validation import check_finite, check_positive, finite_vector

JACOBIAN_STEP_PX = 0.25  # central-difference step of :func:`range_bearing_cov`
_MIN_RAY_SLOPE = 1e-9  # |vertical component| of a unit ray below this never meets the plane


def pixel_ray(pixel: ArrayLike, camera: CameraModel, state: CameraState) -> FloatArray:
    """Unit ray (3,) in the robot frame through ``pixel`` (2,) ``(u, v)`` px."""
    uv = finite_vector(pixel, "pixel", 2)
    ray = pixel_rays(uv, camera.fx, camera.fy, camera.cx, camera.cy)[0]
    return state.rotation() @ ray


def height_point(
    pixel: ArrayLike,
    height_m: float,
    camera: CameraModel,
    state: CameraState,
    beyond_m: float = 0.0,
) -> tuple[float, float] | None:
    """Range (m) and bearing (rad, robot frame) of the point where the ray through ``pixel``
    (2,) ``(u, v)`` px meets the horizontal plane ``z = height_m`` (m, robot frame), moved
    ``beyond_m`` (m) further along its horizontal heading from the camera.

    None if the ray does not reach the plane: it runs parallel to it or away from it (above
    the horizon for a plane below the camera, below it for a plane above).
    """
    check_finite("", "height_m", height_m)
    check_finite("", "beyond_m", beyond_m)
    ray = pixel_ray(pixel, camera, state)
    return _plane_point(ray, float(height_m), np.asarray(state.position, np.float64), beyond_m)


def ground_point(
    pixel: ArrayLike, camera: CameraModel, state: CameraState, beyond_m: float = 0.0
) -> tuple[float, float] | None:
    """Range (m) and bearing (rad) of the ground point (z = 0) seen at ``pixel`` (2,) px, moved
    ``beyond_m`` further from the camera (:func:`height_point`); None above the horizon."""
    return height_point(pixel, 0.0, camera, state, beyond_m)


def range_bearing_cov(
    pixel: ArrayLike,
    camera: CameraModel,
    state: CameraState,
    pixel_std_px: float | ArrayLike,
    height_m: float = 0.0,
    beyond_m: float = 0.0,
) -> FloatArray | None:
    """(2, 2) covariance over ``(range, bearing)`` of :func:`height_point` for independent
    pixel noise of std ``pixel_std_px`` (px): one number for both image axes, or (2,) for
    ``u`` and ``v``. First order, by central differences of ``JACOBIAN_STEP_PX``.

    None if a displaced pixel's ray misses the plane (the pixel lies at the horizon). A zero
    std gives a zero (singular) covariance; callers add their own floors.
    """
    uv = finite_vector(pixel, "pixel", 2)
    std = _pixel_std(pixel_std_px)
    check_finite("", "height_m", height_m)
    check_finite("", "beyond_m", beyond_m)
    steps = JACOBIAN_STEP_PX * np.eye(2)
    samples = np.vstack([uv + steps, uv - steps])  # (4, 2): +u, +v, -u, -v
    rays = pixel_rays(samples, camera.fx, camera.fy, camera.cx, camera.cy) @ state.rotation().T
    origin = np.asarray(state.position, np.float64)
    points = [_plane_point(ray, float(height_m), origin, beyond_m) for ray in rays]
    if any(p is None for p in points):
        return None
    rb = np.array(points, dtype=np.float64)
    jacobian = np.column_stack(
        [
            (rb[:2, 0] - rb[2:, 0]) / (2 * JACOBIAN_STEP_PX),  # d(range, bearing)/du ...
            wrap_angle(rb[:2, 1] - rb[2:, 1]) / (2 * JACOBIAN_STEP_PX),
        ]
    ).T  # (2, 2): rows (range, bearing), columns (u, v)
    cov: FloatArray = jacobian @ np.diag(std**2) @ jacobian.T
    return 0.5 * (cov + cov.T)


def _pixel_std(pixel_std_px: float | ArrayLike) -> FloatArray:
    """The (2,) pixel std of ``u`` and ``v`` from one number or two; raise unless finite, >= 0."""
    if np.ndim(pixel_std_px) == 0:
        check_positive("", "pixel_std_px", pixel_std_px, allow_zero=True)
        return np.full(2, float(pixel_std_px))  # type: ignore[arg-type]
    std = finite_vector(pixel_std_px, "pixel_std_px", 2)
    if (std < 0).any():
        raise ValueError(f"pixel_std_px must be >= 0, got {std}")
    return std


def _plane_point(
    ray: FloatArray, height_m: float, origin: FloatArray, beyond_m: float
) -> tuple[float, float] | None:
    """Range and bearing from the robot origin of where ``ray`` (3,) from ``origin`` (3,)
    meets ``z = height_m``, moved ``beyond_m`` along its horizontal heading; None if it
    does not meet it ahead."""
    rise = height_m - float(origin[2])
    if abs(ray[2]) < _MIN_RAY_SLOPE or rise * ray[2] <= 0.0:
        return None
    t = rise / ray[2]
    horizontal = math.hypot(ray[0], ray[1])
    if horizontal < _MIN_RAY_SLOPE:  # straight down or up: the point is under the camera
        x, y = float(origin[0]), float(origin[1])
    else:
        reach = t + beyond_m / horizontal
        x, y = float(origin[0] + reach * ray[0]), float(origin[1] + reach * ray[1])
    return math.hypot(x, y), math.atan2(y, x)
