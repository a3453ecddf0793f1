"""The Pioneer's sonar ring (spl_env.sensors.ring_sonar) against closed-form scenes: a ray
caster for an infinite wall or a vertical cylinder, hand-computed nearest echoes within each
sonar's fan of rays, range limits that blank instead of clip, and the noise's spread."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest
from numpy.typing import NDArray
from scipy.stats import chi2, norm

from perception.geometry import FloatArray
from perception.validation import InvalidTypeError
from spl_env.robots.diff_drive import DiffDriveConfig
from spl_env.sensors.raycast import RayCaster
from spl_env.sensors.ring_sonar import RingSonar, RingSonarConfig

ROBOT = DiffDriveConfig()  # the Pioneer 3-DX's sixteen sonars
QUIET = RingSonarConfig(range_noise_std_m=0.0)
WALL_BODY = 7


def wall_caster(x_wall: float, body: int = WALL_BODY) -> RayCaster:
    """Rays against the vertical plane ``x = x_wall`` (field frame), from its near side."""

    def cast(starts: FloatArray, ends: FloatArray) -> tuple[FloatArray, NDArray[np.int64]]:
        dx = ends[:, 0] - starts[:, 0]
        with np.errstate(divide="ignore", invalid="ignore"):
            f = (x_wall - starts[:, 0]) / dx
        hit = (dx > 0.0) & (f >= 0.0) & (f < 1.0)
        return np.where(hit, f, 1.0), np.where(hit, body, -1).astype(np.int64)

    return cast


def cylinder_caster(centre: tuple[float, float], radius: float, body: int = 3) -> RayCaster:
    """Rays against a vertical cylinder (infinite height) from outside it (field frame)."""

    def cast(starts: FloatArray, ends: FloatArray) -> tuple[FloatArray, NDArray[np.int64]]:
        D = ends[:, :2] - starts[:, :2]
        m = starts[:, :2] - np.asarray(centre)
        a = np.sum(D * D, axis=1)
        b = 2.0 * np.sum(D * m, axis=1)
        c = np.sum(m * m, axis=1) - radius**2
        disc = b**2 - 4.0 * a * c
        f = (-b - np.sqrt(np.maximum(disc, 0.0))) / (2.0 * a)
        hit = (disc >= 0.0) & (f >= 0.0) & (f < 1.0)
        return np.where(hit, f, 1.0), np.where(hit, body, -1).astype(np.int64)

    return cast


def constant_caster(fraction: float, body: int) -> RayCaster:
    """Every ray hits ``body`` at ``fraction`` of its length."""

    def cast(starts: FloatArray, ends: FloatArray) -> tuple[FloatArray, NDArray[np.int64]]:
        n = len(starts)
        return np.full(n, fraction), np.full(n, body, dtype=np.int64)

    return cast


def wall_ranges(
    pose: tuple[float, float, float], x_wall: float, config: RingSonarConfig
) -> FloatArray:
    """Noiseless ranges (S,) of the ring at ``pose`` facing the wall ``x = x_wall``: per sonar,
    the least ``(x_wall - x_i) / cos(psi_ij)`` over its rays ``psi_ij`` (``x_i`` its disc's field
    x; the axis turned by the cone's evenly spaced offsets) heading towards the wall and within
    ``max_range_m``; NaN if none, or if below ``min_range_m``."""
    x, _, theta = pose
    n = config.rays_per_sonar
    cone = math.radians(config.cone_deg)
    offsets = [0.0] if n == 1 else [cone * (j / (n - 1) - 0.5) for j in range(n)]
    out = []
    for px, py, yaw in ROBOT.sonar_ring:
        x_i = x + px * math.cos(theta) - py * math.sin(theta)
        best = math.inf
        for offset in offsets:
            towards = math.cos(theta + math.radians(yaw) + offset)
            if towards > 1e-12:
                r = (x_wall - x_i) / towards
                if 0.0 <= r < config.max_range_m:
                    best = min(best, r)
        out.append(best if config.min_range_m <= best <= config.max_range_m else math.nan)
    return np.array(out)


def test_a_wall_ahead_gives_the_hand_computed_ranges() -> None:
    # robot at the origin heading +x, wall at x = 2 m; default cone 30° of 7 rays (5° apart)
    ranges = RingSonar(QUIET, ROBOT).measure(
        wall_caster(2.0), (0.0, 0.0, 0.0), np.random.default_rng(0)
    )
    c = math.cos
    expected = [
        math.nan,  # 90° +- 15°: nearest ray at 75° reads 1.931 / cos 75° = 7.5 m > 5 m
        (2.0 - 0.114) / c(math.radians(35.0)),  # 50° +- 15°: the cone's edge at 35°
        (2.0 - 0.148) / c(math.radians(15.0)),  # 30° +- 15°: the edge at 15°
        2.0 - 0.166,  # 10° +- 15°: the ray at 0° meets the wall square on
        2.0 - 0.166,  # -10°
        (2.0 - 0.148) / c(math.radians(15.0)),
        (2.0 - 0.114) / c(math.radians(35.0)),
        math.nan,  # -90°
        *[math.nan] * 8,  # the rear sonars: facing away, or the side ones 8.3 m along rays
    ]
    np.testing.assert_allclose(ranges, expected, rtol=1e-12, atol=0.0)


def test_a_wider_cone_of_three_rays() -> None:
    # cone 60° of 3 rays: the axis and its two edges
    config = RingSonarConfig(cone_deg=60.0, rays_per_sonar=3, range_noise_std_m=0.0)
    ranges = RingSonar(config, ROBOT).measure(
        wall_caster(2.0), (0.0, 0.0, 0.0), np.random.default_rng(0)
    )
    cos = lambda deg: math.cos(math.radians(deg))  # noqa: E731
    assert ranges[0] == pytest.approx((2.0 - 0.069) / cos(60.0), rel=1e-12)  # 90°: edge 60°
    assert ranges[1] == pytest.approx((2.0 - 0.114) / cos(20.0), rel=1e-12)  # 50°: edge 20°
    assert ranges[3] == pytest.approx((2.0 - 0.166) / cos(10.0), rel=1e-12)  # 10°: rays -20, 10, 40
    assert ranges[8] == pytest.approx((2.0 + 0.157) / cos(60.0), rel=1e-12)  # -90° at the back
    assert ranges[15] == pytest.approx((2.0 + 0.157) / cos(60.0), rel=1e-12)
    assert np.isnan(ranges[9:15]).all()  # -130° ... 130°: every ray faces away


def test_a_single_ray_per_sonar_lies_on_its_axis() -> None:
    config = RingSonarConfig(rays_per_sonar=1, range_noise_std_m=0.0)
    ranges = RingSonar(config, ROBOT).measure(
        wall_caster(2.0), (0.0, 0.0, 0.0), np.random.default_rng(0)
    )
    cos = lambda deg: math.cos(math.radians(deg))  # noqa: E731
    assert np.isnan(ranges[0])  # along the wall
    assert ranges[1] == pytest.approx((2.0 - 0.114) / cos(50.0), rel=1e-12)
    assert ranges[2] == pytest.approx((2.0 - 0.148) / cos(30.0), rel=1e-12)
    assert ranges[3] == pytest.approx((2.0 - 0.166) / cos(10.0), rel=1e-12)


@pytest.mark.parametrize(
    ("pose", "x_wall"),
    [
        ((0.0, 0.0, 0.0), 2.0),
        ((1.0, -0.5, 0.7), 3.0),
        ((-2.0, 1.0, -0.4), 0.5),
        ((0.0, 0.0, 3.0), 1.0),
    ],
)
def test_wall_ranges_at_any_pose(pose: tuple[float, float, float], x_wall: float) -> None:
    ranges = RingSonar(QUIET, ROBOT).measure(wall_caster(x_wall), pose, np.random.default_rng(0))
    np.testing.assert_allclose(ranges, wall_ranges(pose, x_wall, QUIET), rtol=1e-12, atol=0.0)


def test_a_cylinder_on_a_sonars_axis_reads_its_near_surface() -> None:
    # sonar 3 sits at (0.166, 0.027) facing 10°: a cylinder centred 1.5 m along its axis
    yaw = math.radians(10.0)
    centre = (0.166 + 1.5 * math.cos(yaw), 0.027 + 1.5 * math.sin(yaw))
    radius = 0.2
    ranges = RingSonar(QUIET, ROBOT).measure(
        cylinder_caster(centre, radius), (0.0, 0.0, 0.0), np.random.default_rng(0)
    )
    assert ranges[3] == pytest.approx(1.5 - radius, rel=1e-12)
    # every other sonar: the nearest of its rays' intersections (distance to the centre along
    # the ray, less the half chord), or NaN; no sonar can read nearer than the surface
    for k, (px, py, mount_yaw) in enumerate(ROBOT.sonar_ring):
        to_centre = np.array(centre) - (px, py)
        best = math.inf
        for offset in np.radians(np.linspace(-15.0, 15.0, 7)):
            u = np.array(
                [
                    math.cos(math.radians(mount_yaw) + offset),
                    math.sin(math.radians(mount_yaw) + offset),
                ]
            )
            along = float(u @ to_centre)
            across = float(u[0] * to_centre[1] - u[1] * to_centre[0])
            if along > 0.0 and abs(across) <= radius:
                best = min(best, along - math.sqrt(radius**2 - across**2))
        expected = best if best < 5.0 else math.nan
        if math.isnan(expected):
            assert np.isnan(ranges[k]), k
        else:
            assert ranges[k] == pytest.approx(expected, rel=1e-9), k
            assert ranges[k] >= float(np.linalg.norm(to_centre)) - radius - 1e-12
    assert np.isfinite(ranges[[2, 3, 4]]).all() and np.isnan(ranges[8:]).all()


def test_nearer_than_min_range_reads_nan_not_min_range() -> None:
    # wall 0.1 m before the front sonars: below 0.15 m; the 50° sonars read 0.152 / cos 35°
    ranges = RingSonar(QUIET, ROBOT).measure(
        wall_caster(0.266), (0.0, 0.0, 0.0), np.random.default_rng(0)
    )
    assert np.isnan(ranges[[2, 3, 4, 5]]).all()  # 0.100 and 0.122 m
    assert ranges[1] == pytest.approx(0.152 / math.cos(math.radians(35.0)), rel=1e-12)
    assert ranges[0] == pytest.approx(0.197 / math.cos(math.radians(75.0)), rel=1e-12)
    assert ranges[6] == ranges[1] and ranges[7] == ranges[0]


def test_beyond_max_range_reads_nan() -> None:
    # the front sonars' square-on rays meet the wall at 4.834 m; wall at 5.3 m: 5.134 m
    sonar = RingSonar(QUIET, ROBOT)
    near = sonar.measure(wall_caster(5.0), (0.0, 0.0, 0.0), np.random.default_rng(0))
    assert near[3] == pytest.approx(4.834, rel=1e-12)
    far = sonar.measure(wall_caster(5.3), (0.0, 0.0, 0.0), np.random.default_rng(0))
    assert np.isnan(far).all()


@pytest.mark.parametrize(("true_m", "limit"), [(0.155, "min"), (4.99, "max")])
def test_noise_across_a_range_limit_blanks_and_never_clips(true_m: float, limit: str) -> None:
    config = RingSonarConfig()  # noise 0.01 m, [0.15, 5] m
    sonar = RingSonar(config, ROBOT)
    rng = np.random.default_rng(11)
    caster = constant_caster(true_m / config.max_range_m, body=2)
    draws = np.array([sonar.measure(caster, (0.0, 0.0, 0.0), rng) for _ in range(300)])
    finite = draws[np.isfinite(draws)]
    assert finite.min() >= config.min_range_m and finite.max() <= config.max_range_m
    assert not np.any(finite == config.min_range_m) and not np.any(finite == config.max_range_m)
    # NaN exactly when the noisy range crosses the limit: probability Phi(-0.5) or Phi(-1)
    margin = (true_m - config.min_range_m) if limit == "min" else (config.max_range_m - true_m)
    p = float(norm.sf(margin / config.range_noise_std_m))
    blank = float(np.isnan(draws).mean())
    assert abs(blank - p) < 4.0 * math.sqrt(p * (1.0 - p) / draws.size)


def test_the_noise_has_the_configured_spread() -> None:
    config = RingSonarConfig(range_noise_std_m=0.03)
    sonar = RingSonar(config, ROBOT)
    rng = np.random.default_rng(5)
    pose = (0.0, 0.0, 0.0)
    exact = wall_ranges(pose, 2.0, QUIET)
    heard = np.isfinite(exact)
    assert heard.sum() == 6
    errors = np.array([sonar.measure(wall_caster(2.0), pose, rng) for _ in range(400)])
    assert np.isfinite(errors[:, heard]).all() and np.isnan(errors[:, ~heard]).all()
    e = (errors[:, heard] - exact[heard]).ravel()
    n = e.size
    assert abs(e.mean()) < 4.0 * config.range_noise_std_m / math.sqrt(n)
    statistic = float(np.sum((e - e.mean()) ** 2)) / config.range_noise_std_m**2
    assert chi2.ppf(1e-4, n - 1) < statistic < chi2.isf(1e-4, n - 1)
    # independent draws per sonar and per measurement
    per_sonar = errors[:, heard] - exact[heard]
    correlation = np.corrcoef(per_sonar.T)
    off_diagonal = correlation[~np.eye(len(correlation), dtype=bool)]
    assert np.all(np.abs(off_diagonal) < 4.0 / math.sqrt(len(per_sonar)))


def test_hits_on_the_robots_own_body_are_no_echo() -> None:
    sonar = RingSonar(QUIET, ROBOT)
    rng = np.random.default_rng(0)
    own = constant_caster(0.2, body=5)  # 1 m along every ray
    np.testing.assert_allclose(
        sonar.measure(own, (0.0, 0.0, 0.0), rng, ignore_body=4), np.full(16, 1.0), rtol=1e-12
    )
    assert np.isnan(sonar.measure(own, (0.0, 0.0, 0.0), rng, ignore_body=5)).all()
    # the robot's own body in the way of the left sonars' rays (starts at y > 0), the wall
    # at x = 2 m for the others: the left sonars hear nothing, the right ones the wall
    wall = wall_caster(2.0)

    def shadowed(starts: FloatArray, ends: FloatArray) -> tuple[FloatArray, NDArray[np.int64]]:
        fractions, bodies = wall(starts, ends)
        left = starts[:, 1] > 0.0
        return np.where(left, 0.01, fractions), np.where(left, 5, bodies).astype(np.int64)

    ranges = sonar.measure(shadowed, (0.0, 0.0, 0.0), rng, ignore_body=5)
    expected = wall_ranges((0.0, 0.0, 0.0), 2.0, QUIET)
    left = ROBOT.sonar_positions_m()[:, 1] > 0.0
    assert np.isnan(ranges[left]).all()
    np.testing.assert_allclose(ranges[~left], expected[~left], rtol=1e-12)
    assert np.isfinite(ranges[[4, 5, 6]]).all()


def test_a_caster_reporting_no_body_is_no_echo() -> None:
    # a fraction below 1 with body -1 is no hit
    ranges = RingSonar(QUIET, ROBOT).measure(
        constant_caster(0.2, body=-1), (0.0, 0.0, 0.0), np.random.default_rng(0)
    )
    assert np.isnan(ranges).all()


def test_rays_fan_from_the_sonar_discs() -> None:
    sonar = RingSonar(RingSonarConfig(cone_deg=20.0, rays_per_sonar=5), ROBOT)
    pose = (1.0, 2.0, math.pi / 2)  # facing +y: robot (x, y) -> field (1 - y, 2 + x)
    starts, ends = sonar.rays(pose)
    assert starts.shape == ends.shape == (16 * 5, 3)
    positions = ROBOT.sonar_positions_m()
    field = np.column_stack([1.0 - positions[:, 1], 2.0 + positions[:, 0]])
    np.testing.assert_allclose(starts[:, :2], np.repeat(field, 5, axis=0), atol=1e-12)
    np.testing.assert_allclose(starts[:, 2], ROBOT.sonar_height_m)
    np.testing.assert_allclose(ends[:, 2], ROBOT.sonar_height_m)
    np.testing.assert_allclose(np.linalg.norm(ends - starts, axis=1), 5.0, rtol=1e-12)
    heading = np.degrees(np.arctan2(*(ends - starts)[:, 1::-1].T))
    yaw = np.array([mount[2] for mount in ROBOT.sonar_ring])
    expected = 90.0 + yaw[:, None] + np.array([-10.0, -5.0, 0.0, 5.0, 10.0])
    difference = (heading - expected.ravel() + 180.0) % 360.0 - 180.0
    np.testing.assert_allclose(difference, 0.0, atol=1e-9)


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("cone_deg", 0.0),
        ("cone_deg", -5.0),
        ("cone_deg", 180.0),
        ("cone_deg", math.nan),
        ("rays_per_sonar", 0),
        ("min_range_m", 0.0),
        ("min_range_m", -0.1),
        ("max_range_m", 0.0),
        ("max_range_m", math.inf),
        ("range_noise_std_m", -0.01),
        ("range_noise_std_m", math.nan),
    ],
)
def test_config_refuses_bad_values(field: str, value: float) -> None:
    kwargs: dict[str, Any] = {field: value}
    with pytest.raises(ValueError, match=rf"RingSonarConfig\.{field}"):
        RingSonarConfig(**kwargs)


@pytest.mark.parametrize(
    ("field", "value"), [("rays_per_sonar", 2.0), ("rays_per_sonar", True), ("cone_deg", "30")]
)
def test_config_refuses_wrong_types(field: str, value: object) -> None:
    kwargs: dict[str, Any] = {field: value}
    with pytest.raises(InvalidTypeError, match=rf"RingSonarConfig\.{field}"):
        RingSonarConfig(**kwargs)


@pytest.mark.parametrize(("low", "high"), [(1.0, 1.0), (2.0, 1.0)])
def test_config_needs_min_below_max_range(low: float, high: float) -> None:
    with pytest.raises(ValueError, match=r"RingSonarConfig\.min_range_m"):
        RingSonarConfig(min_range_m=low, max_range_m=high)


def test_config_accepts_zero_noise_and_defaults() -> None:
    assert RingSonarConfig(range_noise_std_m=0.0).range_noise_std_m == 0.0
    config = RingSonarConfig()
    assert (config.cone_deg, config.rays_per_sonar) == (30.0, 7)
    assert (config.min_range_m, config.max_range_m, config.range_noise_std_m) == (0.15, 5.0, 0.01)


@pytest.mark.parametrize("pose", [[math.nan, 0.0, 0.0], [0.0, math.inf, 0.0], [0.0, 0.0]])
def test_a_pose_that_is_not_finite_or_not_3_is_refused_not_heard_as_silence(pose) -> None:
    with pytest.raises(ValueError, match="robot_pose"):
        RingSonar(QUIET, ROBOT).rays(pose)
