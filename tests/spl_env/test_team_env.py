"""``spl_env.team_v0``: N against N Naos, every one perceiving (PettingZoo ``ParallelEnv``).

The geometric camera mode throughout (fast); episodes of a few seconds.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Iterator
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from pettingzoo.test import parallel_api_test, parallel_seed_test

from perception.geometry import range_bearing, wrap_angle
from perception.types import SensorFrame
from spl_env import NO_POLES_KWARGS, team_v0
from spl_env.envs.team import TeamEnv, mirror_observation
from spl_env.field import FieldDimensions

FAST: dict[str, Any] = {"camera_mode": "geometric", "frontend": "colour", "episode_s": 2.0}
DIMS = FieldDimensions()
STAND = np.zeros(5, dtype=np.float32)


@pytest.fixture
def env() -> Iterator[TeamEnv]:
    env = team_v0.parallel_env(**FAST)
    yield env
    env.close()


def flatten(tree: dict[str, Any], prefix: str = "") -> dict[str, Any]:
    """Nested dicts as one dict keyed by dotted paths."""
    flat: dict[str, Any] = {}
    for key, value in tree.items():
        if isinstance(value, dict):
            flat.update(flatten(value, f"{prefix}{key}."))
        else:
            flat[f"{prefix}{key}"] = value
    return flat


def assert_same(a: dict[str, Any], b: dict[str, Any]) -> None:
    """Nested dicts of arrays and numbers are identical."""
    flat_a, flat_b = flatten(a), flatten(b)
    assert set(flat_a) == set(flat_b)
    for key, value in flat_a.items():
        np.testing.assert_array_equal(value, flat_b[key], err_msg=key)


def frame_of(env: TeamEnv, agent: str) -> SensorFrame:
    """The agent's sensor frame of the last step."""
    frame = env.player(agent).frame
    assert frame is not None
    return frame


def stand(env: TeamEnv) -> dict[str, np.ndarray]:
    return {agent: STAND.copy() for agent in env.agents}


def test_parallel_api_test_passes_without_warnings() -> None:
    env = team_v0.parallel_env(**{**FAST, "episode_s": 1.0})
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        parallel_api_test(env, num_cycles=30)
    env.close()
    env.close()  # closing twice is harmless
    assert [str(w.message) for w in caught] == []


def test_without_poles_every_player_localises_from_the_field_features() -> None:
    """``NO_POLES_KWARGS``: no pole on the field, every player's pose from the field's
    features in its own camera (its own pose filter). PettingZoo's API test passes and the
    observations gain the feature clocks; over 10 s of walking in circles every player sees
    features, and the believed poses lie nearer the truth than the walk odometry alone (which
    is what they would be without the features' corrections)."""
    env = team_v0.parallel_env(**{**FAST, "episode_s": 1.0}, **NO_POLES_KWARGS)
    parallel_api_test(env, num_cycles=10)
    env.close()
    env = team_v0.parallel_env(**{**FAST, "episode_s": 12.0}, **NO_POLES_KWARGS)
    observations, infos = env.reset(seed=5)
    assert all("field_features_since_seen" in o for o in observations.values())
    assert infos[env.possible_agents[0]]["ground_truth"]["landmarks"].shape == (0, 2)
    walk = np.array([0.8, 0.0, 0.4, 0.0, 0.0], dtype=np.float32)  # forward, turning left
    seen = dict.fromkeys(env.possible_agents, 0)
    errors, drift = [], []
    for _ in range(100):
        *_, infos = env.step({agent: walk for agent in env.agents})
        for agent in env.possible_agents:
            perceived, truth = infos[agent]["perception"], infos[agent]["ground_truth"]
            seen[agent] += int(perceived["field_features_count"])
            errors.append(math.dist(perceived["pose"][:2], truth["robot_pose"][:2]))
            drift.append(math.dist(perceived["odometry_pose"][:2], truth["robot_pose"][:2]))
    assert all(count > 0 for count in seen.values()), seen
    assert np.mean(errors) < 0.08
    assert np.mean(errors) < 0.7 * np.mean(drift)
    env.close()


def test_agents_teams_and_the_striker_observation(env: TeamEnv) -> None:
    assert env.possible_agents == ["blue_0", "blue_1", "red_0", "red_1"]
    striker = gym.make("SPL/Striker-v0", **FAST)
    expected = striker.observation_space
    striker.close()
    assert isinstance(expected, gym.spaces.Dict)
    for agent in env.possible_agents:
        space = env.observation_space(agent)
        assert isinstance(space, gym.spaces.Dict)
        assert list(space.keys()) == list(expected.keys())
        for key, box in space.items():
            assert box == expected[key], key
        assert env.action_space(agent) == gym.spaces.Box(-1, 1, (5,), np.float32)
    assert env.action_space("blue_0") is not env.action_space("blue_1")  # seeded apart
    obs, infos = env.reset(seed=0)
    assert [infos[a]["team"] for a in env.possible_agents] == [0, 0, 1, 1]
    assert [r.team for r in env.robots] == [0, 0, 1, 1]
    for agent, player_obs in obs.items():
        assert env.observation_space(agent).contains(player_obs), agent


@pytest.mark.parametrize("players", [1, 3])
def test_one_and_three_a_side_build_and_play(players: int) -> None:
    env = team_v0.parallel_env(players_per_side=players, **FAST)
    names = [f"{team}_{i}" for team in ("blue", "red") for i in range(players)]
    assert env.possible_agents == names
    env.reset(seed=1)
    obs, rewards, *_, infos = env.step(stand(env))
    assert set(obs) == set(rewards) == set(infos) == set(names)
    assert infos["blue_0"]["ground_truth"]["robots"].shape == (2 * players - 1, 3)
    poses = env.world_state.poses
    assert np.all(poses[:players, 0] < 0) and np.all(poses[players:, 0] > 0)  # own halves
    env.close()


def test_same_seed_and_actions_same_observations_rewards_and_info() -> None:
    rng = np.random.default_rng(7)
    actions = rng.uniform(-1, 1, size=(15, 4, 5)).astype(np.float32)

    def rollout() -> list[tuple[Any, ...]]:
        env = team_v0.parallel_env(**FAST)
        out: list[tuple[Any, ...]] = [env.reset(seed=42)]
        for step_actions in actions:
            out.append(env.step(dict(zip(env.possible_agents, step_actions, strict=True))))
        env.close()
        return out

    first, second = rollout(), rollout()
    for a, b in zip(first, second, strict=True):
        for part_a, part_b in zip(a, b, strict=True):
            assert_same(part_a, part_b)
    assert not np.array_equal(
        first[1][0]["red_0"]["head_angles"], first[-1][0]["red_0"]["head_angles"]
    )


def test_pettingzoo_seed_test_passes() -> None:
    parallel_seed_test(lambda: team_v0.parallel_env(**FAST))


def test_seeds_start_episodes_and_reseeding_repeats_them(env: TeamEnv) -> None:
    obs_a, info_a = env.reset(seed=3)
    env.step(stand(env))
    obs_b, info_b = env.reset(seed=3)
    assert_same(obs_a, obs_b)
    assert_same(info_a, info_b)
    _, info_c = env.reset(seed=4)
    truth = [info_c[a]["ground_truth"]["robot_pose"] for a in env.possible_agents]
    assert not np.allclose(truth[0], info_a["blue_0"]["ground_truth"]["robot_pose"])
    assert len({tuple(pose) for pose in truth}) == 4


def test_every_player_perceives_on_its_own(env: TeamEnv) -> None:
    """Each player sees from its own robot: every pole it sights over a second of standing
    (its head glancing round) lies at the range and bearing of the pole's true position from
    its own true pose, not from another robot's; its believed pose lies within 0.3 m and
    0.15 rad of its true pose, nearer to it than to any other robot; the beliefs all differ."""
    env.reset(seed=5)
    sighted = dict.fromkeys(env.possible_agents, 0)
    for _ in range(10):
        *_, infos = env.step(stand(env))
        poses = env.world_state.poses
        for k, agent in enumerate(env.possible_agents):
            seen = infos[agent]["perception"]["sighted"]
            if not seen.any():
                continue
            sightings = infos[agent]["perception"]["sightings"][seen]
            poles = infos[agent]["ground_truth"]["landmarks"][seen]
            for j, pose in enumerate(poses):
                expected = range_bearing(pose, poles)
                off = np.abs(wrap_angle(sightings[:, 1] - expected[:, 1]))
                if j == k:  # the geometric camera's fitted noise: mrad of bearing, ranges less sure
                    assert np.all(off < 0.02), (agent, off)
                    assert np.all(np.abs(sightings[:, 0] / expected[:, 0] - 1.0) < 0.2)
                else:
                    assert np.any(off > 0.1), (agent, j)
            sighted[agent] += len(sightings)
    assert all(count >= 1 for count in sighted.values()), sighted
    poses = env.world_state.poses
    beliefs = []
    for k, agent in enumerate(env.possible_agents):
        belief = infos[agent]["perception"]["pose"]
        truth = infos[agent]["ground_truth"]["robot_pose"]
        np.testing.assert_array_equal(truth, poses[k])
        assert math.dist(belief[:2], truth[:2]) < 0.3, agent
        assert abs(math.remainder(belief[2] - truth[2], math.tau)) < 0.15, agent
        assert int(np.argmin(np.hypot(*(poses[:, :2] - belief[:2]).T))) == k
        beliefs.append(tuple(belief))
    assert len(set(beliefs)) == 4
    for k, agent in enumerate(env.possible_agents):  # each rig reads its own robot's joints
        state = frame_of(env, agent).camera_state
        assert state is not None
        assert (state.head_yaw, state.head_pitch) == tuple(env.world_state.heads[k])


def test_mirror_observation_by_hand() -> None:
    """(x, y, θ) = (1, -0.5, π/6) on the 10.4 x 7.4 m carpet mirrors to (-1, 0.5, 7π/6)."""
    obs = {
        "self_pose_field": np.array([1 / 5.2, -0.5 / 3.7, math.sqrt(3) / 2, 0.5]),
        "ball_range": np.array([0.25]),
    }
    mirrored = mirror_observation(obs)
    np.testing.assert_allclose(
        mirrored["self_pose_field"], [-1 / 5.2, 0.5 / 3.7, -math.sqrt(3) / 2, -0.5]
    )
    assert mirrored["ball_range"] is obs["ball_range"]
    np.testing.assert_allclose(obs["self_pose_field"][0], 1 / 5.2)  # the input is unchanged


def test_red_sees_the_field_turned_blue_does_not() -> None:
    """With a noise-free oracle pose, red_0 at (1, -0.5, π/6) reads the pose (-1, 0.5, 7π/6),
    which blue_0 standing there reads too; the robot-relative keys are the same for both."""
    oracle = {"self_pose": "oracle", "perception.oracle.position_std_m": 1e-12}
    oracle["perception.oracle.heading_std_rad"] = 1e-12
    env = team_v0.parallel_env(**FAST, **oracle)
    env.reset(seed=0)
    robots = {r.name: r for r in env.robots}
    robots["red_0"].place(np.array([1.0, -0.5, math.pi / 6]))
    robots["blue_0"].place(np.array([-1.0, 0.5, math.pi / 6 + math.pi]))
    robots["blue_1"].place(np.array([-3.0, -2.0, 0.0]))
    robots["red_1"].place(np.array([3.0, 2.0, math.pi]))
    obs, *_, infos = env.step(stand(env))
    expected = [-1 / 5.2, 0.5 / 3.7, -math.sqrt(3) / 2, -0.5]
    np.testing.assert_allclose(obs["red_0"]["self_pose_field"], expected, atol=1e-6)
    np.testing.assert_allclose(obs["blue_0"]["self_pose_field"], expected, atol=1e-6)
    np.testing.assert_allclose(  # info stays in the world's field frame
        infos["red_0"]["perception"]["pose"], [1.0, -0.5, math.pi / 6], atol=1e-6
    )
    for k, name in enumerate(env.possible_agents):  # every agent's belief, encoded by hand
        x, y, theta = infos[name]["perception"]["pose"]
        encoded = np.array([x / 5.2, y / 3.7, math.cos(theta), math.sin(theta)])
        sign = 1.0 if k < 2 else -1.0
        np.testing.assert_allclose(obs[name]["self_pose_field"], sign * encoded, atol=1e-6)
    env.close()


@pytest.mark.parametrize(("side", "scorer"), [(1, 0), (-1, 1)])
def test_a_goal_ends_the_episode_for_all_with_ten_each_way(
    env: TeamEnv, side: int, scorer: int
) -> None:
    env.reset(seed=1)
    env.scene.place_ball(np.array([side * (DIMS.half_length_m + 0.2), 0.1]))
    _, rewards, terminated, truncated, infos = env.step(stand(env))
    assert all(terminated.values()) and not any(truncated.values())
    assert env.agents == []
    for agent, info in infos.items():
        terms = info["reward_terms"]
        assert terms["goal"] == (10.0 if info["team"] == scorer else -10.0), agent
        assert terms["out"] == 0.0
        assert rewards[agent] == pytest.approx(sum(terms.values()))
    with pytest.raises(RuntimeError, match="reset"):
        env.step(stand(env))


def test_the_ball_out_costs_the_team_that_kicked_it(env: TeamEnv) -> None:
    env.reset(seed=2)
    robots = {r.name: r for r in env.robots}
    robots["blue_0"].place(np.array([0.0, 2.75, math.pi / 2]))  # facing the touch line
    robots["blue_1"].place(np.array([-3.0, -2.0, 0.0]))
    robots["red_0"].place(np.array([3.0, -2.0, math.pi]))
    robots["red_1"].place(np.array([3.0, 2.0, math.pi]))
    env.scene.place_ball(np.array([0.0, 2.92]))
    kick = {**stand(env), "blue_0": np.array([0, 0, 0, 1.0, 0], dtype=np.float32)}
    _, _, terminated, _, infos = env.step(kick)
    np.testing.assert_allclose(frame_of(env, "blue_0").kick_velocity, [2.0, 0.0])
    for agent in ("blue_1", "red_0", "red_1"):  # only the kicker's perception hears of it
        np.testing.assert_array_equal(frame_of(env, agent).kick_velocity, [0.0, 0.0])
    for _ in range(5):
        if all(terminated.values()):
            break
        _, _, terminated, _, infos = env.step(stand(env))
    assert all(terminated.values())
    out = {agent: info["reward_terms"]["out"] for agent, info in infos.items()}
    assert out == {"blue_0": -1.0, "blue_1": -1.0, "red_0": 0.0, "red_1": 0.0}


def test_progress_is_each_teams_ball_distance_gain(env: TeamEnv) -> None:
    env.reset(seed=2)
    env.scene.place_ball(np.array([1.0, 0.5]))
    env.step(stand(env))
    before = env.world_state.ball.copy()
    env.scene.place_ball(np.array([2.0, 0.5]))
    *_, infos = env.step(stand(env))
    after = env.world_state.ball
    for goal_x, agent in ((DIMS.half_length_m, "blue_0"), (-DIMS.half_length_m, "red_1")):
        goal = np.array([goal_x, 0.0])
        expected = math.dist(before, goal) - math.dist(after, goal)
        assert infos[agent]["reward_terms"]["progress"] == pytest.approx(expected, abs=1e-9)


def test_truncated_after_the_episode_and_info_keeps_its_shapes(env: TeamEnv) -> None:
    rng = np.random.default_rng(0)
    _, first = env.reset(seed=6)
    shapes = {a: {k: np.shape(v) for k, v in flatten(i).items()} for a, i in first.items()}
    truncated: dict[str, bool] = {}
    for _ in range(20):
        actions = {a: rng.uniform(-1, 1, 5).astype(np.float32) for a in env.agents}
        obs, _, terminated, truncated, infos = env.step(actions)
        for agent, info in infos.items():
            assert {k: np.shape(v) for k, v in flatten(info).items()} == shapes[agent]
            assert env.observation_space(agent).contains(obs[agent])
        if all(terminated.values()):
            env.reset()
    assert all(truncated.values()) and env.agents == []


@pytest.mark.parametrize(
    ("overrides", "match"),
    [
        ({"self_pose": "circle_slam"}, r"\['self_pose'\] read the laser, but laser=None"),
        ({"task.max_tracked_robots": 17}, r"task.max_tracked_robots must be <= .*\(16"),
    ],
)
def test_a_team_config_that_cannot_run_is_refused_at_construction(
    overrides: dict[str, Any], match: str
) -> None:
    with pytest.raises(ValueError, match=match):
        team_v0.parallel_env(**FAST, **overrides)


def test_bad_actions_are_refused_naming_the_agent(env: TeamEnv) -> None:
    env.reset(seed=0)
    nan = {**stand(env), "red_1": np.array([0, np.nan, 0, 0, 0], dtype=np.float32)}
    with pytest.raises(ValueError, match="'red_1' must be finite"):
        env.step(nan)
    with pytest.raises(ValueError, match="no action for agent 'blue_1'"):
        env.step({a: STAND for a in ("blue_0", "red_0", "red_1")})
    with pytest.raises(ValueError, match=r"'blue_0' must have shape \(5,\)"):
        env.step({**stand(env), "blue_0": np.zeros(3)})
    with pytest.raises(ValueError, match="must lie in"):
        env.step({**stand(env), "red_0": np.full(5, 1.5)})
    with pytest.raises(ValueError, match="not in the episode"):
        env.step({**stand(env), "green_0": STAND})
    with pytest.raises(ValueError, match=r"not in the episode: \['x', 1\]"):  # keys of any type
        env.step({**stand(env), 1: STAND, "x": STAND})
    with pytest.raises(TypeError, match="'blue_0' must be an array of real numbers"):
        env.step({**stand(env), "blue_0": "abcde"})
    with pytest.raises(TypeError, match="actions must be a dict of agent name to action, got list"):
        env.step([STAND] * 4)
    env.step({**stand(env), "red_0": np.full(5, 1 + 5e-7)})  # a rounding error: the bound
    for seed, error in ((1.5, TypeError), (True, TypeError), (-1, ValueError)):
        with pytest.raises(error, match="seed must be an int >= 0"):
            env.reset(seed=seed)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("overrides", "error", "match"),
    [
        ({"players_per_side": 0}, ValueError, "players_per_side must be an int >= 1"),
        ({"players_per_side": 6}, ValueError, r"players_per_side must be an int in \[1, 5\]"),
        ({"players_per_side": 2.5}, TypeError, "players_per_side"),
        ({"sensors.laser": {}}, ValueError, "laser must be None"),
        ({"camera_mode": "geometric", "frontend": "cnn"}, ValueError, "frontend='colour'"),
        ({"n_other_robots": 3}, TypeError, "unknown config key"),
        ({"task.progress_weight": -1.0}, ValueError, "progress_weight"),
        ({"episode_s": 0.25}, ValueError, "whole number"),
    ],
)
def test_bad_configs_are_refused(overrides: dict[str, Any], error: type, match: str) -> None:
    with pytest.raises(error, match=match):
        team_v0.parallel_env(**overrides)


def test_render_draws_the_field_from_above(env: TeamEnv) -> None:
    with pytest.warns(Warning, match="render_mode=None"):
        assert env.render() is None
    drawn = team_v0.parallel_env(render_mode="rgb_array", **FAST)
    drawn.reset(seed=0)
    image = drawn.render()
    assert image is not None and image.dtype == np.uint8
    assert image.shape == (round(7.4 * 40), round(10.4 * 40), 3)
    drawn.close()
    with pytest.raises(ValueError, match="render_mode"):
        team_v0.parallel_env(render_mode="human", **FAST)
