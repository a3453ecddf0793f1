"""Line-or-circle classification, segment fusion and final circle estimation (seed 001
§5.4.4-5.4.6).

- :func:`classify_segment` (§5.4.4): a segment is a ``"line"``, a ``"circle"`` or
  ``"other"``. Two rules, chosen by :attr:`ClassificationConfig.rule`:

  - ``"seed"``: the seed's threshold on the line fit's residual (its ``R_linear``) and its
    maximum radius. The seed does not say whether ``R_linear`` is a sum or a mean, nor what
    its threshold was (it quotes 0.05 for the wide column of its fig. 5.16, which it could not
    classify); here it is the RMS orthogonal residual of the total least squares line (m),
    which does not grow with the segment's length. Line if it is at most the threshold, else
    circle if the circle fit's radius is at most the maximum, else other.
  - ``"chi_square"``: with the known range noise ``sigma``, a model's sum of squared
    orthogonal residuals over ``sigma^2`` is chi-square with ``n - k`` degrees of freedom
    (``k`` = 2 parameters for a line, 3 for a circle). The line, the simpler and nested model
    (the limit ``R -> inf``), is kept unless its statistic exceeds the upper
    ``significance`` quantile; a rejected line is a circle if the circle passes the same test
    with ``n - 3`` degrees of freedom and its radius is at most the maximum, else other. The
    noise is along the ray, so a residual's orthogonal part is ``sigma cos(incidence)`` or
    less: the statistics are stochastically smaller than chi-square and a true model is
    rejected with probability at most ``significance``.

- :func:`fuse_circles` (§5.4.5): circle segments (points in one frame) whose fits are one
  object are merged and refitted together by :func:`~perception.circles.fits.geometric_fit`.
  The seed's test prints ``R_C1 + R_C2 <= sqrt((x1 - x2)^2 - (y1 - y2)^2)``: with a minus
  inside the root (a conversion error for a plus) and the inequality the wrong way round, as
  it would merge the circles that do *not* intersect while its text says separate objects do
  not intersect. ``"overlap"`` is that test corrected (centres closer than the sum of the
  radii); ``"mahalanobis"`` (default) compares the two fits' ``(xc, yc, R)`` with their KCR
  covariances, which also separates touching objects and adapts to short arcs.

- :func:`estimate_circle` (§5.4.6): the final fit to the points of one object, possibly from
  several poses (in one common frame, each with the position of the sensor that saw it). The
  seed splits the points into the convex and concave branches of its eq. 3.2 for its Kalman
  filter's measurement function; the orthogonal-distance fit in a common frame needs no
  branch label, so arcs seen from different sides simply fit one circle. The seed drops the
  points near the two tangents from the sensor "for stability"; here that is an option
  (:class:`EstimationConfig`), off by default since it made the radius bias worse where
  measured.

Points in metres, angles in radians; ``n`` the number of points of a segment.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Literal, TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.stats import chi2

from perception.circles.fits import (
    CircleFit,
    angles_around_centre,
    geometric_fit,
    kcr_covariance,
)
from perception.circles.lines import LineFit, fit_line_tls
from perception.circles.segmentation import Segment
from perception.geometry import FloatArray, wrap_angle
from perception.validation import (
    InvalidTypeError,
    check_choice,
    check_int,
    check_positive,
    check_probability,
    finite_points,
)

Rule = Literal["seed", "chi_square"]
RULES: tuple[Rule, ...] = ("seed", "chi_square")
Kind = Literal["line", "circle", "other"]
Gate = Literal["overlap", "mahalanobis"]
GATES: tuple[Gate, ...] = ("overlap", "mahalanobis")

_C = TypeVar("_C")
_CIRCLE_PARAMETERS = 3  # (xc, yc, R)
_LINE_PARAMETERS = 2  # (angle, distance)


@dataclass(frozen=True, kw_only=True)
class ClassificationConfig:
    """Settings of :func:`classify_segment` (module docstring for the two rules).

    - ``rule``: ``"seed"`` or ``"chi_square"`` (default).
    - ``sigma_m``: the range noise's standard deviation (m, > 0); default 0.02, seed 001's.
    - ``line_threshold_m``: the seed rule's ``R_linear``, on the line's RMS residual (m, > 0).
      Default 0.03 = 1.5 ``sigma``: the seed's 0.05 keeps small columns as lines (a column of
      R 0.1 m at 1 m leaves a line RMS near 0.03 m), while a straight wall of ``n >= 10``
      points exceeds 0.03 only if chi-square(n - 2) > 2.25 n, probability below 0.005. No
      threshold separates that small column from a wall at this noise and 1° beams: even the
      chi-square test rejects its line in only a quarter of noise draws.
    - ``significance``: the chi-square rule's level (in (0, 1)); default 0.001, so a true
      line or circle is misclassified at most once in a thousand segments.
    - ``max_radius_m``: no circle is larger (m, > 0); default 1.0, twice the largest column radius
      (0.5 m) the tests use. Both rules use it: large arcs are "other".
    - ``min_points``: fewer points are "other" without a fit (int >= 4: a circle test needs
      one degree of freedom); default 5, the segmenters' default.

    Bad fields raise ``ValueError`` (``InvalidTypeError`` for a wrong type) naming
    ``ClassificationConfig.<field>``.
    """

    rule: Rule = "chi_square"
    sigma_m: float = 0.02
    line_threshold_m: float = 0.03
    significance: float = 0.001
    max_radius_m: float = 1.0
    min_points: int = 5

    def __post_init__(self) -> None:
        owner = "ClassificationConfig"
        check_choice(owner, "rule", self.rule, RULES)
        check_positive(owner, "sigma_m", self.sigma_m)
        check_positive(owner, "line_threshold_m", self.line_threshold_m)
        check_probability(owner, "significance", self.significance)
        check_positive(owner, "max_radius_m", self.max_radius_m)
        check_int(owner, "min_points", self.min_points, _CIRCLE_PARAMETERS + 1)


@dataclass(frozen=True, eq=False)
class SegmentModel:
    """What :func:`classify_segment` made of a segment.

    ``kind`` ``"line"``, ``"circle"`` or ``"other"``; ``line`` and ``circle`` the fits (None
    when not computed: both for a segment shorter than ``min_points``, the circle for a kept
    line or when no circle fits); ``statistic`` the line's test statistic, the RMS residual
    (m) under the seed rule, ``SSE / sigma^2`` under the chi-square rule (NaN without a fit);
    ``points`` (n, 2) the segment's points (m).
    """

    kind: Kind
    line: LineFit | None
    circle: CircleFit | None
    statistic: float
    points: FloatArray


@dataclass(frozen=True, kw_only=True)
class FusionConfig:
    """Settings of :func:`fuse_circles`.

    - ``gate``: ``"mahalanobis"`` (default) or ``"overlap"`` (the seed's, module docstring).
    - ``sigma_m``: the noise (m, > 0) of the KCR covariances; default 0.02.
    - ``significance``: two fits are one object unless the squared Mahalanobis distance of
      their ``(xc, yc, R)`` exceeds the chi-square(3) quantile at this level (in (0, 1));
      default 0.001 (16.3).
    """

    gate: Gate = "mahalanobis"
    sigma_m: float = 0.02
    significance: float = 0.001

    def __post_init__(self) -> None:
        check_choice("FusionConfig", "gate", self.gate, GATES)
        check_positive("FusionConfig", "sigma_m", self.sigma_m)
        check_probability("FusionConfig", "significance", self.significance)


@dataclass(frozen=True, eq=False)
class FusedCircle:
    """One object: the ``fit`` to all its ``points`` (n, 2) (m) and the indices ``members``
    of the point sets of :func:`fuse_circles` that were merged into it."""

    fit: CircleFit
    points: FloatArray
    members: tuple[int, ...]


@dataclass(frozen=True, kw_only=True)
class EstimationConfig:
    """Settings of :func:`estimate_circle`.

    - ``tangent_margin_rad``: points whose bearing from their sensor lies within this of a
      tangent from the sensor to the first fit are dropped (rad, >= 0). Default 0, keep all:
      measured on seed 001's laser (1° beams, range noise 0.02 m, R 0.5 m at 1 m, 400 draws)
      the geometric fit's radius is biased by -12 mm with all points and by -20 mm with two
      beams dropped at each tangent, as the grazing points pin the arc's ends. The seed
      dropped them for its polar Kalman filter, whose Jacobian is infinite at the tangents;
      ``math.radians(2.0)`` (two beams) reproduces that.
    """

    tangent_margin_rad: float = 0.0

    def __post_init__(self) -> None:
        check_positive(
            "EstimationConfig", "tangent_margin_rad", self.tangent_margin_rad, allow_zero=True
        )


def classify_segment(segment: Segment, config: ClassificationConfig | None = None) -> SegmentModel:
    """The model (line, circle or other) of ``segment`` under ``config``'s rule (module
    docstring); ``InvalidTypeError`` unless ``segment`` is a Segment."""
    if not isinstance(segment, Segment):
        raise InvalidTypeError(
            f"classify_segment.segment must be a Segment, got {type(segment).__name__}"
        )
    config = _config(config, ClassificationConfig, "classify_segment")
    points = np.asarray(segment.points, dtype=np.float64)
    if len(points) < config.min_points:
        return SegmentModel("other", None, None, math.nan, points)
    line = fit_line_tls(points)
    statistic = _line_statistic(line, config)
    if _line_kept(statistic, len(points), config):
        return SegmentModel("line", line, None, statistic, points)
    circle = _circle_or_none(points)
    kind: Kind = (
        "circle" if circle is not None and _circle_kept(circle, len(points), config) else "other"
    )
    return SegmentModel(kind, line, circle, statistic, points)


def fuse_circles(
    point_sets: Sequence[ArrayLike], config: FusionConfig | None = None
) -> list[FusedCircle]:
    """Merge the point sets (each (n_i, 2), m, one common frame, n_i >= 3) of circle segments
    that see one object, and refit each object's points together with
    :func:`~perception.circles.fits.geometric_fit`.

    Pairs that pass ``config``'s gate are joined transitively (connected components), in the
    order of their first member.
    """
    config = _config(config, FusionConfig, "fuse_circles")
    sets = [
        finite_points(p, f"fuse_circles.point_sets[{i}]", _CIRCLE_PARAMETERS)
        for i, p in enumerate(point_sets)
    ]
    fits = [geometric_fit(p) for p in sets]
    covariances = [_kcr(p, fit, config.sigma_m) for p, fit in zip(sets, fits, strict=True)]
    threshold = float(chi2.isf(config.significance, _CIRCLE_PARAMETERS))
    groups = _components(
        len(sets), lambda i, j: _same_object(i, j, fits, covariances, config, threshold)
    )
    fused = []
    for members in groups:
        points = np.concatenate([sets[i] for i in members])
        fused.append(FusedCircle(geometric_fit(points), points, members))
    return fused


def estimate_circle(
    points: ArrayLike, origins: ArrayLike, config: EstimationConfig | None = None
) -> CircleFit:
    """The final circle (§5.4.6) of one object's ``points`` (N, 2) (m, one common frame).

    ``origins`` is the position of the sensor that saw each point, (N, 2), or one position
    (2,) for all. A first geometric fit gives each sensor's tangents to the circle; points
    within ``config.tangent_margin_rad`` of them are dropped and the rest refitted. ValueError
    if fewer than 3 points remain or a sensor lies inside the first circle (no tangents).
    """
    config = _config(config, EstimationConfig, "estimate_circle")
    p = finite_points(points, "estimate_circle.points", _CIRCLE_PARAMETERS)
    o = _origins(origins, len(p))
    first = geometric_fit(p)
    keep = _off_tangents(p, o, first, config.tangent_margin_rad)
    if keep.sum() < _CIRCLE_PARAMETERS:
        raise ValueError(
            f"estimate_circle: only {int(keep.sum())} of {len(p)} points lie more than "
            f"tangent_margin_rad={config.tangent_margin_rad!r} from the tangents, need 3"
        )
    return geometric_fit(p[keep], initial=first)


def _config(config: _C | None, kind: type[_C], owner: str) -> _C:
    """``config``, or the default ``kind()`` for None; InvalidTypeError for another type."""
    if config is None:
        return kind()
    if not isinstance(config, kind):
        raise InvalidTypeError(
            f"{owner}.config must be a {kind.__name__} or None, got {type(config).__name__}"
        )
    return config


def _line_statistic(line: LineFit, config: ClassificationConfig) -> float:
    """The line's RMS residual (seed rule) or ``SSE / sigma^2`` (chi-square rule)."""
    if config.rule == "seed":
        return line.rms_residual
    return line.sse / config.sigma_m**2


def _line_kept(statistic: float, n: int, config: ClassificationConfig) -> bool:
    """Whether the line's ``statistic`` (of ``n`` points) passes ``config``'s rule."""
    if config.rule == "seed":
        return statistic <= config.line_threshold_m
    return statistic <= chi2.isf(config.significance, n - _LINE_PARAMETERS)


def _circle_kept(circle: CircleFit, n: int, config: ClassificationConfig) -> bool:
    """Whether ``circle`` (of ``n`` points) is small enough and, under the chi-square rule,
    fits them: ``n rms^2 / sigma^2`` within the chi-square(n - 3) quantile."""
    radius = circle.R
    if radius > config.max_radius_m:
        return False
    if config.rule == "seed":
        return True
    statistic = n * circle.rms_residual**2 / config.sigma_m**2
    return bool(statistic <= chi2.isf(config.significance, n - _CIRCLE_PARAMETERS))


def _circle_or_none(points: FloatArray) -> CircleFit | None:
    """The geometric circle fit to ``points``, or None for (exactly) collinear points."""
    try:
        return geometric_fit(points)
    except ValueError:
        return None


def _origins(origins: ArrayLike, n: int) -> FloatArray:
    """``origins`` as a finite (n, 2) array, a single (2,) position repeated."""
    try:
        o = np.array(origins, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise InvalidTypeError(
            f"estimate_circle.origins must be (2,) or (N, 2) numbers, got {origins!r}"
        ) from error
    if o.shape == (2,):
        o = np.tile(o, (n, 1))
    if o.shape != (n, 2) or not np.isfinite(o).all():
        raise ValueError(
            f"estimate_circle.origins must be finite with shape (2,) or ({n}, 2), "
            f"got shape {o.shape}"
        )
    return o


def _off_tangents(
    points: FloatArray, origins: FloatArray, circle: CircleFit, margin: float
) -> NDArray[np.bool_]:
    """A mask (N,) of the points whose bearing from their origin lies more than ``margin``
    (rad) inside the tangents from that origin to ``circle``: ``|phi - theta| < alpha -
    margin`` with ``theta``, ``alpha = asin(R / rho)`` the centre's bearing and the half angle
    (eq. 3.3)."""
    to_centre = circle.centre - origins
    rho = np.linalg.norm(to_centre, axis=1)
    if (rho <= circle.R).any():
        raise ValueError(
            f"estimate_circle.origins must lie outside the first fit (centre "
            f"{circle.centre.tolist()}, R {circle.R:.3f}), got {origins[rho <= circle.R][0]}"
        )
    to_point = points - origins
    offset = wrap_angle(
        np.arctan2(to_point[:, 1], to_point[:, 0]) - np.arctan2(to_centre[:, 1], to_centre[:, 0])
    )
    return np.abs(offset) < np.arcsin(circle.R / rho) - margin


def _kcr(points: FloatArray, fit: CircleFit, sigma: float) -> FloatArray:
    """The KCR covariance (3, 3) of ``fit`` at the angles of ``points`` around its centre."""
    return kcr_covariance(angles_around_centre(points, fit.centre), sigma)


def _same_object(
    i: int,
    j: int,
    fits: Sequence[CircleFit],
    covariances: Sequence[FloatArray],
    config: FusionConfig,
    threshold: float,
) -> bool:
    """Whether fits ``i`` and ``j`` see one object under ``config.gate`` (``threshold``: the
    Mahalanobis gate's chi-square quantile, computed once per fusion)."""
    a, b = fits[i], fits[j]
    if config.gate == "overlap":
        return bool(np.linalg.norm(a.centre - b.centre) < a.R + b.R)
    difference = np.append(a.centre - b.centre, a.R - b.R)
    distance2 = difference @ np.linalg.solve(covariances[i] + covariances[j], difference)
    return bool(distance2 <= threshold)


def _components(n: int, linked: Callable[[int, int], bool]) -> list[tuple[int, ...]]:
    """The connected components of ``0 .. n - 1`` under ``linked`` (union-find), each sorted,
    in the order of their smallest member."""
    parent = list(range(n))

    def root(i: int) -> int:
        while parent[i] != i:
            i = parent[i]
        return i

    for i in range(n):
        for j in range(i + 1, n):
            if root(i) != root(j) and linked(i, j):
                parent[root(j)] = root(i)
    groups: dict[int, list[int]] = {}
    for i in range(n):
        groups.setdefault(root(i), []).append(i)
    return [tuple(members) for members in groups.values()]
