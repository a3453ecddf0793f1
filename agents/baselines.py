"""Scripted head policies for the SPL head-control envs, with SB3's ``predict`` signature.

They read only the observation keys ``SPL/ActiveVision-v0`` and ``SPL/LookAround-v0`` share.

- :class:`HeadScan`: sweeps the head yaw sinusoidally at level pitch (the classic SPL scan);
- :class:`LookAtStalest`: points the head at the reachable mapped pole seen least recently,
  scanning while there is none;
- :class:`FixedHead`: looks straight ahead (a lower bound).

Policies are built from the env's :class:`spl_env.config.EnvConfig` (``from_config``) so that
their actions follow the configured head limits and control rate; head angles become actions
through :func:`spl_env.robots.nao.head_action`, clipped to [-1, 1].
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from typing import Any

import numpy as np

from spl_env.config import EnvConfig
from spl_env.robots.nao import RobotConfig, head_action


class ScriptedPolicy(ABC):
    """Base: the head limits, a clock, and SB3's ``predict``."""

    def __init__(self, robot: RobotConfig, control_dt_s: float) -> None:
        self.robot = robot
        self.control_dt_s = control_dt_s
        self.t_s = 0.0

    @classmethod
    def from_config(cls, config: EnvConfig) -> ScriptedPolicy:
        """The policy for an env built from ``config``."""
        return cls(config.robot, config.control_dt_s)

    def reset(self) -> None:
        """Start of an episode."""
        self.t_s = 0.0

    def look(self, yaw_rad: float, pitch_rad: float) -> np.ndarray:
        """The action (2,) float32 whose head target is ``(yaw_rad, pitch_rad)``.

        Targets beyond the joint limits map beyond [-1, 1] and are clipped there: the head then
        looks as far as its joint goes.
        """
        return np.clip(head_action(self.robot, yaw_rad, pitch_rad), -1.0, 1.0).astype(np.float32)

    @abstractmethod
    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        """Action (2,) float32 for one observation."""

    def predict(
        self,
        obs: dict[str, np.ndarray],
        state: Any = None,
        episode_start: Any = None,
        deterministic: bool = True,
    ) -> tuple[np.ndarray, None]:
        """SB3-style: ``episode_start`` true restarts the policy's clock."""
        if episode_start is not None and np.any(episode_start):
            self.reset()
        action = self.act(obs)
        self.t_s += self.control_dt_s
        return action, None


class HeadScan(ScriptedPolicy):
    """Yaw ``amplitude · sin(2π t / period)`` at level pitch."""

    amplitude_rad = math.radians(90.0)
    period_s = 4.0

    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        yaw = self.amplitude_rad * math.sin(2 * math.pi * self.t_s / self.period_s)
        return self.look(yaw, 0.0)


class LookAtStalest(HeadScan):
    """Look at the reachable mapped pole seen least recently; scan while there is none.

    A pole is reachable when turning the head to its joint limit brings it inside the central
    half of the image (``reach_margin_rad`` beyond the yaw limit).
    """

    reach_margin_rad = math.radians(14.0)

    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        if "landmarks_mask" not in obs:  # a field without poles: there is never one
            return super().act(obs)
        bearings = np.arctan2(obs["landmarks_sin_bearing"], obs["landmarks_cos_bearing"])
        reachable = (obs["landmarks_mask"] > 0.5) & (
            np.abs(bearings) <= self.robot.head_yaw_limit_rad + self.reach_margin_rad
        )
        if not reachable.any():
            return super().act(obs)
        target = int(np.argmax(np.where(reachable, obs["landmarks_since_seen"], -1.0)))
        return self.look(float(bearings[target]), 0.0)


class FixedHead(ScriptedPolicy):
    """Always look straight ahead at level pitch."""

    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        return self.look(0.0, 0.0)


BASELINES: dict[str, type[ScriptedPolicy]] = {
    "scan": HeadScan,
    "look_at_stalest": LookAtStalest,
    "fixed": FixedHead,
}
