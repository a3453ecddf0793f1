"""A detected pole's distance from the rows of its band edges, found to sub-pixel precision.

The CNN's box edges are regressed on a grid of 8 px cells and are off by a pixel or two, which
is 2-4 % of a pole's height at 3-5 m. The pole itself is a ruler of known marks: along its axis
the image changes colour at four heights z (m above the field): the ``top`` of the upper band,
the ``junction`` of the bands, the ``base`` (lower band to white base) and the ``bottom`` (base
to carpet). Given a detection (box and junction keypoint) this module

1. averages the colours of a strip along the image of the pole axis (half as wide as the pole)
   into a row profile, and takes the colour change between neighbouring rows;
2. finds each edge as the strongest change in a window around where the detection puts it, to a
   fraction of a pixel by a parabola through the peak and its two neighbours (the bottom edge
   only on poles near enough, see ``PoleEdgeConfig.bottom_min_band_px``);
3. turns each edge row into the upright elevation ``y = fx tan(e)`` of its ray (robot frame, as
   :func:`perception.vision.cnn_detector.pole_extents` does), so that for a vertical pole whose
   near surface is ``d`` m from the camera ``y = fx (z - h) / d`` with ``h`` the camera height;
4. fits ``y = s z + c`` by least squares, dropping the worst edge while one misses the line by
   more than ``max_residual_px``; at least ``min_edges`` edges must agree, and the camera
   height the fit implies (``-c / s``) must lie within ``max_height_error_m`` of the camera's;
5. the distance to the pole axis is ``fx / s`` plus the pole radius (the edges are seen on the
   near surface).

A pole whose band edges give no distance (cut by the border at both ends, or an edge hidden)
but which is near enough to be at least ``width_min_px`` wide is measured across instead
(:func:`pole_width_distance`): the sub-pixel left and right silhouette edges of its lower band
give the angle it subtends, and a cylinder of radius r subtending 2a stands r / sin(a) away.

No camera height goes into the distance (the gait sways it); it only checks the fit. Edges the
detection puts within ``BORDER_PX`` of the image border are not searched (their windows are
clipped to the image), so a pole cut by the border is measured from what shows.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from perception.geometry import FloatArray, pixel_rays
from perception.types import CameraModel, PoleGeometry
from perception.validation import check_int, check_positive

EDGES: tuple[str, ...] = ("top", "junction", "base", "bottom")
BORDER_PX = 3.0  # an edge the detection puts nearer the image border is not searched
# Relative error of width distances beyond the edge noise (backgrounds of the pole's colour,
# partial occlusion): their RMS on held-out frames is 7 % (median 1.4 %).
WIDTH_REL_STD_FLOOR = 0.07


@dataclass(frozen=True, kw_only=True)
class PoleEdgeConfig:
    """Search and acceptance settings of :func:`pole_edge_distance`."""

    window_fraction: float = 0.35  # search half-window, as a fraction of the band height (px)
    min_window_px: float = 2.0  # smallest search half-window (px)
    strip_fraction: float = 0.5  # strip width averaged per row, as a fraction of the pole width
    min_contrast: float = 12.0  # smallest colour change (RGB distance, 0-255) that is an edge
    max_residual_px: float = 0.8  # an edge farther than this from the fitted line is dropped
    searched_edges: tuple[str, ...] = EDGES
    # The bottom edge is searched only where a band spans this many pixels (nearer than about
    # 3 m). The poles stand just outside the white field line; farther away the strip of carpet
    # between them shrinks below a pixel, the line continues the white base in the image and
    # the edge found lies 1.5-2 px low.
    bottom_min_band_px: float = 20.0
    # Poles at least this wide (px, about 2.5 m or nearer) whose band edges do not give a
    # distance are measured across: from the left and right edges of their lower band.
    width_min_px: float = 12.0
    min_edges: int = 3  # agreeing edges needed for a distance
    max_height_error_m: float = 0.12  # implied camera height vs the camera's
    # Noise of one edge row (px). ``python benchmarks/pole_edges.py`` fits 0.29 px on held-out
    # frames from the median normalised squared range error (what quantisation alone gives), but
    # the tail of larger errors then makes the mean normalised squared error 2.3; at 0.4 px it
    # is 1.2, and replayed square walks (seeds 1300-1304) map slightly better.
    row_std_px: float = 0.4
    # Relative range error beyond the rows' noise (a pole's slight lean, blur across an edge):
    # without it, edge ranges beyond 5 m have a mean normalised squared error of 3.
    rel_std_floor: float = 0.01

    def __post_init__(self) -> None:
        for name in (
            "window_fraction",
            "min_window_px",
            "strip_fraction",
            "min_contrast",
            "max_residual_px",
            "max_height_error_m",
            "row_std_px",
            "rel_std_floor",
            "bottom_min_band_px",
            "width_min_px",
        ):
            check_positive("PoleEdgeConfig", name, getattr(self, name), float_only=True)
        if not (
            isinstance(self.searched_edges, tuple)
            and len(set(self.searched_edges)) == len(self.searched_edges)
            and set(self.searched_edges) <= set(EDGES)
        ):
            raise ValueError(
                "PoleEdgeConfig.searched_edges must be a tuple of distinct names from "
                f"{EDGES}, got {self.searched_edges!r}"
            )
        check_int("PoleEdgeConfig", "min_edges", self.min_edges, 2)
        if self.min_edges > len(self.searched_edges):
            raise ValueError(
                "PoleEdgeConfig.min_edges must be <= len(searched_edges) = "
                f"{len(self.searched_edges)}, got {self.min_edges!r}"
            )


@dataclass(frozen=True)
class EdgeFit:
    """A pole distance from its edges: ``distance_m`` camera-to-axis (horizontal), the names of
    the ``edges`` used, their ``rows`` (px, image v), the fit's ``rms_px`` residual and the
    ``spread_m``, the standard deviation of the used edges' heights (the fit's lever arm)."""

    distance_m: float
    edges: tuple[str, ...]
    rows: FloatArray
    rms_px: float
    spread_m: float
    surface_m: float  # camera to the pole's near surface, fx / slope

    def relative_variance(self, row_std_px: float, fx: float, floor: float = 0.0) -> float:
        """Variance of the distance relative to itself for edge rows of std ``row_std_px``
        (least squares gives ``var(slope) = row_std**2 / (n spread**2)``, and the distance is
        ``fx / slope``), plus ``floor`` squared."""
        slope = fx / self.surface_m
        return row_std_px**2 / (len(self.edges) * self.spread_m**2 * slope**2) + floor**2


def edge_heights(pole: PoleGeometry) -> FloatArray:
    """Heights (4,) m above the field of the :data:`EDGES` of ``pole``."""
    return np.array(
        [pole.top_m, pole.base_top_m + pole.band_height_m, pole.base_top_m, 0.0], dtype=np.float64
    )


def expected_rows(box: FloatArray, keypoint: FloatArray, pole: PoleGeometry) -> FloatArray:
    """Rows (4,) px where a detection with box (4,) pixel edges and band junction ``keypoint``
    (2,) puts the :data:`EDGES`: the box's top and bottom edges, the keypoint's row, and the
    base edge one band below the junction, the band's height taken from the top if the box's
    top is inside the image, else from the junction-to-bottom span."""
    z = edge_heights(pole)
    top, junction, bottom = float(box[1]), float(keypoint[1]), float(box[3])
    if top > 0.5:
        band = (junction - top) * pole.band_height_m / (z[0] - z[1])
    else:
        band = (bottom - junction) * pole.band_height_m / z[1]
    return np.array([top, junction, junction + band, bottom])


def cross_section_px(box: FloatArray, lean: float) -> float:
    """Width (px, at least 1) of a vertical pole's cross-section in a box (4,) pixel edges
    whose image leans by ``lean`` = du/dv: the box width less the lean over its height."""
    return max(float(box[2] - box[0]) - abs(lean) * float(box[3] - box[1]), 1.0)


def colour_changes(profile: FloatArray) -> FloatArray:
    """RGB distance (K - 1,) between neighbouring entries of a (K, 3) colour profile."""
    step = profile[1:] - profile[:-1]
    return np.sqrt((step * step).sum(axis=1))


def row_profile_changes(
    image: NDArray[np.uint8], axis_u: FloatArray, rows: NDArray[np.int64], half_width: int
) -> FloatArray:
    """Colour change (R - 1,) between consecutive ``rows`` (R,) of the strip of columns
    ``round(axis_u[r]) - half_width .. + half_width`` (``axis_u`` (R,) px per row) of ``image``
    (H, W, 3) uint8; entry k lies on the boundary between rows k and k + 1 (v = rows[k] + 0.5).
    Columns outside the image are clamped to it."""
    width = image.shape[1]
    offsets = np.arange(-half_width, half_width + 1)
    cols = np.clip(np.rint(axis_u).astype(np.int64)[:, None] + offsets[None], 0, width - 1)
    return colour_changes(image[rows[:, None], cols].sum(axis=1, dtype=np.int32) / len(offsets))


def _peak(changes: FloatArray, boundaries: FloatArray, lo: float, hi: float, floor: float) -> float:
    """Sub-pixel position of the strongest change with ``lo <= boundary <= hi`` (NaN if none
    reaches ``floor``): the vertex of the parabola through the peak and its neighbours."""
    inside = np.flatnonzero((boundaries >= lo) & (boundaries <= hi))
    if len(inside) == 0:
        return math.nan
    k = int(inside[np.argmax(changes[inside])])
    if changes[k] < floor:
        return math.nan
    offset = 0.0
    if 0 < k < len(changes) - 1:
        left, mid, right = changes[k - 1], changes[k], changes[k + 1]
        curvature = left - 2.0 * mid + right
        if curvature < 0.0:
            offset = float(np.clip(0.5 * (left - right) / curvature, -0.5, 0.5))
    return float(boundaries[k] + offset)


def _line(x: FloatArray, y: FloatArray) -> tuple[float, float]:
    """Least-squares slope and intercept of ``y = slope x + intercept`` over (N,) points."""
    dx = x - x.mean()
    slope = float(dx @ (y - y.mean()) / (dx @ dx))
    return slope, float(y.mean() - slope * x.mean())


def pole_edge_distance(
    image: NDArray[np.uint8],
    box: FloatArray,
    keypoint: FloatArray,
    lean: float,
    camera: CameraModel,
    rotation: FloatArray,
    camera_height_m: float,
    pole: PoleGeometry,
    config: PoleEdgeConfig,
) -> EdgeFit | None:
    """The distance of a detected pole from its band edges (module doc), or None if fewer than
    ``config.min_edges`` edges are found on one line or the fit is implausible.

    ``image`` (H, W, 3) uint8 RGB; ``box`` (4,) pixel edges ``(u0, v0, u1, v1)`` and
    ``keypoint`` (2,) ``(u, v)`` of the detection; ``lean`` the image slope ``du/dv`` of a
    vertical through the box centre; ``rotation`` (3, 3) camera-to-robot;
    ``camera_height_m`` the optical centre's height above the field.
    """
    height = image.shape[0]
    z = edge_heights(pole)
    expected = expected_rows(box, keypoint, pole)
    band_px = abs(expected[3] - expected[1]) * pole.band_height_m / z[1]
    window = max(config.window_fraction * band_px, config.min_window_px)
    searched = np.array([name in config.searched_edges for name in EDGES]) & (
        (expected >= BORDER_PX) & (expected <= height - 1.0 - BORDER_PX)
    )
    searched[3] &= band_px >= config.bottom_min_band_px
    if searched.sum() < config.min_edges:
        return None
    first = max(math.floor(expected[searched].min() - window) - 1, 0)
    last = min(math.ceil(expected[searched].max() + window) + 1, height - 1)
    rows = np.arange(first, last + 1)
    uc, vc = (box[0] + box[2]) / 2.0, (box[1] + box[3]) / 2.0
    half_width = int(config.strip_fraction * cross_section_px(box, lean) / 2.0)
    changes = row_profile_changes(image, uc + lean * (rows - vc), rows, half_width)
    boundaries = rows[:-1] + 0.5
    found = np.full(len(EDGES), math.nan)
    for k in np.flatnonzero(searched):
        e = expected[k]
        found[k] = _peak(changes, boundaries, e - window, e + window, config.min_contrast)
    use = np.isfinite(found)
    if use.sum() < config.min_edges:
        return None
    pixels = np.column_stack([uc + lean * (found[use] - vc), found[use]])
    rays = pixel_rays(pixels, camera.fx, camera.fy, camera.cx, camera.cy) @ rotation.T
    elevation = camera.fx * rays[:, 2] / np.hypot(rays[:, 0], rays[:, 1])
    heights = z[use]
    names = [name for name, u in zip(EDGES, use, strict=True) if u]
    rows_used = found[use]
    while True:
        slope, intercept = _line(heights, elevation)
        residual = elevation - (slope * heights + intercept)
        worst = int(np.argmax(np.abs(residual)))
        if abs(residual[worst]) <= config.max_residual_px:
            break
        if len(heights) <= config.min_edges:
            return None
        keep = np.arange(len(heights)) != worst
        heights, elevation, rows_used = heights[keep], elevation[keep], rows_used[keep]
        names = [n for k, n in enumerate(names) if k != worst]
    if not slope > 0.0:
        return None
    surface_m = camera.fx / slope
    if abs(-intercept / slope - camera_height_m) > config.max_height_error_m:
        return None
    return EdgeFit(
        distance_m=float(surface_m + pole.radius_m),
        edges=tuple(names),
        rows=rows_used.astype(np.float64),
        rms_px=float(np.sqrt(np.mean(residual**2))),
        spread_m=float(np.std(heights)),
        surface_m=float(surface_m),
    )


@dataclass(frozen=True)
class WidthFit:
    """A near pole's distance from its silhouette's width: ``distance_m`` camera-to-axis
    (horizontal), ``width_px`` the measured width and ``half_angle_rad`` half the angle the
    pole subtends."""

    distance_m: float
    width_px: float
    half_angle_rad: float

    def relative_variance(self, row_std_px: float) -> float:
        """Variance of the distance relative to itself for edge columns of std
        ``row_std_px`` (the distance is ``r / sin(half angle)``, nearly inverse in the width),
        plus ``WIDTH_REL_STD_FLOOR`` squared."""
        return 2.0 * row_std_px**2 / self.width_px**2 + WIDTH_REL_STD_FLOOR**2


def pole_width_distance(
    image: NDArray[np.uint8],
    box: FloatArray,
    keypoint: FloatArray,
    lean: float,
    camera: CameraModel,
    rotation: FloatArray,
    pole: PoleGeometry,
    config: PoleEdgeConfig,
) -> WidthFit | None:
    """The distance of a near pole from the sub-pixel left and right edges of its lower band,
    or None if it is narrower than ``config.width_min_px``, its edges are not found or the
    width found is more than 30 % off the box's.

    The columns along rows of the lower band (below the junction ``keypoint``, following the
    image of the pole axis, which leans by ``lean`` = du/dv) are averaged into a column profile;
    each silhouette edge is the strongest colour change within a window around the box's side,
    refined by a parabola. The rays through the two edges (robot frame, ``rotation`` (3, 3)
    camera-to-robot) span twice the half angle ``a`` of a cylinder of radius r at distance
    ``r / sin(a)``. Arguments as for :func:`pole_edge_distance`.
    """
    height, width = image.shape[:2]
    uc, vc = (box[0] + box[2]) / 2.0, (box[1] + box[3]) / 2.0
    box_width = cross_section_px(box, lean)
    if box_width < config.width_min_px:
        return None
    # the lower band is about twice as tall as the pole is wide; keep clear of its ends
    first = max(math.ceil(keypoint[1] + 0.4 * box_width), 0)
    last = min(math.floor(keypoint[1] + 1.6 * box_width), height - 1)
    if last < first + 1:
        return None
    rows = np.arange(first, last + 1)
    window = max(0.25 * box_width, config.min_window_px)
    reach = math.ceil(box_width / 2.0 + window) + 1
    offsets = np.arange(-reach, reach + 1)
    centres = uc + lean * (rows - vc)
    cols = np.rint(centres)[:, None].astype(np.int64) + offsets[None]
    if cols.min() < 0 or cols.max() > width - 1:
        return None  # a side of the pole or its window is cut by the border
    changes = colour_changes(image[rows[:, None], cols].sum(axis=0, dtype=np.int32) / len(rows))
    shift = float(np.rint(centres).mean() - centres.mean())
    boundaries = offsets[:-1].astype(np.float64) + 0.5 + shift
    half = box_width / 2.0
    left = _peak(changes, boundaries, -half - window, -half + window, config.min_contrast)
    right = _peak(changes, boundaries, half - window, half + window, config.min_contrast)
    if not (np.isfinite(left) and np.isfinite(right)):
        return None
    measured = right - left
    if abs(measured / box_width - 1.0) > 0.3:
        return None
    v = float(rows.mean())
    u = float(centres.mean())
    rays = (
        pixel_rays(
            np.array([[u + left, v], [u + right, v]]), camera.fx, camera.fy, camera.cx, camera.cy
        )
        @ rotation.T
    )
    azimuths = np.arctan2(rays[:, 1], rays[:, 0])
    half_angle = 0.5 * abs(float(azimuths[0] - azimuths[1]))
    if not 0.0 < half_angle < math.pi / 4:
        return None
    return WidthFit(
        distance_m=pole.radius_m / math.sin(half_angle),
        width_px=float(measured),
        half_angle_rad=half_angle,
    )
