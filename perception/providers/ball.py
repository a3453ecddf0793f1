"""The ball: sightings from the CNN's ``ball`` detections, and its filter in the field frame."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, ClassVar

import numpy as np

from perception.geometry import invert, transform_points
from perception.providers.base import PerceptionContext, Provider
from perception.representations import (
    BALL,
    BALL_SIGHTINGS,
    IMAGE_DETECTIONS,
    ODOMETRY,
    ROBOT_TRACKS,
    SELF_POSE,
    Prior,
)
from perception.tracking.ball_filter import BallFilter, BallFilterConfig
from perception.types import BallEstimate, BallSighting, OdometryStep, RobotTrack, SlamEstimate
from perception.vision.cnn_ball import CnnBallConfig, ball_in_view, ball_sightings
from perception.vision.cnn_detector import CnnDetectorConfig


class CnnBallSightings(Provider):
    """Ball sightings from the CNN's ``ball`` detections (:mod:`perception.vision.cnn_ball`):
    the ray through each box's centre meets the plane of the ball's centre; flat boxes (a
    painted mark) are looked at in the image and dropped."""

    provides = BALL_SIGHTINGS
    requires: ClassVar[tuple[str, ...]] = (IMAGE_DETECTIONS, "image", "camera", "camera_state")

    def __init__(self, config: CnnBallConfig) -> None:
        self.config = config

    def update(self, inputs: Mapping[str, Any], time_s: float) -> tuple[BallSighting, ...]:
        return ball_sightings(
            inputs[IMAGE_DETECTIONS],
            inputs["camera"],
            inputs["camera_state"],
            self.config,
            image=inputs["image"],
        )


class TwoCameraCnnBallSightings(CnnBallSightings):
    """:class:`CnnBallSightings` of the top camera's CNN pass, and of the bottom camera's image
    read by the same CNN at 1/``bottom_downscale`` resolution: the bottom camera sees the ball
    at the feet, which the top one cannot (nearer than about 0.35 m). Both cameras' sightings,
    best score first."""

    requires = (
        IMAGE_DETECTIONS,
        "image",
        "camera",
        "camera_state",
        "bottom_image",
        "bottom_camera_state",
    )

    def __init__(
        self, config: CnnBallConfig, cnn: CnnDetectorConfig, context: PerceptionContext
    ) -> None:
        super().__init__(config)
        self.detector = context.cnn_detector(cnn)

    def update(self, inputs: Mapping[str, Any], time_s: float) -> tuple[BallSighting, ...]:
        detections = self.detector.detect_objects_downscaled(
            inputs["bottom_image"], self.config.bottom_downscale
        )
        bottom = ball_sightings(
            detections,
            inputs["camera"],
            inputs["bottom_camera_state"],
            self.config,
            self.config.bottom_downscale,
            image=inputs["bottom_image"],
        )
        both = super().update(inputs, time_s) + bottom
        return tuple(sorted(both, key=lambda s: -s.score))


class TrackedBall(Provider):
    """The ball's egocentric Kalman filter (:mod:`perception.tracking.ball_filter`): this
    frame's ball sightings, the odometry and our own kicks, whether the believed ball (a ball
    of ``radius_m``) shows in the top camera's image, and the confirmed robot tracks seen from
    the believed pose (beside them a ball in view may go unseen: a pipeline with this filter
    also tracks the robots); placed on the field with the believed pose. A track kept after its
    robot was last seen counts as well, where the tracker predicts it."""

    provides = BALL
    requires = (
        BALL_SIGHTINGS,
        ODOMETRY,
        SELF_POSE,
        ROBOT_TRACKS,
        "kick_velocity",
        "camera",
        "camera_state",
    )

    def __init__(self, config: BallFilterConfig, radius_m: float) -> None:
        self.filter = BallFilter(config)
        self.radius_m = radius_m

    def reset(self, prior: Prior) -> None:
        self.filter.reset()

    def update(self, inputs: Mapping[str, Any], time_s: float) -> BallEstimate:
        pose, odometry = inputs[SELF_POSE], inputs[ODOMETRY]
        if not isinstance(pose, SlamEstimate):
            raise TypeError(f"self_pose must be a SlamEstimate, got {type(pose).__name__}")
        if not isinstance(odometry, OdometryStep):
            raise TypeError(f"odometry must be an OdometryStep, got {type(odometry).__name__}")
        camera, state = inputs["camera"], inputs["camera_state"]
        margin = self.filter.config.view_margin
        tracks = inputs[ROBOT_TRACKS]
        if not all(isinstance(track, RobotTrack) for track in tracks):
            raise TypeError(f"robot_tracks must be RobotTracks, got {tracks!r}")
        confirmed = [track.state[:2] for track in tracks if track.confirmed]
        robots = transform_points(invert(pose.pose), np.array(confirmed).reshape(-1, 2))
        return self.filter.update(
            time_s,
            inputs[BALL_SIGHTINGS],
            odometry.delta,
            pose,
            inputs["kick_velocity"],
            in_view=lambda point: ball_in_view(point, camera, state, self.radius_m, margin),
            robots=robots,
        )
