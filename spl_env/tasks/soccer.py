"""Soccer tasks: our robot's body is the action; it plays on what perception believes.

The action is ``Box(-1, 1, (5,))`` (``(7,)`` with ``head_control="action"``):

=====  ==================================================================================
index  meaning
=====  ==================================================================================
0-2    walk ``(vx, vy, omega)``, each times its speed limit (0.25 m/s, 0.15 m/s, 1 rad/s;
       :func:`spl_env.robots.nao.walk_target`), robot frame
3      kick: > 0 kicks when the ball lies in the kick zone in front of the feet, at this
       strength (of 2 m/s; :meth:`spl_env.robots.nao.NaoRobot.kick_velocity`); <= 0 no kick
4      kick direction off the heading: times 60 degrees (+ = left)
5-6    only with ``head_control="action"``: the head target
       (:func:`spl_env.robots.nao.head_target`)
=====  ==================================================================================

A kick's direction and speed carry noise (std 6 degrees and 10 %). Without the head in the
action it is scripted: ``"track_ball"`` looks at the believed ball while it was seen within
``ball_lost_after_s`` (glancing round for landmarks every ``glance_period_s`` while the ball is
farther than ``glance_beyond_m``), looks at a sighting that waits for a second one to start a
belief (the ball filter's ``start_confirm_s``; the scan would sweep past it), and searches
otherwise (the scan, its pitch swinging between the scan's and fully down once every two
sweeps); ``"scan"`` always scans at the scan's pitch.

The observation holds what perception believes: our pose and its std, the head's joint angles,
the ball relative to us (:class:`spl_env.observations.ball.BallEncoder`), up to
``max_tracked_robots`` tracked robots and the episode clock. Rewards and termination are the
subclasses', judged on the truth.
"""

from __future__ import annotations

import math
from abc import abstractmethod
from dataclasses import dataclass, field

import numpy as np
from gymnasium import spaces

from perception.geometry import FloatArray
from perception.representations import BALL, PerceptionOutput
from perception.types import BallEstimate
from perception.validation import (
    check_choice,
    check_finite,
    check_in_interval,
    check_int,
    check_positive,
)
from spl_env.field import FieldDimensions
from spl_env.observations.ball import BallEncoder
from spl_env.observations.base import ObservationEncoder
from spl_env.observations.body import EpisodeClockEncoder, HeadEncoder
from spl_env.observations.robots import RobotTracksEncoder
from spl_env.observations.self_pose import SelfPoseEncoder
from spl_env.robots.nao import (
    NaoCommand,
    RobotConfig,
    camera_state_for,
    head_target,
    kick_angle,
    walk_target,
)
from spl_env.tasks.base import Task, TaskConfig, TaskContext
from spl_env.tasks.soccer_skills import SkillConfig
from spl_env.world_state import WorldState

HEAD_CONTROLS = ("track_ball", "scan", "action")
WALK_AND_KICK = 5  # action entries without the head


@dataclass(frozen=True, kw_only=True)
class SoccerTaskConfig(TaskConfig):
    """What every soccer task has: the head's control, the observation's robot rows, the
    scripted players' skills and the goal reward."""

    n_other_robots: int = 1  # the scripted opponents (each task says who they are)
    head_control: str = "track_ball"  # one of HEAD_CONTROLS (module doc)
    ball_lost_after_s: float = 2.0  # track_ball scans once the ball was unseen this long (s)
    scan_amplitude_rad: float = math.radians(90.0)  # the scan's yaw amplitude
    scan_period_s: float = 4.0  # the scan's period (s)
    scan_pitch_rad: float = math.radians(12.0)  # the scan's pitch (down): the ball and poles
    # track_ball glances round for landmarks (one sweep of glance_amplitude_rad either way in
    # glance_s) at the start of every glance_period_s, unless the ball is nearer than
    # glance_beyond_m (about to be kicked): tracking the ball alone, the pose drifts by metres
    # in a minute of SPL/Striker-v0 (geometric camera, seeds 100-111)
    glance_period_s: float = 5.0
    glance_s: float = 2.0
    glance_amplitude_rad: float = 1.2
    glance_beyond_m: float = 1.0
    max_tracked_robots: int = 4  # K: track rows in the observation (nearest first)
    skills: SkillConfig = field(default_factory=SkillConfig)  # the scripted players'
    goal_reward: float = 10.0  # reward for a goal scored (the negative for one conceded)
    kicked_speed_mps: float = 0.3  # a ball this fast has been kicked (ShotWatch)
    stopped_speed_mps: float = 0.05  # a kicked ball this slow is over: missed or saved

    def __post_init__(self) -> None:
        super().__post_init__()
        owner = type(self).__name__
        check_choice(owner, "head_control", self.head_control, HEAD_CONTROLS)
        for name in (
            "ball_lost_after_s",
            "scan_period_s",
            "scan_amplitude_rad",
            "glance_period_s",
            "glance_s",
            "glance_amplitude_rad",
            "glance_beyond_m",
        ):
            check_positive(owner, name, getattr(self, name))
        if not self.glance_s <= self.glance_period_s:
            raise ValueError(
                f"{owner}.glance_s must be <= glance_period_s, got {self.glance_s} and "
                f"{self.glance_period_s}"
            )
        check_finite(owner, "scan_pitch_rad", self.scan_pitch_rad)  # its joints': check_head_reach
        check_int(owner, "max_tracked_robots", self.max_tracked_robots, 1)
        check_positive(owner, "goal_reward", self.goal_reward, allow_zero=True)
        for name in ("kicked_speed_mps", "stopped_speed_mps"):
            check_positive(owner, name, getattr(self, name))
        if not self.stopped_speed_mps < self.kicked_speed_mps:
            raise ValueError(
                f"{owner}.stopped_speed_mps must be < kicked_speed_mps, got "
                f"{self.stopped_speed_mps} and {self.kicked_speed_mps}"
            )

    @property
    def other_robot_teams(self) -> tuple[int, ...]:
        """Every scripted robot plays for the other team (1)."""
        return (1,) * self.n_other_robots


def check_head_reach(config: SoccerTaskConfig, robot: RobotConfig) -> None:
    """ValueError, naming the field, unless the scripted head's scan and glance stay within
    ``robot``'s head joints (a target beyond a joint would be clipped to it: a sine scan with a
    too wide amplitude turns into a square wave)."""
    owner = type(config).__name__
    for name in ("scan_amplitude_rad", "glance_amplitude_rad"):
        check_positive(
            owner, name, getattr(config, name), upper=robot.head_yaw_limit_rad, upper_inclusive=True
        )
    check_in_interval(
        owner,
        "scan_pitch_rad",
        config.scan_pitch_rad,
        robot.head_pitch_min_rad,
        robot.head_pitch_max_rad,
        low_inclusive=True,
        high_inclusive=True,
    )


def ball_in_goal(ball: FloatArray, dims: FieldDimensions) -> int:
    """+1 when the whole ball (2,) lies over the opponent goal line (x > 0) between the posts,
    -1 over our own, 0 otherwise."""
    radius = dims.ball_diameter_m / 2
    over = abs(ball[0]) > dims.half_length_m + dims.line_width_m / 2 + radius
    between = abs(ball[1]) < dims.goal_inner_width_m / 2
    return int(np.sign(ball[0])) if over and between else 0


def ball_out(ball: FloatArray, dims: FieldDimensions) -> bool:
    """Whether the whole ball (2,) lies outside the field's outer lines (a goal counts too)."""
    limit = np.array([dims.half_length_m, dims.half_width_m]) + dims.line_width_m / 2
    return bool(np.any(np.abs(ball) > limit + dims.ball_diameter_m / 2))


def goal_centre(dims: FieldDimensions, side: int) -> FloatArray:
    """The centre (2,) of the opponent goal's line (``side`` +1) or ours (-1)."""
    return np.array([side * dims.half_length_m, 0.0])


class ShotWatch:
    """Whether a shot is over: the ball was kicked (faster than ``kicked_speed_mps``) and has
    slowed below ``stopped_speed_mps`` since. :meth:`reset` per episode, :meth:`stopped`
    every step with the true ball velocity (it may be asked more than once a step)."""

    def __init__(self, config: SoccerTaskConfig) -> None:
        self.config = config
        self._kicked = False

    def reset(self) -> None:
        """A new episode: nothing kicked yet."""
        self._kicked = False

    @property
    def kicked(self) -> bool:
        """Whether the ball has been kicked this episode (as last seen by :meth:`stopped`)."""
        return self._kicked

    def stopped(self, ball_velocity: FloatArray) -> bool:
        """Whether the ball, moving at ``ball_velocity`` (2,) (m/s), stopped after a kick."""
        speed = float(np.hypot(*ball_velocity))
        self._kicked = self._kicked or speed >= self.config.kicked_speed_mps
        return self._kicked and speed < self.config.stopped_speed_mps


def soccer_command(
    action: FloatArray,
    config: SoccerTaskConfig,
    robot: RobotConfig,
    dimensions: FieldDimensions,
    belief: PerceptionOutput | None,
    time_s: float,
) -> NaoCommand:
    """A robot's command from its soccer ``action`` (module doc's table) at ``time_s`` (s): the
    head from the action or scripted on ``belief`` (that robot's last perception output, None
    before the first) as ``config.head_control`` says (:func:`scripted_head`)."""
    head = (
        head_target(robot, action[WALK_AND_KICK:])
        if config.head_control == "action"
        else scripted_head(config, robot, dimensions, belief, time_s)
    )
    kick = bool(action[3] > 0.0)
    return NaoCommand(
        walk=walk_target(robot, action[:3]),
        head=head,
        kick=kick,
        kick_angle_rad=kick_angle(robot, float(action[4])),
        kick_strength=float(action[3]) if kick else 1.0,
    )


def scripted_head(
    config: SoccerTaskConfig,
    robot: RobotConfig,
    dimensions: FieldDimensions,
    belief: PerceptionOutput | None,
    time_s: float,
) -> FloatArray:
    """The head target (2,) (rad) of ``config.head_control`` (module doc) at ``time_s`` (s) for a
    robot whose perception believed ``belief`` last (None before the first frame)."""
    c = config
    if c.head_control == "track_ball" and belief is not None:
        ball = belief.get_as(BALL, BallEstimate)
        if ball.known and time_s - ball.last_seen_s <= c.ball_lost_after_s:
            phase = time_s % c.glance_period_s
            far = math.hypot(*ball.relative[:2]) > c.glance_beyond_m
            if far and phase < c.glance_s:  # a glance round for the landmarks
                yaw = c.glance_amplitude_rad * math.sin(2 * math.pi * phase / c.glance_s)
                return np.array([yaw, c.scan_pitch_rad])
            return look_at_ball(robot, dimensions, ball.relative[:2])
        if not ball.known and ball.candidate is not None:  # look again at a first sighting
            return look_at_ball(robot, dimensions, ball.candidate)
    yaw = c.scan_amplitude_rad * math.sin(2 * math.pi * time_s / c.scan_period_s)
    if c.head_control == "scan":
        return np.array([yaw, c.scan_pitch_rad])
    # searching: every other sweep looks down at the feet, where the top camera is blind
    down = (1.0 - math.cos(math.pi * time_s / c.scan_period_s)) / 2
    pitch = c.scan_pitch_rad + down * (robot.head_pitch_max_rad - c.scan_pitch_rad)
    return np.array([yaw, pitch])


def look_at_ball(robot: RobotConfig, dimensions: FieldDimensions, ball: FloatArray) -> FloatArray:
    """The head target (2,) (rad) that centres the ball at ``ball`` (2,) (robot frame) in the top
    camera of a robot with ``robot``'s body."""
    range_m, bearing = math.hypot(*ball), math.atan2(ball[1], ball[0])
    camera_height = camera_state_for(robot, np.array([bearing, 0.0])).position[2]
    radius = dimensions.ball_diameter_m / 2
    pitch = math.atan2(camera_height - radius, max(range_m, 0.05)) - robot.camera_tilt_rad
    return np.array([bearing, pitch])


class SoccerTask(Task):
    """Our robot's body is the action (module doc); subclasses place the bodies, script the
    opponents, and score."""

    config: SoccerTaskConfig

    def __init__(self, config: SoccerTaskConfig, context: TaskContext) -> None:
        super().__init__(config, context)
        self._belief: PerceptionOutput | None = None

    @property
    def action_space(self) -> spaces.Box:
        size = WALK_AND_KICK + (2 if self.config.head_control == "action" else 0)
        return spaces.Box(-1.0, 1.0, shape=(size,), dtype=np.float32)

    def encoders(self) -> tuple[ObservationEncoder, ...]:
        ctx = self.context
        return (
            SelfPoseEncoder(ctx.dimensions),
            HeadEncoder(ctx.robot),
            BallEncoder(),
            RobotTracksEncoder(self.config.max_tracked_robots),
            EpisodeClockEncoder(self.config.episode_s),
        )

    def reward_requires(self) -> tuple[str, ...]:
        return (BALL,)  # the scripted head reads it

    def perceived(self, output: PerceptionOutput) -> None:
        self._belief = output

    def command(self, action: FloatArray, state: WorldState) -> NaoCommand:
        return soccer_command(
            action,
            self.config,
            self.context.robot,
            self.context.dimensions,
            self._belief,
            state.time_s,
        )

    def start_pose(self, rng: np.random.Generator) -> FloatArray:
        self._belief = None
        return self.our_start(rng)

    @abstractmethod
    def our_start(self, rng: np.random.Generator) -> FloatArray:
        """Our robot's true start pose (3,) for a new episode."""
