"""The task interface: what an env asks of its robots and how it scores them.

A task owns the placement of the bodies at the start of an episode, the scripted bodies, the
action space and its mapping to our robot's command, the observation encoders, the reward
terms and termination. The env core (:mod:`spl_env.envs.core`) owns the one step loop:
physics, sensing, perception, observation, info.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from gymnasium import spaces

from perception.geometry import FloatArray
from perception.representations import PerceptionOutput
from perception.validation import check_int, check_nested_configs
from spl_env.behaviours import WalkerConfig, WanderingRobots
from spl_env.field import FieldDimensions
from spl_env.observations.base import ObservationEncoder
from spl_env.robots.nao import NaoCommand, NaoRobot, RobotConfig
from spl_env.sim.placement import Placement
from spl_env.tasks.episode import EpisodeConfig
from spl_env.world_state import WorldState

MAX_OTHER_ROBOTS = 9  # scripted robots that may share the field with ours


@dataclass(frozen=True, kw_only=True)
class TaskConfig(EpisodeConfig):
    """What every SPL task has: the episode length and the scripted robots walking about."""

    n_other_robots: int = 4  # scripted robots walking to random waypoints (occluders)
    other_walker: WalkerConfig = field(default_factory=WalkerConfig)

    def __post_init__(self) -> None:
        super().__post_init__()
        check_nested_configs(self)
        check_int("TaskConfig", "n_other_robots", self.n_other_robots)
        if not 0 <= self.n_other_robots <= MAX_OTHER_ROBOTS:
            raise ValueError(
                f"TaskConfig.n_other_robots must be an int in [0, {MAX_OTHER_ROBOTS}], "
                f"got {self.n_other_robots!r}"
            )

    @property
    def other_robot_teams(self) -> tuple[int, ...]:
        """The team (0 ours, 1 theirs) of each scripted robot: by default theirs and ours in
        turn."""
        return tuple((k + 1) % 2 for k in range(self.n_other_robots))


@dataclass(frozen=True, kw_only=True)
class TaskContext:
    """What a task is built from: the field, our robot's body, the control rate, the number of
    mapped poles and the placement rules (free poses, collisions) of the env's world."""

    dimensions: FieldDimensions
    robot: RobotConfig
    control_dt_s: float
    n_landmarks: int
    placement: Placement


class Task(ABC):
    """One env's job for our robot (robot 0) among ``config.n_other_robots`` scripted robots.

    The core calls, per episode: :meth:`start_pose`, then :meth:`place_scripted`; per step:
    :meth:`command`, :meth:`scripted_commands`, and after physics and perception
    :meth:`reward_terms` and :meth:`terminated`.
    """

    def __init__(self, config: TaskConfig, context: TaskContext) -> None:
        self.config = config
        self.context = context
        self.wanderers = WanderingRobots(config.other_walker, context.dimensions)

    @property
    @abstractmethod
    def action_space(self) -> spaces.Box:
        """The action space, a ``Box`` in [-1, 1]."""

    @abstractmethod
    def encoders(self) -> tuple[ObservationEncoder, ...]:
        """The observation's encoders, in key order."""

    def reward_requires(self) -> tuple[str, ...]:
        """Representations :meth:`reward_terms` reads (beyond the encoders')."""
        return ()

    @abstractmethod
    def start_pose(self, rng: np.random.Generator) -> FloatArray:
        """Our robot's true start pose (3,) for a new episode (and whatever plan goes with it)."""

    def place_scripted(
        self,
        rng: np.random.Generator,
        others: Sequence[NaoRobot],
        placed: list[NaoRobot],
    ) -> FloatArray:
        """Place the scripted robots ``others`` clear of the ``placed`` ones; returns the ball's
        start position (2,). Default: wanderers anywhere, the ball within ±2 m x ±1.5 m."""
        self.wanderers.reset(rng, others, self.context.placement, placed)
        return np.array([rng.uniform(-2.0, 2.0), rng.uniform(-1.5, 1.5)])

    @abstractmethod
    def command(self, action: FloatArray, state: WorldState) -> NaoCommand:
        """Our robot's command for this step from the (checked) ``action``."""

    def scripted_commands(self, state: WorldState) -> list[NaoCommand]:
        """The scripted robots' commands for this step, in ``state.others`` order."""
        others = state.others
        walks = self.wanderers.commands(
            state.poses[others], self.context.control_dt_s, state.blocked[others]
        )
        return [NaoCommand(walk=walk) for walk in walks]

    @abstractmethod
    def reward_terms(self, state: WorldState, output: PerceptionOutput) -> dict[str, float]:
        """Each reward term of this step; the reward is their sum."""

    def perceived(self, output: PerceptionOutput) -> None:  # noqa: B027  (most tasks need none)
        """What perception believed after the last step, before the next :meth:`command`: for
        a task whose scripted parts of our robot (a head) act on beliefs. Default: ignored."""

    def terminated(self, state: WorldState, output: PerceptionOutput) -> bool:
        """Whether the episode ended in a terminal state (default: never)."""
        return False
