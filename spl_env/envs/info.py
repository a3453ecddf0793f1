"""The ``info`` dict of the SPL envs: vector-safe (fixed shapes, masks), SI units, field frame.

Every entry has the same shape in every step of every episode of an env, so Gymnasium's vector
envs (and Ray RLlib) can stack it. Perception's entries come from one function per
representation, included when the pipeline computes it.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from perception.field.features import FEATURE_KINDS, FieldFeature
from perception.representations import (
    BALL,
    CIRCLE_MAP,
    FIELD_FEATURES,
    ODOMETRY,
    ODOMETRY_POSE,
    POLE_SIGHTINGS,
    ROBOT_TRACKS,
    SELF_POSE,
)
from perception.types import (
    BallEstimate,
    LandmarkObservation,
    MappedCircle,
    OdometryStep,
    RobotTrack,
    SlamEstimate,
)
from spl_env.world_state import WorldState


def _rows(ids: NDArray[np.int64], landmark_ids: NDArray[np.int64]) -> NDArray[np.intp]:
    """Row of each of ``ids`` in the env's fixed landmark order ``landmark_ids``."""
    order = {int(landmark_id): row for row, landmark_id in enumerate(landmark_ids)}
    return np.array([order[int(i)] for i in ids], dtype=np.intp)


@dataclass(frozen=True)
class InfoLayout:
    """The fixed sizes of an env's ``info``: its poles' ids (L,) in row order, the number of
    robot-track rows, of circle-map rows and of field-feature rows."""

    landmark_ids: NDArray[np.int64]
    max_robots: int
    max_circles: int
    max_field_features: int = 32


def self_pose_info(slam: SlamEstimate, layout: InfoLayout) -> dict[str, Any]:
    """``pose`` (3,), ``pose_cov`` (3, 3); the map by the env's landmark order (L rows):
    ``landmarks`` (L, 2), ``landmark_covs`` (L, 2, 2), ``landmarks_mapped`` (L,) bool (rows of
    unmapped poles are zero), ``landmark_ids`` (L,)."""
    landmark_ids = layout.landmark_ids
    n = len(landmark_ids)
    rows = _rows(slam.landmark_ids, landmark_ids)
    landmarks, covs = np.zeros((n, 2)), np.zeros((n, 2, 2))
    mapped = np.zeros(n, dtype=bool)
    landmarks[rows], covs[rows], mapped[rows] = slam.landmarks, slam.landmark_covs, True
    return {
        "pose": slam.pose.copy(),
        "pose_cov": slam.pose_cov.copy(),
        "landmark_ids": landmark_ids.copy(),
        "landmarks": landmarks,
        "landmark_covs": covs,
        "landmarks_mapped": mapped,
    }


def pole_sightings_info(
    sightings: tuple[LandmarkObservation, ...], layout: InfoLayout
) -> dict[str, Any]:
    """This step's sightings by the env's landmark order: ``sightings`` (L, 2) range (m) and
    bearing (rad, robot frame), ``sighted`` (L,) bool (rows of unseen poles are zero)."""
    landmark_ids = layout.landmark_ids
    n = len(landmark_ids)
    values, seen = np.zeros((n, 2)), np.zeros(n, dtype=bool)
    ids = np.array([s.landmark_id for s in sightings], dtype=np.int64)
    for row, sighting in zip(_rows(ids, landmark_ids), sightings, strict=True):
        values[row] = (sighting.range_m, sighting.bearing_rad)
        seen[row] = True
    return {"sightings": values, "sighted": seen}


def robot_tracks_info(tracks: tuple[RobotTrack, ...], layout: InfoLayout) -> dict[str, Any]:
    """The confirmed robot tracks, ``max_robots`` rows, ordered by track id: ``robots`` (K, 2)
    positions, ``robot_velocities`` (K, 2), ``robot_covs`` (K, 2, 2) position covariances,
    ``robot_teams`` (K,) (0 or 1, -1 unknown), ``robot_track_ids`` (K,) and ``robots_tracked``
    (K,) bool; rows past the last track are zero (ids and teams -1)."""
    k = layout.max_robots
    confirmed = sorted((t for t in tracks if t.confirmed), key=lambda t: t.track_id)[:k]
    info: dict[str, Any] = {
        "robots": np.zeros((k, 2)),
        "robot_velocities": np.zeros((k, 2)),
        "robot_covs": np.zeros((k, 2, 2)),
        "robot_teams": np.full(k, -1, dtype=np.int64),
        "robot_track_ids": np.full(k, -1, dtype=np.int64),
        "robots_tracked": np.zeros(k, dtype=bool),
    }
    for row, track in enumerate(confirmed):
        info["robots"][row] = track.state[:2]
        info["robot_velocities"][row] = track.state[2:]
        info["robot_covs"][row] = track.cov[:2, :2]
        info["robot_teams"][row] = -1 if track.team is None else track.team
        info["robot_track_ids"][row] = track.track_id
        info["robots_tracked"][row] = True
    return info


def circle_map_info(circles: tuple[MappedCircle, ...], layout: InfoLayout) -> dict[str, Any]:
    """The confirmed circles of the circle map, ``max_circles`` rows, by circle id:
    ``circles`` (C, 3) ``(x, y, R)`` (m), ``circle_covs`` (C, 3, 3), ``circle_ids`` (C,) and
    ``circles_mapped`` (C,) bool; rows past the last circle are zero (ids -1)."""
    k = layout.max_circles
    confirmed = sorted((c for c in circles if c.confirmed), key=lambda c: c.circle_id)[:k]
    info: dict[str, Any] = {
        "circles": np.zeros((k, 3)),
        "circle_covs": np.zeros((k, 3, 3)),
        "circle_ids": np.full(k, -1, dtype=np.int64),
        "circles_mapped": np.zeros(k, dtype=bool),
    }
    for row, circle in enumerate(confirmed):
        info["circles"][row] = circle.state
        info["circle_covs"][row] = circle.cov
        info["circle_ids"][row] = circle.circle_id
        info["circles_mapped"][row] = True
    return info


def field_features_info(features: tuple[FieldFeature, ...], layout: InfoLayout) -> dict[str, Any]:
    """This frame's field features (robot frame), ``max_field_features`` rows in detection
    order: ``field_features`` (F, 2, 2) the points (a segment's two ends; a point feature's
    point twice), ``field_feature_covs`` (F, 2, 2, 2) their covariances,
    ``field_feature_kinds`` (F,) the index of the kind in
    :data:`perception.field.features.FEATURE_KINDS` (-1 past the last),
    ``field_feature_directions`` (F,) (rad; 0 where ``field_feature_has_direction`` (F,) is
    False: NaN would make equal infos compare unequal) and ``field_features_count``."""
    k = layout.max_field_features
    info = {
        "field_features": np.zeros((k, 2, 2)),
        "field_feature_covs": np.zeros((k, 2, 2, 2)),
        "field_feature_kinds": np.full(k, -1, dtype=np.int64),
        "field_feature_directions": np.zeros(k),
        "field_feature_has_direction": np.zeros(k, dtype=bool),
        "field_features_count": np.int64(min(len(features), k)),
    }
    for row, feature in enumerate(features[:k]):
        points = np.resize(feature.points, (2, 2))
        info["field_features"][row] = points
        info["field_feature_covs"][row] = np.resize(feature.cov, (2, 2, 2))
        info["field_feature_kinds"][row] = FEATURE_KINDS.index(feature.kind)
        if feature.direction is not None:
            info["field_feature_directions"][row] = feature.direction
            info["field_feature_has_direction"][row] = True
    return info


def odometry_info(step: OdometryStep, layout: InfoLayout) -> dict[str, Any]:
    """The odometry the pose estimators used this step (``odometry_delta`` (3,), robot frame),
    the walk's report (``walk_odometry_delta`` (3,)), whether its heading change was visual
    (``visual_heading``), that frame pair's vote margin (``visual_heading_confidence``) and the
    collision flag (``collision``: 1 / -1 turning left / right of the walk, else 0)."""
    return {
        "odometry_delta": np.asarray(step.delta, dtype=np.float64).copy(),
        "walk_odometry_delta": np.asarray(step.walk_delta, dtype=np.float64).copy(),
        "visual_heading": np.bool_(step.visual),
        "visual_heading_confidence": np.int64(step.confidence),
        "collision": np.int64(step.collision),
    }


def ball_info(ball: BallEstimate, layout: InfoLayout) -> dict[str, Any]:
    """The believed ball (field frame): ``ball`` (2,) position (m), ``ball_velocity`` (2,)
    (m/s), ``ball_cov`` (4, 4) over both, ``ball_relative`` (2,) its position in our robot's
    frame (m; the filter's own estimate, free of the pose's error), ``ball_known`` (a ball is
    believed: seen, and not lost since) and ``ball_last_seen_s``
    (s; -1 before the first sighting: -inf would not survive JSON)."""
    return {
        "ball": ball.state[:2].copy(),
        "ball_relative": ball.relative[:2].copy(),
        "ball_velocity": ball.state[2:].copy(),
        "ball_cov": ball.cov.copy(),
        "ball_known": np.bool_(ball.known),
        "ball_last_seen_s": np.float64(
            ball.last_seen_s if math.isfinite(ball.last_seen_s) else -1.0
        ),
    }


PERCEPTION_INFO: Mapping[str, Callable[[Any, InfoLayout], dict[str, Any]]] = {
    ODOMETRY: odometry_info,
    SELF_POSE: self_pose_info,
    POLE_SIGHTINGS: pole_sightings_info,
    ODOMETRY_POSE: lambda pose, layout: {"odometry_pose": np.asarray(pose).copy()},
    ROBOT_TRACKS: robot_tracks_info,
    CIRCLE_MAP: circle_map_info,
    FIELD_FEATURES: field_features_info,
    BALL: ball_info,
}
# what the full info always reads; robot tracks join where the env's task already tracks robots
FULL_INFO_REQUIRES = (SELF_POSE, POLE_SIGHTINGS, ODOMETRY_POSE)


def perception_info(output: Mapping[str, Any], layout: InfoLayout) -> dict[str, Any]:
    """``info["perception"]``: the entries of every representation in ``output`` that has some."""
    info: dict[str, Any] = {}
    for name, entries in PERCEPTION_INFO.items():
        if name in output:
            info.update(entries(output[name], layout))
    return info


def ground_truth_info(state: WorldState) -> dict[str, Any]:
    """``info["ground_truth"]``: our ``robot_pose`` (3,) and ``head`` (2,); ``landmarks`` (L, 2)
    with ``landmark_ids`` (L,); the other ``robots`` (R, 3) and ``robot_teams`` (R,);
    ``ball`` (2,) and ``ball_velocity`` (2,); ``circles`` (K, 3) the goal posts and poles as
    ``(x, y, R)``."""
    return {
        "robot_pose": state.robot_pose.copy(),
        "head": state.head.copy(),
        "landmarks": state.landmarks.copy(),
        "landmark_ids": state.landmark_ids.copy(),
        "robots": state.robots.copy(),
        "robot_teams": state.robot_teams.copy(),
        "ball": state.ball.copy(),
        "ball_velocity": state.ball_velocity.copy(),
        "circles": state.circles.copy(),
    }
