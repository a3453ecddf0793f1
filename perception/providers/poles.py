"""Pole perception: the CNN's detections, pole sightings from either front end, their history."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from perception.providers.base import PerceptionContext, Provider
from perception.representations import IMAGE_DETECTIONS, POLE_LAST_SEEN, POLE_SIGHTINGS, Prior
from perception.types import LandmarkObservation
from perception.vision.cnn_detector import CnnDetectorConfig, Detection
from perception.vision.colour_filter import ColourFilterConfig, ColourPoleDetector


class CnnDetections(Provider):
    """One pass of the packaged CNN over the image: every object it finds, best first.

    Every consumer (pole sightings now; robots and the ball next) reads these detections, so
    the network runs once per frame.
    """

    provides = IMAGE_DETECTIONS
    requires = ("image",)

    def __init__(self, config: CnnDetectorConfig, context: PerceptionContext) -> None:
        self.detector = context.cnn_detector(config)

    def update(self, inputs: Mapping[str, Any], time_s: float) -> tuple[Detection, ...]:
        return tuple(self.detector.detect_objects(inputs["image"]))


class CnnPoleSightings(Provider):
    """Seed 000 §3.4: pole sightings from the CNN's pole detections scoring at least
    ``score_threshold`` (range from the pole's own ruler in the image, bearing from the box and
    the head angles)."""

    provides = POLE_SIGHTINGS
    requires = (IMAGE_DETECTIONS, "image", "camera_state")

    def __init__(
        self, config: CnnDetectorConfig, score_threshold: float, context: PerceptionContext
    ) -> None:
        self.detector = context.cnn_detector(config)
        self.score_threshold = score_threshold

    def update(self, inputs: Mapping[str, Any], time_s: float) -> tuple[LandmarkObservation, ...]:
        confident = [d for d in inputs[IMAGE_DETECTIONS] if d.score >= self.score_threshold]
        found = self.detector.observations(confident, inputs["camera_state"], inputs["image"])
        return tuple(found)


class ColourPoleSightings(Provider):
    """Seed 000 §3.3: the HSV colour filter's pole sightings in the image."""

    provides = POLE_SIGHTINGS
    requires = ("image", "camera_state")

    def __init__(self, config: ColourFilterConfig, context: PerceptionContext) -> None:
        self.detector = ColourPoleDetector(
            config, context.require_camera("the colour filter"), context.codes, context.pole
        )

    def update(self, inputs: Mapping[str, Any], time_s: float) -> tuple[LandmarkObservation, ...]:
        return tuple(self.detector.detect(inputs["image"], inputs["camera_state"]))


class PoleSightingHistory(Provider):
    """When each pole was last sighted: landmark id -> time (s)."""

    provides = POLE_LAST_SEEN
    requires = (POLE_SIGHTINGS,)

    def __init__(self) -> None:
        self._last_seen: dict[int, float] = {}

    def reset(self, prior: Prior) -> None:
        self._last_seen = {}

    def update(self, inputs: Mapping[str, Any], time_s: float) -> dict[int, float]:
        for sighting in inputs[POLE_SIGHTINGS]:
            self._last_seen[sighting.landmark_id] = time_s
        return dict(self._last_seen)
