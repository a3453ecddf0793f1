"""Multi-robot tracking: one constant-velocity Kalman filter per robot seen (seed 004 §6.2).

Each track estimates one other robot in the field frame (:mod:`perception.geometry`)::

    x = (x, y, vx, vy)        (4,)  m, m, m/s, m/s

Symbols, as in :mod:`perception.estimation.kalman` (filterpy; Bar-Shalom, Li & Kirubarajan,
*Estimation with Applications to Tracking and Navigation*, §6.2.2):

- ``x`` (4,), ``P`` (4, 4): a track's state mean and covariance (m, m/s and their products);
- ``F`` (4, 4): constant-velocity transition over ``dt`` seconds, ``[[I, dt I], [0, I]]``;
- ``Q`` (4, 4): covariance of the white-acceleration process noise over ``dt``, the exact
  discretisation of a continuous white acceleration of spectral density ``q`` (m²/s³) per
  axis: ``q [[dt³/3 I, dt²/2 I], [dt²/2 I, dt I]]``;
- ``z`` (2,): a sighting's robot position in the field frame (m);
- ``H`` (2, 4): ``[I, 0]``, the position part of the state;
- ``R`` (2, 2): covariance of ``z`` (m²), from the sighting's ``(range, bearing)`` covariance
  and the SLAM pose covariance, see :func:`sighting_in_field`;
- ``y`` (2,): innovation ``z - H x``;
- ``S`` (2, 2): innovation covariance ``H P H^T + R``;
- ``K`` (4, 2): Kalman gain ``P H^T S^-1``.

One :meth:`RobotTracker.update` per frame: predict every track to the frame's time, drop the
tracks unseen for more than ``drop_after_s``, move the sightings into the field with the SLAM
pose, gate them (chi-square, 2 dof on ``y^T S^-1 y``) and associate them with the tracks by
global nearest neighbour on the pairs' negative log-likelihood ``y^T S^-1 y + ln det S``, fuse
each matched sighting (Joseph form) and start a tentative track from each unmatched one. A
track is confirmed after ``confirm_hits`` sightings and keeps its id for life.

The pose error enters each ``R`` to first order, as if it were new in every sighting; in truth
the SLAM pose error is shared by the sightings of a frame and correlated over time, which this
filter ignores (it is slightly overconfident while the pose is uncertain).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TypeAlias, cast

import numpy as np
from numpy.typing import ArrayLike

from perception.estimation.association import (
    Association,
    global_nearest_neighbour,
    mahalanobis_cost_matrix,
)
from perception.estimation.gating import chi2_threshold
from perception.estimation.kalman import joseph_update, predict
from perception.geometry import FloatArray
from perception.tracking.checked_inputs import (
    TIME_ROUNDING_S,
    checked_self_pose,
    checked_sightings,
)
from perception.types import RobotSighting, RobotTrack, SlamEstimate
from perception.validation import (
    check_finite,
    check_int,
    check_positive,
    check_probability,
)

_H = np.hstack([np.eye(2), np.zeros((2, 2))])  # H (2, 4): the position part of x

SelfPose: TypeAlias = SlamEstimate | tuple[ArrayLike, ArrayLike]
"""The sensing robot's pose: a :class:`SlamEstimate`, or ``(pose (3,), pose_cov (3, 3))``."""


@dataclass(frozen=True, kw_only=True)
class RobotTrackerConfig:
    """Noise model and track management of :class:`RobotTracker`.

    - ``acceleration_psd`` (m²/s³, >= 0): spectral density ``q`` of the white acceleration
      driving each axis; a velocity random walk of variance ``q dt`` per ``dt`` seconds.
    - ``gate_probability`` (in (0, 1)): a sighting may join a track only when ``y^T S^-1 y``
      is within the chi-square (2 dof) quantile at this probability.
    - ``confirm_hits`` (>= 1): sightings (the first included) that confirm a track.
    - ``drop_after_s`` (s, > 0): a track unseen for longer than this is dropped.
    - ``initial_velocity_std`` (m/s, > 0): std of each velocity component of a new track.
    - ``max_tracks`` (>= 1): no track is started while this many exist.
    """

    acceleration_psd: float = 0.1  # m²/s³: q of the white acceleration, per axis
    gate_probability: float = 0.999  # chi-square (2 dof) gate probability, unitless
    confirm_hits: int = 3  # sightings that confirm a track (the first included)
    drop_after_s: float = 2.0  # s: tracks unseen for longer than this are dropped
    initial_velocity_std: float = 0.5  # m/s: std of vx and of vy of a new track
    max_tracks: int = 16  # tracks at most; further unmatched sightings start none

    def __post_init__(self) -> None:
        owner = "RobotTrackerConfig"
        check_positive(owner, "acceleration_psd", self.acceleration_psd, allow_zero=True)
        check_probability(owner, "gate_probability", self.gate_probability)
        check_int(owner, "confirm_hits", self.confirm_hits, 1)
        check_positive(owner, "drop_after_s", self.drop_after_s)
        check_positive(owner, "initial_velocity_std", self.initial_velocity_std)
        check_int(owner, "max_tracks", self.max_tracks, 1)

    @property
    def gate_threshold(self) -> float:
        """Chi-square (2 dof) quantile at ``gate_probability``: ``-2 ln(1 - p)`` (unitless)."""
        return chi2_threshold(self.gate_probability, 2)


def constant_velocity_model(dt: float, acceleration_psd: float) -> tuple[FloatArray, FloatArray]:
    """``F`` and ``Q`` (4, 4) over ``dt`` >= 0 seconds for the state ``(x, y, vx, vy)``.

    ``Q`` is the exact discrete covariance of a white acceleration of spectral density
    ``acceleration_psd`` (m²/s³) on each axis (module docstring).
    """
    check_positive("", "dt", dt, allow_zero=True)
    check_positive("", "acceleration_psd", acceleration_psd, allow_zero=True)
    F = np.eye(4)
    F[0, 2] = F[1, 3] = dt
    q = acceleration_psd
    Q = np.zeros((4, 4))
    Q[0, 0] = Q[1, 1] = q * (dt**3 / 3.0)
    Q[0, 2] = Q[1, 3] = Q[2, 0] = Q[3, 1] = q * (dt**2 / 2.0)
    Q[2, 2] = Q[3, 3] = q * dt
    return F, Q


def sighting_in_field(
    pose: ArrayLike, pose_cov: ArrayLike, range_m: float, bearing_rad: float, cov: ArrayLike
) -> tuple[FloatArray, FloatArray]:
    """``z`` (2,) and ``R`` (2, 2): a robot-frame sighting moved into the field frame.

    ``pose`` (3,) ``(x, y, theta)`` and ``pose_cov`` (3, 3) are the sensing robot's pose in the
    field frame and its covariance; ``(range_m, bearing_rad)`` the sighting in the robot frame
    with covariance ``cov`` (2, 2). With ``phi = theta + bearing``::

        z = (x + range cos(phi), y + range sin(phi))
        R = J_z cov J_z^T + J_pose pose_cov J_pose^T     (first order, symmetrised)

    ``J_z`` (2, 2) and ``J_pose`` (2, 3) being the Jacobians of ``z`` w.r.t. the sighting and
    the pose. The arguments are trusted (:meth:`RobotTracker.update` checks them).
    """
    x, y, theta = np.asarray(pose, dtype=np.float64)
    phi = theta + bearing_rad
    c, s = math.cos(phi), math.sin(phi)
    z = np.array([x + range_m * c, y + range_m * s])
    J_z = np.array([[c, -range_m * s], [s, range_m * c]])
    J_pose = np.array([[1.0, 0.0, -range_m * s], [0.0, 1.0, range_m * c]])
    R = J_z @ np.asarray(cov, dtype=np.float64) @ J_z.T
    R += J_pose @ np.asarray(pose_cov, dtype=np.float64) @ J_pose.T
    return z, 0.5 * (R + R.T)


@dataclass(kw_only=True)
class _Track:
    """A track's mutable filter state (the public view is :class:`RobotTrack`)."""

    track_id: int
    x: FloatArray  # (4,)
    P: FloatArray  # (4, 4)
    hits: int
    confirmed: bool
    last_seen_s: float
    votes: dict[int, int] = field(default_factory=dict)  # team -> sightings naming it

    def vote(self, team: int | None) -> None:
        """Count a sighting's team (None counts for nothing)."""
        if team is not None:
            self.votes[team] = self.votes.get(team, 0) + 1

    def team(self) -> int | None:
        """The team most sightings named; None on a tie for the most or without any vote."""
        if not self.votes:
            return None
        most = max(self.votes.values())
        leaders = [team for team, count in self.votes.items() if count == most]
        return leaders[0] if len(leaders) == 1 else None

    def view(self) -> RobotTrack:
        """A :class:`RobotTrack` with copies of the arrays."""
        return RobotTrack(
            track_id=self.track_id,
            state=self.x.copy(),
            cov=self.P.copy(),
            team=self.team(),
            confirmed=self.confirmed,
            last_seen_s=self.last_seen_s,
        )


class RobotTracker:
    """Tracks of the other robots in the field frame, from robot-frame sightings.

    Call :meth:`update` once per frame, at non-decreasing times, with that frame's sightings
    (possibly none) and the sensing robot's pose as SLAM believes it. :attr:`tracks` holds
    every track (tentative and confirmed) as of the latest update; :meth:`confirmed_tracks`
    the confirmed ones. Track ids are 0, 1, 2, ... in order of birth and never reused (until
    :meth:`reset`).
    """

    def __init__(self, config: RobotTrackerConfig | None = None) -> None:
        if config is None:
            config = RobotTrackerConfig()
        if not isinstance(config, RobotTrackerConfig):
            raise TypeError(f"config must be a RobotTrackerConfig, got {type(config).__name__}")
        self._config = config
        self._gate_threshold = config.gate_threshold
        self._tracks: list[_Track] = []
        self._time_s: float | None = None
        self._next_id = 0

    @property
    def config(self) -> RobotTrackerConfig:
        """The configuration the tracker was built with."""
        return self._config

    @property
    def time_s(self) -> float | None:
        """Time (s) of the latest :meth:`update`; None before the first."""
        return self._time_s

    @property
    def tracks(self) -> tuple[RobotTrack, ...]:
        """All tracks as of the latest update, by increasing ``track_id`` (copies)."""
        return tuple(track.view() for track in self._tracks)

    def confirmed_tracks(self) -> tuple[RobotTrack, ...]:
        """The confirmed tracks as of the latest update, by increasing ``track_id`` (copies)."""
        return tuple(track.view() for track in self._tracks if track.confirmed)

    def reset(self) -> None:
        """Forget every track and the time; the next track id is 0 again."""
        self._tracks = []
        self._time_s = None
        self._next_id = 0

    def update(
        self, time_s: float, sightings: Sequence[RobotSighting], self_pose: SelfPose
    ) -> tuple[RobotTrack, ...]:
        """Fuse one frame's sightings taken at ``time_s`` (s); return :attr:`tracks`.

        ``sightings`` are in the robot frame; ``self_pose`` is the sensing robot's pose in the
        field frame with its covariance (symmetric positive semidefinite; zero for an exactly
        known pose). Steps:

        1. predict every track to ``time_s`` (``F``, ``Q`` of :func:`constant_velocity_model`);
        2. drop the tracks last seen more than ``drop_after_s`` before ``time_s``;
        3. move each sighting into the field: ``z``, ``R`` of :func:`sighting_in_field`;
        4. ``d² = y^T S^-1 y`` of each track/sighting pair, ``S = H P H^T + R`` with that
           sighting's ``R``; pairs beyond the chi-square gate are never matched; the others
           are paired one to one by global nearest neighbour on ``d² + ln det S``;
        5. Joseph update of each matched track, which counts a hit and the sighting's team;
           a track is confirmed at its ``confirm_hits``-th hit;
        6. a tentative track from each unmatched sighting (while fewer than ``max_tracks``
           exist, in the order of ``sightings``): ``x = (z, 0, 0)``,
           ``P = diag(R, initial_velocity_std² I)``.

        Every argument is checked before the tracker changes; bad ones raise ValueError or
        TypeError naming them (``time_s`` must not be earlier than the previous update's).
        """
        check_finite("", "time_s", time_s)
        t = float(time_s)
        if self._time_s is not None and t < self._time_s:
            raise ValueError(f"time_s must not go backwards: got {time_s!r} after {self._time_s!r}")
        checked = _checked_sightings(sightings)
        pose, pose_cov = checked_self_pose(self_pose)

        config = self._config
        if self._time_s is not None and t > self._time_s:
            F, Q = constant_velocity_model(t - self._time_s, config.acceleration_psd)
            for track in self._tracks:
                track.x, track.P = predict(track.x, track.P, F, Q)
        self._time_s = t
        self._tracks = [
            track
            for track in self._tracks
            if t - track.last_seen_s <= config.drop_after_s + TIME_ROUNDING_S
        ]

        measurements = [
            sighting_in_field(pose, pose_cov, r, bearing, cov) for r, bearing, cov, _ in checked
        ]
        association = self._associate(measurements)
        for t_index, m_index in association.matches.tolist():
            track = self._tracks[t_index]
            z, R = measurements[m_index]
            track.x, track.P = joseph_update(track.x, track.P, z - _H @ track.x, _H, R)
            track.hits += 1
            track.confirmed = track.confirmed or track.hits >= config.confirm_hits
            track.last_seen_s = t
            track.vote(checked[m_index][3])
        for m_index in association.unmatched_measurements.tolist():
            if len(self._tracks) >= config.max_tracks:
                break
            z, R = measurements[m_index]
            self._start_track(z, R, t, team=checked[m_index][3])
        return self.tracks

    def _associate(self, measurements: list[tuple[FloatArray, FloatArray]]) -> Association:
        """Gate every track/sighting pair and associate them one to one (global nearest neighbour).

        ``R`` differs per sighting, so the kernel's cost matrix (one ``S`` per track) is built
        one sighting (column) at a time, with ``S = H P H^T + R`` of that pair. A pair is in the
        gate when ``d² = y^T S^-1 y`` is within the chi-square threshold. Among in-gate pairs the
        cost is ``d² + ln det S``, the negative log-likelihood of the pair up to a constant:
        with ``d²`` alone a diffuse (new or long unseen) track, whose large ``S`` makes every
        sighting look near, would take sightings from a precise track nearby.
        """
        n_tracks, n_measurements = len(self._tracks), len(measurements)
        d2 = np.empty((n_tracks, n_measurements))
        log_det = np.empty((n_tracks, n_measurements))
        if n_tracks:
            z_hat = np.array([_H @ track.x for track in self._tracks])  # (T, 2)
            HPHt = np.array([_H @ track.P @ _H.T for track in self._tracks])  # (T, 2, 2)
            for j, (z, R) in enumerate(measurements):
                S = HPHt + R  # (T, 2, 2)
                d2[:, j] = mahalanobis_cost_matrix(z_hat, S, z[None, :])[:, 0]
                log_det[:, j] = np.linalg.slogdet(S)[1]
        in_gate = d2 <= self._gate_threshold
        if not in_gate.any():
            return global_nearest_neighbour(np.full_like(d2, np.inf), 0.0)
        # Shifted to be >= 0 in the gate (a constant per pair: the optimal pairing is the
        # same); out of the gate +inf, beyond any threshold.
        cost = d2 + log_det - log_det[in_gate].min()
        cost = np.where(in_gate, cost, np.inf)
        return global_nearest_neighbour(cost, float(cost[in_gate].max()))

    def _start_track(
        self, z: FloatArray, R: FloatArray, time_s: float, *, team: int | None
    ) -> None:
        """Append a tentative track seen at ``z`` (2,), covariance ``R`` (2, 2), at ``time_s``."""
        config = self._config
        P = np.zeros((4, 4))
        P[:2, :2] = R
        P[2:, 2:] = config.initial_velocity_std**2 * np.eye(2)
        track = _Track(
            track_id=self._next_id,
            x=np.concatenate([z, np.zeros(2)]),
            P=P,
            hits=1,
            confirmed=config.confirm_hits <= 1,
            last_seen_s=time_s,
        )
        track.vote(team)
        self._tracks.append(track)
        self._next_id += 1


def _checked_sightings(
    sightings: object,
) -> list[tuple[float, float, FloatArray, int | None]]:
    """Check ``sightings``; return each one's ``(range_m, bearing_rad, cov (2, 2), team)``."""
    checked = checked_sightings(sightings, RobotSighting)
    out = []
    for i, sighting in enumerate(cast(Sequence[RobotSighting], sightings)):
        check_int(f"sightings[{i}]", "team", sighting.team, 0, optional=True)
        team = None if sighting.team is None else int(sighting.team)
        out.append((*checked[i], team))
    return out
