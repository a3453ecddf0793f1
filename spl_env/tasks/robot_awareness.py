"""Active vision among robots: keep localising while keeping track of the robots nearby."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from perception.geometry import FloatArray
from perception.representations import ROBOT_TRACKS, PerceptionOutput
from perception.types import RobotTrack
from perception.validation import check_int, check_positive
from spl_env.observations.base import ObservationEncoder
from spl_env.observations.robots import RobotTracksEncoder
from spl_env.tasks.active_vision import ActiveVisionTask, ActiveVisionTaskConfig
from spl_env.world_state import WorldState


@dataclass(frozen=True, kw_only=True)
class RobotAwarenessTaskConfig(ActiveVisionTaskConfig):
    """The tracked robots in the observation and the awareness reward."""

    max_tracked_robots: int = 8  # K: track rows in the observation (nearest first)
    awareness_radius_m: float = 3.0  # robots nearer than this should be tracked
    awareness_match_m: float = 0.3  # a confirmed track this close to a robot tracks it
    awareness_weight: float = 0.5  # reward per step when none of the nearby robots is tracked

    def __post_init__(self) -> None:
        super().__post_init__()
        owner = type(self).__name__
        check_int(owner, "max_tracked_robots", self.max_tracked_robots, 1)
        for name in ("awareness_radius_m", "awareness_match_m"):
            check_positive(owner, name, getattr(self, name))
        check_positive(owner, "awareness_weight", self.awareness_weight, allow_zero=True)


def awareness_share(
    position: FloatArray, robots: FloatArray, tracked: FloatArray, radius_m: float, match_m: float
) -> float | None:
    """Share of the other robots at ``robots`` (K, 2) within ``radius_m`` of ``position`` (2,)
    that a tracked position of ``tracked`` (M, 2) lies within ``match_m`` of (field frame, m);
    None when no robot is that near."""
    near = robots[np.hypot(*(robots - position).T) < radius_m]
    if len(near) == 0:
        return None
    if len(tracked) == 0:
        return 0.0
    gaps = np.hypot(*(near[:, None, :] - tracked[None, :, :]).transpose(2, 0, 1))
    return float(np.mean(gaps.min(axis=1) <= match_m))


def tracked_share(
    state: WorldState, tracks: tuple[RobotTrack, ...], radius_m: float, match_m: float
) -> float | None:
    """:func:`awareness_share` of the true robots of ``state`` and the confirmed ``tracks``."""
    positions = np.array([t.state[:2] for t in tracks if t.confirmed]).reshape(-1, 2)
    return awareness_share(state.robot_pose[:2], state.robots[:, :2], positions, radius_m, match_m)


class RobotAwarenessTask(ActiveVisionTask):
    """:class:`ActiveVisionTask` plus the tracked robots in the observation and a reward term
    ``robot_awareness``: ``-awareness_weight * (1 - share)``, with ``share`` the share of the
    robots within ``awareness_radius_m`` tracked within ``awareness_match_m`` (0 when no robot
    is near)."""

    config: RobotAwarenessTaskConfig

    def encoders(self) -> tuple[ObservationEncoder, ...]:
        return (*super().encoders(), RobotTracksEncoder(self.config.max_tracked_robots))

    def reward_requires(self) -> tuple[str, ...]:
        return (*super().reward_requires(), ROBOT_TRACKS)

    def reward_terms(self, state: WorldState, output: PerceptionOutput) -> dict[str, float]:
        c = self.config
        share = tracked_share(
            state, output[ROBOT_TRACKS], c.awareness_radius_m, c.awareness_match_m
        )
        awareness = 0.0 if share is None else -c.awareness_weight * (1.0 - share)
        return {**super().reward_terms(state, output), "robot_awareness": awareness}
