"""Spectators walking between the carpet and the boards: their lanes, their walk, and their
draws from the episode's generator."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import spl_env  # noqa: F401  (registers the env ids)
from spl_env.scenes.spl_field import SceneConfig, SplFieldScene
from spl_env.sim.world import BulletWorld


def test_spectators_walk_their_lane_and_turn_back_at_its_ends() -> None:
    world = BulletWorld(time_step_s=0.01)
    config = SceneConfig(spectators=6, spectator_speed_mps=1.2)
    scene = SplFieldScene(world, config)
    spectators = scene.spectators
    spectators.reset(np.random.default_rng(0))
    carpet_l, carpet_w = config.dimensions.carpet_size_m
    half_l = carpet_l / 2 + config.board_distance_m / 2
    half_w = carpet_w / 2 + config.board_distance_m / 2
    before = spectators.positions
    spectators.move(0.1)
    step = np.linalg.norm(spectators.positions - before, axis=1)
    assert np.all(step <= 1.2 * 1.2 * 0.1 + 1e-12) and np.all(step >= 0.8 * 1.2 * 0.1 - 1e-12)
    for _ in range(300):  # 30 s: every spectator reaches an end of its side and turns
        spectators.move(0.1)
        xy = spectators.positions
        on_long_side = np.isclose(np.abs(xy[:, 1]), half_w)
        on_short_side = np.isclose(np.abs(xy[:, 0]), half_l)
        assert np.all(on_long_side | on_short_side)  # in the strip, between carpet and boards
        assert np.all(np.abs(xy[:, 0]) <= half_l + 1e-9) and np.all(
            np.abs(xy[:, 1]) <= half_w + 1e-9
        )
    # the bodies follow
    np.testing.assert_allclose(world.position(spectators.names[0])[:2], spectators.positions[0])
    world.close()


def test_no_spectators_by_default() -> None:
    world = BulletWorld(time_step_s=0.01)
    assert SplFieldScene(world, SceneConfig()).spectators.names == ()
    world.close()


def test_spectators_in_an_env_repeat_with_the_seed() -> None:
    env = gym.make(
        "SPL/ActiveVision-v1", camera_mode="geometric", frontend="colour", **{"scene.spectators": 4}
    )
    runs = []
    for _ in range(2):
        env.reset(seed=3)
        for _ in range(5):
            env.step(np.zeros(2, dtype=np.float32))
        runs.append(env.unwrapped.scene.spectators.positions.copy())
    np.testing.assert_array_equal(runs[0], runs[1])
    env.reset(seed=4)
    assert not np.allclose(env.unwrapped.scene.spectators.positions, runs[0])
    env.close()


def test_a_bad_spectator_count_is_refused() -> None:
    with pytest.raises((ValueError, TypeError), match="spectators"):
        SceneConfig(spectators=-1)
