"""The striker's options: where to kick and how hard, on the believed pose and ball."""

from __future__ import annotations

import math
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import spl_env  # noqa: F401  (registers the env ids)
from agents.evaluate import load_policy
from agents.options import OptionPolicy
from agents.soccer_baselines import SEARCH, soccer_action
from agents.striker_options import (
    KICK_GEOMETRY,
    StrikerOptions,
    StrikerOptionsConfig,
    StrikerPrimitives,
)
from spl_env.observations.base import squash
from spl_env.observations.poles import RANGE_SCALE_M
from spl_env.tasks.soccer_skills import SkillConfig, approach_and_kick

GEOMETRIC: dict[str, Any] = {"camera_mode": "geometric", "frontend": "colour", "episode_s": 3.0}


@pytest.fixture(scope="module")
def env() -> Iterator[gym.Env]:
    env = gym.make("SPL/Striker-v0", **GEOMETRIC)
    yield env
    env.close()


def _obs(env: gym.Env, pose: tuple[float, float, float]) -> dict[str, np.ndarray]:
    """A zero observation whose believed pose is ``pose`` (field frame) and no ball seen."""
    space = env.observation_space
    assert isinstance(space, gym.spaces.Dict)
    obs = {k: np.zeros(s.shape or (), dtype=np.float32) for k, s in space.spaces.items()}
    length, width = env.get_wrapper_attr("config").scene.dimensions.carpet_size_m
    x, y, theta = pose
    obs["self_pose_field"][:] = (
        x / (length / 2),
        y / (width / 2),
        math.cos(theta),
        math.sin(theta),
    )
    obs["ball_since_seen"][0] = 1.0
    return obs


def _see(obs: dict[str, np.ndarray], prefix: str, bearing: float, range_m: float) -> None:
    """Put a ball (``prefix="ball"``) or the first robot track at ``bearing``, ``range_m``."""
    if prefix == "ball":
        obs["ball_bearing"][:] = (math.cos(bearing), math.sin(bearing))
        obs["ball_range"][0] = squash(range_m, RANGE_SCALE_M)
        obs["ball_since_seen"][0] = 0.0
    else:
        obs["robots_cos_bearing"][0], obs["robots_sin_bearing"][0] = (
            math.cos(bearing),
            math.sin(bearing),
        )
        obs["robots_range"][0] = squash(range_m, RANGE_SCALE_M)
        obs["robots_mask"][0] = 1.0


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"aims_m": ()}, TypeError, "aims_m must be a non-empty tuple"),
        ({"strengths": [1.0]}, TypeError, "strengths must be a non-empty tuple"),
        ({"aims_m": (0.0, math.nan)}, ValueError, "aims_m must be finite"),
        ({"aims_m": ("left",)}, TypeError, "aims_m"),
        ({"strengths": (0.0, 1.0)}, ValueError, r"strengths must be finite and in \(0, 1\]"),
        ({"strengths": (1.5,)}, ValueError, r"strengths must be finite and in \(0, 1\]"),
    ],
)
def test_config_refuses_bad_values(kwargs: dict[str, Any], error: type, match: str) -> None:
    with pytest.raises(error, match=match):
        StrikerOptionsConfig(**kwargs)


def test_options_are_every_aim_with_every_strength(env: gym.Env) -> None:
    primitives = StrikerPrimitives(env.get_wrapper_attr("config"))
    half_length = env.get_wrapper_attr("config").scene.dimensions.half_length_m
    assert primitives.n_options == 6
    target, strength = primitives.target_and_strength(5)  # third aim, second strength
    np.testing.assert_allclose(target, [half_length, 0.45])
    assert strength == 1.0
    target, strength = primitives.target_and_strength(2)
    np.testing.assert_allclose(target, [half_length, 0.0])
    assert strength == 0.35
    with pytest.raises(ValueError, match=r"option \(the action\) must be in \[0, 6\), got 6"):
        primitives.target_and_strength(6)


def test_every_option_searches_while_the_ball_is_unknown(env: gym.Env) -> None:
    config = env.get_wrapper_attr("config")
    primitives = StrikerPrimitives(config)
    obs = _obs(env, (-1.0, 0.5, 0.3))
    for option in range(primitives.n_options):
        np.testing.assert_array_equal(
            primitives.option_action(option, obs), soccer_action(SEARCH, config.robot)
        )


def test_a_choice_is_needed_only_where_a_kick_is_possible(env: gym.Env) -> None:
    """The ball 0.17 m straight ahead of a robot facing the goal's centre: option 4 (left aim,
    soft) kicks from the ball towards (goal line, 0.45 m) at 0.35; the ball 1 m ahead: every
    option walks as approach_and_kick towards the centre does, without a kick."""
    config = env.get_wrapper_attr("config")
    primitives = StrikerPrimitives(config)
    half_length = config.scene.dimensions.half_length_m
    pose = np.array([2.0, -0.5, math.atan2(0.5, half_length - 2.0)])
    obs = _obs(env, (float(pose[0]), float(pose[1]), float(pose[2])))
    _see(obs, "ball", 0.0, 0.17)
    assert primitives.needs_choice(obs)
    action = primitives.option_action(4, obs)
    ball = pose[:2] + 0.17 * np.array([math.cos(pose[2]), math.sin(pose[2])])
    to_aim = np.array([half_length, 0.45]) - ball
    expected_off = math.atan2(to_aim[1], to_aim[0]) - pose[2]
    assert 0.0 < expected_off < config.robot.kick_max_angle_rad
    assert action[3] == pytest.approx(0.35)
    assert action[4] == pytest.approx(expected_off / config.robot.kick_max_angle_rad, abs=1e-4)
    centre = approach_and_kick(
        pose, ball, np.array([half_length, 0.0]), config.robot, SkillConfig()
    )
    np.testing.assert_allclose(action[:3], centre.walk, atol=1e-4)
    _see(obs, "ball", 0.0, 1.0)
    assert not primitives.needs_choice(obs)
    ball = pose[:2] + 1.0 * np.array([math.cos(pose[2]), math.sin(pose[2])])
    centre = approach_and_kick(
        pose, ball, np.array([half_length, 0.0]), config.robot, SkillConfig()
    )
    for option in range(primitives.n_options):
        action = primitives.option_action(option, obs)
        np.testing.assert_allclose(action, soccer_action(centre, config.robot), atol=1e-4)
        assert action[3] == -1.0


def test_kick_geometry_places_the_ball_and_the_goalie_on_the_field(env: gym.Env) -> None:
    dims = env.get_wrapper_attr("config").scene.dimensions
    primitives = StrikerPrimitives(env.get_wrapper_attr("config"))
    obs = _obs(env, (1.0, -1.0, math.pi / 2))  # facing +y
    np.testing.assert_array_equal(primitives.kick_geometry(obs), np.zeros(5))
    _see(obs, "ball", -math.pi / 2, 1.0)  # to the robot's right: +x on the field
    goalie = np.array([dims.half_length_m - 0.4, 0.3])
    offset = goalie - np.array([1.0, -1.0])
    _see(obs, "robot", math.atan2(offset[1], offset[0]) - math.pi / 2, float(np.hypot(*offset)))
    geometry = primitives.kick_geometry(obs)
    expected = [2.0 / dims.half_length_m, -1.0 / dims.half_width_m, 1.0, -0.4, 0.3]
    np.testing.assert_allclose(geometry, expected, atol=1e-4)
    # a track farther than a metre from the goal's centre is no goalie
    _see(obs, "robot", 0.0, 1.0)
    np.testing.assert_allclose(geometry[:2], primitives.kick_geometry(obs)[:2])
    np.testing.assert_array_equal(primitives.kick_geometry(obs)[2:], np.zeros(3))


@pytest.mark.filterwarnings("ignore:.*different from the unwrapped")
@pytest.mark.filterwarnings("ignore:.*Box observation space m")
def test_a_wrapped_step_runs_from_one_kick_chance_to_the_next() -> None:
    """The wrapper's steps are the plain env's steps with the primitives' actions, the option
    used only where a kick is possible; its rewards are the plain steps' sums."""
    kwargs = {**GEOMETRIC, "episode_s": 20.0}
    wrapped = StrikerOptions(gym.make("SPL/PenaltyShootout-v0", **kwargs))
    check_env(wrapped, skip_render_check=True)
    assert wrapped.action_space == gym.spaces.Discrete(6)
    plain = gym.make("SPL/PenaltyShootout-v0", **kwargs)
    primitives = StrikerPrimitives(plain.get_wrapper_attr("config"))
    obs_w, _ = wrapped.reset(seed=4)
    obs_p, _ = plain.reset(seed=4)
    plain_steps, plain_return, done = 0, 0.0, False
    while not primitives.needs_choice(obs_p):  # the walk up to the ball
        obs_p, reward, terminated, truncated, _ = plain.step(primitives.option_action(0, obs_p))
        plain_steps, plain_return = plain_steps + 1, plain_return + float(reward)
        assert not (terminated or truncated)
    assert plain_steps > 10  # 1.2 m behind the ball: some seconds of walking
    wrapped_return, choices = 0.0, 0
    for option in (5, 3, 1, 0, 2, 4):
        np.testing.assert_array_equal(obs_w[KICK_GEOMETRY], primitives.kick_geometry(obs_p))
        for key in obs_p:
            np.testing.assert_array_equal(obs_w[key], obs_p[key])
        obs_w, reward_w, terminated_w, truncated_w, _ = wrapped.step(option)
        wrapped_return, choices = wrapped_return + reward_w, choices + 1
        obs_p, reward, terminated, truncated, _ = plain.step(
            primitives.option_action(option, obs_p)
        )
        plain_return += float(reward)
        done = terminated or truncated
        while not done and not primitives.needs_choice(obs_p):
            obs_p, reward, terminated, truncated, _ = plain.step(primitives.option_action(0, obs_p))
            plain_return, done = plain_return + float(reward), terminated or truncated
        assert (terminated_w, truncated_w) == (terminated, truncated)
        assert wrapped_return == pytest.approx(plain_return, abs=1e-9)
        if done:
            break
    assert done and choices >= 1
    wrapped.close()
    plain.close()


def test_load_policy_plays_a_striker_model_in_the_plain_env(tmp_path: Path, env: gym.Env) -> None:
    from stable_baselines3 import PPO

    wrapped = StrikerOptions(gym.make("SPL/Striker-v0", **GEOMETRIC))
    PPO("MultiInputPolicy", wrapped, n_steps=16, batch_size=16, device="cpu").save(
        tmp_path / "model.zip"
    )
    wrapped.close()
    policy = load_policy(str(tmp_path / "model.zip"), env.get_wrapper_attr("config"))
    assert isinstance(policy, OptionPolicy)
    assert isinstance(policy.primitives, StrikerPrimitives)
    head_env = gym.make("SPL/ActiveVision-v1", camera_mode="geometric", frontend="colour")
    with pytest.raises(ValueError, match="trained on striker options; it cannot play this head"):
        load_policy(str(tmp_path / "model.zip"), head_env.get_wrapper_attr("config"))
    head_env.close()
    obs, _ = env.reset(seed=0)
    for step in range(5):
        action, _ = policy.predict(obs, episode_start=np.array([step == 0]))
        assert env.action_space.contains(action)
        obs, *_ = env.step(action)
