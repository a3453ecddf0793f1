"""Segmentation of a 2-D laser scan into runs of beams that see one object (seed 001).

A scan is what :class:`perception.sensor_models.LaserModel` describes: ``angles`` (N,) (rad,
strictly increasing; :meth:`~perception.sensor_models.LaserModel.beam_angles`) and ``ranges``
(N,) (m) from the scanner centre, NaN where a beam has no return. ``+inf`` (the ROS
convention) is read as no return too, and with a config's ``max_range_m`` so is any range at
or beyond it (for a sensor that reports its maximum range instead of NaN). Every other range
must be finite and > 0: seed 001's simulator wrote 0 for no return, and such a scan must be
converted (0 -> NaN) first; nothing is clipped or guessed here.

Two segmenters, one output (a list of :class:`Segment`, in scan order):

- :func:`segment_breakpoints`, §5.4.3: a breakpoint wherever the range jumps by more than a
  threshold between neighbouring beams. The seed takes the first derivative ``r'(phi)`` and
  calls its peaks (maxima and minima) breakpoints; its printed test
  ``|r'(phi)_i - r'(phi)_{i-1}| > Delta epsilon`` fires on both flanks of such a peak, one beam
  apart, so it is read here as the peak itself: ``|r'| = |r_{i+1} - r_i| / Delta phi``
  above a threshold, which for evenly spaced beams is a range jump above
  ``threshold * Delta phi``. The threshold is given as that jump (m), which does not depend on
  the beam spacing and compares directly with the range noise.
- :func:`segment_scale_space`, §4.3 (Witkin 1984; the hyperstack of Vincken et al. 1997, cut
  down to one dimension): ``r`` smoothed by Gaussians of growing scale, breakpoints that
  persist from the finest scale to the coarsest. It measures jumps against the local trend,
  so it keeps a wall seen at a grazing angle whole (the derivative test cuts it where its
  range grows by more than the threshold a beam), and it drops the two jumps around a single
  moderately outlying range (with the defaults, on a 3 m wall with seed 001's noise: all
  outliers of 0.3 m, 70 % of those of 0.4 m, few larger ones), which the derivative test takes for
  breakpoints. Its price is resolution: structures a few beams wide blend at coarse scales.
  An object of one or two beams may keep one of its two jumps and lose the other, and so
  join a neighbouring segment (the derivative test cuts it out and drops it), and an outlier
  within a few beams of a real jump of the same sign persists with it. On 300 random scenes
  (a wall, 2-5 columns, seed 001's laser and noise) the derivative test found every segment
  to within a beam in 290, this one in 280.

Both end a segment at every beam with no return (such a beam is never in a segment; the
"features composed just by zero" of §5.4.4) and drop segments of fewer than ``min_points``
beams (§5.4.4: short features come from wrong breakpoints and carry little information). The
first and last beams are not neighbours, also for a 360° scan: an object on the seam comes as
two segments.

The segments feed §5.4.4's line/circle classification: each carries its beam index range,
its angles and ranges (the polar ``r(phi)`` the circle model and EKF use) and its points in
the sensor frame (for :func:`perception.circles.lines.fit_line_tls` and the circle fits).
Frames: the sensor frame has its origin at the scanner centre and the robot frame's axes
(x along the heading, y to the left), so a beam at angle ``phi`` and range ``r`` is the point
``r (cos phi, sin phi)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from itertools import pairwise
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.ndimage import gaussian_filter1d

from perception.geometry import FloatArray
from perception.validation import InvalidTypeError, check_int, check_positive

_TRUNCATE = 4.0  # Gaussian kernels are cut at 4 standard deviations (scipy's default)


@dataclass(frozen=True, eq=False)
class Segment:
    """Beams ``start`` to ``stop - 1`` of a scan (``ranges[start:stop]``), all with a return.

    ``angles`` (n,) rad and ``ranges`` (n,) m are those beams' angles and ranges; ``points``
    (n, 2) m the same beams in the sensor frame, ``ranges * (cos angles, sin angles)``, in
    scan order (counter-clockwise seen from above). The arrays are read-only.
    """

    start: int
    stop: int
    angles: FloatArray
    ranges: FloatArray
    points: FloatArray

    def __len__(self) -> int:
        """The number of beams, ``stop - start``."""
        return self.stop - self.start


@dataclass(frozen=True, kw_only=True)
class BreakpointConfig:
    """Settings of :func:`segment_breakpoints` (§5.4.3).

    - ``jump_threshold_m``: a breakpoint lies between neighbouring beams whose ranges differ by
      more than this (m, > 0); the seed's threshold on ``|r'(phi)|`` times the beam spacing.
      Default 0.15 m: 5.3 standard deviations of the difference of two ranges with seed 001's
      0.02 m noise (std 0.028 m), so a 180-beam scan of a smooth surface is split by noise with
      a probability of about 2e-5, while a column 0.15 m or more in front of what lies behind
      it is cut out. A surface seen at a grazing angle also changes range fast: at range ``r``
      and incidence ``a`` (from the surface normal) by ``r tan(a)`` times the beam spacing per
      beam, beyond 0.15 m at 1° spacing once ``r tan(a) > 8.6 m`` (3 m and 71°, 6 m and
      55°); such a wall comes in pieces (:func:`segment_scale_space` keeps it whole). Objects
      at nearly the same range (the seed's plant close to a wall) are not separated.
    - ``min_points``: segments of fewer beams are dropped (int >= 2). Default 5: a line needs
      2 points and a circle 3; 5 leave residual degrees of freedom to classify them (§5.4.4).
    - ``max_range_m``: ranges at or beyond this are no return (m, > 0), or None (default)
      when no return reads NaN or inf only, as :class:`~perception.sensor_models.LaserModel`
      scans do.

    Bad fields raise ``ValueError`` (``InvalidTypeError`` for a wrong type) naming
    ``BreakpointConfig.<field>``.
    """

    jump_threshold_m: float = 0.15
    min_points: int = 5
    max_range_m: float | None = None

    def __post_init__(self) -> None:
        check_positive("BreakpointConfig", "jump_threshold_m", self.jump_threshold_m)
        _check_common("BreakpointConfig", self.min_points, self.max_range_m)


@dataclass(frozen=True, kw_only=True)
class ScaleSpaceConfig:
    """Settings of :func:`segment_scale_space` (§4.3).

    - ``scales_beams``: the standard deviations of the Gaussian smoothing, in beams
      (positive, strictly increasing, at least one). The smoothing runs along the beam index,
      so it assumes evenly spaced beams; in angle a scale is ``s * Delta phi``. Default
      (1, 2, 3): the finest scale finds jumps a beam apart; at the coarsest, 3 beams, a single
      outlying beam has lost most of its height, while jumps 5 beams apart (objects
      ``min_points`` wide) stay apart. With 4 beams the test scene's pole (2 beams, 7 beams
      from a column) loses an edge; every added scale is one more level a breakpoint must
      be found on, so intermediate scales cost more than they give.
    - ``jump_threshold_m``: the smallest jump (m, > 0) a breakpoint must show at every scale,
      measured against the local trend (:func:`segment_scale_space`); an ideal step of height
      ``h`` shows ``h`` at every scale. Default 0.15 m, as :class:`BreakpointConfig`: the
      smoothed noise of seed 001's laser stays well below it (at 1 beam its largest value
      over a 180-beam scan is about 0.09 m on average, and it falls with the scale).
    - ``min_points`` and ``max_range_m``: as in :class:`BreakpointConfig`.

    Bad fields raise ``ValueError`` (``InvalidTypeError`` for a wrong type) naming
    ``ScaleSpaceConfig.<field>``.
    """

    scales_beams: tuple[float, ...] = (1.0, 2.0, 3.0)
    jump_threshold_m: float = 0.15
    min_points: int = 5
    max_range_m: float | None = None

    def __post_init__(self) -> None:
        owner = "ScaleSpaceConfig"
        if not isinstance(self.scales_beams, tuple) or not self.scales_beams:
            raise InvalidTypeError(
                f"{owner}.scales_beams must be a non-empty tuple of scales (beams), "
                f"got {type(self.scales_beams).__name__} {self.scales_beams!r}"
            )
        for k, scale in enumerate(self.scales_beams):
            check_positive(owner, f"scales_beams[{k}]", scale)
        if any(b <= a for a, b in pairwise(self.scales_beams)):
            raise ValueError(
                f"{owner}.scales_beams must be strictly increasing, got {self.scales_beams!r}"
            )
        check_positive(owner, "jump_threshold_m", self.jump_threshold_m)
        _check_common(owner, self.min_points, self.max_range_m)


def segment_breakpoints(
    angles: ArrayLike, ranges: ArrayLike, config: BreakpointConfig | None = None
) -> list[Segment]:
    """Segments of the scan ``(angles, ranges)`` between range jumps (§5.4.3).

    Beams ``i`` and ``i + 1`` are in different segments when either has no return or
    ``|ranges[i + 1] - ranges[i]| > config.jump_threshold_m``. Segments of fewer than
    ``config.min_points`` beams are dropped. See the module docstring for the scan's form; bad
    input raises ``ValueError`` (``InvalidTypeError`` for a wrong type) naming the argument.
    """
    config = BreakpointConfig() if config is None else config
    if not isinstance(config, BreakpointConfig):
        raise InvalidTypeError(f"config must be a BreakpointConfig, got {type(config).__name__}")
    phi, r = _scan("segment_breakpoints", angles, ranges, config.max_range_m)
    with np.errstate(invalid="ignore"):  # NaN - NaN: the no-return cut covers those gaps
        jumps = np.abs(np.diff(r)) > config.jump_threshold_m
    return _segments(phi, r, jumps, config.min_points)


def segment_scale_space(
    angles: ArrayLike, ranges: ArrayLike, config: ScaleSpaceConfig | None = None
) -> list[Segment]:
    """Segments of the scan ``(angles, ranges)`` between breakpoints that persist across
    scales (§4.3).

    The scan is first cut at the beams with no return; each run of beams with a return is
    then treated alone, as the seed's four steps:

    1. Blurring: the run's ranges are smoothed by a Gaussian of each scale ``s`` in
       ``config.scales_beams``, giving ``L_s`` (``scipy.ndimage.gaussian_filter1d``; the run
       is extended past its ends by point reflection, which continues a straight trend).
       Across each gap ``i`` (between beams ``i`` and ``i + 1``) the smoothed jump is
       ``D_s(i) = L_s(i + 1) - L_s(i)``, and with ``k = ceil(2 s)`` the jump against the
       local trend is ``J_s(i) = D_s(i) - (D_s(i - k) + D_s(i + k)) / 2``: zero where ``r``
       is straight or evenly curved over the stretch (a wall at any incidence). Both are
       divided by their value at a unit step, so a step of height ``h`` shows ``h`` (m).
    2. Linking: at each scale the features are the local maxima of ``|D_s|`` (edges as the
       inflection points of ``L_s``, Witkin's) whose ``J_s``, in the direction of ``D_s``,
       reaches ``config.jump_threshold_m``. A feature's parent is the nearest feature at the
       next coarser scale within the same lobe of ``D`` there (the run of gaps around the
       feature's place where ``D`` keeps the feature's sign): as the scale grows an edge
       drifts, and two jumps of one sign a few beams apart merge into one, to which both
       link.
    3. Root labelling: the features of the coarsest scale are the roots.
    4. Downward projection: a feature of the finest scale whose chain of parents reaches a
       root is a breakpoint, placed on the largest raw jump ``r(i + 1) - r(i)`` of its sign
       within ``ceil(s)`` gaps of it (the finest scale ``s``; a Gaussian edge of an object
       narrower than ``2 s`` sits outside it). A feature whose chain breaks did not persist.
       Nor does one on a run's first or last gap: the point reflection mirrors ``D`` about
       the run's ends, where a steady growth of ``|D|`` (a wall turning away) would peak
       like a jump; a single beam at a run's end stays with its neighbours.

    Segments of fewer than ``config.min_points`` beams are dropped. See the module docstring
    for the scan's form; bad input raises ``ValueError`` (``InvalidTypeError`` for a wrong
    type) naming the argument.
    """
    config = ScaleSpaceConfig() if config is None else config
    if not isinstance(config, ScaleSpaceConfig):
        raise InvalidTypeError(f"config must be a ScaleSpaceConfig, got {type(config).__name__}")
    phi, r = _scan("segment_scale_space", angles, ranges, config.max_range_m)
    breaks = np.zeros(max(r.size - 1, 0), dtype=bool)
    for start, stop in _runs(~np.isnan(r)):
        if stop - start >= 2:
            breaks[start : stop - 1] = _persistent_breaks(r[start:stop], config)
    return _segments(phi, r, breaks, config.min_points)


def _check_common(owner: str, min_points: object, max_range_m: object) -> None:
    """Raise unless ``min_points`` is an int >= 2 and ``max_range_m`` None or > 0."""
    check_int(owner, "min_points", min_points, 2)
    if max_range_m is not None:
        check_positive(owner, "max_range_m", max_range_m)


def _scan(
    owner: str, angles: ArrayLike, ranges: ArrayLike, max_range_m: float | None
) -> tuple[FloatArray, FloatArray]:
    """The scan as new float64 arrays ``(angles, ranges)`` (N,), no return as NaN; raise unless
    it has the form the module docstring describes (errors name ``owner.angles`` and
    ``owner.ranges``)."""
    phi = _vector(f"{owner}.angles", angles)
    r = _vector(f"{owner}.ranges", ranges)
    if r.shape != phi.shape:
        raise ValueError(
            f"{owner}.ranges must have the shape of angles {phi.shape} (one range a beam), "
            f"got shape {r.shape}"
        )
    if not np.isfinite(phi).all():
        raise ValueError(f"{owner}.angles must be finite, got {phi}")
    if (np.diff(phi) <= 0.0).any():
        raise ValueError(f"{owner}.angles must be strictly increasing (scan order), got {phi}")
    bad = ~(np.isnan(r) | (r == np.inf) | ((r > 0.0) & (r < np.inf)))
    if bad.any():
        raise ValueError(
            f"{owner}.ranges must be > 0 (m), or NaN or inf for no return (convert a no-return "
            f"code such as seed 001's 0 to NaN first), got {r[bad]} at beams "
            f"{np.flatnonzero(bad)}"
        )
    no_return = r == np.inf
    if max_range_m is not None:
        no_return |= r >= max_range_m
    r[no_return] = np.nan
    return phi, r


def _vector(name: str, value: ArrayLike) -> FloatArray:
    """``value`` as a new 1-D float64 array; errors name the argument ``name``."""
    try:
        array = np.array(value, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise InvalidTypeError(
            f"{name} must be a 1-D array of numbers, got {type(value).__name__} {value!r}"
        ) from error
    if array.ndim != 1:
        raise ValueError(f"{name} must be a 1-D array (one value a beam), got shape {array.shape}")
    return array


def _runs(mask: NDArray[np.bool_]) -> list[tuple[int, int]]:
    """``(start, stop)`` of each maximal run of True in the 1-D ``mask``."""
    edges = np.diff(np.concatenate([[False], mask, [False]]).astype(np.int8))
    starts, stops = np.flatnonzero(edges == 1).tolist(), np.flatnonzero(edges == -1).tolist()
    return list(zip(starts, stops, strict=True))


def _segments(
    phi: FloatArray, r: FloatArray, breaks: NDArray[np.bool_], min_points: int
) -> list[Segment]:
    """The segments of at least ``min_points`` beams, each a run of beams with a return (not
    NaN in ``r``) holding no breakpoint (``breaks`` (N - 1,): True between beams i and i + 1)."""
    if r.size == 0:
        return []
    keep = ~np.isnan(r)
    joined = keep[:-1] & keep[1:] & ~breaks  # beams i and i + 1 in one segment
    bounds = np.flatnonzero(~joined) + 1
    starts = np.concatenate([[0], bounds]).tolist()
    stops = np.concatenate([bounds, [r.size]]).tolist()
    return [
        _segment(phi, r, start, stop)
        for start, stop in zip(starts, stops, strict=True)
        if stop - start >= min_points and keep[start]
    ]


def _segment(phi: FloatArray, r: FloatArray, start: int, stop: int) -> Segment:
    """The :class:`Segment` of beams ``start`` to ``stop - 1``, its arrays read-only."""
    angles, ranges = phi[start:stop].copy(), r[start:stop].copy()
    points = ranges[:, None] * np.column_stack([np.cos(angles), np.sin(angles)])
    for array in (angles, ranges, points):
        array.flags.writeable = False
    return Segment(start, stop, angles, ranges, points)


def _persistent_breaks(r: FloatArray, config: ScaleSpaceConfig) -> NDArray[np.bool_]:
    """Steps 1-4 of :func:`segment_scale_space` on one run of ranges ``r`` (n,) (n >= 2):
    True at the (n - 1,) gaps that hold a breakpoint persisting across all scales."""
    levels = [_level(r, s, config.jump_threshold_m) for s in config.scales_beams]
    raw = np.diff(r)
    reach = math.ceil(config.scales_beams[0])
    breaks = np.zeros(r.size - 1, dtype=bool)
    for gap in levels[0].features[(levels[0].features > 0) & (levels[0].features < r.size - 2)]:
        if _has_root(gap, levels):  # onto the largest raw jump of its sign next to it
            low = max(gap - reach, 0)
            breaks[low + np.argmax(levels[0].sign[gap] * raw[low : gap + reach + 1])] = True
    return breaks


def _has_root(gap: int, levels: list[_Level]) -> bool:
    """Whether the chain of parents of the finest-scale feature at ``gap`` reaches the
    coarsest scale: its parent is the nearest feature in its lobe at the next scale."""
    sign, position = levels[0].sign[gap], gap
    for level in levels[1:]:
        parents = level.features[level.lobe[level.features] == level.lobe[position]]
        if level.sign[position] != sign or parents.size == 0:
            return False
        position = parents[np.argmin(np.abs(parents - position))]
    return True


class _Level(NamedTuple):
    """One scale of the stack: per gap, the sign of ``D`` and the label of its lobe (the
    maximal run of gaps with that sign); the gaps of the features."""

    sign: FloatArray
    lobe: NDArray[np.intp]
    features: NDArray[np.intp]


def _level(r: FloatArray, scale: float, threshold: float) -> _Level:
    """The :class:`_Level` of ``r`` (n,) at ``scale`` (beams): features are the local maxima
    of ``|D|`` (the right end of a flat top) where the trend-free jump ``J`` reaches
    ``threshold`` in the direction of ``D``."""
    d, j = _jumps(r, scale)
    sign = np.sign(d)
    lobe = np.concatenate([[0], np.cumsum(sign[1:] != sign[:-1])])
    size = np.abs(d)
    left = np.concatenate([[-np.inf], size[:-1]])
    right = np.concatenate([size[1:], [-np.inf]])
    features = np.flatnonzero((size >= left) & (size > right) & (j * sign >= threshold))
    return _Level(sign, lobe, features)


def _jumps(r: FloatArray, scale: float) -> tuple[FloatArray, FloatArray]:
    """``D`` and ``J`` (n - 1,) (m) of ``r`` (n,) at ``scale`` (beams), each scaled so that an
    ideal step shows its height (step 1 of :func:`segment_scale_space`)."""
    step = np.repeat([0.0, 1.0], 2 * _reach(scale))  # flat well past the reach on both sides
    unit_d, unit_j = (a[step.size // 2 - 1] for a in _raw_jumps(step, scale))
    d, j = _raw_jumps(r, scale)
    return d / unit_d, j / unit_j


def _reach(scale: float) -> int:
    """Beams past a run's ends that the smoothing and the detrending at ``scale`` read."""
    return math.ceil(_TRUNCATE * scale) + math.ceil(2.0 * scale) + 1


def _raw_jumps(r: FloatArray, scale: float) -> tuple[FloatArray, FloatArray]:
    """``D(i)`` and ``D(i) - (D(i - k) + D(i + k)) / 2`` (n - 1,) of ``r`` (n,) smoothed at
    ``scale``, unscaled."""
    k, pad = math.ceil(2.0 * scale), _reach(scale)
    extended = np.pad(r, pad, mode="reflect", reflect_type="odd")
    smooth = gaussian_filter1d(extended, scale, mode="nearest", truncate=_TRUNCATE)
    d = np.diff(smooth)

    def at(offset: int) -> FloatArray:  # d at the gaps i + offset, i = 0 .. n - 2, of r
        return d[pad + offset : pad + offset + r.size - 1]

    return at(0), at(0) - 0.5 * (at(-k) + at(k))
