"""The robot's horizon in an image and the 1-D grey signal along it (seed 004 §3.2).

The horizon is the image of the points at infinity of the ground plane: the line where the
horizontal plane through the camera centre meets the image. It does not depend on the camera's
height, only on its orientation. A pixel ``(u, v)`` lies on it when its ray (frames of
:mod:`perception.geometry`) is horizontal in the robot frame. With ``n = R[2, :]`` the robot's
z axis in camera coordinates (``R`` the (3, 3) camera-to-robot rotation) that is
``n0 + n1 (cx - u) / fx + n2 (cy - v) / fy = 0``, so the horizon row at column ``u`` is::

    v(u) = cy + (fy / n2) * (n0 + n1 * (cx - u) / fx)

A straight line: at row ``cy`` for a level camera, ``fy * tan(pitch)`` rows higher for a
camera pitched down, tilted by the roll angle for a rolled one. The robot frame is taken to be
level, so the torso's sway enters through ``body_roll`` / ``body_pitch``
(:func:`perception.geometry.camera_rotation`).

The seed sums a band of 30 grey rows centred on the horizon at every 4th column of a 640 x 480
image (the sum is robust to a horizon a few rows off, and cheaper than the mean); here both
scale with the resolution (:meth:`HorizonConfig.for_resolution`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from perception.geometry import FloatArray, camera_rotation
from perception.types import CameraModel, CameraState
from perception.validation import InvalidTypeError, check_finite, check_int

SEED_BAND_ROWS = 30  # seed 004 §3.2: band height (rows) in a 480-row image
SEED_COLUMN_STEP = 4  # seed 004 §3.2: one sample every 4 columns of a 640-column image
SEED_HEIGHT = 480
SEED_WIDTH = 640
_MIN_UP_COMPONENT = 1e-9  # |n2| below this: the camera looks straight up or down, no horizon


def _round_half_up(value: float) -> int:
    """``value`` rounded to the nearest int, halves upwards (Python's ``round`` goes to even)."""
    return math.floor(value + 0.5)


@dataclass(frozen=True, kw_only=True)
class HorizonConfig:
    """Band of image rows summed along the horizon, and the spacing of its samples.

    The defaults are :meth:`for_resolution` of the default 320 x 240 camera
    (:class:`perception.types.CameraModel`): the seed's 30-row band and 4-column step at
    640 x 480, scaled to ``band_rows = round(30 * H / 480) = 15`` and
    ``column_step = round(4 * W / 640) = 2``, i.e. 160 samples.
    """

    band_rows: int = 15  # rows summed at each sample (odd: centred on the horizon row)
    column_step: int = 2  # columns between two samples (px)

    def __post_init__(self) -> None:
        check_int("HorizonConfig", "band_rows", self.band_rows, 1)
        check_int("HorizonConfig", "column_step", self.column_step, 1)

    @classmethod
    def for_resolution(cls, width: int, height: int) -> HorizonConfig:
        """The seed's band and step scaled to a ``width`` x ``height`` px image:
        ``band_rows = round(30 * height / 480)``, ``column_step = round(4 * width / 640)``,
        halves rounded up, each at least 1."""
        check_int("HorizonConfig.for_resolution", "width", width, 1)
        check_int("HorizonConfig.for_resolution", "height", height, 1)
        return cls(
            band_rows=max(1, _round_half_up(SEED_BAND_ROWS * height / SEED_HEIGHT)),
            column_step=max(1, _round_half_up(SEED_COLUMN_STEP * width / SEED_WIDTH)),
        )


@dataclass(frozen=True, eq=False)
class HorizonBand:
    """The 1-D horizon signal of one image, one entry per sampled column (K = ceil(W / step)).

    - ``signal`` (K,): sum of the band's grey values (grey levels x rows);
    - ``columns`` (K,) int: the image column (pixel x) of each sample, ``0, step, 2 step, ...``;
    - ``rows`` (K,): the horizon row (px, may lie outside the image; NaN without a horizon);
    - ``valid`` (K,) bool: whether the horizon row lies inside the image at that column.

    The band is shifted to stay inside the image: where the horizon is less than half a band
    from the top or bottom border, the band is the first or last ``band_rows`` rows. Where the
    horizon itself leaves the image (``valid`` False) the sample is still that border band, a
    signal that does not show the horizon. The arrays are read-only.
    """

    signal: FloatArray
    columns: NDArray[np.int64]
    rows: FloatArray
    valid: NDArray[np.bool_]


def horizon_rows(columns: ArrayLike, camera: CameraModel, rotation: ArrayLike) -> FloatArray:
    """Horizon row ``v`` (px) at each of the (K,) image ``columns`` ``u`` (px).

    ``rotation`` (3, 3) is the camera-to-robot rotation of a level robot frame (z up). All NaN
    when the camera looks straight up or down (the horizon is not a line across the columns).
    """
    u = np.asarray(columns, dtype=np.float64)
    R = np.asarray(rotation, dtype=np.float64)
    if R.shape != (3, 3) or not np.isfinite(R).all():
        raise ValueError(f"rotation must be a finite (3, 3) array, got {R!r}")
    n0, n1, n2 = R[2]
    if abs(n2) < _MIN_UP_COMPONENT:
        return np.full(u.shape, np.nan)
    rows: FloatArray = camera.cy + (camera.fy / n2) * (n0 + n1 * (camera.cx - u) / camera.fx)
    return rows


def horizon_band(
    gray_image: ArrayLike,
    camera: CameraModel,
    state: CameraState,
    config: HorizonConfig,
    *,
    body_roll: float = 0.0,
    body_pitch: float = 0.0,
) -> HorizonBand:
    """Sum ``config.band_rows`` grey rows centred on the horizon at every ``column_step``-th
    column of ``gray_image`` (H, W) (any real dtype; convert an RGB frame with
    ``cv2.cvtColor(image, cv2.COLOR_RGB2GRAY)``).

    The horizon follows from the camera's pose on the robot (``state``) and the torso's sway
    ``body_roll`` / ``body_pitch`` (rad). A band of B rows centred on row ``v`` spans rows
    ``floor(v - (B - 1) / 2 + 0.5)`` onwards (for even B it sits half a row low), shifted into
    the image as :class:`HorizonBand` describes.
    """
    image = np.asarray(gray_image)
    if image.dtype.kind not in "uif":
        raise InvalidTypeError(f"gray_image must hold real numbers, got dtype {image.dtype}")
    if image.shape != (camera.height, camera.width):
        raise ValueError(
            f"gray_image must have shape ({camera.height}, {camera.width}) (camera.height, "
            f"camera.width), got shape {image.shape}"
        )
    if config.band_rows > camera.height:
        raise ValueError(
            f"config.band_rows must be <= the image height {camera.height}, got {config.band_rows}"
        )
    check_finite("", "body_roll", body_roll)
    check_finite("", "body_pitch", body_pitch)
    rotation = camera_rotation(state.head_yaw, state.head_pitch + state.tilt, body_roll, body_pitch)
    columns = np.arange(0, camera.width, config.column_step, dtype=np.int64)
    rows = horizon_rows(columns, camera, rotation)
    valid = np.isfinite(rows) & (rows >= -0.5) & (rows < camera.height - 0.5)
    centre = np.where(np.isfinite(rows), np.clip(rows, -camera.height, 2 * camera.height), 0.0)
    top = np.floor(centre - 0.5 * (config.band_rows - 1) + 0.5).astype(np.int64)
    top = np.clip(top, 0, camera.height - config.band_rows)
    band = image[top[None, :] + np.arange(config.band_rows)[:, None], columns[None, :]]
    signal = band.sum(axis=0, dtype=np.float64)
    for array in (signal, columns, rows, valid):
        array.flags.writeable = False
    return HorizonBand(signal=signal, columns=columns, rows=rows, valid=valid)
