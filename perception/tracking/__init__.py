"""Other robots from robot-frame sightings and sonar (seed 004 §6.2): the sonar filter and
Algorithm 2's sonar rules, and the multi-robot tracker in the field frame."""

from perception.tracking.robot_tracker import (
    RobotTracker,
    RobotTrackerConfig,
    constant_velocity_model,
    sighting_in_field,
)
from perception.tracking.sonar_filter import (
    SonarFilter,
    SonarFilterConfig,
    SonarObservation,
    confirm_with_sonar,
)

__all__ = [
    "RobotTracker",
    "RobotTrackerConfig",
    "SonarFilter",
    "SonarFilterConfig",
    "SonarObservation",
    "confirm_with_sonar",
    "constant_velocity_model",
    "sighting_in_field",
]
