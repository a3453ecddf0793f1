"""Pixels of the field's markings, goal posts and carpet edge, and where they lie on the ground.

The image half of :mod:`perception.vision.field_features`. Images are (H, W, 3) uint8 RGB;
pixel (column i, row j) is centred at ``(u, v) = (i, j)`` as in
:class:`~perception.types.CameraModel`. Ground points are ``(x, y)`` m in the robot frame on
the plane z = 0, found by turning each pixel's ray with :meth:`CameraState.rotation` (frames of
:mod:`perception.geometry`) and meeting the ground.

- :func:`line_runs`: white runs along rows and columns that a line can make: green within
  ``green_gap_px`` beyond both ends (a robot's leg or a post has no green above its foot, the
  floor beyond the carpet none above it) and no longer than ``width_factor`` line widths
  crossing the scan, measured on the ground at the run's middle (plus ``slack_px``: pixels
  partly covered). A run across a line at up to ~50° from its normal passes; any line is
  crossed that steeply by the row scan or the column scan. The runs' middles lie on the
  line's centre line.
- :func:`ground_points`, :func:`ground_jacobians`, :func:`ground_covariances`,
  :func:`pixels_of`: the projection, its derivative by central differences (as in
  :mod:`perception.vision.ground_point`, in ``(x, y)`` rather than range and bearing) and
  the projection back into the image; :func:`row_shifted`: a camera model for an image drawn
  rows higher than the model says (PyBullet's tiny renderer).
- :func:`cut_ends`: whether an image line's end may go on (image side, an occluder).
- :func:`carpet_top`: per column, the row that best splits non-carpet above from carpet below
  (the idea of :mod:`perception.vision.robots`' field boundary, without its envelope).
- :func:`blobs`, :func:`ground_extent`: small white components ringed by green and their
  size on the ground (penalty marks); :func:`post_feet`: the feet of tall, narrow white
  columns standing on the carpet (goal posts).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from perception.geometry import FloatArray, pixel_rays, project_points, ray_ground_intersection
from perception.types import CameraModel, CameraState

BoolImage = NDArray[np.bool_]
JACOBIAN_STEP_PX = 0.25  # central-difference step of :func:`ground_jacobians`


@dataclass(frozen=True, kw_only=True)
class _RowShifted(CameraModel):
    """A camera model whose image shows ``row_offset_px`` rows higher than the plain model
    says: its principal point sits that much higher."""

    row_offset_px: float = 0.0

    @property
    def cy(self) -> float:
        """Principal point row (px), moved up by ``row_offset_px``."""
        return 0.5 * self.height - self.row_offset_px


def row_shifted(camera: CameraModel, row_offset_px: float) -> CameraModel:
    """``camera`` for an image drawn ``row_offset_px`` rows higher than it says (a point it
    puts at row ``v`` shows at ``v - row_offset_px``: PyBullet's tiny renderer, by one row,
    :class:`~perception.types.CameraModel`); ``camera`` itself for 0."""
    if not row_offset_px:
        return camera
    return _RowShifted(
        width=camera.width,
        height=camera.height,
        hfov_deg=camera.hfov_deg,
        row_offset_px=row_offset_px,
    )


def ground_points(
    pixels: FloatArray, camera: CameraModel, state: CameraState
) -> tuple[FloatArray, BoolImage]:
    """Ground points (N, 2) m (robot frame) seen at ``pixels`` (N, 2) px, and a (N,) mask of
    those below the horizon (the others are NaN)."""
    rays = pixel_rays(pixels, camera.fx, camera.fy, camera.cx, camera.cy) @ state.rotation().T
    return ray_ground_intersection(np.asarray(state.position, np.float64), rays)


def ground_jacobians(pixels: FloatArray, camera: CameraModel, state: CameraState) -> FloatArray:
    """(N, 2, 2) ``d(x, y)/d(u, v)`` m/px at ``pixels`` (N, 2) by central differences of
    ``JACOBIAN_STEP_PX``; NaN where a displaced pixel misses the ground."""
    uv = np.asarray(pixels, dtype=np.float64).reshape(-1, 2)
    steps = JACOBIAN_STEP_PX * np.eye(2)
    shifted = np.concatenate([uv[:, None] + steps[None], uv[:, None] - steps[None]], axis=1)
    xy, _ = ground_points(shifted.reshape(-1, 2), camera, state)
    xy = xy.reshape(len(uv), 4, 2)  # +u, +v, -u, -v
    return np.asarray(
        np.stack([xy[:, 0] - xy[:, 2], xy[:, 1] - xy[:, 3]], axis=2) / (2 * JACOBIAN_STEP_PX),
        dtype=np.float64,
    )


def ground_covariances(
    pixels: FloatArray, camera: CameraModel, state: CameraState, pixel_std_px: float
) -> FloatArray:
    """(N, 2, 2) covariance (m²) of the ground points at ``pixels`` (N, 2) for independent
    noise of ``pixel_std_px`` on each image axis, to first order; NaN at the horizon."""
    jac = ground_jacobians(pixels, camera, state)
    return np.asarray(pixel_std_px**2 * jac @ jac.transpose(0, 2, 1), dtype=np.float64)


def pixels_of(points: FloatArray, camera: CameraModel, state: CameraState) -> FloatArray:
    """Image points (N, 2) px of the ground points ``points`` (N, 2) m; NaN behind the camera
    (pixels outside the image are kept: the pinhole extends beyond it)."""
    xyz = np.column_stack([points, np.zeros(len(points))]) - state.position
    uv, _ = project_points(xyz @ state.rotation(), camera.fx, camera.fy, camera.cx, camera.cy)
    return uv


def hsv_mask(hsv: NDArray[np.uint8], bounds: tuple[tuple[int, ...], tuple[int, ...]]) -> BoolImage:
    """Pixels of ``hsv`` (H, W, 3) within the inclusive ``bounds`` ``(low, high)``."""
    lo, hi = (np.array(b, dtype=np.uint8) for b in bounds)
    return np.asarray(cv2.inRange(hsv, lo, hi), dtype=bool)


def _row_runs(mask: BoolImage) -> tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.intp]]:
    """Runs of True along each row of ``mask`` (H, W): rows, first columns, end columns
    (exclusive)."""
    padded = np.pad(mask, ((0, 0), (1, 1))).astype(np.int8)
    step = np.diff(padded, axis=1)
    rows, starts = np.nonzero(step == 1)
    _, ends = np.nonzero(step == -1)
    return rows, starts, ends


def _beside(green: BoolImage, rows: NDArray[np.intp], cols: NDArray[np.intp], sign: int, gap: int):
    """Whether ``green`` holds at one of the ``gap`` pixels beyond ``cols`` (in direction
    ``sign``) on ``rows``; False past the image side."""
    out = np.zeros(len(rows), dtype=bool)
    for k in range(1, gap + 1):
        c = cols + sign * k
        inside = (c >= 0) & (c < green.shape[1])
        out[inside] |= green[rows[inside], c[inside]]
    return out


@dataclass(frozen=True)
class LineRuns:
    """The accepted runs of :func:`line_runs`: their middles ``pixels`` (N, 2) px and
    ``ground`` (N, 2) m, and ``mask`` (H, W), the pixels of all of them."""

    pixels: FloatArray
    ground: FloatArray
    mask: BoolImage


def line_runs(
    white: BoolImage,
    green: BoolImage,
    camera: CameraModel,
    state: CameraState,
    *,
    line_width_m: float,
    width_factor: float,
    slack_px: float,
    green_gap_px: int,
    max_range_m: float,
) -> LineRuns:
    """White runs (along rows, then columns) that a field line can make (module docstring),
    whose middles lie on the ground within ``max_range_m`` of the robot."""
    pixels, grounds = [], []
    mask = np.zeros(white.shape, dtype=bool)
    for transposed in (False, True):
        w, g = (white.T, green.T) if transposed else (white, green)
        rows, starts, ends = _row_runs(w)
        ok = _beside(g, rows, starts, -1, green_gap_px) & _beside(
            g, rows, ends - 1, 1, green_gap_px
        )
        rows, starts, ends = rows[ok], starts[ok], ends[ok]
        middle = 0.5 * (starts + ends - 1)
        uv = np.column_stack([rows, middle] if transposed else [middle, rows]).astype(np.float64)
        xy, hit = ground_points(uv, camera, state)
        hit &= np.hypot(xy[:, 0], xy[:, 1]) <= max_range_m
        jac = ground_jacobians(uv[hit], camera, state)
        along = jac[:, :, 1 if transposed else 0]  # ground step per pixel along the scan
        limit = width_factor * line_width_m / np.hypot(along[:, 0], along[:, 1]) + slack_px
        keep = np.flatnonzero(hit)[(ends[hit] - starts[hit]) <= limit]
        pixels.append(uv[keep])
        grounds.append(xy[keep])
        run_mask = np.zeros((w.shape[0], w.shape[1] + 1), dtype=np.int32)
        np.add.at(run_mask, (rows[keep], starts[keep]), 1)
        np.add.at(run_mask, (rows[keep], ends[keep]), -1)
        filled = np.cumsum(run_mask, axis=1)[:, :-1] > 0
        mask |= filled.T if transposed else filled
    return LineRuns(np.concatenate(pixels), np.concatenate(grounds), mask)


def horizon_rows(camera: CameraModel, state: CameraState, columns: FloatArray) -> FloatArray:
    """Row (C,) px of the horizon at each of ``columns`` (px); -inf where the camera looks so
    steeply that no row is horizontal."""
    r = state.rotation()[2]
    if r[2] <= 1e-9:
        return np.full(len(columns), -np.inf)
    return np.asarray(
        camera.cy + camera.fy * (r[0] + r[1] * (camera.cx - columns) / camera.fx) / r[2],
        dtype=np.float64,
    )


def carpet_top(carpet: BoolImage, first_row: FloatArray) -> FloatArray:
    """Per column of ``carpet`` (H, W), the first row of the carpet: the row that maximises the
    count of carpet less non-carpet pixels from it down, counting no carpet above
    ``first_row`` (W,) (the horizon); NaN where the carpet reaches the image top or a column
    shows none."""
    height = carpet.shape[0]
    rows = np.arange(height)[:, None]
    allowed = carpet & (rows >= first_row[None, :])
    weight = np.where(allowed, 1, -1).astype(np.int32)
    below = np.cumsum(weight[::-1], axis=0)[::-1]
    best = np.argmax(below, axis=0)
    score = below[best, np.arange(carpet.shape[1])]
    return np.where((score > 0) & (best > 0), best, np.nan).astype(np.float64)


@dataclass(frozen=True)
class Blob:
    """A white component: its pixel ``centroid`` (2,) px and its ``pixels`` (K, 2) px."""

    centroid: FloatArray
    pixels: FloatArray


def blobs(
    white: BoolImage,
    green: BoolImage,
    *,
    min_px: int,
    max_px: int,
    ring_px: int,
    green_fraction: float,
) -> list[Blob]:
    """White 8-connected components of ``min_px`` to ``max_px`` pixels, clear of the image
    sides, whose ring (their box widened by ``ring_px``, less the white) is at least
    ``green_fraction`` green."""
    count, labels, stats, centroids = cv2.connectedComponentsWithStats(
        white.astype(np.uint8), connectivity=8
    )
    height, width = white.shape
    out = []
    for k in range(1, count):
        x, y, w, h, area = (int(v) for v in stats[k])
        if not (min_px <= area <= max_px):
            continue
        x0, y0, x1, y1 = x - ring_px, y - ring_px, x + w + ring_px, y + h + ring_px
        if x0 < 0 or y0 < 0 or x1 > width or y1 > height:
            continue
        ring = ~white[y0:y1, x0:x1]
        if green[y0:y1, x0:x1][ring].mean() < green_fraction:
            continue
        ys, xs = np.nonzero(labels[y : y + h, x : x + w] == k)
        out.append(Blob(np.asarray(centroids[k], np.float64), np.column_stack([xs + x, ys + y])))
    return out


def ground_extent(
    blob: Blob, points: FloatArray, centre: FloatArray, camera: CameraModel, state: CameraState
) -> FloatArray:
    """(2,) extent (m) of a ``blob`` on the ground along and across the view to its
    ``centre`` (2,) m: the spread of its pixels' ground ``points`` (K, 2) plus one pixel's
    footprint there."""
    view = centre / max(float(np.hypot(*centre)), 1e-9)
    axes = np.array([view, [-view[1], view[0]]])
    spread = (points - centre) @ axes.T
    footprint = np.abs(axes @ ground_jacobians(blob.centroid[None], camera, state)[0]).sum(axis=1)
    return np.asarray(spread.max(axis=0) - spread.min(axis=0) + footprint, dtype=np.float64)


def cut_ends(ends_px: FloatArray, clear: BoolImage, border_px: float) -> NDArray[np.bool_]:
    """Whether each end of an image line ``ends_px`` (2, 2) px is cut (the line may go on):
    within ``border_px`` of the image side, or something not ``clear`` (carpet or white,
    (H, W)) lies just beyond it (2 to 6 px on along the line: a robot, the goal's net)."""
    height, width = clear.shape
    u, v = ends_px.T
    cut = (u < border_px) | (u > width - 1 - border_px)
    cut |= (v < border_px) | (v > height - 1 - border_px)
    d = ends_px[1] - ends_px[0]
    d = d / max(float(np.hypot(*d)), 1e-9)
    for k, sign in ((0, -1.0), (1, 1.0)):
        beyond = ends_px[k] + sign * np.arange(2.0, 7.0)[:, None] * d
        cols, rows = np.rint(beyond).astype(np.intp).T
        inside = (cols >= 0) & (cols < width) & (rows >= 0) & (rows < height)
        cut[k] |= bool((~clear[rows[inside], cols[inside]]).any())
    return np.asarray(cut, dtype=bool)


def post_feet(
    white: BoolImage,
    ground: BoolImage,
    camera: CameraModel,
    state: CameraState,
    *,
    diameter_m: float,
    width_ratio: tuple[float, float],
    min_height_m: tuple[float, float],
    side_white_max: float,
    max_trim_m: float = 0.1,
) -> list[FloatArray]:
    """Foot pixels (2,) px (bottom centre) of upright white posts standing on ``ground``
    (carpet or line pixels, (H, W)).

    A column counts where a vertical white run ends on ground (within 2 px below it) and
    stands at least ``min_height_m[0]`` tall at the range of its bottom, or
    ``min_height_m[1]`` when the image top cuts it (a lower bound); adjacent such columns
    with bottoms within half a post's width (at least 3 rows) make one post. Its foot is moved
    up past rows where the white runs on sideways beyond it (the line it stands on), over no
    more than ``max_trim_m`` of ground (a board on the white floor beyond the carpet stands on
    more). A post is kept when its width is within ``width_ratio`` of ``diameter_m`` at that
    range and the columns half its width beside it are at most ``side_white_max`` white from
    its foot up to ``min_height_m[1]`` (not a sliver of a wider white thing, nor the legs of a
    grey robot under its wider body).
    """
    height, width = white.shape
    cols, tops, ends = _row_runs(white.T)
    below = np.zeros(len(cols), dtype=bool)
    for k in (0, 1):
        r = ends + k
        inside = r < height
        below[inside] |= ground[r[inside], cols[inside]]
    cols, tops, bottoms = cols[below], tops[below], ends[below] - 1
    foot_xy, hit = ground_points(np.column_stack([cols, bottoms + 0.5]), camera, state)
    tall = np.zeros(len(cols), dtype=bool)
    tall[hit] = _tall_enough(foot_xy[hit], tops[hit], min_height_m, camera, state)
    cols, tops, bottoms = cols[tall], tops[tall], bottoms[tall]
    depth = (np.column_stack([foot_xy[tall], np.zeros(len(cols))]) - state.position) @ (
        state.rotation()[:, 0]
    )
    reach = camera.fx * diameter_m / np.maximum(depth, 1e-3)  # a post's width (px) there
    order = np.lexsort((bottoms, cols))
    cols, tops, bottoms, reach = cols[order], tops[order], bottoms[order], reach[order]
    groups: list[list[int]] = []
    for k in range(len(cols)):
        last = groups[-1][-1] if groups else -1
        step = abs(int(bottoms[k] - bottoms[last])) if last >= 0 else 0
        if last >= 0 and cols[k] - cols[last] == 1 and step <= max(3.0, 0.5 * reach[k]):
            groups[-1].append(k)  # the round foot of a near post curves down to its front
        elif last < 0 or cols[k] != cols[last]:
            groups.append([k])
    feet = []
    for group in groups:
        c0, c1 = int(cols[group[0]]), int(cols[group[-1]])
        top, foot = int(tops[group].min()), int(bottoms[group].max())
        bottom = foot
        while foot > top and (
            (c0 >= 2 and white[foot, c0 - 2]) or (c1 + 2 < width and white[foot, c1 + 2])
        ):
            foot -= 1
        pixel = np.array([0.5 * (c0 + c1), foot + 0.5])
        xy, hit = ground_points(pixel[None], camera, state)
        if not hit[0] or bottom - foot > _rows_over(xy[0], max_trim_m, camera, state) + 2:
            continue  # standing on a white strip wider than a line: the floor, not the carpet
        depth_m = float((np.append(xy[0], 0.0) - state.position) @ state.rotation()[:, 0])
        if depth_m <= 0:
            continue
        expected = camera.fx * diameter_m / depth_m
        if not (width_ratio[0] * expected <= c1 - c0 + 1 <= width_ratio[1] * expected):
            continue
        low = max(int(_row_at(xy[0], min_height_m[1], camera, state)), top)
        side = 2 + (c1 - c0) // 2  # beyond the lean of a post in a pitched camera
        sides = [white[low : foot + 1, c] for c in (c0 - side, c1 + side) if 0 <= c < width]
        if not sides or max(float(s.mean()) for s in sides) > side_white_max:
            continue
        feet.append(pixel)
    return feet


def _rows_over(point: FloatArray, depth_m: float, camera: CameraModel, state: CameraState) -> float:
    """Image rows (px) that the ground from ``point`` (2,) m to ``depth_m`` further from the
    camera spans; inf when the far end lies beyond the horizon."""
    view = point - state.position[:2]
    far = point + depth_m * view / max(float(np.hypot(*view)), 1e-9)
    uv = pixels_of(np.array([point, far]), camera, state)
    return float(uv[0, 1] - uv[1, 1]) if np.isfinite(uv).all() else math.inf


def _row_at(point: FloatArray, height_m: float, camera: CameraModel, state: CameraState) -> float:
    """Image row (px) of the point ``height_m`` above the ground point ``point`` (2,) m; -inf
    behind the camera."""
    offset = np.append(point, height_m) - state.position
    uv, front = project_points(
        (offset @ state.rotation())[None], camera.fx, camera.fy, camera.cx, camera.cy
    )
    return float(uv[0, 1]) if front[0] else -math.inf


def _tall_enough(
    feet: FloatArray,
    tops: NDArray[np.intp],
    height_m: tuple[float, float],
    camera: CameraModel,
    state: CameraState,
) -> NDArray[np.bool_]:
    """Whether white runs from rows ``tops`` (N,) down to the ground points ``feet`` (N, 2) m
    reach ``height_m[0]`` above them, or ``height_m[1]`` when they reach the image top."""
    needed = np.where(tops > 0, height_m[0], height_m[1])
    points = np.column_stack([feet, needed]) - state.position
    uv, front = project_points(
        points @ state.rotation(), camera.fx, camera.fy, camera.cx, camera.cy
    )
    return np.asarray(front & (tops - 0.5 <= np.nan_to_num(uv[:, 1], nan=-np.inf)), dtype=bool)
