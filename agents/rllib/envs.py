"""The envs as RLlib builds them: env creators registered with Ray under :data:`STRIKER_ENV` and
:data:`TEAM_ENV`, each observation flattened to one float32 vector.

RLlib's default models (MLPs) take a flat ``Box``; the SPL envs observe a ``Dict`` of float32
boxes, so the creators flatten it (``gymnasium.spaces.flatten``: the keys in sorted order, each
box raveled). Each env runner process calls the creator itself, so the creators import
:mod:`spl_env` (which registers the ids) where they run, also on another node of a cluster.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from pettingzoo import ParallelEnv
from ray.rllib.env.wrappers.pettingzoo_env import ParallelPettingZooEnv
from ray.tune.registry import register_env

STRIKER_ENV = "spl_striker"
TEAM_ENV = "spl_team"
# the fast training mode: poles and balls projected with the fitted sensor noise, no rendering
FAST_ENV_CONFIG: dict[str, Any] = {"camera_mode": "geometric", "frontend": "colour"}


def make_striker_env(env_config: dict[str, Any]) -> gym.Env:
    """``SPL/Striker-v0`` with its observation flattened to ``Box(float32, (53,))`` (K = 4 robot
    rows).

    ``env_config`` holds env kwargs (``episode_s``, ``camera_mode``, ...) on top of
    :data:`FAST_ENV_CONFIG`; RLlib passes an ``EnvContext`` (a dict).
    """
    import spl_env  # noqa: F401  (registers the env ids in this process)

    env = gym.make("SPL/Striker-v0", **{**FAST_ENV_CONFIG, **env_config})
    return gym.wrappers.FlattenObservation(env)


class FlattenObservations(ParallelEnv[str, np.ndarray, np.ndarray]):
    """A PettingZoo ``ParallelEnv`` whose per-agent ``Dict`` observations are flattened to one
    float32 vector each (as ``gymnasium.wrappers.FlattenObservation`` for one agent)."""

    def __init__(self, env: ParallelEnv[str, Any, np.ndarray]) -> None:
        self.env = env
        self.metadata = env.metadata
        self.possible_agents = list(env.possible_agents)
        self.agents: list[str] = []  # until reset, as PettingZoo's envs
        self.render_mode = getattr(env, "render_mode", None)
        self._inner_spaces = {a: env.observation_space(a) for a in self.possible_agents}
        self.observation_spaces = {a: self._flat_box(a) for a in self.possible_agents}
        self.action_spaces = {a: env.action_space(a) for a in self.possible_agents}

    def _flat_box(self, agent: str) -> gym.spaces.Box:
        """``agent``'s observation space flattened (a ``Dict`` of boxes flattens to a ``Box``)."""
        box = gym.spaces.flatten_space(self._inner_spaces[agent])
        if not isinstance(box, gym.spaces.Box):
            raise TypeError(f"{agent}'s observation space does not flatten to a Box: {box}")
        return box

    def observation_space(self, agent: str) -> gym.spaces.Space[np.ndarray]:
        """The flattened ``Box`` of ``agent``'s observation."""
        return self.observation_spaces[agent]

    def action_space(self, agent: str) -> gym.spaces.Space[np.ndarray]:
        """``agent``'s action space, unchanged."""
        return self.action_spaces[agent]

    def _flatten(self, observations: dict[str, Any]) -> dict[str, np.ndarray]:
        """Each agent's observation as one float32 vector."""
        return {
            a: np.asarray(gym.spaces.flatten(self._inner_spaces[a], obs), dtype=np.float32)
            for a, obs in observations.items()
        }

    def reset(
        self, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, np.ndarray], dict[str, dict[str, Any]]]:
        """The inner env's reset, observations flattened."""
        observations, infos = self.env.reset(seed=seed, options=options)
        self.agents = list(self.env.agents)
        return self._flatten(observations), infos

    def step(
        self, actions: dict[str, np.ndarray]
    ) -> tuple[
        dict[str, np.ndarray],
        dict[str, float],
        dict[str, bool],
        dict[str, bool],
        dict[str, dict[str, Any]],
    ]:
        """The inner env's step, observations flattened."""
        observations, rewards, terminations, truncations, infos = self.env.step(actions)
        self.agents = list(self.env.agents)
        return self._flatten(observations), rewards, terminations, truncations, infos

    def render(self) -> Any:
        """The inner env's render."""
        return self.env.render()

    def close(self) -> None:
        """Close the inner env."""
        self.env.close()


def make_team_env(env_config: dict[str, Any]) -> ParallelPettingZooEnv:
    """The team env (``spl_env.team_v0.parallel_env``) as an RLlib ``MultiAgentEnv``: per-agent
    observations flattened (:class:`FlattenObservations`), agent ids as the env names them
    (``"blue_0"``, ``"red_0"``, ...). ``env_config`` as :func:`make_striker_env`'s."""
    from spl_env import team_v0

    env = team_v0.parallel_env(**{**FAST_ENV_CONFIG, **env_config})
    return ParallelPettingZooEnv(FlattenObservations(env))


def register_envs() -> None:
    """Register :func:`make_striker_env` and :func:`make_team_env` with Ray under
    :data:`STRIKER_ENV` and :data:`TEAM_ENV` (the names ``PPOConfig().environment`` takes)."""
    register_env(STRIKER_ENV, make_striker_env)
    register_env(TEAM_ENV, make_team_env)
