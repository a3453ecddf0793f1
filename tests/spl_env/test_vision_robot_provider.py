"""The ``vision`` robot-sightings provider (seed 004 §6.2 with Algorithm 2's sonar check) on a
rendered frame: a robot without team colours straight ahead is kept only with a sonar return at
its range, and then carries the sonar's range.

``SPL/LookAround-v0`` with no other robots; a grey robot (``team_colours=False``, seed 004's
penalty-test goalie) is added to its world. Our robot stands still facing it, so the camera
state is exact; the sonar is the env's own ray-cast sonar with its noise.
"""

from __future__ import annotations

import functools
from collections.abc import Iterator
from typing import Any

import gymnasium as gym
import numpy as np
import pytest

import spl_env  # noqa: F401  (registers the envs)
from perception.pipeline import PerceptionPipeline, PipelineConfig
from perception.providers.robots import VisionOnlyRobotSightings, VisionRobotSightings
from perception.representations import ROBOT_SIGHTINGS, SONAR_OBSERVATIONS
from perception.tracking.sonar_filter import SonarFilter
from spl_env.robots.nao import NaoRobot

OURS = np.array([-1.0, 0.5, 0.0])
RANGE_M = 1.5  # the grey robot's centre straight ahead
HEAD = np.array([0.0, 0.3])  # yaw, pitch (rad): looking a little down, the feet in view
SONAR_SWEEPS = 5  # the filter's window
FRONT_DEPTH_M = 0.05  # the jersey box's half depth (spl_env.robots.nao)


@pytest.fixture(scope="module")
def scene() -> Iterator[tuple[Any, dict[str, Any]]]:
    env = gym.make(
        "SPL/LookAround-v0", n_other_robots=0, frontend="colour", camera_mode="geometric"
    )
    env.reset(seed=0)
    u = env.unwrapped
    grey = NaoRobot(u.world, "grey", team=1, config=u.config.robot, team_colours=False)
    u.scene.place_ball(np.array([4.4, 2.9]))  # out of the way
    u.robots[0].place(OURS, head=HEAD)
    grey.place(np.array([OURS[0] + RANGE_M, OURS[1], np.pi]))
    image, _ = u.rig.camera_view(u.world)
    rng = np.random.default_rng(3)
    sonar = SonarFilter(u.config.perception.sonar_filter)
    for k in range(SONAR_SWEEPS):
        rays = functools.partial(u.world.ray_test, transparent_body=u.world.body(u.robots[0].name))
        reading = u.rig.sonar.measure(rays, OURS, rng)
        observations = sonar.update(0.1 * k, reading)
    inputs = {
        "image": image,
        "camera_state": u.robots[0].camera_state(),
        SONAR_OBSERVATIONS: observations,
        "sonar_model": u.rig.sonar.model,
    }
    yield u, inputs
    env.close()


def test_sonar_sees_the_grey_robot_in_the_middle_sector(scene: Any) -> None:
    _, inputs = scene
    middle = [o for o in inputs[SONAR_OBSERVATIONS] if o.sector == 1]
    assert middle, "no filtered sonar range ahead"
    # the echo comes from the robot's front surface, a few cm nearer than its centre
    # from the transducers (mount_x_m ahead of our centre) to the grey robot's jersey front
    echo = RANGE_M - FRONT_DEPTH_M - inputs["sonar_model"].mount_x_m
    assert min(abs(o.range_m - echo) for o in middle) < 0.02


def test_vision_only_keeps_the_grey_robot_without_a_team(scene: Any) -> None:
    u, inputs = scene
    provider = VisionOnlyRobotSightings(u.config.perception.vision_robots, u.perception_context)
    (sighting,) = provider.update(inputs, 0.0)
    assert sighting.team is None and not sighting.sonar_confirmed
    assert abs(sighting.range_m - RANGE_M) < 0.1 * RANGE_M
    assert abs(sighting.bearing_rad) < np.radians(2.0)


def test_vision_takes_the_sonar_range_of_a_confirmed_sighting(scene: Any) -> None:
    u, inputs = scene
    cfg = u.config.perception
    provider = VisionRobotSightings(cfg.vision_robots, cfg.sonar_filter, u.perception_context)
    (sighting,) = provider.update(inputs, 0.0)
    assert sighting.sonar_confirmed and sighting.team is None
    # The echo comes from the jersey's front, FRONT_DEPTH_M before the centre of a robot facing
    # us; the provider adds its target depth (a mean over how robots stand) to the echo.
    expected = RANGE_M - FRONT_DEPTH_M + cfg.sonar_filter.target_depth_m
    assert abs(sighting.range_m - expected) < 0.02  # the sonar's 1 cm noise, window-averaged
    sonar_std = u.rig.sonar.model.range_noise_std_m
    assert np.sqrt(sighting.cov[0, 0]) == pytest.approx(sonar_std, rel=0.05)


def test_vision_drops_an_unconfirmed_sighting_without_a_team(scene: Any) -> None:
    u, inputs = scene
    cfg = u.config.perception
    provider = VisionRobotSightings(cfg.vision_robots, cfg.sonar_filter, u.perception_context)
    assert provider.update({**inputs, SONAR_OBSERVATIONS: ()}, 0.0) == ()


def test_pipeline_with_vision_runs_the_sonar_filter(scene: Any) -> None:
    u, _ = scene
    pipeline = PerceptionPipeline(
        PipelineConfig(robot_sightings="vision"), u.perception_context, [ROBOT_SIGHTINGS]
    )
    assert pipeline.representations == (SONAR_OBSERVATIONS, ROBOT_SIGHTINGS)
    assert pipeline.frame_inputs == {"image", "camera_state", "sonar", "sonar_model"}
    assert isinstance(pipeline.provider(ROBOT_SIGHTINGS), VisionRobotSightings)
