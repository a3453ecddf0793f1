"""A ring of single-transducer sonars, like the Pioneer 3-DX's sixteen (seed 001 §5.2.1).

Each sonar hears a cone of ``cone_deg`` about its axis from its disc on the robot's body
(:attr:`spl_env.robots.diff_drive.DiffDriveConfig.sonar_ring`) and reports one range: the
nearest echo, the distance to the nearest surface in the cone (the first sound back). The cone
is a horizontal fan of ``rays_per_sonar`` rays at the discs' height. The range gets Gaussian
noise and reads NaN when nothing was heard or the noisy range lies outside [``min_range_m``,
``max_range_m``] (never clipped).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from perception.geometry import FloatArray
from perception.validation import check_int, check_positive, finite_vector
from spl_env.robots.diff_drive import DiffDriveConfig, sonar_ring_rays
from spl_env.sensors.raycast import RayCaster, cast


@dataclass(frozen=True, kw_only=True)
class RingSonarConfig:
    """Cone, range and noise of each sonar of the ring (Pioneer 3-DX sonar: 0.15 m to 5 m,
    a cone of about 30 degrees, per its operations manual; the noise is a plausible 1 cm)."""

    cone_deg: float = 30.0  # full width of each sonar's cone (deg)
    rays_per_sonar: int = 7  # rays fanned evenly over the cone
    min_range_m: float = 0.15
    max_range_m: float = 5.0
    range_noise_std_m: float = 0.01

    def __post_init__(self) -> None:
        owner = "RingSonarConfig"
        check_positive(owner, "cone_deg", self.cone_deg, upper=180.0)
        check_int(owner, "rays_per_sonar", self.rays_per_sonar, 1)
        check_positive(owner, "min_range_m", self.min_range_m)
        check_positive(owner, "max_range_m", self.max_range_m)
        if self.min_range_m >= self.max_range_m:
            raise ValueError(
                f"{owner}.min_range_m must be < max_range_m, "
                f"got {self.min_range_m} >= {self.max_range_m}"
            )
        check_positive(owner, "range_noise_std_m", self.range_noise_std_m, allow_zero=True)


class RingSonar:
    """The sonar ring of a differential-drive robot: one range per sonar, ring order."""

    def __init__(self, config: RingSonarConfig, robot: DiffDriveConfig) -> None:
        self.config = config
        self.robot = robot
        n = config.rays_per_sonar
        offsets = np.linspace(-0.5, 0.5, n) if n > 1 else np.zeros(1)
        self._offsets = math.radians(config.cone_deg) * offsets  # (n,) rad about each axis

    def rays(self, robot_pose: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Field-frame ray (starts, ends), each (S * rays_per_sonar, 3) (m), sonar-major, from
        the robot at ``robot_pose``, the (3,) field pose ``(x, y, theta)``."""
        pose = finite_vector(robot_pose, "robot_pose", 3)  # a NaN would read as no echo
        return sonar_ring_rays(self.robot, pose, self.config.max_range_m, self._offsets)

    def measure(
        self,
        ray_caster: RayCaster,
        robot_pose: ArrayLike,
        rng: np.random.Generator,
        ignore_body: int = -1,
    ) -> FloatArray:
        """Ranges (S,) (m) of the sonars in ring order, NaN where nothing was heard in range.

        ``ignore_body`` is the robot's own body id, whose hits count as no echo, for a
        ``ray_caster`` that cannot pass through it (the rigs cast through their own robot
        instead: ``BulletWorld.ray_test(..., transparent_body=...)``).
        """
        distances, _ = cast(ray_caster, *self.rays(robot_pose), ignore_body)
        per_sonar = distances.reshape(len(self.robot.sonar_ring), self.config.rays_per_sonar)
        heard = ~np.all(np.isnan(per_sonar), axis=1)
        nearest = np.full(len(per_sonar), np.nan)
        nearest[heard] = np.nanmin(per_sonar[heard], axis=1)
        c = self.config
        noisy = nearest + c.range_noise_std_m * rng.standard_normal(len(nearest))
        in_range = (noisy >= c.min_range_m) & (noisy <= c.max_range_m)
        return np.where(in_range, noisy, np.nan)
