"""A synthetic SLAM world whose noise is exactly the filter's model: for consistency studies.

Huang, Mourikis & Roumeliotis (2008) show the classic EKF SLAM becoming overconfident by Monte
Carlo runs in which every noise is drawn from the very model the filter assumes, so that any
inconsistency is the filter's own (its linearisation), not a mismatched model. :func:`circle_run`
builds such a run: the robot walks a circle among point landmarks; its odometry increments carry
noise drawn from :meth:`perception.slam.EkfSlamConfig.odometry_cov`, its sightings noise drawn
from their reported covariance. The result is a :class:`perception.replay.SightingLog`, so
:func:`perception.replay.replay` scores any back end on it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from perception.geometry import FloatArray, compose, range_bearing
from perception.replay import SightingLog
from perception.slam import EkfSlamConfig
from perception.types import LandmarkObservation


@dataclass(frozen=True, kw_only=True)
class CircleWorld:
    """The walk and the sensor of :func:`circle_run` (field frame, SI units)."""

    radius_m: float = 2.0  # of the circle, centred on the origin
    speed_mps: float = 0.15  # forward speed along it (counter-clockwise)
    dt_s: float = 0.1  # one odometry increment and one frame per step
    steps: int = 6000  # ten minutes at 0.1 s
    range_std_m: float = 0.05  # sighting noise: range std at 0 m
    range_std_per_m: float = 0.03  # plus this fraction of the range
    bearing_std_rad: float = 0.01
    max_range_m: float = 6.0  # landmarks farther away are not seen
    field_of_view_rad: float = math.radians(120.0)  # seen within half of it of the heading
    sighting_probability: float = 0.3  # chance that a landmark in range and view is seen

    def __post_init__(self) -> None:
        for name in (
            "radius_m",
            "speed_mps",
            "dt_s",
            "range_std_m",
            "bearing_std_rad",
            "max_range_m",
            "field_of_view_rad",
        ):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"CircleWorld.{name} must be finite and > 0, got {value!r}")
        if not (math.isfinite(self.range_std_per_m) and self.range_std_per_m >= 0):
            raise ValueError(
                f"CircleWorld.range_std_per_m must be finite and >= 0, got {self.range_std_per_m!r}"
            )
        if not 0 < self.sighting_probability <= 1:
            raise ValueError(
                "CircleWorld.sighting_probability must be in (0, 1], "
                f"got {self.sighting_probability!r}"
            )
        if isinstance(self.steps, bool) or not isinstance(self.steps, int) or self.steps < 1:
            raise ValueError(f"CircleWorld.steps must be an int >= 1, got {self.steps!r}")

    def step_increment(self) -> FloatArray:
        """The true increment (3,) of one step along the circle (robot frame, exact arc)."""
        turn = self.speed_mps * self.dt_s / self.radius_m
        return np.array(
            [
                self.radius_m * math.sin(turn),
                self.radius_m * (1.0 - math.cos(turn)),
                turn,
            ]
        )


def circle_run(
    world: CircleWorld,
    slam: EkfSlamConfig,
    landmark_ids: FloatArray,
    landmarks: FloatArray,
    rng: np.random.Generator,
) -> SightingLog:
    """One Monte Carlo run: true poses, noisy odometry and sightings of ``landmarks`` (L, 2).

    The robot starts at ``(radius, 0)`` heading +y; its start belief is drawn from
    ``slam.initial_pose_std``. Front end name in the log: ``"synthetic"``.
    """
    true_delta = world.step_increment()
    pose = np.array([world.radius_m, 0.0, math.pi / 2])
    start_noise = rng.normal(0.0, np.asarray(slam.initial_pose_std, dtype=np.float64))
    times, deltas, poses, seen = [], [], [], []
    for k in range(world.steps + 1):
        if k == 0:
            delta = np.zeros(3)
        else:
            pose = compose(pose, true_delta)
            noise_cov = slam.odometry_cov(true_delta)
            delta = true_delta + rng.multivariate_normal(np.zeros(3), noise_cov)
        times.append(k * world.dt_s)
        deltas.append(delta)
        poses.append(pose.copy())
        seen.append(_sightings(world, pose, landmark_ids, landmarks, rng))
    return SightingLog(
        times_s=np.array(times),
        odometry_deltas=np.array(deltas),
        sightings={"synthetic": tuple(seen)},
        true_poses=np.array(poses),
        believed_start=poses[0] + start_noise,
        landmark_ids=np.asarray(landmark_ids),
        landmarks=np.asarray(landmarks, dtype=np.float64),
    )


def _sightings(
    world: CircleWorld,
    pose: FloatArray,
    landmark_ids: FloatArray,
    landmarks: FloatArray,
    rng: np.random.Generator,
) -> tuple[LandmarkObservation, ...]:
    """This step's noisy sightings of the landmarks in range and view (each with its chance)."""
    out = []
    for landmark_id, (r, b) in zip(landmark_ids, range_bearing(pose, landmarks), strict=True):
        in_view = r <= world.max_range_m and abs(b) <= world.field_of_view_rad / 2
        if not in_view or rng.uniform() >= world.sighting_probability:
            continue
        range_std = world.range_std_m + world.range_std_per_m * r
        cov = np.diag([range_std**2, world.bearing_std_rad**2])
        z = rng.multivariate_normal([r, b], cov)
        out.append(
            LandmarkObservation(
                landmark_id=int(landmark_id), range_m=float(z[0]), bearing_rad=float(z[1]), cov=cov
            )
        )
    return tuple(out)
