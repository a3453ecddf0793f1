"""An online map of static circular objects from laser scans and a believed robot pose.

Each mapped circle is ``x = (cx, cy, R)`` (m, field frame) with covariance ``P`` (3, 3). Per
scan:

1. the scan is cut into segments (:func:`perception.circles.segmentation.segment_breakpoints`)
   and a segment is a *candidate* when it stands in front of what is around it: the beams
   beside it read farther (by the segmentation's jump) or nothing, and it is not cut by the
   field of view; and when it is no wider than a circle of ``max_radius_m``;
2. a candidate joins the mapped circle whose centre its rough centre (the segment's mean point
   pushed back by half its chord along the mean beam) lies nearest to in the Mahalanobis sense,
   within the chi-square gate (2 dof), else it starts a circle;
3. the candidate's n points update that circle in one vector measurement: the ranges
   ``z_i`` of its beams against seed 001's polar model (eq. 3.2, convex side) of the circle seen
   from the believed sensor position ``s`` along the beam's field direction ``beta_i``::

       h_i(x) = rho cos(beta_i - phi) - sqrt(R^2 - rho^2 sin^2(beta_i - phi)),
       rho = |c - s|,  phi = atan2(c - s)

   with ``H`` (n, 3) from :func:`perception.circles.model.polar_jacobian` and the chain rule,
   and a noise ``R_z = sigma^2 I + J_pose P_pose J_pose^T``: the believed pose's covariance
   enters once per scan, correlated across the points (moving the sensor moves every range).
   The update is iterated (Gauss-Newton re-linearisation, ``iterations``), Joseph form
   (:func:`perception.estimation.kalman.joseph_update`). An update that would leave ``R <= 0``
   or put the sensor inside the circle is refused (counted in ``refused``), never clipped.

A circle is confirmed after ``confirm_hits`` updates. A circle that was not updated by a scan
is checked against it: when every beam that may meet it (given where it and the pose may be)
returned from beyond it by three standard deviations, the scan saw through it, a *miss* (a
beam without a return proves nothing); ``max_misses`` misses in a row drop it (the place
a walking robot stood). Its normalised innovation squared (NIS, per point) is averaged over its
updates; a circle whose average stays above ``max_mean_nis`` after ``confirm_hits`` updates
is not static either and is dropped. The pose error
is correlated over time, which this map (like the robot tracker) ignores: it is somewhat
overconfident while the pose is uncertain.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from perception.circles.model import measure_arc
from perception.circles.scan_circles import stands_clear
from perception.circles.segmentation import BreakpointConfig, Segment, segment_breakpoints
from perception.estimation.gating import chi2_threshold, mahalanobis_squared
from perception.estimation.kalman import joseph_update
from perception.geometry import FloatArray
from perception.types import MappedCircle
from perception.validation import (
    check_covariance,
    check_finite,
    check_instance,
    check_int,
    check_nested_configs,
    check_positive,
    check_probability,
    finite_vector,
)

_OWNER = "CircleMapConfig"


@dataclass(frozen=True, kw_only=True)
class CircleMapConfig:
    """Settings of :class:`CircleMapper` (m, unitless).

    ``segmentation``: how scans are cut (candidates need ``min_points`` beams or more);
    ``range_sigma_m``: the laser's range noise; ``max_radius_m``: wider segments are no circle;
    ``min_radius_m``: a new circle's radius is at least this (a chord of one beam);
    ``gate_probability``: chi-square (2 dof) gate of a candidate's centre on a circle's;
    ``confirm_hits``: updates that confirm a circle; ``max_misses``: scans in a row that see
    through a circle drop it; ``max_mean_nis``: a circle whose mean NIS per point is above this
    after ``confirm_hits`` updates is dropped; ``iterations``:
    re-linearisations per update; ``max_circles``: no circle is started beyond this many.
    """

    segmentation: BreakpointConfig = field(
        default_factory=lambda: BreakpointConfig(jump_threshold_m=0.15, min_points=3)
    )
    range_sigma_m: float = 0.02  # seed 001's laser
    max_radius_m: float = 0.5  # seed 001's largest column
    min_radius_m: float = 0.01
    gate_probability: float = 0.999
    confirm_hits: int = 10
    max_misses: int = 3
    max_mean_nis: float = 4.0
    iterations: int = 3
    max_circles: int = 64

    def __post_init__(self) -> None:
        check_nested_configs(self)
        check_positive(_OWNER, "range_sigma_m", self.range_sigma_m)
        check_positive(_OWNER, "max_radius_m", self.max_radius_m)
        check_positive(_OWNER, "min_radius_m", self.min_radius_m, upper=self.max_radius_m)
        check_probability(_OWNER, "gate_probability", self.gate_probability)
        check_int(_OWNER, "confirm_hits", self.confirm_hits, 1)
        check_int(_OWNER, "max_misses", self.max_misses, 1)
        check_positive(_OWNER, "max_mean_nis", self.max_mean_nis)
        check_int(_OWNER, "iterations", self.iterations, 1)
        check_int(_OWNER, "max_circles", self.max_circles, 1)


@dataclass
class _Circle:
    circle_id: int
    x: FloatArray
    P: FloatArray
    hits: int = 0
    nis_sum: float = 0.0
    misses: int = 0

    @property
    def mean_nis(self) -> float:
        return self.nis_sum / max(self.hits, 1)


@dataclass(frozen=True)
class _Candidate:
    """A candidate segment in the field frame: the sensor ``origin`` (2,), beam directions
    ``beta`` (n,) (rad), ranges ``z`` (n,) (m), points (n, 2) and a rough circle (3,)."""

    origin: FloatArray
    beta: FloatArray
    z: FloatArray
    rough: FloatArray


class CircleMapper:
    """The circle map (module docstring); one :meth:`update` per laser scan."""

    def __init__(self, config: CircleMapConfig | None = None) -> None:
        check_instance("config", config, CircleMapConfig, optional=True)
        self.config = config or CircleMapConfig()
        self._gate = chi2_threshold(self.config.gate_probability, 2)
        self._circles: list[_Circle] = []
        self._next_id = 0
        self.refused = 0  # updates refused (they would have made an impossible circle)

    def reset(self) -> None:
        """Forget every circle."""
        self._circles, self._next_id, self.refused = [], 0, 0

    @property
    def circles(self) -> tuple[MappedCircle, ...]:
        """Every circle, confirmed or not, by id."""
        k = self.config.confirm_hits
        return tuple(
            MappedCircle(
                circle_id=c.circle_id,
                state=c.x.copy(),
                cov=c.P.copy(),
                hits=c.hits,
                confirmed=c.hits >= k,
            )
            for c in self._circles
        )

    def update(
        self,
        angles: ArrayLike,
        ranges: ArrayLike,
        mount_x_m: float,
        pose: ArrayLike,
        pose_cov: ArrayLike,
    ) -> tuple[MappedCircle, ...]:
        """Fuse one scan: beam ``angles`` (B,) (rad, robot frame) and ``ranges`` (B,) (m, NaN
        or +inf for no return) from a scanner ``mount_x_m`` ahead of the robot origin, seen from the
        believed ``pose`` (3,) (field frame) with covariance ``pose_cov`` (3, 3). Returns
        :attr:`circles`."""
        check_finite("CircleMapper.update", "mount_x_m", mount_x_m)
        pose = finite_vector(pose, "pose", 3)
        pose_cov = check_covariance(pose_cov, "pose_cov", 3, singular_ok=True)
        scan = np.array(ranges, dtype=np.float64)
        scan[np.isposinf(scan)] = np.nan  # no return: not a return from beyond a circle
        updated: set[int] = set()
        for segment in segment_breakpoints(angles, scan, self.config.segmentation):
            candidate = self._candidate(segment, scan, pose, mount_x_m)
            if candidate is not None:
                updated |= self._fuse(candidate, pose, pose_cov)
        origin = pose[:2] + mount_x_m * np.array([math.cos(pose[2]), math.sin(pose[2])])
        beta = pose[2] + np.asarray(angles, dtype=np.float64)
        directions = np.column_stack([np.cos(beta), np.sin(beta)])  # (B, 2), field frame
        for circle in self._circles:
            if circle.circle_id in updated:
                circle.misses = 0
            elif self._seen_through(circle, origin, directions, scan, pose, pose_cov):
                circle.misses += 1
        cfg = self.config
        self._circles = [
            c
            for c in self._circles
            if c.misses < cfg.max_misses
            and (c.hits < cfg.confirm_hits or c.mean_nis <= cfg.max_mean_nis)
        ]
        return self.circles

    def _seen_through(
        self,
        circle: _Circle,
        origin: FloatArray,
        directions: FloatArray,
        scan: FloatArray,
        pose: FloatArray,
        pose_cov: FloatArray,
    ) -> bool:
        """Whether the scan (unit beam ``directions`` (B, 2) from ``origin``, field frame) saw
        through the whole place where ``circle`` may be: every beam that may meet it, passing
        its centre closer than ``R`` plus three standard deviations of where the centre lies
        across the beam (the circle's and the believed pose's uncertainty, the heading's times
        the range), returned from farther than the centre's depth plus ``R`` and three standard
        deviations along the beam."""
        offset = circle.x[:2] - origin
        rho = float(np.hypot(*offset))
        radius = float(circle.x[2])
        if not 0.0 < radius < rho:
            return False
        J = _centre_pose_jacobian(circle.x[:2], pose)
        spread = circle.P[:2, :2] + J @ pose_cov @ J.T
        across = np.array([-offset[1], offset[0]]) / rho
        lateral_std = math.sqrt(float(across @ spread @ across))
        depth = directions @ offset  # the centre's depth along each beam
        miss_distance = np.abs(directions[:, 0] * offset[1] - directions[:, 1] * offset[0])
        band = (depth > 0.0) & (miss_distance < radius + 3.0 * lateral_std)
        if not band.any():
            return False
        along_std = math.sqrt(self.config.range_sigma_m**2 + float(np.trace(spread)))
        measured = scan[band]
        # a beam without a return proves nothing: it may have met our own body or gone out of
        # range; only returns from behind the place show that the scan saw through it
        beyond = measured > depth[band] + radius + 3.0 * along_std
        return bool(beyond.all())

    # ----- candidates -------------------------------------------------------------------
    def _candidate(
        self, segment: Segment, ranges: FloatArray, pose: FloatArray, mount_x_m: float
    ) -> _Candidate | None:
        """The segment as a candidate (module docstring, step 1), or None."""
        if not stands_clear(segment, ranges, self.config.segmentation.jump_threshold_m):
            return None  # cut by the field of view, or maybe partly hidden
        spacing = float(np.mean(np.diff(segment.angles))) if len(segment) > 1 else 0.0
        mean_range = float(np.mean(segment.ranges))
        half_chord = 0.5 * mean_range * (float(np.ptp(segment.angles)) + spacing)
        if half_chord > self.config.max_radius_m:
            return None
        c, s = math.cos(pose[2]), math.sin(pose[2])
        rotation = np.array([[c, -s], [s, c]])
        origin = pose[:2] + rotation @ np.array([mount_x_m, 0.0])
        beta = pose[2] + segment.angles
        points = origin + segment.ranges[:, None] * np.column_stack([np.cos(beta), np.sin(beta)])
        direction = np.mean(points, axis=0) - origin
        direction /= np.linalg.norm(direction)
        radius = max(half_chord, self.config.min_radius_m)
        rough = np.array([*(np.mean(points, axis=0) + radius * direction), radius])
        return _Candidate(origin, beta, segment.ranges.copy(), rough)

    # ----- fusion -----------------------------------------------------------------------
    def _fuse(self, candidate: _Candidate, pose: FloatArray, pose_cov: FloatArray) -> set[int]:
        """Associate and fuse one candidate; the id of the circle it updated, if any."""
        circle = self._associate(candidate, pose, pose_cov)
        if circle is None:
            if len(self._circles) >= self.config.max_circles:
                return set()
            circle = self._new_circle(candidate, pose, pose_cov)
        return (
            {circle.circle_id} if self._update_circle(circle, candidate, pose, pose_cov) else set()
        )

    def _associate(
        self, candidate: _Candidate, pose: FloatArray, pose_cov: FloatArray
    ) -> _Circle | None:
        best, best_d2 = None, self._gate
        spread = self._rough_cov(candidate, pose, pose_cov)[:2, :2]
        for circle in self._circles:
            d2 = float(
                mahalanobis_squared(candidate.rough[:2] - circle.x[:2], circle.P[:2, :2] + spread)
            )
            if d2 <= best_d2:
                best, best_d2 = circle, d2
        return best

    def _rough_cov(
        self, candidate: _Candidate, pose: FloatArray, pose_cov: FloatArray
    ) -> FloatArray:
        """Covariance (3, 3) of a candidate's rough circle: half its radius per axis (the rough
        centre's offset is a guess) plus the range noise, and the believed pose's (a heading
        error swings the centre about the robot)."""
        std = 0.5 * candidate.rough[2] + self.config.range_sigma_m
        cov = np.diag([std**2, std**2, (0.5 * candidate.rough[2]) ** 2])
        J = _centre_pose_jacobian(candidate.rough[:2], pose)
        cov[:2, :2] += J @ pose_cov @ J.T
        return cov

    def _new_circle(self, candidate: _Candidate, pose: FloatArray, pose_cov: FloatArray) -> _Circle:
        rough_cov = self._rough_cov(candidate, pose, pose_cov)
        circle = _Circle(self._next_id, candidate.rough.copy(), rough_cov)
        self._next_id += 1
        self._circles.append(circle)
        return circle

    def _update_circle(
        self, circle: _Circle, candidate: _Candidate, pose: FloatArray, pose_cov: FloatArray
    ) -> bool:
        """The iterated EKF update of ``circle`` with the candidate's ranges (module doc);
        whether it was made (not refused)."""
        x, P, nis = circle.x, circle.P, None
        for _ in range(self.config.iterations):
            model = self._measurement(x, candidate, pose)
            if model is None:
                self.refused += 1
                return False
            used, h, H, J_pose = model
            z = candidate.z[used]
            noise = self.config.range_sigma_m**2 * np.eye(len(h)) + J_pose @ pose_cov @ J_pose.T
            # iterated EKF: linearised at x, the innovation taken against the prior circle.x
            y = z - h - H @ (circle.x - x)
            if nis is None:  # at the prior: the normalised innovation squared, per point
                nis = float(mahalanobis_squared(y, H @ circle.P @ H.T + noise)) / len(y)
            x, P = joseph_update(circle.x, circle.P, y, H, noise)
            if not self._valid(x, candidate.origin):
                self.refused += 1
                return False
        circle.x, circle.P = x, P
        circle.nis_sum += float(nis or 0.0)
        circle.hits += 1
        return True

    @staticmethod
    def _measurement(
        x: FloatArray, candidate: _Candidate, pose: FloatArray
    ) -> tuple[NDArray[np.bool_], FloatArray, FloatArray, FloatArray] | None:
        """The beams ``used`` (n,) bool (:func:`~perception.circles.model.measure_arc`), their
        predicted ranges ``h`` (k,), ``H`` (k, 3) on (cx, cy, R) and ``J_pose`` (k, 3) on the
        pose (x, y, theta); None when fewer than three beams are used."""
        arc = measure_arc(x, pose[:2], candidate.origin, candidate.beta)
        if arc is None:
            return None
        return arc.used, arc.ranges, arc.H_circle, arc.H_pose

    @staticmethod
    def _valid(x: FloatArray, origin: FloatArray) -> bool:
        return bool(np.isfinite(x).all() and 0.0 < x[2] < np.hypot(*(x[:2] - origin)))


def _centre_pose_jacobian(point: FloatArray, pose: FloatArray) -> FloatArray:
    """(2, 3): how a point (2,) seen from the robot moves in the field when the believed pose
    (x, y, theta) (3,) moves (a heading error swings it about the robot)."""
    lever = point - pose[:2]
    return np.array([[1.0, 0.0, -lever[1]], [0.0, 1.0, lever[0]]])
