"""Raw range readings of a differential-drive robot: the laser scan, downsampled, and its sonar
ring."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from gymnasium import spaces

from perception.geometry import FloatArray
from perception.validation import check_int, check_positive
from spl_env.observations.base import EncoderInput, box, squash
from spl_env.observations.body import SONAR_SCALE_M


@dataclass(frozen=True)
class ScanEncoder:
    """``scan`` (bins,): the laser scan cut into ``bins`` equal runs of beams, right to left;
    each the nearest return of its run over ``max_range_m``, 1 when no beam of it returned
    (``n_beams`` must be a multiple of ``bins``)."""

    n_beams: int
    bins: int
    max_range_m: float
    requires: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        check_int("ScanEncoder", "bins", self.bins, 1)
        check_positive("ScanEncoder", "max_range_m", self.max_range_m)
        if self.n_beams % self.bins:
            raise ValueError(
                f"ScanEncoder.bins must divide the laser's {self.n_beams} beams, got {self.bins}"
            )

    def spaces(self) -> dict[str, spaces.Box]:
        return {"scan": box(0.0, 1.0, self.bins)}

    def encode(self, data: EncoderInput) -> dict[str, FloatArray]:
        scan = data.frame.laser
        if scan is None or scan.shape != (self.n_beams,):
            raise ValueError(
                f"ScanEncoder needs frame.laser of shape ({self.n_beams},), "
                f"got {None if scan is None else scan.shape}"
            )
        runs = np.where(np.isnan(scan), np.inf, scan).reshape(self.bins, -1).min(axis=1)
        return {"scan": np.minimum(runs / self.max_range_m, 1.0)}


@dataclass(frozen=True)
class SonarRingEncoder:
    """``sonar_ring`` (S,): each sonar's range d / (d + 1 m), ring order; 1 when no echo."""

    n_sonars: int
    requires: tuple[str, ...] = ()

    def spaces(self) -> dict[str, spaces.Box]:
        return {"sonar_ring": box(0.0, 1.0, self.n_sonars)}

    def encode(self, data: EncoderInput) -> dict[str, FloatArray]:
        ranges = data.frame.sonar_ring
        if ranges is None or ranges.shape != (self.n_sonars,):
            raise ValueError(
                f"SonarRingEncoder needs frame.sonar_ring of shape ({self.n_sonars},), "
                f"got {None if ranges is None else ranges.shape}"
            )
        out = np.ones(self.n_sonars)
        echo = np.isfinite(ranges)
        out[echo] = squash(ranges[echo], SONAR_SCALE_M)
        return {"sonar_ring": out}
