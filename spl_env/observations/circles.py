"""The circle map as the observation sees it: where the mapped circles are, how big and how sure."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from gymnasium import spaces

from perception.geometry import FloatArray, range_bearing
from perception.representations import CIRCLE_MAP, SELF_POSE
from perception.types import MappedCircle, SlamEstimate
from spl_env.observations.base import EncoderInput, box, squash
from spl_env.observations.poles import RANGE_SCALE_M
from spl_env.observations.self_pose import STD_SCALE_M

RADIUS_SCALE_M = 0.25  # squashing scale of a circle's radius (m)


def nearest_mapped(
    circles: tuple[MappedCircle, ...], pose: FloatArray, k: int
) -> list[MappedCircle]:
    """The ``k`` confirmed circles nearest to ``pose`` (3,), nearest first."""
    confirmed = [c for c in circles if c.confirmed]
    if not confirmed:
        return []
    distances = np.hypot(*(np.array([c.state[:2] for c in confirmed]) - pose[:2]).T)
    return [confirmed[i] for i in np.argsort(distances, kind="stable")[:k]]


@dataclass(frozen=True)
class CircleMapEncoder:
    """Up to ``max_circles`` confirmed circles of the circle map, nearest first, seen from the
    SLAM pose; rows past the last circle are zero with ``circles_mask`` 0:

    ``circles_cos_bearing``, ``circles_sin_bearing`` (robot frame), ``circles_range``
    r / (r + 3 m) to the centre, ``circles_radius`` R / (R + 0.25 m), ``circles_std``
    s / (s + 0.5 m) with s = sqrt(trace of the centre's covariance), ``circles_mask``."""

    max_circles: int
    requires: tuple[str, ...] = (CIRCLE_MAP, SELF_POSE)

    def spaces(self) -> dict[str, spaces.Box]:
        k = self.max_circles
        return {
            "circles_cos_bearing": box(-1.0, 1.0, k),
            "circles_sin_bearing": box(-1.0, 1.0, k),
            "circles_range": box(0.0, 1.0, k),
            "circles_radius": box(0.0, 1.0, k),
            "circles_std": box(0.0, 1.0, k),
            "circles_mask": box(0.0, 1.0, k),
        }

    def encode(self, data: EncoderInput) -> dict[str, FloatArray]:
        slam = data.output.get_as(SELF_POSE, SlamEstimate)
        circles = nearest_mapped(data.output[CIRCLE_MAP], slam.pose, self.max_circles)
        obs = {key: np.zeros(self.max_circles) for key in self.spaces()}
        if not circles:
            return obs
        n = len(circles)
        states = np.array([c.state for c in circles])
        rb = range_bearing(slam.pose, states[:, :2])
        std = np.sqrt([np.trace(c.cov[:2, :2]) for c in circles])
        obs["circles_cos_bearing"][:n] = np.cos(rb[:, 1])
        obs["circles_sin_bearing"][:n] = np.sin(rb[:, 1])
        obs["circles_range"][:n] = squash(rb[:, 0], RANGE_SCALE_M)
        obs["circles_radius"][:n] = squash(states[:, 2], RADIUS_SCALE_M)
        obs["circles_std"][:n] = squash(std, STD_SCALE_M)
        obs["circles_mask"][:n] = 1.0
        return obs
