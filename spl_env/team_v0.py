"""``spl_env.team_v0``: N against N Naos, every one perceiving, as a PettingZoo ``ParallelEnv``.

PettingZoo's convention::

    from spl_env import team_v0
    env = team_v0.parallel_env(camera_mode="geometric", frontend="colour")  # fast, for training
    observations, infos = env.reset(seed=0)

Keyword arguments are :class:`spl_env.envs.team.TeamEnv`'s (config overrides by dotted path,
top-level name or alias, ``config=``, ``render_mode=``); the class docstring documents agents,
actions, observations (team 1's mirrored), rewards and ``info``.
"""

from __future__ import annotations

from typing import Any

from spl_env.envs.team import TeamConfig, TeamEnv, TeamTaskConfig


def parallel_env(**kwargs: Any) -> TeamEnv:
    """A :class:`TeamEnv` built from ``kwargs``."""
    return TeamEnv(**kwargs)


__all__ = ["TeamConfig", "TeamEnv", "TeamTaskConfig", "parallel_env"]
