"""Names and containers of what perception believes: one representation per name.

A provider (:mod:`perception.providers`) computes one representation from sensor inputs and
other representations; :class:`PerceptionOutput` holds every representation of one step.

Sensor inputs carry the names of the :class:`perception.types.SensorFrame` fields
(:data:`FRAME_INPUTS`); representations (:data:`REPRESENTATIONS`) are, with their types:

=====================  ================================================================
name                   value
=====================  ================================================================
``odometry_pose``      (3,) float64: dead-reckoned pose x, y (m), θ (rad), field frame
``image_detections``   ``tuple[perception.vision.Detection, ...]``: every object the CNN
                       found in this frame (poles, goal posts, ball, robots), best first
``pole_sightings``     ``tuple[LandmarkObservation, ...]``: this frame's pole sightings,
                       robot frame, at most one per landmark id, in id order
``pole_last_seen``     ``Mapping[int, float]``: landmark id -> time (s) of its last sighting
``self_pose``          :class:`perception.types.SlamEstimate`: pose, its covariance and
                       the landmark map (field frame)
``robot_sightings``    ``tuple[RobotSighting, ...]``: other robots seen this frame (robot
                       frame)
``sonar_observations`` ``tuple[SonarObservation, ...]``: reliable sonar echo clusters per
                       sector (seed 004's sonar filter)
``robot_tracks``       ``tuple[RobotTrack, ...]``: tracked robots (field frame)
``circle_map``         ``tuple[MappedCircle, ...]``: static circles mapped from laser
                       scans (field frame), by id
``field_features``     ``tuple[FieldFeature, ...]``: this frame's field lines, junctions,
                       centre circle, marks, posts and edges (robot frame)
``field_feature_last_seen``  ``Mapping[str, float]``: feature kind -> time (s) one was
                       last seen
``horizon_features``   :class:`perception.landmarks.horizon_features.HorizonFeatures`:
                       this frame's 1D SURF features on the horizon, with bearings
``odometry``           :class:`perception.types.OdometryStep`: the motion since the last
                       frame the pose estimators use (the walk's, or with the visual heading)
``field_end``          :class:`perception.landmarks.field_end.FieldEndBelief`: P(facing the
                       away goal) from natural landmarks, and whether it is certain
``ball_sightings``     ``tuple[BallSighting, ...]``: the ball seen this frame (robot frame),
                       best first
``ball``               :class:`perception.types.BallEstimate`: the ball's position and
                       velocity with their covariance (field frame)
=====================  ================================================================
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import dataclass, fields
from typing import Any, TypeVar

import numpy as np

from perception.geometry import FloatArray
from perception.types import SensorFrame

ODOMETRY_POSE = "odometry_pose"
IMAGE_DETECTIONS = "image_detections"
POLE_SIGHTINGS = "pole_sightings"
POLE_LAST_SEEN = "pole_last_seen"
SELF_POSE = "self_pose"
ROBOT_SIGHTINGS = "robot_sightings"
SONAR_OBSERVATIONS = "sonar_observations"
ROBOT_TRACKS = "robot_tracks"
CIRCLE_MAP = "circle_map"
FIELD_FEATURES = "field_features"
FIELD_FEATURE_LAST_SEEN = "field_feature_last_seen"
HORIZON_FEATURES = "horizon_features"
ODOMETRY = "odometry"
FIELD_END = "field_end"
BALL_SIGHTINGS = "ball_sightings"
BALL = "ball"
REPRESENTATIONS = (
    ODOMETRY_POSE,
    IMAGE_DETECTIONS,
    POLE_SIGHTINGS,
    POLE_LAST_SEEN,
    SELF_POSE,
    ROBOT_SIGHTINGS,
    SONAR_OBSERVATIONS,
    ROBOT_TRACKS,
    CIRCLE_MAP,
    FIELD_FEATURES,
    FIELD_FEATURE_LAST_SEEN,
    HORIZON_FEATURES,
    ODOMETRY,
    FIELD_END,
    BALL_SIGHTINGS,
    BALL,
)

# the SensorFrame fields a provider may read (all but its time and the emulated representations)
FRAME_INPUTS = tuple(f.name for f in fields(SensorFrame) if f.name not in ("time_s", "emulated"))

T = TypeVar("T")


@dataclass(frozen=True, kw_only=True)
class Prior:
    """What a provider is told at the start of an episode.

    ``pose`` (3,) is the believed start pose ``(x, y, θ)`` (field frame, m, m, rad); ``rng`` a
    generator for providers that draw noise (the oracles), seeded from the episode's.
    """

    pose: FloatArray
    rng: np.random.Generator

    def __post_init__(self) -> None:
        pose = np.asarray(self.pose, dtype=np.float64)
        if pose.shape != (3,) or not np.isfinite(pose).all():
            raise ValueError(f"Prior.pose must be 3 finite numbers, got {self.pose!r}")
        if not isinstance(self.rng, np.random.Generator):
            raise TypeError(f"Prior.rng must be a numpy Generator, got {type(self.rng).__name__}")


@dataclass(frozen=True)
class PerceptionOutput(Mapping[str, Any]):
    """Every representation one perception step produced, read like a dict by name.

    ``time_s`` is the frame's time (s). :meth:`get_as` reads a representation with a type
    check, for typed consumers.
    """

    time_s: float
    representations: Mapping[str, Any]

    def __getitem__(self, name: str) -> Any:
        try:
            return self.representations[name]
        except KeyError:
            raise KeyError(
                f"representation {name!r} was not computed; this pipeline provides "
                f"{sorted(self.representations)}"
            ) from None

    def __iter__(self) -> Iterator[str]:
        return iter(self.representations)

    def __len__(self) -> int:
        return len(self.representations)

    def get_as(self, name: str, kind: type[T]) -> T:
        """The representation ``name``, checked to be a ``kind``; TypeError otherwise."""
        value = self[name]
        if not isinstance(value, kind):
            raise TypeError(
                f"representation {name!r} is a {type(value).__name__}, expected {kind.__name__}"
            )
        return value
