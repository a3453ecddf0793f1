"""Active vision while walking: the body walks a scripted patrol or seed 000's square walk."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from perception.geometry import FloatArray
from perception.validation import check_choice, check_positive
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
    square_clockwise: bool = False  # the square's sense (UMBmark walks both)

    def __post_init__(self) -> None:
        super().__post_init__()
        owner = "ActiveVisionTaskConfig"
        check_choice(owner, "body_behaviour", self.body_behaviour, BODY_BEHAVIOURS)
        check_positive(owner, "square_side_m", self.square_side_m, upper=5.0, upper_inclusive=True)
        if not isinstance(self.square_clockwise, bool):
            raise TypeError(
                f"{owner}.square_clockwise must be a bool, got "
                f"{type(self.square_clockwise).__name__}"
            )


class ActiveVisionTask(HeadControlTask):
    """``body_behaviour="patrol"``: random waypoints from a random start; ``"square"``: seed
    000's square walk (corners turned in place) around a random centre, counter-clockwise from
    its south-west corner facing east (clockwise: facing north). The walk steers on the true
    pose: it is scenery, not the policy's concern."""

    config: ActiveVisionTaskConfig

    def __init__(self, config: ActiveVisionTaskConfig, context: TaskContext) -> None:
        super().__init__(config, context)
        self._walker: WaypointWalker | None = None

    def start_pose(self, rng: np.random.Generator) -> FloatArray:
        waypoints: FloatArray | None = None
        if self.config.body_behaviour == "square":
            h = self.config.square_side_m / 2
            centre = np.array([rng.uniform(-1.0, 1.0), rng.uniform(-0.5, 0.5)])
            corners = np.array([[h, -h], [h, h], [-h, h], [-h, -h]])
            if self.config.square_clockwise:
                corners = corners[[2, 1, 0, 3]]
            waypoints = centre + corners
            first_leg = waypoints[0] - waypoints[3]
            start = np.array([*waypoints[3], np.arctan2(first_leg[1], first_leg[0])])
        else:
            start = self.context.placement.random_pose(rng, margin_m=1.0)
        self._walker = WaypointWalker(
            self.config.walker, self.context.dimensions, rng, waypoints=waypoints
        )
        return start

    def walk(self, state: WorldState) -> FloatArray:
        if self._walker is None:
            raise RuntimeError("ActiveVisionTask.start_pose() must be called before walk()")
        blocked = bool(state.blocked[state.agent])
        return self._walker.command(state.robot_pose, self.context.control_dt_s, blocked=blocked)
