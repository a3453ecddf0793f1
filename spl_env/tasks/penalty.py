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
from spl_env.tasks.soccer import ball_out
from spl_env.tasks.striker import StrikerTask, StrikerTaskConfig
from spl_env.world_state import WorldState


@dataclass(frozen=True, kw_only=True)
class PenaltyTaskConfig(StrikerTaskConfig):
    """Where the striker starts and the goalie stands, and when a kick is over."""

    episode_s: float = 20.0
    start_behind_ball_m: float = 1.2  # the striker starts this far behind the ball (seed 004)
    goalie_max_offset_m: float = 0.45  # the goalie stands up to this far left or right
    kicked_speed_mps: float = 0.3  # a ball this fast has been kicked
    stopped_speed_mps: float = 0.05  # a kicked ball this slow is over: missed or saved

    def __post_init__(self) -> None:
        super().__post_init__()
        owner = type(self).__name__
        for name in ("start_behind_ball_m", "kicked_speed_mps", "stopped_speed_mps"):
            check_positive(owner, name, getattr(self, name))
        check_positive(owner, "goalie_max_offset_m", self.goalie_max_offset_m, allow_zero=True)
        if not self.stopped_speed_mps < self.kicked_speed_mps:
            raise ValueError(
                f"{owner}.stopped_speed_mps must be < kicked_speed_mps, got "
                f"{self.stopped_speed_mps} and {self.kicked_speed_mps}"
            )


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
        self._kicked = False

    def penalty_mark(self) -> FloatArray:
        """The opponent penalty mark (2,) (m)."""
        dims = self.context.dimensions
        return np.array([dims.half_length_m - dims.penalty_mark_distance_m, 0.0])

    def our_start(self, rng: np.random.Generator) -> FloatArray:
        self._kicked = False
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
        self._last_distance = float(np.hypot(*(ball - np.array([dims.half_length_m, 0.0]))))
        return ball

    def scripted_commands(self, state: WorldState) -> list[NaoCommand]:
        others = state.others[1:]
        walks = self.wanderers.commands(
            state.poses[others], self.context.control_dt_s, state.blocked[others]
        )
        return [NaoCommand(), *(NaoCommand(walk=walk) for walk in walks)]

    def terminated(self, state: WorldState, output: PerceptionOutput) -> bool:
        dims = self.context.dimensions
        speed = float(np.hypot(*state.ball_velocity))
        self._kicked = self._kicked or speed >= self.config.kicked_speed_mps
        stopped = self._kicked and speed < self.config.stopped_speed_mps
        return ball_out(state.ball, dims) or stopped  # a goal is out too
