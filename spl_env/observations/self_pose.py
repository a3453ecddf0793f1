"""The believed pose of our robot and its uncertainty."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from gymnasium import spaces

from perception.geometry import FloatArray
from perception.representations import SELF_POSE
from perception.types import SlamEstimate
from spl_env.observations.base import EncoderInput, box, squash
from spl_env.sim.placement import Area

POSITION_LIMIT = 1.5  # normalised positions saturate here
STD_SCALE_M = 0.5  # squashing scale of position std (m)
STD_SCALE_RAD = 0.5  # squashing scale of heading std (rad)


@dataclass(frozen=True)
class SelfPoseEncoder:
    """``self_pose_field`` (4,): x / half carpet length, y / half carpet width (a room's inner
    half length and width; saturating at ±1.5), cos θ, sin θ; ``self_pose_std`` (3,): std of
    x, y (m) and θ (rad) as s / (s + 0.5)."""

    dimensions: Area
    requires: tuple[str, ...] = (SELF_POSE,)

    def spaces(self) -> dict[str, spaces.Box]:
        return {
            "self_pose_field": box(-POSITION_LIMIT, POSITION_LIMIT, 4),
            "self_pose_std": box(0.0, 1.0, 3),
        }

    def encode(self, data: EncoderInput) -> dict[str, FloatArray]:
        slam = data.output.get_as(SELF_POSE, SlamEstimate)
        carpet_l, carpet_w = self.dimensions.carpet_size_m
        x, y, theta = slam.pose
        pose = np.array([x / (carpet_l / 2), y / (carpet_w / 2), math.cos(theta), math.sin(theta)])
        # documented saturation; an infinite estimate stays infinite so that encode_all refuses it
        finite = np.isfinite(pose[:2])
        pose[:2][finite] = np.clip(pose[:2][finite], -POSITION_LIMIT, POSITION_LIMIT)
        std = np.sqrt(np.clip(np.diag(slam.pose_cov), 0.0, None))
        pose_std = np.concatenate([squash(std[:2], STD_SCALE_M), squash(std[2:], STD_SCALE_RAD)])
        return {"self_pose_field": pose, "self_pose_std": pose_std}
