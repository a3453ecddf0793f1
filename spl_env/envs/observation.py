"""Builds the flat ``Dict`` observation of the SPL envs from what perception believes.

Nothing here reads ground truth: inputs are a :class:`perception.types.PerceptionOutput`, our
robot's joint angles and its sonar. Unbounded quantities are squashed with ``q / (q + scale)``
into [0, 1); positions are divided by the carpet's half size and saturate at ±1.5 (far outside
the boards), which keeps every value inside its ``Box``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from gymnasium import spaces

from perception.geometry import FloatArray, range_bearing
from perception.types import PerceptionOutput
from spl_env.field import FieldDimensions
from spl_env.sim.robot import RobotConfig

POSITION_LIMIT = 1.5  # normalised positions saturate here
STD_SCALE_M = 0.5  # squashing scale of position std (m)
STD_SCALE_RAD = 0.5  # squashing scale of heading std (rad)
RANGE_SCALE_M = 3.0  # squashing scale of landmark range (m)
SINCE_SEEN_SCALE_S = 2.0  # squashing scale of time since a landmark was seen (s)
SONAR_SCALE_M = 1.0  # squashing scale of sonar echo distance (m)


def squash(q: FloatArray | float, scale: float) -> FloatArray:
    """Map q >= 0 to [0, 1) as q / (q + scale)."""
    q = np.asarray(q, dtype=np.float64)
    return q / (q + scale)


@dataclass(frozen=True)
class ObservationBuilder:
    """Observation space and builder for ``n_landmarks`` landmark ids ``0..n_landmarks-1``."""

    dimensions: FieldDimensions
    robot: RobotConfig
    n_landmarks: int
    episode_s: float

    def space(self) -> spaces.Dict:
        """The observation space: a flat Dict of float32 Boxes."""
        n = self.n_landmarks

        def box(low: float, high: float, shape: tuple[int, ...]) -> spaces.Box:
            return spaces.Box(low=low, high=high, shape=shape, dtype=np.float32)

        return spaces.Dict(
            {
                "self_pose_field": box(-POSITION_LIMIT, POSITION_LIMIT, (4,)),
                "self_pose_std": box(0.0, 1.0, (3,)),
                "head_angles": box(-1.0, 1.0, (2,)),
                "landmarks_cos_bearing": box(-1.0, 1.0, (n,)),
                "landmarks_sin_bearing": box(-1.0, 1.0, (n,)),
                "landmarks_range": box(0.0, 1.0, (n,)),
                "landmarks_mask": box(0.0, 1.0, (n,)),
                "landmarks_std": box(0.0, 1.0, (n,)),
                "landmarks_since_seen": box(0.0, 1.0, (n,)),
                "sonar": box(0.0, 1.0, (3,)),
                "time_fraction": box(0.0, 1.0, (1,)),
            }
        )

    def build(
        self, output: PerceptionOutput, head: FloatArray, sonar: FloatArray | None
    ) -> dict[str, np.ndarray]:
        """Observation from the perception output, head joint angles (2,) rad and sonar (3, E)."""
        slam = output.slam
        carpet_l, carpet_w = self.dimensions.carpet_size_m
        x, y, theta = slam.pose
        pose = np.array([x / (carpet_l / 2), y / (carpet_w / 2), math.cos(theta), math.sin(theta)])
        pose[:2] = np.clip(pose[:2], -POSITION_LIMIT, POSITION_LIMIT)  # documented saturation
        std = np.sqrt(np.clip(np.diag(slam.pose_cov), 0.0, None))
        pose_std = np.concatenate([squash(std[:2], STD_SCALE_M), squash(std[2:], STD_SCALE_RAD)])

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
        for landmark_id, seen_s in output.last_seen_s.items():
            since[landmark_id] = squash(output.time_s - seen_s, SINCE_SEEN_SCALE_S)

        cfg = self.robot
        pitch_mid = (cfg.head_pitch_max_rad + cfg.head_pitch_min_rad) / 2
        pitch_half = (cfg.head_pitch_max_rad - cfg.head_pitch_min_rad) / 2
        head_obs = np.array([head[0] / cfg.head_yaw_limit_rad, (head[1] - pitch_mid) / pitch_half])

        nearest = np.ones(3)  # no echo in a sector reads as "far"
        if sonar is not None:
            closest = np.where(np.isnan(sonar), np.inf, sonar).min(axis=1)
            echo = np.isfinite(closest)
            nearest[echo] = squash(closest[echo], SONAR_SCALE_M)
        obs = {
            "self_pose_field": pose,
            "self_pose_std": pose_std,
            "head_angles": head_obs,
            "landmarks_cos_bearing": cos_b,
            "landmarks_sin_bearing": sin_b,
            "landmarks_range": rng,
            "landmarks_mask": mask,
            "landmarks_std": lm_std,
            "landmarks_since_seen": since,
            "sonar": nearest,
            "time_fraction": np.array([min(output.time_s / self.episode_s, 1.0)]),
        }
        diverged = sorted(k for k, v in obs.items() if not np.all(np.isfinite(v)))
        if diverged:
            raise FloatingPointError(f"observation {diverged} not finite: perception diverged")
        return {k: v.astype(np.float32) for k, v in obs.items()}
