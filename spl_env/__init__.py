"""spl-env: Gymnasium environments of the RoboCup SPL field (and seed 001's circle-mapping rooms),
observed through real perception.

Importing the package registers every env id in :data:`ENV_IDS` with Gymnasium::

    import gymnasium as gym
    import spl_env  # noqa: F401
    env = gym.make("SPL/ActiveVision-v0")
"""

from __future__ import annotations

from gymnasium.envs.registration import register, registry

_ENTRY_POINTS = {
    "SPL/ActiveVision-v0": "spl_env.envs.active_vision:ActiveVisionEnv",
    "SPL/ActiveVision-v1": "spl_env.envs.active_vision_robots:ActiveVisionRobotsEnv",
    "SPL/LookAround-v0": "spl_env.envs.look_around:LookAroundEnv",
    "Circles/Office-v0": "spl_env.envs.circles:OfficeEnv",
    "Circles/Backyard-v0": "spl_env.envs.circles:BackyardEnv",
}
ENV_IDS: tuple[str, ...] = tuple(_ENTRY_POINTS)
SPL_ENV_IDS: tuple[str, ...] = tuple(i for i in ENV_IDS if i.startswith("SPL/"))  # Naos, field
CIRCLES_ENV_IDS: tuple[str, ...] = tuple(i for i in ENV_IDS if i.startswith("Circles/"))

for _env_id, _entry_point in _ENTRY_POINTS.items():
    if _env_id not in registry:
        register(id=_env_id, entry_point=_entry_point, max_episode_steps=None)

__all__ = ["CIRCLES_ENV_IDS", "ENV_IDS", "SPL_ENV_IDS"]
