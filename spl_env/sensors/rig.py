"""A Nao's sensor rig: what one robot's camera, walk odometry, sonar and laser report per step.

:class:`NaoRig` turns the world's ground truth into a :class:`perception.types.SensorFrame`.
Every robot in the world can carry one; an env senses with the rigs of the robots whose
perception it runs. In the geometric camera mode nothing is rendered: the rig's emulators
(:mod:`spl_env.sensors.emulation`) deliver their representations instead. The walk odometry
draws from the generator handed to :meth:`NaoRig.reset`, everything else from the one handed to
:meth:`NaoRig.sense` (the env passes its episode generator to both).
"""

from __future__ import annotations

import dataclasses
import functools
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from perception.geometry import FloatArray
from perception.types import CameraState, GroundTruth, SensorFrame
from perception.validation import check_nested_configs
from spl_env.robots.nao import NaoRobot, camera_state_for
from spl_env.sensors.camera import Camera, CameraConfig, EpisodeLighting, blur_length_px
from spl_env.sensors.emulation.ball import CNN_BALL, CNN_BALL_BOTTOM, GeometricBallConfig
from spl_env.sensors.emulation.poles import GeometricCameraConfig
from spl_env.sensors.emulation.robots import CNN_ROBOTS, VISION_ROBOTS, GeometricRobotConfig
from spl_env.sensors.laser import Laser, LaserConfig
from spl_env.sensors.odometry import OdometryConfig, WalkOdometry
from spl_env.sensors.sonar import Sonar, SonarConfig
from spl_env.sim.world import BulletWorld

CAMERA_MODES = ("rendered", "geometric")


@dataclass(frozen=True, kw_only=True)
class RigConfig:
    """A Nao's sensors; ``laser=None`` or ``sonar=None`` switch a sensor off.

    ``camera_mode``: ``"rendered"`` pixels, or the fast ``"geometric"`` emulation of what the
    vision front end would report (:mod:`spl_env.sensors.emulation`).
    """

    camera: CameraConfig = field(default_factory=CameraConfig)
    camera_mode: str = "rendered"
    geometric_camera: GeometricCameraConfig = field(default_factory=GeometricCameraConfig)
    geometric_robots_cnn: GeometricRobotConfig = CNN_ROBOTS  # robot_sightings="cnn"
    geometric_robots_vision: GeometricRobotConfig = VISION_ROBOTS  # robot_sightings="vision"
    geometric_ball: GeometricBallConfig = CNN_BALL  # ball_sightings="cnn", top camera
    geometric_ball_bottom: GeometricBallConfig = CNN_BALL_BOTTOM  # "cnn_both_cameras": bottom
    odometry: OdometryConfig = field(default_factory=OdometryConfig)
    sonar: SonarConfig | None = field(default_factory=SonarConfig)
    laser: LaserConfig | None = None

    def __post_init__(self) -> None:
        check_nested_configs(self)
        if self.camera_mode not in CAMERA_MODES:
            raise ValueError(
                f"RigConfig.camera_mode must be one of {CAMERA_MODES}, got {self.camera_mode!r}"
            )


SONAR_FIELDS = frozenset({"sonar", "sonar_model"})  # the SensorFrame fields the sonar fills
LASER_FIELDS = frozenset({"laser", "laser_model"})  # ... and those the laser fills


class Emulator(Protocol):
    """Produces one representation from the true camera pose, without rendering."""

    def observe(
        self,
        world: BulletWorld,
        robot: NaoRobot,
        camera_state: CameraState,
        rng: np.random.Generator,
        blur_px: float,
    ) -> Any:
        """The representation for this frame; ``blur_px`` is the frame's motion blur (px)."""
        ...


class NaoRig:
    """The sensors of ``robot``: camera, walk odometry, sonar and laser as ``config`` says.

    ``emulators`` (geometric camera mode) map a representation name to its emulator.
    """

    def __init__(
        self,
        config: RigConfig,
        robot: NaoRobot,
        emulators: Mapping[str, Emulator] | None = None,
    ) -> None:
        self.config = config
        self.robot = robot
        self.camera = Camera(config.camera)
        self.odometry = WalkOdometry(config.odometry)
        self.sonar = Sonar(config.sonar) if config.sonar is not None else None
        self.laser = Laser(config.laser) if config.laser is not None else None
        # by name: they draw from one generator in turn, so their order must not be a set's
        # (string hashes change between processes)
        self.emulators = dict(sorted((emulators or {}).items()))
        self.lighting = EpisodeLighting.default()

    def reset(self, rng: np.random.Generator) -> None:
        """Start an episode: draw the odometry's systematic errors, then the episode's lighting
        (randomised when the camera config says so)."""
        self.odometry.reset(rng)
        cam = self.config.camera
        self.lighting = (
            EpisodeLighting.sample(cam.randomisation, rng)
            if cam.randomise_lighting
            else EpisodeLighting.default()
        )

    def sense(
        self,
        world: BulletWorld,
        time_s: float,
        engine_delta: FloatArray,
        yaw_rate_rps: float,
        rng: np.random.Generator,
        *,
        render: bool,
        render_bottom: bool = False,
        truth: GroundTruth | None = None,
        kick_velocity: FloatArray | None = None,
    ) -> tuple[SensorFrame, dict[str, float]]:
        """This step's frame: the image (when ``render``; the bottom camera's too with
        ``render_bottom``: pitched 39.7 degrees further down, same intrinsics) or the emulated
        representations, sonar, laser and the odometry of the walk engine's increment
        ``engine_delta`` (3,).

        ``yaw_rate_rps`` is the camera's turn rate this frame (rad/s), for motion blur;
        ``truth`` is passed on for oracle providers; ``kick_velocity`` (2,) is the ball
        velocity (m/s, robot frame) the motion's kick this step meant to give (none: zero).
        Also returns the seconds spent rendering (or emulating), ``"render"``, and in the other
        sensors, ``"sensors"``.
        """
        t0 = time.perf_counter()
        robot, cam = self.robot, self.config.camera
        camera_state = robot.camera_state()
        image = bottom_image = bottom_state = None
        emulated: dict[str, Any] = {}
        if render:
            position, rotation = robot.camera_pose_world()
            image, _ = self.camera.render(
                world, position, rotation, self.lighting, rng, yaw_rate_rps=yaw_rate_rps
            )
            if render_bottom:
                bottom_state = camera_state_for(robot.config, robot.head, "bottom")
                position, rotation = robot.camera_pose_world("bottom")
                bottom_image, _ = self.camera.render(
                    world, position, rotation, self.lighting, rng, yaw_rate_rps=yaw_rate_rps
                )
        if self.emulators:
            blur = blur_length_px(yaw_rate_rps, cam.exposure_time_s, cam.model.fx)
            for name, emulator in self.emulators.items():
                emulated[name] = emulator.observe(world, robot, camera_state, rng, blur)
        t1 = time.perf_counter()
        self_id = world.body(robot.name)
        rays = functools.partial(world.ray_test, transparent_body=self_id)  # not on our own limbs
        sonar = self.sonar.measure(rays, robot.pose, rng) if self.sonar is not None else None
        laser = self.laser.measure(rays, robot.pose, rng) if self.laser is not None else None
        frame = SensorFrame(
            time_s=time_s,
            odometry_delta=self.odometry.measure(engine_delta),
            camera=cam.model,
            camera_state=camera_state,
            image=image,
            bottom_image=bottom_image,
            bottom_camera_state=bottom_state,
            sonar=sonar,
            sonar_model=self.sonar.model if self.sonar is not None else None,
            laser=laser,
            laser_model=self.laser.model if self.laser is not None else None,
            kick_velocity=np.zeros(2) if kick_velocity is None else kick_velocity.copy(),
            emulated=emulated,
            truth=truth,
        )
        return frame, {"render": t1 - t0, "sensors": time.perf_counter() - t1}

    def camera_view(self, world: BulletWorld) -> tuple[NDArray[np.uint8], NDArray[np.int32]]:
        """A noise-free render of what the camera sees now under the episode's lighting:
        (H, W, 3) uint8 RGB and (H, W) body-id labels; for pictures (the geometric camera mode
        renders nothing while stepping) and ground-truth labels."""
        position, rotation = self.robot.camera_pose_world()
        quiet = Camera(dataclasses.replace(self.config.camera, noise_std=0.0))
        return quiet.render(world, position, rotation, self.lighting, np.random.default_rng(0))
