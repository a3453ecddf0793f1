"""Data types passed between the sensors and the perception stack.

Every array is float64 numpy in SI units (metres, radians, seconds) unless stated. Frames are
defined in :mod:`perception.geometry`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from perception.geometry import FloatArray, camera_rotation
from perception.sensor_models import LaserModel, SonarModel
from perception.validation import check_finite, check_in_interval, check_positive, finite_vector

POLE_COLOURS: tuple[str, ...] = ("pink", "yellow", "blue", "green")


@dataclass(frozen=True, kw_only=True)
class PoleCode:
    """A two-coloured landmark pole: ``landmark_id`` and the colours of its upper and lower band."""

    landmark_id: int
    top: str
    bottom: str

    def __post_init__(self) -> None:
        for name, colour in (("top", self.top), ("bottom", self.bottom)):
            if colour not in POLE_COLOURS:
                raise ValueError(f"PoleCode.{name} must be one of {POLE_COLOURS}, got {colour!r}")
        if (self.top == "pink") == (self.bottom == "pink"):
            raise ValueError(
                f"PoleCode needs exactly one pink band, got top={self.top!r} bottom={self.bottom!r}"
            )


def pole_ids_by_colours(codes: Sequence[PoleCode]) -> dict[tuple[str, str], int]:
    """Landmark id of each ``(top, bottom)`` colour pair; ValueError if ``codes`` repeat a pair
    or an id."""
    ids: dict[tuple[str, str], int] = {}
    for code in codes:
        if (code.top, code.bottom) in ids or code.landmark_id in ids.values():
            raise ValueError(f"codes must have unique colour pairs and ids, got {code} twice")
        ids[(code.top, code.bottom)] = code.landmark_id
    return ids


@dataclass(frozen=True, kw_only=True)
class PoleGeometry:
    """Heights of a landmark pole's bands above the ground (m) and its radius (m)."""

    radius_m: float = 0.05  # pole radius
    base_top_m: float = 0.40  # top of the white base = bottom of the lower colour band
    band_height_m: float = 0.20  # height of each colour band

    def __post_init__(self) -> None:
        for name in ("radius_m", "base_top_m", "band_height_m"):
            check_positive("PoleGeometry", name, getattr(self, name))

    @property
    def lower_centre_m(self) -> float:
        """Height of the lower band's centre (m)."""
        return self.base_top_m + 0.5 * self.band_height_m

    @property
    def upper_centre_m(self) -> float:
        """Height of the upper band's centre (m)."""
        return self.base_top_m + 1.5 * self.band_height_m

    @property
    def top_m(self) -> float:
        """Height of the pole's top (m)."""
        return self.base_top_m + 2.0 * self.band_height_m


@dataclass(frozen=True, kw_only=True)
class CameraModel:
    """Pinhole intrinsics of an undistorted camera: image size (px) and horizontal FOV (deg).

    Square pixels; the principal point is ``(width / 2, height / 2)``. Pixel (column i, row j) is
    centred at ``(u, v) = (i, j)``. PyBullet's tiny renderer agrees along columns; its rows sit up
    to one pixel higher (``tests/spl_env/test_world.py``), which moves both band centres of a
    pole alike and so hardly its range.
    """

    width: int = 320
    height: int = 240
    hfov_deg: float = 56.3  # Nao v6 camera horizontal field of view

    def __post_init__(self) -> None:
        for name in ("width", "height"):
            value = getattr(self, name)
            if not isinstance(value, int) or isinstance(value, bool) or value < 16:
                raise ValueError(f"CameraModel.{name} must be an int >= 16, got {value!r}")
        check_in_interval("CameraModel", "hfov_deg", self.hfov_deg, 0.0, 180.0)

    @property
    def fx(self) -> float:
        """Focal length (px) along the image rows."""
        return 0.5 * self.width / math.tan(math.radians(self.hfov_deg) / 2.0)

    @property
    def fy(self) -> float:
        """Focal length (px) along the image columns (square pixels: equal to ``fx``)."""
        return self.fx

    @property
    def cx(self) -> float:
        """Principal point column (px)."""
        return 0.5 * self.width

    @property
    def cy(self) -> float:
        """Principal point row (px)."""
        return 0.5 * self.height

    @property
    def vfov_deg(self) -> float:
        """Vertical field of view (deg) implied by the aspect ratio."""
        return math.degrees(2.0 * math.atan(0.5 * self.height / self.fy))


@dataclass(frozen=True, kw_only=True)
class CameraState:
    """Where the camera is on the robot when a frame was taken, as the robot's joints report it.

    ``position`` is the optical centre (3,) in the robot frame (m); ``head_yaw``/``head_pitch``
    are the joint angles (rad) and ``tilt`` the camera's fixed downward tilt in the head (rad).
    """

    position: FloatArray
    head_yaw: float
    head_pitch: float
    tilt: float = 0.0

    def __post_init__(self) -> None:
        finite_vector(self.position, "CameraState.position", 3)
        for name in ("head_yaw", "head_pitch", "tilt"):
            check_finite("CameraState", name, getattr(self, name))

    def rotation(self) -> FloatArray:
        """(3, 3) camera-to-robot rotation: computed once per state (a frame's detectors ask
        for it many times), read-only."""
        cached: FloatArray | None = self.__dict__.get("_rotation")
        if cached is None:
            cached = camera_rotation(self.head_yaw, self.head_pitch + self.tilt)
            cached.setflags(write=False)
            object.__setattr__(self, "_rotation", cached)  # not a field: eq and repr ignore it
        return cached


@dataclass(frozen=True, kw_only=True)
class LandmarkObservation:
    """One landmark sighting in the robot frame: range (m), bearing (rad) and their covariance.

    ``cov`` is (2, 2) over ``(range, bearing)``. ``pixel`` is the (2,) image point the bearing was
    taken from; ``box`` is ``(u0, v0, u1, v1)`` in pixels.
    """

    landmark_id: int
    range_m: float
    bearing_rad: float
    cov: FloatArray
    pixel: FloatArray = field(default_factory=lambda: np.full(2, np.nan))
    box: FloatArray = field(default_factory=lambda: np.full(4, np.nan))
    score: float = 1.0


@dataclass(frozen=True, kw_only=True)
class RobotSighting:
    """One other robot seen from ours in one frame (robot frame, seed 004 §6.2).

    ``range_m`` (m) and ``bearing_rad`` (rad) locate the robot's centre on the ground; ``cov``
    (2, 2) is their covariance over ``(range, bearing)``. ``team`` is the waistband's team (0 or
    1, the world's team ids; ours is 0) or None when no waistband colour was found. ``box`` is
    the (4,) pixel box ``(u0, v0, u1, v1)`` it was seen in (NaN when not from an image);
    ``sonar_confirmed`` whether a sonar return confirmed (and set) its range.
    """

    range_m: float
    bearing_rad: float
    cov: FloatArray
    team: int | None = None
    box: FloatArray = field(default_factory=lambda: np.full(4, np.nan))
    sonar_confirmed: bool = False
    score: float = 1.0


@dataclass(frozen=True, kw_only=True)
class BallSighting:
    """The ball seen from our robot in one frame (robot frame).

    ``range_m`` (m) and ``bearing_rad`` (rad) locate the ball's centre over the ground; ``cov``
    (2, 2) is their covariance over ``(range, bearing)``; ``box`` the (4,) pixel box
    ``(u0, v0, u1, v1)`` it was seen in (NaN when not from an image); ``score`` the detector's.
    """

    range_m: float
    bearing_rad: float
    cov: FloatArray
    box: FloatArray = field(default_factory=lambda: np.full(4, np.nan))
    score: float = 1.0


@dataclass(frozen=True, kw_only=True)
class BallEstimate:
    """What perception believes about the ball.

    ``state`` (4,) ``(x, y, vx, vy)`` (m, m/s, field frame) with covariance ``cov`` (4, 4) (the
    believed pose's uncertainty included); ``relative`` (4,) the same in our robot's frame with
    ``relative_cov`` (4, 4); ``known`` False while no ball is believed: before its first
    sighting, or once lost (the states are then zero: the ball may be anywhere);
    ``last_seen_s`` the time (s) of its last sighting (-inf before the first); ``candidate``
    (2,) (m, robot frame) where a sighting waits for a second that agrees with it before a
    belief starts (the best-scored such; a head looking there gives it the chance), None when
    none waits.
    """

    state: FloatArray
    cov: FloatArray
    relative: FloatArray
    relative_cov: FloatArray
    known: bool
    last_seen_s: float
    candidate: FloatArray | None = None


@dataclass(frozen=True, kw_only=True)
class RobotTrack:
    """One tracked robot in the field frame.

    ``state`` (4,) is ``(x, y, vx, vy)`` (m, m/s) with covariance ``cov`` (4, 4); ``team`` the
    team by vote of its sightings (None if undecided); ``confirmed`` after enough hits;
    ``last_seen_s`` the time (s) of its last sighting; ``track_id`` stays with it for life.
    """

    track_id: int
    state: FloatArray
    cov: FloatArray
    team: int | None
    confirmed: bool
    last_seen_s: float


@dataclass(frozen=True, kw_only=True)
class MappedCircle:
    """One circle of the circle map (field frame).

    ``state`` (3,) ``(x, y, R)`` (m) with covariance ``cov`` (3, 3); ``hits`` the sightings
    fused into it; ``confirmed`` once it has enough of them; ``circle_id`` stays with it.
    """

    circle_id: int
    state: FloatArray
    cov: FloatArray
    hits: int
    confirmed: bool


@dataclass(frozen=True, kw_only=True)
class GroundTruth:
    """The true world, for oracle providers only (field frame, SI units).

    An env fills :attr:`SensorFrame.truth` only when a configured provider requires it, so
    that no other provider can read it. ``robot_pose`` (3,) is the sensing robot's pose;
    ``landmark_ids`` (L,) int and ``landmarks`` (L, 2) the mapped poles' ids and positions;
    ``robots`` (R, 2) the other robots' positions with their ``robot_teams`` (R,) (0 or 1);
    ``ball`` (2,) and ``ball_velocity`` (2,) (m, m/s), NaN in a world without a ball.
    """

    robot_pose: FloatArray
    landmark_ids: NDArray[np.int64]
    landmarks: FloatArray
    robots: FloatArray = field(default_factory=lambda: np.zeros((0, 2)))
    robot_teams: NDArray[np.int64] = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    ball: FloatArray = field(default_factory=lambda: np.full(2, np.nan))
    ball_velocity: FloatArray = field(default_factory=lambda: np.full(2, np.nan))


@dataclass(frozen=True, kw_only=True)
class SensorFrame:
    """What one robot's sensors deliver in one control step; every sensor is optional.

    - ``odometry_delta`` (3,): motion since the last frame in the previous odometry pose's frame
      (m, m, rad), or ``None``;
    - ``camera`` and ``camera_state``: the camera's intrinsics and its pose on the robot as the
      joints report it, or ``None`` for a robot without a camera;
    - ``image``: (H, W, 3) uint8 RGB, or ``None`` when nothing was rendered;
    - ``bottom_image`` and ``bottom_camera_state``: the same of a second, lower camera (a Nao's
      bottom camera, same intrinsics), or ``None`` when it is off;
    - ``sonar``: (3, E) echo distances (m) of the left/middle/right sectors, NaN-padded, or
      ``None``; ``sonar_model`` its sector geometry and noise;
    - ``sonar_ring``: (S,) ranges (m) of a ring of single sonars (a Pioneer's sixteen), one
      per sonar in the robot's ring order, NaN for no echo, or ``None``;
    - ``laser``: (B,) ranges (m) with NaN for no return, or ``None``; ``laser_model`` its beam
      angles (:meth:`perception.sensor_models.LaserModel.beam_angles`) and noise;
    - ``kick_velocity`` (2,): the ball velocity (m/s, robot frame) that a kick our robot's
      motion made since the last frame was meant to give; zero when it made none (always, for
      a robot that cannot kick);
    - ``emulated``: representations that a fast emulator produced in place of their providers
      (the geometric camera mode: ``{"pole_sightings": ...}``), keyed by representation name;
    - ``truth``: the ground truth, only when an oracle provider needs it, else ``None``.
    """

    time_s: float
    odometry_delta: FloatArray | None = None
    camera: CameraModel | None = None
    camera_state: CameraState | None = None
    image: NDArray[np.uint8] | None = None
    bottom_image: NDArray[np.uint8] | None = None
    bottom_camera_state: CameraState | None = None
    sonar: FloatArray | None = None
    sonar_model: SonarModel | None = None
    sonar_ring: FloatArray | None = None
    laser: FloatArray | None = None
    laser_model: LaserModel | None = None
    kick_velocity: FloatArray = field(default_factory=lambda: np.zeros(2))
    emulated: Mapping[str, Any] = field(default_factory=dict)
    truth: GroundTruth | None = None


@dataclass(frozen=True, kw_only=True)
class OdometryStep:
    """The motion since the last frame that the pose estimators use (robot frame of the last
    frame): ``delta`` (3,) dx, dy (m), dθ (rad); ``walk_delta`` (3,) what the walk engine
    reported. With visual odometry (seed 004 ch. 5) ``visual`` says dθ came from the horizon,
    ``confidence`` is its frame pair's vote margin (0 otherwise) and ``collision`` is 1 / -1
    while the body turns left / right of what the walk believes, else 0."""

    delta: FloatArray
    walk_delta: FloatArray
    visual: bool = False
    confidence: int = 0
    collision: int = 0


@dataclass(frozen=True, kw_only=True)
class SlamEstimate:
    """The robot pose and landmark map believed by a SLAM back end (field frame).

    ``pose`` (3,), ``pose_cov`` (3, 3); ``landmark_ids`` (L,) int; ``landmarks`` (L, 2);
    ``landmark_covs`` (L, 2, 2): the point landmarks (poles). ``circles``: the map of a back
    end whose landmarks are circles (columns, trunks, posts), ``(x, y, R)`` with (3, 3)
    covariances; empty for the point back ends.
    """

    pose: FloatArray
    pose_cov: FloatArray
    landmark_ids: NDArray[np.int64]
    landmarks: FloatArray
    landmark_covs: FloatArray
    circles: tuple[MappedCircle, ...] = ()


@dataclass(frozen=True, kw_only=True)
class TrackedPoseEstimate(SlamEstimate):
    """A :class:`SlamEstimate` of a filter that knows whether it is following the robot:
    ``accepted`` is True when this frame brought a pose observation that the filter's gate
    took (the frame's features agree with the pose it predicted), False when it brought none
    or one the gate refused; ``restarted`` is True when the filter restarted this frame from
    something other than its own prediction (a relocalisation from one frame's features, or a
    half turn through the centre spot), so that its pose may have jumped. The field-feature
    pose filter's estimate."""

    accepted: bool = False
    restarted: bool = False
