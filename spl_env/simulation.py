"""One SPL world: the scene, our robot, scripted others and the sensors, stepped per control step.

:class:`SplSimulation` turns a walk command and a head target into the ground truth
(:class:`WorldState`) and what the robot's sensors report (:class:`perception.types.SensorFrame`).
Robots walk kinematically at the control rate; the ball is simulated by PyBullet at
``physics_dt_s``. Every random draw uses the generator handed to :meth:`SplSimulation.reset`.
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from perception.geometry import FloatArray, transform_points, wrap_angle
from perception.types import PoleCode, SensorFrame
from spl_env.behaviours import WalkerConfig, WaypointWalker
from spl_env.sensors.camera import Camera, CameraConfig, EpisodeLighting, blur_length_px
from spl_env.sensors.geometric_camera import GeometricCameraConfig, GeometricPoleCamera
from spl_env.sensors.laser import Laser, LaserConfig
from spl_env.sensors.odometry import OdometryConfig, WalkOdometry
from spl_env.sensors.sonar import Sonar, SonarConfig
from spl_env.sim.robot import NaoRobot, RobotConfig
from spl_env.sim.scene import SceneConfig, build_scene
from spl_env.sim.world import BulletWorld
from spl_env.timing import StepTimes

SELF = "self"
CAMERA_MODES = ("rendered", "geometric")


@dataclass(frozen=True, kw_only=True)
class SimConfig:
    """The world and its sensors; ``laser=None`` or ``sonar=None`` switch a sensor off."""

    scene: SceneConfig = field(default_factory=SceneConfig)
    robot: RobotConfig = field(default_factory=RobotConfig)
    camera: CameraConfig = field(default_factory=CameraConfig)
    camera_mode: str = "rendered"  # "rendered" pixels, or fast "geometric" band centres
    geometric_camera: GeometricCameraConfig = field(default_factory=GeometricCameraConfig)
    odometry: OdometryConfig = field(default_factory=OdometryConfig)
    sonar: SonarConfig | None = field(default_factory=SonarConfig)
    laser: LaserConfig | None = None
    control_dt_s: float = 0.1  # one control step = one camera frame (10 Hz)
    physics_dt_s: float = 0.01  # PyBullet time step for the ball
    n_other_robots: int = 4
    other_walker: WalkerConfig = field(default_factory=WalkerConfig)
    scene_seed: int = 0  # picks the posters when the world is built

    def __post_init__(self) -> None:
        if not (0 < self.physics_dt_s <= min(self.control_dt_s, 0.1)) or not (
            self.control_dt_s <= 1.0
        ):
            raise ValueError(
                "SimConfig needs 0 < physics_dt_s <= min(control_dt_s, 0.1 s) and "
                f"control_dt_s <= 1 s, got {self.physics_dt_s} and {self.control_dt_s}"
            )
        ratio = self.control_dt_s / self.physics_dt_s
        if abs(ratio - round(ratio)) > 1e-6:
            raise ValueError(
                f"SimConfig.control_dt_s must be a whole multiple of physics_dt_s, got {ratio:.4f}"
            )
        if not isinstance(self.n_other_robots, int) or not 0 <= self.n_other_robots <= 9:
            raise ValueError(
                f"SimConfig.n_other_robots must be an int in [0, 9], got {self.n_other_robots!r}"
            )
        if self.camera_mode not in CAMERA_MODES:
            raise ValueError(
                f"SimConfig.camera_mode must be one of {CAMERA_MODES}, got {self.camera_mode!r}"
            )
        if not isinstance(self.scene_seed, int) or self.scene_seed < 0:
            raise ValueError(f"SimConfig.scene_seed must be an int >= 0, got {self.scene_seed!r}")

    @property
    def substeps(self) -> int:
        """Physics steps per control step."""
        return round(self.control_dt_s / self.physics_dt_s)


@dataclass(frozen=True, kw_only=True)
class WorldState:
    """Ground truth after a step (field frame, SI units).

    ``robot_pose`` (3,) and ``head`` (2,) of our robot; ``robots`` (R, 3) poses of the others
    with ``robot_teams`` (R,); ``ball`` (2,); ``landmarks`` (L, 2)
    pole positions with ``landmark_ids`` (L,); ``blocked`` whether our robot bumped into
    something this step.
    """

    time_s: float
    robot_pose: FloatArray
    head: FloatArray
    robots: FloatArray
    robot_teams: NDArray[np.int64]
    ball: FloatArray
    landmarks: FloatArray
    landmark_ids: NDArray[np.int64]
    blocked: bool


class SplSimulation:
    """The SPL world with our robot, ``n_other_robots`` scripted robots and our sensors."""

    def __init__(self, config: SimConfig) -> None:
        self.config = config
        self.world = BulletWorld(time_step_s=config.physics_dt_s)
        scene_rng = np.random.default_rng(config.scene_seed)
        self.bodies = build_scene(self.world, config.scene, scene_rng)
        self.robot = NaoRobot(self.world, SELF, team=0, config=config.robot)
        self.others = [
            NaoRobot(self.world, f"robot_{i}", team=(i + 1) % 2, config=config.robot)
            for i in range(config.n_other_robots)
        ]
        self.camera = Camera(config.camera)
        self.odometry = WalkOdometry(config.odometry)
        self.sonar = Sonar(config.sonar) if config.sonar is not None else None
        self.laser = Laser(config.laser) if config.laser is not None else None
        codes = config.scene.poles.codes() if config.scene.poles_enabled else ()
        self.pole_codes: tuple[PoleCode, ...] = codes
        positions = config.scene.poles.positions(config.scene.dimensions)
        self.landmark_ids = np.array([c.landmark_id for c in codes], dtype=np.int64)
        self.landmarks = positions[self.landmark_ids] if len(codes) else np.zeros((0, 2))
        # posts and poles as (x, y, radius) circles the robots walk around
        dims, pole_radius = config.scene.dimensions, config.scene.poles.geometry.radius_m
        self._obstacles = np.array(
            [
                (*self.world.position(n)[:2], dims.goal_post_diameter_m / 2)
                for n in self.bodies.goal_posts
            ]
            + [(*self.world.position(n)[:2], pole_radius) for n in self.bodies.poles.values()]
        ).reshape(-1, 3)
        self.geometric_camera = GeometricPoleCamera(
            config.geometric_camera,
            config.camera.model,
            config.scene.poles.geometry,
            self.landmarks,
            tuple(int(i) for i in self.landmark_ids),
            tuple(self.world.body(self.bodies.poles[int(i)]) for i in self.landmark_ids),
        )
        self._initial_state = self.world.save_state()
        self._rng: np.random.Generator | None = None  # the episode's, from reset()
        self.last_yaw_rate_rps = 0.0
        self._walkers: list[WaypointWalker] = []
        self._others_blocked = [False] * len(self.others)
        self._lighting = EpisodeLighting.default()
        self._time_s = 0.0
        self._blocked = False

    # ----- episode ------------------------------------------------------------------------
    def reset(
        self, rng: np.random.Generator, start_pose: FloatArray
    ) -> tuple[WorldState, SensorFrame, StepTimes]:
        """Restore the initial physics state and place everything; returns the first frame."""
        self.world.restore_state(self._initial_state)
        self._rng = rng
        self._time_s = 0.0
        self._blocked = False
        self.robot.place(start_pose)
        dims = self.config.scene.dimensions
        self._walkers = []
        self._others_blocked = [False] * len(self.others)
        placed = [self.robot]  # robots of this episode so far; the rest still stand where they were
        for other in self.others:
            walker = WaypointWalker(self.config.other_walker, dims, rng)
            other.place(self._free_pose(rng, placed))
            placed.append(other)
            self._walkers.append(walker)
        ball = np.array([rng.uniform(-2.0, 2.0), rng.uniform(-1.5, 1.5)])
        self.world.set_pose(self.bodies.ball, (ball[0], ball[1], dims.ball_diameter_m / 2), 0.0)
        self.world.set_velocity(self.bodies.ball, (0.0, 0.0, 0.0))
        self.odometry.reset(rng)
        cam = self.config.camera
        self._lighting = (
            EpisodeLighting.sample(cam.randomisation, rng)
            if cam.randomise_lighting
            else EpisodeLighting.default()
        )
        frame, render_s, sensors_s = self._sense(np.zeros(3), yaw_rate=0.0)
        return self.state(), frame, StepTimes(physics=0.0, render=render_s, sensors=sensors_s)

    def _free_pose(self, rng: np.random.Generator, placed: list[NaoRobot]) -> FloatArray:
        """A random pose inside the field, clear of the ``placed`` robots, posts and poles."""
        dims = self.config.scene.dimensions
        for _ in range(200):
            pose = np.array(
                [
                    rng.uniform(-dims.half_length_m + 0.5, dims.half_length_m - 0.5),
                    rng.uniform(-dims.half_width_m + 0.5, dims.half_width_m - 0.5),
                    rng.uniform(-math.pi, math.pi),
                ]
            )
            if not self._collides(pose[:2], placed, clearance=0.3):
                return pose
        raise RuntimeError("could not place a robot: the field is too crowded")

    # ----- stepping -----------------------------------------------------------------------
    def step(
        self, walk_command: FloatArray, head_target: FloatArray
    ) -> tuple[WorldState, SensorFrame, StepTimes]:
        """Advance one control step with our robot's walk command (3,) and head target (2,)."""
        dt = self.config.control_dt_s
        t0 = time.perf_counter()
        yaw_before = self.robot.pose[2] + self.robot.head[0]
        self.robot.move_head(head_target, dt)
        engine_delta, self._blocked = self._walk(self.robot, walk_command)
        for i, (other, walker) in enumerate(zip(self.others, self._walkers, strict=True)):
            command = walker.command(other.pose, dt, blocked=self._others_blocked[i])
            _, self._others_blocked[i] = self._walk(other, command)
        self.world.step(self.config.substeps)
        self._time_s += dt
        t1 = time.perf_counter()
        yaw_rate = float(wrap_angle(self.robot.pose[2] + self.robot.head[0] - yaw_before)) / dt
        frame, render_s, sensors_s = self._sense(engine_delta, yaw_rate)
        return (
            self.state(),
            frame,
            StepTimes(physics=t1 - t0, render=render_s, sensors=sensors_s),
        )

    def _walk(self, robot: NaoRobot, command: FloatArray) -> tuple[FloatArray, bool]:
        """Walk one control step: the walk engine's increment (3,) and whether the body was blocked.

        A blocked robot stays where it is while its walk engine (and so its odometry) believes
        it stepped: the slip a real Nao sees when it walks into an obstacle.
        """
        increment = robot.walk_step(command, self.config.control_dt_s)
        new_xy = transform_points(robot.pose, increment[None, :2])[0]
        others = [o for o in (self.robot, *self.others) if o is not robot]
        blocked = self._collides(new_xy, others, clearance=0.0)
        robot.commit_motion(None if blocked else increment)
        robot.sync()
        return increment, blocked

    def _collides(self, xy: FloatArray, robots: list[NaoRobot], clearance: float) -> bool:
        """Whether a robot at ``xy`` overlaps one of ``robots``, a post or a pole, or leaves the
        carpet, with ``clearance`` (m) to spare."""
        r = self.config.robot.body_radius_m
        carpet_l, carpet_w = self.config.scene.dimensions.carpet_size_m
        if abs(xy[0]) > carpet_l / 2 - r or abs(xy[1]) > carpet_w / 2 - r:
            return True
        for robot in robots:
            if math.hypot(*(robot.pose[:2] - xy)) < 2 * r + clearance:
                return True
        d = np.hypot(self._obstacles[:, 0] - xy[0], self._obstacles[:, 1] - xy[1])
        return bool(np.any(d < r + self._obstacles[:, 2] + clearance))

    def _sense(self, engine_delta: FloatArray, yaw_rate: float) -> tuple[SensorFrame, float, float]:
        """Render the camera and read odometry, sonar and laser; returns frame and timings."""
        if self._rng is None:
            raise RuntimeError("call SplSimulation.reset() before stepping")
        self.last_yaw_rate_rps = yaw_rate  # the camera's turn rate this frame (rad/s)
        t0 = time.perf_counter()
        position, rotation = self.robot.camera_pose_world()
        image, band_centres = None, None
        if self.config.camera_mode == "rendered":
            image, _ = self.camera.render(
                self.world, position, rotation, self._lighting, self._rng, yaw_rate_rps=yaw_rate
            )
        else:
            blur = blur_length_px(
                yaw_rate, self.config.camera.exposure_time_s, self.config.camera.model.fx
            )
            band_centres = self.geometric_camera.observe(
                self.world, position, rotation, self._rng, blur_px=blur
            )
        t1 = time.perf_counter()
        self_id = self.world.body(SELF)
        sonar = (
            self.sonar.measure(self.world.ray_test, self.robot.pose, self._rng, ignore_body=self_id)
            if self.sonar is not None
            else None
        )
        laser = (
            self.laser.measure(self.world.ray_test, self.robot.pose, self._rng, ignore_body=self_id)
            if self.laser is not None
            else None
        )
        odometry = self.odometry.measure(engine_delta)
        frame = SensorFrame(
            time_s=self._time_s,
            odometry_delta=odometry,
            camera=self.config.camera.model,
            camera_state=self.robot.camera_state(),
            image=image,
            band_centres=band_centres,
            sonar=sonar,
            laser=laser,
        )
        return frame, t1 - t0, time.perf_counter() - t1

    def camera_view(self) -> NDArray[np.uint8]:
        """A noise-free render of what the camera sees now, (H, W, 3) uint8 RGB: for pictures in
        the geometric camera mode, which renders nothing while stepping."""
        position, rotation = self.robot.camera_pose_world()
        quiet = Camera(dataclasses.replace(self.config.camera, noise_std=0.0))
        image, _ = quiet.render(
            self.world, position, rotation, self._lighting, np.random.default_rng(0)
        )
        return image

    def state(self) -> WorldState:
        """The ground truth now."""
        ball = self.world.position(self.bodies.ball)
        return WorldState(
            time_s=self._time_s,
            robot_pose=self.robot.pose.copy(),
            head=self.robot.head.copy(),
            robots=np.array([o.pose for o in self.others]).reshape(-1, 3),
            robot_teams=np.array([o.team for o in self.others], dtype=np.int64),
            ball=ball[:2],
            landmarks=self.landmarks.copy(),
            landmark_ids=self.landmark_ids.copy(),
            blocked=self._blocked,
        )

    def close(self) -> None:
        """Release the physics client; safe to call twice."""
        self.world.close()
