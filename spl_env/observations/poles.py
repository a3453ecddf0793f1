"""The pole map as the robot believes it: where each pole is, how sure, when last seen."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from gymnasium import spaces

from perception.geometry import FloatArray, range_bearing
from perception.representations import POLE_LAST_SEEN, SELF_POSE
from perception.types import SlamEstimate
from spl_env.observations.base import EncoderInput, box, squash
from spl_env.observations.self_pose import STD_SCALE_M

RANGE_SCALE_M = 3.0  # squashing scale of landmark range (m)
SINCE_SEEN_SCALE_S = 2.0  # squashing scale of time since a landmark was seen (s)


@dataclass(frozen=True)
class PoleMapEncoder:
    """Per pole id ``0..n_landmarks-1`` (index = id), from the SLAM pose and map:
    ``landmarks_cos_bearing``, ``landmarks_sin_bearing`` (robot frame; 0 if not mapped),
    ``landmarks_range`` r / (r + 3 m), ``landmarks_mask`` (1 if mapped), ``landmarks_std``
    s / (s + 0.5 m) with s = sqrt(trace cov) (1 if not mapped), ``landmarks_since_seen``
    t / (t + 2 s) (1 if never)."""

    n_landmarks: int
    requires: tuple[str, ...] = (SELF_POSE, POLE_LAST_SEEN)

    def spaces(self) -> dict[str, spaces.Box]:
        n = self.n_landmarks
        return {
            "landmarks_cos_bearing": box(-1.0, 1.0, n),
            "landmarks_sin_bearing": box(-1.0, 1.0, n),
            "landmarks_range": box(0.0, 1.0, n),
            "landmarks_mask": box(0.0, 1.0, n),
            "landmarks_std": box(0.0, 1.0, n),
            "landmarks_since_seen": box(0.0, 1.0, n),
        }

    def encode(self, data: EncoderInput) -> dict[str, FloatArray]:
        slam = data.output.get_as(SELF_POSE, SlamEstimate)
        n = self.n_landmarks
        cos_b, sin_b, rng = np.zeros(n), np.zeros(n), np.zeros(n)
        mask, lm_std = np.zeros(n), np.ones(n)
        if len(slam.landmark_ids):
            rb = range_bearing(slam.pose, slam.landmarks)
            ids = slam.landmark_ids
            cos_b[ids], sin_b[ids] = np.cos(rb[:, 1]), np.sin(rb[:, 1])
            rng[ids] = squash(rb[:, 0], RANGE_SCALE_M)
            mask[ids] = 1.0
            lm_std[ids] = squash(
                np.sqrt(np.trace(slam.landmark_covs, axis1=1, axis2=2)), STD_SCALE_M
            )
        since = np.ones(n)
        time_s = float(data.output.time_s)
        for landmark_id, seen_s in data.output[POLE_LAST_SEEN].items():
            ago = time_s - float(seen_s)  # squash's arithmetic, in floats
            since[landmark_id] = ago / (ago + SINCE_SEEN_SCALE_S)
        return {
            "landmarks_cos_bearing": cos_b,
            "landmarks_sin_bearing": sin_b,
            "landmarks_range": rng,
            "landmarks_mask": mask,
            "landmarks_std": lm_std,
            "landmarks_since_seen": since,
        }
