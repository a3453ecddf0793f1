"""The env core's step loop (:class:`spl_env.envs.core.SplEnv`): motion-blur turn rate, walking
with collisions, blocked robots whose odometry slips, resets, the clock and the step timings.

Our robot's body is driven by replacing the task's :meth:`walk` (and the other robots'
commands), so that each check knows the commanded motion exactly.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np
import pytest

from perception.geometry import wrap_angle
from perception.representations import POLE_SIGHTINGS, SELF_POSE
from spl_env.envs.look_around import LookAroundEnv
from spl_env.robots.nao import NaoCommand

FAST: dict[str, Any] = {"episode_s": 3.0, "frontend": "colour"}
LEVEL = np.zeros(2, dtype=np.float32)  # head action: yaw 0 (pitch a little up)


def drive(
    monkeypatch: pytest.MonkeyPatch,
    env: LookAroundEnv,
    start: tuple[float, float, float],
    walk: tuple[float, float, float],
    others_stand: bool = True,
) -> None:
    """Make our robot start at ``start`` and walk at ``walk`` (vx, vy, omega); the others stand."""
    task = env.task
    monkeypatch.setattr(task, "start_pose", lambda rng: np.array(start))
    monkeypatch.setattr(task, "walk", lambda state: np.array(walk))
    if others_stand:
        monkeypatch.setattr(
            task, "scripted_commands", lambda state: [NaoCommand() for _ in state.others]
        )


@pytest.fixture
def lone() -> Iterator[LookAroundEnv]:
    env = LookAroundEnv(n_other_robots=0, **FAST)
    yield env
    env.close()


def test_camera_turn_rate_is_wrapped_across_pi(
    monkeypatch: pytest.MonkeyPatch, lone: LookAroundEnv
) -> None:
    drive(monkeypatch, lone, (0.0, 0.0, math.pi - 0.02), (0.0, 0.0, 0.5))
    rates: list[float] = []
    render = lone.rig.camera.render

    def spy(
        world: Any, position: Any, rotation: Any, lighting: Any, rng: Any, yaw_rate_rps: float = 0.0
    ) -> Any:
        rates.append(yaw_rate_rps)
        return render(world, position, rotation, lighting, rng, yaw_rate_rps=yaw_rate_rps)

    monkeypatch.setattr(lone.rig.camera, "render", spy)
    lone.reset(seed=0)
    for _ in range(10):  # turn left in place through +pi
        lone.step(LEVEL)
    assert lone.world_state.robot_pose[2] < 0  # it did cross
    assert len(rates) == 11  # one frame per reset and per step
    assert max(abs(r) for r in rates) <= 0.5 + 1e-9
    # reset, then the 2 rad/s^2 acceleration limit ramps 0.2, 0.4 up to the commanded 0.5 rad/s
    assert rates[:4] == pytest.approx([0.0, 0.2, 0.4, 0.5])
    assert rates[-1] == pytest.approx(0.5)


def test_head_turns_count_in_the_camera_turn_rate(
    monkeypatch: pytest.MonkeyPatch, lone: LookAroundEnv
) -> None:
    drive(monkeypatch, lone, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    rates: list[float] = []
    render = lone.rig.camera.render
    monkeypatch.setattr(
        lone.rig.camera,
        "render",
        lambda *args, yaw_rate_rps=0.0: (
            rates.append(yaw_rate_rps) or render(*args, yaw_rate_rps=yaw_rate_rps)
        ),
    )
    lone.reset(seed=0)
    for _ in range(3):
        lone.step(np.array([1.0, 0.0], dtype=np.float32))  # head towards +119.5°
    # the head turns at its 4 rad/s limit while the body stands
    assert rates == pytest.approx([0.0, 4.0, 4.0, 4.0])


def test_walking_into_a_robot_blocks_without_overlap_while_odometry_slips(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    env = LookAroundEnv(n_other_robots=1, **FAST)
    drive(monkeypatch, env, (0.0, 0.0, 0.0), (0.25, 0.0, 0.0))
    env.reset(seed=0)
    env.robots[1].place(np.array([0.4, 0.0, math.pi]))  # 0.4 m straight ahead, facing us
    r = env.config.robot.body_radius_m
    blocked_steps, odometry_forward_while_blocked = 0, 0.0
    for _ in range(20):
        before = env.robots[0].pose.copy()
        env.step(LEVEL)
        state, frame = env.world_state, env.sensor_frame
        assert math.dist(state.robot_pose[:2], state.robots[0, :2]) >= 2 * r - 1e-9
        assert not state.blocked[1]  # the other one stands: it bumps into nothing
        if state.blocked[state.agent]:
            blocked_steps += 1
            np.testing.assert_allclose(state.robot_pose, before)  # the body did not move...
            assert frame.odometry_delta is not None
            odometry_forward_while_blocked += float(frame.odometry_delta[0])
    env.close()
    assert blocked_steps >= 5  # 0.1 m of gap closes within ~7 steps at <= 0.25 m/s
    # ...but the walk engine believes it stepped, so odometry keeps reporting forward motion
    assert odometry_forward_while_blocked > 0.02


def test_walking_off_the_carpet_is_blocked_at_its_edge(monkeypatch: pytest.MonkeyPatch) -> None:
    env = LookAroundEnv(n_other_robots=0, camera_mode="geometric", **FAST)
    drive(monkeypatch, env, (4.6, 2.0, 0.0), (0.25, 0.0, 0.0))
    env.reset(seed=0)
    edge = env.scene.dimensions.carpet_size_m[0] / 2 - env.config.robot.body_radius_m
    blocked = 0
    for _ in range(30):
        env.step(LEVEL)
        assert env.world_state.robot_pose[0] <= edge
        blocked += bool(env.world_state.blocked[0])
    assert blocked >= 5 and env.world_state.robot_pose[0] > edge - 0.03  # it reached the edge
    env.close()


def test_scripted_robots_walk_about_without_ever_overlapping() -> None:
    env = LookAroundEnv(camera_mode="geometric", **FAST)  # four others walking about
    env.reset(seed=4)
    start = env.world_state.poses.copy()
    r = env.config.robot.body_radius_m
    carpet_l, carpet_w = env.scene.dimensions.carpet_size_m
    for _ in range(30):
        env.step(LEVEL)
        poses = env.world_state.poses
        gaps = np.hypot(*(poses[:, None, :2] - poses[None, :, :2]).transpose(2, 0, 1))
        assert gaps[np.triu_indices(len(poses), 1)].min() >= 2 * r - 1e-9
        assert np.all(np.abs(poses[:, 0]) <= carpet_l / 2 - r)
        assert np.all(np.abs(poses[:, 1]) <= carpet_w / 2 - r)
        posts = env.scene.obstacles
        clear = np.hypot(poses[:, None, 0] - posts[:, 0], poses[:, None, 1] - posts[:, 1])
        assert np.all(clear >= r + posts[:, 2] - 1e-9)
    change = env.world_state.poses[1:] - start[1:]
    moved = np.hypot(change[:, 0], change[:, 1]) + np.abs(wrap_angle(change[:, 2]))
    assert np.all(moved > 0.05)  # the others did walk (or turn towards their waypoint)
    np.testing.assert_allclose(env.world_state.poses[0], start[0])  # we stood (LookAround)
    env.close()


def _episode(env: LookAroundEnv, seed: int, steps: int = 4) -> list[dict[str, Any]]:
    """Truth, sensor readings and belief of each frame of an episode (reset included)."""
    actions = np.random.default_rng(7).uniform(-1, 1, size=(steps, 2)).astype(np.float32)
    env.reset(seed=seed)
    records = []
    for k in range(steps + 1):
        if k:
            env.step(actions[k - 1])
        state, frame, output = env.world_state, env.sensor_frame, env.perception_output
        records.append(
            {
                "poses": state.poses.copy(),
                "heads": state.heads.copy(),
                "ball": state.ball.copy(),
                "odometry_delta": frame.odometry_delta.copy(),
                "image": frame.image.copy(),
                "sonar": frame.sonar.copy(),
                "pose": output[SELF_POSE].pose.copy(),
            }
        )
    return records


def _assert_same(first: list[dict[str, Any]], second: list[dict[str, Any]]) -> None:
    for a, b in zip(first, second, strict=True):
        for key in a:
            np.testing.assert_array_equal(a[key], b[key], err_msg=key)


def test_reset_repeats_the_episode_and_leaves_no_trace() -> None:
    env = LookAroundEnv(n_other_robots=2, **FAST)
    first = _episode(env, seed=5)
    other = _episode(env, seed=6)  # a different episode in between must leave no trace
    again = _episode(env, seed=5)
    env.close()
    fresh = LookAroundEnv(n_other_robots=2, **FAST)
    new_env = _episode(fresh, seed=5)
    fresh.close()
    _assert_same(first, again)
    _assert_same(first, new_env)
    assert not np.array_equal(first[0]["poses"], other[0]["poses"])
    assert not np.array_equal(first[-1]["image"], other[-1]["image"])


def test_the_clock_advances_one_control_step_per_step() -> None:
    env = LookAroundEnv(n_other_robots=0, control_dt_s=0.2, physics_dt_s=0.05, **FAST)
    assert env.config.substeps == 4 and env.config.max_steps == 15
    env.reset(seed=0)
    for k in range(4):
        if k:
            env.step(LEVEL)
        expected = 0.2 * k
        assert env.world_state.time_s == pytest.approx(expected)
        assert env.sensor_frame.time_s == pytest.approx(expected)
        assert env.perception_output.time_s == pytest.approx(expected)
    env.reset(seed=1)
    assert env.world_state.time_s == 0.0
    env.close()


def test_a_rolling_ball_moves_with_the_physics_substeps() -> None:
    env = LookAroundEnv(n_other_robots=0, control_dt_s=0.2, physics_dt_s=0.05, **FAST)
    env.reset(seed=0)
    env.scene.place_ball(np.array([-3.0, 2.0]), np.array([1.0, -0.5]))
    heading = np.array([1.0, -0.5]) / math.hypot(1.0, -0.5)
    xy, speed = np.array([-3.0, 2.0]), math.hypot(1.0, -0.5)
    for _ in range(3):
        env.step(LEVEL)
        ball, velocity = env.world_state.ball, env.world_state.ball_velocity
        step = ball - xy
        # it rolls on along its direction, no faster than it was set going
        assert step[0] * heading[1] - step[1] * heading[0] == pytest.approx(0.0, abs=1e-3)
        assert 0.0 < step @ heading <= speed * 0.2 + 1e-9
        assert 0.0 < np.hypot(*velocity) <= speed + 1e-9
        xy, speed = ball.copy(), float(np.hypot(*velocity))
    env.close()


def test_world_state_names_every_robot_and_ours_first() -> None:
    env = LookAroundEnv(n_other_robots=3, camera_mode="geometric", **FAST)
    env.reset(seed=2)
    state = env.world_state
    assert state.agent == 0 and state.names[0] == "self" and state.kinds == ("nao",) * 4
    assert state.teams[0] == 0 and set(state.teams[1:]) <= {0, 1}
    assert state.poses.shape == (4, 3) and state.heads.shape == (4, 2)
    assert state.blocked.shape == (4,) and state.blocked.dtype == np.bool_
    np.testing.assert_array_equal(state.others, [1, 2, 3])
    np.testing.assert_array_equal(state.robots, state.poses[1:])
    np.testing.assert_array_equal(state.robot_teams, state.teams[1:])
    np.testing.assert_array_equal(state.robot_pose, env.robots[0].pose)
    np.testing.assert_array_equal(state.head, env.robots[0].head)
    truth = state.truth_for(2)
    np.testing.assert_array_equal(truth.robot_pose, env.robots[2].pose)
    np.testing.assert_array_equal(truth.landmarks, env.scene.landmarks)
    np.testing.assert_array_equal(truth.landmark_ids, env.scene.landmark_ids)
    others = [r for k, r in enumerate(env.robots) if k != 2]  # everyone but robot 2, in order
    np.testing.assert_array_equal(truth.robots, [r.pose[:2] for r in others])
    np.testing.assert_array_equal(truth.robot_teams, [r.team for r in others])
    env.close()


def test_perception_runs_on_the_core_pipeline_once_per_step(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    env = LookAroundEnv(n_other_robots=0, **FAST)
    pipeline = env.pipeline
    assert set(pipeline.representations) >= {POLE_SIGHTINGS, SELF_POSE}
    calls: dict[str, list[float]] = {name: [] for name in pipeline.representations}

    def counting(name: str, update: Callable[..., Any]) -> Callable[..., Any]:
        def spy(inputs: Any, time_s: float) -> Any:
            calls[name].append(time_s)
            return update(inputs, time_s)

        return spy

    for name in pipeline.representations:
        provider = pipeline.provider(name)
        monkeypatch.setattr(provider, "update", counting(name, provider.update))
    _, info = env.reset(seed=0)
    assert calls == {name: [0.0] for name in calls}  # once each at reset
    slam = pipeline.provider(SELF_POSE).slam
    for k in range(1, 4):
        *_, info = env.step(LEVEL)
        assert env.pipeline is pipeline and pipeline.provider(SELF_POSE).slam is slam
        for name, times in calls.items():  # once each per step, at the step's time
            assert times == pytest.approx([0.1 * j for j in range(k + 1)]), name
        np.testing.assert_array_equal(info["perception"]["pose"], slam.estimate().pose)
        np.testing.assert_array_equal(env.perception_output[SELF_POSE].pose, slam.estimate().pose)
    env.reset(seed=1)
    assert all(len(times) == 5 and times[-1] == 0.0 for times in calls.values())
    env.close()


@pytest.mark.parametrize("camera_mode", ["rendered", "geometric"])
def test_step_timings_are_reported_only_when_asked(camera_mode: str) -> None:
    plain = LookAroundEnv(n_other_robots=1, camera_mode=camera_mode, **FAST)
    _, info = plain.reset(seed=0)
    assert "timing" not in info
    assert "timing" not in plain.step(LEVEL)[-1]
    plain.close()
    timed = LookAroundEnv(n_other_robots=1, camera_mode=camera_mode, info_timing=True, **FAST)
    _, info = timed.reset(seed=0)
    for _ in range(2):
        timing = info["timing"]
        assert type(timing) is dict
        assert set(timing) == {"physics", "render", "sensors", "perception"}
        assert all(type(s) is float and s >= 0.0 for s in timing.values())
        assert timing == timed.step_times and timing is not timed.step_times
        *_, info = timed.step(LEVEL)
    assert info["timing"]["physics"] > 0.0  # a step does physics; a reset does none
    timed.close()


def test_inspection_and_step_before_reset_raise() -> None:
    env = LookAroundEnv(n_other_robots=0, **FAST)
    for name in ("sensor_frame", "perception_output", "world_state"):
        with pytest.raises(RuntimeError, match="reset"):
            getattr(env, name)
    with pytest.raises(RuntimeError, match="reset"):
        env.step(LEVEL)
    with pytest.raises(ValueError, match="render_mode"):
        LookAroundEnv(render_mode="human", **FAST)
    env.close()
