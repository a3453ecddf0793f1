"""A pose observation: what the unified sensor model (:mod:`perception.field.sensor_model`) says
about the robot pose from one frame's field features, for a pose filter to fuse, and its form
as a linear measurement of the pose (:func:`whitened_measurement`), which both the field's pose
filter (:mod:`perception.field.pose_filter`) and EKF SLAM (:meth:`perception.slam.EkfSlam.
update_pose`) fuse."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from perception.estimation.kalman import wrapped_residual
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


_HEADING = (2,)  # index of the angle in a pose (x, y, theta)
# Eigenvalues of L below this fraction of its largest are rounding, not information: they are
# dropped from L^(1/2) and from a gate's degrees of freedom. L mixes units (1/m², 1/rad²),
# but no real observation is a billion times less certain in one direction than in another.
_RANK_RTOL = 1e-9


def whitened_measurement(
    observation: object, pose: FloatArray, weight: float, name: str = "observation"
) -> tuple[FloatArray, FloatArray, int]:
    """``observation`` (a :class:`PoseObservation`) of the pose estimate ``pose`` (3,) as the
    linear measurement ``y = H e`` with ``R = I``: ``e`` (3,) the residual ``z - pose`` (its
    heading wrapped), ``H = (weight L)^(1/2)`` (3, 3), the symmetric square root of the fused
    share ``weight`` (in (0, 1]) of the information ``L``, so that
    ``H^T R^-1 H = weight L``; and ``rank(L)``, the degrees of freedom of a gate on ``y``.

    Directions ``L`` does not inform (eigenvalues below ``1e-9`` of the largest) have zero rows
    in ``H``: a residual along them neither moves an estimate nor counts against a gate.
    Raises ``TypeError`` (naming ``name``) when ``observation`` is not a PoseObservation,
    ``ValueError`` for a ``weight`` outside (0, 1].
    """
    if not isinstance(observation, PoseObservation):
        raise TypeError(f"{name} must be a PoseObservation, got {type(observation).__name__}")
    check_positive("whitened_measurement", "weight", weight, upper=1.0, upper_inclusive=True)
    # Heading: near ±pi the plain difference z - x can be off by 2 pi.
    e = wrapped_residual(observation.pose, pose, _HEADING)
    eigenvalues, U = np.linalg.eigh(weight * observation.information)
    largest = float(eigenvalues[-1])
    kept = eigenvalues > _RANK_RTOL * largest if largest > 0 else np.zeros(3, dtype=bool)
    root = np.sqrt(np.where(kept, eigenvalues, 0.0))
    H = (U * root) @ U.T
    H = 0.5 * (H + H.T)
    return H @ e, H, int(kept.sum())
