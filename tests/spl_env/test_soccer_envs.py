"""The soccer envs (SPL/Striker-v0, SPL/Goalie-v0, SPL/PenaltyShootout-v0; the checkers also
their -NoPoles ids): the kick, goals and the ball out, the action mapping, the scripted skills
and players, against known geometry."""

from __future__ import annotations

import math
import warnings
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env as gym_check_env

import spl_env
from agents.soccer_baselines import believed_ball, believed_pose
from perception.field.dimensions import FieldDimensions
from perception.representations import BALL, SELF_POSE, PerceptionOutput
from perception.types import BallEstimate, SensorFrame, SlamEstimate
from spl_env import team_v0
from spl_env.envs.core import SplEnv
from spl_env.observations.ball import BallEncoder
from spl_env.observations.base import EncoderInput, unsquash
from spl_env.observations.poles import RANGE_SCALE_M
from spl_env.observations.self_pose import SelfPoseEncoder
from spl_env.robots.nao import NaoRobot, RobotConfig, camera_state_for, kick_intent, walk_target
from spl_env.sensors.rig import NaoRig
from spl_env.tasks.soccer import SoccerTaskConfig, ball_in_goal, ball_out, scripted_head
from spl_env.tasks.soccer_skills import SkillConfig, approach_and_kick, guard_goal

FAST: dict[str, Any] = {"camera_mode": "geometric", "frontend": "colour", "episode_s": 3.0}
DIMS = FieldDimensions()
NAO = RobotConfig()


def core_of(env: gym.Env) -> SplEnv:
    core = env.unwrapped
    assert isinstance(core, SplEnv)
    return core


@pytest.mark.parametrize("env_id", spl_env.SOCCER_ENV_IDS)
def test_checkers_pass_without_warnings(env_id: str) -> None:
    from stable_baselines3.common.env_checker import check_env as sb3_check_env

    env = gym.make(env_id, **FAST)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        gym_check_env(env.unwrapped)
        sb3_check_env(env.unwrapped, warn=True)
    env.close()
    assert [str(w.message) for w in caught] == []


def test_rendered_penalty_sees_the_ball_with_both_cameras() -> None:
    """The default (rendered, both cameras): the ball on the penalty mark 1.2 m ahead is seen
    within the first second, and the believed ball lies within 0.15 m of it."""
    env = gym.make("SPL/PenaltyShootout-v0", episode_s=1.0)
    _, info = env.reset(seed=3)
    for _ in range(10):
        _, _, _, _, info = env.step(np.zeros(5, dtype=np.float32))
    truth, belief = info["ground_truth"], info["perception"]
    assert belief["ball_known"]
    assert math.dist(truth["ball"], belief["ball"]) < 0.15
    assert core_of(env).pipeline.config.ball_sightings == "cnn_both_cameras"
    env.close()


def test_the_sonar_is_measured_only_where_something_reads_it() -> None:
    """The geometric striker neither perceives nor observes the sonar, so its rig casts none;
    the rendered one's robot sightings check the sonar; a head-control env observes it."""
    striker = core_of(gym.make("SPL/Striker-v0", **FAST))
    striker.reset(seed=0)
    assert striker.rig.sonar is None and striker.sensor_frame.sonar is None
    rendered = core_of(gym.make("SPL/Striker-v0", episode_s=3.0))
    assert "sonar" in rendered.pipeline.frame_inputs and rendered.rig.sonar is not None
    head = core_of(gym.make("SPL/ActiveVision-v1", camera_mode="geometric", frontend="colour"))
    assert "sonar" not in head.pipeline.frame_inputs and "sonar" in head.observation_space.spaces
    head.reset(seed=0)
    assert head.sensor_frame.sonar is not None
    for env in (striker, rendered, head):
        env.close()


def test_goal_and_out_geometry() -> None:
    """A goal needs the whole ball over the goal line between the posts (x > 4.5 + 0.025 +
    0.05); out is the whole ball beyond any outer line."""
    line = DIMS.half_length_m + DIMS.line_width_m / 2 + DIMS.ball_diameter_m / 2
    assert ball_in_goal(np.array([line + 0.01, 0.3]), DIMS) == 1
    assert ball_in_goal(np.array([-(line + 0.01), -0.3]), DIMS) == -1
    assert ball_in_goal(np.array([line - 0.01, 0.0]), DIMS) == 0  # on the line
    assert ball_in_goal(np.array([line + 0.01, 0.8]), DIMS) == 0  # wide of the post
    assert ball_out(np.array([line + 0.01, 0.8]), DIMS)
    side = DIMS.half_width_m + DIMS.line_width_m / 2 + DIMS.ball_diameter_m / 2
    assert ball_out(np.array([0.0, side + 0.01]), DIMS)
    assert not ball_out(np.array([0.0, side - 0.01]), DIMS)


def test_kick_intent_and_its_noise() -> None:
    """The kick goes off at the commanded direction (clipped to 60°) and strength x 2 m/s; its
    direction and speed scatter with std 6° and 10 % (chi-square-sized tolerances over 4000
    kicks)."""
    np.testing.assert_allclose(kick_intent(NAO, 0.0, 0.5), [1.0, 0.0])
    np.testing.assert_allclose(
        kick_intent(NAO, 2.0, 1.0), 2.0 * np.array([math.cos(math.pi / 3), math.sin(math.pi / 3)])
    )
    world_free = _Robot(np.array([1.0, 2.0, 0.5]))
    rng = np.random.default_rng(0)
    ball = world_free.pose[:2] + 0.15 * np.array([math.cos(0.5), math.sin(0.5)])
    kicks = np.array([world_free.kick_velocity(ball, rng, 0.3, 0.8) for _ in range(4000)])
    directions = np.arctan2(kicks[:, 1], kicks[:, 0]) - 0.5 - 0.3
    speeds = np.hypot(*kicks.T) / 1.6
    assert abs(np.mean(directions)) < 4 * NAO.kick_angle_std_rad / math.sqrt(4000)
    assert np.std(directions) == pytest.approx(NAO.kick_angle_std_rad, rel=0.06)
    assert abs(np.mean(speeds) - 1.0) < 4 * 0.1 / math.sqrt(4000)
    assert np.std(speeds) == pytest.approx(NAO.kick_speed_std_fraction, rel=0.06)
    behind = world_free.pose[:2] - 0.15 * np.array([math.cos(0.5), math.sin(0.5)])
    assert world_free.kick_velocity(behind, rng) is None


class _Robot(NaoRobot):
    """A Nao's kick geometry without a world (the kick touches no body)."""

    def __init__(self, pose: np.ndarray) -> None:
        self.config = NAO
        self.pose = pose


def test_a_kick_in_the_env_sends_the_ball_and_tells_perception() -> None:
    """The ball placed in the kick zone and a straight full kick: the ball leaves along the
    heading (within 4 std of the direction noise) at 5/7 of 2 m/s give or take the speed noise
    once it rolls, and the frame reports the kick's intended velocity (robot frame)."""
    env = gym.make("SPL/Striker-v0", **FAST)
    core = core_of(env)
    env.reset(seed=0)
    ours = core.robots[0]
    ours.place(np.array([0.0, 0.0, 0.0]))
    core.scene.place_ball(np.array([0.17, 0.0]))
    env.step(np.array([0, 0, 0, 1.0, 0], dtype=np.float32))
    np.testing.assert_allclose(core.sensor_frame.kick_velocity, [2.0, 0.0])
    for _ in range(3):
        env.step(np.array([0, 0, 0, -1.0, 0], dtype=np.float32))
    velocity = core.world_state.ball_velocity
    assert abs(math.atan2(velocity[1], velocity[0])) < 4 * NAO.kick_angle_std_rad
    assert np.hypot(*velocity) == pytest.approx(2.0 * 5 / 7, rel=0.35)
    np.testing.assert_allclose(core.sensor_frame.kick_velocity, [0.0, 0.0])
    env.close()


def test_a_goal_ends_the_striker_episode_with_its_reward() -> None:
    env = gym.make("SPL/Striker-v0", **FAST)
    core = core_of(env)
    env.reset(seed=1)
    core.scene.place_ball(np.array([DIMS.half_length_m + 0.2, 0.1]))
    _, reward, terminated, _, info = env.step(np.zeros(5, dtype=np.float32))
    assert terminated
    assert info["reward_terms"]["goal"] == 10.0 and info["reward_terms"]["out"] == 0.0
    assert reward == pytest.approx(sum(info["reward_terms"].values()))
    env.reset(seed=1)
    core.scene.place_ball(np.array([0.0, DIMS.half_width_m + 0.3]))
    _, _, terminated, _, info = env.step(np.zeros(5, dtype=np.float32))
    assert terminated and info["reward_terms"]["out"] == -1.0
    env.close()


def test_striker_progress_is_the_distance_the_ball_came_nearer_the_goal() -> None:
    env = gym.make("SPL/Striker-v0", **FAST)
    core = core_of(env)
    env.reset(seed=2)
    goal = np.array([DIMS.half_length_m, 0.0])
    core.scene.place_ball(np.array([1.0, 0.5]))
    env.step(np.zeros(5, dtype=np.float32))
    before = core.world_state.ball.copy()
    core.scene.place_ball(np.array([2.0, 0.5]))
    _, _, _, _, info = env.step(np.zeros(5, dtype=np.float32))
    after = core.world_state.ball
    expected = math.dist(before, goal) - math.dist(after, goal)
    assert info["reward_terms"]["progress"] == pytest.approx(expected, abs=1e-9)
    assert info["reward_terms"]["time"] == -0.01
    env.close()


def test_penalty_starts_on_the_mark_with_the_goalie_in_the_goal() -> None:
    env = gym.make("SPL/PenaltyShootout-v0", **FAST)
    offsets = []
    for seed in range(8):
        _, info = env.reset(seed=seed)
        truth = info["ground_truth"]
        mark = DIMS.half_length_m - DIMS.penalty_mark_distance_m
        np.testing.assert_allclose(truth["ball"], [mark, 0.0], atol=1e-6)
        np.testing.assert_allclose(truth["robot_pose"], [mark - 1.2, 0.0, 0.0], atol=1e-9)
        goalie = truth["robots"][0]
        assert goalie[0] == pytest.approx(DIMS.half_length_m - 0.15)
        offsets.append(goalie[1])
    assert max(np.abs(offsets)) <= 0.45 and np.ptp(offsets) > 0.2  # somewhere in the goal
    env.close()


def test_the_goalie_env_kicker_shoots_and_the_episode_ends() -> None:
    """Our goalie standing still: the scripted kicker reaches the ball and kicks it towards our
    goal; the episode ends with a goal conceded or a save, within 30 s."""
    env = gym.make("SPL/Goalie-v0", camera_mode="geometric", frontend="colour")
    env.reset(seed=4)
    fastest, terminated, truncated = 0.0, False, False
    info: dict[str, Any] = {}
    while not (terminated or truncated):
        _, _, terminated, truncated, info = env.step(np.zeros(5, dtype=np.float32))
        velocity = info["ground_truth"]["ball_velocity"]
        if np.hypot(*velocity) > fastest:
            fastest, heading = float(np.hypot(*velocity)), math.atan2(velocity[1], velocity[0])
    assert terminated and fastest > 1.0
    assert abs(math.remainder(heading - math.pi, 2 * math.pi)) < math.radians(60)  # at our goal
    terms = info["reward_terms"]
    assert (terms["goal"], terms["save"]) in ((-10.0, 0.0), (0.0, 1.0))
    env.close()


def test_head_in_the_action_widens_the_action_space() -> None:
    env = gym.make("SPL/Striker-v0", head_control="action", **FAST)
    assert env.action_space.shape == (7,)
    env.reset(seed=0)
    core = core_of(env)
    for _ in range(10):
        env.step(np.array([0, 0, 0, -1, 0, 0.5, -1.0], dtype=np.float32))
    # yaw 0.5 x 119.5°, pitch fully up: reached at 4 rad/s within the second
    np.testing.assert_allclose(
        core.robots[0].head, [0.5 * NAO.head_yaw_limit_rad, NAO.head_pitch_min_rad], atol=1e-9
    )
    with pytest.raises(ValueError, match="finite"):
        env.step(np.array([np.nan, 0, 0, 0, 0, 0, 0], dtype=np.float32))
    env.close()


def _walk(pose: np.ndarray, action: np.ndarray, dt: float) -> np.ndarray:
    """A pose (3,) after walking the action (3,) for ``dt`` s (robot-frame velocity)."""
    vx, vy, omega = walk_target(NAO, action)
    c, s = math.cos(pose[2]), math.sin(pose[2])
    return np.array(
        [pose[0] + (c * vx - s * vy) * dt, pose[1] + (s * vx + c * vy) * dt, pose[2] + omega * dt]
    )


@pytest.mark.parametrize("start", [(-1.0, 0.5, 0.0), (1.0, 0.1, 3.0), (0.0, -1.5, 1.5)])
def test_approach_and_kick_reaches_the_ball_aligned_and_kicks(start: tuple[float, ...]) -> None:
    """From in front of, beside or behind the ball: the skill walks round it (never through it)
    and kicks with the ball in the kick zone, aiming within a degree of the target."""
    ball, target = np.array([0.5, 0.0]), np.array([4.5, 0.0])
    pose, config = np.array(start), SkillConfig()
    for _ in range(400):
        command = approach_and_kick(pose, ball, target, NAO, config)
        if command.kick:
            break
        pose = _walk(pose, command.walk, 0.1)
        assert math.dist(pose[:2], ball) > 0.1, pose  # not through the ball
    else:
        pytest.fail(f"no kick from {start}")
    aim = pose[2] + command.kick_angle_rad
    assert abs(math.remainder(aim - math.atan2(*(target - ball)[::-1]), 2 * math.pi)) < 0.02
    assert abs(command.kick_angle_rad) <= config.kick_heading_tolerance_rad


def test_guard_goal_stands_between_ball_and_goal() -> None:
    goal, config = np.array([-4.5, 0.0]), SkillConfig()
    pose = np.array([-4.3, 0.0, 0.0])
    ball = np.array([-2.5, 1.0])
    command = guard_goal(pose, ball, goal, NAO, config)
    assert not command.kick
    spot = goal + config.guard_distance_m * (ball - goal) / np.linalg.norm(ball - goal)
    # the walk points at the spot (robot frame = field frame at heading 0)
    direction = command.walk[:2] * np.asarray(NAO.max_speed[:2])
    assert np.dot(direction, spot - pose[:2]) > 0.9 * np.linalg.norm(direction) * np.linalg.norm(
        spot - pose[:2]
    )
    wide = guard_goal(pose, np.array([-4.0, 3.0]), goal, NAO, config)
    assert wide.walk[1] > 0  # towards the clipped spot at y = 0.55


def test_the_players_read_back_what_the_encoders_wrote() -> None:
    """believed_pose and believed_ball invert SelfPoseEncoder and BallEncoder."""
    pose = np.array([1.2, -0.7, 2.5])
    relative = np.array([0.8, 0.6, 0.0, 0.0])
    output = PerceptionOutput(
        time_s=1.0,
        representations={
            SELF_POSE: SlamEstimate(
                pose=pose,
                pose_cov=np.eye(3) * 1e-4,
                landmark_ids=np.zeros(0, dtype=np.int64),
                landmarks=np.zeros((0, 2)),
                landmark_covs=np.zeros((0, 2, 2)),
            ),
            BALL: BallEstimate(
                state=np.zeros(4),
                cov=np.eye(4),
                relative=relative,
                relative_cov=np.eye(4) * 1e-4,
                known=True,
                last_seen_s=0.9,
            ),
        },
    )
    data = EncoderInput(output=output, frame=SensorFrame(time_s=1.0))
    obs = {
        **SelfPoseEncoder(DIMS).encode(data),
        **BallEncoder().encode(data),
    }
    obs = {k: v.astype(np.float32) for k, v in obs.items()}
    np.testing.assert_allclose(believed_pose(obs, DIMS.carpet_size_m), pose, atol=1e-5)
    c, s = math.cos(pose[2]), math.sin(pose[2])
    expected = pose[:2] + np.array([c * 0.8 - s * 0.6, s * 0.8 + c * 0.6])
    ball = believed_ball(obs, pose)
    assert ball is not None
    np.testing.assert_allclose(ball, expected, atol=1e-5)
    assert unsquash(0.5, RANGE_SCALE_M) == pytest.approx(RANGE_SCALE_M)
    unseen: dict[str, np.ndarray] = {**obs, "ball_since_seen": np.ones(1, dtype=np.float32)}
    assert believed_ball(unseen, pose) is None


def test_emulators_draw_in_an_order_no_process_changes() -> None:
    """The rig runs its emulators in name order, whatever order it was handed them in (a set's
    order changes with the process's string hashes): the same seed gives the same ball and
    robot sightings either way."""
    runs = []
    for reverse in (False, True):
        env = gym.make("SPL/Striker-v0", **FAST)
        core = core_of(env)
        given = dict(reversed(list(core.rig.emulators.items())) if reverse else core.rig.emulators)
        core.rig = NaoRig(core.rig.config, core.rig.robot, given)
        assert list(core.rig.emulators) == sorted(given)
        obs, _ = env.reset(seed=3)
        steps = [obs]
        for _ in range(5):
            steps.append(env.step(np.zeros(5, dtype=np.float32))[0])
        runs.append(steps)
        env.close()
    for a, b in zip(*runs, strict=True):
        for key in a:
            np.testing.assert_array_equal(a[key], b[key])


def test_the_scripted_head_looks_again_at_a_waiting_sighting() -> None:
    """No ball believed: with a sighting waiting for a second (the ball filter's
    ``candidate``), the head looks at it, by hand ``(atan2(y, x), atan2(h - r, range) -
    camera tilt)`` with the camera's height ``h`` at that yaw; without one it scans."""
    candidate = np.array([1.5, 0.6])
    config = SoccerTaskConfig()

    def belief(waiting: np.ndarray | None) -> PerceptionOutput:
        ball = BallEstimate(
            state=np.zeros(4),
            cov=np.eye(4),
            relative=np.zeros(4),
            relative_cov=np.eye(4),
            known=False,
            last_seen_s=-math.inf,
            candidate=waiting,
        )
        return PerceptionOutput(time_s=1.0, representations={BALL: ball})

    head = scripted_head(config, NAO, DIMS, belief(candidate), 1.0)
    yaw = math.atan2(0.6, 1.5)
    height = camera_state_for(NAO, np.array([yaw, 0.0])).position[2]
    pitch = math.atan2(height - DIMS.ball_diameter_m / 2, math.hypot(1.5, 0.6))
    np.testing.assert_allclose(head, [yaw, pitch - NAO.camera_tilt_rad], atol=1e-12)
    scan = scripted_head(config, NAO, DIMS, belief(None), 1.0)
    assert scan[0] == pytest.approx(
        config.scan_amplitude_rad * math.sin(2 * math.pi / config.scan_period_s)
    )


@pytest.mark.parametrize(
    ("env_id", "overrides", "match"),
    [
        # an infinite bound crashed numpy's draw; the ball would start beyond the touch lines
        ("SPL/Goalie-v0", {"task.shot_distance_m": (1.5, math.inf)}, r"shot_distance_m\[1\]"),
        # ... or the kicker, up to 1 m behind it, beyond the carpet's edge (less its body)
        ("SPL/Goalie-v0", {"task.shot_distance_m": (1.5, 3.6)}, r"shot_distance_m.*<= 3\.53 m"),
        ("SPL/Goalie-v0", {"task.shot_distance_m": (30.0, 40.0)}, r"inside the touch lines"),
        # our robot would start behind our own goal line (7.7 m = 9 m - 1.3 m from it)
        ("SPL/PenaltyShootout-v0", {"task.start_behind_ball_m": 20.0}, r"\(0, 7\.7\]"),
        # the goalie would stand beside its goal (half its 1.5 m inner width less its body)
        ("SPL/PenaltyShootout-v0", {"task.goalie_max_offset_m": 0.7}, r"\[0, 0\.6\]"),
        # head targets beyond the joints were clipped to them silently
        ("SPL/Striker-v0", {"task.scan_pitch_rad": 3.0}, r"scan_pitch_rad must be finite and in"),
        ("SPL/Striker-v0", {"task.scan_amplitude_rad": 100.0}, r"scan_amplitude_rad.*2\.0856"),
        ("SPL/Goalie-v0", {"task.glance_amplitude_rad": 2.5}, r"glance_amplitude_rad.*2\.0856"),
    ],
)
def test_start_places_and_head_scans_outside_the_field_or_joints_are_refused(
    env_id: str, overrides: dict[str, Any], match: str
) -> None:
    with pytest.raises(ValueError, match=match):
        gym.make(env_id, camera_mode="geometric", frontend="colour", **overrides)


def test_the_team_env_refuses_a_scan_beyond_the_head_joints() -> None:
    with pytest.raises(ValueError, match=r"TeamTaskConfig\.scan_amplitude_rad"):
        team_v0.parallel_env(
            camera_mode="geometric", frontend="colour", **{"task.scan_amplitude_rad": 100.0}
        )
