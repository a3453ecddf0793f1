"""Range (arc) measurements of circles: seed 001's polar model on a mounted scanner
(perception.circles.model.measure_arc) against ray/circle intersections solved in closed form and
central differences; the range fusion of CircleSlam.update_scan on noiseless and noisy arcs
(convergence, consistency, no bias over seeds); provisional admission and its exact
marginalisation; and the arcs of a synthetic scan (perception.circles.scan_circles.scan_arcs)."""

from __future__ import annotations

import copy
import dataclasses
import math
from typing import Any

import numpy as np
import pytest
from numpy.typing import ArrayLike
from scipy.optimize import least_squares

from perception.circles.classification import classify_segment
from perception.circles.model import TANGENT_ROOT, measure_arc
from perception.circles.scan_circles import ScanCirclesConfig, scan_arcs, scan_circles
from perception.circles.segmentation import segment_breakpoints
from perception.geometry import FloatArray, relative, wrap_angle
from perception.sensor_models import LaserModel
from perception.slam.circle_slam import (
    ArcObservation,
    CircleObservation,
    CircleSlam,
    CircleSlamConfig,
    CircleUpdateResult,
)

BEAMS = np.radians(np.arange(-90.0, 90.5, 1.0))  # robot-frame beam angles, 1° apart
MOUNT_X_M = 0.2  # the scanner this far ahead of the robot origin
SIGMA_M = 0.02  # range noise
TRUE = np.array([2.0, 1.0, 0.3])  # a column (c_x, c_y, R) (m, world)
PRIOR_COV = np.diag([0.05**2, 0.05**2, 0.05**2])  # covariance of the fit that maps it


def intersect(origin: ArrayLike, beta: ArrayLike, circle: ArrayLike) -> FloatArray:
    """Near root of ``|o + t d - c|^2 = R^2``, ``d = (cos beta, sin beta)``: ``t^2 + 2 b t +
    q = 0`` with ``b = d . (o - c)``, ``q = |o - c|^2 - R^2``; NaN where the ray misses."""
    o, (cx, cy, R) = np.asarray(origin, dtype=np.float64), np.asarray(circle, dtype=np.float64)
    beta = np.asarray(beta, dtype=np.float64)
    w = o - np.array([cx, cy])
    b = np.cos(beta) * w[0] + np.sin(beta) * w[1]
    disc = b**2 - (w @ w - R**2)
    t = -b - np.sqrt(np.where(disc >= 0.0, disc, np.nan))
    return np.where(t > 0.0, t, np.nan)


def scanner(pose: ArrayLike, mount: float = MOUNT_X_M) -> FloatArray:
    """The scanner's world position (2,) on the robot at ``pose``."""
    x, y, th = np.asarray(pose, dtype=np.float64)
    return np.array([x + mount * math.cos(th), y + mount * math.sin(th)])


def arc(pose: ArrayLike, circle: ArrayLike = TRUE, rng: Any = None, **kw: Any) -> ArcObservation:
    """The arc of ``circle`` seen from ``pose`` with 1° beams (noisy when ``rng`` is given)."""
    t = intersect(scanner(pose), pose[2] + BEAMS, circle)
    hit = np.isfinite(t)
    r = t[hit] if rng is None else t[hit] + SIGMA_M * rng.standard_normal(int(hit.sum()))
    return ArcObservation(BEAMS[hit], r, **kw)


def fit_of(pose: ArrayLike, circle: ArrayLike, cov: FloatArray = PRIOR_COV) -> CircleObservation:
    """A circle fit at ``circle`` (world) as seen, robot frame, from ``pose``."""
    x, y, _ = relative(pose, (circle[0], circle[1], 0.0))
    return CircleObservation(np.array([x, y]), float(circle[2]), cov)


def ring(n: int, radius: float = 1.6, centre: FloatArray = TRUE) -> list[FloatArray]:
    """``n`` poses around ``centre``, each facing it a little off axis."""
    angles = 2 * math.pi * np.arange(n) / n
    x, y = centre[0] + radius * np.cos(angles), centre[1] + radius * np.sin(angles)
    return list(np.column_stack([x, y, wrap_angle(angles - 3.0)]))


EXACT = CircleSlamConfig(  # noiseless odometry, start pose known exactly, circles mapped at once
    translation_noise_m_per_sqrt_m=0.0,
    translation_noise_m_per_sqrt_rad=0.0,
    heading_noise_rad_per_sqrt_m=0.0,
    rotation_noise_rad_per_sqrt_rad=0.0,
    initial_pose_std=(0.0, 0.0, 0.0),
    min_views=1,
)


def mapped(pose: ArrayLike, circle: ArrayLike, cov: FloatArray = PRIOR_COV) -> CircleSlam:
    """A filter at ``pose`` (known exactly) with ``circle`` mapped from one fit of ``cov``."""
    slam = CircleSlam(EXACT, pose=pose)
    assert slam.update([fit_of(pose, circle, cov)]).added.tolist() == [[0, 0]]
    return slam


def move_to(slam: CircleSlam, pose: ArrayLike) -> None:
    """Drive the (noiseless) filter to ``pose``."""
    slam.predict(relative(slam.pose, pose), np.zeros((3, 3)))


def partition(result: CircleUpdateResult) -> list[int]:
    """Every arc index the result names, sorted, with repeats."""
    pairs = [result.matched[:, 1], result.added[:, 1]]
    rest = [result.buffered, result.ambiguous, result.refused, result.dropped]
    return sorted(np.concatenate(pairs + rest).tolist())


# --- measure_arc ---------------------------------------------------------------------------------

POSE = np.array([0.3, -0.2, 0.4])
CIRCLE = np.array([2.5, 1.8, 0.6])


def tangent_roots(origin: ArrayLike, beta: ArrayLike, circle: ArrayLike) -> FloatArray:
    """``sqrt(R^2 - p^2) / R`` per beam, ``p`` the distance from the centre to the beam's line
    (NaN where the line misses): the half chord, the root of :func:`intersect`'s quadratic."""
    d = np.column_stack([np.cos(beta), np.sin(beta)])
    w = np.asarray(circle[:2]) - np.asarray(origin)
    p = np.abs(d[:, 0] * w[1] - d[:, 1] * w[0])
    inside = circle[2] ** 2 - p**2
    return np.sqrt(np.where(inside >= 0, inside, np.nan)) / circle[2]


def test_measure_arc_ranges_are_ray_circle_intersections() -> None:
    origin, beta = scanner(POSE), POSE[2] + np.radians(np.arange(-90.0, 90.0, 0.25))
    m = measure_arc(CIRCLE, POSE[:2], origin, beta)
    assert m is not None
    t = intersect(origin, beta, CIRCLE)
    np.testing.assert_allclose(m.ranges, t[m.used], rtol=0, atol=1e-12)
    # used: the beams that hit, at least TANGENT_ROOT R inside the tangents
    assert TANGENT_ROOT == 0.2
    inner = np.isfinite(t) & (np.nan_to_num(tangent_roots(origin, beta, CIRCLE)) >= 0.2)
    np.testing.assert_array_equal(m.used, inner)
    assert (np.isfinite(t) & ~inner).sum() >= 2  # grazing beams left out, one on each side
    assert (~np.isfinite(t)).sum() > 600  # and the misses
    assert m.ranges.shape == (inner.sum(),)
    assert m.H_circle.shape == m.H_pose.shape == (inner.sum(), 3)


def test_measure_arc_none_inside_or_too_few_beams() -> None:
    inside = measure_arc(CIRCLE, CIRCLE[:2], CIRCLE[:2] + np.array([0.1, 0.0]), BEAMS)
    assert inside is None
    assert measure_arc([*CIRCLE[:2], 0.0], POSE[:2], scanner(POSE), BEAMS) is None
    origin = scanner(POSE)
    towards = math.atan2(CIRCLE[1] - origin[1], CIRCLE[0] - origin[0])
    small = np.radians([-1.0, 0.0, 1.0])
    assert measure_arc(CIRCLE, POSE[:2], origin, towards + small[:2]) is None  # 2 beams
    three = measure_arc(CIRCLE, POSE[:2], origin, towards + small)
    assert three is not None and three.used.all()
    away = measure_arc(CIRCLE, POSE[:2], origin, towards + math.pi + small)
    assert away is None  # beams pointing away from the circle


def central(f: Any, x: FloatArray, eps: float = 1e-6) -> FloatArray:
    return np.column_stack([(f(x + eps * e) - f(x - eps * e)) / (2 * eps) for e in np.eye(len(x))])


@pytest.mark.parametrize("mount", [0.0, MOUNT_X_M, -0.35])
def test_measure_arc_jacobians_match_central_differences(mount: float) -> None:
    m = measure_arc(CIRCLE, POSE[:2], scanner(POSE, mount), POSE[2] + BEAMS)
    assert m is not None

    def by_circle(c: FloatArray) -> FloatArray:
        mc = measure_arc(c, POSE[:2], scanner(POSE, mount), POSE[2] + BEAMS)
        assert mc is not None and (mc.used == m.used).all()
        return mc.ranges

    def by_pose(p: FloatArray) -> FloatArray:  # the scanner rides on the robot
        mp = measure_arc(CIRCLE, p[:2], scanner(p, mount), p[2] + BEAMS)
        assert mp is not None and (mp.used == m.used).all()
        return mp.ranges

    for H, numeric in (
        (m.H_circle, central(by_circle, CIRCLE)),
        (m.H_pose, central(by_pose, POSE)),
    ):
        np.testing.assert_allclose(H, numeric, rtol=1e-6, atol=1e-6 * np.abs(numeric).max())
    assert np.abs(m.H_pose[:, 2]).max() > 0.1  # the heading matters


# --- ArcObservation ------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("kwargs", "error"),
    [
        ({"angles": [0.0, np.nan, 0.2], "ranges": [1.0, 1.0, 1.0]}, ValueError),
        ({"angles": [0.0, 0.1, 0.2], "ranges": [1.0, np.inf, 1.0]}, ValueError),
        ({"angles": [0.0, 0.1, 0.2], "ranges": [1.0, 1.0]}, ValueError),
        ({"angles": [0.0, 0.1, 0.2], "ranges": [1.0, 0.0, 1.0]}, ValueError),
        ({"angles": [0.0, 0.1, 0.2], "ranges": [1.0, -1.0, 1.0]}, ValueError),
        ({"angles": [0.0, 0.1], "ranges": [1.0, 1.0], "fit": (2.0, 0.0, 0.3)}, TypeError),
        ({"angles": [0.0, 0.1], "ranges": [1.0, 1.0], "circular": 1}, TypeError),
        ({"angles": [0.0, 0.1], "ranges": [1.0, 1.0], "circular": "yes"}, TypeError),
    ],
)
def test_arc_observation_rejects(kwargs: dict[str, Any], error: type[Exception]) -> None:
    with pytest.raises(error):
        ArcObservation(**kwargs)


# --- update_scan ---------------------------------------------------------------------------------


def test_noiseless_arcs_drive_a_wrong_radius_to_the_truth() -> None:
    poses = ring(8)
    slam = mapped(poses[0], TRUE + np.array([0.02, -0.02, 0.03]))  # R 0.03 m too large
    for _ in range(3):
        for pose in poses:
            move_to(slam, pose)
            result = slam.update_scan([arc(pose)], MOUNT_X_M, SIGMA_M)
            assert result.matched.tolist() == [[0, 0]]
    np.testing.assert_allclose(slam.circles[0], TRUE, rtol=0, atol=1e-3)
    np.testing.assert_allclose(slam.pose, poses[-1], rtol=0, atol=1e-12)  # the pose was known


def map_estimate(
    prior: FloatArray, P: FloatArray, origin: FloatArray, beta: FloatArray, ranges: FloatArray
) -> FloatArray:
    """The circle minimising ``|c - prior|^2_P + sum (r_i - t_i(c))^2 / sigma^2`` (scipy)."""
    L = np.linalg.cholesky(np.linalg.inv(P))

    def residuals(c: FloatArray) -> FloatArray:
        return np.r_[L.T @ (c - prior), (ranges - intersect(origin, beta, c)) / SIGMA_M]

    return least_squares(residuals, prior, xtol=1e-15, ftol=1e-15, gtol=1e-15).x


@pytest.mark.parametrize("offset", [(0.003, -0.002, 0.003), (-0.003, 0.002, -0.003)])
def test_one_range_update_is_the_map_estimate(offset: tuple[float, float, float]) -> None:
    # the iterated EKF is Gauss-Newton on the MAP of the prior and the ranges; with the pose
    # known, the MAP over the circle alone, on the beams chosen at the prior
    checked = 0
    for pose in ring(6):
        slam = mapped(pose, TRUE + offset, np.eye(3) * 0.01**2)
        prior, P = slam.circles[0], slam.circle_covs[0]
        a = arc(pose)
        origin, beta = scanner(pose), pose[2] + a.angles
        chosen = np.nan_to_num(tangent_roots(origin, beta, prior)) >= TANGENT_ROOT
        best = map_estimate(prior, P, origin, beta[chosen], a.ranges[chosen])
        assert slam.update_scan([a], MOUNT_X_M, SIGMA_M).matched.tolist() == [[0, 0]]
        # the update stops early when a chosen beam grazes an iterate: compare only where the
        # chosen beams stay well inside the tangents at the MAP
        if tangent_roots(origin, beta[chosen], best).min() >= 0.25:
            np.testing.assert_allclose(slam.circles[0], best, rtol=0, atol=1e-6)
            checked += 1
    assert checked >= 3


def test_noisy_arcs_consistent_and_unbiased_radius() -> None:
    runs, errors, stds, prior_cov = 16, [], [], np.eye(3) * 0.01**2
    for seed in range(runs):
        rng = np.random.default_rng(seed)
        poses = ring(12)
        start = TRUE + 0.01 * rng.standard_normal(3)  # a fair prior
        slam = mapped(poses[0], start, prior_cov)
        fused = 0
        for pose in poses:
            move_to(slam, pose)
            fused += len(slam.update_scan([arc(pose, rng=rng)], MOUNT_X_M, SIGMA_M).matched)
        assert fused >= 10  # the 0.99 gate misses about one arc in a hundred
        error, std = slam.circles[0, 2] - TRUE[2], math.sqrt(slam.circle_covs[0, 2, 2])
        assert abs(error) < 3 * std, (seed, error, std)
        errors.append(error)
        stds.append(std)
    std = float(np.mean(stds))
    assert std < 0.002  # the ranges did shrink the prior's 0.01
    # unbiased: the mean of 16 independent errors of std ~ std has std std / 4; 3 of those
    # is a 0.3 % false alarm if unbiased. A geometric circle fit of these 25-beam arcs is
    # biased by about -0.0035 m (~4 std), which this bound (~0.0006 m) would catch.
    assert abs(np.mean(errors)) < 3 * std / math.sqrt(runs), (np.mean(errors), std)
    # consistent: the spread of the errors matches the filter's std (chi-square, 15 dof: the
    # ratio lies in [0.5, 1.5] with probability > 0.99)
    assert 0.5 < np.std(errors) / std < 1.5, (np.std(errors), std)


def test_non_circular_arc_never_pairs_by_range() -> None:
    pose = ring(4)[0]
    slam = mapped(pose, TRUE + np.array([0.0, 0.0, 0.03]))
    before = (slam.mean, slam.cov)
    result = slam.update_scan([arc(pose, circular=False)], MOUNT_X_M, SIGMA_M)
    assert result.dropped.tolist() == [0] and len(result.matched) == 0
    np.testing.assert_array_equal(slam.mean, before[0])
    np.testing.assert_array_equal(slam.cov, before[1])
    # with a fit it goes the fit's way: the state equals that of update([fit])
    fit = fit_of(pose, TRUE)
    twin = copy.deepcopy(slam)
    result = slam.update_scan([arc(pose, fit=fit, circular=False)], MOUNT_X_M, SIGMA_M)
    assert result.matched.tolist() == [[0, 0]]
    twin.update([fit])
    np.testing.assert_array_equal(slam.mean, twin.mean)
    np.testing.assert_array_equal(slam.cov, twin.cov)
    # the same arc, circular, pairs by its ranges instead (a different state)
    twin2 = copy.deepcopy(twin)
    twin.update_scan([arc(pose, fit=fit)], MOUNT_X_M, SIGMA_M)
    twin2.update([fit])
    assert not np.allclose(twin.mean, twin2.mean, rtol=0, atol=1e-9)


def test_every_arc_lands_in_exactly_one_field() -> None:
    pose = ring(4)[0]
    slam = mapped(pose, TRUE)
    far = TRUE + np.array([0.0, -2.5, -0.1])  # another column, unmapped
    arcs = [
        arc(pose, far),  # far from every circle, no fit: dropped
        arc(pose),  # the mapped circle: matched by its ranges
        arc(pose, far, fit=fit_of(pose, far)),  # a new circle: added (min_views 1)
        arc(pose, circular=False),  # the mapped circle, not circular, no fit: dropped
    ]
    assert len(arcs[0].ranges) >= 3
    result = slam.update_scan(arcs, MOUNT_X_M, SIGMA_M)
    assert result.dropped.tolist() == [0, 3]
    assert result.matched.tolist() == [[0, 1]] and result.added.tolist() == [[1, 2]]
    assert partition(result) == [0, 1, 2, 3]
    np.testing.assert_allclose(slam.circles, [TRUE, far], atol=1e-9)


@pytest.mark.parametrize(
    ("arcs", "mount", "sigma", "error"),
    [
        ("good", math.nan, SIGMA_M, ValueError),
        ("good", MOUNT_X_M, 0.0, ValueError),
        ("good", MOUNT_X_M, -0.02, ValueError),
        ("mixed", MOUNT_X_M, SIGMA_M, TypeError),
        ("single", MOUNT_X_M, SIGMA_M, TypeError),
    ],
)
def test_update_scan_rejects_bad_arguments(
    arcs: str, mount: float, sigma: float, error: Any
) -> None:
    config = dataclasses.replace(EXACT, admission="provisional", min_views=3, min_views_max_age=1)
    pose = ring(4)[0]
    slam = CircleSlam(config, pose=pose)
    slam.update([fit_of(pose, TRUE)])
    good = arc(pose)
    given = {"good": [good], "mixed": [good, fit_of(pose, TRUE)], "single": good}[arcs]
    before = (slam.mean, slam.cov, slam.hits)
    with pytest.raises(error):
        slam.update_scan(given, mount, sigma)  # type: ignore[arg-type]
    np.testing.assert_array_equal(slam.mean, before[0])
    np.testing.assert_array_equal(slam.cov, before[1])
    np.testing.assert_array_equal(slam.hits, before[2])
    slam.update([])  # the refused call counted no update: the circle (max age 1) is still here
    assert slam.n_circles == 1
    slam.update([])
    assert slam.n_circles == 0


# --- provisional admission -----------------------------------------------------------------------

PROVISIONAL = CircleSlamConfig(admission="provisional", min_views=3, min_views_max_age=2)
OTHER = np.array([1.0, 2.5, 0.2])  # a second column (world)


def test_provisional_circle_enters_at_once_and_is_confirmed() -> None:
    pose = ring(4)[0]
    slam = CircleSlam(PROVISIONAL, pose=pose)
    assert slam.update([fit_of(pose, TRUE)]).added.tolist() == [[0, 0]]
    assert slam.n_circles == 1 and slam.hits.tolist() == [1] and slam.confirmed.tolist() == [False]
    slam.update([fit_of(pose, TRUE)])
    assert slam.hits.tolist() == [2] and slam.confirmed.tolist() == [False]
    slam.update([fit_of(pose, TRUE)])
    assert slam.hits.tolist() == [3] and slam.confirmed.tolist() == [True]
    for _ in range(5):  # a confirmed circle stays, seen or not
        slam.update([])
    assert slam.n_circles == 1 and slam.circle_ids.tolist() == [0]


def test_unconfirmed_circle_is_marginalised_exactly() -> None:
    pose = ring(4)[0]
    slam = CircleSlam(PROVISIONAL, pose=pose)
    slam.update([fit_of(pose, OTHER), fit_of(pose, TRUE)])  # ids 0 (OTHER) and 1 (TRUE)
    assert slam.circle_ids.tolist() == [0, 1]
    for step in range(2):
        slam.predict([0.1, 0.0, 0.05])  # noisy odometry: the pose and both circles correlate
        slam.update([fit_of(slam.pose, TRUE)])
        assert slam.n_circles == 2, step  # OTHER unseen for 1, then 2 updates: kept
    slam.predict([0.1, 0.0, 0.05])
    mu, sigma = slam.mean, slam.cov
    assert np.abs(sigma[3:6, 6:9]).max() > 1e-6  # the two circles are correlated
    result = slam.update([])  # OTHER unseen for 3 > min_views_max_age updates
    assert slam.n_circles == 1 and slam.circle_ids.tolist() == [1]
    assert slam.hits.tolist() == [3] and slam.confirmed.tolist() == [True]
    keep = np.r_[0:3, 6:9]
    np.testing.assert_array_equal(slam.mean, mu[keep])
    np.testing.assert_array_equal(slam.cov, sigma[np.ix_(keep, keep)])
    assert partition(result) == []
    slam.update([fit_of(slam.pose, OTHER)])  # seen again: a new circle, a new id
    assert slam.circle_ids.tolist() == [1, 2] and slam.confirmed.tolist() == [True, False]


def test_admission_is_validated() -> None:
    with pytest.raises(ValueError, match="admission"):
        CircleSlamConfig(admission="bogus")  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="admission"):
        CircleSlamConfig(admission=None)  # type: ignore[arg-type]
    assert CircleSlam(CircleSlamConfig()).confirmed.shape == (0,)


# --- scan_arcs -----------------------------------------------------------------------------------

ANGLES = LaserModel().beam_angles()  # seed 001: 180 beams over 180°
COLUMN = (2.0, 0.5, 0.3)  # (x, y, R) (m, laser frame)
BACKGROUND_M = 8.0


def laser_scan(column: Any = COLUMN) -> FloatArray:
    """Ranges (B,) of ``column`` (laser frame), ``BACKGROUND_M`` beside it."""
    t = intersect((0.0, 0.0), ANGLES, column)
    return np.where(np.isfinite(t), t, BACKGROUND_M)


def sector(shape: Any, half_width: float, centre: float = 0.0) -> FloatArray:
    """Ranges (B,): ``shape(angle)`` within ``half_width`` of ``centre`` (rad), else the
    background."""
    on = np.abs(ANGLES - centre) <= half_width
    return np.where(on, shape(np.where(on, ANGLES, 0.0)), BACKGROUND_M)


def test_scan_arcs_of_a_column() -> None:
    ranges = laser_scan()
    (found,) = scan_arcs(ANGLES, ranges, MOUNT_X_M, ScanCirclesConfig())
    hit = np.isfinite(intersect((0.0, 0.0), ANGLES, COLUMN))
    np.testing.assert_array_equal(found.angles, ANGLES[hit])
    np.testing.assert_array_equal(found.ranges, ranges[hit])
    assert found.circular is True and found.fit is not None
    np.testing.assert_allclose(found.fit.centre, [COLUMN[0] + MOUNT_X_M, COLUMN[1]], atol=1e-6)
    assert abs(found.fit.R - COLUMN[2]) < 1e-6


@pytest.mark.parametrize(
    ("ranges", "kind"),
    [
        (sector(lambda a: 3.0 / np.cos(a), 0.2), "line"),  # a plank: a line, a circle's limit
        (sector(lambda a: 2.0 + 1.5 * np.abs(a), 0.25), "other"),  # a wedge: neither
        (sector(lambda a: 0.6 + 0.0 * a, 0.7), "circle"),  # concave: holds the sensor
    ],
)
def test_scan_arcs_without_fit(ranges: FloatArray, kind: str) -> None:
    config = ScanCirclesConfig()
    (found,) = scan_arcs(ANGLES, ranges, MOUNT_X_M, config)
    (segment,) = segment_breakpoints(ANGLES, ranges, config.segmentation)[1:-1]
    assert classify_segment(segment, config.classification).kind == kind
    np.testing.assert_array_equal(found.ranges, ranges[ranges < BACKGROUND_M])
    assert found.circular is (kind != "other") and found.fit is None


def test_scan_circles_are_the_fits_of_scan_arcs() -> None:
    plank = sector(lambda a: 3.0 / np.cos(a), 0.15, -0.45)
    ranges = np.minimum(laser_scan(), plank)  # a plank on the right, then the column
    config = ScanCirclesConfig()
    arcs = scan_arcs(ANGLES, ranges, MOUNT_X_M, config)
    assert [a.fit is None for a in arcs] == [True, False]
    fits = scan_circles(ANGLES, ranges, MOUNT_X_M, config)
    assert len(fits) == 1
    np.testing.assert_array_equal(fits[0].z, arcs[1].fit.z)  # type: ignore[union-attr]
    np.testing.assert_array_equal(fits[0].cov, arcs[1].fit.cov)  # type: ignore[union-attr]


def test_scan_arcs_feed_update_scan() -> None:
    # a scan of the world column TRUE from a known pose, through scan_arcs: its arc is the
    # hand-made one (robot-frame angles, ranges from the scanner) and fuses as that one does
    pose = ring(4)[1]
    world = intersect(scanner(pose), pose[2] + ANGLES, TRUE)
    hit = np.isfinite(world)
    (found,) = scan_arcs(ANGLES, np.where(hit, world, BACKGROUND_M), MOUNT_X_M, ScanCirclesConfig())
    np.testing.assert_array_equal(found.angles, ANGLES[hit])
    slam, twin = (mapped(pose, TRUE + np.array([0.0, 0.0, 0.02])) for _ in range(2))
    assert slam.update_scan([found], MOUNT_X_M, SIGMA_M).matched.tolist() == [[0, 0]]
    twin.update_scan([ArcObservation(ANGLES[hit], world[hit])], MOUNT_X_M, SIGMA_M)
    np.testing.assert_allclose(slam.mean, twin.mean, rtol=0, atol=1e-12)
    assert abs(slam.circles[0, 2] - TRUE[2]) < 0.02  # mapped 0.02 too large: it moved closer


@pytest.mark.parametrize(
    ("args", "match"),
    [
        ({"circle": [math.nan, 1.0, 0.3]}, "circle must be finite"),
        ({"circle": [2.0, 1.0]}, r"circle must have shape \(3,\)"),
        ({"origin": [0.0, math.inf]}, "origin must be finite"),
        ({"robot_xy": [math.nan, 0.0]}, "robot_xy must be finite"),
        ({"beta": [0.1, math.nan, 0.3]}, r"beta must be a finite \(n,\) array"),
    ],
)
def test_measure_arc_refuses_nan_and_wrong_shapes_naming_the_argument(
    args: dict[str, Any], match: str
) -> None:
    good = {"circle": TRUE, "robot_xy": [0.0, 0.0], "origin": [0.2, 0.0], "beta": BEAMS[80:100]}
    with pytest.raises(ValueError, match=match):
        measure_arc(**{**good, **args})


@pytest.mark.parametrize("mount", [math.nan, math.inf])
def test_scan_arcs_refuses_a_mount_that_is_not_finite(mount: float) -> None:
    with pytest.raises(ValueError, match="mount_x_m must be finite"):
        scan_arcs(BEAMS, np.full(len(BEAMS), 2.0), mount, ScanCirclesConfig())
