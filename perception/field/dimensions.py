"""SPL field geometry (rule book 2025).

All numbers are metres in the field frame: origin at the centre spot, x towards the opponent
(positive) goal, y to the left, z up. Lines are described by their centre lines; each painted line
is ``line_width_m`` wide.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from perception.geometry import FloatArray


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
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise TypeError(
                    f"FieldDimensions.{name} must be a real number, got {type(value).__name__}"
                )
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"FieldDimensions.{name} must be finite and > 0, got {value}")
        half_length = self.half_length_m
        # (name, its extent, what it must stay within, that bound's name): the markings fit
        # inside the lines, one inside the other
        for name, extent, bound, within in (
            ("penalty_area_width_m", self.penalty_area_width_m, self.width_m, "width_m"),
            (
                "goal_area_width_m",
                self.goal_area_width_m,
                self.penalty_area_width_m,
                "penalty_area_width_m",
            ),
            (
                "goal_inner_width_m",
                self.goal_inner_width_m,
                self.goal_area_width_m,
                "goal_area_width_m",
            ),
            ("penalty_area_length_m", self.penalty_area_length_m, half_length, "length_m / 2"),
            (
                "goal_area_length_m",
                self.goal_area_length_m,
                self.penalty_area_length_m,
                "penalty_area_length_m",
            ),
            ("penalty_mark_distance_m", self.penalty_mark_distance_m, half_length, "length_m / 2"),
            (
                "centre_circle_diameter_m",
                self.centre_circle_diameter_m,
                min(self.width_m, self.length_m - 2 * self.penalty_area_length_m),
                "min(width_m, length_m - 2 penalty_area_length_m)",
            ),
        ):
            if extent >= bound:
                raise ValueError(
                    f"FieldDimensions.{name} must be < {within} ({bound}), got {extent}"
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
