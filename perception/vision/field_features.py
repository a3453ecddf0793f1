"""Field features from one camera image (seed 004 §2.1-2.2): lines, junctions, the centre
circle, penalty marks, goal posts and the carpet's edge, on the ground in the robot frame.

:func:`detect_field_features` turns an (H, W, 3) uint8 RGB image, the camera's intrinsics and
its pose on the robot (:class:`~perception.types.CameraState`, as the joints report it) into
:class:`~perception.field.features.FieldFeature` s (robot frame: x forward, y left, m; kinds
and direction conventions in that module's table). Steps:

1. **Line pixels.** Carpet ``green_hsv`` and line ``white_hsv`` (tuned on rendered frames:
   carpet H ≈ 62, S ≈ 173, V ≈ 124; lines V ≈ 246, a far line thinner than a pixel V ≈ 145;
   the goal's net V ≈ 88 stays out). Below the horizon, white runs along rows and columns with
   green just beyond both ends and no wider than a line at their range
   (:func:`~perception.vision.field_pixels.line_runs`): robots, posts, the ball and the white
   floor beyond the carpet fail one or the other. Their middles are the line's centre line.
2. **Segments.** Collinear run middles in the image (iterated Hough + total least squares,
   :func:`~perception.vision.field_geometry.image_lines`: straight lines stay straight in an
   undistorted image, where the noise is a pixel everywhere; on the ground it grows with the
   square of the range and no single tolerance suits near and far). Each group's ends are
   projected to the ground; a group that bends on the ground (``min_curvature``,
   :func:`~perception.vision.field_geometry.curvature`) is a piece of the circle, not a line.
   Collinear pieces that overlap or nearly meet are merged (``merge_*``), then those shorter
   than ``min_line_m`` dropped. An end at the image side, the range limit or an occluder
   (something neither carpet nor white just beyond it) is *open*: the line may go on.
3. **Junctions** of near-perpendicular segments (``junction_*``): L ``corner``, ``t_junction``,
   ``x_junction`` (:func:`~perception.vision.field_geometry.find_junctions`); none where an
   open end makes the kind uncertain (a T's bar cut by the image side looks like an L).
4. **Centre circle** (drawn as a 32-gon of 0.15 m pieces): among the run middles left over,
   in short or bent pieces, within ``circle_max_range_m``, a Hough vote for the centre of a
   circle of ``circle_radius_m``, checked for an unbroken, bending arc and by the Hyper fit's
   radius, refined with the radius fixed
   (:func:`~perception.vision.field_geometry.find_circle`); straight pieces lying on it are
   dropped from the lines. A segment through its centre is the halfway line: it gives the
   circle's direction and, where it crosses the circle, two ``x_junction`` s. The white of
   the centre mark is not reported as a penalty mark.
5. **Penalty marks**: white components ringed by green whose ground extent is a mark's
   (``mark_size_m``) and as long along the view as across it (``mark_elongation_slack_m``):
   a ball, standing up, stretches along the view on the ground, too far from 0.8 m out and
   by 0.05 m or more nearer; clear of lines.
   **Goal posts**: tall narrow white columns standing on the carpet, their foot projected
   and moved ``post_diameter_m / 2`` along the view to the post's centre
   (:func:`~perception.vision.field_pixels.post_feet`). **Field edge**: the carpet's top edge
   per column, its straight stretches of ``min_edge_m`` or more as 2-point segments.
6. **Covariance** of every point: ``pixel_std_px`` on each image axis propagated through the
   ground projection by central differences
   (:func:`~perception.vision.field_pixels.ground_covariances`), plus ``floor_std_m`` and
   ``range_std_fraction`` of the range (camera sway the robot does not sense) on each axis.
   Junctions and circle centres take the covariance at their own pixel.

**Row offset.** PyBullet's tiny renderer draws the image one row higher than
:class:`~perception.types.CameraModel` says (pixel ``(i, j)`` centred at ``(i, j)``): every
ground point then comes out too far by a row's footprint on the ground (about 1 cm at 1 m,
5 cm at 3 m, 15 cm at 5 m, measured by ``benchmarks/field_feature_detection.py``).
``row_offset_px = 1`` moves the principal point up by a row and takes that out (line ends
within 5 mm, median); the default 0 is right for a camera that obeys the model.

Known limits: the goal's net stands on the carpet in front of its edge, so its foot is taken
for the edge there; a goal post is found only when ``min_post_height_m`` of it is in view
(more than a robot's height), or ``min_cut_post_height_m`` up to the image top (more than a
landmark pole's white base), so not when the image top cuts it lower, and a grey robot
side-on whose top is cut off can pass for one; lines beyond ``max_range_m`` are not used.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

import cv2
import numpy as np
from numpy.typing import NDArray

from perception.field.features import FEATURE_KINDS, FieldFeature
from perception.geometry import FloatArray
from perception.types import CameraModel, CameraState
from perception.validation import check_in_interval, check_int, check_positive, check_rgb_image
from perception.vision.colour_filter import HsvRange, check_hsv_range
from perception.vision.field_geometry import (
    Segment,
    curvature,
    find_circle,
    find_junctions,
    image_lines,
    merge_segments,
)
from perception.vision.field_pixels import (
    GroundProjection,
    blobs,
    carpet_top,
    cut_ends,
    ground_extent,
    horizon_rows,
    hsv_mask,
    line_runs,
    masked_median,
    post_feet,
    row_shifted,
    rows_from,
)

_OWNER = "FieldFeatureConfig"


@dataclass(frozen=True, kw_only=True)
class FieldFeatureConfig:
    """Colours, tolerances and noise model of :func:`detect_field_features` (module docstring).

    Field sizes default to the SPL rule book 2025 (ARCHITECTURE §7).
    """

    green_hsv: HsvRange = ((52, 80, 30), (72, 255, 255))  # carpet
    white_hsv: HsvRange = ((0, 0, 110), (179, 60, 255))  # lines, posts (net V ≈ 88 excluded)
    white_contrast: float = 0.12  # ... and V this fraction above the carpet's median V
    line_width_m: float = 0.05  # painted line width
    run_width_factor: float = 1.6  # runs up to this many line widths across (crossing ≤ ~50°)
    run_slack_px: float = 2.0  # ... plus this (px): pixels partly covered
    green_gap_px: int = 2  # green must lie this close (px) beyond both ends of a run
    horizon_margin_px: float = 3.0  # nothing above the horizon + this (px) is ground
    max_range_m: float = 6.0  # run middles beyond this range (m) are not used
    line_tol_px: float = 1.5  # a run middle this close (px) to an image line is on it
    min_line_points: int = 12  # fewer run middles make no line
    split_gap_px: float = 10.0  # a line is split where its middles leave a larger gap (px)
    split_gap_m: float = 0.25  # ... or a larger gap on the ground (m)
    hough_theta_step_deg: float = 1.0
    hough_rho_step_px: float = 2.0
    min_line_m: float = 0.35  # shorter segments are dropped (a circle piece is 0.15 m)
    min_curvature: float = 0.67  # segments bent more (1/m; half the circle's) ...
    curvature_sigmas: float = 3.0  # ... and by this many standard errors are circle pieces
    merge_angle_deg: float = 5.0  # segments within this angle ...
    merge_offset_m: float = 0.1  # ... and offset (m) of each other's line ...
    merge_gap_m: float = 0.5  # ... overlapping or this close (m) along it are one
    junction_angle_deg: float = 15.0  # segments within this of a right angle may meet
    junction_end_m: float = 0.2  # an intersection this close (m) to an end is at that end
    open_border_px: float = 3.0  # a segment's end this close (px) to the image side is cut
    circle_radius_m: float = 0.75  # centre circle radius (Ø 1.5 m)
    circle_radius_tol_m: float = 0.15  # free-radius fit must land within this (m)
    circle_tol_m: float = 0.06  # a point this close (m) to the circle is on it
    circle_cell_m: float = 0.05  # centre vote grid (m)
    circle_max_range_m: float = 4.5  # farther points are too coarse to tell an arc (m)
    min_circle_points: int = 25
    min_circle_arc_deg: float = 45.0  # the points must cover this arc about the centre
    centre_line_m: float = 0.15  # a segment this close (m) to the circle's centre crosses it
    mark_size_m: tuple[float, float] = (0.06, 0.2)  # penalty mark extent (0.1 m square)
    mark_elongation_slack_m: float = 0.025  # along the view no longer than across plus this
    # (and a pixel's footprint): the ball 0.5-0.7 m ahead is 0.05-0.09 m longer (its blob
    # taken as lying on the ground)
    mark_px: tuple[int, int] = (3, 2000)  # pixel count of a mark's component
    mark_green_fraction: float = 0.9  # of the ring around a mark
    mark_clearance_m: float = 0.3  # marks lie this far (m) from any line (1.3 m on the field)
    mark_max_range_m: float = 3.5  # farther, a mark is a pixel or two tall, like line debris
    post_diameter_m: float = 0.1  # goal post
    post_width_ratio: tuple[float, float] = (0.5, 1.8)  # of the post's expected width
    min_post_height_m: float = 0.65  # white at least this tall (a Nao: 0.57) ...
    min_cut_post_height_m: float = 0.45  # ... or this when cut by the image top (a pole's
    # white base: 0.4)
    post_side_white_max: float = 0.5  # columns beside a post at most this much white
    min_edge_m: float = 0.5  # shorter straight stretches of the carpet's edge are dropped
    edge_tol_px: float = 1.5  # edge points this close (px) to a line are on it
    edge_max_range_m: float = 12.0
    pixel_std_px: float = 1.0  # std of each image coordinate of a measured point
    row_offset_px: float = 0.0  # the image shows this many rows higher than the camera
    # model says (PyBullet's tiny renderer: 1.0, module docstring)
    floor_std_m: float = 0.01  # added to each axis's std (m)
    range_std_fraction: float = 0.01  # ... and this fraction of the range
    min_direction_std_rad: float = 0.01

    def __post_init__(self) -> None:
        check_hsv_range(_OWNER, "green_hsv", self.green_hsv)
        check_hsv_range(_OWNER, "white_hsv", self.white_hsv)
        for name in ("green_gap_px", "min_line_points", "min_circle_points"):
            check_int(_OWNER, name, getattr(self, name), 1)
        for item in fields(self):
            if item.type == "float" and item.name not in _OWN_RULES:
                zero = item.name in _NON_NEGATIVE
                check_positive(_OWNER, item.name, getattr(self, item.name), allow_zero=zero)
        check_in_interval(_OWNER, "row_offset_px", self.row_offset_px, -5.0, 5.0)
        for name in ("merge_angle_deg", "junction_angle_deg"):
            check_in_interval(_OWNER, name, getattr(self, name), 0.0, 45.0, high_inclusive=True)
        check_in_interval(_OWNER, "min_circle_arc_deg", self.min_circle_arc_deg, 0.0, 360.0)
        for name in ("mark_green_fraction", "post_side_white_max"):
            check_in_interval(_OWNER, name, getattr(self, name), 0.0, 1.0, high_inclusive=True)
        for name in ("mark_size_m", "post_width_ratio", "mark_px"):
            pair = getattr(self, name)
            if not (
                isinstance(pair, tuple)
                and len(pair) == 2
                and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in pair)
                and all(math.isfinite(v) for v in pair)
                and 0 < pair[0] < pair[1]
            ):
                raise ValueError(f"{_OWNER}.{name} must be (lo, hi) with 0 < lo < hi, got {pair!r}")


# FieldFeatureConfig's float fields that may be 0, and those with a rule of their own; the
# other float fields must be > 0
_NON_NEGATIVE = frozenset(
    {"white_contrast", "run_slack_px", "horizon_margin_px", "merge_gap_m", "floor_std_m"}
    | {"open_border_px", "range_std_fraction"}
)
_OWN_RULES = frozenset(
    {"row_offset_px", "merge_angle_deg", "junction_angle_deg", "min_circle_arc_deg"}
    | {"mark_green_fraction", "post_side_white_max"}
)


def detection_covariances(
    projection: GroundProjection, pixels: FloatArray, points: FloatArray, config: FieldFeatureConfig
) -> FloatArray:
    """(N, 2, 2) covariance the detector with ``config`` reports for the ground ``points``
    (N, 2) m seen at ``pixels`` (N, 2) px through ``projection`` (its row-shifted camera):
    ``pixel_std_px`` through the ground projection (at or beyond the horizon, the closed form at
    the image centre), plus ``floor_std_m + range_std_fraction * range`` on each axis (module
    docstring, step 6). The geometric camera mode's emulator reports the same."""
    cov = projection.covariances(pixels, config.pixel_std_px)
    distance = np.hypot(points[:, 0], points[:, 1])
    bad = ~np.isfinite(cov).all(axis=(1, 2))
    if bad.any():
        h = float(projection.position[2])
        std = (distance[bad] ** 2 + h**2) / (h * projection.fy) * config.pixel_std_px
        cov[bad] = std[:, None, None] ** 2 * np.eye(2)
    floor = (config.floor_std_m + config.range_std_fraction * distance) ** 2
    return np.asarray(cov + floor[:, None, None] * np.eye(2), dtype=np.float64)


class _Frame:
    """One image's masks and the camera, with the covariance model of ``config``."""

    def __init__(
        self,
        image: NDArray[np.uint8],
        camera: CameraModel,
        state: CameraState,
        config: FieldFeatureConfig,
    ) -> None:
        check_rgb_image(image, camera.height, camera.width)
        self.camera = row_shifted(camera, config.row_offset_px)
        self.state, self.config = state, config
        self.projection = GroundProjection(self.camera, state)
        hsv = np.asarray(cv2.cvtColor(image, cv2.COLOR_RGB2HSV), dtype=np.uint8)
        self.green = hsv_mask(hsv, config.green_hsv)
        (h_lo, s_lo, v_lo), white_hi = config.white_hsv
        if self.green.any():  # white must also stand out from this frame's carpet: V this high
            carpet_v = masked_median(hsv, 2, self.green)
            v_lo = max(v_lo, math.ceil((1.0 + config.white_contrast) * carpet_v))
        if v_lo <= white_hi[2]:
            self.white = hsv_mask(hsv, ((h_lo, s_lo, v_lo), white_hi))
        else:
            self.white = np.zeros_like(self.green)
        columns = np.arange(camera.width, dtype=np.float64)
        self.horizon = horizon_rows(self.projection, columns)
        self.below = rows_from(self.horizon + config.horizon_margin_px, camera.height)
        self.clear = self.green | self.white  # what may lie beyond a line's end
        self.white_below = self.white & self.below  # the line and mark candidates

    def covariances(self, pixels: FloatArray, points: FloatArray) -> FloatArray:
        """(N, 2, 2) covariance of the ground ``points`` (N, 2) m seen at ``pixels`` (N, 2)."""
        return detection_covariances(self.projection, pixels, points, self.config)

    def point_covariances(self, points: FloatArray) -> FloatArray:
        """:meth:`covariances` of ground ``points`` (N, 2) at their own (virtual) pixels."""
        return self.covariances(self.projection.pixels_of(points), points)

    def segments(
        self, pixels: FloatArray, ground: FloatArray, tol_px: float, min_m: float, max_m: float
    ) -> list[tuple[Segment, NDArray[np.intp]]]:
        """Ground segments of ``min_m`` or longer, within ``max_m``, from the collinear groups
        of the image points ``pixels`` (N, 2) (on the ground at ``ground`` (N, 2) m), with each
        group's indices."""
        cfg = self.config
        lines = image_lines(
            pixels,
            tol_px=tol_px,
            min_points=cfg.min_line_points,
            split_gap_px=cfg.split_gap_px,
            theta_step_rad=math.radians(cfg.hough_theta_step_deg),
            rho_step_px=cfg.hough_rho_step_px,
            ground=ground,
            split_gap_m=cfg.split_gap_m,
        )
        if not lines:
            return []
        ends_px = np.array([line.ends for line in lines])  # (L, 2, 2)
        ends, hit = self.projection.points(ends_px.reshape(-1, 2))
        ends = ends.reshape(-1, 2, 2)
        distance = np.hypot(ends[..., 0], ends[..., 1])  # (L, 2)
        length = np.hypot(*(ends[:, 1] - ends[:, 0]).T)
        ok = hit.reshape(-1, 2).all(axis=1) & (length >= min_m) & (distance.max(axis=1) <= max_m)
        if not ok.any():
            return []
        cut = cut_ends(ends_px[ok], self.clear, cfg.open_border_px) | (
            distance[ok] > cfg.max_range_m - cfg.junction_end_m
        )
        covs = self.covariances(ends_px[ok].reshape(-1, 2), ends[ok].reshape(-1, 2))
        return [
            (Segment(e, c, (bool(o[0]), bool(o[1]))), lines[k].indices)
            for k, e, c, o in zip(
                np.flatnonzero(ok), ends[ok], covs.reshape(-1, 2, 2, 2), cut, strict=True
            )
        ]


def _on_circle(segment: Segment, centre: FloatArray, radius: float, tol: float) -> bool:
    """Whether both ends and the middle of ``segment`` lie within ``tol`` of the circle."""
    points = np.vstack([segment.ends, segment.ends.mean(axis=0)])
    return bool((np.abs(np.hypot(*(points - centre).T) - radius) <= tol).all())


def detect_field_features(
    image: NDArray[np.uint8],
    camera: CameraModel,
    state: CameraState,
    config: FieldFeatureConfig | None = None,
) -> tuple[FieldFeature, ...]:
    """Field features in ``image`` (H, W, 3) uint8 RGB taken by ``camera`` from ``state``.

    Returns them in the robot frame (module docstring), in the order of
    :data:`~perception.field.features.FEATURE_KINDS`. Raises ``ValueError`` if ``image`` is
    not of the camera's size.
    """
    cfg = FieldFeatureConfig() if config is None else config
    frame = _Frame(image, camera, state, cfg)
    runs = line_runs(
        frame.white_below,
        frame.green,
        frame.projection,
        line_width_m=cfg.line_width_m,
        width_factor=cfg.run_width_factor,
        slack_px=cfg.run_slack_px,
        green_gap_px=cfg.green_gap_px,
        max_range_m=cfg.max_range_m,
    )
    found = frame.segments(runs.pixels, runs.ground, cfg.line_tol_px, 0.0, math.inf)
    pool = np.ones(len(runs.pixels), dtype=bool)  # leftovers, short and bent pieces: circle?
    straight = []
    for segment, indices in found:
        kappa, std = curvature(runs.ground[indices])
        bent = abs(kappa) >= max(cfg.min_curvature, cfg.curvature_sigmas * std)
        pool[indices] = bent or segment.length < cfg.min_line_m
        if not bent:
            straight.append(segment)
    pool &= np.hypot(runs.ground[:, 0], runs.ground[:, 1]) <= cfg.circle_max_range_m
    circle = find_circle(
        runs.ground[pool],
        cfg.circle_radius_m,
        tol_m=cfg.circle_tol_m,
        radius_tol_m=cfg.circle_radius_tol_m,
        min_points=cfg.min_circle_points,
        min_arc_rad=math.radians(cfg.min_circle_arc_deg),
        cell_m=cfg.circle_cell_m,
    )
    if circle is not None:  # pieces of the circle's polygon taken for lines belong to it
        tol = 2 * cfg.circle_tol_m
        straight = [
            s for s in straight if not _on_circle(s, circle.centre, cfg.circle_radius_m, tol)
        ]
    segments = merge_segments(  # short pieces too: a T's bar cut short by the image side
        straight,
        angle_tol_rad=math.radians(cfg.merge_angle_deg),
        offset_tol_m=cfg.merge_offset_m,
        gap_tol_m=cfg.merge_gap_m,
    )
    segments = [s for s in segments if s.length >= cfg.min_line_m]
    features = [FieldFeature.trusted("line", s.ends, s.cov) for s in segments]
    carpet = frame.green | runs.mask  # the carpet with its painted lines
    features += _field_edges(frame, carpet)
    junctions = find_junctions(
        segments,
        angle_tol_rad=math.radians(cfg.junction_angle_deg),
        end_tol_m=cfg.junction_end_m,
        min_direction_std_rad=cfg.min_direction_std_rad,
    )
    if junctions:
        covs = frame.point_covariances(np.array([j.point for j in junctions]))
        features += [
            FieldFeature.trusted(j.kind, j.point[None], c[None], j.direction, j.direction_std)
            for j, c in zip(junctions, covs, strict=True)
        ]
    centre = None if circle is None else circle.centre
    if centre is not None:
        features += _circle_features(frame, centre, segments)
    features += _marks(frame, centre, segments)
    features += _posts(frame, carpet)
    order = {kind: k for k, kind in enumerate(FEATURE_KINDS)}
    return tuple(sorted(features, key=lambda f: order[f.kind]))


def _circle_features(
    frame: _Frame, centre: FloatArray, segments: list[Segment]
) -> list[FieldFeature]:
    """The centre circle at ``centre`` (2,) m and, when a segment passes through it (the
    halfway line), its direction and the two crossings seen as ``x_junction`` s."""
    cfg = frame.config
    cov = frame.point_covariances(centre[None])
    through = [
        s
        for s in segments
        if abs(float((centre - s.ends[0]) @ np.array([-s.direction[1], s.direction[0]])))
        <= cfg.centre_line_m
    ]
    if not through:
        return [FieldFeature.trusted("centre_circle", centre[None], cov)]
    line = max(through, key=lambda s: s.length)
    d = line.direction
    angle = math.atan2(d[1], d[0]) % math.pi
    std = max(line.normal_std() * math.sqrt(2) / line.length, cfg.min_direction_std_rad)
    out = [FieldFeature.trusted("centre_circle", centre[None], cov, angle, std)]
    crossings = np.array([centre + sign * cfg.circle_radius_m * d for sign in (-1.0, 1.0)])
    along = (crossings - line.ends[0]) @ d
    seen = (along >= -cfg.junction_end_m) & (along <= line.length + cfg.junction_end_m)
    if seen.any():
        covs = frame.point_covariances(crossings[seen])
        out += [
            FieldFeature.trusted("x_junction", p[None], c[None], angle, std)
            for p, c in zip(crossings[seen], covs, strict=True)
        ]
    return out


def _marks(
    frame: _Frame, circle_centre: FloatArray | None, segments: list[Segment]
) -> list[FieldFeature]:
    """Penalty marks: small white blobs ringed by green, at least 2 px each way, within
    ``mark_max_range_m``, whose ground extent along and across the view (pixel centres' spread
    plus one pixel's footprint) is within ``mark_size_m`` and no longer along than across by
    more than a footprint and ``mark_elongation_slack_m``; not at the circle's centre (the
    centre mark) nor within ``mark_clearance_m`` of a line (a far line thinner than a pixel is
    drawn broken into such blobs)."""
    cfg, projection = frame.config, frame.projection
    out = []
    for blob in blobs(
        frame.white_below,
        frame.green,
        min_px=cfg.mark_px[0],
        max_px=cfg.mark_px[1],
        min_side_px=2,
        ring_px=2,
        green_fraction=cfg.mark_green_fraction,
    ):
        points, hit = projection.points(np.vstack([blob.centroid, blob.pixels]))
        if not hit.all():
            continue
        centre = points[0]
        if np.hypot(*centre) > cfg.mark_max_range_m:
            continue
        if circle_centre is not None and np.hypot(*(centre - circle_centre)) < cfg.mark_size_m[1]:
            continue
        if any(s.distance(centre) < cfg.mark_clearance_m for s in segments):
            continue
        extent, footprint = ground_extent(blob, points[1:], centre, projection)
        lo, hi = cfg.mark_size_m
        # a square is as long along the view as across it, however it is turned; a pixel's
        # footprint more at most, measured (the ball near the feet is longer: it stands up)
        square = extent[0] - extent[1] <= footprint[0] + cfg.mark_elongation_slack_m
        if (extent >= lo).all() and (extent <= hi).all() and square:
            cov = frame.covariances(blob.centroid[None], centre[None])
            out.append(FieldFeature.trusted("penalty_mark", centre[None], cov))
    return out


def _posts(frame: _Frame, carpet: NDArray[np.bool_]) -> list[FieldFeature]:
    """Goal posts: their feet (:func:`post_feet`, the ``carpet`` (H, W) mask with its lines)
    moved a radius along the view."""
    cfg, projection = frame.config, frame.projection
    feet = post_feet(
        frame.white,
        carpet,
        projection,
        diameter_m=cfg.post_diameter_m,
        width_ratio=cfg.post_width_ratio,
        min_height_m=(cfg.min_post_height_m, cfg.min_cut_post_height_m),
        side_white_max=cfg.post_side_white_max,
    )
    if not feet:
        return []
    pixels = np.array(feet)
    points, hit = projection.points(pixels)
    pixels, points = pixels[hit], points[hit]
    view = points - projection.position[:2]
    view /= np.maximum(np.hypot(view[:, 0], view[:, 1]), 1e-9)[:, None]
    centres = points + 0.5 * cfg.post_diameter_m * view
    keep = np.hypot(centres[:, 0], centres[:, 1]) <= cfg.max_range_m
    covs = frame.covariances(pixels[keep], centres[keep])
    return [
        FieldFeature.trusted("goal_post", p[None], c[None])
        for p, c in zip(centres[keep], covs, strict=True)
    ]


def _field_edges(frame: _Frame, carpet: NDArray[np.bool_]) -> list[FieldFeature]:
    """Straight stretches of the top edge of the ``carpet`` (H, W) mask (line pixels count as
    carpet) in the image, on the ground."""
    cfg = frame.config
    top = carpet_top(carpet & frame.below)
    columns = np.flatnonzero(np.isfinite(top))
    rows = top[columns]
    pixels = np.column_stack([columns, rows - 0.5]).astype(np.float64)  # the edge between rows
    pixels = pixels[pixels[:, 1] >= frame.horizon[columns] + cfg.horizon_margin_px]
    ground, hit = frame.projection.points(pixels)
    found = frame.segments(
        pixels[hit], ground[hit], cfg.edge_tol_px, cfg.min_edge_m, cfg.edge_max_range_m
    )
    merged = merge_segments(
        [s for s, _ in found],
        angle_tol_rad=math.radians(cfg.merge_angle_deg),
        offset_tol_m=cfg.merge_offset_m,
        gap_tol_m=cfg.merge_gap_m,
    )
    return [FieldFeature.trusted("field_edge", s.ends, s.cov) for s in merged]
