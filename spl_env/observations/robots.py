"""The other robots as perception tracks them: where, how fast, how sure, which team."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from gymnasium import spaces

from perception.geometry import FloatArray, range_bearing, rot_z
from perception.representations import ROBOT_TRACKS, SELF_POSE
from perception.types import RobotTrack, SlamEstimate
from spl_env.observations.base import EncoderInput, box, squash
from spl_env.observations.poles import RANGE_SCALE_M, SINCE_SEEN_SCALE_S
from spl_env.observations.self_pose import STD_SCALE_M

SPEED_SCALE_MPS = 0.3  # squashing scale of each velocity component (m/s)
ROBOT_KEYS = (  # RobotTracksEncoder's keys, in order
    "robots_cos_bearing",
    "robots_sin_bearing",
    "robots_range",
    "robots_velocity_x",
    "robots_velocity_y",
    "robots_std",
    "robots_team",
    "robots_since_seen",
    "robots_mask",
)


def nearest_confirmed(tracks: tuple[RobotTrack, ...], pose: FloatArray, k: int) -> list[RobotTrack]:
    """The ``k`` confirmed tracks nearest to ``pose`` (3,), nearest first."""
    confirmed = [t for t in tracks if t.confirmed]
    if not confirmed:
        return []
    distances = np.hypot(*(np.array([t.state[:2] for t in confirmed]) - pose[:2]).T)
    return [confirmed[i] for i in np.argsort(distances, kind="stable")[:k]]


@dataclass(frozen=True)
class RobotTracksEncoder:
    """Up to ``max_robots`` confirmed tracks, nearest first, seen from the SLAM pose; rows past
    the last track are zero with ``robots_mask`` 0:

    ``robots_cos_bearing``, ``robots_sin_bearing`` (robot frame), ``robots_range`` r / (r + 3 m),
    ``robots_velocity_x``, ``robots_velocity_y`` (robot frame) v / (|v| + 0.3 m/s),
    ``robots_std`` s / (s + 0.5 m) with s = sqrt(trace of the position covariance),
    ``robots_team`` +1 ours, -1 theirs, 0 unknown, ``robots_since_seen`` t / (t + 2 s),
    ``robots_mask``. ``our_team`` is our team id in the world (0 or 1)."""

    max_robots: int
    our_team: int = 0
    requires: tuple[str, ...] = (ROBOT_TRACKS, SELF_POSE)

    def spaces(self) -> dict[str, spaces.Box]:
        signed = {"robots_cos_bearing", "robots_sin_bearing", "robots_velocity_x"}
        signed |= {"robots_velocity_y", "robots_team"}
        return {
            key: box(-1.0 if key in signed else 0.0, 1.0, self.max_robots) for key in ROBOT_KEYS
        }

    def encode(self, data: EncoderInput) -> dict[str, FloatArray]:
        slam = data.output.get_as(SELF_POSE, SlamEstimate)
        tracks = nearest_confirmed(data.output[ROBOT_TRACKS], slam.pose, self.max_robots)
        obs = {key: np.zeros(self.max_robots) for key in ROBOT_KEYS}
        if not tracks:
            return obs
        n = len(tracks)
        states = np.array([t.state for t in tracks])
        rb = range_bearing(slam.pose, states[:, :2])
        velocity = states[:, 2:] @ rot_z(slam.pose[2])[:2, :2]  # field -> robot frame
        std = np.sqrt([np.trace(t.cov[:2, :2]) for t in tracks])
        since = np.array([data.output.time_s - t.last_seen_s for t in tracks])
        teams = [
            0.0 if t.team is None else (1.0 if t.team == self.our_team else -1.0) for t in tracks
        ]
        obs["robots_cos_bearing"][:n] = np.cos(rb[:, 1])
        obs["robots_sin_bearing"][:n] = np.sin(rb[:, 1])
        obs["robots_range"][:n] = squash(rb[:, 0], RANGE_SCALE_M)
        obs["robots_velocity_x"][:n] = velocity[:, 0] / (np.abs(velocity[:, 0]) + SPEED_SCALE_MPS)
        obs["robots_velocity_y"][:n] = velocity[:, 1] / (np.abs(velocity[:, 1]) + SPEED_SCALE_MPS)
        obs["robots_std"][:n] = squash(std, STD_SCALE_M)
        obs["robots_team"][:n] = teams
        obs["robots_since_seen"][:n] = squash(np.maximum(since, 0.0), SINCE_SEEN_SCALE_S)
        obs["robots_mask"][:n] = 1.0
        return obs
