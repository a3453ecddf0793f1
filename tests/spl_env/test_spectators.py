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
    dt = 0.1
    before = spectators.positions
    steps = []
    for _ in range(2):  # one of two steps is whole: a lane is many steps long
        spectators.move(dt)
        steps.append(spectators.positions - before)
        before = spectators.positions
    whole = np.where(
        (np.linalg.norm(steps[0], axis=1) > np.linalg.norm(steps[1], axis=1))[:, None], *steps
    )
    speed = np.linalg.norm(whole, axis=1) / dt  # each one's own, within the spread
    assert np.all(speed <= 1.2 * 1.2 + 1e-9) and np.all(speed >= 0.8 * 1.2 - 1e-9)
    # the lane's axis (the way it walks) and half-length: a long side runs along x at
    # |y| = half_w, a short one along y at |x| = half_l
    axis = np.argmax(np.abs(whole), axis=1)
    assert np.all(np.abs(whole[np.arange(len(whole)), 1 - axis]) < 1e-12)
    on_long = axis == 0
    half = np.where(on_long, half_l, half_w)
    rows = np.arange(len(speed))
    along = spectators.positions[rows, axis]
    turns = np.zeros(len(speed), dtype=int)
    for _ in range(300):  # 30 s: every spectator reaches an end of its side and turns
        spectators.move(dt)
        xy = spectators.positions
        across = xy[rows, 1 - axis]  # the lane stays put, between carpet and boards
        np.testing.assert_allclose(np.abs(across), np.where(on_long, half_w, half_l))
        now = xy[rows, axis]
        moved = now - along
        at_end = np.isclose(np.abs(along), half)
        # from an end: back inward by a whole step; elsewhere: a whole step, or a part of one
        # that ends at the end
        inward = at_end & (np.sign(moved) == -np.sign(along))
        np.testing.assert_array_equal(inward, at_end)
        whole = np.isclose(np.abs(moved), speed * dt)
        clipped = np.isclose(np.abs(now), half) & (np.abs(moved) < speed * dt)
        assert np.all(whole | clipped), (moved, speed * dt)
        assert np.all(np.abs(now) <= half + 1e-9)
        turns += at_end
        along = now
    assert np.all(turns >= 1)
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
