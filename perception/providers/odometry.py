"""Dead reckoning: the pose from odometry alone, the baseline every localiser must beat."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from perception.geometry import FloatArray, compose
from perception.providers.base import Provider
from perception.representations import ODOMETRY, ODOMETRY_POSE, Prior


class DeadReckoning(Provider):
    """Composes each frame's odometry increment (3,) onto the prior pose (field frame)."""

    provides = ODOMETRY_POSE
    requires = (ODOMETRY,)

    def __init__(self) -> None:
        self._pose = np.zeros(3)

    def reset(self, prior: Prior) -> None:
        self._pose = np.asarray(prior.pose, dtype=np.float64).copy()

    def update(self, inputs: Mapping[str, Any], time_s: float) -> FloatArray:
        self._pose = compose(self._pose, inputs[ODOMETRY].delta)
        return self._pose.copy()
