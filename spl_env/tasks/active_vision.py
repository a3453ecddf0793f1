"""Active vision while walking: the body walks a scripted patrol or seed 000's square walk."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from perception.geometry import FloatArray
from spl_env.behaviours import WalkerConfig, WaypointWalker
from spl_env.tasks.base import TaskContext
from spl_env.tasks.head_control import HeadControlTask, HeadControlTaskConfig
from spl_env.world_state import WorldState

BODY_BEHAVIOURS = ("patrol", "square")


@dataclass(frozen=True, kw_only=True)
class ActiveVisionTaskConfig(HeadControlTaskConfig):
    """Our robot's scripted walk."""

    body_behaviour: str = "patrol"  # our walk: "patrol" (random waypoints) or "square"
    walker: WalkerConfig = field(default_factory=WalkerConfig)  # our robot's walking
    square_side_m: float = 1.8  # side of the "square" walk (seed 000's one-minute square)

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.body_behaviour not in BODY_BEHAVIOURS:
            raise ValueError(
                f"ActiveVisionTaskConfig.body_behaviour must be one of {BODY_BEHAVIOURS}, "
                f"got {self.body_behaviour!r}"
            )
        if not (math.isfinite(self.square_side_m) and 0 < self.square_side_m <= 5.0):
            raise ValueError(
                "ActiveVisionTaskConfig.square_side_m must be in (0, 5] m, "
                f"got {self.square_side_m}"
            )


class ActiveVisionTask(HeadControlTask):
    """``body_behaviour="patrol"``: random waypoints from a random start; ``"square"``: seed
    000's square walk (corners turned in place) around a random centre. The walk steers on the
    true pose: it is scenery, not the policy's concern."""

    config: ActiveVisionTaskConfig

    def __init__(self, config: ActiveVisionTaskConfig, context: TaskContext) -> None:
        super().__init__(config, context)
        self._walker: WaypointWalker | None = None

    def start_pose(self, rng: np.random.Generator) -> FloatArray:
        waypoints: FloatArray | None = None
        if self.config.body_behaviour == "square":
            h = self.config.square_side_m / 2
            centre = np.array([rng.uniform(-1.0, 1.0), rng.uniform(-0.5, 0.5)])
            waypoints = centre + np.array([[h, -h], [h, h], [-h, h], [-h, -h]])
            start = np.array([*waypoints[3], 0.0])
        else:
            start = self.random_field_pose(rng)
        self._walker = WaypointWalker(
            self.config.walker, self.context.dimensions, rng, waypoints=waypoints
        )
        return start

    def walk(self, state: WorldState) -> FloatArray:
        if self._walker is None:
            raise RuntimeError("ActiveVisionTask.start_pose() must be called before walk()")
        blocked = bool(state.blocked[state.agent])
        return self._walker.command(state.robot_pose, self.context.control_dt_s, blocked=blocked)
