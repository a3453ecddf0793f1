"""The ``info`` dict of the SPL envs: vector-safe (fixed shapes, masks), SI units, field frame.

Every entry has the same shape in every step of every episode of an env, so Gymnasium's vector
envs (and Ray RLlib) can stack it. Perception's entries come from one function per
representation, included when the pipeline computes it.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from perception.representations import ODOMETRY_POSE, POLE_SIGHTINGS, SELF_POSE
from perception.types import LandmarkObservation, SlamEstimate
from spl_env.world_state import WorldState


def _rows(ids: NDArray[np.int64], landmark_ids: NDArray[np.int64]) -> NDArray[np.intp]:
    """Row of each of ``ids`` in the env's fixed landmark order ``landmark_ids``."""
    order = {int(landmark_id): row for row, landmark_id in enumerate(landmark_ids)}
    return np.array([order[int(i)] for i in ids], dtype=np.intp)


def self_pose_info(slam: SlamEstimate, landmark_ids: NDArray[np.int64]) -> dict[str, Any]:
    """``pose`` (3,), ``pose_cov`` (3, 3); the map by the env's landmark order (L rows):
    ``landmarks`` (L, 2), ``landmark_covs`` (L, 2, 2), ``landmarks_mapped`` (L,) bool (rows of
    unmapped poles are zero), ``landmark_ids`` (L,)."""
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
    sightings: tuple[LandmarkObservation, ...], landmark_ids: NDArray[np.int64]
) -> dict[str, Any]:
    """This step's sightings by the env's landmark order: ``sightings`` (L, 2) range (m) and
    bearing (rad, robot frame), ``sighted`` (L,) bool (rows of unseen poles are zero)."""
    n = len(landmark_ids)
    values, seen = np.zeros((n, 2)), np.zeros(n, dtype=bool)
    ids = np.array([s.landmark_id for s in sightings], dtype=np.int64)
    for row, sighting in zip(_rows(ids, landmark_ids), sightings, strict=True):
        values[row] = (sighting.range_m, sighting.bearing_rad)
        seen[row] = True
    return {"sightings": values, "sighted": seen}


PERCEPTION_INFO: Mapping[str, Callable[[Any, NDArray[np.int64]], dict[str, Any]]] = {
    SELF_POSE: self_pose_info,
    POLE_SIGHTINGS: pole_sightings_info,
    ODOMETRY_POSE: lambda pose, ids: {"odometry_pose": np.asarray(pose).copy()},
}
FULL_INFO_REQUIRES = tuple(PERCEPTION_INFO)


def perception_info(output: Mapping[str, Any], landmark_ids: NDArray[np.int64]) -> dict[str, Any]:
    """``info["perception"]``: the entries of every representation in ``output`` that has some."""
    info: dict[str, Any] = {}
    for name, entries in PERCEPTION_INFO.items():
        if name in output:
            info.update(entries(output[name], landmark_ids))
    return info


def ground_truth_info(state: WorldState) -> dict[str, Any]:
    """``info["ground_truth"]``: our ``robot_pose`` (3,) and ``head`` (2,); ``landmarks`` (L, 2)
    with ``landmark_ids`` (L,); the other ``robots`` (R, 3) and ``robot_teams`` (R,);
    ``ball`` (2,) and ``ball_velocity`` (2,)."""
    return {
        "robot_pose": state.robot_pose.copy(),
        "head": state.head.copy(),
        "landmarks": state.landmarks.copy(),
        "landmark_ids": state.landmark_ids.copy(),
        "robots": state.robots.copy(),
        "robot_teams": state.robot_teams.copy(),
        "ball": state.ball.copy(),
        "ball_velocity": state.ball_velocity.copy(),
    }
