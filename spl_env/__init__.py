"""spl-env: Gymnasium environments of the RoboCup SPL field (and seed 001's circle-mapping rooms),
observed through real perception.

Importing the package registers every env id in :data:`ENV_IDS` with Gymnasium::

    import gymnasium as gym
    import spl_env  # noqa: F401
    env = gym.make("SPL/ActiveVision-v0")
"""

from __future__ import annotations

from gymnasium.envs.registration import register, registry

# the SPL ids that also come without poles, localising from the field's own features
_NO_POLES = {
    "SPL/ActiveVision-NoPoles-v1": "SPL/ActiveVision-v1",
    "SPL/LookAround-NoPoles-v0": "SPL/LookAround-v0",
    "SPL/Striker-NoPoles-v0": "SPL/Striker-v0",
    "SPL/Goalie-NoPoles-v0": "SPL/Goalie-v0",
    "SPL/PenaltyShootout-NoPoles-v0": "SPL/PenaltyShootout-v0",
}
# without poles the robot localises from field features, with the textured posters around
# the field: natural landmarks on the horizon (seed 004 ch. 3-5) need upright structure
NO_POLES_KWARGS = {
    "scene.poles_enabled": False,
    "scene.poster_set": "textured",
    "self_pose": "field_features",
}
_ENTRY_POINTS = {
    "SPL/ActiveVision-v0": "spl_env.envs.active_vision:ActiveVisionEnv",
    "SPL/ActiveVision-v1": "spl_env.envs.active_vision_robots:ActiveVisionRobotsEnv",
    "SPL/LookAround-v0": "spl_env.envs.look_around:LookAroundEnv",
    "SPL/Striker-v0": "spl_env.envs.soccer:StrikerEnv",
    "SPL/Goalie-v0": "spl_env.envs.soccer:GoalieEnv",
    "SPL/PenaltyShootout-v0": "spl_env.envs.soccer:PenaltyShootoutEnv",
    "Circles/Office-v0": "spl_env.envs.circles:OfficeEnv",
    "Circles/Backyard-v0": "spl_env.envs.circles:BackyardEnv",
}
ENV_IDS: tuple[str, ...] = (*_ENTRY_POINTS, *_NO_POLES)
SPL_ENV_IDS: tuple[str, ...] = tuple(i for i in ENV_IDS if i.startswith("SPL/"))  # Naos, field
CIRCLES_ENV_IDS: tuple[str, ...] = tuple(i for i in ENV_IDS if i.startswith("Circles/"))


def pole_env_id(env_id: str) -> str:
    """The id of the env with poles that ``env_id`` is (a ``-NoPoles`` id's pole env, which
    the no-poles settings :data:`NO_POLES_KWARGS` were added to), else ``env_id`` itself."""
    return _NO_POLES.get(env_id, env_id)


_SOCCER = ("SPL/Striker-v0", "SPL/Goalie-v0", "SPL/PenaltyShootout-v0")
SOCCER_ENV_IDS: tuple[str, ...] = tuple(i for i in SPL_ENV_IDS if pole_env_id(i) in _SOCCER)
# the SPL ids whose action is the head (active vision), the body walking a scripted path
HEAD_CONTROL_ENV_IDS: tuple[str, ...] = tuple(i for i in SPL_ENV_IDS if i not in SOCCER_ENV_IDS)

for _env_id, _entry_point in _ENTRY_POINTS.items():
    if _env_id not in registry:
        register(id=_env_id, entry_point=_entry_point, max_episode_steps=None)
for _env_id, _with_poles in _NO_POLES.items():
    if _env_id not in registry:
        register(
            id=_env_id,
            entry_point=_ENTRY_POINTS[_with_poles],
            max_episode_steps=None,
            kwargs=NO_POLES_KWARGS,
        )

__all__ = [
    "CIRCLES_ENV_IDS",
    "ENV_IDS",
    "HEAD_CONTROL_ENV_IDS",
    "NO_POLES_KWARGS",
    "SOCCER_ENV_IDS",
    "SPL_ENV_IDS",
    "pole_env_id",
]
