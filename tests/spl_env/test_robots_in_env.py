"""SPL/ActiveVision-v1: the robot-track encoder, the awareness reward, the geometric mode's robot
sightings and tracking in the env, against known geometry."""

from __future__ import annotations

import dataclasses
import math

import gymnasium as gym
import numpy as np
import pytest

import spl_env  # noqa: F401
from perception.representations import ROBOT_SIGHTINGS, ROBOT_TRACKS, SELF_POSE, PerceptionOutput
from perception.types import CameraModel, RobotTrack, SensorFrame, SlamEstimate
from spl_env.observations.base import EncoderInput
from spl_env.observations.robots import RobotTracksEncoder
from spl_env.sensors.emulation.robots import (
    VISION_ROBOTS,
    GeometricRobotConfig,
    GeometricRobotSightings,
)
from spl_env.tasks.robot_awareness import tracked_share
from spl_env.world_state import WorldState

FAST = {"episode_s": 2.0, "camera_mode": "geometric", "frontend": "colour"}


def track(track_id: int, xy: tuple[float, float], *, confirmed: bool = True, **kw) -> RobotTrack:
    state = np.array([*xy, *kw.get("velocity", (0.0, 0.0))])
    return RobotTrack(
        track_id=track_id,
        state=state,
        cov=np.diag([kw.get("var", 0.01)] * 2 + [0.1, 0.1]),
        team=kw.get("team"),
        confirmed=confirmed,
        last_seen_s=kw.get("seen", 1.0),
    )


def state_with(robots: list[tuple[float, float]]) -> WorldState:
    n = len(robots) + 1
    poses = np.array([[0.0, 0.0, 0.0], *[[x, y, 0.0] for x, y in robots]])
    return WorldState(
        time_s=1.0,
        names=tuple(f"r{k}" for k in range(n)),
        kinds=("nao",) * n,
        teams=np.array([0] + [1] * (n - 1)),
        poses=poses,
        heads=np.zeros((n, 2)),
        blocked=np.zeros(n, dtype=bool),
        agent=0,
        ball=np.zeros(2),
        ball_velocity=np.zeros(2),
        landmarks=np.zeros((0, 2)),
        landmark_ids=np.zeros(0, dtype=np.int64),
        circles=np.zeros((0, 3)),
    )


def test_tracked_share_counts_the_near_robots_with_a_close_confirmed_track() -> None:
    state = state_with([(1.0, 0.0), (0.0, 2.0), (5.0, 0.0)])  # the last is beyond 3 m
    assert tracked_share(state, (), 3.0, 0.3) == 0.0
    tracks = (track(0, (1.1, 0.1)), track(1, (0.0, 2.5)), track(2, (5.0, 0.0)))
    assert tracked_share(state, tracks, 3.0, 0.3) == 0.5  # 0.14 m: tracked; 0.5 m: not
    tentative = (track(0, (1.0, 0.0), confirmed=False),)
    assert tracked_share(state, tentative, 3.0, 0.3) == 0.0
    assert tracked_share(state_with([(4.0, 0.0)]), tracks, 3.0, 0.3) is None


def test_robot_track_encoder_from_a_turned_pose() -> None:
    pose = np.array([1.0, 1.0, math.pi / 2])  # facing +y
    slam = SlamEstimate(
        pose=pose,
        pose_cov=np.eye(3) * 1e-4,
        landmark_ids=np.zeros(0, dtype=np.int64),
        landmarks=np.zeros((0, 2)),
        landmark_covs=np.zeros((0, 2, 2)),
    )
    tracks = (
        track(4, (1.0, 3.0), velocity=(0.0, 0.3), team=0, var=0.02, seen=1.5),  # 2 m ahead
        track(7, (0.0, 1.0), team=1),  # 1 m to the left: nearest
        track(9, (1.0, 1.5), confirmed=False),  # tentative: not shown
    )
    output = PerceptionOutput(time_s=2.0, representations={SELF_POSE: slam, ROBOT_TRACKS: tracks})
    data = EncoderInput(output=output, frame=SensorFrame(time_s=2.0, camera=CameraModel()))
    obs = RobotTracksEncoder(max_robots=3).encode(data)
    np.testing.assert_allclose(obs["robots_mask"], [1, 1, 0])
    np.testing.assert_allclose(obs["robots_cos_bearing"], [0, 1, 0], atol=1e-12)
    np.testing.assert_allclose(obs["robots_sin_bearing"], [1, 0, 0], atol=1e-12)
    np.testing.assert_allclose(obs["robots_range"], [1 / 4, 2 / 5, 0])
    np.testing.assert_allclose(obs["robots_velocity_x"], [0, 0.5, 0], atol=1e-12)  # 0.3 forward
    np.testing.assert_allclose(obs["robots_velocity_y"], [0, 0, 0], atol=1e-12)
    np.testing.assert_allclose(obs["robots_team"], [-1, 1, 0])
    s7 = math.sqrt(0.02)  # sqrt of the trace of the position covariance (2 x 0.01)
    np.testing.assert_allclose(obs["robots_std"], [s7 / (s7 + 0.5), 0.2 / 0.7, 0])
    np.testing.assert_allclose(obs["robots_since_seen"], [1 / 3, 0.5 / 2.5, 0])


def test_geometric_robot_sightings_follow_view_and_occlusion() -> None:
    env = gym.make("SPL/ActiveVision-v1", n_other_robots=3, robot_frontend="cnn", **FAST)
    env.reset(seed=0)
    core = env.unwrapped
    ours, a, b, c = core.robots
    ours.place(np.array([0.0, 0.0, 0.0]))
    a.place(np.array([2.0, 0.3, 0.0]))  # in view, 2 m ahead
    b.place(np.array([3.5, 0.3, 0.0]))  # straight behind a: hidden
    c.place(np.array([0.0, 2.0, 0.0]))  # 90 deg to the left: outside the 56 deg FOV
    core.scene.place_ball(np.array([-3.0, -2.0]))
    emulator = core.rig.emulators[ROBOT_SIGHTINGS]
    seen = [
        emulator.observe(core.world, ours, ours.camera_state(), np.random.default_rng(k), 0.0)
        for k in range(200)
    ]
    counts = [len(s) for s in seen]
    assert max(counts) == 1  # only a, never the hidden or the unseen one
    assert 0.88 < np.mean(counts) <= 1.0  # the configured 94 % detection chance
    ranges = np.array([s[0].range_m for s in seen if s])
    bearings = np.array([s[0].bearing_rad for s in seen if s])
    true_range, true_bearing = math.hypot(2.0, 0.3), math.atan2(0.3, 2.0)
    assert abs(np.mean(ranges) - true_range) < 0.02
    assert np.std(ranges) == pytest.approx(0.043 * true_range, rel=0.25)
    assert abs(np.mean(bearings) - true_bearing) < math.radians(0.2)
    env.close()


def test_geometric_vision_sightings_need_a_team_or_the_sonar() -> None:
    env = gym.make("SPL/ActiveVision-v1", n_other_robots=2, robot_frontend="vision", **FAST)
    env.reset(seed=0)
    core = env.unwrapped
    ours, near, far = core.robots
    ours.place(np.array([0.0, 0.0, 0.0]))
    near.place(np.array([1.5, 0.2, 0.0]))  # 1.5 m: inside the sonar's middle cone and range
    far.place(np.array([3.0, -0.4, 0.0]))  # 3 m: beyond the sonar's 2.55 m
    core.scene.place_ball(np.array([-3.0, -2.0]))
    assert isinstance(core.rig.emulators[ROBOT_SIGHTINGS], GeometricRobotSightings)
    sonar = core.config.sensors.sonar
    sure = dataclasses.replace(
        VISION_ROBOTS, recall=(1.0,) * 4, sonar_confirm_probability=1.0, team_probability=0.0
    )
    emulator = GeometricRobotSightings(sure, core.config.sensors.camera.model, core.robots, sonar)
    seen = [
        emulator.observe(core.world, ours, ours.camera_state(), np.random.default_rng(k), 0.0)
        for k in range(100)
    ]
    assert all(len(s) == 1 and s[0].sonar_confirmed and s[0].team is None for s in seen)
    ranges = np.array([s[0].range_m for s in seen])
    true_range = math.hypot(1.5, 0.2)
    assert np.std(ranges) == pytest.approx(sure.sonar_range_std_fraction * true_range, rel=0.3)
    assert abs(np.mean(ranges) - true_range) < 0.01
    assert seen[0][0].cov[0, 0] == pytest.approx(sonar.range_noise_std_m**2)
    with_team = dataclasses.replace(sure, team_probability=1.0)  # the far one now stays
    emulator = GeometricRobotSightings(
        with_team, core.config.sensors.camera.model, core.robots, sonar
    )
    found = emulator.observe(core.world, ours, ours.camera_state(), np.random.default_rng(0), 0.0)
    assert [s.team for s in found] == [near.team, far.team]
    assert [s.sonar_confirmed for s in found] == [True, False]
    with pytest.raises(ValueError, match="no sonar"):
        GeometricRobotSightings(sure, core.config.sensors.camera.model, core.robots, None)
    env.close()


@pytest.mark.parametrize("camera_mode", ["geometric", "rendered"])
def test_oracle_sightings_give_tracks_at_the_true_robots(camera_mode: str) -> None:
    env = gym.make(
        "SPL/ActiveVision-v1",
        episode_s=4.0,
        camera_mode=camera_mode,
        frontend="oracle",
        self_pose="oracle",
        robot_frontend="oracle",
    )
    obs, info = env.reset(seed=1)
    errors = []
    for _ in range(40):
        obs, _, _, _, info = env.step(np.array([0.0, 0.0], dtype=np.float32))
        p, gt = info["perception"], info["ground_truth"]
        for xy in p["robots"][p["robots_tracked"]]:
            errors.append(np.min(np.hypot(*(gt["robots"][:, :2] - xy).T)))
    assert env.unwrapped.sensor_frame.image is None  # every provider is an oracle: no render
    assert len(errors) > 20 and np.median(errors) < 0.15
    assert env.observation_space.contains(obs)
    env.close()


def test_geometric_robot_config_bands_and_bad_values() -> None:
    config = GeometricRobotConfig(
        band_edges_m=(1.0, 2.0),
        recall=(0.1, 0.2, 0.3),
        range_std_fraction=(0.01,) * 3,
        bearing_std_rad=(0.01,) * 3,
    )
    assert [config.band(r) for r in (0.5, 1.0, 1.5, 2.5)] == [0, 1, 1, 2]
    with pytest.raises(ValueError, match="band_edges_m"):
        GeometricRobotConfig(band_edges_m=(2.0, 1.0), recall=(1.0, 1.0, 1.0))
    with pytest.raises(ValueError, match="recall must hold one value per band"):
        GeometricRobotConfig(band_edges_m=(1.0,), recall=(0.9,))
    two = {"band_edges_m": (1.0,), "range_std_fraction": (0.1, 0.1), "bearing_std_rad": (0.1, 0.1)}
    with pytest.raises(ValueError, match=r"recall\[1\]"):
        GeometricRobotConfig(recall=(0.9, 1.2), **two)
    with pytest.raises(ValueError, match=r"bearing_std_rad\[0\]"):
        GeometricRobotConfig(**{**two, "bearing_std_rad": (0.0, 0.1)}, recall=(0.9, 0.9))
    with pytest.raises(ValueError, match="team_probability"):
        GeometricRobotConfig(team_probability=-0.1)
    with pytest.raises(TypeError, match="sonar_check"):
        GeometricRobotConfig(sonar_check=1)  # type: ignore[arg-type]
