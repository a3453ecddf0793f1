"""Oracle providers: the ground truth plus configured noise, for ablations.

They read :attr:`perception.types.SensorFrame.truth`, which an env fills only when one of them
is configured; they are chosen by name (``"oracle"``), never by default. Every draw uses the
episode's generator handed over in :class:`perception.representations.Prior`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from perception.geometry import FloatArray, range_bearing, rot_z, wrap_angle
from perception.providers.base import PerceptionContext, Provider
from perception.representations import (
    BALL,
    BALL_SIGHTINGS,
    POLE_SIGHTINGS,
    ROBOT_SIGHTINGS,
    SELF_POSE,
    Prior,
)
from perception.types import (
    BallEstimate,
    BallSighting,
    GroundTruth,
    LandmarkObservation,
    RobotSighting,
    SlamEstimate,
)
from perception.validation import check_positive


@dataclass(frozen=True, kw_only=True)
class OracleConfig:
    """Noise of the oracle providers (standard deviations, SI units)."""

    range_std_m: float = 0.05  # pole sighting range noise
    bearing_std_rad: float = 0.01  # pole sighting bearing noise
    max_range_m: float = 8.0  # poles beyond are not sighted (as the colour filter's limit)
    position_std_m: float = 0.05  # self pose x and y noise
    heading_std_rad: float = 0.02  # self pose heading noise
    landmark_std_m: float = 0.05  # noise of each mapped pole coordinate
    ball_velocity_std_mps: float = 0.05  # noise of each ball velocity component (ball oracle)

    def __post_init__(self) -> None:
        for name in (
            "ball_velocity_std_mps",
            "range_std_m",
            "bearing_std_rad",
            "max_range_m",
            "position_std_m",
            "heading_std_rad",
            "landmark_std_m",
        ):
            check_positive("OracleConfig", name, getattr(self, name))


class _Oracle(Provider):
    """An oracle keeps the episode's prior for its generator."""

    def __init__(self, config: OracleConfig) -> None:
        self.config = config
        self._prior: Prior | None = None

    def reset(self, prior: Prior) -> None:
        self._prior = prior

    @property
    def rng(self) -> np.random.Generator:
        """The generator of the episode's prior."""
        if self._prior is None:
            raise RuntimeError("an oracle provider must be reset() with the episode's prior first")
        return self._prior.rng


class _InViewOracle(_Oracle):
    """An oracle of things seen by the camera: those within ``max_range_m`` whose bearing lies
    inside the horizontal field of view around the head yaw, with Gaussian noise."""

    requires = ("truth", "camera_state")

    def __init__(self, config: OracleConfig, context: PerceptionContext) -> None:
        super().__init__(config)
        camera = context.require_camera(f"the {type(self).__name__} oracle")
        self.half_fov_rad = math.radians(camera.hfov_deg) / 2

    def seen(
        self, inputs: Mapping[str, Any], points: FloatArray
    ) -> tuple[NDArray[np.intp], list[float], list[float], FloatArray]:
        """Indices of ``points`` (N, 2) (field frame) in view, their noisy ranges (m) and
        bearings (rad, robot frame), and the (2, 2) covariance of the noise."""
        truth: GroundTruth = inputs["truth"]
        c = self.config
        cov = np.diag([c.range_std_m**2, c.bearing_std_rad**2])
        if len(points) == 0:
            return np.zeros(0, dtype=np.intp), [], [], cov
        rb = range_bearing(truth.robot_pose, points)
        off_axis = np.abs(wrap_angle(rb[:, 1] - inputs["camera_state"].head_yaw))
        seen = np.flatnonzero((rb[:, 0] <= c.max_range_m) & (off_axis <= self.half_fov_rad))
        noise = self.rng.normal(0.0, 1.0, size=(len(seen), 2)) * (c.range_std_m, c.bearing_std_rad)
        ranges = [max(float(rb[k, 0] + n[0]), 1e-3) for k, n in zip(seen, noise, strict=True)]
        bearings = [float(wrap_angle(rb[k, 1] + n[1])) for k, n in zip(seen, noise, strict=True)]
        return seen, ranges, bearings, cov


class OraclePoleSightings(_InViewOracle):
    """Every pole in view (:class:`_InViewOracle`), with Gaussian range and bearing noise; no
    occlusion."""

    provides = POLE_SIGHTINGS

    def update(self, inputs: Mapping[str, Any], time_s: float) -> tuple[LandmarkObservation, ...]:
        truth: GroundTruth = inputs["truth"]
        seen, ranges, bearings, cov = self.seen(inputs, truth.landmarks)
        sightings = [
            LandmarkObservation(
                landmark_id=int(truth.landmark_ids[k]), range_m=r, bearing_rad=b, cov=cov.copy()
            )
            for k, r, b in zip(seen, ranges, bearings, strict=True)
        ]
        return tuple(sorted(sightings, key=lambda s: s.landmark_id))


class OracleRobotSightings(_InViewOracle):
    """Every other robot in view (:class:`_InViewOracle`), with Gaussian range and bearing
    noise and its true team; no occlusion."""

    provides = ROBOT_SIGHTINGS

    def update(self, inputs: Mapping[str, Any], time_s: float) -> tuple[RobotSighting, ...]:
        truth: GroundTruth = inputs["truth"]
        seen, ranges, bearings, cov = self.seen(inputs, truth.robots)
        return tuple(
            RobotSighting(range_m=r, bearing_rad=b, cov=cov.copy(), team=int(truth.robot_teams[k]))
            for k, r, b in zip(seen, ranges, bearings, strict=True)
        )


class OracleSelfPose(_Oracle):
    """The true pose and pole map with Gaussian noise and the matching diagonal covariances."""

    provides = SELF_POSE
    requires = ("truth",)

    def update(self, inputs: Mapping[str, Any], time_s: float) -> SlamEstimate:
        rng = self.rng
        truth: GroundTruth = inputs["truth"]
        c = self.config
        pose_std = np.array([c.position_std_m, c.position_std_m, c.heading_std_rad])
        pose = truth.robot_pose + rng.normal(0.0, 1.0, size=3) * pose_std
        pose[2] = wrap_angle(pose[2])
        n = len(truth.landmark_ids)
        landmarks = truth.landmarks + rng.normal(0.0, c.landmark_std_m, size=(n, 2))
        return SlamEstimate(
            pose=pose,
            pose_cov=np.diag(pose_std**2),
            landmark_ids=np.asarray(truth.landmark_ids, dtype=np.int64).copy(),
            landmarks=landmarks,
            landmark_covs=np.repeat(np.eye(2)[None] * c.landmark_std_m**2, n, axis=0),
        )


class OracleBallSightings(_InViewOracle):
    """The ball when in view (:class:`_InViewOracle`), with Gaussian range and bearing noise;
    no occlusion. Nothing in a world without a ball."""

    provides = BALL_SIGHTINGS

    def update(self, inputs: Mapping[str, Any], time_s: float) -> tuple[BallSighting, ...]:
        truth: GroundTruth = inputs["truth"]
        ball = truth.ball[None] if np.all(np.isfinite(truth.ball)) else np.zeros((0, 2))
        _, ranges, bearings, cov = self.seen(inputs, ball)
        return tuple(
            BallSighting(range_m=r, bearing_rad=b, cov=cov.copy())
            for r, b in zip(ranges, bearings, strict=True)
        )


class OracleBall(_Oracle):
    """The true ball, always known, with Gaussian noise (``position_std_m`` on each position
    axis, ``ball_velocity_std_mps`` on each velocity axis) and the matching diagonal
    covariance, relative to the true pose; ValueError in a world without a ball."""

    provides = BALL
    requires = ("truth",)

    def update(self, inputs: Mapping[str, Any], time_s: float) -> BallEstimate:
        truth: GroundTruth = inputs["truth"]
        state = np.concatenate([truth.ball, truth.ball_velocity])
        if not np.all(np.isfinite(state)):
            raise ValueError("the ball oracle needs a world with a ball (truth.ball is NaN)")
        c = self.config
        std = np.array([c.position_std_m] * 2 + [c.ball_velocity_std_mps] * 2)
        noisy = state + self.rng.normal(0.0, 1.0, size=4) * std
        x, y, theta = truth.robot_pose
        back = rot_z(-theta)[:2, :2]
        relative = np.concatenate([back @ (noisy[:2] - (x, y)), back @ noisy[2:]])
        return BallEstimate(
            state=noisy,
            cov=np.diag(std**2),
            relative=relative,
            relative_cov=np.diag(std**2),  # isotropic per pair: the same in any frame
            known=True,
            last_seen_s=time_s,
        )
