"""EKF SLAM with known correspondences (seed 000 chapter 2.1, Algorithm 5) and its back ends.

The state is the robot pose in the field frame followed by the field positions of the mapped
landmarks, in the order they were added to the map::

    mu = (x, y, theta, m1_x, m1_y, ..., mL_x, mL_y)        (3 + 2L,)  m, m, rad, m, ...

Symbols, as in the seed and in Thrun, Burgard & Fox, *Probabilistic Robotics*, ch. 10:

- ``mu``, ``Sigma``: state mean (3 + 2L,) and covariance (3 + 2L, 3 + 2L);
- ``G``: (3, 3) Jacobian of the motion model ``g(pose, delta)`` w.r.t. the pose;
- ``V``: (3, 3) Jacobian of ``g`` w.r.t. the odometry increment ``delta = (dx, dy, dtheta)``;
- ``M``: (3, 3) covariance of ``delta`` (robot frame), see :meth:`EkfSlamConfig.odometry_cov`;
- ``H``: Jacobian of the range-bearing model ``h`` (eq. 2.11) w.r.t. the state; only the pose
  and the observed landmark's columns are nonzero, so it is kept as a (2, 5) block;
- ``Q``: (2, 2) covariance of one ``(range, bearing)`` measurement ``z``;
- ``S``: (2, 2) innovation covariance ``H Sigma H^T + Q``;
- ``K``: (3 + 2L, 2) Kalman gain ``Sigma H^T S^-1``;
- ``y``: (2,) innovation ``z - h(mu)`` with the bearing wrapped.

The correction, its gate and the checks of inputs come from :mod:`perception.estimation` and
:mod:`perception.validation`, where (filterpy's symbols) this ``Q`` is called ``R``.

Besides the pole sightings, :meth:`EkfSlam.update_pose` fuses an observation of the pose itself
(the field features' unified sensor model): ``H`` is then (3, 3), ``(w L)^(1/2)`` on the pose
columns, with ``R = I`` (:func:`perception.field.pose_observation.whitened_measurement`); and
:meth:`EkfSlam.inflate_pose` adds to the pose block of ``Sigma`` motion the odometry did not
report.

The four back ends of seed 000 (§2.1.3, §3.2.1, Table 4.1), chosen by ``EkfSlamConfig.backend``:

- ``"classic"``: Algorithm 5. A landmark enters the map at its first sighting; every sighting
  of a mapped landmark is fused; all Jacobians are taken at the current estimate.
- ``"gated"``: a sighting of a mapped landmark is discarded when its range differs from the
  predicted range by more than ``gate_range_m`` (0.4 m) or its bearing by more than
  ``gate_bearing_rad`` (pi/3, wrapped). ``gate="mahalanobis"`` replaces these thresholds by a
  chi-square validation gate on ``y^T S^-1 y``.
- ``"minimal_view"``: a landmark enters the map only once it has been seen ``min_views``
  (default 3) times in about the same field position; it is initialised from the latest of
  those sightings and the earlier ones are discarded.
- ``"fej"``: the first-estimates Jacobian EKF of Huang, Mourikis & Roumeliotis (ICRA 2008).
  ``G`` uses the difference of the predicted positions ``p_{k+1|k} - p_{k|k-1}`` and ``H`` is
  taken at the predicted pose of the step and at each landmark's first estimate, so the filter
  keeps the 3 unobservable directions (global translation and rotation) of the true system and
  gains no spurious information about the heading.

``min_views`` and ``gate`` are independent of the back end: any back end may buffer new
landmarks and gate sightings of mapped ones (the seed's "minimal view FEJ-EKF, n=5").

Odometry noise is modelled on the robot-frame increment ``(dx, dy, dtheta)`` rather than on
``(rot1, trans, rot2)``: a Nao walks omnidirectionally, and a sidestep is then no noisier than a
step forward. Its variance grows linearly with the distance walked and the angle turned (a
random walk), so the accumulated uncertainty does not depend on how finely the motion is sliced
into increments (the form of the random errors in :mod:`spl_env.sensors.odometry`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from perception.estimation.gating import chi2_threshold, within_gate
from perception.estimation.kalman import innovation_covariance, joseph_update, wrapped_residual
from perception.field.pose_observation import PoseObservation, whitened_measurement
from perception.geometry import FloatArray, compose, wrap_angle
from perception.types import LandmarkObservation, SlamEstimate
from perception.validation import (
    check_choice,
    check_covariance,
    check_finite,
    check_int,
    check_positive,
    check_probability,
    finite_vector,
    is_finite_real,
)

_MIN_RANGE_M = 1e-6  # below this a landmark estimate sits on the robot and h cannot be linearised
_BEARING = (1,)  # index of the angle in a (range, bearing) measurement
_POSE = np.arange(3)  # state indices of the robot pose
_WHITE = np.eye(3)  # covariance of a whitened pose measurement (unitless)
_WHITE.flags.writeable = False

BACKENDS = ("classic", "gated", "minimal_view", "fej")  # values of EkfSlamConfig.backend
GATES = ("none", "thresholds", "mahalanobis")  # values of EkfSlamConfig.gate
_DEFAULT_MIN_VIEWS = {"minimal_view": 3}  # seed Table 4.1: n = 3 did best; 1 for the others
_DEFAULT_GATE = {"gated": "thresholds"}  # "none" for the others
# Positive real fields: name -> (upper bound, whether the bound itself is allowed); all are > 0.
_POSITIVE_LIMITS = {
    "gate_range_m": (math.inf, False),
    "gate_bearing_rad": (math.pi, True),
    "gate_probability": (1.0, False),
    "min_views_radius_m": (math.inf, False),
}


@dataclass(frozen=True, kw_only=True)
class EkfSlamConfig:
    """Noise model of :class:`EkfSlam`.

    With the odometry defaults as white noise, dead reckoning over a one-minute square walk
    (1.78 m sides at 0.15 m/s, 90° turns in place at 0.5 rad/s) ends 0.50 m from the truth on
    average (std 0.25; 1500 seeds), as in seed 000's Nao dataset (mean 0.50 m, std 0.20). Much
    of a Nao's drift is systematic, which a white-noise filter can only cover by a larger random
    walk, so these exceed the random part of :class:`spl_env.sensors.odometry.OdometryConfig`.

    The back end (see the module docstring) and its measurement filters:

    - ``backend``: one of :data:`BACKENDS`.
    - ``min_views``: sightings "in about the same place" a landmark needs before it enters the
      map (>= 1); None is the back end's default, :attr:`resolved_min_views`.
    - ``gate``: one of :data:`GATES`, the test a sighting of a mapped landmark must pass to be
      fused; None is the back end's default, :attr:`resolved_gate`.
    - ``gate_range_m`` (m), ``gate_bearing_rad`` (rad, in (0, pi]): the ``"thresholds"`` gate
      discards a sighting whose ``|y_range|`` or ``|wrap(y_bearing)|`` exceeds them (seed §3.2:
      0.4 m and pi/3).
    - ``gate_probability``: the ``"mahalanobis"`` gate discards a sighting whose
      ``y^T S^-1 y`` exceeds the chi-square (2 dof) quantile at this probability, in (0, 1).
    - ``min_views_radius_m`` (m): a new sighting counts towards ``min_views`` when its field
      position lies within this distance of the mean of the buffered positions.
    """

    translation_noise_m_per_sqrt_m: float = 0.13  # std of each of dx, dy per sqrt(m walked)
    translation_noise_m_per_sqrt_rad: float = 0.02  # std of each of dx, dy per sqrt(rad turned)
    heading_noise_rad_per_sqrt_m: float = 0.035  # std of dtheta per sqrt(m walked)
    rotation_noise_rad_per_sqrt_rad: float = 0.05  # std of dtheta per sqrt(rad turned)
    initial_pose_std: tuple[float, float, float] = (0.02, 0.02, 0.02)  # m, m, rad: start pose
    backend: str = "classic"
    min_views: int | None = None  # None: 3 for "minimal_view", 1 otherwise
    gate: str | None = None  # None: "thresholds" for "gated", "none" otherwise
    gate_range_m: float = 0.4  # m: largest |range - predicted range| fused by "thresholds"
    gate_bearing_rad: float = math.pi / 3  # rad: largest |wrapped bearing error| fused
    gate_probability: float = 0.99  # "mahalanobis": rejects beyond this chi-square(2) quantile
    min_views_radius_m: float = 0.5  # m: "about the same place" for min_views

    def __post_init__(self) -> None:
        for name in (
            "translation_noise_m_per_sqrt_m",
            "translation_noise_m_per_sqrt_rad",
            "heading_noise_rad_per_sqrt_m",
            "rotation_noise_rad_per_sqrt_rad",
        ):
            check_positive("EkfSlamConfig", name, getattr(self, name), allow_zero=True)
        std = self.initial_pose_std
        if not (
            isinstance(std, tuple)
            and len(std) == 3
            and all(is_finite_real(s) and s >= 0 for s in std)
        ):
            raise ValueError(
                "EkfSlamConfig.initial_pose_std must be a tuple of 3 finite values >= 0 "
                f"(m, m, rad), got {std!r}"
            )
        check_choice("EkfSlamConfig", "backend", self.backend, BACKENDS)
        check_choice("EkfSlamConfig", "gate", self.gate, GATES, optional=True)
        check_int("EkfSlamConfig", "min_views", self.min_views, 1, optional=True)
        for name, (upper, inclusive) in _POSITIVE_LIMITS.items():
            check_positive(
                "EkfSlamConfig", name, getattr(self, name), upper=upper, upper_inclusive=inclusive
            )

    @property
    def resolved_min_views(self) -> int:
        """``min_views``, or the back end's default when None: 3 for "minimal_view", else 1."""
        if self.min_views is not None:
            return int(self.min_views)
        return _DEFAULT_MIN_VIEWS.get(self.backend, 1)

    @property
    def resolved_gate(self) -> str:
        """``gate``, or the back end's default when None: "thresholds" for "gated", else "none"."""
        if self.gate is not None:
            return self.gate
        return _DEFAULT_GATE.get(self.backend, "none")

    @property
    def gate_mahalanobis_threshold(self) -> float:
        """Chi-square (2 dof) quantile at ``gate_probability``: ``-2 ln(1 - p)`` (unitless)."""
        return chi2_threshold(self.gate_probability, 2)

    def odometry_cov(self, odometry_delta: ArrayLike) -> FloatArray:
        """``M`` (3, 3): covariance of the odometry increment ``(dx, dy, dtheta)`` (robot frame).

        Diagonal, with ``d = hypot(dx, dy)`` (m)::

            var(dx) = var(dy) = translation_noise_m_per_sqrt_m² d
                                + translation_noise_m_per_sqrt_rad² |dtheta|
            var(dtheta) = heading_noise_rad_per_sqrt_m² d
                          + rotation_noise_rad_per_sqrt_rad² |dtheta|
        """
        dx, dy, dtheta = finite_vector(odometry_delta, "odometry_delta", 3)
        dist, turn = math.hypot(dx, dy), abs(dtheta)
        var_xy = (
            self.translation_noise_m_per_sqrt_m**2 * dist
            + self.translation_noise_m_per_sqrt_rad**2 * turn
        )
        var_theta = (
            self.heading_noise_rad_per_sqrt_m**2 * dist
            + self.rotation_noise_rad_per_sqrt_rad**2 * turn
        )
        return np.diag([var_xy, var_xy, var_theta])


def motion(pose: ArrayLike, delta: ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Odometry motion model ``g``: the pose (3,) after the increment, and ``G``, ``V`` (3, 3).

    ``pose`` (3,) is in the field frame; ``delta`` (3,) = ``(dx, dy, dtheta)`` in the frame of
    the previous pose. Seed eq. 2.9 with eq. 2.6-2.8 substituted gives
    ``delta_trans cos(theta + delta_rot1) = dx cos(theta) - dy sin(theta)`` (and likewise for
    y), i.e. exactly ``compose(pose, delta)``; computing it that way needs no atan2, so a turn in
    place (``delta_trans ~ 0``, ``delta_rot1`` undefined) is exact.
    """
    theta = float(np.asarray(pose, dtype=np.float64)[2])
    dx, dy, _ = np.asarray(delta, dtype=np.float64)
    c, s = math.cos(theta), math.sin(theta)
    G = np.array([[1.0, 0.0, -s * dx - c * dy], [0.0, 1.0, c * dx - s * dy], [0.0, 0.0, 1.0]])
    V = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    return compose(pose, delta), G, V


def observe(pose: ArrayLike, landmark: ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Range-bearing model ``h`` (eq. 2.11): ``z_hat`` (2,), ``H_pose`` (2, 3), ``H_lm`` (2, 2).

    ``pose`` (3,) and ``landmark`` (2,) are in the field frame; ``z_hat`` is (range m, bearing
    rad in the robot frame, wrapped to [-pi, pi)). Raises ValueError when the landmark is
    within 1 µm of the robot, where the bearing is undefined.
    """
    x, y, theta = np.asarray(pose, dtype=np.float64)
    dx, dy = np.asarray(landmark, dtype=np.float64) - (x, y)
    q = dx * dx + dy * dy
    r = math.sqrt(q)
    if r < _MIN_RANGE_M:
        raise ValueError(f"landmark estimate {r:.2g} m from the robot: h cannot be linearised")
    z_hat = np.array([r, float(wrap_angle(math.atan2(dy, dx) - theta))])
    H_lm = np.array([[dx / r, dy / r], [-dy / q, dx / q]])
    H_pose = np.column_stack([-H_lm, [0.0, -1.0]])
    return z_hat, H_pose, H_lm


def inverse_observe(pose: ArrayLike, z: ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Landmark field position ``m`` (2,) seen at ``z = (range, bearing)`` from ``pose`` (3,).

    Also returns the Jacobians ``dm/dpose`` (2, 3) and ``dm/dz`` (2, 2) (Algorithm 5 line 11).
    """
    x, y, theta = np.asarray(pose, dtype=np.float64)
    r, bearing = np.asarray(z, dtype=np.float64)
    c, s = math.cos(theta + bearing), math.sin(theta + bearing)
    m = np.array([x + r * c, y + r * s])
    J_pose = np.array([[1.0, 0.0, -r * s], [0.0, 1.0, r * c]])
    J_z = np.array([[c, -r * s], [s, r * c]])
    return m, J_pose, J_z


class EkfSlam:
    """EKF SLAM over the robot pose and point landmarks with known ids (field frame).

    ``initial_pose`` (3,) is the start pose ``(x, y, theta)``; its covariance is
    ``diag(config.initial_pose_std)²``. Call :meth:`predict` with each odometry increment and
    :meth:`update` with each frame's landmark sightings. ``config.backend`` picks the back end
    (module docstring); ``config.resolved_min_views`` and ``config.resolved_gate`` the filters.

    Linearisation points. Step k is everything between the k-th :meth:`predict` and the next;
    ``p_{k|k-1}`` (:attr:`predicted_pose`) is the pose right after that predict, before any
    update (the initial pose before the first predict), and ``p_{k|k}`` the current pose.

    - classic ``G``: ``[[1, 0, -(y_{k+1|k} - y_{k|k})], [0, 1, x_{k+1|k} - x_{k|k}], [0, 0, 1]]``;
      FEJ ``G``: the same with ``p_{k|k-1}`` in place of ``p_{k|k}`` (Huang et al. 2008).
      ``V`` is taken at the current heading ``theta_{k|k}`` in both.
    - classic ``H``: at the current pose and landmark estimate; FEJ ``H`` (pose and landmark
      blocks): at ``p_{k|k-1}`` and at the landmark's first estimate, its position when it was
      added to the map, for every sighting of the step (even after earlier sightings of the same
      :meth:`update` call moved the pose). ``H`` does not depend on the heading. The innovation
      ``y = z - h(mu)`` always uses the current estimate.

    See :meth:`linearisation_point`, :meth:`measurement_jacobian` and :attr:`motion_jacobian`.
    """

    def __init__(self, config: EkfSlamConfig, initial_pose: ArrayLike) -> None:
        if not isinstance(config, EkfSlamConfig):
            raise TypeError(f"config must be an EkfSlamConfig, got {type(config).__name__}")
        self._config = config
        self._fej = config.backend == "fej"
        self._min_views = config.resolved_min_views
        self._gate = config.resolved_gate
        # only a Mahalanobis gate computes its threshold (chi2_threshold imports scipy.stats)
        self._gate_threshold = (
            config.gate_mahalanobis_threshold if self._gate == "mahalanobis" else math.inf
        )
        self._mu = finite_vector(initial_pose, "initial_pose", 3)
        self._mu[2] = wrap_angle(self._mu[2])
        self._sigma = np.diag(np.square(np.asarray(config.initial_pose_std, dtype=np.float64)))
        self._column: dict[int, int] = {}  # landmark id -> index of its x in mu
        self._first_estimate: dict[int, FloatArray] = {}  # landmark id -> (2,) m when added
        self._pending: dict[int, list[FloatArray]] = {}  # unmapped id -> buffered (2,) positions
        self._predicted_pose = self._mu.copy()  # p_{k|k-1}
        self._G = np.eye(3)  # G of the latest predict
        self._rejected = 0
        self._rejected_poses = 0

    @property
    def config(self) -> EkfSlamConfig:
        """The configuration the filter was built with."""
        return self._config

    @property
    def mean(self) -> FloatArray:
        """``mu`` (3 + 2L,), a copy."""
        return self._mu.copy()

    @property
    def cov(self) -> FloatArray:
        """``Sigma`` (3 + 2L, 3 + 2L), a copy."""
        return self._sigma.copy()

    @property
    def landmark_ids(self) -> tuple[int, ...]:
        """Ids of the mapped landmarks in state order."""
        return tuple(self._column)

    @property
    def rejected(self) -> int:
        """How many sightings of mapped landmarks the gate has discarded so far."""
        return self._rejected

    @property
    def rejected_poses(self) -> int:
        """How many pose observations :meth:`update_pose`'s gate has refused so far."""
        return self._rejected_poses

    @property
    def pending_views(self) -> dict[int, int]:
        """Unmapped landmark id -> consistent sightings buffered towards ``min_views`` (a copy)."""
        return {landmark_id: len(views) for landmark_id, views in self._pending.items()}

    @property
    def predicted_pose(self) -> FloatArray:
        """``p_{k|k-1}`` (3,): the pose after the latest predict, before any update (a copy)."""
        return self._predicted_pose.copy()

    @property
    def motion_jacobian(self) -> FloatArray:
        """``G`` (3, 3) the latest :meth:`predict` used (the identity before the first), a copy."""
        return self._G.copy()

    def linearisation_point(self, landmark_id: int) -> tuple[FloatArray, FloatArray]:
        """Pose (3,) and landmark position (2,) at which ``H`` of a sighting is taken now.

        Classic: the current estimates. FEJ: ``p_{k|k-1}`` and the landmark's first estimate.
        Raises ValueError when the landmark is not mapped.
        """
        self._require_mapped(landmark_id, "landmark_id")
        if self._fej:
            return self._predicted_pose.copy(), self._first_estimate[landmark_id].copy()
        column = self._column[landmark_id]
        return self._mu[:3].copy(), self._mu[column : column + 2].copy()

    def measurement_jacobian(self, landmark_id: int) -> FloatArray:
        """``H`` (2, 3 + 2L) of a sighting of a mapped landmark, as :meth:`update` would use it."""
        self._require_mapped(landmark_id, "landmark_id")
        H_block, index = self._jacobian(landmark_id)
        H = np.zeros((2, len(self._mu)))
        H[:, index] = H_block
        return H

    def predict(self, odometry_delta: ArrayLike) -> None:
        """Move the pose by the odometry increment ``(dx, dy, dtheta)`` (m, m, rad).

        The increment is in the frame of the previous odometry pose. Only the pose block and the
        pose-landmark cross blocks of ``Sigma`` change: O(L) per call. FEJ takes ``G`` from
        ``p_{k+1|k} - p_{k|k-1}`` (class docstring).
        """
        delta = finite_vector(odometry_delta, "odometry_delta", 3)
        pose, G, V = motion(self._mu[:3], delta)
        if self._fej:
            G = first_estimates_motion_jacobian(pose, self._predicted_pose)
        M = self._config.odometry_cov(delta)
        sigma = self._sigma
        pose_cov = G @ sigma[:3, :3] @ G.T + V @ M @ V.T
        sigma[:3, :3] = 0.5 * (pose_cov + pose_cov.T)
        sigma[:3, 3:] = G @ sigma[:3, 3:]
        sigma[3:, :3] = sigma[:3, 3:].T
        self._mu[:3] = pose
        self._predicted_pose = pose.copy()
        self._G = G

    def update(self, observations: Sequence[LandmarkObservation]) -> int:
        """Fuse landmark sightings one after another (Algorithm 5 lines 8-19); return how many.

        A sighting of a mapped landmark corrects the state unless the gate rejects it (then it
        changes nothing but :attr:`rejected`). A sighting of an unmapped one is buffered; the
        ``min_views``-th consistent one adds the landmark to the map. The return value counts
        corrections and additions: ``len(observations)`` minus rejected and buffered sightings.
        All observations are checked before any is used, so a bad one leaves the filter
        unchanged.
        """
        if isinstance(observations, LandmarkObservation) or not isinstance(observations, Sequence):
            raise TypeError(
                "observations must be a sequence of LandmarkObservation, "
                f"got {type(observations).__name__}"
            )
        checked = [_measurement(obs, f"observations[{i}]") for i, obs in enumerate(observations)]
        before = self._map_state()  # a sighting the model cannot use leaves the filter as it was
        fused = 0
        for k, (landmark_id, z, Q) in enumerate(checked):
            try:
                if landmark_id in self._column:
                    fused += self._correct(landmark_id, z, Q)
                else:
                    fused += self._sight_unmapped(landmark_id, z, Q)
            except ValueError as error:
                self._restore(before)
                raise ValueError(f"observations[{k}] cannot be used: {error}") from error
        return fused

    def _map_state(self) -> tuple[Any, ...]:
        """What :meth:`update` changes, to put back (the arrays are replaced, never written)."""
        pending = {k: list(v) for k, v in self._pending.items()}
        return (
            self._mu,
            self._sigma,
            dict(self._column),
            dict(self._first_estimate),
            pending,
            self._rejected,
        )

    def _restore(self, state: tuple[Any, ...]) -> None:
        """Put back a :meth:`_map_state`."""
        (self._mu, self._sigma, self._column, self._first_estimate, self._pending) = state[:5]
        self._rejected = state[5]

    def update_pose(
        self,
        observation: PoseObservation,
        *,
        weight: float = 1.0,
        gate_probability: float | None = None,
    ) -> bool:
        """Fuse an observation of the robot pose itself (the field features' unified sensor
        model, :func:`perception.field.sensor_model.observe_pose`); return whether it was fused.

        The observation is the linear measurement ``y = H e`` of the pose block with ``R = I``
        (:func:`~perception.field.pose_observation.whitened_measurement`: ``H = (weight
        L)^(1/2)``, ``weight`` in (0, 1] the share of its information ``L`` fused), so the
        update is ``Sigma+ = (Sigma^-1 + weight L_full)^-1`` with ``L`` in the pose block; the
        cross-covariances carry it to the landmarks. ``H`` does not depend on the state, so
        every back end (FEJ too) takes the same update. With ``gate_probability`` in (0, 1),
        the observation is refused (counted in :attr:`rejected_poses`, the filter unchanged)
        when ``y^T S^-1 y`` exceeds the chi-square quantile with ``rank(L)`` degrees of freedom;
        None fuses every observation. One that carries no information is not fused either.
        """
        if gate_probability is not None:
            check_probability("update_pose", "gate_probability", gate_probability)
        y, H, rank = whitened_measurement(observation, self._mu[:3], weight)
        if rank == 0:
            return False
        S = innovation_covariance(self._sigma, H, _WHITE, _POSE)
        if gate_probability is not None and not within_gate(
            y, S, chi2_threshold(gate_probability, rank)
        ):
            self._rejected_poses += 1
            return False
        self._apply(y, H, _WHITE, _POSE, S)
        return True

    def inflate_pose(self, extra_cov: ArrayLike) -> None:
        """Add ``extra_cov`` (3, 3), symmetric positive semidefinite (m², m², rad² and
        products), to the pose block of ``Sigma``: motion the odometry did not report (a
        slip, a blocked walk), so later observations may pull the pose back. The landmarks'
        blocks and the cross-covariances stay; ``Sigma`` stays positive semidefinite. A bad
        argument raises and leaves the filter unchanged."""
        extra = check_covariance(extra_cov, "extra_cov", 3, singular_ok=True)
        self._sigma[:3, :3] += extra

    def innovation(self, observation: LandmarkObservation) -> tuple[FloatArray, FloatArray]:
        """``y`` (2,) and ``S`` (2, 2) of a sighting of an already mapped landmark.

        These are what :meth:`update` would gate on and fuse (FEJ: ``S`` with the FEJ ``H``).
        Leaves the filter unchanged. Raises ValueError when the landmark is not mapped.
        """
        landmark_id, z, Q = _measurement(observation, "observation")
        self._require_mapped(landmark_id, "observation.landmark_id")
        y, S, _, _ = self._linearise(landmark_id, z, Q)
        return y, S

    def estimate(self) -> SlamEstimate:
        """The current pose and map as a :class:`SlamEstimate` (copies)."""
        n_landmarks = len(self._column)
        columns = 3 + 2 * np.arange(n_landmarks)
        blocks = columns[:, None] + np.arange(2)  # (L, 2) state indices of each landmark
        return SlamEstimate(
            pose=self._mu[:3].copy(),
            pose_cov=self._sigma[:3, :3].copy(),
            landmark_ids=np.array(self.landmark_ids, dtype=np.int64),
            landmarks=self._mu[3:].reshape(n_landmarks, 2).copy(),
            landmark_covs=self._sigma[blocks[:, :, None], blocks[:, None, :]],
        )

    def _require_mapped(self, landmark_id: int, name: str) -> None:
        """Raise ValueError naming ``name`` unless ``landmark_id`` is in the map."""
        check_int("EkfSlam", name, landmark_id)
        if landmark_id not in self._column:
            raise ValueError(f"{name} {landmark_id} is not mapped; mapped ids: {self.landmark_ids}")

    def _jacobian(self, landmark_id: int) -> tuple[FloatArray, FloatArray]:
        """The nonzero block of ``H`` (2, 5) at the linearisation point, and its state indices."""
        column = self._column[landmark_id]
        if self._fej:
            _, H_pose, H_lm = observe(self._predicted_pose, self._first_estimate[landmark_id])
        else:
            _, H_pose, H_lm = observe(self._mu[:3], self._mu[column : column + 2])
        return np.hstack([H_pose, H_lm]), np.array([0, 1, 2, column, column + 1])

    def _linearise(
        self, landmark_id: int, z: FloatArray, Q: FloatArray
    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """``y`` (2,), ``S`` (2, 2), the nonzero block of ``H`` (2, 5) and its state indices."""
        column = self._column[landmark_id]
        z_hat, _, _ = observe(self._mu[:3], self._mu[column : column + 2])
        # Bearings are angles: near ±pi (behind the robot) z - h(mu) can be off by 2 pi.
        y = wrapped_residual(z, z_hat, _BEARING)
        H, index = self._jacobian(landmark_id)
        return y, innovation_covariance(self._sigma, H, Q, index), H, index

    def _passes_gate(self, y: FloatArray, S: FloatArray) -> bool:
        """Whether the gate lets a sighting with innovation ``y`` and covariance ``S`` through."""
        config = self._config
        if self._gate == "thresholds":
            return abs(y[0]) <= config.gate_range_m and abs(y[1]) <= config.gate_bearing_rad
        if self._gate == "mahalanobis":
            return within_gate(y, S, self._gate_threshold)
        return True

    def _correct(self, landmark_id: int, z: FloatArray, Q: FloatArray) -> bool:
        """One gated EKF correction with a sighting of a mapped landmark; whether it was fused."""
        y, S, H, index = self._linearise(landmark_id, z, Q)
        if not self._passes_gate(y, S):
            self._rejected += 1
            return False
        self._apply(y, H, Q, index, S)  # Q is the measurement covariance (the kernel's R)
        return True

    def _apply(
        self, y: FloatArray, H: FloatArray, R: FloatArray, index: ArrayLike, S: FloatArray
    ) -> None:
        """The Joseph-form correction with innovation ``y``, the nonzero block ``H`` of the
        measurement Jacobian at state ``index``, measurement covariance ``R`` and ``S``
        (sparse H: O(n^2)); the heading wrapped."""
        mu, self._sigma = joseph_update(self._mu, self._sigma, y, H, R, index, S=S)
        mu[2] = wrap_angle(mu[2])
        self._mu = mu

    def _sight_unmapped(self, landmark_id: int, z: FloatArray, Q: FloatArray) -> bool:
        """Buffer a sighting of an unmapped landmark; add it at the ``min_views``-th in place.

        The sighting's field position is ``inverse_observe`` from the current pose. It joins the
        buffer when within ``min_views_radius_m`` of the buffer's mean and restarts the buffer
        otherwise. A full buffer is dropped and the landmark added from this latest sighting.
        Returns whether the landmark was added.
        """
        if self._min_views > 1:
            m, _, _ = inverse_observe(self._mu[:3], z)
            views = self._pending.get(landmark_id, [])
            if views:
                offset = m - np.mean(views, axis=0)
                if math.hypot(offset[0], offset[1]) > self._config.min_views_radius_m:
                    views = []
            views.append(m)
            if len(views) < self._min_views:
                self._pending[landmark_id] = views
                return False
            self._pending.pop(landmark_id, None)
        self._add_landmark(landmark_id, z, Q)
        return True

    def _add_landmark(self, landmark_id: int, z: FloatArray, Q: FloatArray) -> None:
        """Append a landmark from a sighting, with its full first-order covariance."""
        m, J_pose, J_z = inverse_observe(self._mu[:3], z)
        n = len(self._mu)
        cross = J_pose @ self._sigma[:3, :]  # Cov(m, state) (2, n)
        sigma_mm = cross[:, :3] @ J_pose.T + J_z @ Q @ J_z.T
        sigma = np.empty((n + 2, n + 2))
        sigma[:n, :n] = self._sigma
        sigma[n:, :n] = cross
        sigma[:n, n:] = cross.T
        sigma[n:, n:] = 0.5 * (sigma_mm + sigma_mm.T)
        self._sigma = sigma
        self._mu = np.concatenate([self._mu, m])
        self._column[landmark_id] = n
        self._first_estimate[landmark_id] = m


def first_estimates_motion_jacobian(
    predicted: ArrayLike, previous_predicted: ArrayLike
) -> FloatArray:
    """FEJ ``G`` (3, 3) from the new prediction ``p_{k+1|k}`` and the previous ``p_{k|k-1}``.

    Both are (3,) poses in the field frame; only their positions enter (Huang, Mourikis &
    Roumeliotis 2008): ``[[1, 0, -(y_{k+1|k} - y_{k|k-1})], [0, 1, x_{k+1|k} - x_{k|k-1}],
    [0, 0, 1]]``.
    """
    x1, y1, _ = np.asarray(predicted, dtype=np.float64)
    x0, y0, _ = np.asarray(previous_predicted, dtype=np.float64)
    return np.array([[1.0, 0.0, -(y1 - y0)], [0.0, 1.0, x1 - x0], [0.0, 0.0, 1.0]])


def _measurement(obs: object, name: str) -> tuple[int, FloatArray, FloatArray]:
    """Check one sighting; return its landmark id, ``z`` (2,) and ``Q`` (2, 2)."""
    if not isinstance(obs, LandmarkObservation):
        raise TypeError(f"{name} must be a LandmarkObservation, got {type(obs).__name__}")
    check_int(name, "landmark_id", obs.landmark_id)
    check_positive(name, "range_m", obs.range_m)
    check_finite(name, "bearing_rad", obs.bearing_rad)
    Q = check_covariance(obs.cov, f"{name}.cov", 2)
    z = np.array([obs.range_m, obs.bearing_rad], dtype=np.float64)
    return int(obs.landmark_id), z, Q
