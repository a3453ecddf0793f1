"""Other robots (seed 004 ch. 6): filtered sonar, robot sightings from either front end, tracks."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from perception.providers.base import Provider
from perception.representations import (
    IMAGE_DETECTIONS,
    ROBOT_SIGHTINGS,
    ROBOT_TRACKS,
    SELF_POSE,
    SONAR_OBSERVATIONS,
    Prior,
)
from perception.tracking.robot_tracker import RobotTracker, RobotTrackerConfig
from perception.tracking.sonar_filter import SonarFilter, SonarFilterConfig, SonarObservation
from perception.types import RobotSighting, RobotTrack
from perception.vision.cnn_robots import CnnRobotConfig, robot_sightings


class FilteredSonar(Provider):
    """Seed 004's sonar filter: reliable echo clusters per sector over a rolling window."""

    provides = SONAR_OBSERVATIONS
    requires = ("sonar",)

    def __init__(self, config: SonarFilterConfig) -> None:
        self.filter = SonarFilter(config)

    def reset(self, prior: Prior) -> None:
        self.filter.reset()

    def update(self, inputs: Mapping[str, Any], time_s: float) -> tuple[SonarObservation, ...]:
        return self.filter.update(time_s, inputs["sonar"])


class CnnRobotSightings(Provider):
    """Robot sightings from the CNN's ``robot`` detections: the ground point of each box's
    bottom centre (no team: the CNN does not see waistbands)."""

    provides = ROBOT_SIGHTINGS
    requires = (IMAGE_DETECTIONS, "camera", "camera_state")

    def __init__(self, config: CnnRobotConfig) -> None:
        self.config = config

    def update(self, inputs: Mapping[str, Any], time_s: float) -> tuple[RobotSighting, ...]:
        return robot_sightings(
            inputs[IMAGE_DETECTIONS], inputs["camera"], inputs["camera_state"], self.config
        )


class TrackedRobots(Provider):
    """Constant-velocity tracks of the other robots in the field frame, from this frame's robot
    sightings moved to the field with the believed pose (its covariance in the noise)."""

    provides = ROBOT_TRACKS
    requires = (ROBOT_SIGHTINGS, SELF_POSE)

    def __init__(self, config: RobotTrackerConfig) -> None:
        self.tracker = RobotTracker(config)

    def reset(self, prior: Prior) -> None:
        self.tracker.reset()

    def update(self, inputs: Mapping[str, Any], time_s: float) -> tuple[RobotTrack, ...]:
        return self.tracker.update(time_s, inputs[ROBOT_SIGHTINGS], inputs[SELF_POSE])
