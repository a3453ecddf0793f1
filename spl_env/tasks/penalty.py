"""Penalty shoot-out (seed 004's penalty test as a task): one kick from the penalty mark past a
goalie standing somewhere in the goal."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from perception.geometry import FloatArray
from perception.representations import PerceptionOutput
from perception.validation import check_positive
from spl_env.robots.nao import NaoCommand, NaoRobot
from spl_env.tasks.base import TaskContext
from spl_env.tasks.soccer import ShotWatch, ball_out
from spl_env.tasks.striker import StrikerTask, StrikerTaskConfig
from spl_env.world_state import WorldState


@dataclass(frozen=True, kw_only=True)
class PenaltyTaskConfig(StrikerTaskConfig):
    """Where the striker starts and the goalie stands."""

    episode_s: float = 20.0
    start_behind_ball_m: float = 1.2  # the striker starts this far behind the ball (seed 004)
    goalie_max_offset_m: float = 0.45  # the goalie stands up to this far left or right

    def __post_init__(self) -> None:
        super().__post_init__()
        owner = type(self).__name__
        check_positive(owner, "start_behind_ball_m", self.start_behind_ball_m)
        check_positive(owner, "goalie_max_offset_m", self.goalie_max_offset_m, allow_zero=True)


class PenaltyTask(StrikerTask):
    """The ball lies on the opponent penalty mark, our robot ``start_behind_ball_m`` behind it
    facing the goal; the goalie (the other team) stands just in front of its goal line, a uniform
    ``goalie_max_offset_m`` to either side, and does not move; defenders, if any, wander.

    Reward terms as :class:`StrikerTask`'s. Terminated on a goal, the ball out, or a kicked
    ball slower than ``stopped_speed_mps`` (missed or saved).
    """

    config: PenaltyTaskConfig

    def __init__(self, config: PenaltyTaskConfig, context: TaskContext) -> None:
        super().__init__(config, context)
        owner, dims = type(config).__name__, context.dimensions
        check_positive(
            owner,
            "start_behind_ball_m",
            config.start_behind_ball_m,
            upper=dims.length_m - dims.penalty_mark_distance_m,  # from our goal line
            upper_inclusive=True,
        )
        check_positive(
            owner,
            "goalie_max_offset_m",
            config.goalie_max_offset_m,
            allow_zero=True,
            upper=dims.goal_inner_width_m / 2 - context.robot.body_radius_m,  # in its goal
            upper_inclusive=True,
        )
        self._shot = ShotWatch(config)

    def penalty_mark(self) -> FloatArray:
        """The opponent penalty mark (2,) (m)."""
        dims = self.context.dimensions
        return np.array([dims.half_length_m - dims.penalty_mark_distance_m, 0.0])

    def our_start(self, rng: np.random.Generator) -> FloatArray:
        self._shot.reset()
        mark = self.penalty_mark()
        return np.array([mark[0] - self.config.start_behind_ball_m, mark[1], 0.0])

    def place_scripted(
        self, rng: np.random.Generator, others: Sequence[NaoRobot], placed: list[NaoRobot]
    ) -> FloatArray:
        dims = self.context.dimensions
        goalie, defenders = others[0], others[1:]
        offset = rng.uniform(-self.config.goalie_max_offset_m, self.config.goalie_max_offset_m)
        goalie.place(np.array([dims.half_length_m - 0.15, offset, np.pi]))
        placed.append(goalie)
        self.wanderers.reset(rng, defenders, self.context.placement, placed)
        ball = self.penalty_mark()
        self._last_distance = self.goal_distance(ball)
        return ball

    def scripted_commands(self, state: WorldState) -> list[NaoCommand]:
        others = state.others[1:]
        walks = self.wanderers.commands(
            state.poses[others], self.context.control_dt_s, state.blocked[others]
        )
        return [NaoCommand(), *(NaoCommand(walk=walk) for walk in walks)]

    def terminated(self, state: WorldState, output: PerceptionOutput) -> bool:
        stopped = self._shot.stopped(state.ball_velocity)
        return ball_out(state.ball, self.context.dimensions) or stopped  # a goal is out too
