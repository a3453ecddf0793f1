"""What an interpreter of a range scan needs to know about the sensor that made it.

A laser scan (B,) or a sonar reading (3, max_echoes) is just distances; these models give them
their geometry and noise: where each beam or sector points, from where, over which range, and
how noisy its distances are. The simulator builds its sensors from the same models (through
``spl_env.sensors.laser.LaserConfig.model`` and ``spl_env.sensors.sonar.SonarConfig.model``), so
a scan is interpreted with the geometry it was made with.

Frames: angles are in the robot frame, in radians, 0 = the robot's heading, positive to its left
(counter-clockwise seen from above). The sensor sits ``mount_x_m`` ahead of the robot origin on
its heading, ``mount_height_m`` above the ground; distances (m) are measured from there.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from perception.geometry import FloatArray

N_SONAR_SECTORS = 3  # left, middle, right


def _check_positive(prefix: str, owner: object, *names: str) -> None:
    """Raise ValueError naming the first of ``names`` whose value is not finite and > 0."""
    for name in names:
        value = getattr(owner, name)
        if not (math.isfinite(value) and value > 0):
            raise ValueError(f"{prefix}.{name} must be finite and > 0, got {value}")


def _check_int(prefix: str, name: str, value: object) -> None:
    """Raise ValueError unless ``value`` is an int >= 1 (bool not allowed)."""
    if not isinstance(value, int) or isinstance(value, bool) or value < 1:
        raise ValueError(f"{prefix}.{name} must be an int >= 1, got {value!r}")


def _check_ranges(prefix: str, model: LaserModel | SonarModel) -> None:
    """Raise ValueError unless the range interval is valid, the noise std finite and >= 0 and
    the mount's forward offset finite."""
    _check_positive(prefix, model, "min_range_m", "max_range_m", "mount_height_m")
    if model.min_range_m >= model.max_range_m:
        raise ValueError(
            f"{prefix}.min_range_m must be < max_range_m, "
            f"got {model.min_range_m} >= {model.max_range_m}"
        )
    if not (math.isfinite(model.range_noise_std_m) and model.range_noise_std_m >= 0):
        raise ValueError(
            f"{prefix}.range_noise_std_m must be finite and >= 0, got {model.range_noise_std_m}"
        )
    if not math.isfinite(model.mount_x_m):
        raise ValueError(f"{prefix}.mount_x_m must be finite, got {model.mount_x_m}")


@dataclass(frozen=True, kw_only=True)
class LaserModel:
    """A planar laser scanner: ``n_beams`` beams evenly spaced over ``fov_deg``, centred on the
    robot's heading, in a horizontal plane ``mount_height_m`` above the ground.

    A scan is (n_beams,) ranges (m) from the scanner centre, beam i along ``beam_angles()[i]``;
    each range carries Gaussian noise of ``range_noise_std_m``, and a beam with no return in
    [``min_range_m``, ``max_range_m``] reads NaN.
    """

    n_beams: int  # beams, evenly spaced over the field of view
    fov_deg: float  # field of view (deg, in (0, 360]), centred on the robot's heading
    min_range_m: float  # nearer returns are dropped
    max_range_m: float  # beams reach this far
    range_noise_std_m: float  # Gaussian range noise
    mount_x_m: float  # scanner centre ahead of the robot origin
    mount_height_m: float  # scan plane above the ground

    def __post_init__(self) -> None:
        _check_int("laser", "n_beams", self.n_beams)
        if not (0.0 < self.fov_deg <= 360.0):
            raise ValueError(f"laser.fov_deg must be in (0, 360], got {self.fov_deg}")
        _check_ranges("laser", self)

    def beam_angles(self) -> FloatArray:
        """Beam directions (n_beams,) in the robot frame (rad, 0 = forward, + = left):
        ``-fov/2 + i * fov / n_beams``, from the robot's right to its left (seed 001's
        φ = 0°, 1°, ..., 179° for 180 beams over 180°, with φ = angle + 90°)."""
        fov = math.radians(self.fov_deg)
        return -0.5 * fov + fov * np.arange(self.n_beams) / self.n_beams


@dataclass(frozen=True, kw_only=True)
class SonarModel:
    """A sonar that hears three horizontal sectors (left, middle, right) at ``mount_height_m``.

    A reading is (3, max_echoes) echo distances (m) from the transducers, one row per sector in
    that order, nearest first and NaN-padded: the nearest point of each reflecting surface in
    the sector's cone, echoes closer together than ``echo_merge_m`` merged into the nearer one,
    each with Gaussian noise of ``range_noise_std_m``, only those in [``min_range_m``,
    ``max_range_m``]. An echo says something is at that distance somewhere in the cone, not
    at which bearing.
    """

    sector_centres_deg: tuple[float, float, float]  # left, middle, right (deg, + = left)
    sector_widths_deg: tuple[float, float, float]  # full cone widths (deg, in (0, 180])
    min_range_m: float  # no distance below this
    max_range_m: float  # nothing heard beyond this
    max_echoes: int  # echoes reported per sector, nearest first
    echo_merge_m: float  # echoes closer than this merge into one
    range_noise_std_m: float  # Gaussian noise on each echo's distance
    mount_x_m: float  # transducers ahead of the robot origin
    mount_height_m: float  # transducers above the ground

    def __post_init__(self) -> None:
        _check_ranges("sonar", self)
        _check_positive("sonar", self, "echo_merge_m")
        if len(self.sector_centres_deg) != N_SONAR_SECTORS or not all(
            math.isfinite(c) for c in self.sector_centres_deg
        ):
            raise ValueError(
                f"sonar.sector_centres_deg must be 3 finite angles, got {self.sector_centres_deg}"
            )
        if len(self.sector_widths_deg) != N_SONAR_SECTORS or not all(
            0.0 < w <= 180.0 for w in self.sector_widths_deg
        ):
            raise ValueError(
                "sonar.sector_widths_deg must be 3 widths in (0, 180], "
                f"got {self.sector_widths_deg}"
            )
        _check_int("sonar", "max_echoes", self.max_echoes)

    def sector_centres_rad(self) -> FloatArray:
        """Sector axes (3,) in the robot frame (rad, + = left): left, middle, right."""
        return np.deg2rad(np.asarray(self.sector_centres_deg))

    def sector_widths_rad(self) -> FloatArray:
        """Full cone widths (3,) (rad) of the left, middle and right sectors."""
        return np.deg2rad(np.asarray(self.sector_widths_deg))

    def sector_bounds_rad(self) -> FloatArray:
        """Cone edges (3, 2) in the robot frame (rad): each sector's (right, left) edge,
        ``centre -/+ width / 2``; sectors may overlap."""
        half = 0.5 * self.sector_widths_rad()
        centres = self.sector_centres_rad()
        return np.stack([centres - half, centres + half], axis=1)
