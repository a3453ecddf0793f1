"""Sonar and laser models against closed-form scenes behind a fake ray caster (no PyBullet)."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import fields, replace

import numpy as np
import pytest
from scipy.stats import binom, chi2

from perception.sensor_models import LaserModel, SonarModel
from spl_env.sensors.laser import Laser, LaserConfig
from spl_env.sensors.sonar import Sonar, SonarConfig, merge_echoes, surface_echoes

# Fraction along each ray (N,) where it first meets a shape, inf where it does not.
Shape = Callable[[np.ndarray, np.ndarray], np.ndarray]


def wall(normal: tuple[float, float], offset: float) -> Shape:
    """The vertical plane ``normal . (x, y) = offset``."""
    n = np.array([*normal, 0.0])

    def fraction(starts: np.ndarray, ends: np.ndarray) -> np.ndarray:
        s, e = starts @ n, ends @ n
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (offset - s) / (e - s)
        return np.where((e != s) & (t >= 0) & (t <= 1), t, np.inf)

    return fraction


def cylinder(centre: tuple[float, float], radius: float) -> Shape:
    """An infinitely tall vertical cylinder."""

    def fraction(starts: np.ndarray, ends: np.ndarray) -> np.ndarray:
        d, f = ends[:, :2] - starts[:, :2], starts[:, :2] - np.asarray(centre)
        a, b, c = np.sum(d * d, 1), 2 * np.sum(f * d, 1), np.sum(f * f, 1) - radius**2
        disc = b**2 - 4 * a * c
        t = (-b - np.sqrt(np.maximum(disc, 0.0))) / (2 * a)
        return np.where((disc >= 0) & (t >= 0) & (t <= 1), t, np.inf)

    return fraction


class Scene:
    """A fake :class:`RayCaster`: the nearest of some shapes, each with a body id."""

    def __init__(self, *bodies: tuple[int, Shape]) -> None:
        self.bodies = bodies

    def __call__(self, starts: np.ndarray, ends: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        fractions = np.full(len(starts), np.inf)
        ids = np.full(len(starts), -1, dtype=np.int64)
        for body, shape in self.bodies:
            t = shape(starts, ends)
            nearer = t < fractions
            fractions[nearer], ids[nearer] = t[nearer], body
        return np.where(np.isfinite(fractions), fractions, 1.0), ids


def assert_chi2_std(residuals: np.ndarray, std: float) -> None:
    """Residuals are N(0, std²): their normalised sum of squares lies in a 1e-4 chi-square band."""
    r = np.ravel(residuals) / std
    lo, hi = chi2.ppf([1e-4, 1 - 1e-4], df=r.size)
    assert lo < np.sum(r**2) < hi


RNG = np.random.default_rng
EXACT_LASER = LaserConfig(range_noise_std_m=0.0)
EXACT_SONAR = SonarConfig(range_noise_std_m=0.0, dropout_probability=0.0)


# --- laser ---------------------------------------------------------------------------------------


def test_laser_beams_follow_seed_001() -> None:
    angles = Laser(LaserConfig()).beam_angles()
    assert angles.shape == (180,)
    np.testing.assert_allclose(np.rad2deg(angles), np.arange(-90.0, 90.0), atol=1e-12)


@pytest.mark.parametrize("pose", [(0.0, 0.0, 0.0), (1.0, 2.0, math.pi / 2)])
def test_laser_sees_a_wall_at_d_over_cos_angle(pose: tuple[float, float, float]) -> None:
    d = 2.0  # the wall is d ahead of the robot, facing it
    heading = np.array([math.cos(pose[2]), math.sin(pose[2])])
    scene = Scene((3, wall(tuple(heading), float(heading @ pose[:2]) + d)))
    laser = Laser(EXACT_LASER)
    angles = laser.beam_angles()
    ranges = laser.measure(scene, pose, RNG(0))
    with np.errstate(divide="ignore"):
        expected = np.where(np.cos(angles) > 1e-9, d / np.cos(angles), np.inf)
    expected[expected > EXACT_LASER.max_range_m] = np.nan
    np.testing.assert_allclose(ranges, expected, rtol=1e-12)
    assert np.isnan(ranges[0]) and np.isfinite(ranges[90])


def test_laser_measures_from_its_mount() -> None:
    laser = Laser(replace(EXACT_LASER, mount_x_m=0.2))
    ranges = laser.measure(Scene((0, cylinder((3.0, 0.0), 0.5))), (0.0, 0.0, 0.0), RNG(0))
    assert ranges[90] == pytest.approx(3.0 - 0.5 - 0.2, abs=1e-12)


def test_laser_returns_nan_for_nothing_and_for_its_own_body() -> None:
    laser = Laser(EXACT_LASER)
    assert np.all(np.isnan(laser.measure(Scene(), (0.0, 0.0, 0.0), RNG(0))))
    own = Scene((4, cylinder((0.0, 0.0), 5.0)))
    assert np.all(np.isnan(laser.measure(own, (0.0, 0.0, 0.0), RNG(0), ignore_body=4)))


def test_laser_range_noise_matches_seed_001_sigma() -> None:
    laser = Laser(LaserConfig())
    scene = Scene((1, wall((1.0, 0.0), 3.0)))
    rng = RNG(7)
    front = np.abs(laser.beam_angles()) < math.radians(60)
    scans = np.array([laser.measure(scene, (0.0, 0.0, 0.0), rng) for _ in range(50)])[:, front]
    assert_chi2_std(scans - 3.0 / np.cos(laser.beam_angles()[front]), 0.02)


def test_laser_drops_noisy_returns_beyond_its_range() -> None:
    laser = Laser(LaserConfig(max_range_m=5.0, range_noise_std_m=0.05))
    scene = Scene((1, cylinder((5.0, 0.0), 0.02)))  # central beam hits at 4.98
    ranges = np.array([laser.measure(scene, (0.0, 0.0, 0.0), RNG(s))[90] for s in range(400)])
    assert np.all(ranges[np.isfinite(ranges)] <= 5.0)
    assert 0 < np.count_nonzero(np.isnan(ranges)) < 400


def test_laser_is_deterministic_per_seed() -> None:
    laser, scene = Laser(LaserConfig()), Scene((1, wall((1.0, 0.0), 3.0)))
    first = laser.measure(scene, (0.0, 0.0, 0.0), RNG(11))
    np.testing.assert_array_equal(first, laser.measure(scene, (0.0, 0.0, 0.0), RNG(11)))
    assert not np.array_equal(first, laser.measure(scene, (0.0, 0.0, 0.0), RNG(12)))


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("n_beams", 0),
        ("fov_deg", 400.0),
        ("max_range_m", -1.0),
        ("range_noise_std_m", -0.1),
        ("min_range_m", 20.0),
    ],
)
def test_bad_laser_config_raises_naming_the_field(field: str, value: object) -> None:
    with pytest.raises(ValueError, match=f"laser.{field}"):
        LaserConfig(**{field: value})  # type: ignore[arg-type]


def test_configs_are_the_perception_models() -> None:
    # The configs are the models perception interprets the readings with; the sonar adds only
    # the simulation's rays per sector and dropout. A plain LaserModel configures a Laser too.
    laser_config, sonar_config = LaserConfig(n_beams=90), SonarConfig(max_echoes=4)
    assert isinstance(laser_config, LaserModel) and isinstance(sonar_config, SonarModel)
    assert Laser(laser_config).model is laser_config
    assert Sonar(sonar_config).model is sonar_config
    shared = {f.name for f in fields(SonarModel)}
    assert {f.name for f in fields(SonarConfig)} - shared == {
        "rays_per_sector",
        "dropout_probability",
    }
    assert all(getattr(SonarConfig(), name) == getattr(SonarModel(), name) for name in shared)
    scene = Scene((1, wall((1.0, 0.0), 3.0)))
    np.testing.assert_array_equal(
        Laser(LaserModel(n_beams=90)).measure(scene, (0.0, 0.0, 0.0), RNG(5)),
        Laser(laser_config).measure(scene, (0.0, 0.0, 0.0), RNG(5)),
    )


def test_laser_rejects_bad_pose_and_bad_caster_output() -> None:
    laser = Laser(LaserConfig())
    with pytest.raises(ValueError, match="robot_pose"):
        laser.measure(Scene(), (0.0, 0.0), RNG(0))
    with pytest.raises(ValueError, match="ray_caster"):
        laser.measure(lambda s, e: (np.ones(3), np.full(3, -1)), (0.0, 0.0, 0.0), RNG(0))


# --- sonar ---------------------------------------------------------------------------------------


def test_sonar_rays_fan_from_the_chest() -> None:
    config = SonarConfig()
    starts, ends = Sonar(config).rays((1.0, -1.0, math.pi))
    assert starts.shape == ends.shape == (3 * config.rays_per_sector, 3)
    expected_start = [1.0 - config.mount_x_m, -1.0, config.mount_height_m]
    np.testing.assert_allclose(starts, np.broadcast_to(expected_start, starts.shape), atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(ends - starts, axis=1), config.max_range_m)


def test_ray_fans_are_float_and_fresh_whatever_the_numbers_given() -> None:
    # whole-number mounts and ranges are valid config values: the rays must not become integers
    sonar = Sonar(SonarConfig(mount_x_m=0, mount_height_m=1, max_range_m=2))
    starts, ends = sonar.rays((0.4, 0.3, 0.2))
    assert starts.dtype == ends.dtype == np.float64
    np.testing.assert_allclose(starts[0], [0.4, 0.3, 1.0], atol=1e-15)
    np.testing.assert_allclose(np.linalg.norm(ends - starts, axis=1), 2.0)
    starts[:] = np.nan  # each call's arrays are the caller's own
    assert np.all(np.isfinite(sonar.rays((0.4, 0.3, 0.2))[0]))


def test_sonar_sees_a_cylinder_ahead_in_the_middle_and_in_both_side_cones() -> None:
    # The default side cones (60° wide, centred 25° out) overlap the middle by 5°: a central
    # obstacle echoes on both sides too (seed 004), on their rays nearest ahead, 1° off axis.
    d, r = 1.5, 0.1
    sonar = Sonar(EXACT_SONAR)
    echoes = sonar.measure(Scene((2, cylinder((d, 0.0), r))), (0.0, 0.0, 0.0), RNG(0))
    assert echoes.shape == (3, 10)
    centre = d - EXACT_SONAR.mount_x_m  # from the transducers
    off = math.radians(1.0)
    side = centre * math.cos(off) - math.sqrt(r**2 - (centre * math.sin(off)) ** 2)
    np.testing.assert_allclose(echoes[:, 0], [side, centre - r, side], rtol=1e-12)
    assert np.all(np.isnan(echoes[:, 1:]))


def test_sonar_with_disjoint_sectors_sees_a_cylinder_ahead_only_in_the_middle() -> None:
    config = replace(EXACT_SONAR, sector_centres_deg=(40.0, 0.0, -40.0))  # 60°, 40°, 60° wide
    echoes = Sonar(config).measure(Scene((2, cylinder((1.5, 0.0), 0.1))), (0.0, 0.0, 0.0), RNG(0))
    assert echoes[1, 0] == pytest.approx(1.5 - config.mount_x_m - 0.1, abs=1e-12)
    assert np.all(np.isnan(echoes[1, 1:])) and np.all(np.isnan(echoes[[0, 2]]))


@pytest.mark.parametrize(("bearing_deg", "sector"), [(45.0, 0), (-45.0, 2)])
def test_sonar_sees_a_cylinder_to_the_side_only_in_that_sector(
    bearing_deg: float, sector: int
) -> None:
    # A rotated robot, and a cylinder 1.2 m from the transducers along a ray at 45° to a side.
    pose = np.array([0.5, 0.5, 0.4])
    origin = pose[:2] + EXACT_SONAR.mount_x_m * np.array([math.cos(0.4), math.sin(0.4)])
    bearing = 0.4 + math.radians(bearing_deg)
    centre = origin + 1.2 * np.array([math.cos(bearing), math.sin(bearing)])
    echoes = Sonar(EXACT_SONAR).measure(Scene((5, cylinder(tuple(centre), 0.05))), pose, RNG(0))
    assert echoes[sector, 0] == pytest.approx(1.2 - 0.05, abs=1e-12)
    others = [s for s in range(3) if s != sector]
    assert np.all(np.isnan(echoes[others])) and np.all(np.isnan(echoes[sector, 1:]))


def test_sonar_gives_one_echo_per_wall_per_sector() -> None:
    d = 1.0
    echoes = Sonar(EXACT_SONAR).measure(Scene((1, wall((1.0, 0.0), d))), (0.0, 0.0, 0.0), RNG(0))
    near = d - EXACT_SONAR.mount_x_m
    # The middle sector has a ray straight ahead; the side sectors' nearest rays are 1° off.
    expected = [near / math.cos(math.radians(1.0)), near, near / math.cos(math.radians(1.0))]
    np.testing.assert_allclose(echoes[:, 0], expected, rtol=1e-12)
    assert np.all(np.isnan(echoes[:, 1:]))


def middle_sector_scene(distances: list[float]) -> Scene:
    """Thin cylinders in the middle sector, each on a ray, at the given distances from the sonar."""
    sonar = Sonar(EXACT_SONAR)
    n = EXACT_SONAR.rays_per_sector
    angles = sonar.ray_angles()[n + 3 : 2 * n : 6]  # -16°, -8°, 0°, 8°, 16°
    x0 = EXACT_SONAR.mount_x_m
    r = 0.02
    return Scene(
        *(
            (10 + i, cylinder((x0 + (s + r) * math.cos(a), (s + r) * math.sin(a)), r))
            for i, (s, a) in enumerate(zip(distances, angles, strict=False))
        )
    )


def test_sonar_echoes_sorted_merged_and_capped() -> None:
    scene = middle_sector_scene([1.8, 0.6, 1.2, 0.63, 1.5])
    sonar = Sonar(replace(EXACT_SONAR, max_echoes=3))
    echoes = sonar.measure(scene, (0.0, 0.0, 0.0), RNG(0))
    # 0.6 and 0.63 are within 5 cm and merge into 0.6; then the 3 nearest.
    np.testing.assert_allclose(echoes[1], [0.6, 1.2, 1.5], atol=1e-12)
    all_echoes = Sonar(EXACT_SONAR).measure(scene, (0.0, 0.0, 0.0), RNG(0))[1]
    np.testing.assert_allclose(all_echoes[:4], [0.6, 1.2, 1.5, 1.8], atol=1e-12)
    assert np.all(np.isnan(all_echoes[4:]))


def test_sonar_drops_echoes_outside_its_range() -> None:
    scene = middle_sector_scene([0.2, 1.0])  # 0.2 m is inside the blind zone
    echoes = Sonar(EXACT_SONAR).measure(scene, (0.0, 0.0, 0.0), RNG(0))
    assert echoes[1, 0] == pytest.approx(1.0, abs=1e-12) and np.isnan(echoes[1, 1])
    noisy = Sonar(replace(EXACT_SONAR, range_noise_std_m=0.05))
    edge = middle_sector_scene([2.54])
    firsts = np.array([noisy.measure(edge, (0.0, 0.0, 0.0), RNG(s))[1, 0] for s in range(200)])
    seen = firsts[np.isfinite(firsts)]
    assert 0 < len(seen) < 200 and np.all(seen < EXACT_SONAR.max_range_m)


def test_sonar_range_noise_and_dropout_match_the_config() -> None:
    config = replace(EXACT_SONAR, range_noise_std_m=0.01, dropout_probability=0.3)
    sonar, rng = Sonar(config), RNG(3)
    scene = middle_sector_scene([1.0])
    firsts = np.array([sonar.measure(scene, (0.0, 0.0, 0.0), rng)[1, 0] for _ in range(2000)])
    lost = int(np.count_nonzero(np.isnan(firsts)))
    assert binom.ppf(1e-4, 2000, 0.3) <= lost <= binom.ppf(1 - 1e-4, 2000, 0.3)
    assert_chi2_std(firsts[np.isfinite(firsts)] - 1.0, 0.01)


def test_sonar_ignores_its_own_body_and_is_deterministic() -> None:
    own = Scene((4, cylinder((0.0, 0.0), 1.0)))
    assert np.all(np.isnan(Sonar(EXACT_SONAR).measure(own, (0.0, 0.0, 0.0), RNG(0), 4)))
    sonar, scene = Sonar(SonarConfig()), middle_sector_scene([0.6, 1.2, 1.8])
    first = sonar.measure(scene, (0.0, 0.0, 0.0), RNG(9))
    np.testing.assert_array_equal(first, sonar.measure(scene, (0.0, 0.0, 0.0), RNG(9)))


def test_surface_echoes_split_runs_of_rays_per_body() -> None:
    nan = math.nan
    distances = [1.0, 0.9, nan, 2.0, 2.1, 0.5, 0.4, 1.5]
    bodies = [3, 3, -1, 3, 3, 7, 7, 3]
    assert sorted(surface_echoes(distances, bodies)) == [0.4, 0.9, 1.5, 2.0]
    # a NaN distance is no hit whatever the body: it splits the run too
    assert surface_echoes([1.0, nan, 0.8], [3, 3, 3]) == [1.0, 0.8]
    assert surface_echoes([], []) == []
    # chains by consecutive spacing, in any input order: 1.0-1.04-1.08 is one echo at 1.0
    assert merge_echoes([1.2, 1.08, 1.0, 1.04], 0.05) == [1.0, 1.2]
    assert merge_echoes([2.0, 1.0], 0.05) == [1.0, 2.0]
    assert merge_echoes([], 0.05) == []
    # no echo is not an echo: NaN anywhere, and surfaces whose nearest point is not finite
    assert merge_echoes([3.0, nan, 1.0], 0.05) == [1.0, 3.0]
    inf = math.inf
    assert surface_echoes([inf, inf, 1.0], [3, 3, 4]) == [1.0]


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("min_range_m", 3.0),
        ("sector_widths_deg", (60.0, 0.0, 60.0)),
        ("rays_per_sector", 0),
        ("max_echoes", 2.5),
        ("dropout_probability", 1.0),
        ("range_noise_std_m", math.nan),
    ],
)
def test_bad_sonar_config_raises_naming_the_field(field: str, value: object) -> None:
    with pytest.raises(ValueError, match=f"sonar.{field}"):
        SonarConfig(**{field: value})  # type: ignore[arg-type]
