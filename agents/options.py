"""Options for learned policies: the policy picks one of a few scripted primitives, not raw
actuator targets.

A primitive set (:class:`Primitives`) turns an option index and the plain env's observation
into that env's action, and may add keys it derives from the observation (what the choice
needs in a form a small network reads easily). :class:`OptionsWrapper` gives an env the action space
``Discrete(n_options)`` (what PPO trains on); :class:`OptionPolicy` turns a model trained on it
back into a policy of the plain env (SB3's ``predict`` on the env's own observations and
actions). :mod:`agents.head_options` (where to look) and :mod:`agents.striker_options` (where
to kick, how hard) are the package's primitive sets.
"""

from __future__ import annotations

from typing import Any, Protocol

import gymnasium as gym
import numpy as np
from gymnasium import spaces


class Primitives(Protocol):
    """Scripted primitives an option policy picks from."""

    @property
    def n_options(self) -> int:
        """How many options there are."""
        ...

    def reset(self) -> None:
        """Start of an episode (clocks and other state)."""
        ...

    def observation_space(self, space: spaces.Dict) -> spaces.Dict:
        """What the option policy sees, given the plain env's observation space ``space``."""
        ...

    def observe(self, obs: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        """What the option policy sees of one plain observation ``obs`` (its keys, plus any
        the primitives derive from them)."""
        ...

    def needs_choice(self, obs: dict[str, np.ndarray]) -> bool:
        """Whether the option picked for ``obs`` makes a difference; where it does not, every
        option gives the same action and nobody is asked."""
        ...

    def option_action(self, option: int, obs: dict[str, np.ndarray]) -> np.ndarray:
        """The plain env's action for ``option`` and one observation ``obs``; advances any
        clock by one control step."""
        ...


def check_option(option: int, n_options: int) -> None:
    """Refuse an option index (the wrapper's action) outside ``[0, n_options)``."""
    if not 0 <= option < n_options:
        raise ValueError(f"option (the action) must be in [0, {n_options}), got {option}")


class OptionsWrapper(gym.Wrapper, gym.utils.RecordConstructorArgs):
    """An env whose action is an option of ``primitives`` (``Discrete(n_options)``).

    One step of the wrapper is one step of the env with the chosen option's action, then as
    many more as pass before the primitives need a choice again (each with the action every
    option gives there; their rewards summed), or until the episode ends. ``reset`` likewise
    runs the env to the first choice (its info is then the last of those steps'); should the
    episode end before it, the next ``step`` returns that end (the same info) without stepping
    the env. Rewards before the first choice count in the first step's reward.
    """

    def __init__(self, env: gym.Env, primitives: Primitives) -> None:
        gym.utils.RecordConstructorArgs.__init__(self)
        gym.Wrapper.__init__(self, env)
        self.primitives = primitives
        self.action_space = spaces.Discrete(primitives.n_options)
        self.observation_space = primitives.observation_space(
            dict_observation_space(env, type(self).__name__)
        )
        self._obs: dict[str, np.ndarray] | None = None  # None: no episode running
        self._carried = 0.0  # reward of the steps before the first choice
        self._ended: tuple[bool, bool, dict[str, Any]] | None = None  # an end reset ran into

    def reset(self, **kwargs: Any) -> tuple[Any, dict[str, Any]]:
        obs, info = self.env.reset(**kwargs)
        self.primitives.reset()
        obs, reward, terminated, truncated, info = self._run_to_choice(obs, 0.0, False, False, info)
        self._obs, self._carried = obs, reward
        self._ended = (terminated, truncated, info) if terminated or truncated else None
        return self.primitives.observe(obs), info

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict[str, Any]]:
        if self._obs is None:
            raise RuntimeError("no episode is running: call reset() before step()")
        option = self.option_of(action)
        carried, self._carried = self._carried, 0.0
        if self._ended is not None:
            terminated, truncated, info = self._ended
            observation, self._obs, self._ended = self.primitives.observe(self._obs), None, None
            return observation, carried, terminated, truncated, info
        obs, reward, terminated, truncated, info = self.env.step(
            self.primitives.option_action(option, self._obs)
        )
        obs, total, terminated, truncated, info = self._run_to_choice(
            obs, carried + float(reward), terminated, truncated, info
        )
        self._obs = None if terminated or truncated else obs
        return self.primitives.observe(obs), total, terminated, truncated, info

    def option_of(self, action: Any) -> int:
        """The option index ``action`` (an integer scalar of the action space) names."""
        value = np.asarray(action)
        if value.size != 1 or not np.issubdtype(value.dtype, np.integer):
            raise TypeError(
                f"action must be one integer option index, got {action!r} of dtype {value.dtype}"
            )
        option = int(value.reshape(()))
        check_option(option, self.primitives.n_options)
        return option

    def _run_to_choice(
        self,
        obs: dict[str, np.ndarray],
        reward: float,
        terminated: bool,
        truncated: bool,
        info: dict[str, Any],
    ) -> tuple[dict[str, np.ndarray], float, bool, bool, dict[str, Any]]:
        """From ``obs``, step the env with the choice-free action until a choice is needed or
        the episode ends: the last observation, ``reward`` plus theirs, and the last step's
        end flags and info."""
        while not (terminated or truncated) and not self.primitives.needs_choice(obs):
            obs, step_reward, terminated, truncated, info = self.env.step(
                self.primitives.option_action(0, obs)
            )
            reward += float(step_reward)
        return obs, reward, terminated, truncated, info


def dict_observation_space(env: gym.Env, owner: str) -> spaces.Dict:
    """``env``'s observation space, refused unless it is a ``Dict`` (the primitives read keys)."""
    if not isinstance(env.observation_space, spaces.Dict):
        raise TypeError(f"{owner} needs a Dict observation space, got {env.observation_space}")
    return env.observation_space


class OptionPolicy:
    """A model trained on an :class:`OptionsWrapper` as a policy of the plain env."""

    def __init__(self, model: Any, primitives: Primitives) -> None:
        self.model = model
        self.primitives = primitives

    def predict(
        self,
        obs: dict[str, np.ndarray],
        state: Any = None,
        episode_start: Any = None,
        deterministic: bool = True,
    ) -> tuple[np.ndarray, None]:
        """SB3-style: the plain env's action of the option the model picks for ``obs``."""
        batched = {k: np.shape(v) for k, v in obs.items() if np.ndim(v) > 1}
        if batched:
            raise ValueError(
                f"obs must be one observation of the plain env (1-D entries), got shapes {batched}"
            )
        if episode_start is not None and np.any(episode_start):
            self.primitives.reset()
        option = 0  # any: no choice is needed
        if self.primitives.needs_choice(obs):
            picked, _ = self.model.predict(
                self.primitives.observe(obs), deterministic=deterministic
            )
            option = int(np.asarray(picked).reshape(()))
        return self.primitives.option_action(option, obs), None
