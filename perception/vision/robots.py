"""Robot detection from field-edge indents (seed 004 §6.2, Algorithm 2 without its sonar step).

Other robots stand on the green carpet and stick up above its far edge in the image (a Nao is
about as tall as the camera is high, so its top lies near the horizon while the carpet's edge
lies below it): each cuts an *indent* into the carpet's top edge, as in rUNSWift's detector.
Per frame (an (H, W, 3) uint8 RGB image; while searching, pixel (column i, row j) covers
[i, i+1) x [j, j+1); measured pixels are then moved by -0.5 px into the camera model's
coordinates, where pixel (i, j) is centred at (u, v) = (i, j)):

1. **Field boundary.** Every ``column_step_px`` columns, the carpet's top edge ``raw``: the
   row that best splits the column into non-carpet above and carpet below (the maximum over
   rows of the count of carpet minus non-carpet pixels below it, so that small clutter does not
   end the carpet). Carpet is ``green_hsv`` (its saturation floor lowered per column where a
   window's glare washes the carpet out, ``glare_saturation_ratio``), and white
   (``white_hsv``) in vertical runs no longer than ``line_thin_factor`` field lines across
   the view: a line lying on the carpet is carpet, a robot's grey legs are not. Rows more
   than ``horizon_margin_px`` above the horizon are never carpet. After a median over
   ``median_columns`` columns, the greatest convex minorant in image rows (the carpet is
   convex, so its top edge is a convex function of the column; this is its upper envelope) is
   the boundary ``smooth`` that bridges the indents. A hull vertex with little support among
   its neighbours (green clutter above the carpet, ``spike_*``) is dropped.
2. **Indents.** A column is indented where ``raw`` lies ``min_indent_px`` or more below
   ``smooth`` (gaps of fewer than ``gap_columns`` columns bridged); the rows between show what
   stands in front of the carpet's edge, ``raw`` is its bottom. A run of indented columns is
   split where the ground distance of its bottom jumps (``split_fraction``, ``split_min_m``:
   robots at different ranges overlapping, a robot before a goal's net) after filling notches
   narrower than ``notch_m`` (between the legs); a piece too narrow for a robot, or narrower
   than ``overhang_m`` beside a nearer piece (an arm), is merged back.
3. **Algorithm 2** per box, from the boundary down to the lowest bottom of its columns:
   *line 3*, shrink its bottom and sides while the bottom row or side column is at least
   ``shrink_green_fraction`` carpet; also cut off bottom rows no wider than
   ``line_across_factor`` field lines covering ``min_line_m`` of ground or more (a line
   running from under the feet towards the camera). The base is the bottom edge, centred on
   the non-carpet columns of the lowest ``base_band_m`` (the feet: vertical edges lean in a
   pitched camera, and the arms set the box's width), and :func:`ground_point` gives its
   range. A box wider than ``split_width_ratio`` robots holding several jerseys side by side
   is split between them. *Lines 6-7*, the team is that of the largest cluster of a team's
   jersey/waistband colour (``team_hsv``: blue team 0, red team 1) of ``min_waistband_px``
   pixels in vertical runs of ``team_min_height_m``, between the heights
   ``team_search_heights_m`` at that range, around the box as wide as a robot, not running on
   beyond its window (a poster). *Lines 8-11*, if the base lies within ``bottom_margin_px``
   of the image bottom (the feet may be cut off) and a team colour was found, the cluster's
   lower edge, the waistband's, ``waistband_bottom_m`` up on a standing robot, gives the range
   instead (:func:`height_point`). *Line 4*, at that range reject boxes narrower or wider
   than ``width_ratio`` times a ``robot_width_m`` wide robot (not the wide test for a robot
   cut off at the bottom without a waistband: it stands nearer than its base says), and boxes
   at the image's side narrower than ``side_min_ratio`` robots (a cut-off part). *Line 12*,
   reject boxes whose rows are narrower than ``min_width_m`` at that range (rows' widths: a
   leaning edge widens the box, not a row). Algorithm 2's "not tall enough" test is implied:
   an indent reaches from the carpet's edge down to its base, so a box is exactly as tall as
   the part of a robot there below the edge.

   Not in the seed, for this field's other things that cut indents: a landmark pole (every
   one carries a pink band; 0.1 m thick) is a box under ``pole_max_width_m`` with a pink
   cluster as wide, taller than wide, its lower edge ``pole_band_ratio`` band heights above
   the base (pixel ratios hold when the unsensed gait sway tilts the camera); a goal post (or
   a pole's white base) is a box narrower than ``post_max_width_m`` without a team colour.
   The goal's nets are too wide. Field lines lie flat: their runs are carpet.

The sonar confirmation (Algorithm 2 lines 14-17: a sighting without a team colour needs a
sonar return at its range) is not done here: sightings without a team are returned with
``team=None``. A sighting's range and bearing are of the robot's centre (``centre_offset_m``
behind its feet, ``waistband_offset_m`` behind its waistband's front, along the view); the
covariance propagates ``pixel_std_px`` through the ground (or waistband-height) projection
(:func:`range_bearing_cov`) with floors for the camera sway the robot does not sense, and
``cut_range_std_fraction`` of the range more when it was measured at the image bottom (an
upper bound). Ranges beyond ``max_range_m`` are dropped.

Measured by ``benchmarks/robot_detection.py`` (walking frames of ``SPL/ActiveVision-v0``).
Known limits: a ball or another object just in front of a robot's feet moves its base down
(ranged too near); robots side by side at one range without distinct jerseys merge (too
wide); a robot touching ours fills the image and is ranged at the image bottom.

Speed: one HSV conversion and one white and one carpet-hue mask of the whole image per frame;
the sampled columns, each candidate's box and its windows are views of them (copying a strided
strip of pixels costs more than converting the whole image).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray
from scipy.ndimage import grey_closing, median_filter

from perception.geometry import FloatArray, pixel_rays, project_points, ray_ground_intersection
from perception.types import CameraModel, CameraState, RobotSighting
from perception.validation import (
    check_in_interval,
    check_int,
    check_positive,
    check_reals,
    check_rgb_image,
)
from perception.vision.colour_filter import HsvRange, check_hsv_range
from perception.vision.field_pixels import (
    best_splits,
    hsv_mask,
    row_runs,
    rows_from,
    run_pixels,
    transposed,
)
from perception.vision.ground_point import ground_point, height_point, range_bearing_cov

"""Inclusive ``((h, s, v) low, (h, s, v) high)`` bounds, OpenCV convention (H 0-179)."""

_OWNER = "RobotDetectorConfig"  # names the fields in error messages
REJECTIONS = (
    "above_horizon",
    "too_narrow",
    "cut_at_side",
    "too_wide",
    "narrow_m",
    "pole",
    "post",
    "out_of_range",
)
"""Why :meth:`RobotDetector.candidates` rejected a box (``RobotCandidate.rejected``)."""


@dataclass(frozen=True, kw_only=True)
class RobotDetectorConfig:
    """Colours, scan, size gates and noise model of :class:`RobotDetector`.

    Colours are tuned on rendered frames: the carpet sits at H ≈ 62 (S ≈ 173; S down to ≈ 75
    in a window's glare, where greyish-green poster paint at S 60-80 would pass) and keeps
    within a few hue units under randomised lighting. The blue jersey and waistband sit at
    H 114-119 (98 % of their pixels; the landmark poles' blue band at 108-114), the red ones at
    H 0-2 and 179 (the poles' pink at 164, mauve poster paint at 172).
    """

    green_hsv: HsvRange = ((52, 80, 30), (72, 255, 255))
    glare_saturation_ratio: float = 0.6  # under glare, carpet down to this of its median S ...
    min_green_saturation: int = 40  # ... but no less than this
    min_glare_samples: int = 10  # carpet-hued pixels in a column's lower third to judge glare
    white_hsv: HsvRange = ((0, 0, 90), (179, 60, 255))  # field lines (and robots' grey)
    line_width_m: float = 0.05  # field line width
    line_thin_factor: float = 2.0  # white runs up to this many line widths are carpet
    line_across_factor: float = 1.5  # a box's bottom rows no wider than this many lines ...
    min_line_m: float = 0.15  # ... covering this much ground (m) or more are a field line
    column_step_px: int = 2  # scan every this many columns
    horizon_margin_px: float = 12.0  # no carpet above horizon - this (unsensed gait sway)
    median_columns: int = 5  # median of the raw boundary over this many sampled columns (odd)
    spike_columns: int = 10  # a hull vertex with neighbours on this many columns each side ...
    spike_tolerance_px: float = 3.0  # ... fewer than spike_support of them this close to the
    spike_support: float = 0.3  # ... hull, is green clutter above the carpet: dropped
    min_indent_px: int = 3  # non-green rows below the boundary that make a column indented
    gap_columns: int = 3  # narrower gaps (sampled columns) between indented columns are bridged
    notch_m: float = 0.06  # narrower upward notches in an indent's bottom are filled (legs)
    split_fraction: float = 0.1  # split an indent where its bottom's distance jumps by this
    split_min_m: float = 0.15  # ... fraction of the nearer distance, and at least this (m)
    overhang_m: float = 0.11  # narrower pieces beside a nearer one are part of it (an arm)
    robot_width_m: float = 0.2  # a Nao's body width (legs 0.17 m, arms 0.27 m, side-on 0.11 m)
    split_width_ratio: float = 1.3  # wider boxes (robot widths) are split between their jerseys
    width_ratio: tuple[float, float] = (0.4, 2.2)  # box width / width of robot_width_m
    min_width_m: float = 0.08  # Algorithm 2 line 12: narrower boxes are not robots
    post_max_width_m: float = 0.13  # narrower boxes without a team colour are goal posts
    team_hsv: tuple[tuple[HsvRange, ...], tuple[HsvRange, ...]] = (
        (((115, 80, 30), (124, 255, 255)),),  # team 0: blue
        (((0, 80, 30), (8, 255, 255)), ((172, 80, 30), (179, 255, 255))),  # team 1: red
    )
    min_waistband_px: int = 8  # a smaller colour cluster sets no team
    team_search_heights_m: tuple[float, float] = (0.15, 0.55)  # rows searched for the colour
    team_search_margin: float = 0.5  # window widened by this fraction of the box width per side
    team_max_width: float = 1.5  # wider colour clusters (box widths) are not a robot's
    team_min_height_m: float = 0.06  # team colour in thinner vertical runs (up to 5 px) is not
    pole_hsv: tuple[HsvRange, ...] = (((150, 80, 60), (170, 255, 255)),)  # poles' pink
    pole_max_width_m: float = 0.16  # boxes this narrow or less are checked for a pole's band
    pole_search_m: float = 1.2  # pole pink is searched above the base up to this height
    pole_min_px: int = 6  # a pink band of this many pixels or more ...
    pole_band_ratio: tuple[float, float] = (1.4, 3.6)  # ... this many band heights up: a pole
    waistband_bottom_m: float = 0.26  # lower edge of the waistband on a standing robot
    shrink_green_fraction: float = 0.7  # Algorithm 2 line 3: "mostly green"
    bottom_margin_px: int = 2  # a base this close to the image bottom may be cut off
    side_margin_px: int = 2  # a box this close to the image's left or right side is cut off ...
    side_min_ratio: float = 0.8  # ... and rejected if narrower than this many robot widths
    base_band_m: float = 0.08  # the base is centred on the robot's lowest this much (its feet)
    centre_offset_m: float = 0.045  # robot centre behind the front of its feet
    waistband_offset_m: float = 0.055  # robot centre behind the front of its waistband
    max_range_m: float = 6.0  # farther indents are a few pixels wide (and mostly goal posts)
    pixel_std_px: float = 1.0  # std of each coordinate of the base (or waistband) pixel
    range_std_floor_fraction: float = 0.03  # relative range std added (sway, segmentation)
    bearing_std_floor_rad: float = 0.01  # bearing std added (sway the robot does not sense)
    cut_range_std_fraction: float = 0.5  # relative range std added when ranged at the bottom

    def __post_init__(self) -> None:
        check_hsv_range(_OWNER, "green_hsv", self.green_hsv)
        check_hsv_range(_OWNER, "white_hsv", self.white_hsv)
        if not (isinstance(self.pole_hsv, tuple) and self.pole_hsv):
            raise ValueError(f"{_OWNER}.pole_hsv must be a non-empty tuple of HSV ranges")
        for k, colour in enumerate(self.pole_hsv):
            check_hsv_range(_OWNER, f"pole_hsv[{k}]", colour)
        if not (isinstance(self.team_hsv, tuple) and len(self.team_hsv) == 2):
            raise ValueError(f"{_OWNER}.team_hsv must be a pair (team 0, team 1) of HSV ranges")
        for team, ranges in enumerate(self.team_hsv):
            if not (isinstance(ranges, tuple) and ranges):
                raise ValueError(f"{_OWNER}.team_hsv[{team}] must be a non-empty tuple of ranges")
            for k, value in enumerate(ranges):
                check_hsv_range(_OWNER, f"team_hsv[{team}][{k}]", value)
        check_int(_OWNER, "column_step_px", self.column_step_px, 1)
        check_int(_OWNER, "median_columns", self.median_columns, 1)
        check_int(_OWNER, "gap_columns", self.gap_columns, 1)
        check_int(_OWNER, "spike_columns", self.spike_columns, 0)
        check_int(_OWNER, "min_green_saturation", self.min_green_saturation, 0)
        if self.median_columns % 2 == 0:
            raise ValueError(f"{_OWNER}.median_columns must be odd, got {self.median_columns}")
        for name in ("min_indent_px", "min_waistband_px", "pole_min_px", "min_glare_samples"):
            check_int(_OWNER, name, getattr(self, name), 1)
        check_int(_OWNER, "bottom_margin_px", self.bottom_margin_px, 0)
        check_int(_OWNER, "side_margin_px", self.side_margin_px, 0)
        check_reals(_OWNER, "width_ratio", self.width_ratio, 2)
        lo, hi = self.width_ratio
        if not 0.0 < lo < hi:
            raise ValueError(
                f"{_OWNER}.width_ratio must be (lo, hi) with 0 < lo < hi, got {self.width_ratio}"
            )
        for name in (
            "shrink_green_fraction",
            "spike_support",
            "glare_saturation_ratio",
        ):
            check_in_interval(_OWNER, name, getattr(self, name), 0.0, 1.0, high_inclusive=True)
        for name in (
            "horizon_margin_px",
            "spike_tolerance_px",
            "split_fraction",
            "centre_offset_m",
            "waistband_offset_m",
            "range_std_floor_fraction",
            "bearing_std_floor_rad",
            "cut_range_std_fraction",
            "min_width_m",
            "side_min_ratio",
            "pole_max_width_m",
            "post_max_width_m",
            "team_search_margin",
            "team_min_height_m",
        ):
            check_positive(_OWNER, name, getattr(self, name), allow_zero=True)
        for name in (
            "notch_m",
            "base_band_m",
            "pole_search_m",
            "split_min_m",
            "split_width_ratio",
            "overhang_m",
            "line_width_m",
            "line_thin_factor",
            "line_across_factor",
            "min_line_m",
            "robot_width_m",
            "waistband_bottom_m",
            "max_range_m",
            "pixel_std_px",
            "team_max_width",
        ):
            check_positive(_OWNER, name, getattr(self, name))
        for name in ("team_search_heights_m", "pole_band_ratio"):
            heights = getattr(self, name)
            if not (
                isinstance(heights, tuple)
                and len(heights) == 2
                and all(isinstance(x, (int, float)) and math.isfinite(x) for x in heights)
                and 0.0 <= heights[0] < heights[1]
            ):
                raise ValueError(
                    f"{_OWNER}.{name} must be (lo, hi) with 0 <= lo < hi, got {heights!r}"
                )
        if self.waistband_bottom_m >= self.team_search_heights_m[1]:
            raise ValueError(
                f"{_OWNER}.waistband_bottom_m must lie below team_search_heights_m[1], got "
                f"{self.waistband_bottom_m} >= {self.team_search_heights_m[1]}"
            )


@dataclass(frozen=True)
class FieldBoundary:
    """The carpet's top edge in one image, per sampled column.

    ``columns`` (C,) the sampled image columns; ``raw`` (C,) the row (px, search coordinates:
    the first carpet row) where the carpet starts going down each column, the image height
    where the column shows no carpet; ``smooth`` (C,) its upper envelope, the boundary the
    indents are measured from. A column is indented where ``raw`` lies below ``smooth``: the
    rows between are what stands in front of the carpet's edge, ``raw`` its bottom.
    ``line_limit`` (H,) is the longest vertical white run (px) ending at each image row that
    counts as a field line, i.e. as carpet; ``row_distance`` (H,) the ground distance (m) from
    the camera seen at each row (centre column; inf above the horizon); ``saturation_floor``
    (C,) the least saturation of carpet green in each sampled column (lower under glare).
    """

    columns: NDArray[np.intp]
    raw: FloatArray
    smooth: FloatArray
    line_limit: FloatArray
    row_distance: FloatArray
    saturation_floor: FloatArray


@dataclass(frozen=True)
class RobotCandidate:
    """One field-edge indent and what Algorithm 2 made of it.

    ``box`` (4,) ``(u0, v0, u1, v1)`` its pixel edges after shrinking (camera coordinates);
    ``base`` (2,) the pixel its range was measured at (the base or, for a cut-off robot, the
    waistband's lower edge); ``cut`` whether the base lies at the image bottom; ``team`` the
    waistband colour's team or None (None too for a box rejected by its width before the
    colour was searched); ``rejected`` the :data:`REJECTIONS` entry that dropped it
    or None; ``sighting`` the sighting when it was kept.
    """

    box: FloatArray
    base: FloatArray
    cut: bool
    team: int | None
    rejected: str | None
    sighting: RobotSighting | None


@dataclass(frozen=True)
class _Colours:
    """One image in HSV ``hsv`` (H, W, 3) uint8 and its ``white`` and carpet-``hued`` masks
    (H, W) (``white_hsv``; ``green_hsv`` at any saturation up to its ceiling), each made once
    per frame: the conversion and the masks are per pixel, so any window of them is that
    window's own."""

    hsv: NDArray[np.uint8]
    white: NDArray[np.bool_]
    hued: NDArray[np.bool_]


@dataclass(frozen=True)
class _Cluster:
    """A colour cluster: pixel count, pixel box ``(u0, v0, u1, v1)`` (search coordinates,
    exclusive ends) and the (2,) camera-coordinate point of its lower edge at its centre
    column."""

    area: int
    box: tuple[int, int, int, int]
    lower: FloatArray


class RobotDetector:
    """Finds other robots in a camera image as field-edge indents (seed 004 §6.2).

    ``camera`` gives the image size and intrinsics. See the module docstring for the method.
    """

    def __init__(self, config: RobotDetectorConfig, camera: CameraModel) -> None:
        self.config = config
        self.camera = camera
        step = config.column_step_px
        self._sampled = slice(step // 2, None, step)  # the sampled columns, as a slice ...
        self._columns = np.arange(camera.width, dtype=np.intp)[self._sampled]  # ... and array
        low, high = config.white_hsv
        self._white = (np.array(low, dtype=np.uint8), np.array(high, dtype=np.uint8))
        (h_lo, _, v_lo), (h_hi, s_hi, v_hi) = config.green_hsv  # any saturation up to s_hi
        self._green_hued = (
            np.array([h_lo, 0, v_lo], np.uint8),
            np.array([h_hi, s_hi, v_hi], np.uint8),
        )
        self._pole = [tuple(np.array(b, dtype=np.uint8) for b in r) for r in config.pole_hsv]
        self._teams = [
            [tuple(np.array(b, dtype=np.uint8) for b in r) for r in ranges]
            for ranges in config.team_hsv
        ]

    # ----- public API ---------------------------------------------------------------------
    def detect(self, image: NDArray[np.uint8], state: CameraState) -> list[RobotSighting]:
        """Robot sightings in ``image`` (H, W, 3) uint8 RGB taken from ``state``, left to right.

        Raises ``ValueError`` if ``image`` is not of the camera's size.
        """
        return [c.sighting for c in self.candidates(image, state) if c.sighting is not None]

    def candidates(self, image: NDArray[np.uint8], state: CameraState) -> list[RobotCandidate]:
        """Every indent of ``image`` with Algorithm 2's verdict (for inspection and tuning)."""
        colours = self._colours(image)
        boundary = self._boundary(colours, state)
        step, last = self.config.column_step_px, self.camera.width - 1
        out: list[RobotCandidate] = []
        for k0, k1 in self._groups(boundary, state):
            u0, u1 = k0 * step, min((k1 + 1) * step - 1, last)
            out += self._examine(colours, state, boundary, u0, u1)
        return out

    def field_boundary(self, image: NDArray[np.uint8], state: CameraState) -> FieldBoundary:
        """Step 1 and the scans of step 2: the carpet's top edge and each column's indent."""
        return self._boundary(self._colours(image), state)

    def _colours(self, image: NDArray[np.uint8]) -> _Colours:
        """The :class:`_Colours` of ``image`` (H, W, 3) uint8 RGB; ``ValueError`` if it is not
        of the camera's size."""
        self._check_image(image)
        hsv = np.asarray(cv2.cvtColor(image, cv2.COLOR_RGB2HSV), dtype=np.uint8)
        return _Colours(hsv, hsv_mask(hsv, self._white), hsv_mask(hsv, self._green_hued))

    def _boundary(self, colours: _Colours, state: CameraState) -> FieldBoundary:
        """:meth:`field_boundary` of the image of ``colours``."""
        cfg = self.config
        height = self.camera.height
        columns = self._columns
        sampled = colours.hsv[:, self._sampled]  # (H, C, 3), a view
        floor = self._saturation_floor(sampled)
        hued = colours.hued[:, self._sampled]
        green = _carpet_green(hued, sampled[..., 1], floor)  # (H, C)
        white = colours.white[:, self._sampled]
        line_limit, row_distance = self._line_limits(state)
        green |= white & _thin_runs(white, line_limit)  # field lines are carpet here
        green &= rows_from(self._horizon_rows(state, columns) - cfg.horizon_margin_px, height)
        best, score = best_splits(green)  # maximise (green - non-green) over the rows below
        raw = np.where(score > 0, best, height).astype(np.float64)
        if cfg.median_columns > 1 and len(raw) >= cfg.median_columns:
            filtered = median_filter(raw, size=cfg.median_columns, mode="nearest")
        else:
            filtered = raw
        return FieldBoundary(
            columns=columns,
            raw=raw,
            smooth=_lower_hull(
                filtered, cfg.spike_columns, cfg.spike_tolerance_px, cfg.spike_support
            ),
            line_limit=line_limit,
            row_distance=row_distance,
            saturation_floor=floor,
        )

    def _saturation_floor(self, hsv: NDArray[np.uint8]) -> FloatArray:
        """The least saturation (C,) of carpet green in each column of ``hsv`` (H, C, 3).

        ``green_hsv``'s, but lower where a window's glare washes the carpet out: at most
        ``glare_saturation_ratio`` of the median saturation of the carpet-hued pixels in the
        column's lower third (the carpet there, where there are ``min_glare_samples`` of
        them), down to ``min_green_saturation``.
        """
        cfg = self.config
        (h_lo, s_lo, v_lo), (h_hi, _, _) = cfg.green_hsv
        lower = hsv[2 * hsv.shape[0] // 3 :]
        hued = (lower[..., 0] >= h_lo) & (lower[..., 0] <= h_hi) & (lower[..., 2] >= v_lo)
        hued &= lower[..., 1] >= cfg.min_green_saturation
        count = hued.sum(axis=0)
        enough = count >= cfg.min_glare_samples
        median = np.full(hsv.shape[1], np.inf)
        if enough.any():  # each column's hued saturations first (255: none can sort after it)
            saturations = np.where(hued, lower[..., 1], np.uint8(255)).T[enough]  # (C', H') uint8
            ranked = np.sort(saturations, axis=1, kind="stable")  # a radix sort for uint8
            n, rows = count[enough], np.arange(int(enough.sum()))
            middle = ranked[rows, (n - 1) // 2].astype(np.float64) + ranked[rows, n // 2]
            median[enough] = middle / 2.0  # the middle one, or the mean of the middle two
        floor: FloatArray = np.clip(
            cfg.glare_saturation_ratio * median, cfg.min_green_saturation, s_lo
        )
        return floor

    # ----- steps --------------------------------------------------------------------------
    def _line_limits(self, state: CameraState) -> tuple[FloatArray, FloatArray]:
        """How long a vertical run of white (H,) (px) ending at each image row can be and still
        be a field line, and each row's ground distance (H,) (m) from the camera.

        A line ``line_width_m`` wide lying across the view spans ``line_width_m`` over the
        ground extent of one row; runs up to ``line_thin_factor`` times that, plus one pixel,
        are lines (measured along the centre column; rows above the horizon allow none). A
        robot's legs make much longer runs.
        """
        cfg, cam = self.config, self.camera
        edges = np.arange(2 * cam.height + 1, dtype=np.float64) / 2 - 0.5  # row edges, centres
        pixels = np.column_stack([np.full(len(edges), cam.cx), edges])
        rays = pixel_rays(pixels, cam.fx, cam.fy, cam.cx, cam.cy) @ state.rotation().T
        xy, hits = ray_ground_intersection(state.position, rays)
        distance = np.full(len(edges), np.inf)
        distance[hits] = np.hypot(*(xy[hits] - state.position[:2]).T)
        top, centre, bottom = distance[0:-1:2], distance[1::2], distance[2::2]
        finite = np.isfinite(top) & np.isfinite(bottom)
        extent = np.where(finite, top - np.where(finite, bottom, 0.0), np.inf)
        extent = np.where(extent > 0, extent, np.inf)
        along: FloatArray = cfg.line_thin_factor * cfg.line_width_m / extent + 1.0
        return along, centre

    def _check_image(self, image: NDArray[np.uint8]) -> None:
        """Raise ``ValueError`` unless ``image`` is an (H, W, 3) uint8 array of the camera."""
        check_rgb_image(image, self.camera.height, self.camera.width)

    def _horizon_rows(self, state: CameraState, columns: NDArray[np.intp]) -> FloatArray:
        """Row (C,) of the horizon at each column (the image height where it lies below).

        A ray through pixel (u, v) is horizontal where the robot-frame z of
        ``R (1, (cx - u)/fx, (cy - v)/fy)`` vanishes; rows below it look down.
        """
        cam = self.camera
        r = state.rotation()[2]
        if r[2] <= 1e-9:  # camera upside down or looking straight up/down: no clean horizon
            return np.zeros(len(columns))
        return np.asarray(
            cam.cy + cam.fy * (r[0] + r[1] * (cam.cx - columns) / cam.fx) / r[2], dtype=np.float64
        )

    def _groups(self, boundary: FieldBoundary, state: CameraState) -> list[tuple[int, int]]:
        """Regions ``(k0, k1)`` (inclusive sampled-column indices) of indented columns.

        Runs of indented columns closer than a leg gap are joined (:meth:`_bridge_notches`).
        A run of neighbouring indented columns is split where the ground distance of its
        bottom jumps (by more than ``split_fraction`` of the nearer distance, at least
        ``split_min_m``): robots at different ranges overlapping in the image, or a robot in
        front of a goal's net. Upward notches in the bottom narrower than ``notch_m`` at the
        run's nearest range (the gap between a robot's legs) are filled before. A piece too
        narrow for a robot at its own range (an arm, a sliver of an occluded robot) is
        merged back into its nearer neighbour.
        """
        cfg, cam = self.config, self.camera
        step = cfg.column_step_px
        # a gap of up to ``gap_columns - 1`` sampled columns (a far robot's crotch just below
        # the boundary, a field line behind it) does not split an indent
        closed = boundary.raw
        if cfg.gap_columns > 1 and len(closed) > cfg.gap_columns:
            closed = grey_closing(closed, size=cfg.gap_columns, mode="nearest")
        indented = closed - boundary.smooth >= cfg.min_indent_px
        edges = np.diff(np.concatenate([[0], indented.astype(np.int8), [0]]))
        rises, falls = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1
        raw = boundary.raw.astype(np.float64)
        raw_distance = self._bottom_distance(boundary.columns, raw, state)
        runs = self._bridge_notches(
            list(zip(rises.tolist(), falls.tolist(), strict=True)), raw_distance
        )
        groups: list[tuple[int, int]] = []
        for a, b in runs:
            columns = boundary.columns[a : b + 1]
            ends = raw[a : b + 1]
            nearest = float(np.min(raw_distance[a : b + 1]))
            width = math.ceil(cam.fx * cfg.notch_m / max(nearest, 0.1) / step) + 1
            if width >= 2 and len(ends) > 2:
                ends = grey_closing(ends, size=width, mode="nearest")
            distance = self._bottom_distance(columns, ends, state)
            near = np.minimum(distance[1:], distance[:-1])
            # a bottom above the horizon (inf) is a jump from any neighbour
            finite = np.isfinite(distance)
            step_m = np.where(
                finite[1:] & finite[:-1], np.diff(np.where(finite, distance, 0.0)), np.inf
            )
            jump = np.abs(step_m) > np.maximum(cfg.split_min_m, cfg.split_fraction * near)
            cuts = np.flatnonzero(jump)
            starts = np.concatenate([[0], cuts + 1])
            stops = np.concatenate([cuts, [len(ends) - 1]])
            pieces = [
                [int(s), int(t), float(np.min(distance[s : t + 1]))]
                for s, t in zip(starts, stops, strict=True)
            ]
            merged = True
            while merged and len(pieces) > 1:
                merged = False
                for i, (s, t, d) in enumerate(pieces):
                    neighbours = [j for j in (i - 1, i + 1) if 0 <= j < len(pieces)]
                    j = min(neighbours, key=lambda n: pieces[n][2])
                    if pieces[j][2] >= d:
                        continue
                    wide_px = (t - s + 1) * step
                    narrow = wide_px < cfg.width_ratio[0] * cam.fx * cfg.robot_width_m / max(d, 0.1)
                    overhang = wide_px < cam.fx * cfg.overhang_m / max(pieces[j][2], 0.1)
                    if not (narrow or overhang):
                        continue
                    lo, hi = min(i, j), max(i, j)
                    pieces[lo : hi + 1] = [[pieces[lo][0], pieces[hi][1], min(d, pieces[j][2])]]
                    merged = True
                    break
            groups += [(a + int(s), a + int(t)) for s, t, _ in pieces]
        return groups

    def _bridge_notches(
        self, runs: list[tuple[int, int]], bottom_distance: FloatArray
    ) -> list[tuple[int, int]]:
        """Runs ``(k0, k1)`` (inclusive sampled-column indices) of indented columns, neighbours
        joined where the gap between them is narrower than ``notch_m`` at the nearer run's
        nearest range (``bottom_distance`` (C,) m: each sampled column's boundary on the
        ground): a near robot's legs, whose crotch shows the boundary behind them (a goal's
        net) over more sampled columns than ``gap_columns`` bridges."""
        cfg, cam = self.config, self.camera
        joined: list[tuple[int, int]] = []
        nearest_m: list[float] = []
        for a, b in runs:
            near = float(np.min(bottom_distance[a : b + 1]))
            if joined:
                gap_px = (a - joined[-1][1] - 1) * cfg.column_step_px
                nearer = min(near, nearest_m[-1])
                if gap_px < cam.fx * cfg.notch_m / max(nearer, 0.1):
                    joined[-1] = (joined[-1][0], b)
                    nearest_m[-1] = nearer
                    continue
            joined.append((a, b))
            nearest_m.append(near)
        return joined

    def _bottom_distance(
        self, columns: NDArray[np.intp], ends: FloatArray, state: CameraState
    ) -> FloatArray:
        """Ground distance (C,) (m) from the robot origin of each column's indent bottom (the
        lower edge of row ``ends - 1``); inf where that edge lies above the horizon."""
        cam = self.camera
        pixels = np.column_stack([columns.astype(np.float64), ends - 0.5])
        rays = pixel_rays(pixels, cam.fx, cam.fy, cam.cx, cam.cy) @ state.rotation().T
        xy, hits = ray_ground_intersection(state.position, rays)
        return np.where(hits, np.hypot(xy[:, 0], xy[:, 1]), np.inf)

    def _examine(
        self,
        colours: _Colours,
        state: CameraState,
        boundary: FieldBoundary,
        u0: int,
        u1: int,
        split: bool = True,
    ) -> list[RobotCandidate]:
        """Algorithm 2 (lines 3-13, 18) on the indent over image columns ``u0..u1`` of the
        image of ``colours``.

        With ``split``, a box wider than ``split_width_ratio`` robots that holds several
        jerseys side by side is split between them and each part examined on its own.
        """
        cfg, cam = self.config, self.camera
        inside = (boundary.columns >= u0) & (boundary.columns <= u1)
        if not inside.any():
            inside = np.abs(boundary.columns - (u0 + u1) / 2) <= cfg.column_step_px
        v0 = max(math.floor(float(np.min(boundary.smooth[inside]))), 0)
        v1 = min(int(np.max(boundary.raw[inside])), cam.height) - 1
        if v1 < v0:
            return []
        # carpet: green, or white in runs no longer than a field line (computed from the image
        # top, so that runs through the boundary keep their length)
        window = np.s_[: v1 + 1, u0 : u1 + 1]
        white = colours.white[window]
        floor = np.interp(np.arange(u0, u1 + 1), boundary.columns, boundary.saturation_floor)
        green = _carpet_green(colours.hued[window], colours.hsv[window][..., 1], floor)
        green = (green | (white & _thin_runs(white, boundary.line_limit[: v1 + 1])))[v0:]
        # line 3: shrink the bottom and sides while mostly green
        top, bottom, left, right = 0, green.shape[0] - 1, 0, green.shape[1] - 1
        fraction = cfg.shrink_green_fraction
        bottom = _last_below(green.mean(axis=1), fraction, top, bottom)
        # not in the seed: a field line running from under the feet towards the camera is not
        # the robot: bottom rows no wider than ``line_across_factor`` line widths, covering
        # ``min_line_m`` of ground or more (a leg's tapering corner covers less)
        distance = boundary.row_distance[v0:]
        end = bottom
        while end > top:
            cols = np.flatnonzero(~green[end, left : right + 1])
            line_px = cfg.line_across_factor * cam.fx * cfg.line_width_m / distance[end] + 1.0
            if len(cols) and cols[-1] - cols[0] + 1 > line_px:
                break
            end -= 1
        near = distance[bottom]  # inf for a bottom row above the horizon: no ground, no line
        if math.isfinite(near) and distance[end] - near >= cfg.min_line_m:
            bottom = end
        column_green = green[top : bottom + 1].mean(axis=0)
        left = _first_below(column_green, fraction, left, right)
        right = _last_below(column_green, fraction, left, right)
        u0, u1, v1 = u0 + left, u0 + right, v0 + bottom
        box = np.array([u0, v0, u1 + 1, v1 + 1], dtype=np.float64) - 0.5
        cut = v1 >= cam.height - 1 - cfg.bottom_margin_px
        # the base: the bottom edge, centred on the feet, the rows of the lowest
        # ``base_band_m`` of a robot there (vertical edges lean in a pitched camera, so the
        # box's centre, set by the arms, is off the feet; an oblique robot's far foot stands
        # a little higher in the image)
        base = np.array([(u0 + u1) / 2.0, v1 + 0.5])  # camera coordinates
        near = ground_point(base, cam, state)
        reach = self._depth(state, *near) if near is not None else -1.0
        band = max(2, round(cam.fy * cfg.base_band_m / reach)) if reach > 0 else 2
        feet = ~green[max(bottom - band + 1, top) : bottom + 1, left : right + 1].all(axis=0)
        if feet.any():
            base[0] = u0 + float(np.flatnonzero(feet)[[0, -1]].mean())
        body = ~green[top : bottom + 1, left : right + 1]
        filled = body.any(axis=1)
        spans = (body.shape[1] - np.argmax(body[:, ::-1], axis=1) - np.argmax(body, axis=1))[filled]
        row_width_px = _upper_quartile(spans) if len(spans) else 0.0

        def reject(reason: str, team: int | None = None) -> list[RobotCandidate]:
            return [RobotCandidate(box, base, cut, team, reason, None)]

        at_base = ground_point(base, cam, state, beyond_m=cfg.centre_offset_m)
        depth = -1.0 if at_base is None else self._depth(state, *at_base)
        if at_base is None or depth <= 0:
            return reject("above_horizon")
        width_px = u1 - u0 + 1.0
        if split and width_px > cfg.split_width_ratio * cam.fx * cfg.robot_width_m / depth:
            parts = self._jersey_split(colours.hsv, state, at_base, (u0, u1), v1, cut, depth)
            if len(parts) > 1:
                return [
                    c
                    for a, b in parts
                    for c in self._examine(colours, state, boundary, a, b, split=False)
                ]
        if not cut:  # ranged at its base whatever the colours: its width is judged first
            too = self._width_rejection(width_px, depth, u0, u1, wide_test=True)
            if too is not None:
                return reject(too)
        # lines 6-7: the waistband's colour, searched where a standing robot shows its body
        waist = self._waistband(colours.hsv, state, at_base, (u0, u1), v1, cut, depth)
        team = None if waist is None else waist[0]
        pixel, height_m, beyond_m = base, 0.0, cfg.centre_offset_m
        range_m, bearing = at_base
        if waist is not None and cut:  # lines 8-9: the waistband, assuming the robot stands
            lower = waist[1].lower
            at_waist = height_point(
                lower, cfg.waistband_bottom_m, cam, state, beyond_m=cfg.waistband_offset_m
            )
            if at_waist is not None:
                pixel, height_m, beyond_m = lower, cfg.waistband_bottom_m, cfg.waistband_offset_m
                range_m, bearing = at_waist
                depth = self._depth(state, range_m, bearing)
        located = (range_m, bearing)

        def verdict(reason: str) -> list[RobotCandidate]:
            return [RobotCandidate(box, pixel, cut, team, reason, None)]

        if depth <= 0:
            return verdict("above_horizon")
        if cut:  # (a box not cut off passed these tests before its colour was searched)
            too = self._width_rejection(width_px, depth, u0, u1, wide_test=pixel is not base)
            if too is not None:
                return verdict(too)
        # line 12: too narrow in metres (rows' widths: a leaning edge widens the box, not a row)
        width_m = row_width_px * depth / cam.fx
        if width_m < cfg.min_width_m:
            return verdict("narrow_m")
        # not in the seed: every landmark pole (0.1 m thick) carries a pink band, no robot does
        if width_m < cfg.pole_max_width_m and self._pole_colour(
            colours.hsv, state, located, (u0, u1), v1
        ):
            return verdict("pole")
        # not in the seed: a narrow white column without a jersey is a goal post (or the
        # white base of a landmark pole)
        if team is None and width_m < cfg.post_max_width_m:
            return verdict("post")
        # a base or waistband at the image bottom may be cut off: its range is an upper bound
        bound = pixel[1] >= cam.height - 0.5 - cfg.bottom_margin_px
        cov = self._covariance(pixel, state, height_m, beyond_m, range_m, bound)
        if cov is None or not (0.0 < range_m <= cfg.max_range_m):
            return verdict("out_of_range")
        sighting = RobotSighting(
            range_m=float(range_m), bearing_rad=float(bearing), cov=cov, team=team, box=box
        )
        return [RobotCandidate(box, pixel, cut, team, None, sighting)]

    def _width_rejection(
        self, width_px: float, depth: float, u0: int, u1: int, wide_test: bool
    ) -> str | None:
        """Algorithm 2 line 4 for a box over columns ``u0..u1``, ``width_px`` wide, at
        ``depth`` (m, > 0): ``"too_narrow"``, ``"cut_at_side"`` (not in the seed: a robot cut by
        the image's side shows a part whose base and centre are not the robot's) or, with
        ``wide_test`` (not for a robot cut off at the bottom without a waistband: it stands
        nearer than its base says, so it may be wider), ``"too_wide"``; None when it passes."""
        cfg, cam = self.config, self.camera
        (lo, hi), robot_m = cfg.width_ratio, cfg.robot_width_m
        if width_px < lo * cam.fx * robot_m / depth:
            return "too_narrow"
        at_side = u0 <= cfg.side_margin_px or u1 >= cam.width - 1 - cfg.side_margin_px
        if at_side and width_px < cfg.side_min_ratio * cam.fx * robot_m / depth:
            return "cut_at_side"
        if wide_test and width_px > hi * cam.fx * robot_m / depth:
            return "too_wide"
        return None

    def _waistband(
        self,
        hsv: NDArray[np.uint8],
        state: CameraState,
        at_base: tuple[float, float],
        cols: tuple[int, int],
        bottom: int,
        cut: bool,
        depth: float,
    ) -> tuple[int, _Cluster] | None:
        """Team and cluster of the largest team-coloured cluster of a box.

        Searched between the heights ``team_search_heights_m`` above the base at ``at_base``
        (range, bearing), or above the whole box when its base is ``cut``, and around the
        box's columns ``cols`` as wide as a whole robot at the base's ``depth`` (the box may
        hold only part of one: split off an arm, cut by the image side). None if no cluster
        of ``min_waistband_px`` pixels counts (see :meth:`_cluster`).
        """
        cfg, cam = self.config, self.camera
        rows = self._team_rows(state, at_base, bottom, cut)
        size = max(cols[1] - cols[0] + 1.0, cam.fx * cfg.robot_width_m / depth)
        window = self._window(cols, cfg.team_search_margin * size + 2.0)
        inner = (math.floor(cols[0] - 0.25 * size), math.ceil(cols[1] + 0.25 * size))
        best: tuple[int, _Cluster] | None = None
        min_rows = min(max(round(cam.fy * cfg.team_min_height_m / depth), 1), 5)
        max_width = cfg.team_max_width * size
        for team, ranges in enumerate(self._teams):
            found = self._cluster(
                hsv, rows, window, ranges, cfg.min_waistband_px, max_width, inner, min_rows
            )
            if found is not None and (best is None or found.area > best[1].area):
                best = (team, found)
        return best

    def _jersey_split(
        self,
        hsv: NDArray[np.uint8],
        state: CameraState,
        at_base: tuple[float, float],
        cols: tuple[int, int],
        bottom: int,
        cut: bool,
        depth: float,
    ) -> list[tuple[int, int]]:
        """Column ranges (inclusive) of ``cols`` split midway between the jerseys side by side
        in it, or ``[cols]``.

        A jersey is a cluster of either team's colour between the heights
        ``team_search_heights_m`` at the base's range (the whole height above a cut-off base),
        of ``min_waistband_px`` pixels and a quarter to one and a half robot widths wide.
        """
        cfg, cam = self.config, self.camera
        r0, r1 = self._team_rows(state, at_base, bottom, cut)
        c0, c1 = cols
        if r1 < r0:
            return [cols]
        window = hsv[r0 : r1 + 1, c0 : c1 + 1]
        mask = np.zeros(window.shape[:2], dtype=np.uint8)
        for ranges in self._teams:
            for lo, hi in ranges:
                mask |= np.asarray(cv2.inRange(window, lo, hi), dtype=np.uint8)
        _, _, stats, _ = cv2.connectedComponentsWithStats(mask, connectivity=8)
        robot_px = cam.fx * cfg.robot_width_m / depth
        x, w, area = (stats[1:, i] for i in (cv2.CC_STAT_LEFT, cv2.CC_STAT_WIDTH, cv2.CC_STAT_AREA))
        ok = (area >= cfg.min_waistband_px) & (w >= 0.25 * robot_px) & (w <= 1.5 * robot_px)
        spans = sorted((int(a), int(a + b - 1)) for a, b in zip(x[ok], w[ok], strict=True))
        merged: list[list[int]] = []
        for a, b in spans:
            if merged and a <= merged[-1][1]:
                merged[-1][1] = max(merged[-1][1], b)
            else:
                merged.append([a, b])
        if len(merged) < 2:
            return [cols]
        cuts = [c0 + (merged[i][1] + merged[i + 1][0] + 1) // 2 for i in range(len(merged) - 1)]
        bounds = [c0, *cuts, c1 + 1]
        return [(bounds[i], bounds[i + 1] - 1) for i in range(len(bounds) - 1)]

    def _team_rows(
        self, state: CameraState, at_base: tuple[float, float], bottom: int, cut: bool
    ) -> tuple[int, int]:
        """The rows (inclusive) a team colour is searched in: between the heights
        ``team_search_heights_m`` above the base at ``at_base`` (range, bearing), or every row
        down to the box's ``bottom`` when its base is ``cut``."""
        if cut:
            return 0, bottom
        heights = self.config.team_search_heights_m
        high = self._row_at_height(state, *at_base, heights[1])
        low = self._row_at_height(state, *at_base, heights[0])
        return max(math.floor(high), 0), min(max(math.ceil(low), 0), bottom)

    def _pole_colour(
        self,
        hsv: NDArray[np.uint8],
        state: CameraState,
        at_base: tuple[float, float],
        cols: tuple[int, int],
        bottom: int,
    ) -> bool:
        """Whether a landmark pole's colour band stands on the box's base (row ``bottom``).

        That is a cluster of one of ``pole_hsv`` (the poles' pink: every pole has a pink band,
        no robot wears pink) of ``pole_min_px`` pixels above the base, up to the height
        ``pole_search_m`` at the base's range ``at_base`` (range, bearing), at least half and
        at most one and a half times as wide as the box's columns ``cols`` (a poster behind
        runs on beyond) and taller than wide, whose lower edge lies between
        ``pole_band_ratio`` band heights above the base (a band 0.2 m tall with its lower edge
        0.4 or 0.6 m up: 2 or 3; a band cut by the image top is taken as twice as tall as
        wide). Pixel ratios hold when the camera's pitch is off by the gait's sway; a far
        pole's band seen behind a robot is smaller and higher up.
        """
        cfg = self.config
        high = self._row_at_height(state, *at_base, cfg.pole_search_m)
        rows = (max(math.floor(high), 0), bottom)
        width = cols[1] - cols[0] + 1
        window = self._window(cols, width + 2.0)  # the band leans with the camera's roll
        lo, hi = cfg.pole_band_ratio
        for colour in self._pole:
            found = self._cluster(hsv, rows, window, [colour], cfg.pole_min_px, 1.5 * width, cols)
            if found is None:
                continue
            x0, y0, x1, y1 = found.box
            height = float(y1 - y0) if y0 > 0 else max(float(y1 - y0), 2.0 * (x1 - x0))
            if (
                x1 - x0 >= 0.5 * width
                and height >= x1 - x0
                and lo * height <= bottom + 1 - y1 <= hi * height
            ):
                return True
        return False

    def _window(self, cols: tuple[int, int], margin: float) -> tuple[int, int]:
        """Columns ``cols`` widened by ``margin`` px on each side, clipped to the image."""
        m = math.ceil(margin)
        return max(cols[0] - m, 0), min(cols[1] + m, self.camera.width - 1)

    def _cluster(
        self,
        hsv: NDArray[np.uint8],
        rows: tuple[int, int],
        cols: tuple[int, int],
        ranges: list[tuple[NDArray[np.uint8], ...]],
        min_px: int,
        max_width: float,
        inner: tuple[int, int],
        min_rows: int = 1,
    ) -> _Cluster | None:
        """The largest cluster of the colour ``ranges`` (HSV bounds) in the window of ``rows``
        and ``cols`` (inclusive pixel ranges) of the image whose HSV is ``hsv`` (H, W, 3).

        Only pixels in vertical runs of ``min_rows`` or more count (a thin stripe of a poster
        behind does not join a jersey to the rest of the poster). A cluster counts if it has
        ``min_px`` pixels, is at most ``max_width`` px wide, its centre column lies within the
        columns ``inner`` (the object's) and it does not touch the window's left or right side
        inside the image (colour that runs on beyond the object is a poster behind it). None
        if no cluster counts.
        """
        (r0, r1), (c0, c1) = rows, cols
        if r1 < r0 or c1 < c0:
            return None
        window = hsv[r0 : r1 + 1, c0 : c1 + 1]
        mask = np.zeros(window.shape[:2], dtype=np.uint8)
        for lo, hi in ranges:
            mask |= np.asarray(cv2.inRange(window, lo, hi), dtype=np.uint8)
        if min_rows > 1:
            kernel = np.ones((min_rows, 1), dtype=np.uint8)
            mask = np.asarray(cv2.morphologyEx(mask, cv2.MORPH_OPEN, kernel), dtype=np.uint8)
        if int(np.count_nonzero(mask)) < min_px:
            return None
        _, labels, stats, _ = cv2.connectedComponentsWithStats(mask, connectivity=8)
        x, w, area = (stats[:, i] for i in (cv2.CC_STAT_LEFT, cv2.CC_STAT_WIDTH, cv2.CC_STAT_AREA))
        mid = c0 + x + (w - 1) / 2
        ok = (area >= min_px) & (w <= max_width) & (mid >= inner[0]) & (mid <= inner[1])
        ok &= (x > 0) | (c0 == 0)
        ok &= (x + w < c1 - c0 + 1) | (c1 == self.camera.width - 1)
        ok[0] = False
        if not ok.any():
            return None
        k = int(np.argmax(np.where(ok, area, -1)))
        ys, xs = np.nonzero(labels == k)
        lowest = int(ys.max())
        centre = float(xs[ys >= lowest - 1].mean())
        box = (c0 + int(xs.min()), r0 + int(ys.min()), c0 + int(xs.max()) + 1, r0 + lowest + 1)
        return _Cluster(int(area[k]), box, np.array([c0 + centre, r0 + lowest + 0.5]))

    def _point(self, range_m: float, bearing: float, height_m: float) -> FloatArray:
        """Robot-frame point (3,) at ``range_m``, ``bearing`` and ``height_m``."""
        return np.array([range_m * math.cos(bearing), range_m * math.sin(bearing), height_m])

    def _depth(self, state: CameraState, range_m: float, bearing: float) -> float:
        """Distance (m) along the optical axis of the ground point at ``range_m``, ``bearing``."""
        offset = self._point(range_m, bearing, 0.0) - state.position
        return float(state.rotation()[:, 0] @ offset)

    def _row_at_height(
        self, state: CameraState, range_m: float, bearing: float, height_m: float
    ) -> float:
        """Image row (camera coordinates) of the point ``height_m`` above the ground point, or
        -1 (above the image) when that point lies behind the camera (a camera looking steeply
        down at a near robot: the point is above its view)."""
        cam = self.camera
        offset = self._point(range_m, bearing, height_m) - state.position
        uv, front = project_points(offset @ state.rotation(), cam.fx, cam.fy, cam.cx, cam.cy)
        return float(uv[0, 1]) if front[0] else -1.0

    def _covariance(
        self,
        pixel: FloatArray,
        state: CameraState,
        height_m: float,
        beyond_m: float,
        range_m: float,
        bound: bool,
    ) -> FloatArray | None:
        """(2, 2) covariance of (range, bearing) from ``pixel_std_px`` plus the floors; with
        ``bound`` (the range is only an upper bound) ``cut_range_std_fraction`` of the range
        is added to the range std."""
        cfg = self.config
        cov = range_bearing_cov(
            pixel, self.camera, state, cfg.pixel_std_px, height_m=height_m, beyond_m=beyond_m
        )
        if cov is None:
            return None
        floor = cfg.range_std_floor_fraction + (cfg.cut_range_std_fraction if bound else 0.0)
        floors = np.diag([(floor * range_m) ** 2, cfg.bearing_std_floor_rad**2])
        total: FloatArray = cov + floors
        if not (np.isfinite(total).all() and total[0, 0] > 0 and np.linalg.det(total) > 0):
            return None
        return total


def _upper_quartile(values: NDArray[np.intp]) -> float:
    """``np.percentile(values, 75)`` of whole numbers (N,), N >= 1, without its overhead: the
    linear interpolation at 0.75 (N - 1) between the sorted values, exact for these."""
    ordered = np.sort(values)
    position = 0.75 * (len(ordered) - 1)
    low = int(position)
    high = min(low + 1, len(ordered) - 1)
    return float(ordered[low] + (ordered[high] - ordered[low]) * (position - low))


def _last_below(shares: FloatArray, fraction: float, low: int, high: int) -> int:
    """The last index in ``low + 1 .. high`` whose share (of ``shares``) is below ``fraction``,
    or ``low``: where shrinking from ``high`` while the share reaches ``fraction`` stops."""
    below = np.flatnonzero(shares[low + 1 : high + 1] < fraction)
    return low + 1 + int(below[-1]) if below.size else low


def _first_below(shares: FloatArray, fraction: float, low: int, high: int) -> int:
    """The first index in ``low .. high - 1`` whose share is below ``fraction``, or ``high``:
    where shrinking from ``low`` while the share reaches ``fraction`` stops."""
    below = np.flatnonzero(shares[low:high] < fraction)
    return low + int(below[0]) if below.size else high


def _carpet_green(
    hued: NDArray[np.bool_], saturation: NDArray[np.uint8], floor: FloatArray
) -> NDArray[np.bool_]:
    """Carpet green (H, W): the ``hued`` pixels (H, W) (``green_hsv`` at any saturation up to
    its own ceiling) whose ``saturation`` (H, W) reaches the per-column floor ``floor`` (W,)."""
    least = np.ceil(floor).astype(np.uint8)  # whole saturations: s >= floor iff s >= this
    return hued & (saturation >= least[None, :])


def _thin_runs(white: NDArray[np.bool_], limit: FloatArray) -> NDArray[np.bool_]:
    """Which pixels of ``white`` (H, C) lie in a vertical run no longer than ``limit`` (H,)
    px at the run's bottom row."""
    width = white.shape[1]
    cols, tops, ends = row_runs(transposed(white))
    thin = (ends - tops) <= limit[ends - 1]
    out = np.zeros(white.size, dtype=bool)
    out[run_pixels(tops[thin] * width + cols[thin], width, (ends - tops)[thin])] = True
    return out.reshape(white.shape)


def _hull_vertices(values: FloatArray, indices: NDArray[np.intp]) -> NDArray[np.intp]:
    """Vertices (subset of ``indices``, increasing) of the greatest convex minorant of the
    points ``(indices, values[indices])``."""
    hull: list[int] = []
    vals = values.tolist()  # Python floats: the same arithmetic, without numpy scalars
    for k in indices.tolist():
        while len(hull) >= 2:
            a, b = hull[-2], hull[-1]
            # drop b when it lies on or above the chord a-k (not a vertex of the lower hull)
            if (vals[b] - vals[a]) * (k - a) >= (vals[k] - vals[a]) * (b - a):
                hull.pop()
            else:
                break
        hull.append(k)
    return np.array(hull, dtype=np.intp)


def _lower_hull(
    values: FloatArray, window: int = 0, tolerance: float = 0.0, support: float = 0.0
) -> FloatArray:
    """Greatest convex minorant of ``values`` (C,) over their indices, evaluated at each index.

    In image rows (growing downwards) this is the upper envelope of the carpet's top edge. A
    hull vertex fewer than ``support`` of whose ``window`` neighbours on each side lie within
    ``tolerance`` of the hull is a spike (green clutter above the carpet) and is dropped, and
    the hull recomputed, until none is left.
    """
    n = len(values)
    if n <= 2:
        return np.asarray(values, dtype=np.float64).copy()
    keep = np.ones(n, dtype=bool)
    while True:
        vertices = _hull_vertices(values, np.flatnonzero(keep))
        hull = np.interp(np.arange(n), vertices, values[vertices]).astype(np.float64)
        if window <= 0 or len(vertices) <= 2:
            return hull
        close = np.abs(values - hull) <= tolerance
        spikes = []
        for v in vertices[1:-1].tolist():
            lo, hi = max(v - window, 0), min(v + window + 1, n)
            if close[lo:hi].mean() < support:
                spikes.append(v)
        if not spikes:
            return hull
        keep[spikes] = False
