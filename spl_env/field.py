"""SPL field geometry (rule book 2025) and the landmark-pole layout of seed 000.

All numbers are metres in the field frame: origin at the centre spot, x towards the opponent
(positive) goal, y to the left, z up. Lines are described by their centre lines; each painted line
is ``line_width_m`` wide.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from perception.geometry import FloatArray
from perception.types import PoleCode, PoleGeometry


@dataclass(frozen=True, kw_only=True)
class FieldDimensions:
    """SPL rule book 2025 field numbers (m)."""

    length_m: float = 9.0  # between the goal lines
    width_m: float = 6.0  # between the touch lines
    line_width_m: float = 0.05
    border_strip_m: float = 0.7  # carpet beyond the outer lines
    centre_circle_diameter_m: float = 1.5
    penalty_area_length_m: float = 1.65
    penalty_area_width_m: float = 4.0
    goal_area_length_m: float = 0.6
    goal_area_width_m: float = 2.2
    penalty_mark_distance_m: float = 1.3  # from the goal line
    penalty_mark_diameter_m: float = 0.1
    goal_post_diameter_m: float = 0.1
    goal_inner_width_m: float = 1.5
    goal_height_m: float = 0.8
    goal_depth_m: float = 0.5
    ball_diameter_m: float = 0.1

    def __post_init__(self) -> None:
        for name, value in vars(self).items():
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"FieldDimensions.{name} must be finite and > 0, got {value}")
        if self.penalty_area_width_m >= self.width_m:
            raise ValueError(
                "FieldDimensions.penalty_area_width_m must be < width_m, "
                f"got {self.penalty_area_width_m} >= {self.width_m}"
            )

    @property
    def half_length_m(self) -> float:
        """Distance from the centre to a goal line (m)."""
        return 0.5 * self.length_m

    @property
    def half_width_m(self) -> float:
        """Distance from the centre to a touch line (m)."""
        return 0.5 * self.width_m

    @property
    def carpet_size_m(self) -> tuple[float, float]:
        """Carpet length and width (m), border strip included."""
        return (
            self.length_m + 2 * self.border_strip_m,
            self.width_m + 2 * self.border_strip_m,
        )

    def line_segments(self) -> FloatArray:
        """Straight field lines as (N, 4) rows ``(x0, y0, x1, y1)`` of their centre lines."""
        hl, hw = self.half_length_m, self.half_width_m
        segs = [
            (-hl, -hw, hl, -hw),  # touch lines
            (-hl, hw, hl, hw),
            (-hl, -hw, -hl, hw),  # goal lines
            (hl, -hw, hl, hw),
            (0.0, -hw, 0.0, hw),  # halfway line
        ]
        for side in (-1.0, 1.0):
            for depth, width in (
                (self.penalty_area_length_m, self.penalty_area_width_m),
                (self.goal_area_length_m, self.goal_area_width_m),
            ):
                x_in = side * (hl - depth)
                segs += [
                    (side * hl, -width / 2, x_in, -width / 2),
                    (side * hl, width / 2, x_in, width / 2),
                    (x_in, -width / 2, x_in, width / 2),
                ]
        return np.array(segs, dtype=np.float64)

    def penalty_marks(self) -> FloatArray:
        """(2, 2) centres of the penalty marks, own side first."""
        x = self.half_length_m - self.penalty_mark_distance_m
        return np.array([[-x, 0.0], [x, 0.0]])

    def goal_posts(self) -> FloatArray:
        """(4, 2) goal-post centres: own goal right, left, opponent goal right, left.

        The posts stand behind the goal line, their front touching its outer edge.
        """
        x = self.half_length_m + 0.5 * self.line_width_m + 0.5 * self.goal_post_diameter_m
        y = 0.5 * self.goal_inner_width_m + 0.5 * self.goal_post_diameter_m
        return np.array([[-x, -y], [-x, y], [x, -y], [x, y]])


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
        if len(self.x_positions_m) != 3:
            raise ValueError(
                f"PoleLayout.x_positions_m must hold 3 values, got {len(self.x_positions_m)}"
            )
        if not all(math.isfinite(x) for x in self.x_positions_m):
            raise ValueError(f"PoleLayout.x_positions_m must be finite, got {self.x_positions_m}")
        if not (math.isfinite(self.offset_outside_m) and self.offset_outside_m > 0):
            raise ValueError(
                f"PoleLayout.offset_outside_m must be finite and > 0, got {self.offset_outside_m}"
            )

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
