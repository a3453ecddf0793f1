"""Striker: score against a scripted goalie, on what perception believes."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from perception.geometry import FloatArray
from perception.representations import PerceptionOutput
from perception.validation import check_positive
from spl_env.robots.nao import NaoCommand, NaoRobot, walk_target
from spl_env.tasks.base import TaskContext
from spl_env.tasks.soccer import SoccerTask, SoccerTaskConfig, ball_in_goal, ball_out, goal_centre
from spl_env.tasks.soccer_skills import guard_goal
from spl_env.world_state import WorldState


@dataclass(frozen=True, kw_only=True)
class StrikerTaskConfig(SoccerTaskConfig):
    """The striker's reward weights; ``n_other_robots`` is the goalie plus defenders (1 = the
    goalie alone)."""

    episode_s: float = 60.0
    progress_weight: float = 1.0  # reward per metre the ball comes nearer the goal's centre
    time_cost: float = 0.01  # reward -time_cost per step
    out_penalty: float = 1.0  # reward -out_penalty when the ball leaves the field elsewhere

    def __post_init__(self) -> None:
        super().__post_init__()
        owner = type(self).__name__
        if self.n_other_robots < 1:
            raise ValueError(
                f"{owner}.n_other_robots must be >= 1 (the goalie), got {self.n_other_robots}"
            )
        for name in ("progress_weight", "time_cost", "out_penalty"):
            check_positive(owner, name, getattr(self, name), allow_zero=True)


class StrikerTask(SoccerTask):
    """Our robot starts in its own half, the ball anywhere in front of the opponent's penalty
    area; the goalie (the first scripted robot, the other team) guards the goal at +x
    (:func:`spl_env.tasks.soccer_skills.guard_goal`); defenders (the others) walk to random
    waypoints.

    Reward terms: ``goal`` +goal_reward for a goal at +x, -goal_reward for one at -x;
    ``progress`` progress_weight x the metres the ball came nearer the opponent goal's centre
    this step; ``time`` -time_cost; ``out`` -out_penalty when the ball leaves the field other
    than through a goal. Terminated on a goal or the ball out.
    """

    config: StrikerTaskConfig

    def __init__(self, config: StrikerTaskConfig, context: TaskContext) -> None:
        super().__init__(config, context)
        self._last_distance = 0.0

    def our_start(self, rng: np.random.Generator) -> FloatArray:
        dims = self.context.dimensions
        x = rng.uniform(-dims.half_length_m + 1.0, -0.5)
        y = rng.uniform(-dims.half_width_m + 0.8, dims.half_width_m - 0.8)
        return np.array([x, y, rng.uniform(-np.pi / 2, np.pi / 2)])

    def place_scripted(
        self, rng: np.random.Generator, others: Sequence[NaoRobot], placed: list[NaoRobot]
    ) -> FloatArray:
        dims = self.context.dimensions
        goalie, defenders = others[0], others[1:]
        goalie.place(np.array([dims.half_length_m - 0.3, rng.uniform(-0.3, 0.3), np.pi]))
        placed.append(goalie)
        self.wanderers.reset(rng, defenders, self.context.placement, placed)
        ball = np.array([rng.uniform(0.0, 2.5), rng.uniform(-2.0, 2.0)])
        self._last_distance = self.goal_distance(ball)
        return ball

    def goal_distance(self, ball: FloatArray) -> float:
        """The ball's (2,) distance (m) to the opponent goal's centre."""
        return float(np.hypot(*(ball - goal_centre(self.context.dimensions, 1))))

    def scripted_commands(self, state: WorldState) -> list[NaoCommand]:
        others = state.others
        dims, robot = self.context.dimensions, self.context.robot
        goalie_pose = state.poses[others[0]]
        guard = guard_goal(goalie_pose, state.ball, goal_centre(dims, 1), robot, self.config.skills)
        walks = self.wanderers.commands(
            state.poses[others[1:]], self.context.control_dt_s, state.blocked[others[1:]]
        )
        return [
            NaoCommand(walk=walk_target(robot, guard.walk)),
            *(NaoCommand(walk=walk) for walk in walks),
        ]

    def reward_terms(self, state: WorldState, output: PerceptionOutput) -> dict[str, float]:
        c, dims = self.config, self.context.dimensions
        distance = self.goal_distance(state.ball)
        progress, self._last_distance = self._last_distance - distance, distance
        goal = ball_in_goal(state.ball, dims)
        out = ball_out(state.ball, dims) and goal == 0
        return {
            "goal": c.goal_reward * goal,
            "progress": c.progress_weight * progress,
            "time": -c.time_cost,
            "out": -c.out_penalty * out,
        }

    def terminated(self, state: WorldState, output: PerceptionOutput) -> bool:
        return ball_out(state.ball, self.context.dimensions)
