"""Where to kick and how hard: options for a learned striker.

A striker that outputs walk speeds and kick triggers must first learn to walk behind a rolling
ball; one that picks *where to kick it and how hard* leaves the approach to the scripted skill
(:func:`spl_env.tasks.soccer_skills.approach_and_kick` towards the goal's centre on the
believed pose and ball, as the centre-kicking striker of :mod:`agents.soccer_baselines`) and
learns only the kick. The choice is asked for only when a kick is possible (the ball in the
kick zone, the robot facing the goal): option ``i * S + j`` (``A`` aims, ``S`` strengths,
:class:`StrikerOptionsConfig`) kicks the ball towards the point ``(opponent goal line,
aims_m[i])`` at ``strengths[j]`` of the full kick; soft kicks dribble, full ones shoot. While
the ball is unknown the robot turns on the spot (:data:`agents.soccer_baselines.SEARCH`).

:class:`StrikerOptions` wraps a soccer env (``SPL/Striker-v0``, ``SPL/PenaltyShootout-v0``)
so that its action space is ``Discrete(A S)`` and one of its steps runs from one kick to the
next chance of one (:class:`agents.options.OptionsWrapper`); :class:`agents.options.OptionPolicy`
with :class:`StrikerPrimitives` plays a model trained on it in the plain env.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from agents.options import OptionsWrapper, check_option
from agents.soccer_baselines import (
    SEARCH,
    believed_ball,
    believed_goalie,
    believed_pose,
    soccer_action,
)
from perception.geometry import FloatArray, wrap_angle
from perception.validation import check_finite, check_in_interval
from spl_env.config import EnvConfig
from spl_env.tasks.soccer import SoccerTaskConfig, goal_centre
from spl_env.tasks.soccer_skills import SkillCommand, SkillConfig, approach_and_kick

_OWNER = "StrikerOptionsConfig"
KICK_GEOMETRY = "kick_geometry"  # the observation key the options add


@dataclass(frozen=True, kw_only=True)
class StrikerOptionsConfig:
    """The options' aims and strengths.

    ``aims_m``: points on the opponent goal line, by their y (m; the goal's inner half width is
    0.75 m: ±0.45 m leaves the ball's kick noise room inside a post); ``strengths``: kick
    strengths in (0, 1] of the full kick (2 m/s; 0.35 moved the ball 1.2-3.3 m in three
    tries, the walking robot pushing it on: a dribble).
    """

    aims_m: tuple[float, ...] = (-0.45, 0.0, 0.45)
    strengths: tuple[float, ...] = (0.35, 1.0)

    def __post_init__(self) -> None:
        for name in ("aims_m", "strengths"):
            values = getattr(self, name)
            if not isinstance(values, tuple) or not values:
                raise TypeError(f"{_OWNER}.{name} must be a non-empty tuple, got {values!r}")
        for aim in self.aims_m:
            check_finite(_OWNER, "aims_m", aim)
        for strength in self.strengths:
            check_in_interval(_OWNER, "strengths", strength, 0.0, 1.0, high_inclusive=True)

    @property
    def n_options(self) -> int:
        return len(self.aims_m) * len(self.strengths)


class StrikerPrimitives:
    """The soccer action (5,) of each option for one observation (stateless)."""

    def __init__(
        self,
        config: EnvConfig,
        options: StrikerOptionsConfig | None = None,
        skills: SkillConfig | None = None,
    ) -> None:
        self.options = options if options is not None else StrikerOptionsConfig()
        self.robot = config.robot
        self.dimensions = config.scene.dimensions
        self.skills = skills if skills is not None else SkillConfig()
        self.goal = goal_centre(self.dimensions, 1)
        self.targets = [self.goal + np.array([0.0, aim]) for aim in self.options.aims_m]

    @property
    def n_options(self) -> int:
        return self.options.n_options

    def reset(self) -> None:
        """Nothing to restart: the options read only the observation."""

    def observation_space(self, space: spaces.Dict) -> spaces.Dict:
        """``space`` plus ``kick_geometry`` (:meth:`kick_geometry`)."""
        if KICK_GEOMETRY in space.spaces:
            raise ValueError(f"the observation space already has a {KICK_GEOMETRY!r} key")
        box = spaces.Box(-np.inf, np.inf, shape=(5,), dtype=np.float32)
        return spaces.Dict({**space.spaces, KICK_GEOMETRY: box})

    def observe(self, obs: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        """``obs`` plus ``kick_geometry`` (:meth:`kick_geometry`)."""
        return {**obs, KICK_GEOMETRY: self.kick_geometry(obs)}

    def kick_geometry(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        """(5,) float32, from the believed pose, ball and robot tracks (field frame): the ball
        ``(x / half length, y / half width)`` (0 before it is seen), 1 when a goalie is tracked
        (:func:`agents.soccer_baselines.believed_goalie`) else 0, and the goalie's offset from
        the goal's centre (m; 0 when none is tracked)."""
        dims, centre = self.dimensions, self.goal
        pose = believed_pose(obs, dims.carpet_size_m)
        ball = believed_ball(obs, pose)
        goalie = believed_goalie(obs, pose, centre)
        ball_xy = (
            (0.0, 0.0)
            if ball is None
            else (ball[0] / dims.half_length_m, ball[1] / dims.half_width_m)
        )
        offset = (0.0, 0.0) if goalie is None else tuple(goalie - centre)
        return np.array([*ball_xy, float(goalie is not None), *offset], dtype=np.float32)

    def target_and_strength(self, option: int) -> tuple[np.ndarray, float]:
        """The point (2,) (field frame) ``option`` kicks at, and its strength."""
        check_option(option, self.n_options)
        aim, strength = divmod(option, len(self.options.strengths))
        return self.targets[aim], self.options.strengths[strength]

    def approach(self, obs: dict[str, np.ndarray]) -> tuple[FloatArray, FloatArray, SkillCommand]:
        """The believed pose (3,), ball (2,) and the walk to kick it at the goal's centre (the
        search while the ball is unknown, the pose then standing in for the ball)."""
        pose = believed_pose(obs, self.dimensions.carpet_size_m)
        ball = believed_ball(obs, pose)
        if ball is None:
            return pose, pose[:2], SEARCH
        return pose, ball, approach_and_kick(pose, ball, self.goal, self.robot, self.skills)

    def needs_choice(self, obs: dict[str, np.ndarray]) -> bool:
        """Whether the ball can be kicked now: approach_and_kick towards the goal's centre
        would kick (the ball in the kick zone, the robot within ``kick_heading_tolerance_rad``
        of the heading it wants: the goal's centre, with the default ``face_ball_beyond_m``)."""
        return self.approach(obs)[2].kick

    def option_action(self, option: int, obs: dict[str, np.ndarray]) -> np.ndarray:
        """The soccer action (5,) float32 of ``option`` for ``obs``: the walk towards the kick
        at the goal's centre (every option the same), and where a kick is possible, the
        option's kick (towards its target from the ball, at its strength)."""
        target, strength = self.target_and_strength(option)
        pose, ball, command = self.approach(obs)
        if not command.kick:
            return soccer_action(command, self.robot)
        aim = target - ball
        off = float(wrap_angle(math.atan2(aim[1], aim[0]) - pose[2]))
        return soccer_action(replace(command, kick_angle_rad=off), self.robot, strength)


class StrikerOptions(OptionsWrapper):
    """A soccer env whose action is an option (``Discrete(A S)``; module docstring)."""

    def __init__(self, env: gym.Env) -> None:
        config = env.get_wrapper_attr("config")
        if not isinstance(config.task, SoccerTaskConfig) or env.action_space.shape != (5,):
            raise ValueError(
                "StrikerOptions needs a soccer env with the scripted head (action shape (5,)), "
                f"got a {type(config.task).__name__} env with action space {env.action_space}"
            )
        super().__init__(env, StrikerPrimitives(config))
