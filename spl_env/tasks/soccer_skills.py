"""Soccer skills as geometry: walk to the ball and kick it at a target; guard a goal.

Pure functions of poses and points in one frame (the field frame of the truth for the scripted
opponents in an env; the believed pose and ball for the scripted policies of
:mod:`agents.soccer_baselines`), returning a :class:`SkillCommand`: the walk as an action
(3,) in [-1, 1] (:func:`spl_env.robots.nao.walk_target` scales it) and whether to kick.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from perception.geometry import FloatArray, wrap_angle
from perception.validation import check_positive
from spl_env.robots.nao import RobotConfig, in_kick_zone

_OWNER = "SkillConfig"


@dataclass(frozen=True, kw_only=True)
class SkillConfig:
    """Gains and distances of the skills (SI units)."""

    kick_distance_m: float = 0.17  # the ball's distance ahead of the robot's centre at a kick
    position_gain: float = 2.0  # walk speed (m/s) per metre from the target, before limits
    heading_gain: float = 2.0  # turn rate (rad/s) per radian off the heading, before limits
    kick_heading_tolerance_rad: float = math.radians(12.0)  # kick only this well aligned
    detour_m: float = 0.35  # a robot on the wrong side of the ball walks round it this wide
    face_ball_beyond_m: float = 0.5  # farther from its kick spot, a robot walks facing the ball
    guard_distance_m: float = 0.45  # a goalie stands this far out from the goal's centre
    guard_half_width_m: float = 0.55  # ... and at most this far to the side of it

    def __post_init__(self) -> None:
        for name in (
            "kick_distance_m",
            "position_gain",
            "heading_gain",
            "kick_heading_tolerance_rad",
            "detour_m",
            "face_ball_beyond_m",
            "guard_distance_m",
            "guard_half_width_m",
        ):
            check_positive(_OWNER, name, getattr(self, name))


@dataclass(frozen=True)
class SkillCommand:
    """A skill's output: ``walk`` (3,) the walk action ``(vx, vy, omega)`` in [-1, 1] (robot
    frame, of the speed limits), ``kick`` whether to kick now and ``kick_angle_rad`` its
    direction off the heading (rad, + = left)."""

    walk: FloatArray
    kick: bool
    kick_angle_rad: float = 0.0


def walk_to(
    pose: FloatArray, target: FloatArray, heading: float, robot: RobotConfig, config: SkillConfig
) -> FloatArray:
    """The walk action (3,) in [-1, 1] that takes ``pose`` (3,) towards the point ``target``
    (2,) facing ``heading`` (rad), proportional to the errors, each component saturating at
    its speed limit."""
    c, s = math.cos(pose[2]), math.sin(pose[2])
    dx, dy = target[0] - pose[0], target[1] - pose[1]
    error = np.array([c * dx + s * dy, -s * dx + c * dy])  # robot frame
    turn = float(wrap_angle(heading - pose[2]))
    velocity = np.array([*(config.position_gain * error), config.heading_gain * turn])
    return np.clip(velocity / np.asarray(robot.max_speed), -1.0, 1.0)


def approach_and_kick(
    pose: FloatArray,
    ball: FloatArray,
    target: FloatArray,
    robot: RobotConfig,
    config: SkillConfig,
) -> SkillCommand:
    """Walk behind ``ball`` (2,) on the line from ``target`` (2,) through it (facing the ball
    while farther than ``face_ball_beyond_m`` from that spot, then ``target``) and kick once
    the ball lies in the kick zone with the heading within ``kick_heading_tolerance_rad``,
    towards ``target`` (the kick's direction takes up the heading's error). A
    robot ahead of the ball (on the target's side) walks round it, ``detour_m`` to the side it
    is on, rather than through it."""
    direction = np.asarray(target, dtype=np.float64) - ball
    norm = float(np.hypot(*direction))
    d = direction / norm if norm > 1e-9 else np.array([math.cos(pose[2]), math.sin(pose[2])])
    heading = math.atan2(d[1], d[0])
    offset = pose[:2] - ball
    behind = -float(d @ offset)  # > 0: the robot is behind the ball
    aside = float(d[0] * offset[1] - d[1] * offset[0])  # > 0: left of the kick line
    if behind < config.kick_distance_m / 2 and abs(aside) < config.detour_m:
        side = 1.0 if aside >= 0 else -1.0
        normal = np.array([-d[1], d[0]])
        waypoint = ball + side * config.detour_m * normal - d * config.kick_distance_m
        return SkillCommand(walk=walk_to(pose, waypoint, heading, robot, config), kick=False)
    stand = ball - d * config.kick_distance_m
    to_ball = ball - pose[:2]
    if float(np.hypot(*(stand - pose[:2]))) > config.face_ball_beyond_m:
        heading = math.atan2(to_ball[1], to_ball[0])  # walk forwards, the ball in view
    off = float(wrap_angle(heading - pose[2]))
    aligned = abs(off) <= config.kick_heading_tolerance_rad
    kick = aligned and in_kick_zone(robot, pose, ball)
    walk = walk_to(pose, stand, heading, robot, config)
    return SkillCommand(walk=walk, kick=kick, kick_angle_rad=off if kick else 0.0)


def guard_goal(
    pose: FloatArray,
    ball: FloatArray,
    goal_centre: FloatArray,
    robot: RobotConfig,
    config: SkillConfig,
) -> SkillCommand:
    """Stand between ``ball`` (2,) and ``goal_centre`` (2,), ``guard_distance_m`` out from the
    goal's centre towards the ball and at most ``guard_half_width_m`` to its side, facing the
    ball; never kicks."""
    towards = np.asarray(ball, dtype=np.float64) - goal_centre
    norm = float(np.hypot(*towards))
    out = -np.sign(goal_centre[0]) if goal_centre[0] != 0 else 1.0  # into the field
    unit = towards / norm if norm > 1e-9 else np.array([out, 0.0])
    stand = goal_centre + config.guard_distance_m * unit
    stand[1] = float(np.clip(stand[1], -config.guard_half_width_m, config.guard_half_width_m))
    facing = ball - pose[:2]
    heading = math.atan2(facing[1], facing[0]) if np.hypot(*facing) > 1e-9 else pose[2]
    return SkillCommand(walk=walk_to(pose, stand, heading, robot, config), kick=False)
