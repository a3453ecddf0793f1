"""Scripted players for the soccer envs (``SPL/Striker-v0``, ``SPL/PenaltyShootout-v0``,
``SPL/Goalie-v0`` and their ``-NoPoles`` ids), reading only the observation, with SB3's
``predict`` signature.

- :class:`CentreKickStriker`: walk behind the believed ball and kick it at the goal's centre;
- :class:`GoalieAwareStriker`: the same, aiming at the middle of the wider gap beside the
  tracked goalie (the confirmed track nearest the goal's centre, within ``goalie_radius_m``);
  at the centre while no goalie is tracked;
- :class:`ScriptedGoalie`: stand between the believed ball and our goal's centre; kick the ball
  away when it lies in the kick zone.

While no ball is believed (not seen yet, or lost) they turn on the spot (the env's head
scans). The skills are :mod:`spl_env.tasks.soccer_skills`' (the env's scripted opponents use
them on the truth). Built from the env's config (``from_config``).
"""

from __future__ import annotations

import math
from abc import abstractmethod

import numpy as np

from agents.baselines import ScriptedPolicy
from perception.geometry import FloatArray
from spl_env.config import EnvConfig
from spl_env.observations.base import unsquash
from spl_env.observations.poles import RANGE_SCALE_M
from spl_env.robots.nao import RobotConfig, in_kick_zone
from spl_env.tasks.soccer import goal_centre
from spl_env.tasks.soccer_skills import (
    SkillCommand,
    SkillConfig,
    approach_and_kick,
    guard_goal,
)

SEARCH_TURN = 0.6  # walk action omega while the ball is unknown (of the turn speed limit)
GOALIE_RADIUS_M = 1.0  # a track this near the opponent goal's centre is its goalie
SEARCH = SkillCommand(walk=np.array([0.0, 0.0, SEARCH_TURN]), kick=False)  # turn on the spot


def believed_pose(obs: dict[str, np.ndarray], carpet_size_m: tuple[float, float]) -> FloatArray:
    """The believed pose (3,) ``(x, y, θ)`` from ``self_pose_field`` (field frame)."""
    p = obs["self_pose_field"].astype(np.float64)
    return np.array(
        [p[0] * carpet_size_m[0] / 2, p[1] * carpet_size_m[1] / 2, math.atan2(p[3], p[2])]
    )


def relative_point(pose: FloatArray, cos_b: float, sin_b: float, range_m: float) -> FloatArray:
    """The field point (2,) at ``range_m`` and bearing ``atan2(sin_b, cos_b)`` from ``pose``."""
    heading = pose[2] + math.atan2(sin_b, cos_b)
    return pose[:2] + range_m * np.array([math.cos(heading), math.sin(heading)])


def believed_ball(obs: dict[str, np.ndarray], pose: FloatArray) -> FloatArray | None:
    """The believed ball (2,) (field frame), or None while no ball is believed (before it was
    first seen, and after the ball filter lost it)."""
    if obs["ball_since_seen"][0] >= 1.0:
        return None
    cos_b, sin_b = obs["ball_bearing"]
    range_m = float(unsquash(obs["ball_range"][0], RANGE_SCALE_M))
    return relative_point(pose, float(cos_b), float(sin_b), range_m)


def tracked_robots(obs: dict[str, np.ndarray], pose: FloatArray) -> FloatArray:
    """The confirmed robot tracks' positions (K, 2) (field frame)."""
    rows = np.flatnonzero(obs["robots_mask"] > 0.5)
    ranges = unsquash(obs["robots_range"][rows], RANGE_SCALE_M)
    return np.array(
        [
            relative_point(
                pose, float(obs["robots_cos_bearing"][k]), float(obs["robots_sin_bearing"][k]), r
            )
            for k, r in zip(rows, ranges, strict=True)
        ]
    ).reshape(-1, 2)


def believed_goalie(
    obs: dict[str, np.ndarray], pose: FloatArray, goal: FloatArray
) -> FloatArray | None:
    """The goalie (2,) (field frame): the confirmed track nearest the goal's centre ``goal``
    (2,), None when none lies within :data:`GOALIE_RADIUS_M`."""
    robots = tracked_robots(obs, pose)
    if len(robots) == 0:
        return None
    distances = np.hypot(*(robots - goal).T)
    nearest = int(np.argmin(distances))
    return robots[nearest] if distances[nearest] <= GOALIE_RADIUS_M else None


def soccer_action(command: SkillCommand, robot: RobotConfig, strength: float = 1.0) -> np.ndarray:
    """The soccer env's action (5,) float32 of ``command``: the walk, a kick at ``strength``
    (0-1] or none, its direction (:func:`spl_env.robots.nao.kick_angle`'s inverse, clipped to
    [-1, 1])."""
    direction = np.clip(command.kick_angle_rad / robot.kick_max_angle_rad, -1.0, 1.0)
    kick = strength if command.kick else -1.0
    return np.array([*command.walk, kick, direction], dtype=np.float32)


class SoccerPolicy(ScriptedPolicy):
    """Base: the field, the skills, and the search while the ball is unknown."""

    def __init__(self, config: EnvConfig, skills: SkillConfig | None = None) -> None:
        super().__init__(config.robot, config.control_dt_s)
        self.dimensions = config.scene.dimensions
        self.skills = skills if skills is not None else SkillConfig()

    @classmethod
    def from_config(cls, config: EnvConfig) -> SoccerPolicy:
        return cls(config)

    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        pose = believed_pose(obs, self.dimensions.carpet_size_m)
        ball = believed_ball(obs, pose)
        command = SEARCH if ball is None else self.skill(obs, pose, ball)
        return soccer_action(command, self.robot)

    @abstractmethod
    def skill(self, obs: dict[str, np.ndarray], pose: FloatArray, ball: FloatArray) -> SkillCommand:
        """What to do with the ball believed at ``ball`` (2,) from ``pose`` (3,)."""


class CentreKickStriker(SoccerPolicy):
    """Walk behind the ball and kick it at the opponent goal's centre."""

    def skill(self, obs: dict[str, np.ndarray], pose: FloatArray, ball: FloatArray) -> SkillCommand:
        return approach_and_kick(pose, ball, self.aim(obs, pose), self.robot, self.skills)

    def aim(self, obs: dict[str, np.ndarray], pose: FloatArray) -> FloatArray:
        """The point (2,) to kick at."""
        return goal_centre(self.dimensions, 1)


class GoalieAwareStriker(CentreKickStriker):
    """Kick at the middle of the wider gap between the tracked goalie and a post."""

    goalie_half_width_m = 0.2  # the goalie blocks this far to either side (arms and ball)

    def aim(self, obs: dict[str, np.ndarray], pose: FloatArray) -> FloatArray:
        centre = goal_centre(self.dimensions, 1)
        goalie = believed_goalie(obs, pose, centre)
        if goalie is None:
            return centre
        post = self.dimensions.goal_inner_width_m / 2 - self.dimensions.ball_diameter_m
        y = wider_gap_middle(float(goalie[1]), post, self.goalie_half_width_m)
        return np.array([centre[0], y])


def wider_gap_middle(goalie_y: float, post_m: float, goalie_half_width_m: float) -> float:
    """The middle (m on the goal line) of the wider gap between a goalie at ``goalie_y``
    blocking ``goalie_half_width_m`` to either side and the posts at ``±post_m`` (less a
    ball): :class:`GoalieAwareStriker`'s aim."""
    left = (goalie_y + goalie_half_width_m, post_m)
    right = (-post_m, goalie_y - goalie_half_width_m)
    low, high = max(left, right, key=lambda g: g[1] - g[0])
    return (low + high) / 2


class ScriptedGoalie(SoccerPolicy):
    """Stand between the ball and our goal; kick the ball away when it is in the kick zone."""

    def skill(self, obs: dict[str, np.ndarray], pose: FloatArray, ball: FloatArray) -> SkillCommand:
        guard = guard_goal(pose, ball, goal_centre(self.dimensions, -1), self.robot, self.skills)
        return SkillCommand(walk=guard.walk, kick=in_kick_zone(self.robot, pose, ball))


SOCCER_BASELINES: dict[str, type[SoccerPolicy]] = {
    "centre_kick": CentreKickStriker,
    "goalie_aware": GoalieAwareStriker,
    "goalie": ScriptedGoalie,
}
