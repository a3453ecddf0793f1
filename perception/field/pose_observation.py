"""A pose observation: what the unified sensor model (:mod:`perception.field.sensor_model`) says
about the robot pose from one frame's field features, for a pose filter to fuse."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from perception.geometry import FloatArray, wrap_angle
from perception.validation import (
    InvalidTypeError,
    check_covariance,
    check_positive,
    finite_vector,
)


@dataclass(frozen=True, eq=False)
class PoseObservation:
    """The robot pose ``(x, y, theta)`` (3,) (m, m, rad, field frame) that one frame's features
    put the robot at, and ``information`` (3, 3), the inverse of its covariance: symmetric
    positive semidefinite and possibly singular, since a single field line says nothing about
    where along it the robot stands (its direction along the line has zero information).

    ``rms_error_m``: the weighted RMS distance (m, >= 0) between the features, placed from
    ``pose``, and the map features they were matched to; ``features`` how many were used.
    """

    pose: FloatArray
    information: FloatArray
    rms_error_m: float
    features: int

    def __post_init__(self) -> None:
        pose = finite_vector(self.pose, "PoseObservation.pose", 3)
        pose[2] = wrap_angle(pose[2])
        information = check_covariance(
            self.information, "PoseObservation.information", 3, singular_ok=True
        )
        check_positive("PoseObservation", "rms_error_m", self.rms_error_m, allow_zero=True)
        if isinstance(self.features, bool) or not isinstance(self.features, (int, np.integer)):
            raise InvalidTypeError(
                f"PoseObservation.features must be an int, got {type(self.features).__name__}"
            )
        if self.features < 1:
            raise ValueError(f"PoseObservation.features must be >= 1, got {self.features}")
        object.__setattr__(self, "pose", pose)
        object.__setattr__(self, "information", information)
        object.__setattr__(self, "features", int(self.features))
