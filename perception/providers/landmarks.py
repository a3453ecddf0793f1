"""Natural landmarks and the odometry the pose estimators use, as providers.

``horizon_features``: :class:`HorizonFeatureProvider`, the frame's 1D SURF features on the
horizon (:mod:`perception.landmarks.horizon_features`) less those on detected robots.
``odometry``: :class:`WalkOdometry` (the walk engine's report, as it is) or
:class:`VisualOdometry` (its heading change replaced by the visual heading odometry of seed 004
ch. 5 when the horizon's votes are confident, with the collision flag).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from perception.landmarks.horizon_features import (
    HorizonFeatureConfig,
    HorizonFeatures,
    horizon_features,
)
from perception.landmarks.matching import MatchingConfig
from perception.landmarks.visual_odometry import (
    CollisionDetector,
    VisualHeadingOdometry,
    VisualOdometryConfig,
    nearest_neighbours,
)
from perception.providers.base import PerceptionContext, Provider
from perception.representations import HORIZON_FEATURES, ODOMETRY, ROBOT_SIGHTINGS, Prior
from perception.types import CameraModel, OdometryStep, RobotSighting
from perception.validation import check_nested_configs, finite_vector


class HorizonFeatureProvider(Provider):
    """The 1D SURF features on the horizon of the frame's image, less those on detected
    robots (seed 004 discards them for visual odometry and natural landmarks alike)."""

    provides = HORIZON_FEATURES
    requires = ("image", "camera_state", ROBOT_SIGHTINGS)

    def __init__(self, config: HorizonFeatureConfig, context: PerceptionContext) -> None:
        self.config = config
        self.camera: CameraModel = context.require_camera("the horizon features")

    def update(self, inputs: Mapping[str, Any], time_s: float) -> HorizonFeatures:
        found = horizon_features(inputs["image"], self.camera, inputs["camera_state"], self.config)
        return features_off_robots(found, inputs[ROBOT_SIGHTINGS])


class WalkOdometry(Provider):
    """The walk engine's odometry, as it reports it."""

    provides = ODOMETRY
    requires = ("odometry_delta",)

    def update(self, inputs: Mapping[str, Any], time_s: float) -> OdometryStep:
        delta = finite_vector(inputs["odometry_delta"], "frame.odometry_delta", 3)
        return OdometryStep(delta=delta, walk_delta=delta)


@dataclass(frozen=True, kw_only=True)
class VisualOdometryProviderConfig:
    """The visual heading odometry and its frame-to-frame matching."""

    odometry: VisualOdometryConfig = field(default_factory=VisualOdometryConfig)
    matching: MatchingConfig = field(default_factory=MatchingConfig)

    def __post_init__(self) -> None:
        check_nested_configs(self)


class VisualOdometry(Provider):
    """The walk's translation with the heading change of the horizon features (seed 004
    ch. 5), the walk's heading change where their votes are not confident."""

    provides = ODOMETRY
    requires = ("odometry_delta", HORIZON_FEATURES)

    def __init__(self, config: VisualOdometryProviderConfig) -> None:
        self.config = config
        self.heading = VisualHeadingOdometry(config.odometry, nearest_neighbours(config.matching))
        self.collisions = CollisionDetector(config.odometry)

    def reset(self, prior: Prior) -> None:
        self.heading.reset()
        self.collisions.reset()

    def update(self, inputs: Mapping[str, Any], time_s: float) -> OdometryStep:
        walk = np.asarray(inputs["odometry_delta"], dtype=np.float64)
        step = self.heading.update(inputs[HORIZON_FEATURES], float(walk[2]))
        collision = self.collisions.update(step.delta_rad, float(walk[2]))
        return OdometryStep(
            delta=np.array([walk[0], walk[1], step.delta_rad]),
            walk_delta=walk,
            visual=step.visual,
            confidence=step.confidence,
            collision=collision,
        )


def features_off_robots(
    features: HorizonFeatures, sightings: Sequence[RobotSighting]
) -> HorizonFeatures:
    """``features`` less those whose column lies in a sighted robot's image box (seed 004
    discards them in visual odometry and natural landmark recognition alike)."""
    x = features.features.x
    on_robots = np.zeros(len(x), dtype=bool)
    for sighting in sightings:
        u0, _, u1, _ = sighting.box
        if np.isfinite(u0) and np.isfinite(u1):
            on_robots |= (x >= u0) & (x <= u1)
    return features.without(on_robots)
