"""SPL field geometry (rule book 2025; :class:`FieldDimensions`, which perception owns as the
field map's source) and the landmark-pole layout of seed 000.

All numbers are metres in the field frame: origin at the centre spot, x towards the opponent
(positive) goal, y to the left, z up.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from perception.field.dimensions import FieldDimensions
from perception.geometry import FloatArray
from perception.types import PoleCode, PoleGeometry
from perception.validation import check_nested_configs, check_positive, check_reals

__all__ = ["FieldDimensions", "PoleLayout"]


@dataclass(frozen=True, kw_only=True)
class PoleLayout:
    """Six two-coloured landmark poles just outside the touch lines (seed 000 §3.1.2).

    Seed 000 spreads the Gutmann-Fox poles around a 9 x 6 m field: three along each touch line
    (by default at x = -3, 0 and 3 m), pink over a colour on the left side and the colour over
    pink on the right, so that every pole has a unique colour code.
    """

    x_positions_m: tuple[float, float, float] = (-3.0, 0.0, 3.0)
    offset_outside_m: float = 0.35  # beyond the touch line
    geometry: PoleGeometry = field(default_factory=PoleGeometry)

    def __post_init__(self) -> None:
        check_nested_configs(self)
        check_reals("PoleLayout", "x_positions_m", self.x_positions_m, 3)
        check_positive("PoleLayout", "offset_outside_m", self.offset_outside_m)

    def codes(self) -> tuple[PoleCode, ...]:
        """The six pole codes, ids 0..5: left side pink-over-colour, right side colour-over-pink."""
        colours = ("yellow", "green", "blue")
        left = [PoleCode(landmark_id=i, top="pink", bottom=c) for i, c in enumerate(colours)]
        right = [PoleCode(landmark_id=3 + i, top=c, bottom="pink") for i, c in enumerate(colours)]
        return tuple(left + right)

    def positions(self, dims: FieldDimensions) -> FloatArray:
        """(6, 2) field positions of the poles in id order."""
        y = dims.half_width_m + self.offset_outside_m
        xs = np.array(self.x_positions_m, dtype=np.float64)
        return np.concatenate(
            [np.column_stack([xs, np.full(3, y)]), np.column_stack([xs, np.full(3, -y)])]
        )
