"""The range-bearing Jacobian and information gain against independent computations; the greedy
information head planner on synthetic observations of ``SPL/ActiveVision-v1``."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest

import spl_env  # noqa: F401  (registers the ids)
from agents.baselines import GreedyInformation, HeadScan
from agents.information_gain import information_gain, range_bearing_jacobian
from spl_env.config import EnvConfig
from spl_env.robots.nao import RobotConfig


def _range_bearing(pose: np.ndarray, landmark: np.ndarray) -> np.ndarray:
    dx, dy = landmark - pose[:2]
    return np.array([math.hypot(dx, dy), math.atan2(dy, dx) - pose[2]])


def _random_cov(rng: np.random.Generator, n: int) -> np.ndarray:
    a = rng.normal(size=(n, n))
    return a @ a.T + 0.1 * np.eye(n)


def test_jacobian_matches_central_differences() -> None:
    rng = np.random.default_rng(7)
    eps = 1e-6
    for _ in range(5):
        pose = np.array([*rng.uniform(-4.0, 4.0, 2), rng.uniform(-math.pi, math.pi)])
        landmark = rng.uniform(-5.0, 5.0, 2)
        delta = landmark - pose[:2]
        direction, distance = math.atan2(delta[1], delta[0]), float(np.linalg.norm(delta))
        numeric = np.zeros((2, 3))
        for j in range(3):
            step = np.zeros(3)
            step[j] = eps
            diff = _range_bearing(pose + step, landmark) - _range_bearing(pose - step, landmark)
            diff[1] = math.remainder(diff[1], 2 * math.pi)
            numeric[:, j] = diff / (2 * eps)
        jacobian = range_bearing_jacobian(np.array([direction]), np.array([distance]))
        assert jacobian.shape == (1, 2, 3)
        np.testing.assert_allclose(jacobian[0], numeric, atol=1e-6)


def test_jacobians_of_several_landmarks_stack() -> None:
    directions, ranges = np.array([0.3, -2.0, 1.5]), np.array([1.0, 2.5, 4.0])
    stacked = range_bearing_jacobian(directions, ranges)
    assert stacked.shape == (3, 2, 3)
    for k in range(3):
        single = range_bearing_jacobian(directions[k : k + 1], ranges[k : k + 1])
        np.testing.assert_array_equal(stacked[k], single[0])


def test_information_gain_without_sightings_is_zero() -> None:
    cov = _random_cov(np.random.default_rng(1), 3)
    assert information_gain(cov, np.zeros((0, 2, 3)), np.zeros((0, 2, 2))) == pytest.approx(
        0.0, abs=1e-12
    )


def test_information_gain_of_one_sighting_is_the_kalman_entropy_drop() -> None:
    rng = np.random.default_rng(3)
    for _ in range(5):
        prior = _random_cov(rng, 3)
        h = rng.normal(size=(2, 3))
        noise = _random_cov(rng, 2)
        posterior = prior - prior @ h.T @ np.linalg.inv(h @ prior @ h.T + noise) @ h @ prior
        expected = 0.5 * math.log(np.linalg.det(prior) / np.linalg.det(posterior))
        gain = information_gain(prior, h[None], noise[None])
        assert gain == pytest.approx(expected, rel=1e-9)
        assert gain > 0.0


def test_two_sightings_give_more_than_either() -> None:
    rng = np.random.default_rng(5)
    prior = np.diag([0.2, 0.3, 0.1]) ** 2
    h = range_bearing_jacobian(np.array([0.4, 2.0]), np.array([2.0, 3.0]))
    noise = np.stack([_random_cov(rng, 2) * 1e-3 for _ in range(2)])
    both = information_gain(prior, h, noise)
    first = information_gain(prior, h[:1], noise[:1])
    second = information_gain(prior, h[1:], noise[1:])
    assert both > first > 0.0 and both > second > 0.0
    # a second update with the second sighting from the posterior of the first adds up
    info = np.linalg.inv(prior) + h[0].T @ np.linalg.inv(noise[0]) @ h[0]
    assert both == pytest.approx(first + information_gain(np.linalg.inv(info), h[1:], noise[1:]))


@pytest.fixture(scope="module")
def av_env() -> tuple[EnvConfig, gym.spaces.Dict]:
    env = gym.make("SPL/ActiveVision-v1", camera_mode="geometric", frontend="colour")
    config, space = env.get_wrapper_attr("config"), env.observation_space
    env.close()
    assert isinstance(space, gym.spaces.Dict)
    return config, space


def _obs(
    env: tuple[EnvConfig, gym.spaces.Dict],
    bearings_deg: list[float],
    ranges_m: list[float],
    *,
    mapped: list[bool] | None = None,
    since_seen_s: list[float] | None = None,
    head_yaw_deg: float = 0.0,
) -> dict[str, np.ndarray]:
    config, space = env
    obs = {key: np.zeros(box.shape or (), np.float32) for key, box in space.spaces.items()}
    bearings, ranges = np.radians(bearings_deg), np.asarray(ranges_m, float)
    since = np.ones(6) if since_seen_s is None else np.asarray(since_seen_s, float)
    obs["landmarks_mask"][:] = 1.0 if mapped is None else np.asarray(mapped, float)
    obs["landmarks_cos_bearing"][:] = np.cos(bearings)
    obs["landmarks_sin_bearing"][:] = np.sin(bearings)
    obs["landmarks_range"][:] = ranges / (ranges + 3.0)
    obs["landmarks_std"][:] = 0.05 / (0.05 + 0.5)
    obs["landmarks_since_seen"][:] = since / (since + 2.0)
    x, y, heading = 0.5, -1.0, math.radians(20.0)
    half_l, half_w = (size / 2 for size in config.scene.dimensions.carpet_size_m)
    obs["self_pose_field"][:] = [x / half_l, y / half_w, math.cos(heading), math.sin(heading)]
    std = np.array([0.2, 0.2, 0.1])
    obs["self_pose_std"][:] = std / (std + 0.5)
    obs["head_angles"][0] = math.radians(head_yaw_deg) / config.robot.head_yaw_limit_rad
    return obs


def _yaw_deg(action: np.ndarray) -> float:
    return math.degrees(float(action[0]) * RobotConfig().head_yaw_limit_rad)


def _counted_half_view_deg(policy: GreedyInformation) -> float:
    return math.degrees(policy.half_fov_rad - policy.view_margin_rad)


def test_greedy_looks_at_the_one_pole_in_range(av_env: tuple[EnvConfig, gym.spaces.Dict]) -> None:
    policy = GreedyInformation.from_config(av_env[0])
    assert policy.max_range_m == 6.0
    far = [7.0] * 5
    obs = _obs(av_env, [60.0, 0.0, -30.0, 100.0, -100.0, 10.0], [2.5, *far], head_yaw_deg=60.0)
    action, _ = policy.predict(obs, episode_start=np.array([True]))
    assert abs(_yaw_deg(action) - 60.0) <= 5.0
    # from straight ahead too: the centring puts the pole near the middle of the image, the
    # turn cost holding it back by at most a grid step or two
    obs = _obs(av_env, [60.0, 0.0, -30.0, 100.0, -100.0, 10.0], [2.5, *far])
    action, _ = policy.predict(obs, episode_start=np.array([True]))
    assert 0.0 <= 60.0 - _yaw_deg(action) <= 2 * math.degrees(policy.yaw_step_rad) + 0.5


def test_greedy_ignores_poles_beyond_max_range(av_env: tuple[EnvConfig, gym.spaces.Dict]) -> None:
    policy = GreedyInformation.from_config(av_env[0])
    obs = _obs(av_env, [60.0, 0.0, -30.0, 100.0, -100.0, 10.0], [7.0] * 6, head_yaw_deg=60.0)
    action, _ = policy.predict(obs, episode_start=np.array([True]))
    assert _yaw_deg(action) == pytest.approx(60.0, abs=5.0)  # nothing to gain: it stays
    ranges = [7.0, 7.0, 2.0, 7.0, 7.0, 7.0]  # only the pole at -30° is near
    obs = _obs(av_env, [60.0, 0.0, -30.0, 100.0, -100.0, 10.0], ranges, head_yaw_deg=60.0)
    action, _ = policy.predict(obs, episode_start=np.array([True]))
    assert abs(_yaw_deg(action) + 30.0) <= _counted_half_view_deg(policy)


def _two_poles(
    policy: GreedyInformation, env: tuple[EnvConfig, gym.spaces.Dict], seen: bool
) -> list[float]:
    yaws = []
    for k in range(8):
        obs = _obs(
            env,
            [-50.0, 50.0, 0.0, 100.0, -100.0, 180.0],
            [2.5, 2.5, 7.0, 7.0, 7.0, 7.0],
            since_seen_s=[1.0, 0.0 if seen else 1.0, 1.0, 1.0, 1.0, 1.0],
            head_yaw_deg=50.0,
        )
        action, _ = policy.predict(obs, episode_start=np.array([k == 0]))
        yaws.append(_yaw_deg(action))
    return yaws


def test_greedy_turns_away_from_a_pole_it_keeps_seeing(
    av_env: tuple[EnvConfig, gym.spaces.Dict],
) -> None:
    policy = GreedyInformation.from_config(av_env[0])
    half_view = _counted_half_view_deg(policy)
    # unseen, the two poles promise the same: the turn cost keeps the head on the +50° one
    assert all(abs(yaw - 50.0) <= half_view for yaw in _two_poles(policy, av_env, seen=False))
    # the +50° pole seen at every step thins the tracked covariance along its directions
    yaws = _two_poles(policy, av_env, seen=True)
    assert all(abs(yaw + 50.0) <= half_view for yaw in yaws[3:])


def test_greedy_scans_with_no_pole_mapped(av_env: tuple[EnvConfig, gym.spaces.Dict]) -> None:
    greedy, scan = GreedyInformation.from_config(av_env[0]), HeadScan.from_config(av_env[0])
    obs = _obs(av_env, [60.0, 0.0, -30.0, 100.0, -100.0, 10.0], [2.0] * 6, mapped=[False] * 6)
    yaws = []
    for k in range(45):
        start = np.array([k == 0])
        action, _ = greedy.predict(obs, episode_start=start)
        np.testing.assert_array_equal(action, scan.predict(obs, episode_start=start)[0])
        yaws.append(_yaw_deg(action))
    assert max(yaws) > 80.0 and min(yaws) < -80.0  # a real sweep, not a fixed head


def test_greedy_sweeps_each_explore_period_while_a_pole_is_unmapped(
    av_env: tuple[EnvConfig, gym.spaces.Dict],
) -> None:
    greedy, scan = GreedyInformation.from_config(av_env[0]), HeadScan.from_config(av_env[0])
    assert greedy.period_s == 4.0 and greedy.explore_period_s == 8.0
    assert greedy.control_dt_s == pytest.approx(0.1)
    obs = _obs(
        av_env,
        [60.0, 0.0, -30.0, 100.0, -100.0, 10.0],
        [2.5, 7.0, 7.0, 7.0, 7.0, 7.0],
        mapped=[True, True, True, True, True, False],
    )
    greedy_actions, scan_actions = [], []
    for k in range(201):
        start = np.array([k == 0])
        greedy_actions.append(greedy.predict(obs, episode_start=start)[0])
        scan_actions.append(scan.predict(obs, episode_start=start)[0])
    g, s = np.array(greedy_actions), np.array(scan_actions)
    # steps of 0.1 s: a 40-step sweep every 80 steps
    for sweep in (0, 80, 160):
        np.testing.assert_array_equal(g[sweep : sweep + 40], s[sweep : sweep + 40])
        assert not np.allclose(g[sweep + 40], s[sweep + 40])  # the sweep is over
    for between in (slice(41, 80), slice(121, 160)):
        assert np.ptp(g[between, 0]) == 0.0  # the held target
        assert abs(_yaw_deg(g[between][0]) - 60.0) <= _counted_half_view_deg(greedy)
        assert not np.allclose(g[between], s[between])
