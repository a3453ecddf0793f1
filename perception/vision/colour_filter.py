"""Seed 000's colour-filter detector of the two-coloured landmark poles (§3.3).

A pole is a white base with two colour bands of equal height on top, one of them pink. Per frame
(an (H, W, 3) uint8 RGB image; while searching, pixel (column i, row j) covers
[i, i+1) x [j, j+1); measured centres are then moved by -0.5 px into the camera model's
coordinates, where pixel (i, j) is centred at (u, v) = (i, j) as PyBullet renders):

1. one HSV conversion and ``inRange`` masks (OpenCV HSV: H 0-179, S and V 0-255); the
   connected components of the pink mask are the pink segments. Those smaller than
   ``min_segment_area_px``, touching the image border (a clipped band's centre is biased) or
   without a band's proportions take no part;
2. partner search (seed §3.3.1 steps 1-4): from each pink segment's weighted centre probe at
   distance d = 1.2 x the longer of its centre-to-top and centre-to-bottom distances, straight
   down (270°), then up (90°), then at 270° ± α and 90° ± α for α = 2°, 4°, ... 60°; the first
   probe on a yellow, blue or green segment gives the partner. Unlike the seed, the partner
   colours are segmented inside the pole's *corridor* only: the strip along the image of the
   vertical through the pink centre, a little narrower than the pink. A band then stays apart
   from same-coloured clutter behind it (posters, jerseys), which would otherwise merge with it.
   Where a pink band has merged with pink clutter beside it into a misshapen segment, the search
   also starts from the yellow, blue and green segments around that segment, the other way
   round (their partner colour is pink, cut to their corridor);
3. base check (steps 5-6): the same probes from the lower segment's centre, downwards only, must
   meet white;
4. range and bearing (replacing seed eqs. 3.1/3.2, fitted to the Nao's 640 px images): the rays
   through the two band centres, in the robot frame, have elevations e_u and e_l; the band
   centres sit on one vertical axis at known heights z_u and z_l, so the horizontal distance to
   the pole's near surface is d = (z_u - z_l) / (tan e_u - tan e_l), with no need for the camera
   height. The pole axis lies a further π/4 · radius behind (the mean depth of a cylinder's
   visible surface across its silhouette) along the ray through the midpoint of the two centres;
5. plausibility: both segments are about as tall as their centre spacing and as each other,
   the segment the search started from about half as wide, the partner fills its corridor; the
   lower band centre appears where a pole at distance d would show it given the camera height
   (within ``elevation_tolerance_rad``, which covers the gait sway the robot does not sense);
   the range is finite, positive and within ``max_range_m``.

The (range, bearing) covariance propagates ``pixel_std_px`` on each centre coordinate through
step 4 to first order (central differences), with floors for what the pixels do not show.

Speed: one HSV conversion and one pink mask per frame; components are labelled only inside the
pink mask's bounding box, around misshapen pink segments and in the corridors of segments whose
probes met a partner colour; white is only tested at the probe pixels.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numpy as np
from numpy.typing import NDArray

from perception.geometry import FloatArray, pixel_rays, project_points, wrap_angle
from perception.types import (
    CameraModel,
    CameraState,
    LandmarkObservation,
    PoleCode,
    PoleGeometry,
    pole_ids_by_colours,
)
from perception.validation import (
    check_in_interval,
    check_int,
    check_positive,
    check_reals,
    check_rgb_image,
)

HsvRange = tuple[tuple[int, int, int], tuple[int, int, int]]
"""Inclusive ``((h, s, v) low, (h, s, v) high)`` bounds, OpenCV convention."""

PARTNER_COLOURS: tuple[str, ...] = ("yellow", "blue", "green")
_SEGMENT_COLOURS: tuple[str, ...] = ("pink", *PARTNER_COLOURS)
_HSV_MAX = (179, 255, 255)
_JACOBIAN_STEP_PX = 0.25  # central-difference step for the covariance
_UP_STEP = np.array([0.0, 0.0, 0.01])  # (m) along the vertical, to find its image direction
_OWNER = "ColourFilterConfig"  # names the fields in error messages


@dataclass(frozen=True, kw_only=True)
class ColourFilterConfig:
    """HSV masks, partner search, plausibility gates and noise model of :class:`ColourPoleDetector`.

    The HSV ranges are tuned on rendered frames under randomised lighting: the renderer keeps
    band hues within a few units of their paint (pink ≈ 164, yellow ≈ 26, blue ≈ 112, green
    ≈ 79), glare lowers saturation and clipped highlights shift pink down to ≈ 155. The hue
    ranges are tight because posters and jerseys carry similar colours: mauve poster paint sits
    at H ≈ 172, olive at 31-33, the blue jersey at 115-117, the carpet at 62; dark magenta poster
    stripes are kept out of pink by its value floor.
    """

    pink_hsv: HsvRange = ((155, 85, 90), (169, 255, 255))
    yellow_hsv: HsvRange = ((23, 130, 70), (30, 255, 255))
    blue_hsv: HsvRange = ((108, 110, 60), (114, 255, 255))
    green_hsv: HsvRange = ((75, 100, 60), (84, 255, 255))
    white_hsv: HsvRange = ((0, 0, 80), (179, 45, 255))
    min_segment_area_px: int = 6  # smaller segments are noise (a band 8 m away covers ~25 px)
    search_distance_factor: float = 1.2  # seed 000 §3.3.1 step 2: probe at this x extent
    alpha_step_deg: float = 2.0  # seed 000 §3.3.1 step 4
    alpha_max_deg: float = 60.0  # seed 000 §3.3.1 step 4
    band_height_ratio: tuple[float, float] = (0.75, 1.3)  # segment height / centre spacing (~1)
    max_height_mismatch: float = 1.2  # taller / shorter band segment (clutter stretches one)
    band_width_ratio: tuple[float, float] = (0.3, 0.75)  # pink mean width (area / height) / spacing
    max_box_width_ratio: float = 0.9  # pink bounding-box width / centre spacing (a band: ~0.5)
    corridor_width_ratio: float = 0.7  # partner corridor width / pink mean width
    min_corridor_fill: float = 0.7  # fraction of its corridor rows the partner band covers
    elevation_tolerance_rad: float = 0.05  # lower band centre vs camera height; gait sway ~0.035
    max_range_m: float = 8.0  # farther poles are a few pixels wide
    pixel_std_px: float = 0.3  # std of each coordinate of a segment centre
    range_std_floor_fraction: float = 0.01  # relative range std added (segmentation bias)
    bearing_std_floor_rad: float = 0.004  # bearing std added for gait sway the robot does not sense

    def __post_init__(self) -> None:
        for colour in (*_SEGMENT_COLOURS, "white"):
            check_hsv_range("ColourFilterConfig", f"{colour}_hsv", self.hsv_range(colour))
        check_int(_OWNER, "min_segment_area_px", self.min_segment_area_px, 1)
        for name in ("search_distance_factor", "max_height_mismatch"):
            check_in_interval(_OWNER, name, getattr(self, name), 1.0, math.inf)
        check_positive(_OWNER, "alpha_step_deg", self.alpha_step_deg)
        alpha_max = self.alpha_max_deg
        check_in_interval(_OWNER, "alpha_max_deg", alpha_max, 0.0, 90.0, low_inclusive=True)
        for name in ("band_height_ratio", "band_width_ratio"):
            check_reals(_OWNER, name, getattr(self, name), 2)
            lo, hi = getattr(self, name)
            if not 0.0 < lo < hi:
                raise ValueError(
                    f"ColourFilterConfig.{name} must be (lo, hi) with 0 < lo < hi, "
                    f"got {getattr(self, name)}"
                )
        fill = self.min_corridor_fill
        check_in_interval(
            _OWNER, "min_corridor_fill", fill, 0.0, 1.0, low_inclusive=True, high_inclusive=True
        )
        for name in (
            "max_box_width_ratio",
            "corridor_width_ratio",
            "elevation_tolerance_rad",
            "max_range_m",
            "pixel_std_px",
        ):
            check_positive(_OWNER, name, getattr(self, name))
        for name in ("range_std_floor_fraction", "bearing_std_floor_rad"):
            check_positive(_OWNER, name, getattr(self, name), allow_zero=True)

    def hsv_range(self, colour: str) -> HsvRange:
        """The HSV range of ``colour`` (pink, yellow, blue, green or white)."""
        value: HsvRange = getattr(self, f"{colour}_hsv")
        return value


def check_hsv_range(owner: str, name: str, value: HsvRange) -> None:
    """Raise ``ValueError`` naming ``owner.name`` unless ``value`` is a valid :data:`HsvRange`:
    two (h, s, v) tuples of ints (not bools), low <= high, within OpenCV's HSV bounds."""
    ok = (
        isinstance(value, tuple)
        and len(value) == 2
        and all(isinstance(b, tuple) and len(b) == 3 for b in value)
        and all(isinstance(x, int) and not isinstance(x, bool) for b in value for x in b)
        and all(0 <= lo <= hi <= top for lo, hi, top in zip(*value, _HSV_MAX, strict=True))
    )
    if not ok:
        raise ValueError(
            f"{owner}.{name} must be ((h, s, v), (h, s, v)) ints with "
            f"0 <= low <= high <= {_HSV_MAX}, got {value!r}"
        )


@dataclass(frozen=True)
class _Band:
    """One colour segment: colour name, weighted centre (2,) ``(u, v)`` px, box and area."""

    colour: str
    centre: FloatArray
    box: FloatArray  # (4,) u0, v0, u1, v1: pixel edges (px)
    area: int

    def reach(self, factor: float) -> float:
        """Seed step 2: ``factor`` x the longer centre-to-top / centre-to-bottom distance (px)."""
        v = self.centre[1]
        return factor * max(v - self.box[1], self.box[3] - v)


@dataclass(frozen=True)
class _Segments:
    """Connected components of one colour's mask inside a window of the image.

    ``origin`` is the window's top-left pixel ``(col, row)``; ``labels`` (h, w) int32 the
    window's component labels, 0 for pixels not of the colour; ``stats`` (K, 5) OpenCV
    ``(x, y, w, h, area)`` and ``centres`` (K, 2) weighted centres ``(u, v)`` px, both in image
    coordinates; ``usable`` (K,) the components big enough and clear of the window's edge (a
    clipped segment's centre is biased; component 0, the background, is not usable).
    """

    colour: str
    origin: NDArray[np.intp]
    labels: NDArray[np.int32]
    stats: NDArray[np.int32]
    centres: FloatArray
    usable: NDArray[np.bool_]

    def label_at(self, pixels: NDArray[np.intp]) -> NDArray[np.int32]:
        """Component labels (K,) at image pixels (K, 2) ``(col, row)``; outside: the edge's."""
        local = pixels - self.origin
        cols = np.clip(local[:, 0], 0, self.labels.shape[1] - 1)
        rows = np.clip(local[:, 1], 0, self.labels.shape[0] - 1)
        return self.labels[rows, cols]

    def band(self, k: int) -> _Band:
        """Segment ``k`` as a :class:`_Band`."""
        x, y, w, h, area = (int(s) for s in self.stats[k])
        return _Band(self.colour, self.centres[k], np.array([x, y, x + w, y + h], float), area)


class ColourPoleDetector:
    """Finds landmark poles by colour and measures their range and bearing (robot frame).

    ``camera`` gives the image size and intrinsics, ``codes`` the poles' colour codes (one id
    per (top, bottom) pair) and ``pole`` the band heights. See the module docstring for the
    method.
    """

    def __init__(
        self,
        config: ColourFilterConfig,
        camera: CameraModel,
        codes: Sequence[PoleCode],
        pole: PoleGeometry,
    ) -> None:
        self.config = config
        self.camera = camera
        self.pole = pole
        self._ids = pole_ids_by_colours(codes)
        self._bounds = {
            colour: tuple(np.array(b, dtype=np.uint8) for b in config.hsv_range(colour))
            for colour in _SEGMENT_COLOURS
        }
        self._partners = {  # partner colours of a seed colour, with their stacked HSV bounds
            colour: (partners, _stacked_bounds(config, partners))
            for colour, partners in (
                ("pink", PARTNER_COLOURS),
                *((c, ("pink",)) for c in PARTNER_COLOURS),
            )
        }
        self._white_bounds = _stacked_bounds(config, ("white",))
        self._partner_dirs = _probe_directions(config, both_ways=True)
        self._base_dirs = _probe_directions(config, both_ways=False)

    def detect(
        self,
        image: NDArray[np.uint8],
        camera_state: CameraState,
    ) -> list[LandmarkObservation]:
        """Landmark sightings in ``image`` (H, W, 3) uint8 RGB taken from ``camera_state``.

        At most one observation per landmark id: of duplicates, the one with the larger band
        area. Raises ``ValueError`` if ``image`` is not of the camera's size.
        """
        self._check_image(image)
        hsv = np.asarray(cv2.cvtColor(image, cv2.COLOR_RGB2HSV), dtype=np.uint8)
        pink_mask = np.asarray(cv2.inRange(hsv, *self._bounds["pink"]), dtype=np.uint8)
        x, y, w, h = cv2.boundingRect(pink_mask)
        if w == 0:
            return []
        # one pixel of margin: a segment then touches the window's edge only at the image border
        u0, v0, u1, v1 = self._clip((x - 1, y - 1, x + w + 1, y + h + 1))
        pink = self._segments(pink_mask[v0:v1, u0:u1], "pink", (u0, v0))
        rotation = camera_state.rotation()
        best: dict[int, tuple[int, LandmarkObservation]] = {}
        for seed in self._seeds(hsv, pink):
            pair = self._pair(seed, hsv, rotation)
            if pair is None:
                continue
            upper, lower, landmark_id = pair
            area = upper.area + lower.area
            if area <= best.get(landmark_id, (0, None))[0]:
                continue
            box = np.concatenate(
                [np.minimum(upper.box[:2], lower.box[:2]), np.maximum(upper.box[2:], lower.box[2:])]
            )
            # from search coordinates (pixel i spans [i, i+1)) to the camera model's (centred on i)
            observation = self.observe_band_centres(
                landmark_id, upper.centre - 0.5, lower.centre - 0.5, box - 0.5, camera_state
            )
            if observation is not None:
                best[landmark_id] = (area, observation)
        return [best[i][1] for i in sorted(best)]

    def _check_image(self, image: NDArray[np.uint8]) -> None:
        """Raise ``ValueError`` unless ``image`` is an (H, W, 3) uint8 array of the camera."""
        check_rgb_image(image, self.camera.height, self.camera.width)

    def _clip(self, window: tuple[float, float, float, float]) -> tuple[int, int, int, int]:
        """``window`` ``(u0, v0, u1, v1)`` px rounded outwards and clipped to the image."""
        return (
            max(math.floor(window[0]), 0),
            max(math.floor(window[1]), 0),
            min(math.ceil(window[2]), self.camera.width),
            min(math.ceil(window[3]), self.camera.height),
        )

    def _segments(self, mask: NDArray[np.uint8], colour: str, origin: tuple[int, int]) -> _Segments:
        """Components of a window's ``mask`` (h, w) whose top-left pixel is ``origin``."""
        _, labels, raw_stats, centroids = cv2.connectedComponentsWithStats(mask, connectivity=8)
        stats = np.asarray(raw_stats, dtype=np.int32)
        x, y, w, h, area = stats.T
        usable = (
            (area >= self.config.min_segment_area_px)
            & (x > 0)
            & (y > 0)
            & (x + w < mask.shape[1])
            & (y + h < mask.shape[0])
        )
        usable[0] = False
        stats[:, :2] += origin
        centres = np.asarray(centroids, dtype=np.float64) + np.add(origin, 0.5)
        return _Segments(
            colour,
            np.array(origin, dtype=np.intp),
            np.asarray(labels, dtype=np.int32),
            stats,
            centres,
            usable,
        )

    def _seeds(self, hsv: NDArray[np.uint8], pink: _Segments) -> list[_Band]:
        """The segments to start the partner search from.

        These are the usable pink segments with a band's proportions (the seed's method) and,
        for a pink band merged with pink clutter behind it into a misshapen segment, the usable
        partner-colour segments with a band's proportions in a window around that segment
        (1.5 segment heights above and below, half of one to the sides).
        """
        fit = pink.usable & self._band_proportioned(pink.stats)
        seeds = [pink.band(int(k)) for k in np.flatnonzero(fit)]
        misshapen = ~fit & (pink.stats[:, 4] >= 3 * self.config.min_segment_area_px)
        misshapen[0] = False
        partner_seeds: dict[tuple[str, tuple[float, ...]], _Band] = {}  # one per segment
        for k in np.flatnonzero(misshapen):
            x, y, w, h = pink.stats[k, :4].tolist()
            window = self._clip(
                (x - h / 2 - 2, y - 1.5 * h - 2, x + w + h / 2 + 2, y + 2.5 * h + 2)
            )
            for colour in PARTNER_COLOURS:
                for band in self._proportioned_segments(hsv, colour, window):
                    partner_seeds[(colour, tuple(band.box))] = band
        return seeds + list(partner_seeds.values())

    def _proportioned_segments(
        self,
        hsv: NDArray[np.uint8],
        colour: str,
        window: tuple[int, int, int, int],
    ) -> list[_Band]:
        """Usable segments of ``colour`` with a band's proportions inside ``window`` (px)."""
        u0, v0, u1, v1 = window
        mask = np.asarray(cv2.inRange(hsv[v0:v1, u0:u1], *self._bounds[colour]), np.uint8)
        if not mask.any():
            return []
        segments = self._segments(mask, colour, (u0, v0))
        fit = segments.usable & self._band_proportioned(segments.stats)
        return [segments.band(int(k)) for k in np.flatnonzero(fit)]

    def _band_proportioned(self, stats: NDArray[np.int32]) -> NDArray[np.bool_]:
        """Which segments (K, 5 OpenCV stats) can be a band of a pole within ``max_range_m``.

        Necessary conditions of :meth:`_band_shaped` and of the range gate, tested first to
        save partner searches: the bounds on height, mean width and box width per centre
        spacing bound the ratios of mean width and box width to height; and the spacing of a
        pole's band centres is at least ``fy * band height / range`` pixels (the image of a
        vertical gap only grows off the optical axis).
        """
        cfg = self.config
        _, _, w, h, area = stats.T.astype(np.float64)
        h_lo, h_hi = cfg.band_height_ratio
        w_lo, w_hi = cfg.band_width_ratio
        min_spacing = self.camera.fy * self.pole.band_height_m / cfg.max_range_m
        return (
            (area >= w_lo / h_hi * h * h)
            & (area <= w_hi / h_lo * h * h)
            & (w <= cfg.max_box_width_ratio / h_lo * h)
            & (h >= h_lo * min_spacing)
        )

    def _pair(
        self,
        seed: _Band,
        hsv: NDArray[np.uint8],
        rotation: FloatArray,
    ) -> tuple[_Band, _Band, int] | None:
        """Seed steps 3-6 from one segment: (upper band, lower band, landmark id) or None.

        ``rotation`` (3, 3) is the camera-to-robot rotation of the frame.
        """
        found = self._find_partner(seed, hsv, rotation)
        if found is None:
            return None
        partner, fill = found
        upper, lower = (seed, partner) if seed.centre[1] < partner.centre[1] else (partner, seed)
        landmark_id = self._ids.get((upper.colour, lower.colour))
        if (
            landmark_id is None
            or fill < self.config.min_corridor_fill
            or not self._band_shaped(seed, partner)
        ):
            return None
        points = self._probe_points(lower, self._base_dirs)
        if not _in_range(hsv, points, self._white_bounds).any():
            return None
        return upper, lower, landmark_id

    def _find_partner(
        self,
        seed: _Band,
        hsv: NDArray[np.uint8],
        rotation: FloatArray,
    ) -> tuple[_Band, float] | None:
        """The first usable segment of a partner colour met by the probes around ``seed``.

        Seed steps 3-4; the partner colours of pink are yellow, blue and green, theirs is pink.
        They are segmented only inside the pole's corridor through ``seed`` (see
        :meth:`_corridor`), and only those a probe lands on. Returns the segment and the
        fraction of the corridor it fills over its rows.
        """
        colours, bounds = self._partners[seed.colour]
        points = self._probe_points(seed, self._partner_dirs)
        hits = _in_range(hsv, points, bounds)  # (K, C)
        corridor = self._corridor(seed, rotation) if hits.any() else None
        if corridor is None:
            return None
        (u0, v0, u1, v1), inside = corridor
        found = np.zeros(hits.shape, dtype=np.int32)  # usable segment label per probe and colour
        segments: dict[str, _Segments] = {}
        for j in np.flatnonzero(hits.any(axis=0)):
            colour = colours[j]
            in_colour = cv2.inRange(hsv[v0:v1, u0:u1], *self._bounds[colour])
            mask = np.asarray(cv2.bitwise_and(in_colour, inside), dtype=np.uint8)
            segments[colour] = self._segments(mask, colour, (u0, v0))
            labels = segments[colour].label_at(points)
            found[:, j] = np.where(hits[:, j] & segments[colour].usable[labels], labels, 0)
        probes = np.flatnonzero(found.any(axis=1))
        if len(probes) == 0:
            return None
        first = int(np.argmax(found[probes[0]] > 0))
        partner = segments[colours[first]].band(int(found[probes[0], first]))
        rows = inside[int(partner.box[1]) - v0 : int(partner.box[3]) - v0]
        return partner, partner.area / max(int(np.count_nonzero(rows)), 1)

    def _corridor(
        self,
        seed: _Band,
        rotation: FloatArray,
    ) -> tuple[tuple[int, int, int, int], NDArray[np.uint8]] | None:
        """The image strip where the pole through band ``seed`` can show its other band.

        The strip follows the image of the vertical line through the seed's centre (a pole leans
        in the image when the camera pitches), is ``corridor_width_ratio`` x its mean width
        wide and has horizontal ends just beyond the farthest a partner passing
        :meth:`_band_shaped` can reach. Cutting the partner colour to this strip separates a
        band from same-coloured clutter behind it (posters).
        Returns the strip's window ``(u0, v0, u1, v1)`` px, clipped to the image and one column
        wider than the strip (so that a segment touches the window's edge only at the strip's
        ends or the image border), and the (v1 - v0, u1 - u0) uint8 mask of the strip in it;
        None if the vertical does not show as a line through the seed.
        """
        cam = self.camera
        ray = rotation @ pixel_rays(seed.centre, cam.fx, cam.fy, cam.cx, cam.cy)[0]
        above, _ = project_points(
            (rotation.T @ (ray + _UP_STEP))[None], cam.fx, cam.fy, cam.cx, cam.cy
        )
        du, dv = above[0] - seed.centre
        height = seed.box[3] - seed.box[1]
        if not dv < -1e-3 * height:  # NaN too: the vertical must point up in the image
            return None
        lo, hi = self.config.band_height_ratio
        half_length = (1.0 + 0.5 * hi) / lo * height + 1.0  # partner centre + half its height
        half_width = max(0.5 * self.config.corridor_width_ratio * seed.area / height, 1.0)
        shift = half_length * du / dv  # centre-line offset at the ends (px)
        uc, vc = seed.centre
        corners = np.array(
            [
                [uc - shift - half_width, vc - half_length],
                [uc - shift + half_width, vc - half_length],
                [uc + shift + half_width, vc + half_length],
                [uc + shift - half_width, vc + half_length],
            ]
        )
        u0, v0, u1, v1 = self._clip(
            (corners[:, 0].min() - 1, vc - half_length, corners[:, 0].max() + 1, vc + half_length)
        )
        inside = np.zeros((v1 - v0, u1 - u0), dtype=np.uint8)
        # fixed point with 4 fractional bits; OpenCV puts pixel centres on integers
        polygon = np.round((corners - (u0 + 0.5, v0 + 0.5)) * 16).astype(np.int32)
        cv2.fillConvexPoly(inside, polygon, 255, shift=4)
        return (u0, v0, u1, v1), inside

    def _probe_points(self, band: _Band, directions: FloatArray) -> NDArray[np.intp]:
        """Pixels (K, 2) ``(col, row)`` at the band's reach along (K, 2) unit ``directions``.

        Probes outside the image are moved onto the border pixels, where no usable segment is.
        """
        points = band.centre + band.reach(self.config.search_distance_factor) * directions
        cols = np.clip(np.floor(points[:, 0]), 0, self.camera.width - 1)
        rows = np.clip(np.floor(points[:, 1]), 0, self.camera.height - 1)
        return np.column_stack([cols, rows]).astype(np.intp)

    def _band_shaped(self, seed: _Band, partner: _Band) -> bool:
        """Whether the segments have a band's proportions, measured in their centre spacing.

        A band is as tall as the spacing and as the other band, and half as wide; the partner's
        width is that of the corridor it was cut to, so only the seed's width (mean: area /
        height, and of the box) is tested.
        """
        cfg = self.config
        spacing = float(np.linalg.norm(seed.centre - partner.centre))
        lo, hi = np.multiply(cfg.band_height_ratio, spacing)
        heights = [band.box[3] - band.box[1] for band in (seed, partner)]
        width_lo, width_hi = np.multiply(cfg.band_width_ratio, spacing)
        return (
            all(lo <= h <= hi for h in heights)
            and max(heights) <= cfg.max_height_mismatch * min(heights)
            and width_lo <= seed.area / heights[0] <= width_hi
            and seed.box[2] - seed.box[0] <= cfg.max_box_width_ratio * spacing
        )

    def observe_band_centres(
        self,
        landmark_id: int,
        upper: FloatArray,
        lower: FloatArray,
        box: FloatArray,
        state: CameraState,
    ) -> LandmarkObservation | None:
        """Range, bearing and covariance of a pole from its band centres, or None if implausible.

        ``upper`` and ``lower`` are the (2,) ``(u, v)`` pixel centres of the upper and lower
        colour band, ``box`` the (4,) pixel box of both; ``state`` is the camera as the joints
        report it. This is the measurement model shared with the geometric camera mode.
        """
        cfg = self.config
        q = np.concatenate([upper, lower])
        steps = _JACOBIAN_STEP_PX * np.eye(4)
        samples = np.vstack([q, q + steps, q - steps])  # (9, 4)
        axis, residual = self._locate(samples[:, :2], samples[:, 2:], state)
        rng = np.hypot(axis[:, 0], axis[:, 1])
        bearing = np.arctan2(axis[:, 1], axis[:, 0])
        plausible = abs(residual[0]) <= cfg.elevation_tolerance_rad
        if not (plausible and 0.0 < rng[0] <= cfg.max_range_m):
            return None
        d_range = (rng[1:5] - rng[5:]) / (2 * _JACOBIAN_STEP_PX)
        d_bearing = wrap_angle(bearing[1:5] - bearing[5:]) / (2 * _JACOBIAN_STEP_PX)
        pixel_var = cfg.pixel_std_px**2
        var_range = pixel_var * np.sum(d_range**2) + (cfg.range_std_floor_fraction * rng[0]) ** 2
        var_bearing = pixel_var * np.sum(d_bearing**2) + cfg.bearing_std_floor_rad**2
        if not (np.isfinite(var_range) and np.isfinite(var_bearing)):
            return None
        return LandmarkObservation(
            landmark_id=landmark_id,
            range_m=float(rng[0]),
            bearing_rad=float(bearing[0]),
            cov=np.diag([var_range, var_bearing]),
            pixel=(upper + lower) / 2,
            box=np.asarray(box, dtype=np.float64),
        )

    def _locate(
        self,
        upper: FloatArray,
        lower: FloatArray,
        state: CameraState,
    ) -> tuple[FloatArray, FloatArray]:
        """Pole axis points (N, 2) in the robot frame (m) from band centres (N, 2) px each.

        Also returns (N,) elevation residuals (rad): the lower centre's ray elevation minus the
        elevation at which a pole at the measured distance would show it. Both are NaN where the
        upper ray is not above the lower one.
        """
        cam, pole = self.camera, self.pole
        n = len(upper)
        pixels = np.concatenate([upper, lower, (upper + lower) / 2])
        rays = pixel_rays(pixels, cam.fx, cam.fy, cam.cx, cam.cy) @ state.rotation().T
        horizontal = np.hypot(rays[:, 0], rays[:, 1])
        tan_up, tan_low = (rays[:n, 2] / horizontal[:n], rays[n : 2 * n, 2] / horizontal[n : 2 * n])
        dtan = tan_up - tan_low
        with np.errstate(divide="ignore", invalid="ignore"):
            surface = np.where(dtan > 0, (pole.upper_centre_m - pole.lower_centre_m) / dtan, np.nan)
        heading = rays[2 * n :, :2] / horizontal[2 * n :, None]
        axis = state.position[:2] + (surface + 0.25 * math.pi * pole.radius_m)[:, None] * heading
        residual = np.arctan(tan_low) - np.arctan2(pole.lower_centre_m - state.position[2], surface)
        return axis, residual


def _stacked_bounds(
    config: ColourFilterConfig,
    colours: tuple[str, ...],
) -> tuple[NDArray[np.uint8], NDArray[np.uint8]]:
    """Low and high HSV bounds (C, 3) of ``colours``."""
    ranges = [config.hsv_range(c) for c in colours]
    return (
        np.array([r[0] for r in ranges], dtype=np.uint8),
        np.array([r[1] for r in ranges], dtype=np.uint8),
    )


def _in_range(
    hsv: NDArray[np.uint8],
    points: NDArray[np.intp],
    bounds: tuple[NDArray[np.uint8], NDArray[np.uint8]],
) -> NDArray[np.bool_]:
    """(K, C) whether the pixels (K, 2) ``(col, row)`` of ``hsv`` lie in each of C ranges."""
    values = hsv[points[:, 1], points[:, 0]][:, None, :]
    return np.all((values >= bounds[0]) & (values <= bounds[1]), axis=2)


def _probe_directions(config: ColourFilterConfig, *, both_ways: bool) -> FloatArray:
    """Unit probe directions (K, 2) in image coordinates (u right, v down), in search order.

    Angles as in the seed (90° up, 270° down): 270°, [90°], then for α = step, 2 step, ... up to
    ``alpha_max_deg``: 270° - α, 270° + α, [90° - α, 90° + α]; bracketed ones with ``both_ways``.
    """
    bases = (270.0, 90.0) if both_ways else (270.0,)
    alphas = np.arange(config.alpha_step_deg, config.alpha_max_deg + 1e-9, config.alpha_step_deg)
    angles = list(bases)
    for alpha in alphas:
        for base in bases:
            angles += [base - alpha, base + alpha]
    theta = np.radians(angles)
    return np.column_stack([np.cos(theta), -np.sin(theta)])
