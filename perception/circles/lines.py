"""Total least squares line fits to 2-D laser points (seed 001 §5.4.4: the linear segments).

A line is written in its normal form (Arras & Siegwart 1997)::

    x cos(alpha) + y sin(alpha) = d,    d >= 0,

``alpha`` (rad, in [-pi, pi)) the angle of the normal ``n = (cos alpha, sin alpha)`` that points
from the origin (the sensor) to the line, ``d`` (m) the line's distance from the origin. The
orthogonal residual of a point ``p`` is ``p . n - d``: its signed distance to the line,
positive on the side away from the origin.

The total least squares line minimises the sum of squared orthogonal residuals, unlike the
ordinary regression ``y = m x + b`` of the seed's §2.4.1 (eqs. 2.3-2.4), which measures
residuals along y, depends on the orientation of the axes and cannot fit a vertical line. It
passes through the centroid ``c`` of the points along their principal direction. With the
scatter sums ``S_xx = sum (x - c_x)^2``, ``S_yy``, ``S_xy = sum (x - c_x)(y - c_y)``, the
normal that minimises ``S_xx cos^2 + 2 S_xy sin cos + S_yy sin^2`` is at::

    alpha = atan2(-2 S_xy, S_yy - S_xx) / 2,

and the minimum, the sum of squared residuals, is the smaller eigenvalue of the scatter matrix.
The seed's linear residue of §5.4.4 (``R_linear = 0.05``) does not say whether it is a sum or
a mean; a fit reports both the sum of squared residuals and their RMS. Points in the sensor
frame: x forward, y left, metres.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from perception.geometry import FloatArray, wrap_angle
from perception.validation import check_finite, finite_points


@dataclass(frozen=True, eq=False)
class LineFit:
    """A line fitted to ``n_points`` points by total least squares.

    - ``point`` (2,) m: the centroid of the points, on the line;
    - ``direction`` (2,): unit vector along the line, the normal turned by +90°
      (``(-sin alpha, cos alpha)``), so along increasing bearing from the sensor: scan order
      for the points of a segment;
    - ``angle`` (rad, [-pi, pi)) and ``distance`` (m, >= 0): the normal form
      ``x cos(angle) + y sin(angle) = distance``. For a line through the origin (``distance``
      0) the normal's sign is arbitrary;
    - ``rms_residual`` (m): ``sqrt(sse / n_points)``, the RMS orthogonal residual;
    - ``sse`` (m^2): the sum of squared orthogonal residuals.

    The arrays are read-only.
    """

    point: FloatArray
    direction: FloatArray
    angle: float
    distance: float
    rms_residual: float
    sse: float
    n_points: int


def fit_line_tls(points: ArrayLike) -> LineFit:
    """The total least squares line through ``points`` (N, 2) (m), N >= 2 (module docstring).

    The points must be finite (drop beams with no return, NaN, first) and not all equal
    (they give no direction): ``ValueError`` otherwise, ``InvalidTypeError`` for a wrong type.
    If the points scatter equally in every direction the line's direction is arbitrary (the
    fit still returns one).
    """
    p = finite_points(points, "fit_line_tls.points", 2)
    if (p == p[0]).all():
        raise ValueError(f"fit_line_tls.points must not all be equal (no direction), got {p[0]}")
    centroid = p.mean(axis=0)
    u = p - centroid
    s_xx, s_yy, s_xy = (u[:, 0] ** 2).sum(), (u[:, 1] ** 2).sum(), (u[:, 0] * u[:, 1]).sum()
    alpha = 0.5 * math.atan2(-2.0 * s_xy, s_yy - s_xx)
    distance = centroid[0] * math.cos(alpha) + centroid[1] * math.sin(alpha)
    if distance < 0.0:  # turn the normal to point from the origin to the line
        alpha, distance = alpha + math.pi, -distance
    alpha = float(wrap_angle(alpha))
    residuals = orthogonal_residuals(p, alpha, distance)
    sse = float(residuals @ residuals)
    direction = np.array([-math.sin(alpha), math.cos(alpha)])
    for array in (centroid, direction):
        array.flags.writeable = False
    return LineFit(
        point=centroid,
        direction=direction,
        angle=alpha,
        distance=float(distance),
        rms_residual=math.sqrt(sse / len(p)),
        sse=sse,
        n_points=len(p),
    )


def orthogonal_residuals(points: ArrayLike, angle: float, distance: float) -> FloatArray:
    """Signed distances (N,) (m) of ``points`` (N, 2) (m) to the line
    ``x cos(angle) + y sin(angle) = distance``: ``p . (cos angle, sin angle) - distance``,
    positive on the side the normal points to (away from the origin when ``distance > 0``).

    ``angle`` (rad) and ``distance`` (m) must be finite, the points finite (N >= 0):
    ``ValueError`` otherwise, ``InvalidTypeError`` for a wrong type.
    """
    check_finite("orthogonal_residuals", "angle", angle)
    check_finite("orthogonal_residuals", "distance", distance)
    p = finite_points(points, "orthogonal_residuals.points")
    return p @ np.array([math.cos(angle), math.sin(angle)]) - distance
