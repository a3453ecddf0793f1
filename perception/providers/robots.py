"""Other robots (seed 004 ch. 6): filtered sonar, robot sightings from either front end, tracks."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, ClassVar

from perception.providers.base import PerceptionContext, Provider
from perception.representations import (
    IMAGE_DETECTIONS,
    ROBOT_SIGHTINGS,
    ROBOT_TRACKS,
    SELF_POSE,
    SONAR_OBSERVATIONS,
    Prior,
)
from perception.tracking.robot_tracker import RobotTracker, RobotTrackerConfig
from perception.tracking.sonar_filter import (
    SonarFilter,
    SonarFilterConfig,
    SonarObservation,
    confirm_with_sonar,
)
from perception.types import RobotSighting, RobotTrack
from perception.vision.cnn_robots import CnnRobotConfig, robot_sightings
from perception.vision.robots import RobotDetector, RobotDetectorConfig


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


class VisionOnlyRobotSightings(Provider):
    """Robot sightings from field-edge indents (seed 004 §6.2, :class:`RobotDetector`) without
    the sonar check: sightings without a team colour are kept (``team=None``). An ablation of
    :class:`VisionRobotSightings`, and the front end of a robot without sonar."""

    provides = ROBOT_SIGHTINGS
    requires: ClassVar[tuple[str, ...]] = ("image", "camera_state")

    def __init__(self, config: RobotDetectorConfig, context: PerceptionContext) -> None:
        self.detector = RobotDetector(config, context.require_camera("the robot detector"))

    def update(self, inputs: Mapping[str, Any], time_s: float) -> tuple[RobotSighting, ...]:
        return tuple(self.detector.detect(inputs["image"], inputs["camera_state"]))


class VisionRobotSightings(VisionOnlyRobotSightings):
    """Seed 004's robot detection complete (§6.2, Algorithm 2): field-edge indents with their
    team colour, then the sonar check against this frame's filtered sonar ranges
    (:func:`confirm_with_sonar`): a sighting at a sonar range takes it, and one with neither a
    team colour nor a sonar confirmation is dropped."""

    requires = ("image", "camera_state", SONAR_OBSERVATIONS, "sonar_model")

    def __init__(
        self,
        config: RobotDetectorConfig,
        sonar: SonarFilterConfig,
        context: PerceptionContext,
    ) -> None:
        super().__init__(config, context)
        self.sonar = sonar

    def update(self, inputs: Mapping[str, Any], time_s: float) -> tuple[RobotSighting, ...]:
        return confirm_with_sonar(
            super().update(inputs, time_s),
            inputs[SONAR_OBSERVATIONS],
            inputs["sonar_model"],
            self.sonar,
        )


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
