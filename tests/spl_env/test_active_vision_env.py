"""Gymnasium contract of every registered env id: checkers, spaces, resets, bad input.

Same-seed determinism, light info and the step timings are tested on the env core
(``test_env_core.py``, ``test_core_step.py``)."""

from __future__ import annotations

import warnings
from collections.abc import Iterator

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env as gym_check_env

from spl_env import HEAD_CONTROL_ENV_IDS as ENV_IDS

FAST = {"episode_s": 3.0}  # 30 steps: short episodes keep the suite quick


@pytest.fixture(params=ENV_IDS)
def env(request: pytest.FixtureRequest) -> Iterator[gym.Env]:
    e = gym.make(request.param, render_mode="rgb_array", **FAST)
    yield e
    e.close()


def test_gymnasium_check_env_without_warnings(env: gym.Env) -> None:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        gym_check_env(env.unwrapped, skip_render_check=False)
    assert [str(w.message) for w in caught] == []


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_sb3_check_env_without_warnings(env_id: str) -> None:
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    e = gym.make(env_id, **FAST)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        sb3_check_env(e.unwrapped, warn=True)
    e.close()
    assert [str(w.message) for w in caught] == []


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_random_rollout_stays_inside_observation_space(env_id: str) -> None:
    e = gym.make(env_id, episode_s=30.0)
    e.action_space.seed(1)
    obs, info = e.reset(seed=1)
    assert e.observation_space.contains(obs)
    for _ in range(300):
        obs, reward, terminated, truncated, info = e.step(e.action_space.sample())
        assert e.observation_space.contains(obs), {k: (v.min(), v.max()) for k, v in obs.items()}
        assert np.isfinite(reward)
        assert reward == pytest.approx(sum(info["reward_terms"].values()))
        cov = info["perception"]["pose_cov"]
        np.testing.assert_allclose(cov, cov.T, atol=1e-12)
        assert np.linalg.eigvalsh(cov).min() >= -1e-12
        if terminated or truncated:
            obs, info = e.reset()
    e.close()


def test_reset_with_same_seed_repeats_episode(env: gym.Env) -> None:
    a = np.array([0.5, 0.0], dtype=np.float32)

    def episode(seed: int) -> list[dict[str, np.ndarray]]:
        env.reset(seed=seed)
        return [env.step(a)[0] for _ in range(5)]

    first = episode(3)
    other = episode(4)  # a different episode in between must leave no trace
    second = episode(3)
    assert any(
        not np.array_equal(f["self_pose_field"], o["self_pose_field"])
        for f, o in zip(first, other, strict=True)
    )
    for f, s in zip(first, second, strict=True):
        for key in f:
            np.testing.assert_array_equal(f[key], s[key])


def test_info_contract(env: gym.Env) -> None:
    _, first = env.reset(seed=0)
    _, _, _, _, info = env.step(env.action_space.sample())
    assert set(info) == set(first) == {"perception", "ground_truth", "reward_terms"}
    assert "timing" not in info  # only with info_timing=True
    per, gt = info["perception"], info["ground_truth"]
    n = len(per["landmark_ids"])
    assert n == (0 if "NoPoles" in env.spec.id else 6)
    shapes = {
        "pose": (3,),
        "pose_cov": (3, 3),
        "odometry_pose": (3,),
        "odometry_delta": (3,),
        "walk_odometry_delta": (3,),
        "visual_heading": (),
        "visual_heading_confidence": (),
        "collision": (),
        "landmark_ids": (n,),
        "landmarks": (n, 2),
        "landmark_covs": (n, 2, 2),
        "landmarks_mapped": (n,),
    }
    if n:  # the pole sightings
        shapes |= {"sightings": (n, 2), "sighted": (n,)}
    else:  # the field features the pose comes from, 32 rows
        shapes |= {
            "field_features": (32, 2, 2),
            "field_feature_covs": (32, 2, 2, 2),
            "field_feature_kinds": (32,),
            "field_feature_directions": (32,),
            "field_feature_has_direction": (32,),
            "field_features_count": (),
        }
    tracks_robots = env.spec is not None and env.spec.id.startswith("SPL/ActiveVision-")
    tracks_robots &= env.spec is not None and env.spec.id.endswith("-v1")
    if tracks_robots:  # v1 adds the confirmed robot tracks, 16 rows
        k = env.unwrapped.config.perception.robot_tracker.max_tracks
        shapes |= {
            "robots": (k, 2),
            "robot_velocities": (k, 2),
            "robot_covs": (k, 2, 2),
            "robot_teams": (k,),
            "robot_track_ids": (k,),
            "robots_tracked": (k,),
        }
    assert {k: v.shape for k, v in per.items()} == shapes
    assert per["landmarks_mapped"].dtype == np.bool_
    assert np.all(per["landmarks"][~per["landmarks_mapped"]] == 0.0)
    assert np.all(per["landmark_covs"][~per["landmarks_mapped"]] == 0.0)
    if n:
        assert per["sighted"].dtype == np.bool_
        assert np.all(per["sightings"][~per["sighted"]] == 0.0)
    n_others = env.unwrapped.config.task.n_other_robots
    assert {k: v.shape for k, v in gt.items()} == {
        "robot_pose": (3,),
        "head": (2,),
        "landmarks": (n, 2),
        "landmark_ids": (n,),
        "robots": (n_others, 3),
        "robot_teams": (n_others,),
        "ball": (2,),
        "ball_velocity": (2,),
        "circles": (4 + n, 3),  # 4 goal posts and the poles
    }
    np.testing.assert_array_equal(per["landmark_ids"], gt["landmark_ids"])
    # every entry keeps its shape from step to step (vector envs stack them)
    for part in ("perception", "ground_truth"):
        for key, value in info[part].items():
            assert np.shape(first[part][key]) == np.shape(value), key
    terms = {"position_error", "uncertainty", "information"}
    terms |= {"robot_awareness"} if tracks_robots else set()
    assert set(info["reward_terms"]) == terms


def test_information_term_pays_for_the_fall_of_the_position_std() -> None:
    env = gym.make(
        "SPL/ActiveVision-v0",
        camera_mode="geometric",
        frontend="colour",
        episode_s=10.0,
        **{"task.information_weight": 4.0},
    )
    _, info = env.reset(seed=5)
    assert info["reward_terms"]["information"] == 0.0  # no previous step at time 0
    std = float(np.sqrt(np.trace(info["perception"]["pose_cov"][:2, :2])))
    fell = rose = False
    for k in range(100):  # a head sweep: poles come into view and leave it
        info = env.step(np.array([np.sin(k / 4), 0.0], dtype=np.float32))[4]
        new_std = float(np.sqrt(np.trace(info["perception"]["pose_cov"][:2, :2])))
        assert info["reward_terms"]["information"] == pytest.approx(4.0 * (std - new_std))
        assert info["reward_terms"]["uncertainty"] == pytest.approx(-0.5 * new_std)
        fell, rose = fell or new_std < std, rose or new_std > std
        std = new_std
    assert fell and rose  # sightings shrink the std, walking without them grows it
    _, info = env.reset(seed=6)  # a new episode: the first step compares with its reset's std
    assert info["reward_terms"]["information"] == 0.0
    reset_std = float(np.sqrt(np.trace(info["perception"]["pose_cov"][:2, :2])))
    info = env.step(np.array([0.0, 0.0], dtype=np.float32))[4]
    new_std = float(np.sqrt(np.trace(info["perception"]["pose_cov"][:2, :2])))
    assert info["reward_terms"]["information"] == pytest.approx(4.0 * (reset_std - new_std))
    env.close()


def test_truncates_after_episode_length(env: gym.Env) -> None:
    env.reset(seed=0)
    steps, truncated = 0, False
    while not truncated:
        *_, terminated, truncated, _ = env.step(np.zeros(2, dtype=np.float32))
        assert not terminated
        steps += 1
    assert steps == 30


def test_render_returns_rgb_image(env: gym.Env) -> None:
    env.reset(seed=0)
    env.step(env.action_space.sample())
    image = env.render()
    assert image.dtype == np.uint8 and image.ndim == 3 and image.shape[2] == 3
    assert image.shape[0] > 100 and image.shape[1] > 100


def test_close_twice(env: gym.Env) -> None:
    env.reset(seed=0)
    env.close()
    env.close()


@pytest.mark.parametrize(
    "action, match",
    [
        (np.array([np.nan, 0.0], dtype=np.float32), "finite"),
        (np.array([1.5, 0.0], dtype=np.float32), r"\[-1, 1\]"),
        (np.zeros(3, dtype=np.float32), "shape"),
        ([[0.0], 0.0], r"action must be an array of shape \(2,\)"),  # ragged nesting
    ],
)
def test_bad_actions_raise(env: gym.Env, action: np.ndarray, match: str) -> None:
    env.reset(seed=0)
    with pytest.raises(ValueError, match=match):
        env.step(action)


GEOMETRIC = {"camera_mode": "geometric", "frontend": "colour", **FAST}


def test_actions_of_other_than_real_numbers_raise_type_errors() -> None:
    env = gym.make(ENV_IDS[0], **GEOMETRIC)
    env.reset(seed=0)
    for action in ("ab", {"yaw": 0.0}, ["0", "0"], np.ones(2, bool), np.zeros(2) + 1j):
        with pytest.raises(TypeError, match="action must be an array of real numbers"):
            env.step(action)
    env.close()


def test_an_action_a_rounding_error_outside_the_box_acts_as_the_bound() -> None:
    """Within 1e-6 outside a bound the action is the bound: the same step as on it."""
    outside, on = (gym.make(ENV_IDS[0], **GEOMETRIC) for _ in range(2))
    outside.reset(seed=3)
    on.reset(seed=3)
    a = outside.step(np.array([1 + 5e-7, -1 - 5e-7]))[0]
    b = on.step(np.array([1.0, -1.0]))[0]
    for key in a:
        np.testing.assert_array_equal(a[key], b[key])
    outside.close()
    on.close()


def test_step_before_reset_raises() -> None:
    e = gym.make(ENV_IDS[0], **FAST)
    with pytest.raises(gym.error.ResetNeeded):
        e.step(np.zeros(2, dtype=np.float32))
    with pytest.raises(RuntimeError, match="reset"):
        e.unwrapped.step(np.zeros(2, dtype=np.float32))
    e.close()


def test_make_kwargs_override_config_fields() -> None:
    e = gym.make(ENV_IDS[0], episode_s=2.0, n_other_robots=1, **{"sensors.camera.noise_std": 0.0})
    cfg = e.unwrapped.config
    assert cfg.task.episode_s == 2.0 and cfg.task.n_other_robots == 1
    assert cfg.sensors.camera.noise_std == 0.0 and cfg.max_steps == 20
    e.close()
    with pytest.raises(TypeError, match="unknown config key 'no_such_field'"):
        gym.make(ENV_IDS[0], no_such_field=1)
    with pytest.raises(TypeError, match=r"did you mean.*'sensors\.camera\.noise_std'"):
        gym.make(ENV_IDS[0], noise_std=0.0)
    with pytest.raises(ValueError, match="episode_s"):
        gym.make(ENV_IDS[0], episode_s=-1.0)


def test_every_id_is_registered_with_its_own_env_class() -> None:
    from spl_env.envs.active_vision import ActiveVisionEnv
    from spl_env.envs.active_vision_robots import ActiveVisionRobotsEnv
    from spl_env.envs.look_around import LookAroundEnv

    assert ENV_IDS == (
        "SPL/ActiveVision-v0",
        "SPL/ActiveVision-v1",
        "SPL/LookAround-v0",
        "SPL/ActiveVision-NoPoles-v1",
        "SPL/LookAround-NoPoles-v0",
    )
    classes = []
    for env_id in ENV_IDS:
        e = gym.make(env_id, **FAST)
        classes.append(type(e.unwrapped))
        assert e.spec is not None and e.spec.id == env_id
        e.close()
    assert classes == [
        ActiveVisionEnv,
        ActiveVisionRobotsEnv,
        LookAroundEnv,
        ActiveVisionRobotsEnv,
        LookAroundEnv,
    ]


@pytest.mark.parametrize("clockwise", [False, True])
def test_the_square_walk_goes_round_in_the_sense_asked_for(clockwise: bool) -> None:
    env = gym.make(
        "SPL/ActiveVision-v1",
        camera_mode="geometric",
        frontend="colour",
        body_behaviour="square",
        square_side_m=1.0,
        n_other_robots=0,  # nothing to block the walk
        **{"task.square_clockwise": clockwise},
    )
    env.reset(seed=4)
    robot = env.unwrapped.robots[0]
    path = [robot.pose.copy()]
    for _ in range(400):  # a lap: four 6.7 s legs and four turns
        env.step(np.zeros(2, dtype=np.float32))
        path.append(robot.pose.copy())
    xy = np.array(path)[:, :2] - path[0][:2]
    # the signed area the path sweeps (shoelace): positive counter-clockwise
    area = 0.5 * float(np.sum(xy[:-1, 0] * xy[1:, 1] - xy[1:, 0] * xy[:-1, 1]))
    assert (area < -0.5) if clockwise else (area > 0.5)  # a lap sweeps about 1 m2, signed
    env.close()
