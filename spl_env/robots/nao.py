"""The Nao robot module: a Nao-sized body of primitive shapes, its command and its head mapping.

:class:`NaoCommand` is what drives one control step (walk velocity, head target, kick);
:func:`head_target` and :func:`head_action` are the one mapping between a head action in
[-1, 1] and joint targets, used by tasks, observations and scripted policies alike.

The walk is kinematic: the body follows the commanded velocity within Nao-like speed and
acceleration limits, and sways with the gait (roll, pitch and bob), which moves the camera in a
way the robot's joint sensors do not report. Head yaw and pitch follow targets within the Nao v6
joint limits and a speed limit. Frames: see :mod:`perception.geometry`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from perception.geometry import (
    FloatArray,
    camera_rotation,
    compose,
    rot_x,
    rot_y,
    rot_z,
    wrap_angle,
)
from perception.types import CameraState
from perception.validation import check_finite, check_positive, check_reals, finite_vector
from spl_env.sim.world import BulletWorld, LinkSpec, VisualPart

NAO_GREY = (0.82, 0.82, 0.84, 1.0)
TEAM_JERSEY_RGBA = ((0.12, 0.22, 0.80, 1.0), (0.85, 0.12, 0.10, 1.0))
TEAM_WAISTBAND_RGBA = ((0.05, 0.10, 0.55, 1.0), (0.65, 0.05, 0.05, 1.0))


@dataclass(frozen=True, kw_only=True)
class RobotConfig:
    """Nao v6 body numbers, walk/head limits and the kick."""

    body_radius_m: float = 0.15  # plan-view radius used for collisions between robots
    max_speed: tuple[float, float, float] = (0.25, 0.15, 1.0)  # vx, vy (m/s), omega (rad/s)
    max_accel: tuple[float, float, float] = (0.5, 0.4, 2.0)  # m/s^2, m/s^2, rad/s^2
    head_yaw_limit_rad: float = math.radians(119.5)  # Nao v6 HeadYaw range ±119.5°
    head_pitch_min_rad: float = math.radians(-38.5)  # Nao v6 HeadPitch, up
    head_pitch_max_rad: float = math.radians(29.5)  # Nao v6 HeadPitch, down
    head_speed_rps: float = 4.0  # head joint speed limit (rad/s)
    head_yaw_joint_height_m: float = 0.44  # above the ground, standing
    camera_offset_m: tuple[float, float, float] = (0.0587, 0.0, 0.0636)  # top camera in head frame
    head_pitch_joint_offset_m: float = 0.017  # HeadPitch above HeadYaw
    camera_tilt_rad: float = math.radians(1.2)  # Nao v6 top camera tilt in the head
    bottom_camera_offset_m: tuple[float, float, float] = (0.0506, 0.0, 0.0179)  # in head frame
    bottom_camera_tilt_rad: float = math.radians(39.7)  # Nao v6 bottom camera tilt in the head
    gait_frequency_hz: float = 1.6  # full gait cycles per second while walking
    sway_roll_rad: float = 0.035  # torso roll amplitude at full walking speed
    sway_pitch_rad: float = 0.012  # torso pitch amplitude at full walking speed
    sway_bob_m: float = 0.008  # vertical bob amplitude at full walking speed
    kick_reach_m: float = 0.25  # a kick reaches a ball this far ahead of the robot centre
    kick_half_width_m: float = 0.12  # ... and this far to either side
    kick_speed_mps: float = 2.0  # ball speed a kick at full strength gives
    kick_max_angle_rad: float = math.radians(60.0)  # a kick's direction off the heading, at most
    kick_angle_std_rad: float = math.radians(6.0)  # a kick's direction noise (std)
    kick_speed_std_fraction: float = 0.1  # a kick's speed noise (std / speed)
    # A systematic veer of the body that the walk engine does not know of (rad per metre
    # walked, + = left): the robot turns while its engine, and so its odometry, reports
    # straight (seed 004 §5.3's uncalibrated robot had a left turn bias). 0 by default.
    turn_bias_rad_per_m: float = 0.0
    # A blocked robot (walking into another robot, a post or the carpet's edge) pivots away
    # from what it hit at this rate (rad/s) while its engine reports the step it wanted
    # (seed 004 §5.2: an arm caught on a robot turns the body). 0 by default: it just stops.
    bump_turn_rps: float = 0.0

    def __post_init__(self) -> None:
        for name in ("max_speed", "max_accel"):
            values = getattr(self, name)
            check_reals("RobotConfig", name, values, 3)
            for k, value in enumerate(values):
                check_positive("RobotConfig", f"{name}[{k}]", value)
        for name in (
            "body_radius_m",
            "head_yaw_limit_rad",
            "head_speed_rps",
            "head_yaw_joint_height_m",
            "gait_frequency_hz",
            "kick_reach_m",
            "kick_half_width_m",
            "kick_speed_mps",
            "kick_max_angle_rad",
        ):
            check_positive("RobotConfig", name, getattr(self, name))
        for name in ("kick_angle_std_rad", "kick_speed_std_fraction"):
            check_positive("RobotConfig", name, getattr(self, name), allow_zero=True)
        if not self.kick_max_angle_rad <= math.pi / 2:
            raise ValueError(
                f"RobotConfig.kick_max_angle_rad must be <= pi/2, got {self.kick_max_angle_rad}"
            )
        if not self.head_yaw_limit_rad <= math.pi:
            raise ValueError(
                f"RobotConfig.head_yaw_limit_rad must be <= pi, got {self.head_yaw_limit_rad}"
            )
        check_finite("RobotConfig", "head_pitch_min_rad", self.head_pitch_min_rad)
        check_finite("RobotConfig", "head_pitch_max_rad", self.head_pitch_max_rad)
        if not -math.pi / 2 < self.head_pitch_min_rad < 0 < self.head_pitch_max_rad < math.pi / 2:
            raise ValueError(
                "RobotConfig needs -pi/2 < head_pitch_min_rad < 0 < head_pitch_max_rad < pi/2, got "
                f"{self.head_pitch_min_rad} and {self.head_pitch_max_rad}"
            )
        for name in ("camera_offset_m", "bottom_camera_offset_m"):
            check_reals("RobotConfig", name, getattr(self, name), 3)
        for name in (
            "head_pitch_joint_offset_m",
            "camera_tilt_rad",
            "bottom_camera_tilt_rad",
            "turn_bias_rad_per_m",
        ):
            check_finite("RobotConfig", name, getattr(self, name))
        check_positive("RobotConfig", "bump_turn_rps", self.bump_turn_rps, allow_zero=True)
        for name in ("sway_roll_rad", "sway_pitch_rad", "sway_bob_m"):
            check_positive("RobotConfig", name, getattr(self, name), allow_zero=True)


def camera_state_for(
    config: RobotConfig, head: FloatArray, camera: Literal["top", "bottom"] = "top"
) -> CameraState:
    """Where the ``camera`` (top or bottom) of a standing Nao with ``config`` is, robot frame,
    at the head joint angles ``head`` (2,) (yaw, pitch; rad)."""
    head_rot = rot_z(head[0]) @ rot_y(head[1])
    neck = np.array([0.0, 0.0, config.head_yaw_joint_height_m])
    pitch_joint = neck + rot_z(head[0]) @ np.array([0.0, 0.0, config.head_pitch_joint_offset_m])
    top = camera == "top"
    offset = config.camera_offset_m if top else config.bottom_camera_offset_m
    return CameraState(
        position=pitch_joint + head_rot @ np.asarray(offset),
        head_yaw=float(head[0]),
        head_pitch=float(head[1]),
        tilt=config.camera_tilt_rad if top else config.bottom_camera_tilt_rad,
    )


@dataclass(frozen=True, kw_only=True)
class NaoCommand:
    """One control step's command to a Nao.

    ``walk`` (3,): body-frame velocity ``(vx, vy, omega)`` (m/s, m/s, rad/s), limited by the
    walk engine; ``head`` (2,): yaw and pitch targets (rad), or ``None`` to keep the head where
    it is; ``kick``: kick the ball if it lies in the kick zone in front of the feet, towards
    ``kick_angle_rad`` (rad, off the heading, + = left) at ``kick_strength`` (0-1] of the full
    kick's speed (:meth:`NaoRobot.kick_velocity`).
    """

    walk: FloatArray = field(default_factory=lambda: np.zeros(3))
    head: FloatArray | None = None
    kick: bool = False
    kick_angle_rad: float = 0.0
    kick_strength: float = 1.0

    def __post_init__(self) -> None:
        finite_vector(self.walk, "NaoCommand.walk", 3)  # a NaN would stay in the walk for good
        if self.head is not None:
            finite_vector(self.head, "NaoCommand.head", 2)
        if not math.isfinite(self.kick_angle_rad):
            raise ValueError(f"NaoCommand.kick_angle_rad must be finite, got {self.kick_angle_rad}")
        if not 0.0 < self.kick_strength <= 1.0:
            raise ValueError(
                f"NaoCommand.kick_strength must be in (0, 1], got {self.kick_strength}"
            )


def head_target(config: RobotConfig, action: FloatArray) -> FloatArray:
    """Head joint targets (2,) (rad) of a head action (2,) in [-1, 1].

    Yaw is ``a[0] * head_yaw_limit_rad``; pitch runs linearly from ``head_pitch_min_rad``
    (``a[1] = -1``, up) to ``head_pitch_max_rad`` (``a[1] = 1``, down).
    """
    a = np.asarray(action, dtype=np.float64)
    yaw = a[0] * config.head_yaw_limit_rad
    pitch = config.head_pitch_min_rad + (a[1] + 1.0) / 2.0 * (
        config.head_pitch_max_rad - config.head_pitch_min_rad
    )
    return np.array([yaw, pitch])


def walk_target(config: RobotConfig, action: FloatArray) -> FloatArray:
    """The walk command (3,) ``(vx, vy, omega)`` (m/s, m/s, rad/s) of a walk action (3,) in
    [-1, 1]: each component times its speed limit ``max_speed``."""
    return np.asarray(action, dtype=np.float64) * np.asarray(config.max_speed)


def kick_angle(config: RobotConfig, action: float) -> float:
    """The kick direction (rad, off the heading, + = left) of a kick-direction action in
    [-1, 1]: ``action * kick_max_angle_rad``."""
    return float(action) * config.kick_max_angle_rad


def kick_aim(config: RobotConfig, angle_rad: float) -> float:
    """A kick's direction (rad, off the heading): ``angle_rad`` clipped to the foot's reach
    ``kick_max_angle_rad``."""
    return float(np.clip(angle_rad, -config.kick_max_angle_rad, config.kick_max_angle_rad))


def kick_intent(config: RobotConfig, angle_rad: float, strength: float) -> FloatArray:
    """The ball velocity (2,) (m/s, robot frame) a kick towards ``angle_rad`` off the heading
    (:func:`kick_aim`) at ``strength`` (0-1] means to give, before its noise."""
    aim = kick_aim(config, angle_rad)
    return config.kick_speed_mps * strength * np.array([math.cos(aim), math.sin(aim)])


def in_kick_zone(config: RobotConfig, pose: FloatArray, ball_xy: FloatArray) -> bool:
    """Whether the ball (2,) lies in the kick zone of a robot at ``pose`` (3,) (one frame, m):
    ``kick_reach_m`` ahead of its centre at most, ``kick_half_width_m`` to either side."""
    c, s = math.cos(pose[2]), math.sin(pose[2])
    dx, dy = ball_xy[0] - pose[0], ball_xy[1] - pose[1]
    ahead, aside = c * dx + s * dy, -s * dx + c * dy
    return 0.0 < ahead <= config.kick_reach_m and abs(aside) <= config.kick_half_width_m


def head_action(config: RobotConfig, yaw_rad: float, pitch_rad: float) -> FloatArray:
    """The head action (2,) whose target is ``(yaw_rad, pitch_rad)``: :func:`head_target`'s
    inverse, not clipped (angles beyond the joint limits map beyond [-1, 1]); also how the
    observations encode the head's joint angles."""
    pitch_mid = (config.head_pitch_max_rad + config.head_pitch_min_rad) / 2
    pitch_half = (config.head_pitch_max_rad - config.head_pitch_min_rad) / 2
    return np.array([yaw_rad / config.head_yaw_limit_rad, (pitch_rad - pitch_mid) / pitch_half])


def _body_parts(team: int, team_colours: bool) -> list[VisualPart]:
    """Legs, waistband, jersey and arms of a standing Nao (about 0.57 m tall with the head);
    waistband and jersey in ``team``'s colours, or grey like the rest without ``team_colours``."""
    parts = [
        VisualPart(shape="box", size=(0.045, 0.035, 0.13), position=(0.0, y, 0.13), rgba=NAO_GREY)
        for y in (-0.05, 0.05)
    ]
    parts.append(
        VisualPart(
            shape="box",
            size=(0.055, 0.085, 0.02),
            position=(0.0, 0.0, 0.28),
            rgba=TEAM_WAISTBAND_RGBA[team] if team_colours else NAO_GREY,
        )
    )
    parts.append(
        VisualPart(
            shape="box",
            size=(0.05, 0.08, 0.07),
            position=(0.0, 0.0, 0.37),
            rgba=TEAM_JERSEY_RGBA[team] if team_colours else NAO_GREY,
        )
    )
    parts += [
        VisualPart(shape="box", size=(0.03, 0.025, 0.1), position=(0.0, y, 0.34), rgba=NAO_GREY)
        for y in (-0.11, 0.11)
    ]
    return parts


class NaoRobot:
    """One robot in a :class:`BulletWorld`: pose, walk state, head joints and camera geometry.

    ``team`` (0 or 1) is the robot's team; it wears the team's jersey and waistband unless
    ``team_colours`` is False (seed 004's penalty test: a goalie without a waistband).
    """

    def __init__(
        self,
        world: BulletWorld,
        name: str,
        *,
        team: int,
        config: RobotConfig,
        team_colours: bool = True,
    ) -> None:
        if team not in (0, 1):
            raise ValueError(f"team must be 0 or 1, got {team!r}")
        if not isinstance(team_colours, bool):
            raise TypeError(f"team_colours must be a bool, got {type(team_colours).__name__}")
        self.world = world
        self.name = name
        self.team = team
        self.team_colours = team_colours
        self.config = config
        head = VisualPart(
            shape="box", size=(0.05, 0.065, 0.06), position=(0.0, 0.0, 0.045), rgba=NAO_GREY
        )
        world.add_articulated(
            name,
            _body_parts(team, team_colours),
            [
                LinkSpec(
                    parent=0, offset=(0.0, 0.0, config.head_yaw_joint_height_m), axis=(0, 0, 1)
                ),
                LinkSpec(
                    parent=1,
                    offset=(0.0, 0.0, config.head_pitch_joint_offset_m),
                    axis=(0, 1, 0),
                    parts=(head,),
                ),
            ],
        )
        # the last camera poses computed, by camera, with the robot state they were computed at
        # (the config is part of the state: it holds the camera offsets)
        self._camera_pose_memo: dict[str, tuple[tuple[Any, ...], tuple[FloatArray, FloatArray]]]
        self._camera_pose_memo = {}
        self._camera_state_memo: tuple[tuple[Any, ...], CameraState] | None = None
        self.pose = np.zeros(3)
        self.velocity = np.zeros(3)
        self.head = np.zeros(2)
        self.gait_phase = 0.0

    def place(self, pose: FloatArray, head: FloatArray | None = None) -> None:
        """Put the robot standing still at ``pose`` (3,) with head angles (2,) (rad)."""
        self.pose = np.asarray(pose, dtype=np.float64).copy()
        self.velocity = np.zeros(3)
        self.head = np.zeros(2) if head is None else np.asarray(head, dtype=np.float64).copy()
        self.gait_phase = 0.0
        self.sync()

    def walk_step(self, command: FloatArray, dt_s: float) -> FloatArray:
        """Advance the walk by ``dt_s`` towards ``command`` (vx, vy m/s, omega rad/s).

        The velocity changes at most by the acceleration limits and stays within the speed
        limits. Returns the walk engine's increment (3,) in the robot frame; the caller decides
        whether the body may move there (see :meth:`commit_motion`).
        """
        cfg = self.config
        velocity = []  # per component, in floats: a step costs no array operations
        for now, wanted, top, accel in zip(
            self.velocity.tolist(),
            np.asarray(command).tolist(),
            cfg.max_speed,
            cfg.max_accel,
            strict=True,
        ):
            target = min(max(wanted, -top), top)
            change = accel * dt_s
            velocity.append(now + min(max(target - now, -change), change))
        self.velocity = np.array(velocity)
        speed = self._speed_fraction_of(velocity)
        self.gait_phase = (
            self.gait_phase + 2 * math.pi * cfg.gait_frequency_hz * dt_s * (speed > 1e-3)
        ) % (2 * math.pi)
        vx, vy, omega = (v * dt_s for v in velocity)
        if abs(omega) < 1e-9:
            return np.array([vx, vy, 0.0])
        # constant body-frame twist over the step: exact arc increment
        s, c = math.sin(omega), math.cos(omega)
        return np.array([(vx * s - vy * (1 - c)) / omega, (vx * (1 - c) + vy * s) / omega, omega])

    def commit_motion(
        self, increment: FloatArray | None, contact_xy: FloatArray | None = None, dt_s: float = 0.0
    ) -> None:
        """Move by the walk engine's ``increment`` (3,) robot frame, the body veering by
        ``turn_bias_rad_per_m`` per metre of it; or, blocked (``None``), stop, and pivot for
        ``dt_s`` (s) at ``bump_turn_rps`` away from the ``contact_xy`` (2,) (m, field frame) it
        ran into, when given."""
        if increment is None:
            self.velocity = np.zeros(3)
            if contact_xy is not None and self.config.bump_turn_rps > 0.0:
                self.pose = self.pose.copy()
                self.pose[2] = wrap_angle(self.pose[2] + self._bump_turn(contact_xy, dt_s))
            return
        dx, dy, dtheta = np.asarray(increment, dtype=np.float64).tolist()
        veer = self.config.turn_bias_rad_per_m * math.hypot(dx, dy)
        self.pose = compose(self.pose, (dx, dy, dtheta + veer))

    def _bump_turn(self, contact_xy: FloatArray, dt_s: float) -> float:
        """The pivot (rad) away from ``contact_xy`` (2,) over ``dt_s``: right (negative) when the
        contact lies to the left of the heading, left otherwise."""
        dx, dy = contact_xy[0] - self.pose[0], contact_xy[1] - self.pose[1]
        side = -math.sin(self.pose[2]) * dx + math.cos(self.pose[2]) * dy
        return -math.copysign(self.config.bump_turn_rps * dt_s, side)

    def in_kick_zone(self, ball_xy: FloatArray) -> bool:
        """Whether the ball (2,) (m, field frame) lies in this robot's kick zone
        (:func:`in_kick_zone`)."""
        return in_kick_zone(self.config, self.pose, ball_xy)

    def kick_velocity(
        self,
        ball_xy: FloatArray,
        rng: np.random.Generator,
        angle_rad: float = 0.0,
        strength: float = 1.0,
    ) -> FloatArray | None:
        """Ball velocity (2,) (m/s, field frame) of a kick now towards ``angle_rad`` off the
        heading (clipped to ``kick_max_angle_rad``, the foot's reach) at ``strength`` (0-1] of
        ``kick_speed_mps``, its direction and speed disturbed by Gaussian noise
        (``kick_angle_std_rad``, ``kick_speed_std_fraction``) drawn from ``rng``; None when the
        ball (2,) is outside the kick zone (:meth:`in_kick_zone`, no draw then)."""
        if not self.in_kick_zone(ball_xy):
            return None
        cfg = self.config
        noise = rng.normal(0.0, 1.0, size=2)
        direction = self.pose[2] + kick_aim(cfg, angle_rad) + cfg.kick_angle_std_rad * noise[0]
        speed = max(
            cfg.kick_speed_mps * strength * (1.0 + cfg.kick_speed_std_fraction * noise[1]), 0.0
        )
        return speed * np.array([math.cos(direction), math.sin(direction)])

    def move_head(self, target: FloatArray, dt_s: float) -> None:
        """Turn the head towards ``target`` (yaw, pitch) rad within joint and speed limits."""
        cfg = self.config
        lo = np.array([-cfg.head_yaw_limit_rad, cfg.head_pitch_min_rad])
        hi = np.array([cfg.head_yaw_limit_rad, cfg.head_pitch_max_rad])
        goal = np.clip(target, lo, hi)  # targets beyond a joint stop end at the stop
        step = cfg.head_speed_rps * dt_s
        self.head = self.head + np.clip(goal - self.head, -step, step)

    def sway(self) -> tuple[float, float, float]:
        """Current torso roll, pitch (rad) and bob (m) from the gait phase and walking speed."""
        cfg = self.config
        speed = self._speed_fraction()
        phase = self.gait_phase
        return (
            cfg.sway_roll_rad * speed * math.sin(phase),
            cfg.sway_pitch_rad * speed * math.sin(2 * phase),
            cfg.sway_bob_m * speed * (math.cos(2 * phase) - 1) / 2,
        )

    def _speed_fraction(self) -> float:
        """The walk's speed now: :meth:`_speed_fraction_of` the robot's velocity."""
        return self._speed_fraction_of(self.velocity.tolist())

    def _speed_fraction_of(self, velocity: list[float]) -> float:
        """The largest fraction of its speed limit (``config.max_speed``) among the components
        of the walk velocity ``velocity`` ``(vx, vy, omega)`` (m/s, m/s, rad/s)."""
        (vx, vy, omega), (top_x, top_y, top_omega) = velocity, self.config.max_speed
        return max(abs(vx) / top_x, abs(vy) / top_y, abs(omega) / top_omega)

    def sync(self) -> None:
        """Push pose, sway and head joints into the physics world."""
        roll, pitch, bob = self.sway()
        self.world.set_pose(
            self.name, (self.pose[0], self.pose[1], bob), self.pose[2], roll=roll, pitch=pitch
        )
        self.world.set_joints(self.name, self.head.tolist())

    def camera_state(self) -> CameraState:
        """The camera pose the robot's joint sensors report (no sway): robot frame (computed
        once per head position; its ``position`` is read-only, as the frames share it)."""
        key = (self.config, *self.head.tolist())
        if self._camera_state_memo is None or self._camera_state_memo[0] != key:
            state = camera_state_for(self.config, self.head)
            state.position.setflags(write=False)
            self._camera_state_memo = (key, state)
        return self._camera_state_memo[1]

    def camera_pose_world(
        self, camera: Literal["top", "bottom"] = "top"
    ) -> tuple[FloatArray, FloatArray]:
        """True position (3,) and rotation (3, 3) of the top or bottom camera in the field
        frame, sway included (computed once per state of the robot: the sensors of a step ask
        several times)."""
        state = (
            self.config,
            *self.pose.tolist(),
            *self.head.tolist(),
            *self.velocity.tolist(),
            float(self.gait_phase),
        )
        memo = self._camera_pose_memo.get(camera)
        if memo is None or memo[0] != state:
            memo = (state, self._camera_pose_now(camera))
            self._camera_pose_memo[camera] = memo
        position, rotation = memo[1]
        return position.copy(), rotation.copy()

    def _camera_pose_now(self, camera: Literal["top", "bottom"]) -> tuple[FloatArray, FloatArray]:
        """:meth:`camera_pose_world`, computed."""
        roll, pitch, bob = self.sway()
        body = rot_z(self.pose[2]) @ rot_y(pitch) @ rot_x(roll)
        state = camera_state_for(self.config, self.head, camera)
        position = np.array([self.pose[0], self.pose[1], bob]) + body @ state.position
        rotation = rot_z(self.pose[2]) @ camera_rotation(
            state.head_yaw, state.head_pitch + state.tilt, body_roll=roll, body_pitch=pitch
        )
        return position, rotation
