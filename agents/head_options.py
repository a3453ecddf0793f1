"""Where-to-look choices for a learned head policy: pick a target, not a joint angle.

A head policy that outputs joint targets must learn to hold a pole mid-image while the body
walks and turns; one that picks *what* to look at leaves that to a primitive and learns only
the choice. Options, for an env with P poles (``landmarks_*`` keys; P = 0 without poles):

- ``0 .. P-1``: look at pole i where the belief puts it (the scan step while it is unmapped or
  out of the head's reach);
- ``P``: continue the head scan (:class:`agents.baselines.HeadScan`);
- ``P + 1``: look at the nearest tracked robot (the scan step when none is tracked).

:class:`HeadOptions` wraps a head-control env so that its action space is ``Discrete(P + 2)``
(what PPO trains on); :class:`OptionPolicy` turns a model trained on it back into a policy of
the plain env (SB3's ``predict`` on the env's own observations and actions).
"""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from agents.baselines import HeadScan
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

    def option_action(self, option: int, obs: dict[str, np.ndarray]) -> np.ndarray:
        """The head action (2,) float32 of ``option`` for ``obs``; advances the clock."""
        if not 0 <= option < self.n_options:
            raise ValueError(f"option must be in [0, {self.n_options}), got {option}")
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


class HeadOptions(gym.Wrapper, gym.utils.RecordConstructorArgs):
    """A head-control env whose action is an option (``Discrete(P + 2)``; module docstring)."""

    def __init__(self, env: gym.Env) -> None:
        gym.utils.RecordConstructorArgs.__init__(self)
        gym.Wrapper.__init__(self, env)
        if not isinstance(env.observation_space, spaces.Dict):
            raise TypeError(
                f"HeadOptions needs a Dict observation space, got {env.observation_space}"
            )
        self.primitives = HeadPrimitives(
            env.get_wrapper_attr("config"), pole_count(env.observation_space)
        )
        self.action_space = spaces.Discrete(self.primitives.n_options)
        self._obs: dict[str, np.ndarray] | None = None

    def reset(self, **kwargs: Any) -> tuple[Any, dict[str, Any]]:
        obs, info = self.env.reset(**kwargs)
        self.primitives.reset()
        self._obs = obs
        return obs, info

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict[str, Any]]:
        if self._obs is None:
            raise RuntimeError("call reset() before step()")
        option = int(np.asarray(action).reshape(()))
        obs, reward, terminated, truncated, info = self.env.step(
            self.primitives.option_action(option, self._obs)
        )
        self._obs = obs
        return obs, float(reward), terminated, truncated, info


class OptionPolicy:
    """A model trained on :class:`HeadOptions` as a policy of the plain env."""

    def __init__(self, model: Any, config: EnvConfig, n_poles: int) -> None:
        self.model = model
        self.primitives = HeadPrimitives(config, n_poles)

    def predict(
        self,
        obs: dict[str, np.ndarray],
        state: Any = None,
        episode_start: Any = None,
        deterministic: bool = True,
    ) -> tuple[np.ndarray, None]:
        """SB3-style: the head action (2,) of the option the model picks for ``obs``."""
        batched = {k: np.shape(v) for k, v in obs.items() if np.ndim(v) > 1}
        if batched:
            raise ValueError(
                f"obs must be one observation of the plain env (1-D entries), got shapes {batched}"
            )
        if episode_start is not None and np.any(episode_start):
            self.primitives.reset()
        option, _ = self.model.predict(obs, deterministic=deterministic)
        return self.primitives.option_action(int(np.asarray(option).reshape(())), obs), None
