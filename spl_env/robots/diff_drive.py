"""A differential-drive robot like seed 001's Pioneer 3-DX: wheels, kinematics, encoders.

The robot has two driven wheels of radius ``r`` on one axle, ``L`` apart, and a rear caster.
An action (2,) in [-1, 1] sets the left and right wheel speeds (:func:`wheel_speeds_from_action`);
over a control step of ``dt`` the wheels turn by ``(φl, φr) = (wl, wr) dt`` (rad) and the robot
runs along a circular arc of length and turn (seed 001 eqs. 5.4 and 5.5)::

    Δs = r (φr + φl) / 2,      Δθ = r (φr - φl) / L

(seed 001 prints eq. 5.5 with ``+`` and a factor 2, a typo: its ω = (V_r - V_l) / D two lines
above is the one used here). Eq. 5.3 moves the robot by ``Δs`` along the mid-step heading
``θ + Δθ / 2``; the exact arc moves it along that same heading by the chord
``Δs sin(Δθ/2) / (Δθ/2)``, which :func:`arc_increment` uses, so that a step is exact for
constant wheel speeds (eq. 5.3 is short of it by about ``Δs Δθ² / 24``, 1e-5 m for a step of
0.12 m and 0.06 rad).

Wheel encoders (:class:`WheelEncoders`) count the wheel rotations in ticks, with the errors of
the :class:`DiffDriveConfig`'s noise model; :func:`dead_reckoning_increment` turns a step's
ticks back into a robot-frame increment with the same arc, for an odometry provider. With
perfect encoders it is the true increment up to the ticks' quantisation.

Frames: the field frame has x, y in m and the heading θ in rad, counter-clockwise; the robot
frame has its origin at the middle of the axle (the turning centre), x forward, y to the left.
A robot-frame increment (3,) ``(dx, dy, dθ)`` is given in the frame of the robot at the start of
the step and composes with :func:`perception.geometry.compose`.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from perception.geometry import FloatArray, compose, transform_points
from perception.sensor_models import LaserModel
from perception.validation import (
    InvalidTypeError,
    check_finite,
    check_in_interval,
    check_int,
    check_positive,
    finite_vector,
)
from spl_env.sim.world import BulletWorld, VisualPart

# The Pioneer 3-DX's 16 sonars: x, y (m, robot frame) and heading (deg, + = left) of each disc,
# from ARIA's p3dx.p robot parameter file (SonarUnit 0-15). Eight front sonars at +90, +50,
# +30, +10, -10, -30, -50, -90 deg, then eight rear ones mirrored about the axle, -90 round
# the back to +90 deg; all on the body's edge.
PIONEER_SONAR_RING: tuple[tuple[float, float, float], ...] = (
    (0.069, 0.136, 90.0),
    (0.114, 0.119, 50.0),
    (0.148, 0.078, 30.0),
    (0.166, 0.027, 10.0),
    (0.166, -0.027, -10.0),
    (0.148, -0.078, -30.0),
    (0.114, -0.119, -50.0),
    (0.069, -0.136, -90.0),
    (-0.157, -0.136, -90.0),
    (-0.203, -0.119, -130.0),
    (-0.237, -0.078, -150.0),
    (-0.255, -0.027, -170.0),
    (-0.255, 0.027, 170.0),
    (-0.237, 0.078, 150.0),
    (-0.203, 0.119, 130.0),
    (-0.157, 0.136, 90.0),
)

PIONEER_RED = (0.72, 0.08, 0.06, 1.0)
WHEEL_BLACK = (0.08, 0.08, 0.08, 1.0)
LASER_GREY = (0.25, 0.25, 0.28, 1.0)
# Plan-view chassis (m, robot frame): a box inside the sonar ring's outline, so that no sonar
# ray starts inside the robot's own body.
CHASSIS_X_M = (-0.20, 0.11)
CHASSIS_HALF_WIDTH_M = 0.115
WHEEL_HALF_WIDTH_M = 0.024  # Pioneer 3-DX wheels are 47.5 mm wide (datasheet)
CASTER_RADIUS_M = 0.035
CASTER_X_M = -0.20
LASER_HOUSING_RADIUS_M = 0.03  # Hokuyo UST-30LX: a 50 mm square body
LASER_HOUSING_HEIGHT_M = 0.05  # its body, below the scan plane
LASER_WINDOW_GAP_M = 0.01  # scan plane above the housing's top, so beams start in free space


@dataclass(frozen=True, kw_only=True)
class DiffDriveConfig:
    """Pioneer 3-DX numbers: wheels, speed limit, body, sensor mounts and encoder errors.

    Encoder noise model (drawn by :meth:`WheelEncoders.reset` and applied by
    :meth:`WheelEncoders.measure`): each wheel ``i`` in (left, right) turning by ``φ_i`` (rad)
    in a step is measured as::

        φ'_i = (1 + s_i) φ_i + k sqrt(|φ_i|) z_i,     s_i ~ N(0, σ_s²) per episode,
                                                       z_i ~ N(0, 1) every step

    and counted in whole ticks of ``2π / encoder_ticks_per_rev`` (the counter keeps the
    fraction, so quantisation never accumulates beyond one tick). ``s_i`` is a wheel's
    effective radius error (tyre wear, load): Borenstein & Feng's (1996) unequal wheel
    diameters, the dominant systematic odometry error of a differential drive. Driving straight
    for ``d`` m, dead reckoning then turns by ``(s_r - s_l) d / L``: a heading drift of
    ``sqrt(2) σ_s / L`` rad/m in std across episodes (0.0186 rad/m, about 1.1°/m, with the
    defaults), the drift seed 001's dead reckoning shows. The white term, scaled by
    ``sqrt(|φ|)`` so that it does not depend on how finely the motion is sliced, adds a
    heading random walk of ``k sqrt(2 r) / L`` rad per sqrt(m) driven straight (0.0058).
    The two noise defaults are a plausible uncalibrated robot, not a fit to data: seed 001
    gives no numbers for its drift.
    """

    wheel_radius_m: float = 0.0975  # r: seed 001 Fig. 4.1 and eq. 5.1 (R = 0.0975 m)
    axle_length_m: float = 0.381  # L, the wheel separation: seed 001's robot axis D = 0.381 m
    # P3-DX top speed 1.2 m/s (datasheet) at the wheel radius: 12.3 rad/s. Turning in place at
    # full speed then gives 2 r w / L = 6.3 rad/s (the datasheet's 300°/s is 5.2 rad/s).
    max_wheel_speed_rad_per_s: float = 1.2 / 0.0975
    body_radius_m: float = 0.25  # collision disc about the axle centre (ARIA p3dx.p RobotRadius)
    body_height_m: float = 0.237  # top deck above the ground (P3-DX datasheet: 23.7 cm)
    laser_mount_x_m: float = 0.018  # scanner centre ahead of the axle (ARIA p3dx.p LaserX)
    laser_mount_height_m: float = 0.30  # scan plane on top (LaserModel's Pioneer default)
    sonar_ring: tuple[tuple[float, float, float], ...] = PIONEER_SONAR_RING  # x, y (m), yaw (deg)
    sonar_height_m: float = 0.21  # estimate: above the wheel tops (0.195 m), below the deck
    # P3-DX: 500-tick motor encoders behind a 38.3:1 gearbox = 19150 ticks per wheel turn
    # (MobileRobots P3-DX datasheet, seed 001's [MobileRobots]); 32 µm of wheel travel a tick.
    encoder_ticks_per_rev: int = 19150
    encoder_scale_error_std: float = 0.005  # σ_s: per-wheel scale error, drawn per episode (1)
    encoder_noise_rad_per_sqrt_rad: float = 0.005  # k: white noise per sqrt(rad) turned

    def __post_init__(self) -> None:
        owner = "DiffDriveConfig"
        for name in (
            "wheel_radius_m",
            "axle_length_m",
            "max_wheel_speed_rad_per_s",
            "body_radius_m",
            "body_height_m",
            "laser_mount_height_m",
            "sonar_height_m",
        ):
            check_positive(owner, name, getattr(self, name))
        check_finite(owner, "laser_mount_x_m", self.laser_mount_x_m)
        check_int(owner, "encoder_ticks_per_rev", self.encoder_ticks_per_rev, 1)
        check_in_interval(
            owner,
            "encoder_scale_error_std",
            self.encoder_scale_error_std,
            0.0,
            0.2,
            low_inclusive=True,
            high_inclusive=True,
        )
        check_positive(
            owner,
            "encoder_noise_rad_per_sqrt_rad",
            self.encoder_noise_rad_per_sqrt_rad,
            allow_zero=True,
        )
        self._check_body_layout()
        _check_sonar_ring(self.sonar_ring)

    def _check_body_layout(self) -> None:
        """Raise unless the wheels lie in the collision disc, the sonar ring between the wheel
        tops and the deck, and the laser's scan plane above the deck."""
        if not self.body_radius_m > self.axle_length_m / 2:
            raise ValueError(
                "DiffDriveConfig.body_radius_m must be > axle_length_m / 2 "
                f"({self.axle_length_m / 2}), got {self.body_radius_m}"
            )
        wheel_top_m = 2 * self.wheel_radius_m
        if not wheel_top_m < self.sonar_height_m < self.body_height_m:
            raise ValueError(
                "DiffDriveConfig.sonar_height_m must be in (2 * wheel_radius_m, body_height_m) "
                f"= ({wheel_top_m}, {self.body_height_m}), got {self.sonar_height_m}"
            )
        if not self.laser_mount_height_m > self.body_height_m + LASER_WINDOW_GAP_M:
            raise ValueError(
                "DiffDriveConfig.laser_mount_height_m must be > body_height_m + "
                f"{LASER_WINDOW_GAP_M} ({self.body_height_m + LASER_WINDOW_GAP_M}), "
                f"got {self.laser_mount_height_m}"
            )

    @property
    def tick_rad(self) -> float:
        """One encoder tick of wheel rotation (rad)."""
        return 2 * math.pi / self.encoder_ticks_per_rev

    def sonar_positions_m(self) -> FloatArray:
        """Sonar disc positions (S, 2) in the robot frame (m), ring order."""
        return np.array([mount[:2] for mount in self.sonar_ring], dtype=np.float64).reshape(-1, 2)

    def sonar_directions_rad(self) -> FloatArray:
        """Sonar axes (S,) in the robot frame (rad, 0 = forward, + = left), ring order."""
        return np.deg2rad([mount[2] for mount in self.sonar_ring])

    def mounted_laser(self, scanner: LaserModel) -> LaserModel:
        """``scanner`` (a :class:`LaserModel` or subclass) moved to this robot's laser mount."""
        return dataclasses.replace(
            scanner, mount_x_m=self.laser_mount_x_m, mount_height_m=self.laser_mount_height_m
        )


def _check_sonar_ring(ring: object) -> None:
    """Raise unless ``ring`` is a non-empty tuple of finite ``(x_m, y_m, yaw_deg)`` triples."""
    expected = "a non-empty tuple of (x_m, y_m, yaw_deg) triples"
    if not isinstance(ring, tuple):
        raise InvalidTypeError(
            f"DiffDriveConfig.sonar_ring must be {expected}, got {type(ring).__name__} {ring!r}"
        )
    if not ring:
        raise ValueError(f"DiffDriveConfig.sonar_ring must be {expected}, got ()")
    for k, mount in enumerate(ring):
        if not isinstance(mount, tuple) or len(mount) != 3:
            raise ValueError(
                f"DiffDriveConfig.sonar_ring[{k}] must be a triple (x_m, y_m, yaw_deg), "
                f"got {mount!r}"
            )
        for value, field_name in zip(mount, ("x_m", "y_m", "yaw_deg"), strict=True):
            check_finite("DiffDriveConfig", f"sonar_ring[{k}].{field_name}", value)


def wheel_speeds_from_action(action: ArrayLike, config: DiffDriveConfig) -> FloatArray:
    """Wheel speeds (2,) (rad/s; left, right; + = forward) of an action (2,) in [-1, 1].

    ``±1`` is ``±max_wheel_speed_rad_per_s``. A NaN, a value outside [-1, 1] or another shape
    raises ValueError.
    """
    a = finite_vector(action, "action", 2)
    if np.any(np.abs(a) > 1.0):
        raise ValueError(f"action must lie in [-1, 1] (left, right wheel), got {a.tolist()}")
    return a * config.max_wheel_speed_rad_per_s


def arc_travel(wheel_rotations_rad: ArrayLike, config: DiffDriveConfig) -> tuple[float, float]:
    """Arc length ``Δs`` (m) and turn ``Δθ`` (rad) of the axle centre when the wheels turn by
    ``wheel_rotations_rad`` (2,) (left, right): seed 001 eqs. 5.4 and 5.5."""
    left, right = config.wheel_radius_m * np.asarray(wheel_rotations_rad, dtype=np.float64)
    return float(right + left) / 2, float(right - left) / config.axle_length_m


def arc_increment(distance_m: float, turn_rad: float) -> FloatArray:
    """Robot-frame increment (3,) ``(dx, dy, dθ)`` of a circular arc of length ``distance_m``
    (m) turning by ``turn_rad`` (rad): the chord ``Δs sin(Δθ/2) / (Δθ/2)`` along ``Δθ / 2``
    (seed 001 eq. 5.3 with the exact chord); a straight line of ``Δs`` when ``Δθ = 0``."""
    half_turn = turn_rad / 2
    chord = distance_m * float(np.sinc(half_turn / math.pi))  # np.sinc(x) = sin(πx) / (πx)
    return np.array([chord * math.cos(half_turn), chord * math.sin(half_turn), turn_rad])


def wheel_increment(wheel_rotations_rad: ArrayLike, config: DiffDriveConfig) -> FloatArray:
    """Exact robot-frame increment (3,) when the wheels turn by ``wheel_rotations_rad`` (2,)
    (rad; left, right) at constant speeds, e.g. ``wheel_speeds * dt``."""
    return arc_increment(*arc_travel(wheel_rotations_rad, config))


def dead_reckoning_increment(ticks: ArrayLike, config: DiffDriveConfig) -> FloatArray:
    """Robot-frame increment (3,) ``(dx, dy, dθ)`` that a step's encoder ``ticks`` (2,) (left,
    right) imply: seed 001's dead reckoning (eqs. 5.3-5.5) with the exact arc."""
    return wheel_increment(np.asarray(ticks, dtype=np.float64) * config.tick_rad, config)


class WheelEncoders:
    """The two wheel encoders, counting noisy wheel rotations in ticks (see
    :class:`DiffDriveConfig` for the noise model).

    Call :meth:`reset` at the start of every episode; it draws the episode's per-wheel scale
    errors and keeps ``rng`` for the white noise of every later :meth:`measure`.
    """

    def __init__(self, config: DiffDriveConfig) -> None:
        self.config = config
        self._episode: tuple[np.random.Generator, FloatArray] | None = None
        self._measured_rad = np.zeros(2)  # measured rotation since reset (rad), not quantised
        self._counts = np.zeros(2, dtype=np.int64)  # ticks counted since reset

    def reset(self, rng: np.random.Generator) -> None:
        """Draw this episode's scale errors (2,) from ``rng``, zero the counters and use
        ``rng`` from now on."""
        scale_errors = self.config.encoder_scale_error_std * rng.standard_normal(2)
        self._episode = (rng, scale_errors)
        self._measured_rad = np.zeros(2)
        self._counts = np.zeros(2, dtype=np.int64)

    def _current(self) -> tuple[np.random.Generator, FloatArray]:
        if self._episode is None:
            raise RuntimeError("WheelEncoders.reset(rng) must be called first")
        return self._episode

    @property
    def scale_errors(self) -> FloatArray:
        """The per-wheel scale errors (2,) ``(s_l, s_r)`` drawn by the last :meth:`reset`."""
        return self._current()[1].copy()

    def measure(self, wheel_rotations_rad: ArrayLike) -> NDArray[np.int64]:
        """Ticks (2,) (left, right; + = forward) counted while the wheels truly turn by
        ``wheel_rotations_rad`` (2,) (rad) in one step."""
        rng, scale_errors = self._current()
        true_rad = finite_vector(wheel_rotations_rad, "wheel_rotations_rad", 2)
        white = self.config.encoder_noise_rad_per_sqrt_rad * np.sqrt(np.abs(true_rad))
        self._measured_rad += (1.0 + scale_errors) * true_rad
        self._measured_rad += white * rng.standard_normal(2)
        counts = np.floor(self._measured_rad / self.config.tick_rad).astype(np.int64)
        ticks, self._counts = counts - self._counts, counts
        return ticks


def sonar_ring_rays(
    config: DiffDriveConfig,
    robot_pose: ArrayLike,
    length_m: float,
    offsets_rad: ArrayLike = (0.0,),
) -> tuple[FloatArray, FloatArray]:
    """Field-frame rays (starts, ends), each (S * n, 3) (m), sonar-major: from each sonar's disc
    at ``sonar_height_m``, ``length_m`` long, along its axis turned by each of the ``offsets_rad``
    (n,) (rad, + = left; the default: along the axis), for the robot's (3,) field pose."""
    offsets = np.asarray(offsets_rad, dtype=np.float64).reshape(-1)
    positions = np.repeat(config.sonar_positions_m(), len(offsets), axis=0)
    directions = (config.sonar_directions_rad()[:, None] + offsets[None, :]).ravel()
    tips = positions + length_m * np.column_stack([np.cos(directions), np.sin(directions)])
    height = np.full((len(positions), 1), config.sonar_height_m)
    starts = np.hstack([transform_points(robot_pose, positions), height])
    ends = np.hstack([transform_points(robot_pose, tips), height])
    return starts, ends


def _body_parts(config: DiffDriveConfig) -> list[VisualPart]:
    """Chassis, two wheels, rear caster and laser housing of a Pioneer-like robot.

    Wheels are thin boxes: a :class:`VisualPart` turns only about z, so a cylinder cannot lie on
    its side.
    """
    r = config.wheel_radius_m
    chassis_bottom_m = r / 2
    back_m, front_m = CHASSIS_X_M
    parts = [
        VisualPart(
            shape="box",
            size=(
                (front_m - back_m) / 2,
                CHASSIS_HALF_WIDTH_M,
                (config.body_height_m - chassis_bottom_m) / 2,
            ),
            position=((front_m + back_m) / 2, 0.0, (config.body_height_m + chassis_bottom_m) / 2),
            rgba=PIONEER_RED,
        )
    ]
    parts += [
        VisualPart(
            shape="box",
            size=(r, WHEEL_HALF_WIDTH_M, r),
            position=(0.0, side * config.axle_length_m / 2, r),
            rgba=WHEEL_BLACK,
        )
        for side in (1, -1)
    ]
    parts.append(
        VisualPart(
            shape="sphere",
            size=(CASTER_RADIUS_M,),
            position=(CASTER_X_M, 0.0, CASTER_RADIUS_M),
            rgba=WHEEL_BLACK,
        )
    )
    housing_top_m = config.laser_mount_height_m - LASER_WINDOW_GAP_M
    housing_height_m = min(LASER_HOUSING_HEIGHT_M, housing_top_m - config.body_height_m)
    parts.append(
        VisualPart(
            shape="cylinder",
            size=(LASER_HOUSING_RADIUS_M, housing_height_m),
            position=(config.laser_mount_x_m, 0.0, housing_top_m - housing_height_m / 2),
            rgba=LASER_GREY,
        )
    )
    return parts


class DiffDriveRobot:
    """A differential-drive robot in a :class:`BulletWorld`: pose and wheel speeds.

    The body is kinematic like :class:`~spl_env.robots.nao.NaoRobot`'s and has the same motion
    interface (``pose``, :meth:`walk_step`, :meth:`commit_motion`, :meth:`sync`), so that
    :meth:`spl_env.sim.placement.Placement.walk` drives it with the same collision handling.
    Wheel speeds follow the command at once (no acceleration limit).
    """

    def __init__(self, world: BulletWorld, name: str, *, config: DiffDriveConfig) -> None:
        self.world = world
        self.name = name
        self.config = config
        world.add_static(name, _body_parts(config))
        self.pose = np.zeros(3)
        self.wheel_speeds = np.zeros(2)

    def place(self, pose: ArrayLike) -> None:
        """Put the robot standing still at the field pose ``pose`` (3,) ``(x, y, θ)``."""
        self.pose = finite_vector(pose, "pose", 3)
        self.wheel_speeds = np.zeros(2)
        self.sync()

    def walk_step(self, wheel_speeds: ArrayLike, dt_s: float) -> FloatArray:
        """Drive the wheels at ``wheel_speeds`` (2,) (rad/s; left, right) for ``dt_s`` (s).

        Speeds beyond ``max_wheel_speed_rad_per_s`` are clipped. Returns the wheels' exact
        increment (3,) in the robot frame; the caller decides whether the body may move there
        (:meth:`commit_motion`). Named like the Nao's walk step for ``Placement.walk``.
        """
        limit = self.config.max_wheel_speed_rad_per_s
        speeds = finite_vector(wheel_speeds, "wheel_speeds", 2)
        self.wheel_speeds = np.clip(speeds, -limit, limit)
        return wheel_increment(self.wheel_speeds * dt_s, self.config)

    def wheel_rotations(self, dt_s: float) -> FloatArray:
        """Rotations (2,) (rad; left, right) of the wheels in a step of ``dt_s`` (s) at the
        current speeds: what :meth:`WheelEncoders.measure` counts, whether or not the body moved
        (a blocked robot's wheels slip)."""
        return self.wheel_speeds * dt_s

    def commit_motion(
        self, increment: FloatArray | None, contact_xy: FloatArray | None = None, dt_s: float = 0.0
    ) -> None:
        """Move by ``increment`` (3,) robot frame, or stay where blocked (``None``; the wheels
        slip, whatever was hit at ``contact_xy`` over ``dt_s``)."""
        if increment is not None:
            self.pose = compose(self.pose, increment)

    def sync(self) -> None:
        """Push the pose into the physics world."""
        self.world.set_pose(self.name, (self.pose[0], self.pose[1], 0.0), self.pose[2])
