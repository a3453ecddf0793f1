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
- :class:`GroundProjection` (one per frame; :func:`ground_points`, :func:`ground_covariances`
  and :func:`pixels_of` make one for a single call): the projection, its derivative by
  central differences (as in :mod:`perception.vision.ground_point`, in ``(x, y)`` rather
  than range and bearing) and the projection back into the image; :func:`row_shifted`: a
  camera model for an image drawn rows higher than the model says (PyBullet's tiny
  renderer).
- :func:`cut_ends`: whether an image line's end may go on (image side, an occluder).
- :func:`carpet_top`: per column, the row that best splits non-carpet above from carpet below
  (:func:`best_splits`, which :mod:`perception.vision.robots`' field boundary shares and
  gives an envelope).
- Mask helpers: :func:`row_runs` and :func:`run_pixels` (runs of a mask along its rows, the
  pixels of runs), :func:`transposed` (a mask's columns as rows, for column scans) and
  :func:`rows_from` (the rows below a per-column limit such as :func:`horizon_rows`), also
  used by :mod:`perception.vision.robots`; :func:`hsv_mask` and
  :func:`masked_median` (colour masks and a channel's median over one).
- :func:`blobs`, :func:`ground_extent`: small white components ringed by green and their
  size on the ground (penalty marks); :func:`post_feet`: the feet of tall, narrow white
  columns standing on the carpet (goal posts).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import ArrayLike, NDArray

from perception.geometry import FloatArray, project_points
from perception.types import CameraModel, CameraState

BoolImage = NDArray[np.bool_]
JACOBIAN_STEP_PX = 0.25  # central-difference step of :meth:`GroundProjection.jacobians`


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


class GroundProjection:
    """Between image points ``(u, v)`` px of ``camera`` and ground points ``(x, y)`` m (robot
    frame) seen from ``state``, with the rotation and intrinsics worked out once (one frame
    asks many times)."""

    def __init__(self, camera: CameraModel, state: CameraState) -> None:
        self.rotation = state.rotation()  # (3, 3) camera to robot
        self.position = np.asarray(state.position, dtype=np.float64)  # (3,) m
        self.fx, self.fy, self.cx, self.cy = camera.fx, camera.fy, camera.cx, camera.cy

    def points(self, pixels: FloatArray) -> tuple[FloatArray, BoolImage]:
        """Ground points (N, 2) m seen at ``pixels`` (N, 2) px, and a (N,) mask of those below
        the horizon (the others are NaN), by a unit ray's z less than -1e-9."""
        uv = np.asarray(pixels, dtype=np.float64).reshape(-1, 2)
        left = (self.cx - uv[:, 0]) / self.fx  # the ray (1, left, up) in the camera frame
        up = (self.cy - uv[:, 1]) / self.fy
        (rx, ry, rz), o = self.rotation, self.position
        down = rz[0] + rz[1] * left + rz[2] * up  # the ray's robot-frame z
        hit = down < -1e-9 * np.sqrt(1.0 + left * left + up * up)
        t = -o[2] / np.where(hit, down, np.nan)  # NaN off the ground
        xy = np.empty((len(uv), 2))
        xy[:, 0] = o[0] + t * (rx[0] + rx[1] * left + rx[2] * up)
        xy[:, 1] = o[1] + t * (ry[0] + ry[1] * left + ry[2] * up)
        return xy, hit

    def jacobians(self, pixels: FloatArray) -> FloatArray:
        """(N, 2, 2) ``d(x, y)/d(u, v)`` m/px at ``pixels`` (N, 2) by central differences of
        ``JACOBIAN_STEP_PX``; NaN where a displaced pixel misses the ground."""
        uv = np.asarray(pixels, dtype=np.float64).reshape(-1, 2)
        steps = JACOBIAN_STEP_PX * np.array([[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]])
        xy, _ = self.points((uv[:, None] + steps[None]).reshape(-1, 2))
        xy = xy.reshape(len(uv), 4, 2)  # +u, +v, -u, -v
        return np.asarray(
            np.stack([xy[:, 0] - xy[:, 2], xy[:, 1] - xy[:, 3]], axis=2) / (2 * JACOBIAN_STEP_PX),
            dtype=np.float64,
        )

    def slopes(self, pixels: FloatArray, axes: NDArray[np.intp]) -> FloatArray:
        """(N, 2) ``d(x, y)/du`` or ``d(x, y)/dv`` m/px at ``pixels`` (N, 2), each along its own
        image axis ``axes`` (N,) (0: u, 1: v): that column of :meth:`jacobians`, to the last
        bit, at half the projections."""
        uv = np.asarray(pixels, dtype=np.float64).reshape(-1, 2)
        step = np.zeros_like(uv)
        step[np.arange(len(uv)), axes] = JACOBIAN_STEP_PX
        ahead, _ = self.points(uv + step)
        behind, _ = self.points(uv - step)
        return np.asarray((ahead - behind) / (2 * JACOBIAN_STEP_PX), dtype=np.float64)

    def covariances(self, pixels: FloatArray, pixel_std_px: float) -> FloatArray:
        """(N, 2, 2) covariance (m²) of the ground points at ``pixels`` (N, 2) for independent
        noise of ``pixel_std_px`` on each image axis, to first order; NaN at the horizon."""
        jac = self.jacobians(pixels)
        return np.asarray(pixel_std_px**2 * jac @ jac.transpose(0, 2, 1), dtype=np.float64)

    def project(self, points: FloatArray) -> tuple[FloatArray, BoolImage]:
        """Image points (N, 2) px of robot-frame points (N, 3) m and a (N,) mask of those in
        front of the camera (the others are NaN)."""
        cam = (np.asarray(points, dtype=np.float64) - self.position) @ self.rotation
        return project_points(cam, self.fx, self.fy, self.cx, self.cy)

    def pixels_of(self, points: FloatArray) -> FloatArray:
        """Image points (N, 2) px of the ground points ``points`` (N, 2) m; NaN behind the
        camera (pixels outside the image are kept: the pinhole extends beyond it)."""
        return self.project(np.column_stack([points, np.zeros(len(points))]))[0]

    def depths(self, points: FloatArray) -> FloatArray:
        """Distance (N,) m along the optical axis of the ground points ``points`` (N, 2) m."""
        offset = np.column_stack([points, np.zeros(len(points))]) - self.position
        return np.asarray(offset @ self.rotation[:, 0], dtype=np.float64)


def ground_points(
    pixels: FloatArray, camera: CameraModel, state: CameraState
) -> tuple[FloatArray, BoolImage]:
    """:meth:`GroundProjection.points` of ``pixels`` (N, 2) px."""
    return GroundProjection(camera, state).points(pixels)


def ground_covariances(
    pixels: FloatArray, camera: CameraModel, state: CameraState, pixel_std_px: float
) -> FloatArray:
    """:meth:`GroundProjection.covariances` at ``pixels`` (N, 2) px."""
    return GroundProjection(camera, state).covariances(pixels, pixel_std_px)


def pixels_of(points: FloatArray, camera: CameraModel, state: CameraState) -> FloatArray:
    """:meth:`GroundProjection.pixels_of` the ground ``points`` (N, 2) m."""
    return GroundProjection(camera, state).pixels_of(points)


def hsv_mask(hsv: NDArray[np.uint8], bounds: tuple[ArrayLike, ArrayLike]) -> BoolImage:
    """Pixels of ``hsv`` (H, W, 3; rows may be a window's, pixels contiguous) within the
    inclusive ``bounds`` ``(low, high)`` (3,) each (uint8 arrays pass through uncopied)."""
    lo, hi = (np.asarray(b, dtype=np.uint8) for b in bounds)
    return np.asarray(cv2.inRange(hsv, lo, hi), dtype=bool)


def masked_median(image: NDArray[np.uint8], channel: int, mask: BoolImage) -> float:
    """Median (as :func:`numpy.median`: the mean of the middle two of an even count) of
    ``channel`` of ``image`` (H, W, C) over the pixels of ``mask`` (H, W), which holds some."""
    histogram = cv2.calcHist([image], [channel], mask.view(np.uint8), [256], [0, 256])
    counts = np.cumsum(histogram.ravel())  # float32, exact: at most H * W < 2**24
    n = int(counts[-1])
    low, high = np.searchsorted(counts, [(n - 1) // 2, n // 2], side="right")
    return 0.5 * float(low + high)


def row_runs(mask: BoolImage) -> tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.intp]]:
    """Runs of True along each row of ``mask`` (H, W): rows, first columns, end columns
    (exclusive), in row-major order."""
    height, width = mask.shape
    padded = np.zeros((height + 1, width + 1), dtype=bool)  # False before each row and after all
    padded[:height, 1:] = mask
    flat = padded.ravel()
    changes = np.flatnonzero(flat[1:] != flat[:-1]) + 1  # alternately a run's start and end
    rows = changes[0::2] // (width + 1)
    first = rows * (width + 1) + 1  # each run's row's column 0 in ``flat``
    return rows, changes[0::2] - first, changes[1::2] - first


def transposed(mask: BoolImage) -> BoolImage:
    """``mask`` (H, W) transposed, (W, H) and contiguous: OpenCV's transpose, many times faster
    than NumPy's copy of a transposed view (which the column scans would otherwise make)."""
    if not mask.size:
        return np.zeros(mask.shape[::-1], dtype=bool)
    flipped = cv2.transpose(np.ascontiguousarray(mask).view(np.uint8))
    return np.asarray(flipped).view(np.bool_)


def _beside(
    padded: BoolImage, rows: NDArray[np.intp], cols: NDArray[np.intp], sign: int, gap: int
) -> NDArray[np.bool_]:
    """Whether green holds at one of the ``gap`` pixels beyond ``cols`` (in direction
    ``sign``) on ``rows``; ``padded`` (H, W + 2 gap) is the green image with ``gap`` columns
    of False (past the image side) on either side."""
    out = padded[rows, cols + gap + sign]
    for k in range(2, gap + 1):
        out |= padded[rows, cols + gap + sign * k]
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
    projection: GroundProjection,
    *,
    line_width_m: float,
    width_factor: float,
    slack_px: float,
    green_gap_px: int,
    max_range_m: float,
) -> LineRuns:
    """White runs (along rows, then columns) that a field line can make (module docstring),
    whose middles lie on the ground within ``max_range_m`` of the robot."""
    height, width = white.shape
    rows, starts, ends = _green_ended_runs(white, green, green_gap_px)
    cols, tops, bottoms = _green_ended_runs(transposed(white), transposed(green), green_gap_px)
    uv = np.concatenate(
        [
            np.column_stack([0.5 * (starts + ends - 1), rows]),
            np.column_stack([cols, 0.5 * (tops + bottoms - 1)]),
        ]
    ).astype(np.float64)
    in_row = np.repeat([True, False], [len(rows), len(cols)])  # runs of the row scan
    first = np.concatenate([rows * width + starts, tops * width + cols])  # flat pixel index
    step = np.where(in_row, 1, width)  # on to the run's next pixel
    run_px = np.concatenate([ends - starts, bottoms - tops])
    xy, hit = projection.points(uv)
    hit &= np.hypot(xy[:, 0], xy[:, 1]) <= max_range_m
    along = projection.slopes(uv[hit], np.where(in_row[hit], 0, 1))  # m per pixel on
    limit = width_factor * line_width_m / np.hypot(along[:, 0], along[:, 1]) + slack_px
    keep = np.flatnonzero(hit)[run_px[hit] <= limit]
    mask = np.zeros(height * width, dtype=bool)
    mask[run_pixels(first[keep], step[keep], run_px[keep])] = True
    return LineRuns(uv[keep], xy[keep], mask.reshape(height, width))


def _green_ended_runs(
    white: BoolImage, green: BoolImage, gap: int
) -> tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.intp]]:
    """The runs of ``white`` (H, W) along its rows with ``green`` (H, W) within ``gap`` px
    beyond both ends: rows, first columns and end columns (exclusive)."""
    rows, starts, ends = row_runs(white)
    padded = np.zeros((green.shape[0], green.shape[1] + 2 * gap), dtype=bool)
    padded[:, gap:-gap] = green
    ok = _beside(padded, rows, starts, -1, gap) & _beside(padded, rows, ends - 1, 1, gap)
    return rows[ok], starts[ok], ends[ok]


def run_pixels(
    first: NDArray[np.intp], step: NDArray[np.intp] | int, length: NDArray[np.intp]
) -> NDArray[np.intp]:
    """Flat image indices of the pixels of runs starting at the flat index ``first`` (R,) and
    going on ``length`` (R,) pixels ``step`` (R,) (or one for all) apart: 1 along a row, W
    down a column."""
    starts = np.cumsum(length) - length
    within = np.arange(int(length.sum())) - np.repeat(starts, length)
    steps = np.repeat(step, length) if np.ndim(step) else step
    return np.asarray(np.repeat(first, length) + within * steps, dtype=np.intp)


def horizon_rows(projection: GroundProjection, columns: FloatArray) -> FloatArray:
    """Row (C,) px of the horizon at each of ``columns`` (px); -inf where the camera looks so
    steeply that no row is horizontal."""
    r, p = projection.rotation[2], projection
    if r[2] <= 1e-9:
        return np.full(len(columns), -np.inf)
    return np.asarray(p.cy + p.fy * (r[0] + r[1] * (p.cx - columns) / p.fx) / r[2], np.float64)


def rows_from(first_row: FloatArray, height: int) -> BoolImage:
    """(H, C) mask of the rows at or below ``first_row`` (C,) (px, any real) in each column."""
    first = np.clip(np.ceil(first_row), 0, height).astype(np.int16)  # whole rows: the same
    return np.asarray(np.arange(height, dtype=np.int16)[:, None] >= first[None, :])


def best_splits(carpet: BoolImage) -> tuple[NDArray[np.intp], NDArray[np.int32]]:
    """Per column of ``carpet`` (H, W), the first row that maximises the count of carpet less
    non-carpet pixels from it down, and that count (W,) each."""
    height, width = carpet.shape
    # (W + 1, H + 1) integral image of the columns: carpet above each row, summed over columns
    summed = np.asarray(cv2.integral(transposed(carpet).view(np.uint8)), dtype=np.int32)
    # carpet less the rest from row r down is 2 (above[H] - above[r]) - (H - r), with above[r]
    # the column's carpet above row r: the column's constant 2 above[H] - H plus the key
    # r - 2 above[r], whose argmax (the first of equals) it shares. Worked in place: a frame's
    # fresh (W, H) temporaries cost more in page faults than in arithmetic.
    key = summed[:-1]  # (W, H + 1), becoming -2 above, then the key in its first H columns
    np.subtract(key, summed[1:], out=key)
    key *= 2
    key[:, :-1] += np.arange(height, dtype=np.int32)
    best = np.argmax(key[:, :-1], axis=1)
    score = key[np.arange(width), best] - key[:, -1] - height  # key[H] is -2 above[H]
    return best, score


def carpet_top(carpet: BoolImage) -> FloatArray:
    """Per column of ``carpet`` (H, W) (none above the horizon), the first row of the carpet:
    the row that maximises the count of carpet less non-carpet pixels from it down; NaN where
    the carpet reaches the image top or a column shows none."""
    best, score = best_splits(carpet)
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
    min_side_px: int,
    ring_px: int,
    green_fraction: float,
) -> list[Blob]:
    """White 8-connected components of ``min_px`` to ``max_px`` pixels, at least
    ``min_side_px`` wide and tall, clear of the image sides, whose ring (their box widened by
    ``ring_px``, less the white) is at least ``green_fraction`` green."""
    mask = np.ascontiguousarray(white).view(np.uint8)
    # BBDT labels as the default algorithm does (raster order), and is faster with stats
    _, labels, stats, centroids = cv2.connectedComponentsWithStatsWithAlgorithm(
        mask, 8, cv2.CV_32S, cv2.CCL_BBDT
    )
    height, width = white.shape
    x, y, w, h, area = stats.T
    x0, y0, x1, y1 = x - ring_px, y - ring_px, x + w + ring_px, y + h + ring_px
    sized = (area >= min_px) & (area <= max_px) & (w >= min_side_px) & (h >= min_side_px)
    sized &= (x0 >= 0) & (y0 >= 0) & (x1 <= width) & (y1 <= height)
    sized[0] = False  # the background
    out = []
    for k in np.flatnonzero(sized).tolist():
        ring = ~white[y0[k] : y1[k], x0[k] : x1[k]]
        if green[y0[k] : y1[k], x0[k] : x1[k]][ring].mean() < green_fraction:
            continue
        ys, xs = np.nonzero(labels[y[k] : y[k] + h[k], x[k] : x[k] + w[k]] == k)
        pixels = np.column_stack([xs + x[k], ys + y[k]])
        out.append(Blob(np.asarray(centroids[k], np.float64), pixels))
    return out


def ground_extent(
    blob: Blob, points: FloatArray, centre: FloatArray, projection: GroundProjection
) -> tuple[FloatArray, FloatArray]:
    """(2,) extent (m) of a ``blob`` on the ground along and across the view to its
    ``centre`` (2,) m: the spread of its pixels' ground ``points`` (K, 2) plus one pixel's
    footprint there; and that footprint (2,) m, along and across."""
    view = centre / max(float(np.hypot(*centre)), 1e-9)
    axes = np.array([view, [-view[1], view[0]]])
    spread = (points - centre) @ axes.T
    footprint = np.abs(axes @ projection.jacobians(blob.centroid[None])[0]).sum(axis=1)
    extent = spread.max(axis=0) - spread.min(axis=0) + footprint
    return np.asarray(extent, dtype=np.float64), np.asarray(footprint, dtype=np.float64)


def cut_ends(ends_px: FloatArray, clear: BoolImage, border_px: float) -> NDArray[np.bool_]:
    """Whether each end of the image lines ``ends_px`` (L, 2, 2) px is cut (the line may go
    on), (L, 2): within ``border_px`` of the image side, or something not ``clear`` (carpet or
    white, (H, W)) lies just beyond it (2 to 6 px on along the line: a robot, the goal's net)."""
    height, width = clear.shape
    u, v = ends_px[..., 0], ends_px[..., 1]
    cut = (u < border_px) | (u > width - 1 - border_px)
    cut |= (v < border_px) | (v > height - 1 - border_px)
    d = ends_px[:, 1] - ends_px[:, 0]
    d = d / np.maximum(np.hypot(d[:, 0], d[:, 1]), 1e-9)[:, None]
    outward = np.stack([-d, d], axis=1)  # (L, 2, 2): from each end away from the other
    beyond = ends_px[:, :, None] + np.arange(2.0, 7.0)[:, None] * outward[:, :, None]
    cols, rows = np.rint(beyond).astype(np.intp).transpose(3, 0, 1, 2)  # (L, 2, 5) each
    inside = (cols >= 0) & (cols < width) & (rows >= 0) & (rows < height)
    blocked = np.zeros(cols.shape, dtype=bool)
    blocked[inside] = ~clear[rows[inside], cols[inside]]
    return np.asarray(cut | blocked.any(axis=2), dtype=bool)


def post_feet(
    white: BoolImage,
    ground: BoolImage,
    projection: GroundProjection,
    *,
    diameter_m: float,
    width_ratio: tuple[float, float],
    min_height_m: tuple[float, float],
    side_white_max: float,
    max_trim_m: float = 0.1,
) -> list[FloatArray]:
    """Foot pixels (2,) px (bottom centre) of upright white posts standing on ``ground``
    (carpet or line pixels, (H, W)).

    A column counts where a vertical white run ends on ground (within 2 px below it) and stands
    at least ``min_height_m[0]`` tall at the range of its bottom, or ``min_height_m[1]`` when
    the image top cuts it (a lower bound); adjacent such columns with bottoms within half a
    post's width (at least 3 rows) make one candidate. Its extent on each row is the white run
    through those columns (a post leaning in the image, off its centre in a pitched or rolled
    camera, has fewer tall columns than it is wide). Its foot is moved up past rows where that
    run is wider than a post there, or than its own median run by more than 2 px or a quarter
    (the line it stands on runs sideways), over no more than ``max_trim_m`` of ground (a board
    on the white floor beyond the carpet stands on more); the foot pixel is the middle of the
    run on the foot's row. A candidate is kept when, from its foot up to ``min_height_m[0]``
    (under the crossbar), its median run is within ``width_ratio`` of ``diameter_m`` at that
    range and steady (upper and lower quartile within 2 px or a quarter of it: not a robot's
    legs, arms and body), and the pixels half its width beyond each run's ends are at most
    ``side_white_max`` white from its foot up to ``min_height_m[1]`` on either side (not a
    sliver of a wider white thing). Candidates whose runs share a pixel there are one post (a
    lean splits its tall columns): the lowest foot is kept.
    """
    height, width = white.shape
    cols, tops, ends = row_runs(transposed(white))
    below = np.zeros(len(cols), dtype=bool)
    for k in (0, 1):
        r = ends + k
        inside = r < height
        below[inside] |= ground[r[inside], cols[inside]]
    cols, tops, bottoms = cols[below], tops[below], ends[below] - 1
    foot_xy, hit = projection.points(np.column_stack([cols, bottoms + 0.5]))
    tall = np.zeros(len(cols), dtype=bool)
    tall[hit] = _tall_enough(foot_xy[hit], tops[hit], min_height_m, projection)
    cols, tops, bottoms = cols[tall], tops[tall], bottoms[tall]
    depth = projection.depths(foot_xy[tall])
    reach = projection.fx * diameter_m / np.maximum(depth, 1e-3)  # a post's width (px) there
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
    feet: list[FloatArray] = []
    spans: list[tuple[int, NDArray[np.intp], NDArray[np.intp]]] = []
    for group in groups:
        c0, c1 = int(cols[group[0]]), int(cols[group[-1]])
        top, bottom = int(tops[group].min()), int(bottoms[group].max())
        left, right = _runs_through(white[top : bottom + 1], c0, c1)
        run_px = right - left + 1  # per row from top to bottom
        xy, hit = projection.points(np.array([[0.5 * (c0 + c1), bottom + 0.5]]))
        depth_m = float(projection.depths(xy)[0]) if hit[0] else 0.0
        if depth_m <= 0:
            continue
        steady = float(np.median(run_px))  # the post's own width, whatever its range
        widest = min(
            width_ratio[1] * projection.fx * diameter_m / depth_m, steady + max(2.0, steady / 4)
        )
        foot = bottom
        while foot > top and run_px[foot - top] > widest:
            foot -= 1  # the line the post stands on
        pixel = np.array([0.5 * (left[foot - top] + right[foot - top]), foot + 0.5])
        xy, hit = projection.points(pixel[None])
        if not hit[0] or bottom - foot > _rows_over(xy[0], max_trim_m, projection) + 2:
            continue  # standing on a white strip wider than a line: the floor, not the carpet
        depth_m = float(projection.depths(xy)[0])
        if depth_m <= 0:
            continue
        expected = projection.fx * diameter_m / depth_m
        high = max(int(_row_at(xy[0], min_height_m[0], projection)), top)
        under_bar = slice(high - top, foot - top + 1)  # the crossbar joins the two posts
        median_px = float(np.median(run_px[under_bar]))
        if not (width_ratio[0] * expected <= median_px <= width_ratio[1] * expected):
            continue
        lower_q, upper_q = np.percentile(run_px[under_bar], [25, 75])
        if upper_q - lower_q > max(2.0, 0.25 * median_px):
            continue
        low = max(int(_row_at(xy[0], min_height_m[1], projection)), top)
        rows = np.arange(low, foot + 1)
        side = 2 + int(median_px) // 2
        side_white = [
            np.where((c >= 0) & (c < width), white[rows, np.clip(c, 0, width - 1)], False).mean()
            for c in (left[rows - top] - side, right[rows - top] + side)
        ]
        if max(side_white) > side_white_max:
            continue
        span = (high, left[under_bar], right[under_bar])
        same = [k for k, other in enumerate(spans) if _overlap(span, other)]
        if not same:
            feet.append(pixel)
            spans.append(span)
        elif pixel[1] > feet[same[0]][1]:
            feet[same[0]], spans[same[0]] = pixel, span
    return feet


def _overlap(
    a: tuple[int, NDArray[np.intp], NDArray[np.intp]],
    b: tuple[int, NDArray[np.intp], NDArray[np.intp]],
) -> bool:
    """Whether two candidates' white runs ``(first row, left (R,), right (R,))`` share a pixel
    on a row both span."""
    top = max(a[0], b[0])
    bottom = min(a[0] + len(a[1]), b[0] + len(b[1]))
    if bottom <= top:
        return False
    ra, rb = slice(top - a[0], bottom - a[0]), slice(top - b[0], bottom - b[0])
    return bool(np.any((a[1][ra] <= b[2][rb]) & (b[1][rb] <= a[2][ra])))


def _runs_through(white: BoolImage, c0: int, c1: int) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """Per row of ``white`` (R, W), the first and last column (R,) of the white run through
    columns ``c0..c1``: the run holding the white pixel of those columns nearest their middle;
    an empty run (last = first - 1) at the middle where none of them is white on that row.
    """
    rows, width = white.shape
    columns = np.arange(width)
    centre = (c0 + c1) // 2
    off = np.where(white[:, c0 : c1 + 1], np.abs(columns[c0 : c1 + 1] - centre), width)
    found = off.min(axis=1) < width
    seed = np.where(found, c0 + np.argmin(off, axis=1), centre)
    r = np.arange(rows)
    gap_before = np.maximum.accumulate(np.where(white, -1, columns), axis=1)
    gap_after = np.minimum.accumulate(np.where(white, width, columns)[:, ::-1], axis=1)[:, ::-1]
    first = np.where(found, gap_before[r, seed] + 1, centre)
    return first, np.where(found, gap_after[r, seed] - 1, centre - 1)


def _rows_over(point: FloatArray, depth_m: float, projection: GroundProjection) -> float:
    """Image rows (px) that the ground from ``point`` (2,) m to ``depth_m`` further from the
    camera spans; inf when the far end lies beyond the horizon."""
    view = point - projection.position[:2]
    far = point + depth_m * view / max(float(np.hypot(*view)), 1e-9)
    uv = projection.pixels_of(np.array([point, far]))
    return float(uv[0, 1] - uv[1, 1]) if np.isfinite(uv).all() else math.inf


def _row_at(point: FloatArray, height_m: float, projection: GroundProjection) -> float:
    """Image row (px) of the point ``height_m`` above the ground point ``point`` (2,) m; -inf
    behind the camera."""
    uv, front = projection.project(np.append(point, height_m)[None])
    return float(uv[0, 1]) if front[0] else -math.inf


def _tall_enough(
    feet: FloatArray,
    tops: NDArray[np.intp],
    height_m: tuple[float, float],
    projection: GroundProjection,
) -> NDArray[np.bool_]:
    """Whether white runs from rows ``tops`` (N,) down to the ground points ``feet`` (N, 2) m
    reach ``height_m[0]`` above them, or ``height_m[1]`` when they reach the image top."""
    needed = np.where(tops > 0, height_m[0], height_m[1])
    uv, front = projection.project(np.column_stack([feet, needed]))
    return np.asarray(front & (tops - 0.5 <= np.nan_to_num(uv[:, 1], nan=-np.inf)), dtype=bool)
