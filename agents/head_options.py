"""Where-to-look choices for a learned head policy: pick a target, not a joint angle.

A head policy that outputs joint targets must learn to hold a pole mid-image while the body
walks and turns; one that picks *what* to look at leaves that to a primitive and learns only
the choice. Options, for an env with P poles (``landmarks_*`` keys; P = 0 without poles):

- ``0 .. P-1``: look at pole i where the belief puts it (the scan step while it is unmapped or
  out of the head's reach);
- ``P``: continue the head scan (:class:`agents.baselines.HeadScan`);
- ``P + 1``: look at the nearest tracked robot (the scan step when none is tracked).

:class:`HeadOptions` wraps a head-control env so that its action space is ``Discrete(P + 2)``
(what PPO trains on); :class:`agents.options.OptionPolicy` with :class:`HeadPrimitives` turns a
model trained on it back into a policy of the plain env.
"""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from agents.baselines import HeadScan
from agents.options import OptionsWrapper, check_option, dict_observation_space
from spl_env.config import EnvConfig


class HeadPrimitives(HeadScan):
    """The head action (2,) of each option for one observation; the scan keeps its clock."""

    def __init__(self, config: EnvConfig, n_poles: int) -> None:
        super().__init__(config.robot, config.control_dt_s)
        self.n_poles = n_poles
        # a pole counts as reachable when the head at its limit holds it inside the image's
        # central half (half the half field of view beyond the limit)
        half_fov_rad = math.radians(config.sensors.camera.model.hfov_deg) / 2
        self.reach_rad = config.robot.head_yaw_limit_rad + half_fov_rad / 2

    @property
    def n_options(self) -> int:
        return self.n_poles + 2

    def observation_space(self, space: spaces.Dict) -> spaces.Dict:
        """The plain observation space: the head options need nothing derived."""
        return space

    def observe(self, obs: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        """The plain observation."""
        return obs

    def needs_choice(self, obs: dict[str, np.ndarray]) -> bool:
        """Always: every option looks somewhere else."""
        return True

    def option_action(self, option: int, obs: dict[str, np.ndarray]) -> np.ndarray:
        """The head action (2,) float32 of ``option`` for ``obs``; advances the clock."""
        check_option(option, self.n_options)
        bearing = self.target_bearing(option, obs)
        action = self.act(obs) if bearing is None else self.look(bearing, 0.0)
        self.t_s += self.control_dt_s
        return action

    def target_bearing(self, option: int, obs: dict[str, np.ndarray]) -> float | None:
        """The bearing (rad, robot frame) ``option`` looks at, None for the scan step."""
        if option < self.n_poles:
            if obs["landmarks_mask"][option] < 0.5:
                return None
            bearing = math.atan2(
                obs["landmarks_sin_bearing"][option], obs["landmarks_cos_bearing"][option]
            )
            return bearing if abs(bearing) <= self.reach_rad else None
        if option == self.n_poles + 1 and "robots_mask" in obs and obs["robots_mask"][0] > 0.5:
            return math.atan2(obs["robots_sin_bearing"][0], obs["robots_cos_bearing"][0])
        return None


def pole_count(observation_space: spaces.Space) -> int:
    """P: the poles a Dict observation space describes (0 without ``landmarks_mask``)."""
    if not isinstance(observation_space, spaces.Dict):
        raise TypeError(f"observation_space must be a Dict space, got {observation_space}")
    mask = observation_space.spaces.get("landmarks_mask")
    return 0 if mask is None else int(np.prod(mask.shape or ()))


class HeadOptions(OptionsWrapper):
    """A head-control env whose action is an option (``Discrete(P + 2)``; module docstring)."""

    def __init__(self, env: gym.Env) -> None:
        poles = pole_count(dict_observation_space(env, "HeadOptions"))
        super().__init__(env, HeadPrimitives(env.get_wrapper_attr("config"), poles))
