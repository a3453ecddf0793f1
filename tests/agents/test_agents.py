"""Scripted baselines against their definitions; PPO runs on the env; the CLIs write their files."""

from __future__ import annotations

import argparse
import json
import math
import re
import shutil
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import pytest

import spl_env
from agents.baselines import BASELINES, FixedHead, HeadScan, LookAtStalest
from agents.demo import main as demo_main
from agents.evaluate import (
    EpisodeRecord,
    add_overrides_argument,
    default_policy,
    env_kwargs_for,
    episode_metrics,
    load_policy,
    parse_overrides,
    run_episode,
    summarise,
)
from agents.evaluate import main as evaluate_main
from agents.learning_curves import parse_baselines
from agents.train import check_config, default_config_path, load_config, train
from agents.train import main as train_main
from spl_env.envs.active_vision import ActiveVisionConfig
from spl_env.robots.nao import head_action, head_target

CONFIG = ActiveVisionConfig()
FAST_GOALIE = {"camera_mode": "geometric", "frontend": "colour"}
ROBOT = CONFIG.robot


def _obs(n: int = 6) -> dict[str, np.ndarray]:
    return {
        "landmarks_mask": np.zeros(n, np.float32),
        "landmarks_since_seen": np.ones(n, np.float32),
        "landmarks_cos_bearing": np.zeros(n, np.float32),
        "landmarks_sin_bearing": np.zeros(n, np.float32),
    }


@pytest.mark.parametrize("yaw_deg, pitch_deg", [(0, 0), (30, -10), (-119.5, 29.5), (90, -38.5)])
def test_look_inverts_the_envs_action_scaling(yaw_deg: float, pitch_deg: float) -> None:
    action = FixedHead.from_config(CONFIG).look(math.radians(yaw_deg), math.radians(pitch_deg))
    assert action.dtype == np.float32 and action.shape == (2,)
    target = head_target(ROBOT, action)
    np.testing.assert_allclose(np.degrees(target), [yaw_deg, pitch_deg], atol=1e-4)


def test_look_beyond_the_joint_limits_is_clipped_to_the_action_space() -> None:
    action = FixedHead.from_config(CONFIG).look(math.radians(150.0), math.radians(-60.0))
    np.testing.assert_array_equal(action, np.array([1.0, -1.0], np.float32))


def test_head_scan_is_the_sinusoid() -> None:
    policy = HeadScan.from_config(CONFIG)
    for k in range(40):
        action, _ = policy.predict(_obs(), episode_start=np.array([k == 0]))
        expected = (
            math.radians(90) * math.sin(2 * math.pi * 0.1 * k / 4.0) / ROBOT.head_yaw_limit_rad
        )
        assert action[0] == pytest.approx(expected, abs=1e-6)
        assert action[1] == pytest.approx(head_action(ROBOT, 0.0, 0.0)[1])
    first, _ = policy.predict(_obs(), episode_start=np.array([True]))  # a new episode restarts it
    assert first[0] == pytest.approx(0.0)


def test_look_at_stalest_points_at_least_recent_pole() -> None:
    obs = _obs()
    obs["landmarks_mask"][[1, 4]] = 1.0
    obs["landmarks_since_seen"][[1, 4]] = [0.2, 0.7]
    bearing = math.radians(30.0)
    obs["landmarks_cos_bearing"][4] = math.cos(bearing)
    obs["landmarks_sin_bearing"][4] = math.sin(bearing)
    action, _ = LookAtStalest.from_config(CONFIG).predict(obs)
    assert action[0] == pytest.approx(30.0 / 119.5, abs=1e-6)
    # a staler pole right behind the robot is out of the head's reach and is skipped
    obs["landmarks_mask"][5] = 1.0
    obs["landmarks_since_seen"][5] = 0.9
    obs["landmarks_cos_bearing"][5] = -1.0
    action, _ = LookAtStalest.from_config(CONFIG).predict(obs)
    assert action[0] == pytest.approx(30.0 / 119.5, abs=1e-6)


@pytest.mark.parametrize("env_id", spl_env.HEAD_CONTROL_ENV_IDS)
@pytest.mark.parametrize("name", sorted(BASELINES))
def test_baselines_run_on_every_env(env_id: str, name: str) -> None:
    env = gym.make(env_id, camera_mode="geometric", frontend="colour", episode_s=1.0)
    record = run_episode(env, load_policy(name, env.get_wrapper_attr("config")), seed=0)
    env.close()
    assert len(record.true_poses) == 11 and all(s > 0 for s in record.step_seconds[1:])


def test_evaluation_needs_the_full_info() -> None:
    env = gym.make(
        "SPL/LookAround-v0", camera_mode="geometric", frontend="colour", info_level="light"
    )
    with pytest.raises(ValueError, match="info_level='full'"):
        run_episode(env, load_policy("fixed", env.get_wrapper_attr("config")), seed=0)
    env.close()


def test_fixed_head_and_override_parsing() -> None:
    assert FixedHead.from_config(CONFIG).predict(_obs())[0][0] == 0.0
    with pytest.raises(ValueError, match="key=value"):
        parse_overrides(["episode_s"])
    assert parse_overrides(["episode_s=3", "body_behaviour=square"]) == {
        "episode_s": 3,
        "body_behaviour": "square",
    }


@pytest.mark.parametrize(
    "words",
    [
        ["--set", "episode_s=3", "body_behaviour=square"],
        ["--set", "episode_s=3", "--set", "body_behaviour=square"],
    ],
)
def test_set_takes_pairs_after_one_flag_or_the_flag_again(words: list[str]) -> None:
    parser = argparse.ArgumentParser()
    add_overrides_argument(parser)
    parser.add_argument("--out")
    args = parser.parse_args([*words, "--out", "x"])
    assert parse_overrides(args.set) == {"episode_s": 3, "body_behaviour": "square"}
    assert parser.parse_args([]).set == []


def _strict_json(path: Path) -> dict:
    """``path`` parsed as standard JSON: NaN and Infinity (which Python writes) are refused."""

    def refuse(token: str) -> None:
        raise ValueError(f"{path} holds {token}: not valid JSON")

    return json.loads(path.read_text(), parse_constant=refuse)


def test_a_no_poles_id_trains_with_its_pole_envs_config_and_a_missing_one_is_named() -> None:
    assert default_config_path("SPL/Striker-NoPoles-v0") == default_config_path("SPL/Striker-v0")
    assert default_config_path("SPL/ActiveVision-NoPoles-v1").name == "SPL_ActiveVision-v1.json"
    with pytest.raises(ValueError, match="no training config is shipped for env 'SPL/Goalie-v0'"):
        default_config_path("SPL/Goalie-v0")


@pytest.fixture(scope="module")
def trained_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A run directory with ``model.zip`` and ``config.json`` after 2048 PPO steps (~60 s)."""
    config = load_config(default_config_path("SPL/ActiveVision-v0"))
    config["env_kwargs"] = {"episode_s": 20.0}
    config["ppo"] = {**config["ppo"], "n_steps": 1024, "n_epochs": 1}
    out = tmp_path_factory.mktemp("ppo") / "run"
    train("SPL/ActiveVision-v0", config, 2048, out, seed=0)
    return out


def test_ppo_learn_2048_steps_smoke(trained_run: Path) -> None:
    """Plumbing only: PPO.learn runs 2048 steps on the env, saves, loads and acts in the action
    space. Nothing here says whether the policy got any better."""
    saved = json.loads((trained_run / "config.json").read_text())
    assert saved["timesteps"] == 2048 and saved["env_kwargs"] == {"episode_s": 20.0}
    assert "algorithm" not in saved  # the shipped config holds only keys train() reads
    from stable_baselines3 import PPO

    model = PPO.load(trained_run / "model.zip", device="cpu")
    assert model.num_timesteps == 2048
    env = gym.make("SPL/ActiveVision-v0", episode_s=1.0)
    obs, _ = env.reset(seed=0)
    action, _ = model.predict(obs, deterministic=True)
    assert env.action_space.contains(action)
    env.close()


def test_evaluate_uses_the_env_kwargs_saved_beside_the_model(
    trained_run: Path, tmp_path: Path
) -> None:
    run = tmp_path / "run"
    run.mkdir()
    shutil.copy(trained_run / "model.zip", run / "model.zip")
    (run / "config.json").write_text(json.dumps({"env_kwargs": {"episode_s": 1.0}}))
    model = str(run / "model.zip")
    evaluate_main(["--policy", model, "--episodes", "1", "--out", str(tmp_path / "a")])
    assert _strict_json(tmp_path / "a" / "metrics.json")["episodes"][0]["steps"] == 10
    evaluate_main(
        ["--policy", model, "--episodes", "1", "--out", str(tmp_path / "b"), "--set", "episode_s=2"]
    )
    assert _strict_json(tmp_path / "b" / "metrics.json")["episodes"][0]["steps"] == 20


def test_env_kwargs_for_merges_the_saved_config_under_the_overrides(tmp_path: Path) -> None:
    model = str(tmp_path / "model.zip")
    with pytest.raises(ValueError, match="no such model file"):
        env_kwargs_for(model, {})
    (tmp_path / "model.zip").write_bytes(b"")  # only its config beside it is read
    assert env_kwargs_for(model, {"episode_s": 3}) == {"episode_s": 3}  # no config.json beside it
    env_kwargs = {"episode_s": 2.0, "body_behaviour": "square"}
    config = {"policy": "MultiInputPolicy", "ppo": {}, "env_kwargs": env_kwargs}
    (tmp_path / "config.json").write_text(json.dumps(config))
    assert env_kwargs_for(model, {}) == {"episode_s": 2.0, "body_behaviour": "square"}
    assert env_kwargs_for(model, {"episode_s": 3}) == {"episode_s": 3, "body_behaviour": "square"}
    assert env_kwargs_for("scan", {"episode_s": 3}) == {"episode_s": 3}  # baselines: no config
    (tmp_path / "config.json").write_text(json.dumps({"policy": "MultiInputPolicy"}))
    with pytest.raises(ValueError, match="env_kwargs"):
        env_kwargs_for(model, {})


def test_evaluate_writes_metrics_and_plot(tmp_path: Path) -> None:
    evaluate_main(
        ["--policy", "scan", "--episodes", "2", "--out", str(tmp_path), "--set", "episode_s=2"]
    )
    result = _strict_json(tmp_path / "metrics.json")
    first, second = result["episodes"]
    assert first["steps"] == second["steps"] == 20
    assert first["mean_step_ms"] > 0 and second["mean_step_ms"] > 0
    assert first["mean_position_error_m"] != second["mean_position_error_m"]  # different seeds
    for key in ("return", "mean_position_error_m", "mean_odometry_error_m", "mean_pose_nees"):
        assert result["mean"][key] == pytest.approx((first[key] + second[key]) / 2)
    assert (tmp_path / "trajectory.png").stat().st_size > 0
    with pytest.raises(SystemExit):  # a usage error (the message: the test of CLI mistakes)
        evaluate_main(["--policy", "nonsense", "--episodes", "1", "--out", str(tmp_path)])


def _record(
    mapped: list[bool], estimates: np.ndarray, reward_terms: dict[str, float] | None = None
) -> EpisodeRecord:
    """Two steps at the origin, poles 3 and 5 at (1, 1) and (2, 2); the map in info's layout;
    the last step's ``reward_terms`` (a head task's by default)."""
    pose = np.zeros(3)
    ids = np.array([3, 5])
    return EpisodeRecord(
        true_poses=[pose, pose],
        slam_poses=[pose, pose],
        odometry_poses=[pose, pose],
        pose_covs=[np.eye(3), np.eye(3)],
        step_seconds=[0.0, 0.01],
        final_info={
            "ground_truth": {"landmark_ids": ids, "landmarks": np.array([[1.0, 1.0], [2.0, 2.0]])},
            "perception": {
                "landmark_ids": ids,
                "landmarks": estimates,
                "landmarks_mapped": np.array(mapped),
            },
            "reward_terms": reward_terms or {"position_error": -0.1},
        },
    )


@pytest.mark.parametrize(("goal", "scored"), [(10.0, 1.0), (0.0, 0.0), (-10.0, 0.0), (None, None)])
def test_scored_says_whether_the_episode_ended_in_our_goal(
    goal: float | None, scored: float | None
) -> None:
    terms = {"time": -0.01} if goal is None else {"goal": goal, "time": -0.01}
    metrics = episode_metrics(_record([True, True], np.ones((2, 2)), terms))
    assert metrics["scored"] == scored


def test_only_mapped_landmarks_are_scored() -> None:
    metrics = episode_metrics(_record([False, True], np.array([[0.0, 0.0], [2.0, 2.5]])))
    assert metrics["landmarks_mapped"] == 1
    assert metrics["mean_landmark_error_m"] == pytest.approx(0.5)


def test_no_mapped_landmark_is_null_not_nan() -> None:
    metrics = episode_metrics(_record([False, False], np.zeros((2, 2))))
    assert metrics["landmarks_mapped"] == 0 and metrics["mean_landmark_error_m"] is None
    assert "null" in json.dumps(metrics, allow_nan=False)
    mapped = {**metrics, "mean_landmark_error_m": 0.3}
    assert summarise([metrics, metrics])["mean_landmark_error_m"] is None
    assert summarise([metrics, mapped])["mean_landmark_error_m"] == pytest.approx(0.3)


def test_demo_writes_its_pictures_and_metrics(tmp_path: Path) -> None:
    demo_main(["--out", str(tmp_path), "--frames", "2", "--set", "episode_s=1"])
    assert _strict_json(tmp_path / "metrics.json")["steps"] == 10
    for name in ("frames.png", "trajectory.png"):
        assert (tmp_path / name).stat().st_size > 0


@pytest.mark.parametrize(
    "main, argv, flag",
    [
        (evaluate_main, ["--episodes", "0"], "--episodes"),
        (demo_main, ["--frames", "0"], "--frames"),
    ],
)
def test_cli_counts_below_one_are_usage_errors(
    main, argv: list[str], flag: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit) as exit_info:
        main([*argv, "--out", str(tmp_path)])
    assert exit_info.value.code == 2
    assert f"{flag} must be >= 1" in capsys.readouterr().err


GEOMETRIC = ["--set", "camera_mode=geometric", "frontend=colour", "episode_s=1"]


@pytest.mark.parametrize(
    ("main", "argv", "message"),
    [
        (evaluate_main, ["--env", "SPL/Nope-v0"], "Environment `Nope` doesn't exist"),
        (evaluate_main, ["--policy", "nope"], "policy must be one of"),
        (evaluate_main, ["--set", "=3"], "--set takes key=value, got '=3'"),
        (evaluate_main, [*GEOMETRIC, "episode_s=2"], "--set gives 'episode_s' twice"),
        (evaluate_main, [*GEOMETRIC, "nosuchkey=3"], "unknown config key 'nosuchkey'"),
        (evaluate_main, ["--seed", "-1"], "--seed must be >= 0, got -1"),
        (evaluate_main, ["--env", "SPL/Striker-v0", "--policy", "scan"], "'scan' moves the head"),
        (
            evaluate_main,
            ["--env", "SPL/ActiveVision-v1", "--policy", "centre_kick"],
            "'centre_kick' plays soccer",
        ),
        (
            evaluate_main,
            ["--env", "SPL/ActiveVision-v0", "--policy", "pretrained:active_vision", *GEOMETRIC],
            r"trained on other observations .*lacks: \['robots_cos_bearing'",
        ),
        (
            demo_main,
            ["--env", "SPL/ActiveVision-v0", "--policy", "pretrained:striker", *GEOMETRIC],
            "trained on striker options; it cannot play this head env",
        ),
        (
            evaluate_main,
            ["--env", "SPL/Striker-v0", "--policy", "pretrained:active_vision", *GEOMETRIC],
            r"trained on SPL/ActiveVision-v1 and carries its settings, which SPL/Striker-v0 "
            r"refuses \(unknown config key 'task.information_weight'",
        ),
        (evaluate_main, [*GEOMETRIC, "info_level=light"], "info_level must stay 'full'"),
        (demo_main, [*GEOMETRIC, "info_level=light"], "info_level must stay 'full'"),
        (evaluate_main, ["--env", "Circles/Office-v0"], r"WaypointDriver"),
        (train_main, ["--timesteps", "0"], "--timesteps must be >= 1, got 0"),
        (train_main, ["--env", "SPL/Nope-v0"], "no env 'SPL/Nope-v0' is registered"),
        (train_main, ["--set", "bogus=1"], "unknown config key 'bogus'"),
    ],
)
def test_cli_mistakes_end_in_one_line_before_any_episode(
    main, argv: list[str], message: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """A user's mistake is a usage error (exit 2) with its message, not a traceback."""
    with pytest.raises(SystemExit) as exit_info:
        main([*argv, "--out", str(tmp_path / "out")])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert re.search(message, err), err
    assert "Traceback" not in err


def test_a_training_config_that_is_not_json_is_named(tmp_path: Path) -> None:
    path = tmp_path / "bad.json"
    path.write_text("{x")
    with pytest.raises(ValueError, match=f"training config {re.escape(str(path))} is not valid"):
        load_config(path)


def test_a_soccer_env_plays_its_own_scripted_player_by_default(tmp_path: Path) -> None:
    evaluate_main(
        ["--env", "SPL/Striker-v0", "--episodes", "1", "--out", str(tmp_path), *GEOMETRIC]
    )
    assert json.loads((tmp_path / "metrics.json").read_text())["policy"] == "centre_kick"
    goalie = gym.make("SPL/Goalie-v0", **FAST_GOALIE)
    assert default_policy(goalie.get_wrapper_attr("config")) == "goalie"
    goalie.close()
    assert default_policy(CONFIG) == "scan"


def test_override_pairs_are_refused_without_a_key_or_twice() -> None:
    with pytest.raises(ValueError, match="key=value, got '=3'"):
        parse_overrides(["=3"])
    with pytest.raises(ValueError, match="'episode_s' twice"):
        parse_overrides(["episode_s=3", "episode_s=4"])


@pytest.mark.parametrize("pair", ["scan", "scan=abc", "scan=nan", "=1"])
def test_learning_curve_baselines_must_be_finite_named_values(pair: str) -> None:
    with pytest.raises(ValueError, match="NAME=VALUE with a finite VALUE"):
        parse_baselines([pair])


@pytest.mark.parametrize(
    ("change", "match"),
    [
        ({"n_envs": 0}, "n_envs must be an int >= 1, got 0"),
        ({"n_envs": True}, "n_envs must be an int >= 1, got True"),
        ({"options": "yes"}, r"options must be one of \['head', 'striker'\], got 'yes'"),
        ({"options": "head", "warm_start": {}}, "options or warm_start, not both"),
        ({"head_options": True}, 'head_options is now "options": "head"'),
        ({"warm_start": {"teacher": "nonsense"}}, "teacher"),
    ],
)
def test_training_config_refuses_bad_options(change: dict[str, Any], match: str) -> None:
    config = {**load_config(default_config_path("SPL/ActiveVision-v0")), **change}
    with pytest.raises(ValueError, match=match):
        check_config(config)
    with pytest.raises(ValueError, match=match):  # before any env process starts
        train("SPL/ActiveVision-v0", config, 16, Path("unused"), seed=0)


def test_a_warm_start_on_an_env_whose_action_is_not_the_head_is_refused_at_once() -> None:
    """The warm start imitates a scripted head policy: on a soccer env it is refused before
    any env or model is made (it had failed later, on the teacher's action shape)."""
    config = {**load_config(default_config_path("SPL/ActiveVision-v0")), "warm_start": {}}
    with pytest.raises(ValueError, match=r"warm_start imitates a scripted head policy.*Striker"):
        train("SPL/Striker-v0", config, 16, Path("unused"), seed=0)
