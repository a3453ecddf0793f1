"""Planar laser range finder of seed 001: 180 beams over the front 180°, σ = 0.02 m range noise.

Seed 001 scans φ = 0°, 1°, ..., 179° from the robot's right to its left; here the same beams are
given in the robot frame, ``-fov/2 + i * fov / n_beams`` (so φ = angle + 90°). A beam that hits
nothing, or whose noisy range falls outside the laser's range, returns NaN, never a fake
max-range value.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from perception.geometry import FloatArray
from perception.sensor_models import LaserModel
from spl_env.sensors.raycast import RayCaster, RayFan, cast


class LaserConfig(LaserModel):
    """Beam layout, range and noise of the simulated laser: exactly a
    :class:`perception.sensor_models.LaserModel` (defaults: seed 001's Hokuyo UST-30LX set-up),
    which validates the fields (``ValueError`` naming ``laser.<field>``).

    The simulation adds no setting of its own; the subclass only gives the env config's
    ``sensors.laser`` field its name. Any ``LaserModel`` configures a :class:`Laser`.
    """


# A finer scanner for the SPL field, like a Hokuyo UTM-30LX (0.25° steps over 270°, 0.1-30 m),
# with seed 001's range noise: 0.05 m poles and goal posts take 1-2 beams of the 1° laser at
# 2-3 m (too few for a segment), 4-8 of this one.
FINE_LASER = LaserConfig(n_beams=1080, fov_deg=270.0, max_range_m=30.0)


class Laser:
    """Ray-cast planar laser scanner; ``model`` (its config) is the geometry and noise it scans
    with."""

    def __init__(self, config: LaserModel) -> None:
        self.config = config
        self.model: LaserModel = config
        self._fan = RayFan(
            mount_x_m=config.mount_x_m,
            mount_height_m=config.mount_height_m,
            angles=config.beam_angles(),
            length_m=config.max_range_m,
        )

    def beam_angles(self) -> FloatArray:
        """Beam directions (n_beams,) in the robot frame (rad, 0 = forward, + = left): the
        model's :meth:`~perception.sensor_models.LaserModel.beam_angles`."""
        return self.model.beam_angles()

    def rays(self, robot_pose: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Field-frame beam (starts, ends), each (n_beams, 3) (m), for the (3,) field pose."""
        return self._fan.rays(robot_pose)

    def measure(
        self,
        ray_caster: RayCaster,
        robot_pose: ArrayLike,
        rng: np.random.Generator,
        ignore_body: int = -1,
    ) -> FloatArray:
        """Ranges (n_beams,) (m) from the scanner centre, NaN where no return.

        ``ignore_body`` is the robot's own body id, whose hits count as no return, for a
        ``ray_caster`` that cannot pass through it (the rigs cast through their own robot
        instead: ``BulletWorld.ray_test(..., transparent_body=...)``).
        """
        m = self.model
        distances, _ = cast(ray_caster, *self.rays(robot_pose), ignore_body)
        noisy = distances + m.range_noise_std_m * rng.standard_normal(m.n_beams)
        in_range = (noisy >= m.min_range_m) & (noisy <= m.max_range_m)
        return np.where(in_range, noisy, np.nan)
