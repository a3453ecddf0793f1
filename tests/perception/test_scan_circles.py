"""The circles of one laser scan (perception.circles.scan_circles) against synthetic scans
traced in closed form (ray/circle and ray/line intersections) with seed 001's laser: true
centres and radii, the first-order covariance of a fit to range noise, and hand-made
segments for :func:`stands_clear`."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import pytest
from numpy.typing import NDArray
from scipy.stats import chi2

from perception.circles.classification import ClassificationConfig
from perception.circles.fits import kcr_covariance
from perception.circles.scan_circles import ScanCirclesConfig, scan_circles, stands_clear
from perception.circles.segmentation import (
    BreakpointConfig,
    ScaleSpaceConfig,
    Segment,
    segment_breakpoints,
)
from perception.geometry import FloatArray
from perception.sensor_models import LaserModel
from perception.slam.circle_slam import CircleObservation
from perception.validation import InvalidTypeError

LASER = LaserModel()  # seed 001: 180 beams over 180°, 10 m, sigma 0.02 m
ANGLES = LASER.beam_angles()
SIGMA_M = 0.02
MOUNT_X_M = 0.018  # the Pioneer's laser ahead of its axle
WALL = (1.0, 0.0, 4.0)  # a wall across the scanner's view, x = 4 m (laser frame)
COLUMN = (2.0, 0.5, 0.3)  # (x, y, R) (m, laser frame): a column in front of the wall
CONFIG = ScanCirclesConfig()

Circle = tuple[float, float, float]
Wall = tuple[float, float, float]


def trace(
    circles: Sequence[Circle] = (),
    walls: Sequence[Wall] = (),
    max_range: float = LASER.max_range_m,
) -> FloatArray:
    """Noiseless ranges (B,) (m, NaN for no return) of the beams from the laser (origin of the
    laser frame) to the nearest of ``circles`` ``(x, y, R)`` and ``walls`` ``(n_x, n_y, c)``
    (the lines ``n . p = c``, unit normal ``n``, ``c > 0``)."""
    d = np.column_stack([np.cos(ANGLES), np.sin(ANGLES)])
    ranges = np.full(len(ANGLES), np.inf)
    for nx, ny, c in walls:
        towards = d @ np.array([nx, ny])
        ahead = towards > 0.0
        ranges[ahead] = np.minimum(ranges[ahead], c / towards[ahead])
    for cx, cy, R in circles:
        b = d @ np.array([cx, cy])  # the ray's closest approach to the centre, along it
        disc = b**2 - (cx**2 + cy**2 - R**2)
        t = b - np.sqrt(np.maximum(disc, 0.0))  # the near intersection
        ranges = np.where((disc >= 0.0) & (t > 0.0), np.minimum(ranges, t), ranges)
    return np.where(ranges <= max_range, ranges, np.nan)


def beams_on(circle: Circle) -> NDArray[np.bool_]:
    """Mask (B,) of the beams that hit ``circle`` alone in an empty scene."""
    return np.isfinite(trace([circle]))


def robot_centre(circle: Circle, mount_x_m: float = MOUNT_X_M) -> FloatArray:
    """The circle's centre (2,) in the robot frame: the laser sits ``mount_x_m`` ahead."""
    return np.array([circle[0] + mount_x_m, circle[1]])


def first_order_covariance(circle: Circle, sigma: float) -> FloatArray:
    """The first-order covariance (3, 3) of the geometric fit to the beams on ``circle`` when
    each range has noise ``sigma`` along its beam.

    The residual of point ``i`` moves by the noise's component along the circle's normal
    ``u_i``, ``sigma cos(a_i)`` (``a_i`` the incidence); least squares ``(U^T U)^-1 U^T e``
    then has the sandwich covariance ``sigma^2 A (U^T diag(cos^2 a) U) A``, ``A = (U^T U)^-1``,
    with rows ``U_i = (cos phi_i, sin phi_i, 1)`` (the KCR bound when every ``a_i = 0``).
    """
    hit = beams_on(circle)
    ranges = trace([circle])[hit]
    rays = np.column_stack([np.cos(ANGLES[hit]), np.sin(ANGLES[hit])])
    normals = ranges[:, None] * rays - np.array(circle[:2])
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    U = np.column_stack([normals, np.ones(len(normals))])
    cos_incidence = np.abs(np.sum(rays * normals, axis=1))
    A = np.linalg.inv(U.T @ U)
    return np.asarray(sigma**2 * A @ (U.T @ (cos_incidence[:, None] ** 2 * U)) @ A)


def true_angles(circle: Circle) -> FloatArray:
    """The angles (around the true centre) of the true points the beams hit on ``circle``."""
    hit = beams_on(circle)
    ranges = trace([circle])[hit]
    x = ranges * np.cos(ANGLES[hit]) - circle[0]
    y = ranges * np.sin(ANGLES[hit]) - circle[1]
    return np.arctan2(y, x)


def make_segment(ranges: FloatArray, start: int, stop: int) -> Segment:
    """Beams ``start`` to ``stop - 1`` of ``ranges`` as a Segment (evenly spaced angles)."""
    angles = np.radians(np.arange(len(ranges), dtype=np.float64))[start:stop]
    r = np.asarray(ranges[start:stop], dtype=np.float64)
    return Segment(
        start, stop, angles, r, r[:, None] * np.column_stack([np.cos(angles), np.sin(angles)])
    )


# ---------------------------------------------------------------------------------------------
# stands_clear on hand-made segments


@pytest.mark.parametrize(
    ("ranges", "clear"),
    [
        ([5.0, 2.0, 2.0, 2.0, 5.0], True),  # farther beyond both ends by far more than the jump
        ([np.nan, 2.0, 2.0, 2.0, np.nan], True),  # nothing beside it
        ([np.inf, 2.0, 2.0, 2.0, 3.0], True),  # inf: no return
        ([1.0, 2.0, 2.0, 2.0, 5.0], False),  # something nearer on its right may hide part of it
        ([5.0, 2.0, 2.0, 2.0, 1.5], False),  # ... or on its left
        ([2.1, 2.0, 2.0, 2.0, 5.0], False),  # farther by 0.1 m only: it touches its neighbour
        ([5.0, 2.0, 2.0, 3.0, 3.1], False),  # the left end (3.0) has a neighbour 0.1 m behind
        ([2.4, 2.0, 2.0, 3.0, 3.4], True),  # each end compared with its own neighbour
    ],
)
def test_stands_clear_compares_each_end_with_its_neighbour(
    ranges: list[float], clear: bool
) -> None:
    scan = np.array(ranges)
    assert stands_clear(make_segment(scan, 1, 4), scan, 0.25) is clear


def test_stands_clear_refuses_a_segment_at_the_field_of_view_edge() -> None:
    scan = np.array([2.0, 2.0, 2.0, 9.0, 9.0, 9.0])
    assert not stands_clear(make_segment(scan, 0, 3), scan, 0.15)  # first beam: cut on its right
    scan = scan[::-1].copy()
    assert not stands_clear(make_segment(scan, 3, 6), scan, 0.15)  # last beam: cut on its left
    assert stands_clear(make_segment(scan, 3, 5), np.append(scan[:5], np.nan), 0.15)


def test_stands_clear_uses_the_jump_given() -> None:
    scan = np.array([2.3, 2.0, 2.0, 2.0, 2.3])  # 0.3 m behind both ends
    segment = make_segment(scan, 1, 4)
    assert stands_clear(segment, scan, 0.2)
    assert not stands_clear(segment, scan, 0.4)


# ---------------------------------------------------------------------------------------------
# noiseless scenes


def test_a_column_before_a_wall_is_one_observation_at_its_true_place() -> None:
    observations = scan_circles(ANGLES, trace([COLUMN], [WALL]), MOUNT_X_M, CONFIG)
    assert len(observations) == 1
    (obs,) = observations
    assert isinstance(obs, CircleObservation)
    np.testing.assert_allclose(obs.centre, robot_centre(COLUMN), atol=1e-6)
    assert abs(obs.R - COLUMN[2]) < 1e-6
    # noiseless points on the true circle: the fitted points are the true ones
    expected = CONFIG.covariance_scale * kcr_covariance(true_angles(COLUMN), SIGMA_M)
    np.testing.assert_allclose(obs.cov, expected, rtol=1e-6)


@pytest.mark.parametrize("mount_x_m", [0.0, 0.018, -0.25])
def test_centres_move_by_the_mount_only(mount_x_m: float) -> None:
    (obs,) = scan_circles(ANGLES, trace([COLUMN], [WALL]), mount_x_m, CONFIG)
    np.testing.assert_allclose(obs.centre, robot_centre(COLUMN, mount_x_m), atol=1e-6)
    assert abs(obs.R - COLUMN[2]) < 1e-6


def test_several_columns_come_in_scan_order() -> None:
    # right to left: beam angles increase counter-clockwise
    columns = [(3.0, -1.5, 0.25), (2.5, 0.0, 0.3), (1.5, 1.2, 0.2)]
    observations = scan_circles(ANGLES, trace(columns, [WALL]), MOUNT_X_M, CONFIG)
    assert len(observations) == 3
    for obs, column in zip(observations, columns, strict=True):
        np.testing.assert_allclose(obs.centre, robot_centre(column), atol=1e-6)
        assert abs(obs.R - column[2]) < 1e-6


def test_a_column_with_nothing_behind_it_is_seen() -> None:
    (obs,) = scan_circles(ANGLES, trace([COLUMN]), MOUNT_X_M, CONFIG)
    np.testing.assert_allclose(obs.centre, robot_centre(COLUMN), atol=1e-6)


def test_a_plain_wall_gives_no_circle() -> None:
    assert scan_circles(ANGLES, trace(walls=[WALL]), MOUNT_X_M, CONFIG) == ()
    assert scan_circles(ANGLES, trace(walls=[(1.0, 0.0, 1.5)]), MOUNT_X_M, CONFIG) == ()
    # a corner: a wall ahead and one on the left, at grazing angles near their ends
    corner = [WALL, (0.0, 1.0, 1.0)]
    assert scan_circles(ANGLES, trace(walls=corner), MOUNT_X_M, CONFIG) == ()


def test_an_empty_scan_gives_no_circle() -> None:
    assert scan_circles(ANGLES, np.full(len(ANGLES), np.nan), MOUNT_X_M, CONFIG) == ()


@pytest.mark.parametrize("side", [-1.0, 1.0])
def test_a_column_cut_by_the_field_of_view_is_not_seen(side: float) -> None:
    # centred on the edge of the 180° view (beam 0 at -90°; the last beam at +89°)
    cut = (0.0, 2.0 * side, 0.3)
    hit = beams_on(cut)
    assert hit[0 if side < 0 else -1] and hit.sum() >= 5  # the view's first or last beam on it
    assert scan_circles(ANGLES, trace([cut]), MOUNT_X_M, CONFIG) == ()
    # the same column turned 30° into the view is whole, and seen
    turn = math.radians(30.0) * -side
    whole = (
        cut[0] * math.cos(turn) - cut[1] * math.sin(turn),
        cut[0] * math.sin(turn) + cut[1] * math.cos(turn),
        0.3,
    )
    (obs,) = scan_circles(ANGLES, trace([whole]), MOUNT_X_M, CONFIG)
    np.testing.assert_allclose(obs.centre, robot_centre(whole), atol=1e-6)


def test_a_column_partly_hidden_by_a_nearer_one_is_not_seen() -> None:
    far = (2.5, 0.9, 0.5)  # spans 19.8° +- 10.8° from the laser
    near = (1.0, 0.0, 0.2)  # spans 0° +- 11.5°: hides the far column's right part
    ranges = trace([far, near], [WALL])
    visible_far = np.isclose(ranges, trace([far]), atol=1e-12) & beams_on(far)
    assert 5 <= visible_far.sum() < beams_on(far).sum()
    observations = scan_circles(ANGLES, ranges, MOUNT_X_M, CONFIG)
    # the near column stands clear (what lies beside it is > 0.15 m farther): only it
    assert len(observations) == 1
    np.testing.assert_allclose(observations[0].centre, robot_centre(near), atol=1e-6)
    assert abs(observations[0].R - near[2]) < 1e-6
    # the same visible arc with nothing beside it (no return) is whole, and seen
    alone = np.where(visible_far, ranges, np.nan)
    (obs,) = scan_circles(ANGLES, alone, MOUNT_X_M, CONFIG)
    np.testing.assert_allclose(obs.centre, robot_centre(far), atol=1e-6)


def test_a_column_touching_a_wall_at_its_range_is_not_seen() -> None:
    # a wall on the left (y = 1 m) seen at grazing angles; a column of R 0.3 m touches it,
    # and the wall beside the column's left edge reads nearly the edge's range (2.56 m at
    # 23°, the edge about 2.58 m): nothing separates the column from the wall
    column = (2.5, 0.7, 0.3)
    assert scan_circles(ANGLES, trace([column], [(0.0, 1.0, 1.0)]), MOUNT_X_M, CONFIG) == ()
    # the wall 0.6 m farther off reads 4.1 m beside the edge: the column stands clear
    (obs,) = scan_circles(ANGLES, trace([column], [(0.0, 1.0, 1.6)]), MOUNT_X_M, CONFIG)
    np.testing.assert_allclose(obs.centre, robot_centre(column), atol=1e-6)
    assert abs(obs.R - column[2]) < 1e-6


def test_a_circle_round_the_scanner_is_no_object() -> None:
    # the scanner inside a circle of R 0.9 m seen over 30° of beams only (others no return):
    # the segment stands clear and fits a small circle, but one seen from inside
    inside = (0.2, 0.0, 0.9)
    d = np.column_stack([np.cos(ANGLES), np.sin(ANGLES)])
    b = d @ np.array(inside[:2])
    far = b + np.sqrt(b**2 - (inside[0] ** 2 + inside[1] ** 2 - inside[2] ** 2))
    ranges = np.where(np.abs(ANGLES) < math.radians(15.0), far, np.nan)
    assert segment_breakpoints(ANGLES, ranges)  # one segment, with NaN on both sides
    assert scan_circles(ANGLES, ranges, MOUNT_X_M, CONFIG) == ()


def test_a_column_larger_than_the_classifier_allows_is_not_seen() -> None:
    big = (3.0, 0.0, 1.2)  # max_radius_m is 1 m
    assert scan_circles(ANGLES, trace([big], [(1.0, 0.0, 6.0)]), MOUNT_X_M, CONFIG) == ()
    allowed = ScanCirclesConfig(classification=ClassificationConfig(max_radius_m=1.5))
    (obs,) = scan_circles(ANGLES, trace([big], [(1.0, 0.0, 6.0)]), MOUNT_X_M, allowed)
    assert abs(obs.R - 1.2) < 1e-6


def test_the_covariance_scales_with_covariance_scale() -> None:
    ranges = trace([COLUMN], [WALL])
    (four,) = scan_circles(ANGLES, ranges, MOUNT_X_M, ScanCirclesConfig(covariance_scale=4.0))
    (one,) = scan_circles(ANGLES, ranges, MOUNT_X_M, ScanCirclesConfig(covariance_scale=1.0))
    np.testing.assert_allclose(one.cov, kcr_covariance(true_angles(COLUMN), SIGMA_M), rtol=1e-6)
    np.testing.assert_allclose(four.cov, 4.0 * one.cov, rtol=1e-12)
    # the classifier's sigma is the KCR's: 1.5 times the noise, 2.25 times the covariance
    wide = ScanCirclesConfig(
        covariance_scale=1.0, classification=ClassificationConfig(sigma_m=1.5 * SIGMA_M)
    )
    (loose,) = scan_circles(ANGLES, ranges, MOUNT_X_M, wide)
    np.testing.assert_allclose(loose.cov, 2.25 * one.cov, rtol=1e-9)


# ---------------------------------------------------------------------------------------------
# range noise


def test_a_noisy_column_lies_within_its_kcr_bound() -> None:
    rng = np.random.default_rng(20240501)
    clean = trace([COLUMN], [WALL])
    kcr = kcr_covariance(true_angles(COLUMN), SIGMA_M)
    truth = np.append(robot_centre(COLUMN), COLUMN[2])
    hit = beams_on(COLUMN)
    rays = np.column_stack([np.cos(ANGLES[hit]), np.sin(ANGLES[hit])])
    for _ in range(20):
        ranges = clean + SIGMA_M * rng.standard_normal(len(clean))
        observations = scan_circles(ANGLES, ranges, MOUNT_X_M, CONFIG)
        assert len(observations) == 1
        (obs,) = observations
        error = obs.z - truth
        # beam noise is no larger than the isotropic noise the bound assumes
        assert error @ np.linalg.solve(kcr, error) <= chi2.isf(1e-4, 3)
        assert np.all(np.abs(error) <= 4.0 * np.sqrt(np.diag(kcr)))
        # the covariance: covariance_scale x KCR at the fitted points round the fitted centre
        points = ranges[hit, None] * rays
        fitted_centre = obs.centre - np.array([MOUNT_X_M, 0.0])
        offsets = points - fitted_centre
        angles = np.arctan2(offsets[:, 1], offsets[:, 0])
        expected = CONFIG.covariance_scale * kcr_covariance(angles, SIGMA_M)
        np.testing.assert_allclose(obs.cov, expected, rtol=1e-9)
        np.testing.assert_allclose(obs.cov, obs.cov.T, rtol=1e-12)
        assert np.linalg.eigvalsh(obs.cov).min() > 0.0


def test_noisy_fits_scatter_as_the_first_order_covariance_says() -> None:
    # Monte Carlo: the squared Mahalanobis error under the sandwich covariance of beam noise
    # is chi-square(3) to first order; its mean over N draws lies within 3 +- 3 sqrt(6 / N)
    rng = np.random.default_rng(7)
    clean = trace([COLUMN], [WALL])
    cov = first_order_covariance(COLUMN, SIGMA_M)
    kcr = kcr_covariance(true_angles(COLUMN), SIGMA_M)
    assert np.all(np.linalg.eigvalsh(kcr - cov) >= -1e-15)  # the sandwich is below the bound
    truth = np.append(robot_centre(COLUMN), COLUMN[2])
    n = 200
    nees = np.empty(n)
    kcr_nees = np.empty(n)
    for k in range(n):
        ranges = clean + SIGMA_M * rng.standard_normal(len(clean))
        (obs,) = scan_circles(ANGLES, ranges, MOUNT_X_M, CONFIG)
        error = obs.z - truth
        nees[k] = error @ np.linalg.solve(cov, error)
        kcr_nees[k] = error @ np.linalg.solve(kcr, error)
    band = 3.0 * math.sqrt(6.0 / n)
    assert abs(nees.mean() - 3.0) < band
    assert kcr_nees.mean() < 3.0 + band


# ---------------------------------------------------------------------------------------------
# config


@pytest.mark.parametrize("value", [0.0, -1.0, math.nan, math.inf])
def test_config_refuses_a_bad_covariance_scale(value: float) -> None:
    with pytest.raises(ValueError, match=r"ScanCirclesConfig\.covariance_scale"):
        ScanCirclesConfig(covariance_scale=value)


def test_config_refuses_a_covariance_scale_of_the_wrong_type() -> None:
    with pytest.raises(InvalidTypeError, match=r"ScanCirclesConfig\.covariance_scale"):
        ScanCirclesConfig(covariance_scale="4")  # type: ignore[arg-type]


def test_config_refuses_other_segmenters_and_classifiers() -> None:
    with pytest.raises(InvalidTypeError, match=r"ScanCirclesConfig\.segmentation"):
        ScanCirclesConfig(segmentation=ScaleSpaceConfig())  # type: ignore[arg-type]
    with pytest.raises(InvalidTypeError, match=r"ScanCirclesConfig\.classification"):
        ScanCirclesConfig(classification=None)  # type: ignore[arg-type]


def test_config_defaults() -> None:
    config = ScanCirclesConfig()
    assert config.covariance_scale == 4.0
    assert config.segmentation == BreakpointConfig()
    assert config.classification == ClassificationConfig()
