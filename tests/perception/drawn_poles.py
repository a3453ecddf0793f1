"""Analytic images of poles for the pole-measurement tests: a level camera, area-blended edges."""

from __future__ import annotations

import math

import numpy as np

from perception.types import CameraModel, PoleGeometry
from perception.vision.pole_edges import edge_heights

CAMERA = CameraModel()
POLE = PoleGeometry()
COLOURS = {  # from the top down: background, upper band, lower band, white base, carpet
    "sky": (230, 230, 235),
    "pink": (230, 60, 160),
    "blue": (40, 70, 200),
    "white": (245, 245, 245),
    "carpet": (40, 140, 60),
}


def draw_pole(surface_m: float, camera_height_m: float, half_width_px: int = 4) -> np.ndarray:
    """A level camera's image of a pole straight ahead with its near surface ``surface_m`` away:
    each pixel row covering [j - 0.5, j + 0.5] mixes the colours of the heights it spans by
    area (the analytic image, edges at sub-pixel rows)."""
    image = np.zeros((CAMERA.height, CAMERA.width, 3), np.float64)
    z = edge_heights(POLE)  # top, junction, base, bottom
    boundaries = CAMERA.cy - CAMERA.fy * (z - camera_height_m) / surface_m  # rows, rising
    segments = [  # (row from, row to, colour)
        (-1.0, boundaries[0], COLOURS["sky"]),
        (boundaries[0], boundaries[1], COLOURS["pink"]),
        (boundaries[1], boundaries[2], COLOURS["blue"]),
        (boundaries[2], boundaries[3], COLOURS["white"]),
        (boundaries[3], CAMERA.height + 1.0, COLOURS["carpet"]),
    ]
    behind = [(-1.0, boundaries[3], COLOURS["sky"]), segments[-1]]  # beside the pole
    u = int(CAMERA.cx)
    pole_columns = slice(u - half_width_px, u + half_width_px + 1)
    for j in range(CAMERA.height):
        for parts, columns in ((behind, slice(None)), (segments, pole_columns)):
            row = np.zeros(3)
            for lo, hi, colour in parts:
                row += max(0.0, min(hi, j + 0.5) - max(lo, j - 0.5)) * np.array(colour, float)
            image[j, columns] = row
    return np.rint(image).astype(np.uint8)


def detection_of(surface_m: float, camera_height_m: float, error_px: float = 0.0) -> tuple:
    """Box (4,) and junction keypoint (2,) of the drawn pole, shifted by ``error_px`` like a
    detector's regression error."""
    z = edge_heights(POLE)
    rows = CAMERA.cy - CAMERA.fy * (z - camera_height_m) / surface_m
    box = np.array([CAMERA.cx - 4.5, rows[0] + error_px, CAMERA.cx + 4.5, rows[3] - error_px])
    return box, np.array([CAMERA.cx, rows[1] + error_px])


def draw_band_across(distance_m: float, rows: tuple[int, int]) -> np.ndarray:
    """A level camera's image of a pole's lower band straight ahead, its axis ``distance_m``
    away: the silhouette spans the azimuths ±asin(r / distance), edge columns blended by area."""
    image = np.zeros((CAMERA.height, CAMERA.width, 3), np.float64)
    image[:] = COLOURS["sky"]
    half = CAMERA.fx * math.tan(math.asin(POLE.radius_m / distance_m))
    lo, hi = CAMERA.cx - half, CAMERA.cx + half
    for i in range(CAMERA.width):
        cover = max(0.0, min(hi, i + 0.5) - max(lo, i - 0.5))
        colour = cover * np.array(COLOURS["blue"], float)
        colour += (1 - cover) * np.array(COLOURS["sky"], float)
        image[rows[0] : rows[1], i] = colour
    return np.rint(image).astype(np.uint8)
