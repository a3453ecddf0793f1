"""Recorded back-end inputs, and their replay through any EKF SLAM back end.

Seed 000 compares its back ends on recorded datasets: every back end sees the very same
odometry and sightings. :class:`SightingLog` is such a recording (one episode, one or more front
ends' sightings side by side, with the ground truth to score against), and :func:`replay` runs
one back end over it exactly as :class:`perception.pipeline.PerceptionPipeline` would have live.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from perception.geometry import FloatArray, compose
from perception.metrics import landmark_errors, pose_nees, position_error
from perception.slam import EkfSlam, EkfSlamConfig
from perception.types import LandmarkObservation

Sightings = tuple[tuple[LandmarkObservation, ...], ...]  # per step, that step's sightings


@dataclass(frozen=True, kw_only=True)
class SightingLog:
    """One episode's odometry, sightings and ground truth (field frame, SI units).

    Step 0 is the frame ``reset`` delivered (its odometry increment is zero). ``sightings``
    maps a front-end name to that front end's sightings of each step; all front ends saw the
    same frames.
    """

    times_s: FloatArray  # (T,)
    odometry_deltas: FloatArray  # (T, 3) increments (dx, dy, dtheta), frame of the previous pose
    sightings: Mapping[str, Sightings]  # front end -> T per-step tuples
    true_poses: FloatArray  # (T, 3)
    believed_start: FloatArray  # (3,) the filter's start belief
    landmark_ids: NDArray[np.int64]  # (L,) ids of the true landmarks
    landmarks: FloatArray  # (L, 2) their true positions

    def __post_init__(self) -> None:
        steps = len(self.times_s)
        if self.odometry_deltas.shape != (steps, 3) or self.true_poses.shape != (steps, 3):
            raise ValueError(
                f"SightingLog needs (T, 3) odometry_deltas and true_poses for T={steps} times, "
                f"got {self.odometry_deltas.shape} and {self.true_poses.shape}"
            )
        for name, per_step in self.sightings.items():
            if len(per_step) != steps:
                raise ValueError(
                    f"SightingLog.sightings[{name!r}] must have {steps} steps, got {len(per_step)}"
                )


@dataclass(frozen=True, kw_only=True)
class ReplayResult:
    """Per-step errors of one back end on one log; ``nan`` where nothing was mapped yet."""

    position_errors_m: FloatArray  # (T,) SLAM robot position error
    odometry_errors_m: FloatArray  # (T,) dead-reckoning position error
    pose_nees: FloatArray  # (T,) NEES of the SLAM pose (3 dof)
    landmark_errors_m: FloatArray  # (T,) mean error over the landmarks mapped at that step
    poses: FloatArray  # (T, 3) SLAM pose estimates
    final_landmark_ids: NDArray[np.int64]  # (K,) mapped at the end
    final_landmarks: FloatArray  # (K, 2) their estimates
    rejected: int  # sightings the gate discarded

    def summary(self) -> dict[str, float | int | None]:
        """Means over the episode (the seed's "mean error" columns) and final values."""
        landmark = self.landmark_errors_m[np.isfinite(self.landmark_errors_m)]
        return {
            "mean_position_error_m": float(np.mean(self.position_errors_m)),
            "std_position_error_m": float(np.std(self.position_errors_m)),
            "final_position_error_m": float(self.position_errors_m[-1]),
            "mean_odometry_error_m": float(np.mean(self.odometry_errors_m)),
            "mean_landmark_error_m": float(np.mean(landmark)) if len(landmark) else None,
            "std_landmark_error_m": float(np.std(landmark)) if len(landmark) else None,
            "final_landmark_error_m": (
                float(self.landmark_errors_m[-1])
                if np.isfinite(self.landmark_errors_m[-1])
                else None
            ),
            "mean_pose_nees": float(np.mean(self.pose_nees)),
            "landmarks_mapped": len(self.final_landmark_ids),
            "rejected_sightings": self.rejected,
        }


def replay(log: SightingLog, frontend: str, config: EkfSlamConfig) -> ReplayResult:
    """Run the back end ``config`` over the sightings ``log`` recorded from ``frontend``."""
    if frontend not in log.sightings:
        raise ValueError(
            f"frontend must be one of the log's front ends {tuple(log.sightings)}, got {frontend!r}"
        )
    slam = EkfSlam(config, log.believed_start)
    odometry = np.asarray(log.believed_start, dtype=np.float64).copy()
    steps = len(log.times_s)
    slam_err, odom_err, nees, lm_err = (np.empty(steps) for _ in range(4))
    poses = np.empty((steps, 3))
    for k, (delta, seen) in enumerate(
        zip(log.odometry_deltas, log.sightings[frontend], strict=True)
    ):
        odometry = compose(odometry, delta)
        slam.predict(delta)
        slam.update(seen)
        estimate = slam.estimate()
        truth = log.true_poses[k]
        poses[k] = estimate.pose
        slam_err[k] = position_error(truth, estimate.pose)
        odom_err[k] = position_error(truth, odometry)
        nees[k] = pose_nees(truth, estimate.pose, estimate.pose_cov)
        errors = landmark_errors(
            log.landmark_ids, log.landmarks, estimate.landmark_ids, estimate.landmarks
        )
        lm_err[k] = float(np.mean(errors)) if len(errors) else np.nan
    final = slam.estimate()
    return ReplayResult(
        position_errors_m=slam_err,
        odometry_errors_m=odom_err,
        pose_nees=nees,
        landmark_errors_m=lm_err,
        poses=poses,
        final_landmark_ids=final.landmark_ids,
        final_landmarks=final.landmarks,
        rejected=slam.rejected,
    )
