"""SLAM back ends: estimate the robot pose and a landmark map from odometry and sightings."""

from perception.slam.ekf_slam import BACKENDS, GATES, EkfSlam, EkfSlamConfig

__all__ = ["BACKENDS", "GATES", "EkfSlam", "EkfSlamConfig"]
