"""The circle map in the SPL envs: with the laser on, the observation holds the mapped circles
and ``info`` the map and the true circles, in fixed shapes; without it, neither."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import spl_env  # noqa: F401  (registers the envs)
from perception.geometry import range_bearing
from spl_env.observations.circles import RADIUS_SCALE_M
from spl_env.observations.poles import RANGE_SCALE_M
from spl_env.sensors.laser import FINE_LASER

CIRCLE_KEYS = {
    "circles_cos_bearing",
    "circles_sin_bearing",
    "circles_range",
    "circles_radius",
    "circles_std",
    "circles_mask",
}


def make(**kwargs: object) -> gym.Env:
    return gym.make(
        "SPL/ActiveVision-v1",
        camera_mode="geometric",
        frontend="colour",
        robot_frontend="oracle",
        episode_s=3.0,
        **kwargs,
    )


def test_laser_on_adds_circle_keys_and_info_in_fixed_shapes() -> None:
    env = make(laser=FINE_LASER, observed_circles=5)
    obs, info = env.reset(seed=3)
    assert set(obs) >= CIRCLE_KEYS
    assert all(obs[key].shape == (5,) for key in CIRCLE_KEYS)
    rows = env.unwrapped.config.perception.circle_mapper.max_circles
    truth = env.unwrapped.scene.obstacles
    for _ in range(29):  # a circle is confirmed after 10 updates
        obs, _, _, _, info = env.step(np.zeros(2, dtype=np.float32))
        perception = info["perception"]
        assert perception["circles"].shape == (rows, 3)
        assert perception["circle_covs"].shape == (rows, 3, 3)
        assert perception["circles_mapped"].shape == (rows,)
        assert np.array_equal(info["ground_truth"]["circles"], truth)
        assert env.observation_space.contains(obs)
    mapped = perception["circles"][perception["circles_mapped"]]
    assert len(mapped) >= 1
    n = min(len(mapped), 5)
    assert obs["circles_mask"].tolist() == [1.0] * n + [0.0] * (5 - n)
    # the observed rows are the n mapped circles nearest to the believed pose, seen from it
    rb = range_bearing(perception["pose"], mapped[:, :2])
    nearest = np.argsort(rb[:, 0], kind="stable")[:n]
    np.testing.assert_allclose(obs["circles_cos_bearing"][:n], np.cos(rb[nearest, 1]), atol=1e-6)
    np.testing.assert_allclose(obs["circles_sin_bearing"][:n], np.sin(rb[nearest, 1]), atol=1e-6)
    expected_range = rb[nearest, 0] / (rb[nearest, 0] + RANGE_SCALE_M)
    np.testing.assert_allclose(obs["circles_range"][:n], expected_range, atol=1e-6)
    radius = mapped[nearest, 2]
    np.testing.assert_allclose(
        obs["circles_radius"][:n], radius / (radius + RADIUS_SCALE_M), atol=1e-6
    )
    env.close()


def test_laser_off_has_no_circle_map() -> None:
    env = make()
    obs, info = env.reset(seed=3)
    assert not CIRCLE_KEYS & set(obs)
    assert "circles" not in info["perception"]
    env.close()


def test_check_env_with_the_laser_on() -> None:
    env = make(laser=FINE_LASER)
    check_env(env.unwrapped, skip_render_check=True)
    env.close()


def test_observed_circles_must_be_a_positive_int() -> None:
    with pytest.raises(ValueError, match="observed_circles"):
        make(observed_circles=0)
