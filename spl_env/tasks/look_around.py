"""Stand and look around: the body stands still at a random spot; only the head moves."""

from __future__ import annotations

import numpy as np

from perception.geometry import FloatArray
from spl_env.tasks.head_control import HeadControlTask
from spl_env.world_state import WorldState


class LookAroundTask(HeadControlTask):
    """Our robot stands at a random pose inside the field (1 m from the lines) and never
    walks; the other robots walk about."""

    def start_pose(self, rng: np.random.Generator) -> FloatArray:
        return self.context.placement.random_pose(rng, margin_m=1.0)

    def walk(self, state: WorldState) -> FloatArray:
        return np.zeros(3)
