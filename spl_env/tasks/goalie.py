"""Goalie: keep the ball out of our goal against a scripted kicker, on what perception
believes."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from perception.geometry import FloatArray
from perception.representations import PerceptionOutput
from perception.validation import check_positive, check_reals
from spl_env.robots.nao import NaoCommand, NaoRobot, walk_target
from spl_env.tasks.base import TaskContext
from spl_env.tasks.soccer import (
    ShotWatch,
    SoccerTask,
    SoccerTaskConfig,
    ball_in_goal,
    ball_out,
    goal_centre,
)
from spl_env.tasks.soccer_skills import approach_and_kick
from spl_env.world_state import WorldState

SHOT_ANGLE_MAX_RAD = 0.9  # the ball lies up to this far off the goal's axis, seen from its centre
KICKER_BEHIND_M = (0.5, 1.0)  # the kicker starts this far behind the ball (m)


@dataclass(frozen=True, kw_only=True)
class GoalieTaskConfig(SoccerTaskConfig):
    """Where the shot comes from, and the goalie's rewards; ``n_other_robots`` is the kicker
    plus others walking about."""

    episode_s: float = 30.0
    shot_distance_m: tuple[float, float] = (1.5, 3.5)  # the ball starts this far out (m)
    save_reward: float = 1.0  # reward when a kicked ball stops (or the ball leaves) not in goal

    def __post_init__(self) -> None:
        super().__post_init__()
        owner = type(self).__name__
        if self.n_other_robots < 1:
            raise ValueError(
                f"{owner}.n_other_robots must be >= 1 (the kicker), got {self.n_other_robots}"
            )
        check_reals(owner, "shot_distance_m", self.shot_distance_m, 2)
        low, high = self.shot_distance_m
        if not 0.5 <= low <= high:
            raise ValueError(
                f"{owner}.shot_distance_m must be (low, high) with 0.5 <= low <= high, got "
                f"{self.shot_distance_m}"
            )
        check_positive(owner, "save_reward", self.save_reward, allow_zero=True)


def farthest_shot_m(context: TaskContext) -> float:
    """The largest ``shot_distance_m`` (m) that keeps the ball inside the touch lines and the
    kicker, up to ``KICKER_BEHIND_M[1]`` farther out, on the carpet clear of its edge, for every
    shot angle."""
    dims, sine = context.dimensions, math.sin(SHOT_ANGLE_MAX_RAD)
    carpet_half_width = dims.carpet_size_m[1] / 2 - context.robot.body_radius_m
    return min(dims.half_width_m / sine, carpet_half_width / sine - KICKER_BEHIND_M[1])


class GoalieTask(SoccerTask):
    """Our robot starts on its goal line (at -x) facing the field; the ball lies
    ``shot_distance_m`` out in front of the goal; the kicker (the first scripted robot, the
    other team) starts 0.5-1 m behind the ball, walks up to it and kicks it once at full
    strength at a random point between our posts
    (:func:`spl_env.tasks.soccer_skills.approach_and_kick`); others walk to random waypoints.

    Reward terms: ``goal`` -goal_reward when the ball is in our goal; ``save`` +save_reward
    when a kicked ball stops slower than ``stopped_speed_mps`` or the ball leaves the field
    other than through our goal. Terminated then, or on a goal. Any kick counts: a goalie that
    clears the ball before the kicker reaches it (the kicker then stands, its shot gone) has
    kept it out, and so has one that pushes it over a line.
    """

    config: GoalieTaskConfig

    def __init__(self, config: GoalieTaskConfig, context: TaskContext) -> None:
        super().__init__(config, context)
        limit = farthest_shot_m(context)
        if config.shot_distance_m[1] > limit:
            raise ValueError(
                f"{type(config).__name__}.shot_distance_m must keep the ball inside the touch "
                f"lines and the kicker behind it on the carpet at "
                f"{math.degrees(SHOT_ANGLE_MAX_RAD):.0f} degrees off the goal's axis: high <= "
                f"{math.floor(100 * limit) / 100:.2f} m, got {config.shot_distance_m}"
            )
        self._target = np.zeros(2)
        self._shot = ShotWatch(config)

    def our_start(self, rng: np.random.Generator) -> FloatArray:
        self._shot.reset()
        dims = self.context.dimensions
        return np.array([-dims.half_length_m + 0.2, rng.uniform(-0.3, 0.3), 0.0])

    def place_scripted(
        self, rng: np.random.Generator, others: Sequence[NaoRobot], placed: list[NaoRobot]
    ) -> FloatArray:
        dims = self.context.dimensions
        angle = rng.uniform(-SHOT_ANGLE_MAX_RAD, SHOT_ANGLE_MAX_RAD)
        distance = rng.uniform(*self.config.shot_distance_m)
        ball = goal_centre(dims, -1) + distance * np.array([np.cos(angle), np.sin(angle)])
        behind = rng.uniform(*KICKER_BEHIND_M)
        kicker, rest = others[0], others[1:]
        kicker.place(
            np.array([*(ball + behind * np.array([np.cos(angle), np.sin(angle)])), angle + np.pi])
        )
        placed.append(kicker)
        self.wanderers.reset(rng, rest, self.context.placement, placed)
        half = dims.goal_inner_width_m / 2 - dims.ball_diameter_m
        self._target = np.array([-dims.half_length_m - 0.3, rng.uniform(-half, half)])
        return ball

    def scripted_commands(self, state: WorldState) -> list[NaoCommand]:
        others = state.others
        robot = self.context.robot
        kicker = NaoCommand()  # after its kick the kicker stands
        if not self._shot.kicked:
            skill = approach_and_kick(
                state.poses[others[0]], state.ball, self._target, robot, self.config.skills
            )
            kicker = NaoCommand(
                walk=walk_target(robot, skill.walk),
                kick=skill.kick,
                kick_angle_rad=skill.kick_angle_rad,
            )
        walks = self.wanderers.commands(
            state.poses[others[1:]], self.context.control_dt_s, state.blocked[others[1:]]
        )
        return [kicker, *(NaoCommand(walk=walk) for walk in walks)]

    def _over(self, state: WorldState) -> tuple[bool, bool]:
        """Whether a goal was conceded, and whether the shot is otherwise over (saved)."""
        dims = self.context.dimensions
        conceded = ball_in_goal(state.ball, dims) == -1
        stopped = self._shot.stopped(state.ball_velocity)
        saved = not conceded and (stopped or ball_out(state.ball, dims))
        return conceded, saved

    def reward_terms(self, state: WorldState, output: PerceptionOutput) -> dict[str, float]:
        conceded, saved = self._over(state)
        return {
            "goal": -self.config.goal_reward * conceded,
            "save": self.config.save_reward * saved,
        }

    def terminated(self, state: WorldState, output: PerceptionOutput) -> bool:
        return any(self._over(state))
