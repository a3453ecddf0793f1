"""Horizon features of an image (:mod:`perception.landmarks.horizon_features`): bearings from
the pinhole model, features only where the horizon shows, and the odometry providers."""

from __future__ import annotations

import math

import numpy as np

from perception.landmarks.horizon_features import (
    HorizonFeatureConfig,
    HorizonFeatures,
    horizon_features,
)
from perception.landmarks.surf1d import Surf1dFeatures
from perception.providers.landmarks import WalkOdometry, features_off_robots
from perception.types import CameraModel, CameraState, RobotSighting

CAMERA = CameraModel()


def level(head_yaw: float = 0.0, pitch: float = 0.0) -> CameraState:
    return CameraState(position=np.array([0.05, 0.0, 0.5]), head_yaw=head_yaw, head_pitch=pitch)


def bars(columns: list[int], width: int = 6) -> np.ndarray:
    """A grey RGB image with dark vertical bars centred on ``columns``."""
    image = np.full((CAMERA.height, CAMERA.width, 3), 180, dtype=np.uint8)
    for u in columns:
        image[:, u - width // 2 : u + width // 2] = 40
    return image


def test_bar_features_carry_the_pinhole_bearings_of_their_columns() -> None:
    columns = [60, 140, 220]
    found = horizon_features(bars(columns), CAMERA, level(head_yaw=0.4), HorizonFeatureConfig())
    assert found.head_yaw == 0.4
    dark = found.features.laplacian > 0  # dark blobs: the bars
    # the finest-scale dark feature nearest each bar sits on it (within a sample step)
    for u in columns:
        near = dark & (np.abs(found.features.x - u) <= 2)
        assert near.any()
        x = found.features.x[near]
        expected = np.arctan((CAMERA.cx - x) / CAMERA.fx)  # a level camera: the pinhole angle
        np.testing.assert_allclose(found.bearings[near], expected, atol=1e-12)


def test_a_pitched_camera_keeps_the_horizontal_bearing() -> None:
    """Pitched by p, the horizon row has (cy - v) / fy = tan p, and the ray (1, (cx - u) / fx,
    tan p) levelled by the pitch is (1 / cos p, (cx - u) / fx, 0): its bearing is
    atan((cx - u) cos p / fx)."""
    pitch = math.radians(10)
    found = horizon_features(bars([100, 250]), CAMERA, level(pitch=pitch), HorizonFeatureConfig())
    x = found.features.x
    assert len(x) > 0
    expected = np.arctan((CAMERA.cx - x) * math.cos(pitch) / CAMERA.fx)
    np.testing.assert_allclose(found.bearings, expected, atol=1e-9)


def test_a_featureless_image_gives_none() -> None:
    grey = np.full((CAMERA.height, CAMERA.width, 3), 120, dtype=np.uint8)
    assert len(horizon_features(grey, CAMERA, level(), HorizonFeatureConfig())) == 0


def test_features_on_a_sighted_robot_are_dropped() -> None:
    found = horizon_features(bars([60, 140, 220]), CAMERA, level(), HorizonFeatureConfig())
    robot = RobotSighting(
        range_m=1.0, bearing_rad=0.0, cov=np.eye(2), box=np.array([120.0, 50.0, 160.0, 200.0])
    )
    kept = features_off_robots(found, (robot,))
    on_robot = (found.features.x >= 120) & (found.features.x <= 160)
    assert on_robot.any() and not on_robot.all()
    assert isinstance(kept, HorizonFeatures) and isinstance(kept.features, Surf1dFeatures)
    np.testing.assert_array_equal(kept.features.x, found.features.x[~on_robot])
    np.testing.assert_array_equal(kept.bearings, found.bearings[~on_robot])
    unboxed = RobotSighting(range_m=1.0, bearing_rad=0.0, cov=np.eye(2))  # not from an image
    assert len(features_off_robots(found, (unboxed,))) == len(found)


def test_the_reported_odometry_passes_the_walk_through() -> None:
    delta = np.array([0.01, -0.002, 0.03])
    step = WalkOdometry().update({"odometry_delta": delta}, 0.0)
    np.testing.assert_array_equal(step.delta, delta)
    np.testing.assert_array_equal(step.walk_delta, delta)
    assert not step.visual and step.collision == 0
