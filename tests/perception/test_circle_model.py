"""The polar circle model of seed 001 (perception.circles.model) against Cartesian geometry:
the ranges of eq. 3.2 land on the circle, the half angle of eq. 3.3 bounds the rays that meet
it, and the Jacobian matches central finite differences."""

from __future__ import annotations

import math

import numpy as np
import pytest

from perception.circles.model import BRANCHES, Branch, PolarCircle, polar_jacobian, polar_range
from perception.geometry import FloatArray
from perception.validation import InvalidTypeError

# Seed 001 §4.5's circles and a few more: near and far, small and large, every quadrant.
CIRCLES = [
    (1.5, math.pi / 2, 0.25),
    (1.41, 0.78, 0.25),
    (4.0, 1.57, 0.25),
    (0.6, -2.5, 0.5),
    (2.0, 3.0, 1.2),
    (3.0, -0.4, 0.1),
]


def _rays_inside(circle: PolarCircle, count: int = 41, margin: float = 0.95) -> FloatArray:
    """``count`` rays (rad) within ``margin`` of the half angle around ``theta``."""
    alpha = circle.half_angle
    return circle.theta + np.linspace(-margin * alpha, margin * alpha, count)


@pytest.mark.parametrize("params", CIRCLES)
def test_both_branches_lie_on_the_cartesian_circle(params: tuple[float, float, float]) -> None:
    circle = PolarCircle(*params)
    phi = _rays_inside(circle)
    ranges = {branch: polar_range(phi, *params, branch=branch) for branch in BRANCHES}
    for r in ranges.values():
        assert np.isfinite(r).all()
        points = r[:, None] * np.column_stack([np.cos(phi), np.sin(phi)])
        np.testing.assert_allclose(
            np.linalg.norm(points - circle.centre, axis=1), circle.R, rtol=0, atol=1e-12
        )
    # the convex side is the nearer one; on the central ray the two are rho -+ R
    assert (ranges["convex"] < ranges["concave"]).all()
    rho, theta, R = params
    np.testing.assert_allclose(polar_range(theta, rho, theta, R, "convex"), rho - R, rtol=1e-14)
    np.testing.assert_allclose(polar_range(theta, rho, theta, R, "concave"), rho + R, rtol=1e-14)


@pytest.mark.parametrize("params", CIRCLES)
def test_half_angle_is_that_of_the_tangent_rays(params: tuple[float, float, float]) -> None:
    circle = PolarCircle(*params)
    rho, theta, R = params
    alpha = circle.half_angle
    assert alpha == pytest.approx(math.asin(R / rho), rel=1e-15)  # eq. 3.3
    tangent_length = math.sqrt(rho**2 - R**2)
    for side in (-1.0, 1.0):
        # nudged inside by 1e-13 rad so that rounding cannot put the tangent ray outside
        phi = theta + side * (alpha - 1e-13)
        convex, concave = (float(polar_range(phi, *params, branch=b)) for b in BRANCHES)
        # at the tangent the branches meet, at the tangent length, the radius there at right
        # angles to the ray
        assert convex == pytest.approx(tangent_length, abs=1e-6)
        assert concave == pytest.approx(tangent_length, abs=1e-6)
        point = convex * np.array([math.cos(phi), math.sin(phi)])
        assert abs((point - circle.centre) @ point) < 1e-5
        assert np.isnan(polar_range(theta + side * (alpha + 1e-9), *params))


@pytest.mark.parametrize("params", CIRCLES)
@pytest.mark.parametrize("branch", BRANCHES)
def test_rays_that_miss_give_nan(params: tuple[float, float, float], branch: Branch) -> None:
    circle = PolarCircle(*params)
    alpha = circle.half_angle
    offsets = np.array([alpha + 1e-6, alpha + 0.1, math.pi / 2, 2.0, math.pi])
    phi = circle.theta + np.concatenate([offsets, -offsets])
    assert np.isnan(polar_range(phi, *params, branch=branch)).all()
    assert np.isnan(polar_jacobian(phi, *params, branch=branch)).all()


def _central_differences(
    phi: FloatArray, params: tuple[float, float, float], branch: Branch, step: float = 1e-6
) -> FloatArray:
    """Central differences (N, 3) of polar_range in (rho, theta, R)."""
    columns = []
    for k in range(3):
        dx = np.zeros(3)
        dx[k] = step
        (a, b, c), (d, e, f) = np.add(params, dx), np.subtract(params, dx)
        columns.append(
            (polar_range(phi, a, b, c, branch) - polar_range(phi, d, e, f, branch)) / (2.0 * step)
        )
    return np.column_stack(columns)


@pytest.mark.parametrize("params", CIRCLES)
@pytest.mark.parametrize("branch", BRANCHES)
def test_jacobian_matches_central_differences(
    params: tuple[float, float, float], branch: Branch
) -> None:
    circle = PolarCircle(*params)
    phi = _rays_inside(circle, margin=0.9)  # away from the tangents, where H is infinite
    jac = polar_jacobian(phi, *params, branch=branch)
    assert jac.shape == (len(phi), 3)
    np.testing.assert_allclose(jac, _central_differences(phi, params, branch), rtol=1e-6, atol=1e-7)


def test_polar_circle_round_trips_through_its_centre() -> None:
    circle = PolarCircle.from_centre([-1.0, 2.0], 0.3)
    assert circle.rho == pytest.approx(math.sqrt(5.0), rel=1e-15)
    assert circle.theta == pytest.approx(math.atan2(2.0, -1.0), rel=1e-15)
    np.testing.assert_allclose(circle.centre, [-1.0, 2.0], rtol=1e-14)
    np.testing.assert_array_equal(circle.vector, [circle.rho, circle.theta, 0.3])


@pytest.mark.parametrize(
    ("theta", "wrapped"),
    [(0.3 + 2 * math.pi, 0.3), (-1.5 * math.pi, 0.5 * math.pi), (7.0, 7.0 - 2 * math.pi)],
)
def test_polar_circle_wraps_theta(theta: float, wrapped: float) -> None:
    circle = PolarCircle(1.0, theta, 0.5)
    assert circle.theta == pytest.approx(wrapped, abs=1e-14)
    assert -math.pi <= circle.theta <= math.pi


@pytest.mark.parametrize("R", [1.0, 1.5])
def test_polar_circle_refuses_a_radius_not_below_rho(R: float) -> None:
    with pytest.raises(ValueError, match=r"PolarCircle\.R must be below rho"):
        PolarCircle(1.0, 0.0, R)


@pytest.mark.parametrize(
    ("args", "field"),
    [
        ((math.nan, 0.0, 0.5), "rho"),
        ((1.0, math.nan, 0.5), "theta"),
        ((1.0, 0.0, math.nan), "R"),
        ((math.inf, 0.0, 0.5), "rho"),
        ((1.0, math.inf, 0.5), "theta"),
        ((0.0, 0.0, 0.5), "rho"),
        ((-1.0, 0.0, 0.5), "rho"),
        ((1.0, 0.0, 0.0), "R"),
        ((1.0, 0.0, -0.5), "R"),
    ],
)
def test_polar_circle_refuses_bad_values(args: tuple[float, float, float], field: str) -> None:
    with pytest.raises(ValueError, match=f"PolarCircle.{field}"):
        PolarCircle(*args)


@pytest.mark.parametrize("args", [("1", 0.0, 0.5), (1.0, None, 0.5), (1.0, 0.0, True)])
def test_polar_circle_refuses_non_numbers(args: tuple[object, object, object]) -> None:
    with pytest.raises(InvalidTypeError, match="PolarCircle"):
        PolarCircle(*args)  # type: ignore[arg-type]


def test_bad_branch_is_refused() -> None:
    with pytest.raises(ValueError, match="branch"):
        polar_range(0.0, 1.0, 0.0, 0.5, branch="near")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="branch"):
        polar_jacobian(0.0, 1.0, 0.0, 0.5, branch="near")  # type: ignore[arg-type]
