"""The circle map: static circular objects mapped from laser scans on the believed pose."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from perception.circles.circle_map import CircleMapConfig, CircleMapper
from perception.providers.base import Provider
from perception.representations import CIRCLE_MAP, SELF_POSE, Prior
from perception.sensor_models import LaserModel
from perception.types import MappedCircle, SlamEstimate


class LaserCircleMap(Provider):
    """:class:`perception.circles.circle_map.CircleMapper` on each laser scan, seen from the
    self pose (its covariance in the noise)."""

    provides = CIRCLE_MAP
    requires = ("laser", "laser_model", SELF_POSE)

    def __init__(self, config: CircleMapConfig) -> None:
        self.mapper = CircleMapper(config)

    def reset(self, prior: Prior) -> None:
        self.mapper.reset()

    def update(self, inputs: Mapping[str, Any], time_s: float) -> tuple[MappedCircle, ...]:
        model: LaserModel = inputs["laser_model"]
        slam: SlamEstimate = inputs[SELF_POSE]
        return self.mapper.update(
            model.beam_angles(), inputs["laser"], model.mount_x_m, slam.pose, slam.pose_cov
        )
