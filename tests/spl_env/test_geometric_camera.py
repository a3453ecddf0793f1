"""The geometric camera mode against the renderer and the colour filter on the same views."""

from __future__ import annotations

import math
from collections.abc import Iterator

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

from perception.vision import ColourFilterConfig, ColourPoleDetector
from spl_env.sensors.camera import EpisodeLighting
from spl_env.sensors.geometric_camera import GeometricCameraConfig
from spl_env.simulation import SimConfig, SplSimulation


@pytest.fixture(scope="module")
def sim() -> Iterator[SplSimulation]:
    s = SplSimulation(SimConfig(n_other_robots=1))
    s.reset(np.random.default_rng(0), np.zeros(3))
    yield s
    s.close()


def _look(sim: SplSimulation, pose: tuple[float, float, float], head_yaw: float = 0.0) -> None:
    sim.robot.place(np.array(pose), head=np.array([head_yaw, 0.0]))


def _detector(sim: SplSimulation) -> ColourPoleDetector:
    scene = sim.config.scene
    return ColourPoleDetector(
        ColourFilterConfig(), sim.config.camera.model, sim.pole_codes, scene.poles.geometry
    )


def test_band_centres_agree_with_rendered_detection(sim: SplSimulation) -> None:
    sim.others[0].place(np.array([4.0, -2.5, 0.0]))  # out of the way
    detector = _detector(sim)
    pole = sim.landmarks[1]  # id 1 at (0, 3.35)
    for distance in (1.5, 2.5, 3.5):
        _look(sim, (pole[0], pole[1] - distance, math.pi / 2))
        position, rotation = sim.robot.camera_pose_world()
        seen = {
            b.landmark_id: b for b in sim.geometric_camera.visible(sim.world, position, rotation)
        }
        image, _ = sim.camera.render(
            sim.world, position, rotation, EpisodeLighting.default(), np.random.default_rng(0)
        )
        found = {o.landmark_id: o for o in detector.detect(image, sim.robot.camera_state())}
        assert 1 in seen and 1 in found
        # the detector's reported pixel is the midpoint of its two band centres
        midpoint = (seen[1].upper + seen[1].lower) / 2
        np.testing.assert_allclose(found[1].pixel, midpoint, atol=1.5)


def test_occluded_and_out_of_view_poles_are_not_seen(sim: SplSimulation) -> None:
    pole = sim.landmarks[1]
    _look(sim, (pole[0], pole[1] - 3.0, math.pi / 2))
    sim.others[0].place(np.array([pole[0], pole[1] - 2.4, 0.0]))  # its head blocks the view
    position, rotation = sim.robot.camera_pose_world()
    assert 1 not in [
        b.landmark_id for b in sim.geometric_camera.visible(sim.world, position, rotation)
    ]
    sim.others[0].place(np.array([4.0, -2.5, 0.0]))
    _look(sim, (0.0, 0.0, 0.0))  # facing the goal: the nearest poles are 48° off the axis
    position, rotation = sim.robot.camera_pose_world()
    assert sim.geometric_camera.visible(sim.world, position, rotation) == []


def test_recall_is_piecewise_by_range() -> None:
    config = GeometricCameraConfig(recall_by_range=((2.0, 1.0), (5.0, 0.5)))
    np.testing.assert_array_equal(
        config.recall(np.array([0.5, 1.99, 2.0, 4.9, 5.0, 9.0])), [1.0, 1.0, 0.5, 0.5, 0.0, 0.0]
    )
    assert config.max_range_m == 5.0
    with pytest.raises(ValueError, match="recall_by_range"):
        GeometricCameraConfig(recall_by_range=((3.0, 1.0), (2.0, 0.5)))
    with pytest.raises(ValueError, match="pixel_std_u_px"):
        GeometricCameraConfig(pixel_std_u_px=-1.0)


def test_geometric_env_passes_checker_and_is_deterministic() -> None:
    env = gym.make(
        "SPL/ActiveVision-v0", camera_mode="geometric", episode_s=3.0, render_mode="rgb_array"
    )
    check_env(env.unwrapped, skip_render_check=False)
    a = np.array([0.3, 0.0], dtype=np.float32)
    env.reset(seed=9)
    first = [env.step(a)[0] for _ in range(10)]
    env.reset(seed=9)
    second = [env.step(a)[0] for _ in range(10)]
    for f, s in zip(first, second, strict=True):
        for key in f:
            np.testing.assert_array_equal(f[key], s[key])
    assert env.render().ndim == 3
    env.close()
    with pytest.raises(ValueError, match="camera_mode"):
        gym.make("SPL/ActiveVision-v0", camera_mode="magic")
