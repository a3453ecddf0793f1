"""Range bands: an emulated detector's recall and noise, one value per band of range."""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np

from perception.validation import check_in_interval, check_positive


@dataclass(frozen=True, kw_only=True)
class RangeBands:
    """``band_edges_m`` (B,) (m, increasing, > 0) split the ranges into B + 1 bands;
    ``recall`` (the chance of a sighting), ``range_std_fraction`` (range noise std / range)
    and ``bearing_std_rad`` (rad) hold one value per band. Subclasses set the defaults."""

    band_edges_m: tuple[float, ...] = ()
    recall: tuple[float, ...]
    range_std_fraction: tuple[float, ...]
    bearing_std_rad: tuple[float, ...]

    def __post_init__(self) -> None:
        owner = type(self).__name__
        edges = self.band_edges_m
        if not (
            isinstance(edges, tuple)
            and all(isinstance(e, (int, float)) and math.isfinite(e) and e > 0 for e in edges)
            and all(a < b for a, b in itertools.pairwise(edges))
        ):
            raise ValueError(
                f"{owner}.band_edges_m must be a tuple of increasing ranges > 0, got {edges!r}"
            )
        for name in ("recall", "range_std_fraction", "bearing_std_rad"):
            values = getattr(self, name)
            if not (isinstance(values, tuple) and len(values) == len(edges) + 1):
                raise ValueError(
                    f"{owner}.{name} must hold one value per band ({len(edges) + 1}), "
                    f"got {values!r}"
                )
            for k, value in enumerate(values):
                if name == "recall":
                    check_in_interval(
                        owner, f"recall[{k}]", value, 0, 1, low_inclusive=True, high_inclusive=True
                    )
                else:
                    check_positive(owner, f"{name}[{k}]", value)

    def band(self, range_m: float) -> int:
        """The index of the band holding ``range_m`` (m)."""
        return int(np.searchsorted(self.band_edges_m, range_m, side="right"))
