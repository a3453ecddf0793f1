"""A differential-drive robot's sensor rig: wheel encoders, the sonar ring and the laser.

:class:`DiffDriveRig` turns a step's true wheel rotations and the world into a
:class:`perception.types.SensorFrame`: the odometry increment dead-reckoned from the encoder
ticks (:func:`spl_env.robots.diff_drive.dead_reckoning_increment`), the sixteen sonar ranges
and the laser scan from the robot's laser mount. The encoders draw their episode's scale errors
from the generator handed to :meth:`DiffDriveRig.reset` and their white noise from it too; the
sonar and laser noise come from the one handed to :meth:`DiffDriveRig.sense`.
"""

from __future__ import annotations

import functools
import time
from dataclasses import dataclass, field

import numpy as np

from perception.geometry import FloatArray
from perception.types import GroundTruth, SensorFrame
from perception.validation import check_nested_configs
from spl_env.robots.diff_drive import DiffDriveRobot, WheelEncoders, dead_reckoning_increment
from spl_env.sensors.laser import Laser, LaserConfig
from spl_env.sensors.ring_sonar import RingSonar, RingSonarConfig
from spl_env.sim.world import BulletWorld


@dataclass(frozen=True, kw_only=True)
class DiffDriveRigConfig:
    """The robot's range sensors: the laser (seed 001's: 180 beams over 180°, 0.02 m noise,
    moved to the robot's laser mount) and the sonar ring (``None`` switches it off). The wheel
    encoders' noise is the robot's (:class:`spl_env.robots.diff_drive.DiffDriveConfig`)."""

    laser: LaserConfig = field(default_factory=LaserConfig)
    sonar_ring: RingSonarConfig | None = field(default_factory=RingSonarConfig)

    def __post_init__(self) -> None:
        check_nested_configs(self)


class DiffDriveRig:
    """The sensors of ``robot`` as ``config`` says (the laser at the robot's mount)."""

    def __init__(self, config: DiffDriveRigConfig, robot: DiffDriveRobot) -> None:
        self.config = config
        self.robot = robot
        self.encoders = WheelEncoders(robot.config)
        self.laser = Laser(robot.config.mounted_laser(config.laser))
        self.sonar = (
            RingSonar(config.sonar_ring, robot.config) if config.sonar_ring is not None else None
        )

    def reset(self, rng: np.random.Generator) -> None:
        """Start an episode: the encoders draw their scale errors and keep ``rng``."""
        self.encoders.reset(rng)

    def sense(
        self,
        world: BulletWorld,
        time_s: float,
        wheel_rotations_rad: FloatArray,
        rng: np.random.Generator,
        truth: GroundTruth | None = None,
    ) -> tuple[SensorFrame, dict[str, float]]:
        """This step's frame after the wheels turned by ``wheel_rotations_rad`` (2,) (rad;
        left, right): odometry, sonar ring and laser; ``truth`` is passed on for oracle
        providers. Also returns the seconds spent in the sensors, ``"sensors"``."""
        t0 = time.perf_counter()
        robot = self.robot
        ticks = self.encoders.measure(wheel_rotations_rad)
        self_id = world.body(robot.name)
        rays = functools.partial(world.ray_test, transparent_body=self_id)  # not on our own limbs
        sonar = self.sonar.measure(rays, robot.pose, rng) if self.sonar is not None else None
        laser = self.laser.measure(rays, robot.pose, rng)
        frame = SensorFrame(
            time_s=time_s,
            odometry_delta=dead_reckoning_increment(ticks, robot.config),
            sonar_ring=sonar,
            laser=laser,
            laser_model=self.laser.model,
            truth=truth,
        )
        return frame, {"sensors": time.perf_counter() - t0}
