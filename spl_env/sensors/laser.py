"""Planar laser range finder of seed 001: 180 beams over the front 180°, σ = 0.02 m range noise.

Seed 001 scans φ = 0°, 1°, ..., 179° from the robot's right to its left; here the same beams are
given in the robot frame, ``-fov/2 + i * fov / n_beams`` (so φ = angle + 90°). A beam that hits
nothing, or whose noisy range falls outside the laser's range, returns NaN, never a fake
max-range value.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from perception.geometry import FloatArray
from spl_env.sensors.raycast import RayCaster, cast, fan_rays


@dataclass(frozen=True, kw_only=True)
class LaserConfig:
    """Beam layout, range and noise of the laser (defaults: seed 001's Hokuyo UST-30LX set-up)."""

    n_beams: int = 180  # beams, evenly spaced over the field of view
    fov_deg: float = 180.0  # field of view, centred on the robot's heading
    min_range_m: float = 0.1  # nearer returns are dropped (seed 001's accuracy spec: 0.1-10 m)
    max_range_m: float = 10.0  # beams reach this far
    range_noise_std_m: float = 0.02  # Gaussian range noise (seed 001)
    mount_height_m: float = 0.30  # scan plane above the ground (on top of a Pioneer 3-DX)
    mount_x_m: float = 0.0  # scanner centre ahead of the robot origin

    def __post_init__(self) -> None:
        if not isinstance(self.n_beams, int) or isinstance(self.n_beams, bool) or self.n_beams < 1:
            raise ValueError(f"laser.n_beams must be an int >= 1, got {self.n_beams!r}")
        if not (0.0 < self.fov_deg <= 360.0):
            raise ValueError(f"laser.fov_deg must be in (0, 360], got {self.fov_deg}")
        for name in ("min_range_m", "max_range_m", "mount_height_m"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"laser.{name} must be finite and > 0, got {value}")
        if self.min_range_m >= self.max_range_m:
            raise ValueError(
                f"laser.min_range_m must be < max_range_m, "
                f"got {self.min_range_m} >= {self.max_range_m}"
            )
        if not (math.isfinite(self.range_noise_std_m) and self.range_noise_std_m >= 0):
            raise ValueError(
                f"laser.range_noise_std_m must be finite and >= 0, got {self.range_noise_std_m}"
            )
        if not math.isfinite(self.mount_x_m):
            raise ValueError(f"laser.mount_x_m must be finite, got {self.mount_x_m}")


class Laser:
    """Ray-cast planar laser scanner."""

    def __init__(self, config: LaserConfig) -> None:
        self.config = config
        fov = math.radians(config.fov_deg)
        self._angles = -0.5 * fov + fov * np.arange(config.n_beams) / config.n_beams

    def beam_angles(self) -> FloatArray:
        """Beam directions (n_beams,) in the robot frame (rad, 0 = forward, + = left)."""
        return self._angles.copy()

    def rays(self, robot_pose: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Field-frame beam (starts, ends), each (n_beams, 3) (m), for the (3,) field pose."""
        c = self.config
        return fan_rays(
            robot_pose,
            mount_x_m=c.mount_x_m,
            mount_height_m=c.mount_height_m,
            angles=self._angles,
            length_m=c.max_range_m,
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
        c = self.config
        distances, _ = cast(ray_caster, *self.rays(robot_pose), ignore_body)
        noisy = distances + c.range_noise_std_m * rng.standard_normal(c.n_beams)
        in_range = (noisy >= c.min_range_m) & (noisy <= c.max_range_m)
        return np.where(in_range, noisy, np.nan)
