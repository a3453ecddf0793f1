"""EKF SLAM over the poles (seed 000) as the provider of the robot's pose and landmark map."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from perception.providers.base import Provider
from perception.representations import ODOMETRY, POLE_SIGHTINGS, SELF_POSE, Prior
from perception.slam import EkfSlam, EkfSlamConfig
from perception.types import SlamEstimate


class EkfSlamProvider(Provider):
    """Predicts with each frame's odometry increment, then fuses the frame's pole sightings.

    The back end (classic, gated, minimal view, FEJ) is ``config.backend``; the filter starts
    at the prior's pose with ``config.initial_pose_std``.
    """

    provides = SELF_POSE
    requires = (ODOMETRY, POLE_SIGHTINGS)

    def __init__(self, config: EkfSlamConfig) -> None:
        self.config = config
        self._slam: EkfSlam | None = None

    @property
    def slam(self) -> EkfSlam:
        """The episode's filter (after :meth:`reset`)."""
        if self._slam is None:
            raise RuntimeError("EkfSlamProvider.reset() must be called before reading the filter")
        return self._slam

    def reset(self, prior: Prior) -> None:
        self._slam = EkfSlam(self.config, prior.pose)

    def update(self, inputs: Mapping[str, Any], time_s: float) -> SlamEstimate:
        slam = self.slam
        slam.predict(inputs[ODOMETRY].delta)
        slam.update(inputs[POLE_SIGHTINGS])
        return slam.estimate()
