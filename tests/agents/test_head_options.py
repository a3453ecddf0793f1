import math
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import spl_env  # noqa: F401  (registers the env ids)
from agents.baselines import HeadScan
from agents.evaluate import load_policy
from agents.head_options import HeadOptions, HeadPrimitives, pole_count
from agents.options import OptionPolicy
from spl_env.robots.nao import head_target

GEOMETRIC: dict[str, Any] = {"camera_mode": "geometric", "frontend": "colour", "episode_s": 2.0}


@pytest.fixture(scope="module")
def env() -> Iterator[gym.Env]:
    env = gym.make("SPL/ActiveVision-v1", **GEOMETRIC)
    yield env
    env.close()


def _obs(env: gym.Env) -> dict[str, np.ndarray]:
    space = env.observation_space
    assert isinstance(space, gym.spaces.Dict)
    return {k: np.zeros(s.shape or (), dtype=np.float32) for k, s in space.spaces.items()}


def _yaw(env: gym.Env, action: np.ndarray) -> float:
    return float(head_target(env.get_wrapper_attr("config").robot, action)[0])


def test_options_are_the_poles_the_scan_and_the_nearest_robot(env: gym.Env) -> None:
    assert pole_count(env.observation_space) == 6
    assert HeadOptions(env).action_space == gym.spaces.Discrete(8)
    no_poles = gym.make("SPL/ActiveVision-NoPoles-v1", camera_mode="geometric", episode_s=2.0)
    assert HeadOptions(no_poles).action_space == gym.spaces.Discrete(2)
    no_poles.close()


def test_pole_option_looks_at_the_believed_bearing_or_scans(env: gym.Env) -> None:
    config = env.get_wrapper_attr("config")
    primitives, scan = HeadPrimitives(config, 6), HeadScan.from_config(config)
    obs = _obs(env)
    obs["landmarks_mask"][2] = 1.0
    obs["landmarks_cos_bearing"][2], obs["landmarks_sin_bearing"][2] = (
        math.cos(0.7),
        math.sin(0.7),
    )
    assert _yaw(env, primitives.option_action(2, obs)) == pytest.approx(0.7, abs=1e-5)
    # pole 3 is unmapped: the scan step, on the scan's clock (one step has passed)
    scan.t_s = config.control_dt_s
    np.testing.assert_allclose(primitives.option_action(3, obs), scan.act(obs))
    # a pole behind the robot is out of the head's reach: the scan step too
    obs["landmarks_cos_bearing"][2], obs["landmarks_sin_bearing"][2] = -1.0, 0.0
    scan.t_s = 2 * config.control_dt_s
    np.testing.assert_allclose(primitives.option_action(2, obs), scan.act(obs))


def test_robot_option_looks_at_the_nearest_tracked_robot(env: gym.Env) -> None:
    primitives = HeadPrimitives(env.get_wrapper_attr("config"), 6)
    obs = _obs(env)
    obs["robots_mask"][0] = 1.0
    obs["robots_cos_bearing"][0], obs["robots_sin_bearing"][0] = math.cos(-0.4), math.sin(-0.4)
    assert _yaw(env, primitives.option_action(7, obs)) == pytest.approx(-0.4, abs=1e-5)
    with pytest.raises(ValueError, match=r"option \(the action\) must be in"):
        primitives.option_action(8, obs)


@pytest.mark.filterwarnings("ignore:.*different from the unwrapped")
def test_wrapped_env_steps_with_the_primitive_action(env: gym.Env) -> None:
    wrapped = HeadOptions(gym.make("SPL/ActiveVision-v1", **GEOMETRIC))
    check_env(wrapped, skip_render_check=True)
    plain = gym.make("SPL/ActiveVision-v1", **GEOMETRIC)
    obs_w, _ = wrapped.reset(seed=3)
    obs_p, _ = plain.reset(seed=3)
    primitives = HeadPrimitives(env.get_wrapper_attr("config"), 6)
    for option in (6, 6, 0, 1, 7, 6):
        obs_w, reward_w, *_ = wrapped.step(option)
        obs_p, reward_p, *_ = plain.step(primitives.option_action(option, obs_p))
        assert reward_w == reward_p
        for key in obs_p:
            np.testing.assert_array_equal(obs_w[key], obs_p[key])
    wrapped.close()
    plain.close()


class _FixedModel:
    def __init__(self, option: int) -> None:
        self.option = option

    def predict(self, obs: Any, deterministic: bool = True) -> tuple[np.ndarray, None]:
        return np.array(self.option), None


def test_option_policy_acts_through_the_primitives(env: gym.Env) -> None:
    config = env.get_wrapper_attr("config")
    policy = OptionPolicy(_FixedModel(6), HeadPrimitives(config, 6))
    scan = HeadScan.from_config(config)
    obs = _obs(env)
    for step in range(3):
        action, _ = policy.predict(obs, episode_start=np.array([step == 0]))
        np.testing.assert_allclose(action, scan.predict(obs, episode_start=[step == 0])[0])


def test_load_policy_wraps_a_model_trained_on_options(tmp_path: Path, env: gym.Env) -> None:
    from stable_baselines3 import PPO

    wrapped = HeadOptions(gym.make("SPL/ActiveVision-v1", **GEOMETRIC))
    PPO("MultiInputPolicy", wrapped, n_steps=16, batch_size=16, device="cpu").save(
        tmp_path / "model.zip"
    )
    wrapped.close()
    # no config.json beside it (as RL Zoo saves it): the Discrete action space says options
    policy = load_policy(str(tmp_path / "model.zip"), env.get_wrapper_attr("config"))
    assert isinstance(policy, OptionPolicy)
    obs, _ = env.reset(seed=0)
    action, _ = policy.predict(obs, episode_start=np.array([True]))
    assert env.action_space.contains(action)
    batch = {k: np.stack([v, v]) for k, v in obs.items()}
    with pytest.raises(ValueError, match="one observation"):
        policy.predict(batch)
