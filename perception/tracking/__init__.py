"""Tracking of other robots in the field frame from robot-frame sightings (seed 004 §6.2)."""

from perception.tracking.robot_tracker import (
    RobotTracker,
    RobotTrackerConfig,
    constant_velocity_model,
    sighting_in_field,
)

__all__ = ["RobotTracker", "RobotTrackerConfig", "constant_velocity_model", "sighting_in_field"]
