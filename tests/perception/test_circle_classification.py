"""Line-or-circle classification, segment fusion and final circle estimation (seed 001
§5.4.4-5.4.6) on scans built analytically from ray/line and ray/circle intersections."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pytest
from numpy.typing import ArrayLike
from scipy.stats import binom

from perception.circles.classification import (
    ClassificationConfig,
    EstimationConfig,
    FusionConfig,
    Kind,
    classify_segment,
    estimate_circle,
    fuse_circles,
)
from perception.circles.fits import geometric_fit
from perception.circles.segmentation import Segment
from perception.geometry import FloatArray
from perception.validation import InvalidTypeError

ANGLES = np.radians(np.arange(180.0) - 89.5)  # 180 beams over 180°, 1° apart
SIGMA = 0.02  # m, seed 001's range noise
DRAWS = 50
RULES = ("seed", "chi_square")
# (centre, R): columns of R 0.2-0.5 m at 1.5-4 m, 9 to 14 beams. Smaller ones are beyond any
# rule at this noise and beam spacing: a column of R 0.1 m at 1 m bends its 12 points off a
# line by about the noise, and even the chi-square test rejects the line in 25 % of draws.
COLUMNS = (((1.5, -0.8), 0.2), ((2.0, 0.5), 0.25), ((2.5, 1.0), 0.3), ((4.0, 0.5), 0.5))
WALLS = (((2.5, -1.5), (2.5, 1.5)), ((1.5, -2.0), (3.5, 1.0)))  # facing and oblique


def circle_ranges(
    centre: ArrayLike, R: float, origin: ArrayLike = (0.0, 0.0), heading: float = 0.0
) -> FloatArray:
    """Ranges (180,) of the rays from a sensor at ``origin`` (m) facing ``heading`` (rad) to
    the near side of the circle; NaN where they miss it."""
    c = np.subtract(centre, origin)
    phi = ANGLES + heading
    along = c[0] * np.cos(phi) + c[1] * np.sin(phi)
    inside = R**2 - (c @ c - along**2)
    with np.errstate(invalid="ignore"):
        r = along - np.sqrt(inside)
    return np.where((inside >= 0.0) & (along > 0.0), r, np.nan)


def wall_ranges(a: tuple[float, float], b: tuple[float, float]) -> FloatArray:
    """Ranges (180,) of the rays from the origin to the wall from ``a`` to ``b``; NaN where
    they miss it: ``r u = a + s (b - a)`` with ``0 <= s <= 1``, ``r > 0``."""
    a_, d = np.asarray(a), np.subtract(b, a)
    u = np.column_stack([np.cos(ANGLES), np.sin(ANGLES)])
    det = u[:, 1] * d[0] - u[:, 0] * d[1]
    r = (a_[1] * d[0] - a_[0] * d[1]) / det
    s = (u[:, 0] * a_[1] - u[:, 1] * a_[0]) / det
    return np.where((s >= 0.0) & (s <= 1.0) & (r > 0.0), r, np.nan)


def segments(
    ranges: FloatArray,
    rng: np.random.Generator | None,
    origin: ArrayLike = (0.0, 0.0),
    heading: float = 0.0,
) -> list[Segment]:
    """The runs of finite ``ranges`` as segments, with range noise from ``rng`` (none for
    None), their points in the world frame of a sensor at ``origin`` (m) facing ``heading``
    (rad)."""
    noisy = ranges if rng is None else ranges + rng.normal(0.0, SIGMA, ranges.shape)
    hit = np.isfinite(noisy).astype(int)
    edges = np.flatnonzero(np.diff(np.concatenate([[0], hit, [0]])))
    runs = []
    for start, stop in zip(edges[::2], edges[1::2], strict=True):
        phi, r = ANGLES[start:stop], noisy[start:stop]
        world = phi + heading
        points = r[:, None] * np.column_stack([np.cos(world), np.sin(world)]) + origin
        runs.append(Segment(int(start), int(stop), phi, r, points))
    return runs


def kinds(ranges: FloatArray, rule: str, seed: int) -> list[Kind]:
    """The kind of the single segment of ``ranges`` over DRAWS noise draws."""
    rng = np.random.default_rng(seed)
    config = ClassificationConfig(rule=rule)  # type: ignore[arg-type]
    return [classify_segment(segments(ranges, rng)[0], config).kind for _ in range(DRAWS)]


# With the chi-square rule a true model is rejected with probability p <= 0.001 per segment;
# with the seed rule's 1.5 sigma threshold a wall's line of n >= 10 points with p < 0.005.
# Allowing 2 errors in 50 draws, a correct classifier fails the test with probability
# P(Binomial(50, 0.005) >= 3) < 3e-3 (fixed seeds make it deterministic anyway).
MAX_ERRORS = 2
assert binom.sf(MAX_ERRORS, DRAWS, 0.005) < 3e-3


@pytest.mark.parametrize("rule", RULES)
@pytest.mark.parametrize("wall", WALLS)
def test_a_wall_is_a_line(rule: str, wall: tuple[tuple[float, float], ...]) -> None:
    found = kinds(wall_ranges(*wall), rule, seed=1)
    assert found.count("line") >= DRAWS - MAX_ERRORS, found


@pytest.mark.parametrize("rule", RULES)
@pytest.mark.parametrize(("centre", "R"), COLUMNS)
def test_a_column_is_a_circle(rule: str, centre: tuple[float, float], R: float) -> None:
    found = kinds(circle_ranges(centre, R), rule, seed=2)
    assert found.count("circle") >= DRAWS - MAX_ERRORS, found


@pytest.mark.parametrize("rule", RULES)
def test_a_very_large_arc_is_not_a_circle(rule: str) -> None:
    found = kinds(circle_ranges((5.0, 0.0), 3.0), rule, seed=3)
    assert "circle" not in found
    assert found.count("other") >= DRAWS - MAX_ERRORS, found


def test_a_short_segment_is_other_without_fits() -> None:
    model = classify_segment(segments(circle_ranges((4.0, 0.0), 0.1), None)[0])
    assert (model.kind, model.line, model.circle) == ("other", None, None)
    assert math.isnan(model.statistic)


def occluded_column() -> tuple[list[Segment], FloatArray]:
    """A column of R 0.4 m at 2.5 m split by a pole in front, and a second column: the
    column's two segments and the second's, and the column's points all together."""
    column = circle_ranges((2.5, 0.0), 0.4)
    pole = circle_ranges((1.2, 0.0), 0.05)
    column[np.isfinite(pole)] = np.nan
    runs = segments(column, np.random.default_rng(4))
    other = segments(circle_ranges((2.0, 1.5), 0.3), np.random.default_rng(5))
    return runs + other, np.concatenate([s.points for s in runs])


@pytest.mark.parametrize("gate", ["overlap", "mahalanobis"])
def test_two_parts_of_one_column_fuse(gate: str) -> None:
    parts, column_points = occluded_column()
    assert len(parts) == 3
    fused = fuse_circles([s.points for s in parts], FusionConfig(gate=gate))  # type: ignore[arg-type]
    assert [f.members for f in fused] == [(0, 1), (2,)]
    expected = geometric_fit(column_points)
    np.testing.assert_allclose(fused[0].fit.centre, expected.centre, atol=1e-9)
    assert pytest.approx(expected.R, abs=1e-9) == fused[0].fit.R
    np.testing.assert_allclose(fused[0].fit.centre, (2.5, 0.0), atol=0.05)


def radius_errors(margin_deg: float, centre: tuple[float, float], R: float) -> FloatArray:
    """The final radius errors (m) over 400 noise draws of a column's segment (fixed seed)."""
    rng = np.random.default_rng(6)
    ranges = circle_ranges(centre, R)
    config = EstimationConfig(tangent_margin_rad=math.radians(margin_deg))
    errors = [
        estimate_circle(segments(ranges, rng)[0].points, np.zeros(2), config).R - R
        for _ in range(400)
    ]
    return np.asarray(errors)


def test_noise_free_points_give_the_true_circle_with_or_without_tangent_points() -> None:
    points = segments(circle_ranges((1.0, 0.0), 0.5), None)[0].points
    for margin in (0.0, math.radians(2.0)):
        fit = estimate_circle(points, (0.0, 0.0), EstimationConfig(tangent_margin_rad=margin))
        np.testing.assert_allclose([*fit.centre, fit.R], [1.0, 0.0, 0.5], atol=1e-9)


def test_dropping_points_near_the_tangents_does_not_reduce_the_radius_bias() -> None:
    """Measured, against the seed's claim: under range noise the geometric fit's radius is
    biased low (-12 mm here, R 0.5 m at 1 m) and dropping two beams at each tangent makes it
    worse (-20 mm, standard errors near 1 mm): the points at grazing incidence pin the arc's
    ends. (The seed dropped them for its polar Kalman filter, whose Jacobian is infinite at
    the tangents.)"""
    kept = radius_errors(0.0, (1.0, 0.0), 0.5)
    dropped = radius_errors(2.0, (1.0, 0.0), 0.5)
    assert kept.mean() < 0.0
    assert dropped.mean() < kept.mean() - 0.004


def test_arcs_from_opposite_viewpoints_fit_the_true_circle() -> None:
    centre, R = np.array([3.0, 1.0]), 0.3
    rng = np.random.default_rng(7)
    arcs, origins = [], []
    offset = np.array([1.5, 0.0])
    for origin, heading in ((centre - offset, 0.0), (centre + offset, math.pi)):
        ranges = circle_ranges(centre, R, origin, heading)
        arc = segments(ranges, rng, origin, heading)[0].points
        arcs.append(arc)
        origins.append(np.tile(origin, (len(arc), 1)))
    fit = estimate_circle(np.concatenate(arcs), np.concatenate(origins))
    np.testing.assert_allclose(fit.centre, centre, atol=0.01)
    assert pytest.approx(R, abs=0.01) == fit.R


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda: ClassificationConfig(rule="ransac"), "ClassificationConfig.rule"),
        (lambda: ClassificationConfig(sigma_m=0.0), "ClassificationConfig.sigma_m"),
        (lambda: ClassificationConfig(line_threshold_m=-1.0), "line_threshold_m"),
        (lambda: ClassificationConfig(significance=1.0), "ClassificationConfig.significance"),
        (lambda: ClassificationConfig(max_radius_m=math.inf), "max_radius_m"),
        (lambda: ClassificationConfig(min_points=3), "ClassificationConfig.min_points"),
        (lambda: FusionConfig(gate="touch"), "FusionConfig.gate"),
        (lambda: FusionConfig(sigma_m=-0.02), "FusionConfig.sigma_m"),
        (lambda: FusionConfig(significance=0.0), "FusionConfig.significance"),
        (lambda: EstimationConfig(tangent_margin_rad=-0.1), "tangent_margin_rad"),
    ],
)
def test_bad_config_fields_raise_naming_them(make: Callable[[], object], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        make()


def test_bad_config_types_raise_type_errors() -> None:
    with pytest.raises(InvalidTypeError, match="min_points"):
        ClassificationConfig(min_points=5.0)  # type: ignore[arg-type]
    with pytest.raises(InvalidTypeError, match=r"classify_segment\.config"):
        classify_segment(segments(wall_ranges(*WALLS[0]), None)[0], FusionConfig())  # type: ignore[arg-type]


def test_bad_inputs_raise_naming_the_argument() -> None:
    arc = segments(circle_ranges((1.0, 0.0), 0.5), None)[0].points
    with pytest.raises(InvalidTypeError, match=r"classify_segment\.segment"):
        classify_segment(arc)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"fuse_circles.point_sets\[1\]"):
        fuse_circles([arc, arc[:2]])
    with pytest.raises(ValueError, match=r"estimate_circle\.points must be finite"):
        estimate_circle(np.where(np.arange(len(arc))[:, None] == 3, np.nan, arc), (0.0, 0.0))
    with pytest.raises(ValueError, match=r"estimate_circle\.origins"):
        estimate_circle(arc, np.zeros((2, 2)))
    with pytest.raises(ValueError, match="origins must lie outside"):
        estimate_circle(arc, (1.0, 0.0))
    with pytest.raises(ValueError, match=r"only \d+ of \d+ points lie more than"):
        estimate_circle(arc, (0.0, 0.0), EstimationConfig(tangent_margin_rad=1.0))
