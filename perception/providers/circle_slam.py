"""Circle-landmark EKF SLAM (:mod:`perception.slam.circle_slam`) as a self-pose provider, and
its map as the circle map: the pose from wheel odometry and laser circles alone."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from perception.circles.scan_circles import ScanCirclesConfig, scan_arcs
from perception.providers.base import Provider
from perception.representations import CIRCLE_MAP, ODOMETRY, SELF_POSE, Prior
from perception.sensor_models import LaserModel
from perception.slam.circle_slam import CircleSlam, CircleSlamConfig
from perception.types import MappedCircle, SlamEstimate


class CircleSlamProvider(Provider):
    """Predicts with each frame's odometry increment, then fuses the segments of its laser scan
    (:func:`~perception.circles.scan_circles.scan_arcs`) by their ranges, or their circle fits
    (:meth:`~perception.slam.circle_slam.CircleSlam.update_scan`).

    The estimate has no point landmarks; its map is :attr:`SlamEstimate.circles`, one
    :class:`MappedCircle` per mapped circle (id :attr:`CircleSlam.circle_ids`, ``hits`` the
    sightings fused into it, ``confirmed`` as :attr:`CircleSlam.confirmed`).
    """

    provides = SELF_POSE
    requires = (ODOMETRY, "laser", "laser_model")

    def __init__(self, config: CircleSlamConfig, scan: ScanCirclesConfig) -> None:
        self.config = config
        self.scan = scan
        self._slam: CircleSlam | None = None

    @property
    def slam(self) -> CircleSlam:
        """The episode's filter (after :meth:`reset`)."""
        if self._slam is None:
            raise RuntimeError(
                "CircleSlamProvider.reset() must be called before reading the filter"
            )
        return self._slam

    def reset(self, prior: Prior) -> None:
        self._slam = CircleSlam(self.config, prior.pose)

    def update(self, inputs: Mapping[str, Any], time_s: float) -> SlamEstimate:
        slam = self.slam
        slam.predict(inputs[ODOMETRY].delta)
        model: LaserModel = inputs["laser_model"]
        arcs = scan_arcs(model.beam_angles(), inputs["laser"], model.mount_x_m, self.scan)
        slam.update_scan(arcs, model.mount_x_m, model.range_noise_std_m)
        circles = tuple(
            MappedCircle(circle_id=int(k), state=state, cov=cov, hits=int(n), confirmed=bool(ok))
            for k, state, cov, n, ok in zip(
                slam.circle_ids,
                slam.circles,
                slam.circle_covs,
                slam.hits,
                slam.confirmed,
                strict=True,
            )
        )
        return SlamEstimate(
            pose=slam.pose,
            pose_cov=slam.pose_cov,
            landmark_ids=np.zeros(0, dtype=np.int64),
            landmarks=np.zeros((0, 2)),
            landmark_covs=np.zeros((0, 2, 2)),
            circles=circles,
        )


class SlamCircleMap(Provider):
    """The circle map of a circle-landmark self pose (``self_pose="circle_slam"``): its
    :attr:`SlamEstimate.circles`."""

    provides = CIRCLE_MAP
    requires = (SELF_POSE,)

    def update(self, inputs: Mapping[str, Any], time_s: float) -> tuple[MappedCircle, ...]:
        slam: SlamEstimate = inputs[SELF_POSE]
        return slam.circles
