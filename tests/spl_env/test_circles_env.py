"""``Circles/Office-v0`` and ``Circles/Backyard-v0``: seed 001's world on the env core. The
action drives the wheels, the body stops at walls while the encoders count on, the sensors and
the observation agree with the geometry, the reward is the map's improvement, and every step
is reproducible."""

from __future__ import annotations

import math
from collections.abc import Iterator
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import spl_env  # noqa: F401  (registers the ids)
from agents.drivers import BraitenbergDriver, WaypointDriver, believed_pose, sonar_ranges
from perception.representations import CIRCLE_MAP
from perception.types import MappedCircle
from spl_env import CIRCLES_ENV_IDS
from spl_env.envs.circles import CirclesEnv, OfficeEnv
from spl_env.envs.core import RobotEnv
from spl_env.robots.diff_drive import DiffDriveConfig
from spl_env.scenes.office import OFFICE
from spl_env.tasks.circle_mapping import CircleMappingTaskConfig, map_quality

PIONEER = DiffDriveConfig()
TRUTH = OFFICE.circles


@pytest.fixture
def office() -> Iterator[OfficeEnv]:
    env = OfficeEnv(episode_s=5.0)
    yield env
    env.close()


@pytest.mark.parametrize("env_id", CIRCLES_ENV_IDS)
def test_check_env_passes(env_id: str) -> None:
    env = gym.make(env_id, episode_s=2.0)
    check_env(env.unwrapped, skip_render_check=True)
    env.close()


def test_the_env_adds_no_step_loop_of_its_own() -> None:
    for name in ("step", "reset", "render", "close"):
        assert getattr(CirclesEnv, name) is getattr(RobotEnv, name), name


@pytest.mark.parametrize(
    ("env_id", "episode_s", "objects"),
    [("Circles/Office-v0", 60.0, 6), ("Circles/Backyard-v0", 180.0, 5)],
)
def test_episode_lengths_and_objects_as_seed_001(
    env_id: str, episode_s: float, objects: int
) -> None:
    env = gym.make(env_id)
    config = env.unwrapped.config  # type: ignore[attr-defined]
    assert config.task.episode_s == episode_s
    assert config.max_steps == round(episode_s / 0.1)
    _, info = env.reset(seed=0)
    assert info["ground_truth"]["circles"].shape == (objects, 3)
    env.close()


@pytest.mark.parametrize("bad", [np.array([np.nan, 0.0]), np.array([1.5, 0.0]), np.zeros(3)])
def test_bad_actions_are_refused(office: OfficeEnv, bad: np.ndarray) -> None:
    office.reset(seed=0)
    with pytest.raises(ValueError, match="action"):
        office.step(bad)


def test_a_noiseless_laser_is_refused_for_circle_slam_naming_the_field() -> None:
    with pytest.raises(ValueError, match=r"sensors.laser.range_noise_std_m must be > 0"):
        OfficeEnv(**{"sensors.laser.range_noise_std_m": 0.0})


def test_straight_drive_moves_by_the_wheel_travel(office: OfficeEnv) -> None:
    office.reset(seed=0)
    start = office.world_state.robot_pose.copy()
    for _ in range(10):
        office.step(np.array([0.5, 0.5]))
    pose = office.world_state.robot_pose
    # 1 s at half the top wheel speed: 0.5 * 1.2 m/s, along the start heading
    expected = start[:2] + 0.6 * np.array([math.cos(start[2]), math.sin(start[2])])
    np.testing.assert_allclose(pose[:2], expected, atol=1e-9)
    assert pose[2] == pytest.approx(start[2], abs=1e-12)


def test_turning_in_place_matches_the_axle_kinematics(office: OfficeEnv) -> None:
    office.reset(seed=0)
    start = office.world_state.robot_pose.copy()
    office.step(np.array([-0.1, 0.1]))
    # dθ = r (ωr - ωl) dt / L
    turn = PIONEER.wheel_radius_m * 0.2 * PIONEER.max_wheel_speed_rad_per_s * 0.1
    turn /= PIONEER.axle_length_m
    assert office.world_state.robot_pose[2] - start[2] == pytest.approx(turn, rel=1e-9)
    np.testing.assert_allclose(office.world_state.robot_pose[:2], start[:2], atol=1e-12)


def test_a_wall_blocks_the_body_while_the_encoders_count_on(office: OfficeEnv) -> None:
    office.reset(seed=0)
    # the start faces +x along the south wall: turn to face it (-y), then drive into it
    while abs(math.remainder(office.world_state.robot_pose[2] + math.pi / 2, 2 * math.pi)) > 0.05:
        office.step(np.array([0.05, -0.05]))
    blocked, odometry = [], []
    for _ in range(30):
        info = office.step(np.array([0.5, 0.5]))[-1]
        blocked.append(bool(info["ground_truth"]["blocked"]))
        delta = office.sensor_frame.odometry_delta
        assert delta is not None
        odometry.append(delta[0])
        if blocked[-1]:
            assert info["reward_terms"]["collision"] == pytest.approx(-0.1)
    assert any(blocked)
    wall_y = -OFFICE.half_size_m[1]
    assert office.world_state.robot_pose[1] - PIONEER.body_radius_m >= wall_y - 1e-9
    # blocked steps still count the wheels' turn: about 0.06 m forward per step
    assert np.all(np.array(odometry)[np.array(blocked)] > 0.05)


def test_the_sonars_and_scan_see_the_wall_ahead(office: OfficeEnv) -> None:
    office.reset(seed=0)
    pose = office.world_state.robot_pose
    frame = office.sensor_frame
    assert frame.sonar_ring is not None and frame.laser is not None
    # sonars 0 and 15 face left (+90°) at x = 0.069 / -0.157 m, y = 0.136 m; the start faces
    # +x, about 0.4 m inside the south wall: the right-facing sonars (7, 8) hear it
    right = frame.sonar_ring[[7, 8]]
    distance_to_wall = pose[1] + OFFICE.half_size_m[1] - 0.136 / math.cos(pose[2])
    np.testing.assert_allclose(right, distance_to_wall, atol=0.06)
    obs = office._observation()
    ranges = sonar_ranges(obs)
    np.testing.assert_allclose(ranges[[7, 8]], right, rtol=1e-5)


def test_the_observation_holds_the_believed_pose(office: OfficeEnv) -> None:
    obs, info = office.reset(seed=3)
    for _ in range(20):
        obs, _, _, _, info = office.step(np.array([0.3, 0.35]))
    pose = believed_pose(obs, OFFICE.half_size_m)
    np.testing.assert_allclose(pose, info["perception"]["pose"], atol=1e-5)
    assert np.hypot(*(pose[:2] - info["ground_truth"]["robot_pose"][:2])) < 0.2


def test_frames_carry_no_truth_unless_an_oracle_asks(office: OfficeEnv) -> None:
    office.reset(seed=0)
    assert office.sensor_frame.truth is None
    oracle = OfficeEnv(episode_s=1.0, self_pose="oracle", circle_map="laser")
    oracle.reset(seed=0)
    assert oracle.sensor_frame.truth is not None
    oracle.close()


def test_map_quality_counts_exact_circles_and_penalises_spurious() -> None:
    config = CircleMappingTaskConfig()

    def mapped(states: np.ndarray) -> tuple[MappedCircle, ...]:
        return tuple(
            MappedCircle(circle_id=k, state=s, cov=np.eye(3), hits=3, confirmed=True)
            for k, s in enumerate(states)
        )

    assert map_quality((), TRUTH, config) == 0.0
    assert map_quality(mapped(TRUTH), TRUTH, config) == pytest.approx(len(TRUTH))
    off = TRUTH.copy()
    off[0, 0] += 0.1  # 0.1 m of 0.25: that circle scores 0.6
    assert map_quality(mapped(off), TRUTH, config) == pytest.approx(len(TRUTH) - 0.4)
    ghost = np.vstack([TRUTH, [[0.0, 0.0, 0.3]]])
    assert map_quality(mapped(ghost), TRUTH, config) == pytest.approx(len(TRUTH) - 0.5)


def test_the_return_is_the_final_map_quality_minus_collisions() -> None:
    env = OfficeEnv(episode_s=20.0)
    driver = WaypointDriver.from_config(env.config)
    obs, info = env.reset(seed=1)
    total = sum(info["reward_terms"].values())
    collisions = 0.0
    done = False
    while not done:
        obs, reward, terminated, truncated, info = env.step(driver.predict(obs)[0])
        assert reward == pytest.approx(sum(info["reward_terms"].values()))
        total += reward
        collisions += info["reward_terms"]["collision"]
        done = terminated or truncated
    final = map_quality(env.perception_output[CIRCLE_MAP], TRUTH, env.config.task)
    assert total == pytest.approx(final + collisions)
    assert final > 0.0  # the route maps some of the columns within 20 s
    env.close()


def test_same_seed_same_observations_and_info() -> None:
    def rollout() -> list[Any]:
        env = OfficeEnv(episode_s=3.0)
        obs, info = env.reset(seed=7)
        out = [obs, info]
        for k in range(30):
            obs, _, _, _, info = env.step(np.array([0.4, 0.3 + 0.01 * k]))
            out += [obs, info]
        env.close()
        return out

    def flat(x: Any) -> list[np.ndarray]:
        if isinstance(x, dict):
            return [v for key in sorted(x) for v in flat(x[key])]
        return [np.asarray(x)]

    for a, b in zip(rollout(), rollout(), strict=True):
        for u, v in zip(flat(a), flat(b), strict=True):
            np.testing.assert_array_equal(u, v)


def test_the_laser_circle_map_runs_on_the_circle_slam_pose() -> None:
    # the filter starts certain of its pose (a singular covariance): the laser mapper takes it
    env = OfficeEnv(episode_s=2.0, circle_map="laser")
    env.reset(seed=0)
    for _ in range(15):
        _, _, _, _, info = env.step(np.array([0.3, 0.3], dtype=np.float32))
    mapped = info["perception"]["circles"][info["perception"]["circles_mapped"]]
    truth = info["ground_truth"]["circles"]
    assert len(mapped) >= 1
    nearest = np.min(np.hypot(*(mapped[:, None, :2] - truth[None, :, :2]).transpose(2, 0, 1)), 1)
    assert (nearest < 0.1).all()
    env.close()


def test_braitenberg_keeps_the_robot_off_the_walls() -> None:
    env = OfficeEnv(episode_s=30.0)
    driver = BraitenbergDriver()
    obs, _ = env.reset(seed=0)
    blocked = 0
    done = False
    while not done:
        obs, _, terminated, truncated, info = env.step(driver.predict(obs)[0])
        blocked += int(info["ground_truth"]["blocked"])
        done = terminated or truncated
    assert blocked <= 5  # of 300 steps
    env.close()


def test_render_draws_the_room() -> None:
    env = OfficeEnv(episode_s=1.0, render_mode="rgb_array")
    env.reset(seed=0)
    image = env.render()
    assert image is not None and image.ndim == 3 and image.dtype == np.uint8
    hx, hy = OFFICE.half_size_m
    assert image.shape[0] < image.shape[1]  # the room is longer in x than in y
    assert image.shape[1] / image.shape[0] == pytest.approx((hx + 0.2) / (hy + 0.2), rel=0.02)
    env.close()
