"""The online circle map (perception/circles/circle_map.py) on analytic laser scans.

Scans are built with ray/circle intersections (seed 001's polar model, written here again from
the law of cosines) from known robot poses; the map sees the true pose with a tiny covariance
unless a test says otherwise.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from perception.circles.circle_map import CircleMapConfig, CircleMapper
from perception.circles.segmentation import BreakpointConfig
from perception.sensor_models import LaserModel

ANGLES = np.radians(-90.0 + 0.25 * np.arange(720))  # 0.25° beams over 180°
SIGMA = 0.02
TINY_COV = np.diag([1e-8, 1e-8, 1e-10])
COLUMNS = np.array([[2.0, 0.5, 0.05], [3.0, -1.0, 0.05], [1.5, -0.3, 0.25], [4.0, 1.5, 0.5]])


def scan(pose: np.ndarray, circles: np.ndarray, rng: np.random.Generator | None) -> np.ndarray:
    """Ranges (B,) from ``pose`` to the nearest of ``circles`` (K, 3) along each beam; NaN
    where a beam meets none; Gaussian noise ``SIGMA`` when ``rng`` is given."""
    beta = pose[2] + ANGLES
    u = np.column_stack([np.cos(beta), np.sin(beta)])
    ranges = np.full(len(ANGLES), np.nan)
    for cx, cy, radius in circles:
        d = np.array([cx, cy]) - pose[:2]
        along = u @ d
        across2 = d @ d - along**2
        hit = (across2 <= radius**2) & (along > 0)
        r = along - np.sqrt(np.where(hit, radius**2 - across2, 0.0))
        ranges = np.fmin(ranges, np.where(hit, r, np.nan))
    return ranges if rng is None else ranges + SIGMA * rng.standard_normal(len(ranges))


def drive(steps: int) -> list[np.ndarray]:
    """Poses (3,) of a slow arc past the columns."""
    return [np.array([0.02 * k - 1.0, 0.01 * k, 0.003 * k]) for k in range(steps)]


def matched_error(mapper: CircleMapper, truth: np.ndarray) -> np.ndarray:
    """Per true circle, the |(x, y, R)| error components (K, 2): centre distance and |dR| of
    the nearest confirmed circle."""
    confirmed = np.array([c.state for c in mapper.circles if c.confirmed])
    out = []
    for circle in truth:
        gaps = np.hypot(*(confirmed[:, :2] - circle[:2]).T)
        j = int(np.argmin(gaps))
        out.append([gaps[j], abs(confirmed[j, 2] - circle[2])])
    return np.array(out)


def test_noiseless_scans_map_every_column_exactly() -> None:
    mapper = CircleMapper()
    for pose in drive(100):
        mapper.update(ANGLES, scan(pose, COLUMNS, None), 0.0, pose, TINY_COV)
    errors = matched_error(mapper, COLUMNS)
    assert errors.max() < 1e-3
    assert len([c for c in mapper.circles if c.confirmed]) == len(COLUMNS)
    assert mapper.refused == 0


def test_noisy_scans_map_within_a_centimetre_and_the_covariance_is_honest() -> None:
    rng = np.random.default_rng(4)
    mapper = CircleMapper()
    for pose in drive(100):
        mapper.update(ANGLES, scan(pose, COLUMNS, rng), 0.0, pose, TINY_COV)
    errors = matched_error(mapper, COLUMNS)
    assert errors[:, 0].max() < 0.01 and errors[:, 1].max() < 0.01
    for circle in mapper.circles:
        assert np.allclose(circle.cov, circle.cov.T)
        assert np.linalg.eigvalsh(circle.cov).min() > 0
        truth = COLUMNS[np.argmin(np.hypot(*(COLUMNS[:, :2] - circle.state[:2]).T))]
        gap = circle.state - truth
        # 3 dof: 99.9 % of chi-square draws are below 16.27; the pose is exact here
        assert gap @ np.linalg.solve(circle.cov, gap) < 16.27


def test_a_walking_object_is_not_kept_as_a_static_circle() -> None:
    rng = np.random.default_rng(5)
    mapper = CircleMapper(CircleMapConfig(confirm_hits=5))
    pose = np.array([0.0, 0.0, 0.0])
    wall = np.array([[55.0, 0.0, 50.0]])  # 5 m ahead: beams that pass the walker return
    for k in range(60):
        walker = np.array([[2.0, -0.6 + 0.02 * k, 0.1]])  # 0.2 m/s across the view
        mapper.update(ANGLES, scan(pose, np.vstack([walker, wall]), rng), 0.0, pose, TINY_COV)
    # the places it stood more than a body width (plus the gate's three sigma) ago are dropped
    for circle in mapper.circles:
        assert not circle.confirmed or np.hypot(*(circle.state[:2] - walker[0, :2])) < 0.25


def test_a_column_half_hidden_behind_a_nearer_one_is_not_a_candidate() -> None:
    pose = np.array([0.0, 0.0, 0.0])
    front = np.array([[1.0, 0.0, 0.1]])
    behind = np.array([[3.0, 0.2, 0.15]])  # its right half is in the front column's shadow
    mapper = CircleMapper(CircleMapConfig(confirm_hits=1))
    mapper.update(ANGLES, scan(pose, np.vstack([front, behind]), None), 0.0, pose, TINY_COV)
    states = np.array([c.state for c in mapper.circles])
    assert len(states) == 1 and np.allclose(states[0], front[0], atol=1e-3)


def test_the_pose_covariance_widens_the_map() -> None:
    pose = np.array([0.0, 0.0, 0.0])
    wide = np.diag([0.05**2, 0.05**2, 0.02**2])
    stds = []
    for cov in (TINY_COV, wide):
        mapper = CircleMapper()
        mapper.update(ANGLES, scan(pose, COLUMNS[:1], None), 0.0, pose, cov)
        stds.append(math.sqrt(mapper.circles[0].cov[0, 0]))
    assert stds[1] > 2 * stds[0]


@pytest.mark.parametrize(
    ("field", "value", "match"),
    [
        ("range_sigma_m", 0.0, "range_sigma_m"),
        ("max_radius_m", float("nan"), "max_radius_m"),
        ("min_radius_m", 2.0, "min_radius_m"),
        ("gate_probability", 1.0, "gate_probability"),
        ("confirm_hits", 0, "confirm_hits"),
        ("iterations", 1.5, "iterations"),
        ("segmentation", "breakpoints", "segmentation"),
    ],
)
def test_config_validation(field: str, value: object, match: str) -> None:
    with pytest.raises((ValueError, TypeError), match=match):
        CircleMapConfig(**{field: value})  # type: ignore[arg-type]


def test_bad_pose_and_covariance_are_refused() -> None:
    mapper = CircleMapper(CircleMapConfig(segmentation=BreakpointConfig(min_points=3)))
    ranges = scan(np.zeros(3), COLUMNS, None)
    with pytest.raises(ValueError, match="pose"):
        mapper.update(ANGLES, ranges, 0.0, np.array([0.0, np.nan, 0.0]), TINY_COV)
    with pytest.raises(ValueError, match="pose_cov"):
        mapper.update(ANGLES, ranges, 0.0, np.zeros(3), -TINY_COV)


def test_beams_without_return_as_inf_or_nan_are_alike() -> None:
    """A beam with no return, NaN or +inf, says nothing of what lies beyond a mapped circle:
    three scans blank over a confirmed pole keep it either way (+inf had counted as a return
    from behind it, dropping the pole)."""
    angles = LaserModel().beam_angles()
    pole = np.array([1.2, 0.05, 0.05])  # centre (m), radius (m)
    rho, phi = math.hypot(*pole[:2]), math.atan2(pole[1], pole[0])
    offset = angles - phi
    inside = pole[2] ** 2 - (rho * np.sin(offset)) ** 2
    hit = (inside >= 0) & (np.cos(offset) > 0)
    ranges = np.full(len(angles), 8.0)
    ranges[hit] = rho * np.cos(offset[hit]) - np.sqrt(inside[hit])
    kept = {}
    for no_return in (math.nan, math.inf):
        mapper = CircleMapper()
        for _ in range(12):
            mapper.update(angles, ranges, 0.0, np.zeros(3), np.diag([1e-4] * 3))
        assert [c.confirmed for c in mapper.circles] == [True]
        blank = np.where(np.abs(offset) < 0.2, no_return, ranges)
        for _ in range(3):
            mapper.update(angles, blank, 0.0, np.zeros(3), np.diag([1e-4] * 3))
        kept[no_return] = len(mapper.circles)
    assert list(kept.values()) == [1, 1]
