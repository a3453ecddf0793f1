"""Nao chest sonar with seed 004's three-sector scheme (Ch. 6).

The Nao has two ultrasonic transducer pairs on the chest, yawed 20-25° to either side, each
hearing a 60° cone from 0.25 m to 2.55 m (Nao v3/v4 spec, quoted by seed 004). rUNSWift's
hardware control scheme adds a third sector: transmitting on one side and receiving on the other
only hears obstacles in a narrower (about 40°) cone straight ahead. So the sonar reports, for a
left, a middle and a right sector, the distances of up to ``max_echoes`` echoes (NAOqi reports
10 per side).

Model: each sector is a horizontal fan of rays at the transducers' height. Consecutive rays that
hit the same body form one reflecting surface, whose echo is its nearest point (the first sound
back). Echoes closer together than ``echo_merge_m`` cannot be told apart and merge into the
nearer one (seed 004 clusters returns within 5 cm). Each echo then gets Gaussian range noise, is
lost with the dropout probability, and is dropped (never clipped) when outside the sonar's range.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from perception.geometry import FloatArray
from perception.sensor_models import N_SONAR_SECTORS, SonarModel
from perception.validation import check_in_interval, check_int
from spl_env.sensors.raycast import RayCaster, RayFan, cast


@dataclass(frozen=True, kw_only=True)
class SonarConfig(SonarModel):
    """Geometry and noise of the simulated Nao chest sonar.

    A :class:`perception.sensor_models.SonarModel` (defaults: the Nao's sonar with seed 004's
    three sectors), which validates its fields (``ValueError`` naming ``sonar.<field>``), plus
    two settings of the simulation's own: how finely each sector's cone is sampled and how often
    an echo is lost.
    """

    rays_per_sector: int = 31  # rays fanned evenly over each sector's width
    dropout_probability: float = 0.02  # chance that an echo is lost

    def __post_init__(self) -> None:
        super().__post_init__()
        check_int("sonar", "rays_per_sector", self.rays_per_sector, 1)
        check_in_interval(
            "sonar", "dropout_probability", self.dropout_probability, 0.0, 1.0, low_inclusive=True
        )


class Sonar:
    """Ray-cast model of the Nao sonar, reporting echo distances per left/middle/right sector;
    ``model`` (its config) is the geometry and noise it hears with."""

    def __init__(self, config: SonarConfig) -> None:
        self.config = config
        self.model: SonarModel = config
        n = config.rays_per_sector
        offsets = np.linspace(-0.5, 0.5, n) if n > 1 else np.zeros(1)
        centres = config.sector_centres_rad()[:, None]
        widths = config.sector_widths_rad()[:, None]
        self._angles = (centres + widths * offsets).ravel()
        self._fan = RayFan(
            mount_x_m=config.mount_x_m,
            mount_height_m=config.mount_height_m,
            angles=self._angles,
            length_m=config.max_range_m,
        )

    def ray_angles(self) -> FloatArray:
        """Directions (3 * rays_per_sector,) of the rays in the robot frame (rad), sector-major."""
        return self._angles.copy()

    def rays(self, robot_pose: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Field-frame ray (starts, ends), each (3 * rays_per_sector, 3) (m), sector-major.

        ``robot_pose`` is the robot's (3,) field pose ``(x, y, theta)``; rays run from the
        transducers out to ``max_range_m``.
        """
        return self._fan.rays(robot_pose)

    def measure(
        self,
        ray_caster: RayCaster,
        robot_pose: ArrayLike,
        rng: np.random.Generator,
        ignore_body: int = -1,
    ) -> FloatArray:
        """Echo distances (3, max_echoes) (m) of the left, middle and right sectors.

        Each row is sorted nearest first and NaN-padded. ``ignore_body`` is the robot's own body
        id, whose hits count as no echo, for a ``ray_caster`` that cannot pass through it (the
        rigs cast through their own robot instead: ``BulletWorld.ray_test(...,
        transparent_body=...)``).
        """
        starts, ends = self.rays(robot_pose)
        distances, bodies = cast(ray_caster, starts, ends, ignore_body)
        m, n = self.model, self.config.rays_per_sector
        ranges, hit = distances.tolist(), bodies.tolist()  # floats: 31 rays a sector
        out = np.full((N_SONAR_SECTORS, m.max_echoes), np.nan)
        for sector in range(N_SONAR_SECTORS):
            rows = slice(sector * n, (sector + 1) * n)
            true_echoes = merge_echoes(surface_echoes(ranges[rows], hit[rows]), m.echo_merge_m)
            if not true_echoes:  # silence: no echo, and no noise to draw
                continue
            echoes = self._noisy(true_echoes, rng)
            out[sector, : len(echoes)] = echoes
        return out

    def _noisy(self, echoes: list[float], rng: np.random.Generator) -> list[float]:
        """Add noise and dropouts to true echo distances; keep at most ``max_echoes`` in range,
        nearest first."""
        m = self.model
        noise = rng.standard_normal(len(echoes)).tolist()
        draws = rng.random(len(echoes)).tolist()
        noisy = [e + m.range_noise_std_m * z for e, z in zip(echoes, noise, strict=True)]
        kept = [
            r
            for r, u in zip(noisy, draws, strict=True)
            if u >= self.config.dropout_probability and m.min_range_m <= r <= m.max_range_m
        ]
        return sorted(kept)[: m.max_echoes]


def surface_echoes(distances: Sequence[float], bodies: Sequence[int]) -> list[float]:
    """Nearest distance (E of them) of each reflecting surface seen by a fan of rays, unsorted.

    ``distances`` (R,) are the rays' hit distances (NaN = no hit) and ``bodies`` (R,) the bodies
    hit (-1 = none), in angular order, as lists of floats and ints (a sector's few dozen rays:
    Python floats cost less than NumPy's calls); a surface is a run of consecutive rays on the
    same body (one whose nearest distance is not finite gives no echo).
    """
    nearest: list[float] = []
    surface = -1  # the body of the run the last ray belongs to (-1: no surface)
    for distance, body in zip(distances, bodies, strict=True):
        if body < 0 or math.isnan(distance):
            surface = -1
        elif body != surface:
            nearest.append(distance)
            surface = body
        elif distance < nearest[-1]:
            nearest[-1] = distance
    return [d for d in nearest if math.isfinite(d)]


def merge_echoes(echoes: Iterable[float], merge_m: float) -> list[float]:
    """Sorted echoes: each chain of echoes spaced less than ``merge_m`` becomes its nearest
    (NaN, no echo, is dropped)."""
    e = sorted(x for x in echoes if not math.isnan(x))
    return [x for before, x in itertools.pairwise([-math.inf, *e]) if x - before >= merge_m]
