"""The perception stack wired together, called once per control step.

``SensorFrame`` -> colour-filter pole detections -> EKF SLAM (odometry prediction, landmark
updates) -> :class:`perception.types.PerceptionOutput`. Dead reckoning from the same odometry
runs beside it as the baseline SLAM must beat.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from perception.geometry import compose
from perception.slam import EkfSlam, EkfSlamConfig
from perception.types import (
    CameraModel,
    LandmarkObservation,
    PerceptionOutput,
    PoleCode,
    PoleGeometry,
    SensorFrame,
)
from perception.vision.colour_filter import ColourFilterConfig, ColourPoleDetector


@dataclass(frozen=True, kw_only=True)
class PipelineConfig:
    """The front end and back end configurations."""

    colour_filter: ColourFilterConfig = field(default_factory=ColourFilterConfig)
    slam: EkfSlamConfig = field(default_factory=EkfSlamConfig)


class PerceptionPipeline:
    """Colour-filter front end and classic EKF SLAM back end for one robot."""

    def __init__(
        self,
        config: PipelineConfig,
        camera: CameraModel,
        codes: Sequence[PoleCode],
        pole: PoleGeometry,
        initial_pose: ArrayLike,
    ) -> None:
        self.config = config
        self.detector = ColourPoleDetector(config.colour_filter, camera, codes, pole)
        self.slam = EkfSlam(config.slam, initial_pose)
        self.odometry_pose = np.asarray(initial_pose, dtype=np.float64).copy()
        self.last_seen_s: dict[int, float] = {}

    def step(self, frame: SensorFrame) -> PerceptionOutput:
        """Predict with the frame's odometry, detect poles in its image, update the map."""
        self.odometry_pose = compose(self.odometry_pose, frame.odometry_delta)
        self.slam.predict(frame.odometry_delta)
        observations = self._detect(frame)
        self.slam.update(observations)
        for obs in observations:
            self.last_seen_s[obs.landmark_id] = frame.time_s
        return PerceptionOutput(
            time_s=frame.time_s,
            slam=self.slam.estimate(),
            odometry_pose=self.odometry_pose.copy(),
            observations=observations,
            last_seen_s=dict(self.last_seen_s),
        )

    def _detect(self, frame: SensorFrame) -> tuple[LandmarkObservation, ...]:
        """Pole sightings from the image, or from band centres in the geometric camera mode."""
        if (frame.image is None) == (frame.band_centres is None):
            raise ValueError(
                "frame must carry exactly one of image and band_centres, got "
                f"image={'set' if frame.image is not None else None}, "
                f"band_centres={'set' if frame.band_centres is not None else None}"
            )
        if frame.image is not None:
            return tuple(self.detector.detect(frame.image, frame.camera_state))
        found = (
            self.detector.observe_band_centres(
                b.landmark_id, b.upper, b.lower, b.box, frame.camera_state
            )
            for b in frame.band_centres or ()
        )
        return tuple(obs for obs in found if obs is not None)
