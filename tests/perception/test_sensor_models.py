"""Laser and sonar models: seed 001's beam layout, the sonar's sector geometry, bad input."""

from __future__ import annotations

import dataclasses
import math
from dataclasses import replace
from typing import Any

import numpy as np
import pytest

from perception.sensor_models import LaserModel, SonarModel

SEED_001_LASER = LaserModel(  # Hokuyo UST-30LX on a Pioneer 3-DX: 180 beams over 180°
    n_beams=180,
    fov_deg=180.0,
    min_range_m=0.1,
    max_range_m=10.0,
    range_noise_std_m=0.02,
    mount_x_m=0.0,
    mount_height_m=0.30,
)
NAO_SONAR = SonarModel(  # seed 004's three sectors
    sector_centres_deg=(25.0, 0.0, -25.0),
    sector_widths_deg=(60.0, 40.0, 60.0),
    min_range_m=0.25,
    max_range_m=2.55,
    max_echoes=10,
    echo_merge_m=0.05,
    range_noise_std_m=0.01,
    mount_x_m=0.05,
    mount_height_m=0.30,
)


def test_laser_beams_follow_seed_001() -> None:
    # Seed 001 scans φ = 0°, 1°, ..., 179° from the robot's right to its left; angle = φ - 90°.
    angles = SEED_001_LASER.beam_angles()
    assert angles.shape == (180,)
    np.testing.assert_allclose(np.rad2deg(angles) + 90.0, np.arange(180.0), atol=1e-12)
    assert angles[90] == 0.0  # one beam straight ahead


def test_laser_beams_are_evenly_spaced_from_the_right_edge_of_the_field_of_view() -> None:
    model = replace(SEED_001_LASER, n_beams=360, fov_deg=270.0)
    angles = model.beam_angles()
    assert angles[0] == pytest.approx(-math.radians(135.0), abs=1e-15)
    np.testing.assert_allclose(np.diff(angles), math.radians(270.0) / 360, rtol=1e-12)
    full = replace(SEED_001_LASER, n_beams=4, fov_deg=360.0).beam_angles()
    np.testing.assert_allclose(full, [-math.pi, -math.pi / 2, 0.0, math.pi / 2], atol=1e-15)
    assert replace(SEED_001_LASER, n_beams=1).beam_angles().shape == (1,)


def test_sonar_sector_geometry() -> None:
    np.testing.assert_allclose(np.rad2deg(NAO_SONAR.sector_centres_rad()), [25.0, 0.0, -25.0])
    np.testing.assert_allclose(np.rad2deg(NAO_SONAR.sector_widths_rad()), [60.0, 40.0, 60.0])
    bounds = np.rad2deg(NAO_SONAR.sector_bounds_rad())
    assert bounds.shape == (3, 2)
    # (right, left) edges; the side cones reach 5° past the heading into the middle one.
    np.testing.assert_allclose(bounds, [[-5.0, 55.0], [-20.0, 20.0], [-55.0, 5.0]], atol=1e-12)


def test_models_are_frozen_and_keyword_only() -> None:
    with pytest.raises(dataclasses.FrozenInstanceError):
        SEED_001_LASER.n_beams = 90  # type: ignore[misc]
    with pytest.raises(TypeError):
        LaserModel(180, 180.0, 0.1, 10.0, 0.02, 0.0, 0.3)  # type: ignore[call-arg]
    with pytest.raises(TypeError):
        SonarModel((25.0, 0.0, -25.0))  # type: ignore[call-arg]


def test_defaults_are_seed_001_laser_and_nao_sonar() -> None:
    assert LaserModel() == SEED_001_LASER
    assert SonarModel() == NAO_SONAR


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("n_beams", 0),
        ("n_beams", 90.0),
        ("n_beams", True),
        ("fov_deg", 0.0),
        ("fov_deg", 400.0),
        ("fov_deg", math.nan),
        ("min_range_m", 0.0),
        ("min_range_m", 20.0),
        ("max_range_m", math.inf),
        ("range_noise_std_m", -0.1),
        ("range_noise_std_m", math.nan),
        ("mount_x_m", math.nan),
        ("mount_height_m", -0.3),
    ],
)
def test_bad_laser_model_raises_naming_the_field(field: str, value: Any) -> None:
    with pytest.raises(ValueError, match=f"laser\\.{field}"):
        replace(SEED_001_LASER, **{field: value})


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("sector_centres_deg", (25.0, 0.0)),
        ("sector_centres_deg", (25.0, math.nan, -25.0)),
        ("sector_widths_deg", (60.0, 0.0, 60.0)),
        ("sector_widths_deg", (60.0, 40.0, 200.0)),
        ("min_range_m", 3.0),
        ("max_range_m", -1.0),
        ("max_echoes", 0),
        ("max_echoes", 2.5),
        ("echo_merge_m", 0.0),
        ("range_noise_std_m", -0.01),
        ("mount_x_m", math.inf),
        ("mount_height_m", 0.0),
    ],
)
def test_bad_sonar_model_raises_naming_the_field(field: str, value: Any) -> None:
    with pytest.raises(ValueError, match=f"sonar\\.{field}"):
        replace(NAO_SONAR, **{field: value})
