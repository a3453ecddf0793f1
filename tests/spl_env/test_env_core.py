"""The env core (:class:`spl_env.envs.core.SplEnv`): one step loop for every env, the CNN loaded
once, vector-safe info, the reward's terms, oracle modes, the kick, every robot's rig and
determinism. Geometric camera mode unless rendering is the point."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterator
from typing import Any

import gymnasium as gym
import numpy as np
import pytest

import spl_env  # noqa: F401  (registers the ids)
from spl_env import HEAD_CONTROL_ENV_IDS
from spl_env import SPL_ENV_IDS as ENV_IDS
from spl_env.envs.active_vision import ActiveVisionEnv
from spl_env.envs.core import SplEnv
from spl_env.envs.look_around import LookAroundEnv
from spl_env.robots.nao import NaoCommand, RobotConfig
from spl_env.sensors.rig import NaoRig

FAST: dict[str, Any] = {"camera_mode": "geometric", "frontend": "colour", "episode_s": 2.0}
NAO = RobotConfig()  # documented Nao v6 numbers, restated where a test needs them by hand
YAW_LIMIT = math.radians(119.5)
PITCH_UP, PITCH_DOWN = math.radians(-38.5), math.radians(29.5)


@pytest.fixture
def look_around() -> Iterator[gym.Env]:
    env = gym.make("SPL/LookAround-v0", **FAST)
    yield env
    env.close()


def flatten(info: dict[str, Any], prefix: str = "") -> dict[str, Any]:
    """``{"a.b": value}`` for nested dicts."""
    out: dict[str, Any] = {}
    for key, value in info.items():
        if isinstance(value, dict):
            out.update(flatten(value, f"{prefix}{key}."))
        else:
            out[f"{prefix}{key}"] = value
    return out


def layout(info: dict[str, Any]) -> dict[str, tuple]:
    """Every entry's kind: (shape, dtype) for arrays, the type for the rest."""
    return {
        key: (np.shape(value), np.asarray(value).dtype)
        if isinstance(value, np.ndarray)
        else (type(value),)
        for key, value in flatten(info).items()
    }


def cross(a: np.ndarray, b: np.ndarray) -> float:
    """z of the 2-D cross product: b's offset to the left of the line along a."""
    return float(a[0] * b[1] - a[1] * b[0])


def assert_same(a: Any, b: Any) -> None:
    """Nested dicts of arrays and numbers are identical."""
    if isinstance(a, dict):
        assert set(a) == set(b)
        for key in a:
            assert_same(a[key], b[key])
    else:
        np.testing.assert_array_equal(a, b)


# ----- one step loop ---------------------------------------------------------------------------
@pytest.mark.parametrize("env_class", [LookAroundEnv, ActiveVisionEnv])
def test_envs_add_no_step_loop_of_their_own(env_class: type[SplEnv]) -> None:
    for name in ("step", "reset", "render", "close"):
        assert getattr(env_class, name) is getattr(SplEnv, name), name
        assert name not in vars(env_class), name


def test_look_around_stands_still_while_the_head_follows(look_around: gym.Env) -> None:
    """Our robot never walks; a constant action drives the head to head_target's joint
    targets (by hand from the Nao v6 limits), no faster than 4 rad/s x 0.1 s per step."""
    _, info = look_around.reset(seed=3)
    start = info["ground_truth"]["robot_pose"].copy()
    head = info["ground_truth"]["head"].copy()
    for action in ([0.8, -0.6], [-0.5, 0.9]):
        target = np.array(
            [action[0] * YAW_LIMIT, PITCH_UP + (action[1] + 1) / 2 * (PITCH_DOWN - PITCH_UP)]
        )
        for _ in range(10):  # at most ~3.4 rad to go at 0.4 rad per step
            _, _, _, _, info = look_around.step(np.array(action, dtype=np.float32))
            now = info["ground_truth"]["head"]
            assert np.all(np.abs(now - head) <= 0.4 + 1e-9)
            head = now.copy()
            np.testing.assert_array_equal(info["ground_truth"]["robot_pose"], start)
        np.testing.assert_allclose(head, target, atol=1e-9)
    assert look_around.unwrapped.sensor_frame.camera_state.head_yaw == pytest.approx(head[0])


# ----- the CNN is loaded once ------------------------------------------------------------------
def test_rendered_resets_do_not_reload_the_cnn(monkeypatch: pytest.MonkeyPatch) -> None:
    from perception.vision import cnn_detector

    built: list[object] = []
    original = cnn_detector.CnnPoleDetector.__init__

    def counting_init(self: Any, *args: Any, **kwargs: Any) -> None:
        built.append(self)
        original(self, *args, **kwargs)

    monkeypatch.setattr(cnn_detector.CnnPoleDetector, "__init__", counting_init)
    env = gym.make("SPL/LookAround-v0", episode_s=1.0, n_other_robots=0)
    assert env.unwrapped.config.sensors.camera_mode == "rendered"
    assert env.unwrapped.config.perception.pole_sightings == "cnn"
    for seed in range(3):
        env.reset(seed=seed)
        env.step(env.action_space.sample())
        assert env.unwrapped.sensor_frame.image is not None  # it did render and detect
    env.close()
    assert len(built) == 1


# ----- info ------------------------------------------------------------------------------------
@pytest.mark.parametrize("env_id", ENV_IDS)
def test_info_is_vector_safe(env_id: str) -> None:
    """Same keys, shapes and dtypes at reset and over 20 random steps, whatever the number of
    poles sighted or mapped, and into a second episode."""
    env = gym.make(env_id, **FAST)
    env.action_space.seed(0)
    _, info = env.reset(seed=0)
    expected = layout(info)
    assert set(info) == {"reward_terms", "perception", "ground_truth"}
    n = len(info["ground_truth"]["landmark_ids"])
    if n:  # the pole sightings; a field without poles lists its field features instead
        assert expected["perception.sightings"][0] == (n, 2)
    else:
        assert expected["perception.field_features"][0] == (32, 2, 2)
    assert expected["perception.landmark_covs"][0] == (n, 2, 2)
    assert expected["perception.landmarks_mapped"] == ((n,), np.dtype(bool))
    others = env.unwrapped.config.task.n_other_robots  # type: ignore[attr-defined]
    assert expected["ground_truth.robots"][0] == (others, 3)
    for step in range(25):
        if step == 20:
            _, info = env.reset(seed=1)
        else:
            info = env.step(env.action_space.sample())[4]
        assert layout(info) == expected
        np.testing.assert_array_equal(
            info["perception"]["landmark_ids"], info["ground_truth"]["landmark_ids"]
        )
    env.close()


def test_info_rows_follow_the_env_landmark_order(look_around: gym.Env) -> None:
    """Mapped rows hold landmarks near their true positions; unmapped rows are zero; sighted
    rows hold the range and bearing of the true pole from the true pose within a few
    decimetres."""
    look_around.reset(seed=5)
    for yaw in np.linspace(-1, 1, 20):
        _, _, _, _, info = look_around.step(np.array([yaw, 0.0], dtype=np.float32))
        perception, truth = info["perception"], info["ground_truth"]
        mapped = perception["landmarks_mapped"]
        assert not perception["landmarks"][~mapped].any()
        assert not perception["landmark_covs"][~mapped].any()
        error = np.hypot(*(perception["landmarks"][mapped] - truth["landmarks"][mapped]).T)
        assert np.all(error < 0.5), error
        sighted = perception["sighted"]
        assert not perception["sightings"][~sighted].any()
        x, y, t = truth["robot_pose"]
        for (r, b), (lx, ly) in zip(
            perception["sightings"][sighted], truth["landmarks"][sighted], strict=True
        ):
            assert r == pytest.approx(math.hypot(lx - x, ly - y), abs=0.5)
            assert abs(math.remainder(b - (math.atan2(ly - y, lx - x) - t), 2 * math.pi)) < 0.2
    assert mapped.any()


@pytest.mark.parametrize("env_id", HEAD_CONTROL_ENV_IDS)
def test_light_info_has_only_reward_terms(env_id: str) -> None:
    env = gym.make(env_id, info_level="light", **FAST)
    env.action_space.seed(0)
    _, info = env.reset(seed=0)
    assert set(info) == {"reward_terms"}
    for _ in range(3):
        obs, reward, _, _, info = env.step(env.action_space.sample())
        assert set(info) == {"reward_terms"}
        localisation = {"position_error", "uncertainty", "information"}
        tracks_robots = env_id in ("SPL/ActiveVision-v1", "SPL/ActiveVision-NoPoles-v1")
        awareness = {"robot_awareness"} if tracks_robots else set()
        assert set(info["reward_terms"]) == localisation | awareness
        assert reward == pytest.approx(sum(info["reward_terms"].values()))
        assert env.observation_space.contains(obs)
    env.close()


@pytest.mark.parametrize("env_id", HEAD_CONTROL_ENV_IDS)
def test_reward_is_the_sum_of_its_terms_as_documented(env_id: str) -> None:
    """Reward = -1 x true position error - 0.5 x sqrt(trace of the believed xy covariance),
    recomputed from info's truth and belief."""
    env = gym.make(env_id, **FAST)
    env.action_space.seed(2)
    env.reset(seed=2)
    for _ in range(10):
        _, reward, _, _, info = env.step(env.action_space.sample())
        terms = info["reward_terms"]
        assert reward == pytest.approx(sum(terms.values()), abs=1e-12)
        truth, belief = info["ground_truth"], info["perception"]
        error = math.hypot(*(truth["robot_pose"][:2] - belief["pose"][:2]))
        std = math.sqrt(np.trace(belief["pose_cov"][:2, :2]))
        assert terms["position_error"] == pytest.approx(-error, abs=1e-12)
        assert terms["uncertainty"] == pytest.approx(-0.5 * std, abs=1e-12)
    env.close()


# ----- oracle modes ----------------------------------------------------------------------------
@pytest.mark.parametrize("camera_mode", ["geometric", "rendered"])
def test_oracle_modes_by_name(camera_mode: str) -> None:
    """Oracle sightings and self pose: nothing is rendered (no provider reads pixels), the frame
    carries the truth, the believed pose stays within a few of the oracle's 5 cm std, and its
    covariance is the oracle's diagonal."""
    env = gym.make(
        "SPL/LookAround-v0",
        camera_mode=camera_mode,
        frontend="oracle",
        self_pose="oracle",
        episode_s=2.0,
    )
    env.action_space.seed(0)
    _, info = env.reset(seed=0)
    core = env.unwrapped
    for _ in range(20):
        assert core.sensor_frame.image is None
        assert core.sensor_frame.truth is not None
        truth, belief = info["ground_truth"], info["perception"]
        error = math.hypot(*(truth["robot_pose"][:2] - belief["pose"][:2]))
        assert error < 5 * 0.05  # P(> 5 sigma) of a 2-D Gaussian: exp(-12.5)
        np.testing.assert_allclose(belief["pose_cov"], np.diag([0.05**2, 0.05**2, 0.02**2]))
        assert belief["landmarks_mapped"].all()
        np.testing.assert_array_equal(truth["robot_pose"], core.world_state.robot_pose)
        info = env.step(env.action_space.sample())[4]
    env.close()


def test_non_oracle_frames_carry_no_truth(look_around: gym.Env) -> None:
    look_around.reset(seed=0)
    look_around.step(look_around.action_space.sample())
    assert look_around.unwrapped.sensor_frame.truth is None
    assert "truth" not in look_around.unwrapped.pipeline.frame_inputs


# ----- the kick --------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("ahead", "aside", "kicks"),
    [
        (0.10, 0.0, True),
        (0.24, 0.11, True),
        (0.05, -0.11, True),
        (0.26, 0.0, False),  # beyond the reach (0.25 m)
        (0.15, 0.13, False),  # beyond the half width (0.12 m)
        (0.15, -0.13, False),
        (-0.10, 0.0, False),  # behind
    ],
)
def test_kick_zone_and_direction(
    look_around: gym.Env, ahead: float, aside: float, kicks: bool
) -> None:
    robot = look_around.unwrapped.robots[0]
    noisy = robot.config
    robot.config = dataclasses.replace(noisy, kick_angle_std_rad=0.0, kick_speed_std_fraction=0.0)
    rng = np.random.default_rng(0)
    for pose in ((0.0, 0.0, 0.0), (1.0, -2.0, 2.2), (-3.0, 1.5, -1.0)):
        robot.pose = np.array(pose)
        x, y, t = pose
        ball = np.array(
            [
                x + ahead * math.cos(t) - aside * math.sin(t),
                y + ahead * math.sin(t) + aside * math.cos(t),
            ]
        )
        velocity = robot.kick_velocity(ball, rng)
        assert robot.in_kick_zone(ball) == kicks
        if kicks:
            assert velocity is not None
            np.testing.assert_allclose(velocity, 2.0 * np.array([math.cos(t), math.sin(t)]))
        else:
            assert velocity is None
    robot.config = noisy


@pytest.mark.parametrize(("offset", "moves"), [(0.15, True), (-0.3, False)])
def test_kick_through_the_core_moves_the_ball_along_the_heading(
    monkeypatch: pytest.MonkeyPatch, offset: float, moves: bool
) -> None:
    """Our task's command is replaced by a kick; the step applies it through the core. A ball
    just ahead rolls off along the heading; a ball behind stays put (a kick without noise)."""
    quiet = {"robot.kick_angle_std_rad": 0.0, "robot.kick_speed_std_fraction": 0.0}
    env = gym.make("SPL/LookAround-v0", n_other_robots=0, **FAST, **quiet)
    env.reset(seed=0)
    core = env.unwrapped
    heading = 0.6
    core.robots[0].place(np.array([0.3, -0.2, heading]))
    direction = np.array([math.cos(heading), math.sin(heading)])
    start = np.array([0.3, -0.2]) + offset * direction
    core.scene.place_ball(start)
    kick = NaoCommand(walk=np.zeros(3), kick=True)
    monkeypatch.setattr(core.task, "command", lambda action, state: kick)
    _, _, _, _, info = env.step(np.zeros(2, dtype=np.float32))
    ball, velocity = info["ground_truth"]["ball"], info["ground_truth"]["ball_velocity"]
    moved = ball - start
    if moves:
        assert 0.1 < float(moved @ direction) <= 0.2 + 1e-6  # at most 2 m/s for 0.1 s
        assert abs(cross(direction, moved)) < 0.01
        speed = float(velocity @ direction)
        assert 1.0 < speed <= 2.0 + 1e-6
        assert abs(cross(direction, velocity)) < 0.05
    else:
        np.testing.assert_allclose(moved, 0.0, atol=1e-3)
        np.testing.assert_allclose(velocity, 0.0, atol=1e-2)
    env.close()


# ----- every robot can sense -------------------------------------------------------------------
def test_another_robot_rig_senses_its_own_head_and_surroundings() -> None:
    env = gym.make("SPL/LookAround-v0", n_other_robots=1, **FAST)
    env.reset(seed=0)
    core = env.unwrapped
    other, ours = core.robots[1], core.robots[0]
    core.scene.place_ball(np.array([3.5, 2.5]))  # out of the way
    yaw, pitch = 0.4, 0.2
    other.place(np.array([0.0, 0.5, 0.0]), head=np.array([yaw, pitch]))
    ours.place(np.array([0.6, 0.5, math.pi]))  # 0.6 m straight ahead of the other robot
    rig = NaoRig(core.config.sensors, other)
    rng = np.random.default_rng(0)
    rig.reset(rng)
    frame, times = rig.sense(core.world, 1.5, np.zeros(3), 0.0, rng, render=False)
    assert frame.time_s == 1.5
    assert frame.image is None and frame.emulated == {} and frame.truth is None
    np.testing.assert_array_equal(frame.odometry_delta, np.zeros(3))  # standing: no error
    assert times["render"] >= 0 and times["sensors"] >= 0
    # camera pose from the joint angles by hand: neck 0.44 m, pitch joint 0.017 m above it,
    # the camera (0.0587, 0, 0.0636) in the head frame, pitched by `pitch` then yawed by `yaw`
    ox, oz = NAO.camera_offset_m[0], NAO.camera_offset_m[2]
    along = math.cos(pitch) * ox + math.sin(pitch) * oz
    expected = [math.cos(yaw) * along, math.sin(yaw) * along]
    expected.append(0.44 + 0.017 - math.sin(pitch) * ox + math.cos(pitch) * oz)
    state = frame.camera_state
    assert (state.head_yaw, state.head_pitch) == (yaw, pitch)
    assert state.tilt == pytest.approx(math.radians(1.2))
    np.testing.assert_allclose(state.position, expected, atol=1e-12)
    assert frame.camera == core.config.sensors.camera.model
    # sonar: (3, E) nearest first, NaN-padded, within the model's range; our robot 0.6 m
    # ahead is heard in the middle sector, closer than 0.6 m (its front, seen from the mount)
    sonar, model = frame.sonar, frame.sonar_model
    assert sonar.shape == (3, model.max_echoes)
    for row in sonar:
        heard = row[~np.isnan(row)]
        assert np.all(np.isnan(row[len(heard) :]))
        assert np.all(np.diff(heard) >= 0)
        assert np.all((heard >= model.min_range_m) & (heard <= model.max_range_m))
    middle = sonar[1][~np.isnan(sonar[1])]
    assert len(middle) >= 1 and 0.2 < middle[0] < 0.6, sonar
    # a step's odometry is the increment, scaled by the episode's drawn error, plus noise of
    # the configured std (0.03 m per sqrt(m) on each of dx, dy; 0.07 rad per sqrt(m) on the
    # heading): within 5 std of that, and far from nothing or twice the step
    step_m = 0.3
    delta = rig.sense(core.world, 1.6, np.array([step_m, 0.0, 0.0]), 0.0, rng, render=False)[0]
    errors, odometry = rig.odometry.errors, core.config.sensors.odometry
    xy_std = odometry.translation_noise_m_per_sqrt_m * math.sqrt(step_m)
    expected_x = (1.0 + errors.translation_scale_error) * step_m
    assert abs(delta.odometry_delta[0] - expected_x) < 5 * xy_std
    assert abs(delta.odometry_delta[1]) < 5 * xy_std
    theta_std = odometry.heading_noise_rad_per_sqrt_m * math.sqrt(step_m)
    expected_theta = errors.heading_drift_rad_per_m * step_m
    assert abs(delta.odometry_delta[2] - expected_theta) < 5 * theta_std
    assert 5 * xy_std < 0.5 * step_m  # the band excludes a missing or a doubled step
    env.close()


# ----- determinism -----------------------------------------------------------------------------
@pytest.mark.parametrize("env_id", ENV_IDS)
@pytest.mark.parametrize("info_level", ["full", "light"])
@pytest.mark.parametrize(
    "camera",
    [
        {"camera_mode": "geometric", "frontend": "colour"},
        {"camera_mode": "rendered", "frontend": "cnn"},  # the default: pixels and the CNN
    ],
    ids=["geometric", "rendered"],
)
def test_same_seed_and_actions_same_observations_and_info(
    env_id: str, info_level: str, camera: dict[str, str]
) -> None:
    shape = gym.make(env_id, **{**FAST, **camera}).action_space.shape
    assert shape is not None
    actions = np.random.default_rng(7).uniform(-1, 1, size=(15, *shape)).astype(np.float32)

    def rollout() -> list[tuple[dict, dict, float]]:
        env = gym.make(env_id, info_level=info_level, **{**FAST, **camera})
        obs, info = env.reset(seed=42)
        out = [(obs, info, 0.0)]
        for a in actions:
            obs, reward, _, _, info = env.step(a)
            out.append((obs, info, reward))
        env.close()
        return out

    first, second = rollout(), rollout()
    for (obs_a, info_a, r_a), (obs_b, info_b, r_b) in zip(first, second, strict=True):
        assert_same(obs_a, obs_b)
        assert_same(info_a, info_b)
        assert r_a == r_b
    heads = [obs["head_angles"] for obs, _, _ in first]
    assert not np.array_equal(heads[0], heads[-1])  # the rollout did something
