"""Tasks whose action is the head: look so that localisation stays accurate and certain.

The action is ``Box(-1, 1, (2,))``, the head target (:func:`spl_env.robots.nao.head_target`);
the observation is what perception believes about our pose and the pole map plus the robot's
own head angles, sonar and the episode clock; the reward pays for a small true position error
and a small believed position std. Subclasses decide how the body moves.
"""

from __future__ import annotations

import math
from abc import abstractmethod
from dataclasses import dataclass

import numpy as np
from gymnasium import spaces

from perception.geometry import FloatArray
from perception.representations import SELF_POSE, PerceptionOutput
from perception.types import SlamEstimate
from perception.validation import check_positive
from spl_env.observations.base import ObservationEncoder
from spl_env.observations.body import EpisodeClockEncoder, HeadEncoder, SonarEncoder
from spl_env.observations.poles import PoleMapEncoder
from spl_env.observations.self_pose import SelfPoseEncoder
from spl_env.robots.nao import NaoCommand, head_target
from spl_env.tasks.base import Task, TaskConfig, TaskContext
from spl_env.world_state import WorldState


@dataclass(frozen=True, kw_only=True)
class HeadControlTaskConfig(TaskConfig):
    """The reward weights of a head-control task."""

    error_weight: float = 1.0  # reward per metre of true position error, per step
    uncertainty_weight: float = 0.5  # reward per metre of position std, per step
    information_weight: float = 0.0  # reward per metre the position std fell this step (0: off)

    def __post_init__(self) -> None:
        super().__post_init__()
        for name in ("error_weight", "uncertainty_weight", "information_weight"):
            check_positive(type(self).__name__, name, getattr(self, name), allow_zero=True)


class HeadControlTask(Task):
    """The policy moves the head; :meth:`walk` (a subclass's) moves the body."""

    config: HeadControlTaskConfig

    def __init__(self, config: HeadControlTaskConfig, context: TaskContext) -> None:
        super().__init__(config, context)
        self._previous_std: float | None = None

    @property
    def action_space(self) -> spaces.Box:
        return spaces.Box(-1.0, 1.0, shape=(2,), dtype=np.float32)

    def encoders(self) -> tuple[ObservationEncoder, ...]:
        ctx = self.context
        poles = (PoleMapEncoder(ctx.n_landmarks),) if ctx.n_landmarks else ()
        return (
            SelfPoseEncoder(ctx.dimensions),
            HeadEncoder(ctx.robot),
            *poles,
            SonarEncoder(),
            EpisodeClockEncoder(self.config.episode_s),
        )

    def reward_requires(self) -> tuple[str, ...]:
        return (SELF_POSE,)

    @abstractmethod
    def walk(self, state: WorldState) -> FloatArray:
        """Our body's walk command (3,) (vx, vy m/s, omega rad/s) this step."""

    def command(self, action: FloatArray, state: WorldState) -> NaoCommand:
        return NaoCommand(walk=self.walk(state), head=head_target(self.context.robot, action))

    def reward_terms(self, state: WorldState, output: PerceptionOutput) -> dict[str, float]:
        """``position_error``: -error_weight x the true position error (m); ``uncertainty``:
        -uncertainty_weight x the believed position std sqrt(trace Σ_xy) (m); ``information``:
        information_weight x how much that std fell since the previous step (0 at time 0):
        pays for this step's sightings at once. Over an episode it sums to the weight times the
        first std less the last; under a discount γ it is the potential-based shaping of
        ``-information_weight x std`` plus ``-information_weight (1 - γ) std`` a step, an
        uncertainty penalty beside ``uncertainty``'s."""
        slam = output.get_as(SELF_POSE, SlamEstimate)
        error = float(np.hypot(*(state.robot_pose[:2] - slam.pose[:2])))
        std = float(math.sqrt(max(np.trace(slam.pose_cov[:2, :2]), 0.0)))
        previous = std if output.time_s <= 0.0 or self._previous_std is None else self._previous_std
        self._previous_std = std
        return {
            "position_error": -self.config.error_weight * error,
            "uncertainty": -self.config.uncertainty_weight * std,
            "information": self.config.information_weight * (previous - std),
        }
