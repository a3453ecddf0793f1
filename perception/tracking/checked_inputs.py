"""The checks the trackers make of their inputs before they change: range-and-bearing
sightings and the sensing robot's pose. Errors name the argument, what was expected and what
came. Also the slack of their time comparisons, :data:`TIME_ROUNDING_S`."""

from __future__ import annotations

from collections.abc import Sequence

from perception.geometry import FloatArray
from perception.types import BallSighting, RobotSighting, SlamEstimate
from perception.validation import (
    InvalidTypeError,
    check_covariance,
    check_finite,
    check_positive,
    finite_vector,
)

# frame times summed step by step come out a little off: 0.1 s added 20 times is not 2.0 s, so
# spans of frames are compared with this slack (s)
TIME_ROUNDING_S = 1e-9


def checked_sightings(
    sightings: object, kind: type[RobotSighting] | type[BallSighting]
) -> list[tuple[float, float, FloatArray]]:
    """Check ``sightings``, a sequence of ``kind`` (each with a finite ``score``); return each
    one's ``(range_m > 0, bearing_rad, cov (2, 2) positive definite)``."""
    if isinstance(sightings, (kind, str, bytes)) or not isinstance(sightings, Sequence):
        raise InvalidTypeError(
            f"sightings must be a sequence of {kind.__name__}, got {type(sightings).__name__}"
        )
    checked = []
    for i, sighting in enumerate(sightings):
        name = f"sightings[{i}]"
        if not isinstance(sighting, kind):
            raise InvalidTypeError(
                f"{name} must be a {kind.__name__}, got {type(sighting).__name__}"
            )
        check_positive(name, "range_m", sighting.range_m)
        check_finite(name, "bearing_rad", sighting.bearing_rad)
        check_finite(name, "score", sighting.score)
        if isinstance(sighting, RobotSighting) and sighting.team not in (None, 0, 1):
            raise ValueError(f"{name}.team must be 0, 1 or None, got {sighting.team!r}")
        cov = check_covariance(sighting.cov, f"{name}.cov", 2)
        checked.append((float(sighting.range_m), float(sighting.bearing_rad), cov))
    return checked


def checked_self_pose(self_pose: object) -> tuple[FloatArray, FloatArray]:
    """Check ``self_pose`` (a :class:`SlamEstimate` or a ``(pose, pose_cov)`` pair); return its
    pose (3,) and symmetrised positive semidefinite covariance (3, 3)."""
    if isinstance(self_pose, SlamEstimate):
        values, names = (
            (self_pose.pose, self_pose.pose_cov),
            ("self_pose.pose", "self_pose.pose_cov"),
        )
    elif isinstance(self_pose, (tuple, list)) and len(self_pose) == 2:
        values, names = (self_pose[0], self_pose[1]), ("self_pose[0]", "self_pose[1]")
    else:
        raise TypeError(
            "self_pose must be a SlamEstimate or a (pose (3,), pose_cov (3, 3)) pair, "
            f"got {type(self_pose).__name__}"
        )
    pose = finite_vector(values[0], names[0], 3)
    return pose, check_covariance(values[1], names[1], 3, singular_ok=True)
