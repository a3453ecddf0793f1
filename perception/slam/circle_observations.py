"""What a laser scan tells an EKF about circles, and the range (arc) update that fuses it.

Two observations of one scan: a :class:`CircleObservation` (a circle fitted to a segment, its
centre and radius with a covariance) and an :class:`ArcObservation` (the segment's beams
themselves). An arc is fused into a state that holds the robot pose ``(x, y, theta)`` (its
first three entries, world frame) and a circle whose centre ``(c_x, c_y)`` sits at ``column``
and whose radius either follows it in the state or is known (``radius``, e.g. an SPL pole's):

- the measurement (:func:`perception.circles.model.measure_arc`): the ranges ``z`` (k,) of the
  beams that meet the circle away from its tangents against seed 001's polar model (eq. 3.2,
  convex side), with ``H`` (k, 5 or 6) on the pose and the circle and ``Q = sigma_r^2 I``;
- the pairing cost (:func:`arc_cost`): the normalised innovation squared ``y^T S^-1 y`` over
  the chi-square (k dof) quantile of the gate probability (in the gate: <= 1);
- the update (:func:`fuse_arc`): an iterated EKF on the beams chosen at the prior (Joseph
  form), each iteration re-linearised at the previous one's Gauss-Newton step, halved (up to
  ``STEP_HALVINGS`` times) while one of those beams would graze or miss the circle there, and
  stopped early when no halving helps.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numpy.typing import NDArray

from perception.circles.model import measure_arc
from perception.estimation.gating import chi2_threshold, mahalanobis_squared
from perception.estimation.kalman import innovation_covariance, joseph_update
from perception.geometry import FloatArray, wrap_angle
from perception.validation import (
    InvalidTypeError,
    check_covariance,
    check_positive,
    finite_vector,
)

_POSE = 3  # entries of the pose at the head of the state
ITERATIONS = 3  # Gauss-Newton re-linearisations of an arc update
STEP_HALVINGS = 3  # halvings of a re-linearisation step that would graze a chosen beam


@dataclass(frozen=True, eq=False)
class CircleObservation:
    """A circle seen in one scan: ``centre`` (2,) (m, robot frame), radius ``R`` (m) and the
    covariance ``cov`` (3, 3) of ``(centre_x, centre_y, R)`` (m²), e.g. a
    :class:`~perception.circles.fits.CircleFit` with its
    :func:`~perception.circles.fits.kcr_covariance`, moved from the laser's frame into the
    robot's (the laser sits ahead of the axle)."""

    centre: FloatArray
    R: float
    cov: FloatArray

    def __post_init__(self) -> None:
        centre = finite_vector(self.centre, "CircleObservation.centre", 2)
        check_positive("CircleObservation", "R", self.R)
        cov = check_covariance(self.cov, "CircleObservation.cov", 3)
        object.__setattr__(self, "centre", centre)
        object.__setattr__(self, "cov", cov)

    @property
    def z(self) -> FloatArray:
        """The measurement ``(z_x, z_y, z_R)`` (3,) (m)."""
        return np.array([self.centre[0], self.centre[1], self.R])


@dataclass(frozen=True, eq=False)
class ArcObservation:
    """A segment of one scan that may be (part of) a circle: its beams' ``angles`` (n,) (rad,
    robot frame) and ``ranges`` (n,) (m, from the scanner, finite); ``fit``, the circle
    fitted to it when it was classified as one (the only way a new circle enters the map),
    else None; ``circular``: whether some circle explains its points within the range noise
    (a circle or a line, which is a circle's limit), the condition to be fused by its ranges."""

    angles: FloatArray
    ranges: FloatArray
    fit: CircleObservation | None = None
    circular: bool = True

    def __post_init__(self) -> None:
        angles = finite_vector(self.angles, "ArcObservation.angles", int(np.size(self.angles)))
        ranges = finite_vector(self.ranges, "ArcObservation.ranges", len(angles))
        if (ranges <= 0.0).any():
            raise ValueError(f"ArcObservation.ranges must be > 0 (m), got {ranges.tolist()}")
        if self.fit is not None and not isinstance(self.fit, CircleObservation):
            raise InvalidTypeError(
                f"ArcObservation.fit must be a CircleObservation or None, "
                f"got {type(self.fit).__name__}"
            )
        if not isinstance(self.circular, (bool, np.bool_)):
            raise InvalidTypeError(
                f"ArcObservation.circular must be a bool, got {type(self.circular).__name__}"
            )
        object.__setattr__(self, "circular", bool(self.circular))
        object.__setattr__(self, "angles", angles)
        object.__setattr__(self, "ranges", ranges)


@dataclass(frozen=True)
class ArcCircle:
    """Where the circle an arc is fused into lies in the state: its centre at ``column``,
    ``column + 1``; its radius at ``column + 2`` when ``radius`` is None, else the known
    ``radius`` (m)."""

    column: int
    radius: float | None = None

    @property
    def state_index(self) -> NDArray[np.intp]:
        """The pose's and the circle's state indices (5 or 6,)."""
        size = 3 if self.radius is None else 2
        return np.r_[np.arange(_POSE), self.column + np.arange(size)].astype(np.intp)

    def circle(self, state: FloatArray) -> FloatArray:
        """``(c_x, c_y, R)`` (3,) of this circle in ``state``."""
        c = self.column
        R = state[c + 2] if self.radius is None else self.radius
        return np.array([state[c], state[c + 1], R])


def _measure(
    state: FloatArray, where: ArcCircle, angles: FloatArray, mount_x_m: float
) -> tuple[NDArray[np.bool_], FloatArray, FloatArray] | None:
    """For beams at ``angles`` (n,) (rad, robot frame) of a scanner ``mount_x_m`` ahead of the
    robot origin: those ``used`` (n,), their predicted ranges (k,) and ``H`` (k, 5 or 6) on
    :attr:`ArcCircle.state_index`; None when fewer than three beams meet the circle away from
    its tangents."""
    x, y, theta = state[:_POSE]
    origin = np.array([x + mount_x_m * np.cos(theta), y + mount_x_m * np.sin(theta)])
    arc = measure_arc(where.circle(state), state[:2], origin, theta + angles)
    if arc is None:
        return None
    H_circle = arc.H_circle if where.radius is None else arc.H_circle[:, :2]
    return arc.used, arc.ranges, np.hstack([arc.H_pose, H_circle])


def arc_cost(
    mu: FloatArray,
    sigma: FloatArray,
    where: ArcCircle,
    arc: ArcObservation,
    mount_x_m: float,
    range_sigma_m: float,
    gate_probability: float,
) -> float:
    """The arc's normalised innovation squared on the circle over its gate (module docstring;
    in the gate: <= 1); inf when fewer than three beams meet the circle."""
    model = _measure(mu, where, arc.angles, mount_x_m)
    if model is None:
        return float(np.inf)
    used, ranges, H = model
    Q = range_sigma_m**2 * np.eye(len(ranges))
    S = innovation_covariance(sigma, H, Q, where.state_index)
    d2 = float(mahalanobis_squared(arc.ranges[used] - ranges, S))
    return d2 / _gate(gate_probability, len(ranges))


def fuse_arc(
    mu: FloatArray,
    sigma: FloatArray,
    where: ArcCircle,
    arc: ArcObservation,
    mount_x_m: float,
    range_sigma_m: float,
) -> tuple[FloatArray, FloatArray] | None:
    """The state ``mu`` (n,) and covariance ``sigma`` (n, n) after fusing the arc into the
    circle (module docstring), new arrays with the heading wrapped; None when fewer than three
    beams meet the circle at the prior. Bounds on the result (a radius) are the caller's."""
    index = where.state_index
    model = _measure(mu, where, arc.angles, mount_x_m)
    if model is None:
        return None
    used = model[0]
    angles, z = arc.angles[used], arc.ranges[used]
    Q = range_sigma_m**2 * np.eye(len(z))
    prior, at = mu[index], mu  # the prior and the linearisation point
    for iteration in range(ITERATIONS):
        _, ranges, H = model
        back = prior - at[index]  # iterated EKF: the innovation taken against the prior
        back[2] = wrap_angle(back[2])
        new_mu, new_sigma = joseph_update(mu, sigma, z - ranges - H @ back, H, Q, index)
        if iteration == ITERATIONS - 1:
            break
        step = new_mu - at
        for _ in range(STEP_HALVINGS + 1):
            candidate = _measure(at + step, where, angles, mount_x_m)
            if candidate is not None and candidate[0].all():
                break
            step = 0.5 * step
        else:
            break  # every halved step grazes a chosen beam: keep this iteration's estimate
        at, model = at + step, candidate
    new_mu[2] = wrap_angle(new_mu[2])
    return new_mu, new_sigma


def checked_arcs(arcs: object) -> list[ArcObservation]:
    """``arcs`` as a list, after checking it is a sequence of ArcObservation."""
    if isinstance(arcs, ArcObservation) or not isinstance(arcs, Sequence):
        raise InvalidTypeError(
            f"arcs must be a sequence of ArcObservation, got {type(arcs).__name__}"
        )
    for i, arc in enumerate(arcs):
        if not isinstance(arc, ArcObservation):
            raise InvalidTypeError(f"arcs[{i}] must be an ArcObservation, got {type(arc).__name__}")
    return list(arcs)


@lru_cache(maxsize=256)
def _gate(probability: float, beams: int) -> float:
    """The chi-square quantile of ``probability`` with ``beams`` degrees of freedom."""
    return chi2_threshold(probability, beams)
