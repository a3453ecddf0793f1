"""What an interpreter of a range scan needs to know about the sensor that made it.

A laser scan (B,) or a sonar reading (3, max_echoes) is just distances; these models give them
their geometry and noise: where each beam or sector points, from where, over which range, and
how noisy its distances are. The simulator's sensors are configured with these very models
(``spl_env.sensors.laser.LaserConfig`` is a :class:`LaserModel`;
``spl_env.sensors.sonar.SonarConfig`` is a :class:`SonarModel` plus two settings of the
simulation's own), so a scan is interpreted with the geometry it was made with. The defaults are
seed 001's laser and the Nao's sonar as seed 004 describes it.

Frames: angles are in the robot frame, in radians, 0 = the robot's heading, positive to its left
(counter-clockwise seen from above). The sensor sits ``mount_x_m`` ahead of the robot origin on
its heading, ``mount_height_m`` above the ground; distances (m) are measured from there.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from perception.geometry import FloatArray
from perception.validation import InvalidTypeError, check_finite, check_int, check_positive

N_SONAR_SECTORS = 3  # left, middle, right


def _check_ranges(prefix: str, model: LaserModel | SonarModel) -> None:
    """Raise ValueError unless the range interval is valid, the noise std finite and >= 0 and
    the mount's forward offset finite."""
    for name in ("min_range_m", "max_range_m", "mount_height_m"):
        check_positive(prefix, name, getattr(model, name))
    if model.min_range_m >= model.max_range_m:
        raise ValueError(
            f"{prefix}.min_range_m must be < max_range_m, "
            f"got {model.min_range_m} >= {model.max_range_m}"
        )
    check_positive(prefix, "range_noise_std_m", model.range_noise_std_m, allow_zero=True)
    check_finite(prefix, "mount_x_m", model.mount_x_m)


def _check_sectors(name: str, values: object, *, max_width_deg: float | None = None) -> None:
    """Raise unless ``values`` are one finite angle (deg) per sector; with ``max_width_deg``,
    cone widths in (0, max_width_deg]. Errors name ``sonar.<name>``."""
    if not isinstance(values, (tuple, list)):
        raise InvalidTypeError(
            f"sonar.{name} must be a tuple of {N_SONAR_SECTORS} angles (deg), "
            f"got {type(values).__name__} {values!r}"
        )
    if len(values) != N_SONAR_SECTORS:
        raise ValueError(
            f"sonar.{name} must be {N_SONAR_SECTORS} angles (deg; left, middle, right), "
            f"got {values!r}"
        )
    for k, value in enumerate(values):
        if max_width_deg is None:
            check_finite("sonar", f"{name}[{k}]", value)
        else:
            check_positive(
                "sonar", f"{name}[{k}]", value, upper=max_width_deg, upper_inclusive=True
            )


@dataclass(frozen=True, kw_only=True)
class LaserModel:
    """A planar laser scanner: ``n_beams`` beams evenly spaced over ``fov_deg`` from the robot's
    right, the first at ``-fov/2`` and the last a step short of ``+fov/2`` (seed 001's layout:
    half a step left of centred), in a horizontal plane ``mount_height_m`` above the ground.

    A scan is (n_beams,) ranges (m) from the scanner centre, beam i along ``beam_angles()[i]``;
    each range carries Gaussian noise of ``range_noise_std_m``, and a beam with no return in
    [``min_range_m``, ``max_range_m``] reads NaN. Defaults: seed 001's Hokuyo UST-30LX on a
    Pioneer 3-DX. Bad fields raise ``ValueError`` naming ``laser.<field>``.
    """

    n_beams: int = 180  # beams, evenly spaced over the field of view
    fov_deg: float = 180.0  # field of view (deg, in (0, 360]) from -fov/2 (beam_angles)
    min_range_m: float = 0.1  # nearer returns are dropped (seed 001's accuracy spec: 0.1-10 m)
    max_range_m: float = 10.0  # beams reach this far
    range_noise_std_m: float = 0.02  # Gaussian range noise (seed 001)
    mount_x_m: float = 0.0  # scanner centre ahead of the robot origin
    mount_height_m: float = 0.30  # scan plane above the ground (on top of a Pioneer 3-DX)

    def __post_init__(self) -> None:
        check_int("laser", "n_beams", self.n_beams, 1)
        check_positive("laser", "fov_deg", self.fov_deg, upper=360.0, upper_inclusive=True)
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
    at which bearing. Defaults: the Nao's chest sonar with seed 004's three sectors (Nao v3/v4
    spec: 60° cones, 0.25-2.55 m; rUNSWift's narrower middle sector). Bad fields raise
    ``ValueError`` naming ``sonar.<field>``.
    """

    sector_centres_deg: tuple[float, float, float] = (25.0, 0.0, -25.0)  # left, middle, right
    sector_widths_deg: tuple[float, float, float] = (60.0, 40.0, 60.0)  # 60° cones; middle ~40°
    min_range_m: float = 0.25  # no distance below this (Nao spec, seed 004)
    max_range_m: float = 2.55  # nothing heard beyond this (Nao spec, seed 004)
    max_echoes: int = 10  # echoes reported per sector, nearest first (NAOqi: 10)
    echo_merge_m: float = 0.05  # echoes closer than this merge into one (seed 004: 5 cm)
    range_noise_std_m: float = 0.01  # Gaussian noise on each echo's distance (Nao: 1 cm resolution)
    mount_x_m: float = 0.05  # ahead of the robot origin (Nao: 0.048-0.054 m ahead of the torso)
    mount_height_m: float = 0.30  # transducers on the chest, above the ground

    def __post_init__(self) -> None:
        _check_ranges("sonar", self)
        check_positive("sonar", "echo_merge_m", self.echo_merge_m)
        _check_sectors("sector_centres_deg", self.sector_centres_deg)
        _check_sectors("sector_widths_deg", self.sector_widths_deg, max_width_deg=180.0)
        check_int("sonar", "max_echoes", self.max_echoes, 1)

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
