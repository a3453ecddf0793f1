"""The ground truth of one step (field frame, SI): on the SPL field every robot, the ball and the
landmarks (:class:`WorldState`); in a room, our robot and the circular objects (:class:`RoomState`).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import NDArray

from perception.geometry import FloatArray
from perception.types import GroundTruth


@dataclass(frozen=True, kw_only=True)
class WorldState:
    """Ground truth after a step.

    Robot ``k`` has ``names[k]``, ``kinds[k]`` (``"nao"``), ``teams[k]`` (0 or 1), pose
    ``poses[k]`` (3,) ``(x, y, θ)``, head angles ``heads[k]`` (2,) (yaw, pitch; rad) and
    ``blocked[k]``, whether it bumped into something this step. Robot ``agent`` is the one the
    env's policy drives (ours). ``ball`` (2,) and ``ball_velocity`` (2,) (m, m/s);
    ``landmarks`` (L, 2) pole positions with ``landmark_ids`` (L,); ``circles`` (K, 3) the
    static circular objects ``(x, y, R)`` (m): goal posts and poles.
    """

    time_s: float
    names: tuple[str, ...]
    kinds: tuple[str, ...]
    teams: NDArray[np.int64]
    poses: FloatArray
    heads: FloatArray
    blocked: NDArray[np.bool_]
    agent: int
    ball: FloatArray
    ball_velocity: FloatArray
    landmarks: FloatArray
    landmark_ids: NDArray[np.int64]
    circles: FloatArray

    @property
    def robot_pose(self) -> FloatArray:
        """Our robot's pose (3,)."""
        return self.poses[self.agent]

    @property
    def head(self) -> FloatArray:
        """Our robot's head angles (2,) (rad)."""
        return self.heads[self.agent]

    @cached_property
    def others(self) -> NDArray[np.int64]:
        """Indices (R,) of the robots other than ours."""
        return np.array([k for k in range(len(self.names)) if k != self.agent], dtype=np.int64)

    @property
    def robots(self) -> FloatArray:
        """Poses (R, 3) of the other robots."""
        return self.poses[self.others].reshape(-1, 3)

    @property
    def robot_teams(self) -> NDArray[np.int64]:
        """Teams (R,) of the other robots."""
        return self.teams[self.others]

    def truth_for(self, robot: int) -> GroundTruth:
        """What an oracle provider of robot ``robot`` may read."""
        return GroundTruth(
            robot_pose=self.poses[robot].copy(),
            landmark_ids=self.landmark_ids.copy(),
            landmarks=self.landmarks.copy(),
            robots=np.delete(self.poses, robot, axis=0)[:, :2].copy(),
            robot_teams=np.delete(self.teams, robot),
            ball=self.ball.copy(),
            ball_velocity=self.ball_velocity.copy(),
        )


@dataclass(frozen=True, kw_only=True)
class RoomState:
    """Ground truth after a step in a room of circular objects (the circle-mapping scenes).

    ``robot_pose`` (3,) our differential-drive robot's ``(x, y, θ)``; ``blocked`` whether it
    bumped into something this step; ``circles`` (K, 3) the objects' circles ``(x, y, R)``
    (m; a flat-sided trunk's round part) named ``object_names`` (K,).
    """

    time_s: float
    robot_pose: FloatArray
    blocked: bool
    circles: FloatArray
    object_names: tuple[str, ...]

    def truth_for_agent(self) -> GroundTruth:
        """What an oracle provider of our robot may read: its pose (no point landmarks)."""
        return GroundTruth(
            robot_pose=self.robot_pose.copy(),
            landmark_ids=np.zeros(0, dtype=np.int64),
            landmarks=np.zeros((0, 2)),
        )
