"""Laser scan segmentation (seed 001 §5.4.3 breakpoints, §4.3 scale-space) and TLS line fits,
against a scan built analytically from ray/line and ray/circle intersections."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest
from numpy.typing import NDArray

from perception.circles.lines import LineFit, fit_line_tls, orthogonal_residuals
from perception.circles.segmentation import (
    BreakpointConfig,
    ScaleSpaceConfig,
    Segment,
    segment_breakpoints,
    segment_scale_space,
)
from perception.geometry import FloatArray
from perception.sensor_models import LaserModel

LASER = LaserModel()  # seed 001: 180 beams over 180°, sigma 0.02 m
ANGLES = LASER.beam_angles()
WALL_X = 3.0  # a wall across the scan, x = 3 m ...
WALL_Y = ((-2.5, 0.8), (1.4, 2.5))  # ... in two pieces: a doorway with nothing behind it
COLUMNS = (((1.6, -0.7), 0.15), ((2.0, 0.15), 0.12))  # (centre, radius), ~10 and ~7 beams
POLE = ((1.18, -0.219), 0.02)  # 2 beams (at -11° and -10°): shorter than min_points
Segmenter = Callable[..., list[Segment]]
METHODS: dict[str, Segmenter] = {
    "breakpoints": segment_breakpoints,
    "scale_space": segment_scale_space,
}


def ray_wall(phi: FloatArray, x0: float, y_lo: float, y_hi: float) -> FloatArray:
    """Ranges at which rays at angles ``phi`` meet the segment x = x0, y in [y_lo, y_hi]."""
    with np.errstate(divide="ignore"):
        r = np.where(np.cos(phi) > 0.0, x0 / np.cos(phi), np.inf)
    return np.where((r * np.sin(phi) >= y_lo) & (r * np.sin(phi) <= y_hi), r, np.inf)


def ray_circle(phi: FloatArray, centre: tuple[float, float], R: float) -> FloatArray:
    """Ranges at which rays at angles ``phi`` first meet the circle: the smaller root of
    ``|r u - c|^2 = R^2``, ``r = c.u - sqrt((c.u)^2 - |c|^2 + R^2)``."""
    b = centre[0] * np.cos(phi) + centre[1] * np.sin(phi)
    disc = b**2 - (centre[0] ** 2 + centre[1] ** 2 - R**2)
    root = np.sqrt(np.where(disc >= 0.0, disc, 0.0))
    return np.where((disc >= 0.0) & (b > 0.0), b - root, np.inf)


def scene(noise_std: float = 0.0, seed: int = 0) -> tuple[FloatArray, NDArray[np.intp]]:
    """Ranges (180,) of the scene (NaN for no return) and the object each beam sees (-1 none:
    0, 1 wall pieces, 2, 3 columns, 4 the pole)."""
    hits = np.stack(
        [ray_wall(ANGLES, WALL_X, *ys) for ys in WALL_Y]
        + [ray_circle(ANGLES, c, R) for c, R in (*COLUMNS, POLE)]
    )
    label = np.argmin(hits, axis=0)
    r = hits.min(axis=0)
    label[~np.isfinite(r)] = -1
    noise = noise_std * np.random.default_rng(seed).standard_normal(r.size)
    return np.where(np.isfinite(r), r + noise, np.nan), label


def expected_segments(label: NDArray[np.intp], min_points: int = 5) -> list[tuple[int, int]]:
    """``(start, stop)`` of each run of beams on one object, at least ``min_points`` long."""
    bounds = np.flatnonzero(np.diff(label) != 0) + 1
    starts, stops = np.r_[0, bounds], np.r_[bounds, label.size]
    return [
        (int(a), int(b))
        for a, b in zip(starts, stops, strict=True)
        if label[a] >= 0 and b - a >= min_points
    ]


def spans(segments: list[Segment]) -> list[tuple[int, int]]:
    return [(s.start, s.stop) for s in segments]


def assert_spans_close(found: list[Segment], expected: list[tuple[int, int]]) -> None:
    assert len(found) == len(expected), (spans(found), expected)
    np.testing.assert_allclose(np.array(spans(found)), np.array(expected), atol=1)


@pytest.mark.parametrize("noise_std", [0.0, LASER.range_noise_std_m])
@pytest.mark.parametrize("method", METHODS)
def test_both_methods_find_the_objects_of_a_synthetic_scan(method: str, noise_std: float) -> None:
    ranges, label = scene(noise_std, seed=1)
    expected = expected_segments(label)
    # right wall, column, wall, (pole dropped), wall, column, wall, doorway, wall
    assert [label[a] for a, _ in expected] == [0, 2, 0, 0, 3, 0, 1]
    found = METHODS[method](ANGLES, ranges)
    assert_spans_close(found, expected)
    if noise_std == 0.0:
        assert spans(found) == expected
    for s in found:
        assert len(s) == s.stop - s.start >= 5
        assert np.isfinite(s.ranges).all()  # no beam without a return inside a segment
        np.testing.assert_array_equal(s.angles, ANGLES[s.start : s.stop])
        np.testing.assert_array_equal(s.ranges, ranges[s.start : s.stop])
        np.testing.assert_allclose(
            s.points, s.ranges[:, None] * np.c_[np.cos(s.angles), np.sin(s.angles)]
        )
        assert not s.points.flags.writeable


@pytest.mark.parametrize("method", METHODS)
def test_short_segments_are_dropped_and_kept_with_a_lower_minimum(method: str) -> None:
    ranges, label = scene()
    pole = np.flatnonzero(label == 4)
    assert pole.size == 2
    config_type = BreakpointConfig if method == "breakpoints" else ScaleSpaceConfig
    found = METHODS[method](ANGLES, ranges, config_type(min_points=pole.size))
    assert spans(found) == expected_segments(label, min_points=pole.size)
    assert (int(pole[0]), int(pole[-1]) + 1) in spans(found)


@pytest.mark.parametrize("method", METHODS)
def test_inf_and_max_range_read_as_no_return(method: str) -> None:
    ranges, _ = scene()
    expected = segment_breakpoints(ANGLES, ranges)
    as_inf = np.where(np.isnan(ranges), np.inf, ranges)
    assert spans(METHODS[method](ANGLES, as_inf)) == spans(expected)
    as_max = np.where(np.isnan(ranges), LASER.max_range_m, ranges)
    config_type = BreakpointConfig if method == "breakpoints" else ScaleSpaceConfig
    found = METHODS[method](ANGLES, as_max, config_type(max_range_m=LASER.max_range_m))
    assert spans(found) == spans(expected)
    # without max_range_m the 10 m readings are a far surface of their own
    assert len(METHODS[method](ANGLES, as_max)) > len(expected)


def test_scale_space_keeps_a_grazing_wall_whole() -> None:
    # A wall x = 1 seen at 45° to 80° incidence: its range grows by up to 0.5 m a beam.
    phi = np.deg2rad(np.arange(45.0, 81.0))
    ranges = 1.0 / np.cos(phi)
    assert np.abs(np.diff(ranges)).max() > 0.5
    assert spans(segment_breakpoints(phi, ranges)) == [(0, 27)]  # the rest in short pieces
    assert spans(segment_scale_space(phi, ranges)) == [(0, phi.size)]


@pytest.mark.parametrize("seed", range(5))
def test_scale_space_ignores_a_single_outlier(seed: int) -> None:
    # One beam 0.3 m off on a noisy wall 3 m away (the seed's "big interference"): two jumps
    # that split the wall for the derivative test, but fade out at coarse scales.
    phi = np.deg2rad(np.arange(-30.0, 31.0))
    rng = np.random.default_rng(seed)
    ranges = 3.0 / np.cos(phi) + LASER.range_noise_std_m * rng.standard_normal(phi.size)
    ranges[30] += 0.3
    assert spans(segment_breakpoints(phi, ranges)) == [(0, 30), (31, 61)]
    assert spans(segment_scale_space(phi, ranges)) == [(0, 61)]


def test_scale_space_keeps_two_jumps_that_merge_at_coarse_scales() -> None:
    # A staircase, 3 m, 2 m for 5 beams, 1.7 m: from 2 beams on the two jumps make one
    # feature; both link to it, so both stay breakpoints.
    ranges = np.r_[np.full(30, 3.0), np.full(5, 2.0), np.full(30, 1.7)]
    angles = np.deg2rad(np.arange(ranges.size, dtype=float))
    assert spans(segment_scale_space(angles, ranges)) == [(0, 30), (30, 35), (35, 65)]
    assert spans(segment_breakpoints(angles, ranges)) == [(0, 30), (30, 35), (35, 65)]


@pytest.mark.parametrize("method", METHODS)
def test_degenerate_scans(method: str) -> None:
    segment = METHODS[method]
    assert segment([], []) == []
    assert segment([0.0], [1.0]) == []
    assert segment(ANGLES, np.full(ANGLES.size, np.nan)) == []
    whole = segment(ANGLES[:5], [2.0] * 5)
    assert spans(whole) == [(0, 5)]


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize(
    ("angles", "ranges", "error", "match"),
    [
        (ANGLES, np.ones(179), ValueError, r"\.ranges must have the shape of angles \(180,\)"),
        (ANGLES[::-1], np.ones(180), ValueError, r"\.angles must be strictly increasing"),
        (np.r_[np.nan, ANGLES[1:]], np.ones(180), ValueError, r"\.angles must be finite"),
        (
            ANGLES,
            np.r_[0.0, np.ones(179)],
            ValueError,
            r"\.ranges must be > 0.*seed 001's 0 to NaN first.*beams \[0\]",
        ),
        (ANGLES, np.r_[np.ones(179), -np.inf], ValueError, r"\.ranges must be > 0.*\[179\]"),
        (ANGLES, np.ones((180, 1)), ValueError, r"\.ranges must be a 1-D array"),
        (ANGLES, ["far"] * 180, TypeError, r"\.ranges must be a 1-D array of numbers"),
    ],
)
def test_bad_scans_raise(method: str, angles: Any, ranges: Any, error: type, match: str) -> None:
    with pytest.raises(error, match=f"^segment_{method}{match}"):
        METHODS[method](angles, ranges)


@pytest.mark.parametrize(
    ("make", "error", "match"),
    [
        (lambda: BreakpointConfig(jump_threshold_m=0.0), ValueError, "jump_threshold_m must"),
        (lambda: BreakpointConfig(jump_threshold_m=math.nan), ValueError, "got nan"),
        (lambda: BreakpointConfig(min_points=1), ValueError, r"min_points must be an int >= 2"),
        (lambda: BreakpointConfig(min_points=5.0), TypeError, r"min_points must be an int"),  # type: ignore[arg-type]
        (lambda: BreakpointConfig(max_range_m=-1.0), ValueError, "max_range_m must"),
        (lambda: ScaleSpaceConfig(scales_beams=()), TypeError, "non-empty tuple"),
        (lambda: ScaleSpaceConfig(scales_beams=[1.0]), TypeError, "got list"),  # type: ignore[arg-type]
        (lambda: ScaleSpaceConfig(scales_beams=(1.0, 0.0)), ValueError, r"scales_beams\[1\]"),
        (lambda: ScaleSpaceConfig(scales_beams=(2.0, 1.0)), ValueError, "strictly increasing"),
        (lambda: ScaleSpaceConfig(jump_threshold_m=-0.1), ValueError, "ScaleSpaceConfig.jump"),
        (lambda: ScaleSpaceConfig(min_points=True), TypeError, "ScaleSpaceConfig.min_points"),
    ],
)
def test_bad_configs_raise(make: Callable[[], object], error: type, match: str) -> None:
    with pytest.raises(error, match=match):
        make()


def test_a_config_of_the_wrong_method_raises() -> None:
    with pytest.raises(TypeError, match="config must be a BreakpointConfig, got ScaleSpace"):
        segment_breakpoints(ANGLES, np.ones(180), ScaleSpaceConfig())  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="config must be a ScaleSpaceConfig, got Breakpoint"):
        segment_scale_space(ANGLES, np.ones(180), BreakpointConfig())  # type: ignore[arg-type]


# --- total least squares lines ------------------------------------------------------------


def line_points(alpha: float, d: float, t: FloatArray) -> FloatArray:
    """Points ``d n + t_i n_perp`` on the line of normal angle ``alpha`` and distance ``d``."""
    n = np.array([math.cos(alpha), math.sin(alpha)])
    return d * n + t[:, None] * np.array([-n[1], n[0]])


def assert_same_line(fit: LineFit, alpha: float, d: float) -> None:
    assert fit.distance == pytest.approx(d, abs=1e-12)
    # the normal's angle up to 2 pi (and up to pi for a line through the origin)
    period = math.pi if d == 0.0 else 2.0 * math.pi
    assert math.remainder(fit.angle - alpha, period) == pytest.approx(0.0, abs=1e-12)
    assert -math.pi <= fit.angle < math.pi
    np.testing.assert_allclose(fit.direction, [-math.sin(fit.angle), math.cos(fit.angle)])
    assert fit.sse == pytest.approx(0.0, abs=1e-24)
    assert fit.rms_residual == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize(
    ("alpha", "d"),
    [
        (0.0, 2.0),  # vertical line x = 2
        (math.pi, 2.0),  # vertical line x = -2
        (math.pi / 2, 1.5),  # horizontal y = 1.5
        (-math.pi / 2, 0.5),  # horizontal y = -0.5
        (0.3, 3.0),
        (2.5, 0.7),
        (-2.0, 4.0),
        (1.1, 0.0),  # through the origin
    ],
)
def test_tls_is_exact_on_collinear_points(alpha: float, d: float) -> None:
    t = np.array([-1.3, -0.2, 0.0, 0.4, 2.2])
    points = line_points(alpha, d, t)
    fit = fit_line_tls(points)
    assert_same_line(fit, alpha, d)
    assert fit.n_points == 5
    np.testing.assert_allclose(fit.point, points.mean(axis=0), atol=1e-15)
    np.testing.assert_allclose(
        orthogonal_residuals(points, fit.angle, fit.distance), 0.0, atol=1e-12
    )
    if d > 0.0:  # t grows along the direction, and so does the bearing: scan order
        assert (np.diff(points @ fit.direction) > 0.0).all()
        assert (np.diff(np.unwrap(np.arctan2(points[:, 1], points[:, 0]))) > 0.0).all()
    assert_same_line(fit_line_tls(points[[0, -1]]), alpha, d)  # two points suffice


def test_tls_fits_a_segment_of_the_scene_wall() -> None:
    ranges, _ = scene()
    wall = max(segment_breakpoints(ANGLES, ranges), key=len)
    fit = fit_line_tls(wall.points)
    assert_same_line(fit, 0.0, WALL_X)
    # noisy: close to the wall, and the minimum of the sum of squared residuals
    noisy = scene(LASER.range_noise_std_m, seed=3)[0][wall.start : wall.stop]
    points = noisy[:, None] * np.c_[np.cos(wall.angles), np.sin(wall.angles)]
    fit = fit_line_tls(points)
    assert abs(fit.angle) < 0.06 and abs(fit.point[0] - WALL_X) < 0.02
    assert 0.005 < fit.rms_residual < 0.04
    u = points - points.mean(axis=0)
    eigenvalues, eigenvectors = np.linalg.eigh(u.T @ u)
    assert fit.sse == pytest.approx(eigenvalues[0], rel=1e-9)
    assert abs(fit.direction @ eigenvectors[:, 1]) == pytest.approx(1.0, abs=1e-12)
    for delta in (-1e-3, 1e-3):  # turning the line about the centroid costs residual
        alpha = fit.angle + delta
        d = float(fit.point @ np.array([math.cos(alpha), math.sin(alpha)]))
        turned = orthogonal_residuals(points, alpha, d)
        assert turned @ turned > fit.sse


def test_orthogonal_residuals_are_the_signed_distances() -> None:
    alpha, d = 0.8, 2.0
    t = np.linspace(-3.0, 3.0, 7)
    offsets = np.array([0.5, -0.25, 0.0, 1.0, -3.0, 0.1, 2.5])  # along the normal
    n = np.array([math.cos(alpha), math.sin(alpha)])
    points = line_points(alpha, d, t) + offsets[:, None] * n
    np.testing.assert_allclose(orthogonal_residuals(points, alpha, d), offsets, atol=1e-12)
    # the origin lies d on the near side; a vertical line x = 1 and the points' x - 1
    assert orthogonal_residuals([[0.0, 0.0]], alpha, d) == pytest.approx([-d])
    xy = np.array([[3.0, -7.0], [-1.0, 2.0], [1.0, 0.0]])
    np.testing.assert_allclose(orthogonal_residuals(xy, 0.0, 1.0), xy[:, 0] - 1.0)
    fit = fit_line_tls(points)
    residuals = orthogonal_residuals(points, fit.angle, fit.distance)
    assert fit.sse == pytest.approx(residuals @ residuals)
    assert fit.rms_residual == pytest.approx(math.sqrt(np.mean(residuals**2)))
    assert orthogonal_residuals(np.empty((0, 2)), alpha, d).shape == (0,)


@pytest.mark.parametrize(
    ("points", "error", "match"),
    [
        ([[1.0, 2.0]], ValueError, r"fit_line_tls.points must have shape \(N, 2\) with N >= 2"),
        ([[1.0, 2.0, 3.0]] * 3, ValueError, r"shape \(N, 2\).*got shape \(3, 3\)"),
        (
            [[1.0, 2.0], [np.nan, 1.0], [2.0, 2.0]],
            ValueError,
            r"must be finite, got NaN or infinity in rows \[1\]",
        ),
        ([[1.0, 2.0]] * 4, ValueError, "must not all be equal"),
        ([["a", "b"], ["c", "d"]], TypeError, "must be an \\(N, 2\\) array of numbers"),
    ],
)
def test_bad_line_points_raise(points: Any, error: type, match: str) -> None:
    with pytest.raises(error, match=match):
        fit_line_tls(points)


def test_bad_residual_arguments_raise() -> None:
    with pytest.raises(ValueError, match=r"orthogonal_residuals.angle must be finite, got nan"):
        orthogonal_residuals([[0.0, 0.0]], math.nan, 1.0)
    with pytest.raises(TypeError, match=r"orthogonal_residuals.distance must be a real number"):
        orthogonal_residuals([[0.0, 0.0]], 0.0, "1")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"orthogonal_residuals.points must be finite"):
        orthogonal_residuals([[0.0, np.inf]], 0.0, 1.0)
