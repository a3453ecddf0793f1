"""Planar laser range finder of seed 001: 180 beams over the front 180°, σ = 0.02 m range noise.

Seed 001 scans φ = 0°, 1°, ..., 179° from the robot's right to its left; here the same beams are
given in the robot frame, ``-fov/2 + i * fov / n_beams`` (so φ = angle + 90°). A beam that hits
nothing, or whose noisy range falls outside the laser's range, returns NaN, never a fake
max-range value.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from perception.geometry import FloatArray
from perception.sensor_models import LaserModel
from spl_env.sensors.raycast import RayCaster, cast, fan_rays


@dataclass(frozen=True, kw_only=True)
class LaserConfig:
    """Beam layout, range and noise of the laser (defaults: seed 001's Hokuyo UST-30LX set-up).

    The fields are those of :class:`perception.sensor_models.LaserModel`, which validates them
    (``ValueError`` naming the field) and which :attr:`model` builds.
    """

    n_beams: int = 180  # beams, evenly spaced over the field of view
    fov_deg: float = 180.0  # field of view, centred on the robot's heading
    min_range_m: float = 0.1  # nearer returns are dropped (seed 001's accuracy spec: 0.1-10 m)
    max_range_m: float = 10.0  # beams reach this far
    range_noise_std_m: float = 0.02  # Gaussian range noise (seed 001)
    mount_height_m: float = 0.30  # scan plane above the ground (on top of a Pioneer 3-DX)
    mount_x_m: float = 0.0  # scanner centre ahead of the robot origin

    def __post_init__(self) -> None:
        _ = self.model  # building the model validates the fields

    @property
    def model(self) -> LaserModel:
        """The laser's geometry and noise, as perception interprets its scans."""
        return LaserModel(
            n_beams=self.n_beams,
            fov_deg=self.fov_deg,
            min_range_m=self.min_range_m,
            max_range_m=self.max_range_m,
            range_noise_std_m=self.range_noise_std_m,
            mount_x_m=self.mount_x_m,
            mount_height_m=self.mount_height_m,
        )


class Laser:
    """Ray-cast planar laser scanner; ``model`` is the geometry and noise it scans with."""

    def __init__(self, config: LaserConfig) -> None:
        self.config = config
        self.model = config.model
        self._angles = self.model.beam_angles()

    def beam_angles(self) -> FloatArray:
        """Beam directions (n_beams,) in the robot frame (rad, 0 = forward, + = left)."""
        return self._angles.copy()

    def rays(self, robot_pose: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Field-frame beam (starts, ends), each (n_beams, 3) (m), for the (3,) field pose."""
        m = self.model
        return fan_rays(
            robot_pose,
            mount_x_m=m.mount_x_m,
            mount_height_m=m.mount_height_m,
            angles=self._angles,
            length_m=m.max_range_m,
        )

    def measure(
        self,
        ray_caster: RayCaster,
        robot_pose: ArrayLike,
        rng: np.random.Generator,
        ignore_body: int = -1,
    ) -> FloatArray:
        """Ranges (n_beams,) (m) from the scanner centre, NaN where no return.

        ``ignore_body`` is the robot's own body id, whose hits count as no return.
        """
        m = self.model
        distances, _ = cast(ray_caster, *self.rays(robot_pose), ignore_body)
        noisy = distances + m.range_noise_std_m * rng.standard_normal(m.n_beams)
        in_range = (noisy >= m.min_range_m) & (noisy <= m.max_range_m)
        return np.where(in_range, noisy, np.nan)
