"""SLAM back ends: estimate the robot pose and a landmark map from odometry and sightings."""

from perception.slam.ekf_slam import EkfSlam, EkfSlamConfig

__all__ = ["EkfSlam", "EkfSlamConfig"]
