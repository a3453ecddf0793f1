"""Geometry of field features: straight lines in the image, segments, junctions, the circle.

The pure half of :mod:`perception.vision.field_features` (no image, no camera), so that each
step can be tested alone:

- :func:`image_lines`: collinear groups of image points (px), by an iterated Hough transform
  with a total-least-squares refit. The image is undistorted, so a straight field line is
  straight in the image, with the same (isotropic, pixel) noise everywhere; on the ground the
  noise grows with range and a fixed tolerance would not suit near and far alike. Deterministic
  (no random sampling, unlike RANSAC).
- :func:`curvature`: whether ground points bend (a piece of the circle) or run straight.
- :func:`merge_segments`: ground segments (robot frame, m) that are collinear and overlap (or
  nearly meet) become one.
- :func:`find_junctions`: L corners, T and X junctions from pairs of near-perpendicular ground
  segments, with the direction conventions of :mod:`perception.field.features`.
- :func:`find_circle`: a circle of known radius among ground points (Hough vote for its centre,
  then the Hyper fit to check its radius, then a fixed-radius least-squares centre).

Frames: image points ``(u, v)`` px; ground points ``(x, y)`` m in the robot frame.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import Literal

import cv2
import numpy as np
from numpy.typing import NDArray

from perception.circles.fits import hyper_fit
from perception.geometry import FloatArray

JunctionKind = Literal["corner", "t_junction", "x_junction"]


@dataclass(frozen=True)
class ImageLine:
    """A group of collinear image points: their ``indices`` (K,) into the input, sorted along
    the line, and the line's two ``ends`` (2, 2) px: the feet of the extreme points on the
    total-least-squares line through them."""

    indices: NDArray[np.intp]
    ends: FloatArray


@dataclass(frozen=True)
class Segment:
    """A straight piece seen on the ground: ``ends`` (2, 2) m (robot frame), each end's
    covariance ``cov`` (2, 2, 2) m² and whether each end is ``open`` (2,): cut by the edge
    of the view (the image side, the range limit), so the line may go on beyond it."""

    ends: FloatArray
    cov: FloatArray
    open: tuple[bool, bool] = (False, False)

    @cached_property
    def length(self) -> float:
        """Length (m)."""
        return float(np.hypot(*(self.ends[1] - self.ends[0])))

    @cached_property
    def direction(self) -> FloatArray:
        """Unit vector (2,) from the first end to the second (read-only: it is kept)."""
        d = self.ends[1] - self.ends[0]
        direction = np.asarray(d / np.hypot(*d), dtype=np.float64)
        direction.flags.writeable = False
        return direction

    def distance(self, point: FloatArray) -> float:
        """Distance (m) from ``point`` (2,) m to the segment."""
        a, b = self.ends
        t = float(np.clip((point - a) @ (b - a) / float((b - a) @ (b - a)), 0.0, 1.0))
        return float(np.hypot(*(point - a - t * (b - a))))

    def normal_std(self) -> float:
        """Standard deviation (m) of the ends across the segment (mean of both ends)."""
        d = self.direction
        n = np.array([-d[1], d[0]])
        return float(np.sqrt(np.mean([n @ c @ n for c in self.cov])))


@dataclass(frozen=True)
class Junction:
    """Where two segments meet: ``kind``, ``point`` (2,) m, ``direction`` (rad, robot frame,
    conventions of :mod:`perception.field.features`), ``direction_std`` (rad) and the indices
    ``pair`` of the two segments."""

    kind: JunctionKind
    point: FloatArray
    direction: float
    direction_std: float
    pair: tuple[int, int]


@dataclass(frozen=True)
class CircleFound:
    """A circle among ground points: ``centre`` (2,) m, the free-radius fit's ``radius`` (m),
    the ``inliers`` (N,) mask of the input points and their angular ``arc`` (rad) about it."""

    centre: FloatArray
    radius: float
    inliers: NDArray[np.bool_]
    arc: float


def _tls(points: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Centroid (2,) and unit direction (2,) of the total-least-squares line through (K, 2):
    the principal axis of their scatter, at half the angle of ``(sxx - syy, 2 sxy)`` (in
    [-pi/2, pi/2], so x >= 0; (1, 0) when the points coincide)."""
    centre = points.sum(axis=0) / len(points)  # the mean, without its overhead
    centred = points - centre
    (sxx, sxy), (_, syy) = centred.T @ centred
    angle = 0.5 * math.atan2(2.0 * sxy, sxx - syy)
    return centre, np.array([math.cos(angle), math.sin(angle)])


def image_lines(
    points: FloatArray,
    *,
    tol_px: float,
    min_points: int,
    split_gap_px: float,
    theta_step_rad: float = math.radians(1.0),
    rho_step_px: float = 2.0,
    max_peaks: int = 30,
    ground: FloatArray | None = None,
    split_gap_m: float = 0.0,
) -> list[ImageLine]:
    """Collinear groups among the image points ``points`` (N, 2) px.

    Repeatedly: take the peak of the ``(theta, rho)`` accumulator (steps ``theta_step_rad``,
    ``rho_step_px``) of the votes of every remaining point (OpenCV's ``HoughLinesPointSet`` on
    the points in float32; of equal peaks the first in theta-major order), refit the points
    within ``rho_step_px`` of it by total least squares and take those within ``tol_px`` of the
    refit; they leave the pool (and the next accumulator), are refitted together, and are split
    where consecutive points along the line lie more than ``split_gap_px`` apart or, given
    their ground points ``ground`` (N, 2) m, more than ``split_gap_m`` apart on the ground. The
    pieces of ``min_points`` or more points keep the common line (a far line thinner than a
    pixel is drawn as a staircase with gaps, whose steps alone would lie askew; a few stray
    points beyond a line's end are dropped). Stops when the peak has fewer than ``min_points``
    votes or after ``max_peaks`` peaks.
    """
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    if len(pts) < min_points:  # no peak can have enough votes
        return []
    rho_max = float(np.abs(pts).sum(axis=1).max()) + rho_step_px  # no |rho| can reach it
    pts32 = pts.astype(np.float32).reshape(-1, 1, 2)  # OpenCV's point set
    remaining = np.arange(len(pts))
    out: list[ImageLine] = []
    for _ in range(max_peaks):
        if len(remaining) < min_points:
            break
        # the accumulator's peak, (votes, rho, theta); lines need votes > the threshold
        peak = cv2.HoughLinesPointSet(
            pts32[remaining],
            1,
            min_points - 1,
            -rho_max,
            rho_max,
            rho_step_px,
            0.0,
            math.pi - 1e-9,  # angles 0, theta_step_rad, ... below pi
            theta_step_rad,
        )
        if peak is None or len(peak) == 0:
            break
        _, rho, theta = peak[0]
        p = pts[remaining]
        hough_normal = np.array([math.cos(theta), math.sin(theta)])
        near = np.abs(p @ hough_normal - rho) <= max(rho_step_px, tol_px)
        centre, direction = _tls(p[near])
        normal = np.array([-direction[1], direction[0]])
        near = np.abs((p - centre) @ normal) <= tol_px
        if not near.any():  # cannot happen for a peak; guards the loop's progress
            near = np.abs(p @ hough_normal - rho) <= rho_step_px
        chosen = remaining[near]
        remaining = remaining[~near]
        along = (pts[chosen] - centre) @ direction
        order = np.argsort(along)
        chosen, along = chosen[order], along[order]
        wide = np.diff(along) > split_gap_px
        if ground is not None:
            step = np.diff(ground[chosen], axis=0)
            wide |= np.hypot(step[:, 0], step[:, 1]) > split_gap_m
        cuts = (np.flatnonzero(wide) + 1).tolist()
        centre, direction = _tls(pts[chosen])  # one line for all pieces: they merge again
        s = (pts[chosen] - centre) @ direction
        for lo, hi in zip([0, *cuts], [*cuts, len(chosen)], strict=True):
            if hi - lo >= min_points:
                first, last = s[lo:hi].min(), s[lo:hi].max()
                ends = np.array([centre + first * direction, centre + last * direction])
                out.append(ImageLine(chosen[lo:hi], ends))
    return out


def curvature(points: FloatArray) -> tuple[float, float]:
    """Curvature (1/m) of the least-squares parabola through ground points (K, 2) m, in the
    frame of their total-least-squares line, and its standard error (from the residuals);
    (0, inf) for fewer than 4 points. A straight line gives about 0, a circle 1 / radius."""
    if len(points) < 4:
        return 0.0, math.inf
    centre, direction = _tls(points)
    t = (points - centre) @ direction
    s = (points - centre) @ np.array([-direction[1], direction[0]])
    design = np.column_stack([np.ones_like(t), t, t**2])
    try:  # the normal equations: 3 x 3, well conditioned for ground points near the robot
        inverse = np.linalg.inv(design.T @ design)
    except np.linalg.LinAlgError:
        return 0.0, math.inf
    coef = inverse @ (design.T @ s)
    residual = s - design @ coef
    dof = max(len(points) - 3, 1)
    var = float(residual @ residual) / dof * inverse[2, 2]
    return 2.0 * float(coef[2]), 2.0 * math.sqrt(max(var, 0.0))


def _mergeable(
    a: Segment, b: Segment, angle_tol_rad: float, offset_tol_m: float, gap_tol_m: float
) -> bool:
    """Whether ``a`` and ``b`` lie within ``angle_tol_rad`` (modulo pi) of each other, each
    one's ends within ``offset_tol_m`` of the other's line, and overlap or leave a gap of at
    most ``gap_tol_m`` between them along ``a`` (each test only when the ones before pass)."""
    da, db = a.direction, b.direction
    if not math.acos(min(abs(float(da @ db)), 1.0)) <= angle_tol_rad:  # (NaN fails)
        return False
    na, nb = np.array([-da[1], da[0]]), np.array([-db[1], db[0]])
    offset = max(
        float(np.abs((b.ends - a.ends[0]) @ na).max()),
        float(np.abs((a.ends - b.ends[0]) @ nb).max()),
    )
    if not offset <= offset_tol_m:
        return False
    sb = (b.ends - a.ends[0]) @ da
    return max(float(sb.min()) - a.length, -float(sb.max())) <= gap_tol_m


def _merge_two(a: Segment, b: Segment) -> Segment:
    """One segment spanning ``a`` and ``b``: on the length-weighted mean line, from the
    extreme projection of their ends to the other (each keeping its covariance)."""
    da, db = a.direction, b.direction
    if da @ db < 0:
        db = -db
    d = a.length * da + b.length * db
    d /= np.hypot(*d)
    centre = (a.length * a.ends.mean(axis=0) + b.length * b.ends.mean(axis=0)) / (
        a.length + b.length
    )
    ends = np.vstack([a.ends, b.ends])
    covs = np.concatenate([a.cov, b.cov])
    opens = (*a.open, *b.open)
    s = (ends - centre) @ d
    lo, hi = int(np.argmin(s)), int(np.argmax(s))
    ends = np.array([centre + s[lo] * d, centre + s[hi] * d])
    return Segment(ends, covs[[lo, hi]], (opens[lo], opens[hi]))


def merge_segments(
    segments: list[Segment], *, angle_tol_rad: float, offset_tol_m: float, gap_tol_m: float
) -> list[Segment]:
    """Merge segments that are collinear (directions within ``angle_tol_rad``, each one's ends
    within ``offset_tol_m`` of the other's line) and overlap or leave a gap of at most
    ``gap_tol_m`` between them, until no pair is left; order of first appearance kept."""
    out = list(segments)
    merged = True
    while merged:
        merged = False
        for i in range(len(out)):
            for j in range(i + 1, len(out)):
                if _mergeable(out[i], out[j], angle_tol_rad, offset_tol_m, gap_tol_m):
                    out[i] = _merge_two(out[i], out[j])
                    del out[j]
                    merged = True
                    break
            if merged:
                break
    return out


def _place(segment: Segment, point: FloatArray, end_tol_m: float) -> tuple[str, FloatArray]:
    """Where ``point`` (on the segment's line) lies: ``"end"`` within ``end_tol_m`` of an end
    (``"outside"`` if that end is open: the line may go on), ``"interior"`` between them,
    ``"outside"`` otherwise; and the unit arm (2,) from the point to the farther end."""
    d = segment.direction
    t = float((point - segment.ends[0]) @ d)
    length = segment.length
    near = 0 if t < length / 2 else 1
    arm = segment.ends[1 - near] - point
    arm = arm / max(float(np.hypot(*arm)), 1e-12)
    if min(abs(t), abs(t - length)) <= end_tol_m:
        return ("outside" if segment.open[near] else "end"), arm
    if 0.0 < t < length:
        return "interior", arm
    return "outside", arm


def find_junctions(
    segments: list[Segment],
    *,
    angle_tol_rad: float,
    end_tol_m: float,
    min_direction_std_rad: float = 0.01,
    dedupe_m: float = 0.1,
) -> list[Junction]:
    """Junctions of pairs of ``segments`` that meet at right angles within ``angle_tol_rad``.

    The lines' intersection is a ``corner`` when it lies within ``end_tol_m`` of an end of
    both (no junction if such an end is open: a T's bar cut by the image side looks like an
    L) (direction: the bisector of the arms, into the L's opening), a ``t_junction`` when of
    one and inside the other (direction: along the stem, away from the bar), an
    ``x_junction`` when inside both (direction: along the longer one, in [0, pi)). A
    direction's std is the angular std of the segments involved (their ends' std across them
    over their length), at least ``min_direction_std_rad``. Of junctions closer than
    ``dedupe_m`` the first (T before L) is kept.
    """
    found: list[Junction] = []
    for i in range(len(segments)):
        for j in range(i + 1, len(segments)):
            a, b = segments[i], segments[j]
            da, db = a.direction, b.direction
            if abs(float(da @ db)) > math.sin(angle_tol_rad):
                continue
            # a.ends[0] + s da = b.ends[0] + t db
            s, _ = np.linalg.solve(np.column_stack([da, -db]), b.ends[0] - a.ends[0])
            point = a.ends[0] + s * da
            (pa, arm_a), (pb, arm_b) = _place(a, point, end_tol_m), _place(b, point, end_tol_m)
            if "outside" in (pa, pb):
                continue
            std_a = a.normal_std() * math.sqrt(2) / max(a.length, 1e-6)
            std_b = b.normal_std() * math.sqrt(2) / max(b.length, 1e-6)
            if pa == "end" and pb == "end":
                kind: JunctionKind = "corner"
                bisector = arm_a + arm_b
                direction = math.atan2(bisector[1], bisector[0])
                std = 0.5 * math.hypot(std_a, std_b)
            elif pa == "end" or pb == "end":
                kind = "t_junction"
                arm, std = (arm_a, std_a) if pa == "end" else (arm_b, std_b)
                direction = math.atan2(arm[1], arm[0])
            else:
                kind = "x_junction"
                longer, std = (da, std_a) if a.length >= b.length else (db, std_b)
                direction = math.atan2(longer[1], longer[0]) % math.pi
            found.append(Junction(kind, point, direction, max(std, min_direction_std_rad), (i, j)))
    rank = {"t_junction": 0, "x_junction": 1, "corner": 2}
    kept: list[Junction] = []
    for junction in sorted(found, key=lambda k: rank[k.kind]):
        if all(np.hypot(*(junction.point - k.point)) >= dedupe_m for k in kept):
            kept.append(junction)
    return kept


def _fixed_radius_centre(points: FloatArray, centre: FloatArray, radius: float) -> FloatArray:
    """Centre (2,) minimising ``sum (|p - c| - radius)^2`` by Gauss-Newton from ``centre``."""
    c = centre.astype(np.float64).copy()
    for _ in range(10):
        diff = points - c
        dist = np.maximum(np.hypot(diff[:, 0], diff[:, 1]), 1e-9)
        jac = -diff / dist[:, None]
        # the 2 x 2 normal equations J'J step = -J'r, solved by Cramer's rule
        (a, b), (_, d) = (jac.T @ jac).tolist()
        g0, g1 = (jac.T @ (radius - dist)).tolist()
        det = a * d - b * b
        if not det > 0.0:  # the points lie on one line through the centre: no fix across it
            break
        step = np.array([(d * g0 - b * g1) / det, (a * g1 - b * g0) / det])
        c += step
        if math.hypot(step[0], step[1]) < 1e-6:
            break
    return c


def _longest_arc(
    points: FloatArray, centre: FloatArray, max_gap_rad: float
) -> tuple[float, NDArray[np.bool_]]:
    """The longest angle (rad) about ``centre`` that the points (K, 2) cover without a gap
    wider than ``max_gap_rad`` (2 pi when they go all round), and a (K,) mask of its points."""
    angles = np.arctan2(points[:, 1] - centre[1], points[:, 0] - centre[0])
    order = np.argsort(angles)
    sorted_angles = angles[order]
    everything = np.ones(len(points), dtype=bool)
    if len(points) < 2:
        return 0.0, everything
    gaps = np.diff(np.concatenate([sorted_angles, sorted_angles[:1] + 2 * math.pi]))
    wide = np.flatnonzero(gaps > max_gap_rad)
    if not len(wide):
        return 2 * math.pi, everything
    # runs between the wide gaps, each from the point after one wide gap to the next gap
    starts = (wide + 1) % len(points)
    stops = np.roll(wide, -1)
    spans = (sorted_angles[stops] - sorted_angles[starts]) % (2 * math.pi)
    k = int(np.argmax(spans))
    a, b = int(starts[k]), int(stops[k])
    picked = np.arange(a, b + 1) if a <= b else np.r_[a : len(points), 0 : b + 1]
    mask = np.zeros(len(points), dtype=bool)
    mask[order[picked]] = True
    return float(spans[k]), mask


def find_circle(
    points: FloatArray,
    radius_m: float,
    *,
    tol_m: float,
    radius_tol_m: float,
    min_points: int,
    min_arc_rad: float,
    cell_m: float = 0.05,
    n_angles: int = 64,
    n_peaks: int = 3,
    max_gap_rad: float = math.radians(15.0),
) -> CircleFound | None:
    """The best circle of radius ``radius_m`` among the ground points ``points`` (N, 2) m.

    Each point votes for the centres ``radius_m`` away from it (``n_angles`` of them) on a
    grid of ``cell_m`` cells; the ``n_peaks`` best 3 x 3 blocks of cells (apart by more than
    the radius) are candidates. A candidate's inliers (the points within ``tol_m`` of the
    circle, once its centre is refined with the radius fixed) need ``min_points`` members
    covering ``min_arc_rad`` about the centre without a gap wider than ``max_gap_rad`` (a
    mark and a junction's corner at the right distance are no arc) and, if under 90°, bending
    there (:func:`curvature` at least half the circle's, and 3 standard errors: not straight
    lines that the circle dips into), and the Hyper fit through them a radius within
    ``radius_tol_m`` of ``radius_m`` (a straight stretch has a huge one).
    Of the candidates that pass, the one with most inliers; None if none passes.
    """
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    if len(pts) < max(min_points, 3):
        return None
    phi = np.linspace(0.0, 2 * math.pi, n_angles, endpoint=False)
    ring = radius_m * np.column_stack([np.cos(phi), np.sin(phi)])
    low = pts.min(axis=0) - radius_m - 2 * cell_m
    shape = np.ceil((pts.max(axis=0) + radius_m + 2 * cell_m - low) / cell_m).astype(np.intp) + 1
    votes_at = pts[:, None, :] + ring[None]  # (N, n_angles, 2) m, then in grid cells
    votes_at -= low
    votes_at /= cell_m
    cells = np.floor(votes_at, out=votes_at).astype(np.intp).reshape(-1, 2)
    grid = np.bincount(cells[:, 0] * shape[1] + cells[:, 1], minlength=int(np.prod(shape)))
    padded = np.zeros((shape[0] + 2, shape[1] + 2))  # no votes beyond the grid
    padded[1:-1, 1:-1] = grid.reshape(shape)
    rows = padded[:-2] + padded[1:-1] + padded[2:]
    block = rows[:, :-2] + rows[:, 1:-1] + rows[:, 2:]  # 3 x 3 block sums (exact: counts)
    best: CircleFound | None = None
    apart = math.ceil(radius_m / cell_m)
    for _ in range(n_peaks):
        ix, iy = np.unravel_index(int(np.argmax(block)), block.shape)
        if block[ix, iy] < min_points:
            break
        block[max(ix - apart, 0) : ix + apart + 1, max(iy - apart, 0) : iy + apart + 1] = 0.0
        centre = low + (np.array([ix, iy]) + 0.5) * cell_m
        found = _check_circle(
            pts,
            centre,
            radius_m,
            tol_m,
            cell_m,
            (radius_tol_m, min_points, min_arc_rad, max_gap_rad),
        )
        if found is not None and (best is None or found.inliers.sum() > best.inliers.sum()):
            best = found
    return best


def _check_circle(
    pts: FloatArray,
    centre: FloatArray,
    radius_m: float,
    tol_m: float,
    cell_m: float,
    gates: tuple[float, int, float, float],
) -> CircleFound | None:
    """The circle near the voted ``centre`` (2,) if it passes :func:`find_circle`'s tests
    ``gates``: ``(radius_tol_m, min_points, min_arc_rad, max_gap_rad)``."""
    radius_tol_m, min_points, min_arc_rad, max_gap_rad = gates
    for _ in range(2):  # inliers of the vote, then of the refined centre
        inliers = np.abs(np.hypot(*(pts - centre).T) - radius_m) <= tol_m + cell_m
        if inliers.sum() < max(min_points, 3):
            return None
        centre = _fixed_radius_centre(pts[inliers], centre, radius_m)
    inliers = np.abs(np.hypot(*(pts - centre).T) - radius_m) <= tol_m
    if inliers.sum() < max(min_points, 3):
        return None
    arc, run = _longest_arc(pts[inliers], centre, max_gap_rad)
    if arc < min_arc_rad:
        return None
    if arc < math.pi / 2:  # a straight line meets the ring over ~60° at most: check it bends
        kappa, kappa_std = curvature(pts[inliers][run])
        if abs(kappa) < max(0.5 / radius_m, 3.0 * kappa_std):
            return None
    try:
        free = hyper_fit(pts[inliers])
    except ValueError:  # collinear inliers: a straight line, not a circle
        return None
    if abs(free.R - radius_m) > radius_tol_m:
        return None
    return CircleFound(centre, float(free.R), inliers, arc)
