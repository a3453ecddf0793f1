"""The polar circle model of seed 001 (§3.1, eqs. 3.2-3.3, Jacobian 3.6).

A circle seen from the sensor at the origin is ``(rho, theta, R)``: the distance (m) and angle
(rad, counter-clockwise from the sensor's x axis) of its centre, and its radius (m). A ray at
angle ``phi`` meets it at the ranges (eq. 3.2, with the square on the cosine a typo of the
conversion: the law of cosines gives it without)::

    r(phi) = rho cos(phi - theta) -+ sqrt(R^2 - rho^2 sin^2(phi - theta))

the minus sign for the near, convex side the laser sees, the plus sign for the far, concave
side. The rays that meet a circle not containing the origin lie within ``alpha = asin(R / rho)``
of ``theta`` (eq. 3.3).

The Jacobian here is derived afresh from eq. 3.2; the seed's eq. 3.6 prints the derivative in
theta with a wrong sign on its first term and loses a factor rho on its second (tests check
this one against finite differences).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from perception.geometry import FloatArray, wrap_angle
from perception.validation import check_choice, check_finite, check_positive, finite_vector

Branch = Literal["convex", "concave"]
BRANCHES: tuple[Branch, ...] = ("convex", "concave")


@dataclass(frozen=True)
class PolarCircle:
    """A circle in the sensor's polar frame: centre at distance ``rho`` (m) and angle ``theta``
    (rad, wrapped to [-pi, pi)), radius ``R`` (m). The origin lies outside it (``R < rho``)."""

    rho: float
    theta: float
    R: float

    def __post_init__(self) -> None:
        check_positive("PolarCircle", "rho", self.rho)
        check_finite("PolarCircle", "theta", self.theta)
        check_positive("PolarCircle", "R", self.R)
        if self.rho <= self.R:
            raise ValueError(
                f"PolarCircle.R must be below rho (the sensor outside the circle), "
                f"got R={self.R!r}, rho={self.rho!r}"
            )
        object.__setattr__(self, "theta", float(wrap_angle(self.theta)))

    @classmethod
    def from_centre(cls, centre: ArrayLike, R: float) -> PolarCircle:
        """The circle of centre ``(x, y)`` (m, sensor frame) and radius ``R`` (m)."""
        x, y = np.asarray(centre, dtype=np.float64)
        return cls(float(np.hypot(x, y)), float(np.arctan2(y, x)), float(R))

    @property
    def centre(self) -> FloatArray:
        """The centre (2,) (m, sensor frame)."""
        return self.rho * np.array([np.cos(self.theta), np.sin(self.theta)])

    @property
    def vector(self) -> FloatArray:
        """``(rho, theta, R)`` (3,)."""
        return np.array([self.rho, self.theta, self.R])

    @property
    def half_angle(self) -> float:
        """``alpha = asin(R / rho)`` (rad): the visible rays lie within it of ``theta``."""
        return float(np.arcsin(self.R / self.rho))


def _offset_terms(
    phi: ArrayLike, rho: float, theta: float, R: float
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """``cos(phi - theta)``, ``sin(phi - theta)`` and ``sqrt(R^2 - rho^2 sin^2(phi - theta))``
    (NaN where the ray misses the circle), each shaped like ``phi``."""
    delta = np.asarray(phi, dtype=np.float64) - theta
    c, s = np.cos(delta), np.sin(delta)
    inside = R**2 - (rho * s) ** 2
    root = np.sqrt(np.where(inside >= 0.0, inside, np.nan))
    return c, s, root


def polar_range(
    phi: ArrayLike, rho: float, theta: float, R: float, branch: Branch = "convex"
) -> FloatArray:
    """Eq. 3.2: the range (m) at which rays at angles ``phi`` (rad, any shape) meet the circle
    ``(rho, theta, R)`` on ``branch``; NaN for rays that miss it. Rays pointing away from the
    circle (``|phi - theta| > pi/2``) miss it too."""
    check_choice("polar_range", "branch", branch, BRANCHES)
    c, _, root = _offset_terms(phi, rho, theta, R)
    r = rho * c - root if branch == "convex" else rho * c + root
    return np.where(c > 0.0, r, np.nan)


def polar_jacobian(
    phi: ArrayLike, rho: float, theta: float, R: float, branch: Branch = "convex"
) -> FloatArray:
    """The derivatives (N, 3) of :func:`polar_range` at the N angles ``phi`` (rad) in
    ``(rho, theta, R)``; NaN rows for rays that miss the circle (infinite at its tangents)."""
    check_choice("polar_jacobian", "branch", branch, BRANCHES)
    c, s, root = _offset_terms(np.ravel(phi), rho, theta, R)
    sign = -1.0 if branch == "convex" else 1.0
    with np.errstate(divide="ignore", invalid="ignore"):
        d_rho = c + sign * (-rho * s**2 / root)
        d_theta = rho * s + sign * (rho**2 * s * c / root)
        d_R = sign * R / root
    jac = np.column_stack([d_rho, d_theta, d_R])
    jac[c <= 0.0] = np.nan
    return jac


# beams whose sqrt(R^2 - rho^2 sin^2) is below this fraction of R (within about 2 % of the
# chord of a tangent) are left out of a range measurement: the range's slope there is unbounded
TANGENT_ROOT = 0.2


@dataclass(frozen=True, eq=False)
class ArcMeasurement:
    """The ranges a circle predicts for the beams of a scan segment, and their Jacobians.

    ``used`` (n,) bool: the beams that meet the circle away from its tangents (at least
    :data:`TANGENT_ROOT` of ``R`` inside them); ``ranges`` (k,) (m) their predicted ranges
    (eq. 3.2, convex side); ``H_circle`` (k, 3) their derivatives in the circle ``(c_x, c_y,
    R)`` and ``H_pose`` (k, 3) in the robot pose ``(x, y, theta)`` (all in one world frame).
    """

    used: NDArray[np.bool_]
    ranges: FloatArray
    H_circle: FloatArray
    H_pose: FloatArray


def measure_arc(
    circle: ArrayLike, robot_xy: ArrayLike, origin: ArrayLike, beta: ArrayLike
) -> ArcMeasurement | None:
    """The :class:`ArcMeasurement` of ``circle`` (3,) ``(c_x, c_y, R)`` (m, world frame) for
    beams leaving the scanner at ``origin`` (2,) (m, world) along the world directions ``beta``
    (n,) (rad), the scanner mounted on a robot whose origin is at ``robot_xy`` (2,) (m, world):
    turning the robot turns every beam and swings the scanner about the robot origin.

    None when the circle holds the scanner (``R >= rho``), has ``R <= 0``, or fewer than three
    beams are used. ValueError, naming the argument, for one that is not finite or of the
    wrong shape.
    """
    cx, cy, radius = finite_vector(circle, "circle", 3)
    o = finite_vector(origin, "origin", 2)
    finite_vector(robot_xy, "robot_xy", 2)
    beams = np.asarray(beta, dtype=np.float64)
    if beams.ndim != 1 or not np.isfinite(beams).all():
        raise ValueError(f"beta must be a finite (n,) array, got {beams.tolist()}")
    offset = np.array([cx, cy]) - o
    rho = float(np.hypot(*offset))
    if not 0.0 < radius < rho:
        return None
    phi = float(np.arctan2(offset[1], offset[0]))
    h = polar_range(beams, rho, phi, radius)
    root = rho * np.cos(beams - phi) - h  # sqrt(R^2 - rho^2 sin^2), NaN where the beam misses
    used = np.isfinite(h) & (root >= TANGENT_ROOT * radius)
    if used.sum() < 3:
        return None
    d = polar_jacobian(beams[used], rho, phi, radius)  # on (rho, phi, R)
    across = np.array([-offset[1], offset[0]]) / rho**2  # d phi / d c
    d_dc = np.outer(d[:, 0], offset / rho) + np.outer(d[:, 1], across)
    mount = o - np.asarray(robot_xy, dtype=np.float64)
    # moving the robot by e moves the circle by -e relative to the scanner
    d_theta = -d[:, 1] - d_dc @ np.array([-mount[1], mount[0]])
    return ArcMeasurement(
        used=used,
        ranges=h[used],
        H_circle=np.column_stack([d_dc, d[:, 2]]),
        H_pose=np.column_stack([-d_dc, d_theta]),
    )
