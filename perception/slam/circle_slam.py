"""Online EKF SLAM with circular landmarks (columns, tree trunks) from odometry and laser circles.

Seed 001 (chapter 5) maps circles offline from GPS or true poses because dead reckoning drifts;
here the robot pose and the circles are estimated together, online, from the robot-frame
odometry increments and the circles fitted to each laser scan (:mod:`perception.circles.fits`).

State, in the world (field) frame, circles in the order they entered the map::

    mu = (x, y, theta, c1_x, c1_y, R1, ..., cK_x, cK_y, RK)        (3 + 3K,)  m, m, rad, m, ...

Symbols as in :mod:`perception.slam.ekf_slam` and :mod:`perception.estimation.kalman`:
``Sigma`` (3 + 3K, 3 + 3K) the state covariance; ``G``, ``V`` (3, 3) the Jacobians of the motion
model ``g`` w.r.t. the pose and the increment; ``M`` (3, 3) the increment's covariance; ``z``
(3,) a circle observation ``(z_x, z_y, z_R)`` (m, robot frame) and ``Q`` (3, 3) its covariance
(the kernel's ``R``, here taken by the radius); ``H`` the measurement Jacobian, nonzero only in
the pose's and the observed circle's columns, kept as a (3, 6) block; ``y = z - h(mu)``, ``S =
H Sigma H^T + Q`` (3, 3).

Motion (:func:`perception.slam.ekf_slam.motion`, the odometry model of the point SLAM): the
increment ``u = (dx, dy, dtheta)`` is given in the frame of the previous pose, ``p' = p ⊕ u``,
and only the pose rows of the state move::

    Sigma_pp <- G Sigma_pp G^T + V M V^T,        Sigma_pm <- G Sigma_pm

Measurement: seen from the pose ``(p, theta)``, ``p = (x, y)``, a circle ``(c, R)``,
``c = (c_x, c_y)``, appears at its centre in the robot frame with its radius (``Rot(a)``: the
rotation by ``a``)::

    h(pose, circle) = (Rot(-theta) (c - p), R)

    d = c - p,  (cos, sin) = (cos theta, sin theta),  (h_x, h_y) = Rot(-theta) d:

    H_pose   = [[-cos, -sin,  h_y],        H_circle = [[ cos, sin, 0],
                [ sin, -cos, -h_x],                    [-sin, cos, 0],
                [   0,    0,    0]]                    [   0,   0, 1]]

Its inverse initialises a circle, ``circle = (p + Rot(theta) z_xy, z_R)``, with the Jacobians
``J_pose = [[1, 0, -w_y], [0, 1, w_x], [0, 0, 0]]`` (``w = Rot(theta) z_xy``) and ``J_z =
diag(Rot(theta), 1)``; the new blocks are ``Sigma_mm = J_pose Sigma_pp J_pose^T + J_z Q J_z^T``
and ``Sigma_m* = J_pose Sigma_p*``. No entry of ``z`` is an angle, so ``y`` needs no wrapping.

One :meth:`CircleSlam.update` with the observations of a scan:

1. Radius bounds. An observation whose ``z_R`` lies outside ``radius_bounds_m`` is refused.
2. Association. The cost of observation j for circle k is ``y^T S^-1 y`` (chi-square, 3 dof,
   for a correct pair), at the state before this update; global nearest neighbour
   (:func:`~perception.estimation.association.global_nearest_neighbour`) pairs them one to one
   inside the gate ``chi2_3(gate_probability)``.
3. Correction. The pairs are fused one after another, each linearised at the current estimate,
   with the Joseph form (:func:`~perception.estimation.kalman.joseph_update`), which keeps
   ``Sigma`` symmetric positive semidefinite under rounding. R > 0 is kept by refusal, not by a
   change of variable: the radii stay in the state as they are (``h`` is then linear in them)
   and a correction whose result would put any radius outside ``radius_bounds_m`` is refused
   whole, leaving the state as it was. Nothing is clipped.
4. New circles. An unpaired observation whose cost exceeds ``chi2_3(new_circle_probability)``
   (a stricter probability than the gate's) for every mapped circle is a sighting of a new one;
   one between the two thresholds is ambiguous and is dropped. With ``min_views`` n > 1 (the
   minimal view of seed 000 Table 4.1) a new sighting first joins a tentative circle, by global
   nearest neighbour of world-frame centres within ``min_views_radius_m`` of the mean of its
   earlier sightings (else it starts one); the n-th sighting adds the circle, initialised from
   that latest sighting alone. A tentative circle unseen for ``min_views_max_age`` updates is
   forgotten, so spurious circles never reach the map nor pile up. With ``admission =
   "provisional"`` a new circle enters the state at its first sighting instead, *provisional*
   until its ``min_views``-th (:attr:`CircleSlam.confirmed`), and one unseen for
   ``min_views_max_age`` updates before that is removed from the state (marginalised: its rows
   and columns dropped, exact for a Gaussian). The map is then anchored at the pose of each
   circle's first sighting, not of its n-th, when dead reckoning has drifted further.

Ranges (:meth:`CircleSlam.update_scan`): a scan may instead be given as its segments
(:class:`ArcObservation`), each fused by its beams' ranges against seed 001's polar model of a
mapped circle (eq. 3.2, convex side, :func:`perception.circles.model.measure_arc`: ``z`` the k
ranges of the beams that meet the circle away from its tangents, ``H`` (k, 6) on the pose and
the circle, ``Q = sigma_r^2 I``). An arc pairs with a circle by global nearest neighbour on its
normalised innovation squared over the chi-square (k dof) quantile of ``gate_probability`` (in
the gate: <= 1) and is fused by an iterated EKF (:mod:`perception.slam.circle_observations`).
Only arcs that some circle explains within the range noise (``ArcObservation.circular``, the
classification's test) pair by their ranges: the flat face of a trunk cut by a chord, with its
rounded ends, is explained by neither a line nor a circle. Ranges carry no fit's bias: a circle
fit of a short arc is pulled towards a smaller radius, and one is only made when the arc looks
curved enough not to be a line, a selection that pulls the same way. Arcs that pair with no
circle go through steps 1-4 by their circle fit, when they have one.

Consistency (tests/perception/test_circle_slam.py, 30 Monte Carlo laps among 4 columns): the
pose NEES stays in its 95 % chi-square band; the map NEES does at a quarter of the default
odometry noise but not at the default, where the linearisation in the heading makes the map
2-4 times overconfident (the EKF's known inconsistency).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from perception.estimation.association import global_nearest_neighbour, mahalanobis_cost_matrix
from perception.estimation.gating import chi2_threshold
from perception.estimation.kalman import innovation_covariance, joseph_update
from perception.geometry import FloatArray, wrap_angle
from perception.slam.circle_observations import (
    ArcCircle,
    ArcObservation,
    CircleObservation,
    arc_cost,
    checked_arcs,
    fuse_arc,
)
from perception.slam.ekf_slam import EkfSlamConfig, motion
from perception.validation import (
    InvalidTypeError,
    check_choice,
    check_covariance,
    check_finite,
    check_int,
    check_positive,
    check_probability,
    finite_vector,
    is_finite_real,
)

IntArray = NDArray[np.intp]
Admission = Literal["buffered", "provisional"]
ADMISSIONS: tuple[Admission, ...] = ("buffered", "provisional")

_POSE = 3  # entries of the pose in the state
_CIRCLE = 3  # entries of a circle in the state: (c_x, c_y, R)
_DOF = 3  # dimension of a circle observation, for the chi-square gates
_ODOMETRY_FIELDS = (
    "translation_noise_m_per_sqrt_m",
    "translation_noise_m_per_sqrt_rad",
    "heading_noise_rad_per_sqrt_m",
    "rotation_noise_rad_per_sqrt_rad",
)


@dataclass(frozen=True, kw_only=True)
class CircleSlamConfig:
    """Noise model, gates and map-building rules of :class:`CircleSlam`.

    Odometry: the random walk of :meth:`EkfSlamConfig.odometry_cov` (same fields, same
    formula), with defaults loose enough to cover, as white noise, the heading drift of
    :class:`spl_env.robots.diff_drive.DiffDriveConfig`'s default encoders (about 0.019 rad per
    m driven, mostly systematic); not a fit to data. :meth:`CircleSlam.predict` may take an
    increment's covariance instead.

    - ``initial_pose_std`` (m, m, rad): standard deviations of the start pose, the default of
      :meth:`CircleSlam.reset`.
    - ``gate_probability``: an observation pairs with a circle only inside the chi-square (3
      dof) gate of this probability, in (0, 1).
    - ``new_circle_probability``: an unpaired observation is a new circle only outside every
      mapped circle's gate of this probability, in [``gate_probability``, 1).
    - ``min_views`` (>= 1): consistent sightings a new circle needs before it enters the map
      (1: at once); ``min_views_radius_m`` (m): a sighting is consistent with a tentative
      circle when its world centre lies within this of the mean of the earlier ones;
      ``min_views_max_age`` (>= 1): a tentative circle unseen for this many updates is dropped.
    - ``radius_bounds_m`` (m): ``(low, high)``, ``0 < low < high``: the radii an observation
      may report and the map may hold (module docstring, R > 0 by refusal).
    - ``admission``: ``"buffered"`` (default: sightings wait outside the state until the
      ``min_views``-th) or ``"provisional"`` (new circles enter the state at once and leave it
      unless confirmed in time; module docstring, step 4).
    """

    translation_noise_m_per_sqrt_m: float = 0.05  # std of each of dx, dy per sqrt(m driven)
    translation_noise_m_per_sqrt_rad: float = 0.01  # std of each of dx, dy per sqrt(rad turned)
    heading_noise_rad_per_sqrt_m: float = 0.05  # std of dtheta per sqrt(m driven)
    rotation_noise_rad_per_sqrt_rad: float = 0.03  # std of dtheta per sqrt(rad turned)
    initial_pose_std: tuple[float, float, float] = (0.02, 0.02, 0.02)  # m, m, rad
    gate_probability: float = 0.99  # chi-square(3) gate of association
    new_circle_probability: float = 0.9999  # chi-square(3) gate a new circle lies outside of
    min_views: int = 3  # seed 000 Table 4.1: n = 3 did best for point landmarks
    min_views_radius_m: float = 0.2  # m: "about the same place" for min_views
    min_views_max_age: int = 10  # updates: a tentative circle unseen this long is forgotten
    radius_bounds_m: tuple[float, float] = (0.01, 2.0)  # m: columns and trunks
    admission: Admission = "buffered"

    def __post_init__(self) -> None:
        owner = "CircleSlamConfig"
        for name in _ODOMETRY_FIELDS:
            check_positive(owner, name, getattr(self, name), allow_zero=True)
        _check_tuple(owner, "initial_pose_std", self.initial_pose_std, 3, "(m, m, rad)")
        check_probability(owner, "gate_probability", self.gate_probability)
        check_probability(owner, "new_circle_probability", self.new_circle_probability)
        if self.new_circle_probability < self.gate_probability:
            raise ValueError(
                f"{owner}.new_circle_probability must be >= gate_probability "
                f"({self.gate_probability!r}), got {self.new_circle_probability!r}"
            )
        check_int(owner, "min_views", self.min_views, 1)
        check_positive(owner, "min_views_radius_m", self.min_views_radius_m)
        check_int(owner, "min_views_max_age", self.min_views_max_age, 1)
        _check_tuple(owner, "radius_bounds_m", self.radius_bounds_m, 2, "(low, high) in m")
        check_choice(owner, "admission", self.admission, ADMISSIONS)
        low, high = self.radius_bounds_m
        if not 0.0 < low < high:
            raise ValueError(
                f"{owner}.radius_bounds_m must satisfy 0 < low < high, got {self.radius_bounds_m!r}"
            )

    @property
    def gate_threshold(self) -> float:
        """Chi-square (3 dof) quantile at ``gate_probability`` (unitless)."""
        return chi2_threshold(self.gate_probability, _DOF)

    @property
    def new_circle_threshold(self) -> float:
        """Chi-square (3 dof) quantile at ``new_circle_probability`` (unitless)."""
        return chi2_threshold(self.new_circle_probability, _DOF)

    @cached_property
    def _odometry(self) -> EkfSlamConfig:
        """The point SLAM's config with these odometry fields, for its noise model."""
        return EkfSlamConfig(**{name: getattr(self, name) for name in _ODOMETRY_FIELDS})

    def odometry_cov(self, increment: ArrayLike) -> FloatArray:
        """``M`` (3, 3) of a robot-frame increment ``(dx, dy, dtheta)`` (m, m, rad).

        :meth:`perception.slam.ekf_slam.EkfSlamConfig.odometry_cov` with this config's fields.
        """
        return self._odometry.odometry_cov(increment)


@dataclass(frozen=True)
class CircleUpdateResult:
    """What :meth:`CircleSlam.update` did with each of its M observations (indices into them).

    Every observation index appears in exactly one field:

    - ``matched`` (F, 2): (circle, observation) pairs fused into the state;
    - ``added`` (A, 2): (circle, observation): circles this update added to the map;
    - ``buffered`` (B,): sightings of new circles held by tentative circles (``min_views``);
    - ``ambiguous`` (D,): unpaired, yet inside the new-circle gate of a mapped circle: dropped;
    - ``refused`` (E,): radius outside ``radius_bounds_m``, observed or after the correction;
    - ``dropped`` (G,): arcs of :meth:`CircleSlam.update_scan` without a fit that met no
      circle (always empty from :meth:`CircleSlam.update`).
    """

    matched: IntArray
    added: IntArray
    buffered: IntArray
    ambiguous: IntArray
    refused: IntArray
    dropped: IntArray = field(default_factory=lambda: np.zeros(0, dtype=np.intp))


@dataclass
class _Outcome:
    """What an update did so far, as lists of observation indices (of pairs for the first
    two), for :class:`CircleUpdateResult`."""

    matched: list[tuple[int, int]] = field(default_factory=list)
    added: list[tuple[int, int]] = field(default_factory=list)
    buffered: list[int] = field(default_factory=list)
    ambiguous: list[int] = field(default_factory=list)
    refused: list[int] = field(default_factory=list)
    dropped: list[int] = field(default_factory=list)

    def result(self) -> CircleUpdateResult:
        """The lists as index arrays, the unpaired ones sorted."""
        return CircleUpdateResult(
            matched=np.array(self.matched, dtype=np.intp).reshape(-1, 2),
            added=np.array(self.added, dtype=np.intp).reshape(-1, 2),
            buffered=np.array(self.buffered, dtype=np.intp),
            ambiguous=np.array(sorted(self.ambiguous), dtype=np.intp),
            refused=np.array(sorted(self.refused), dtype=np.intp),
            dropped=np.array(sorted(self.dropped), dtype=np.intp),
        )


def observe_circle(pose: ArrayLike, circle: ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray]:
    """``h``: the circle (3,) ``(c_x, c_y, R)`` (m, world) seen from ``pose`` (3,) (world).

    Returns ``z_hat`` (3,) ``(Rot(-theta) (c - p), R)`` (m, robot frame) and the Jacobians
    ``H_pose`` (3, 3) and ``H_circle`` (3, 3) (module docstring).
    """
    x, y, theta = np.asarray(pose, dtype=np.float64)
    cx, cy, R = np.asarray(circle, dtype=np.float64)
    c, s = np.cos(theta), np.sin(theta)
    dx, dy = cx - x, cy - y
    hx, hy = c * dx + s * dy, -s * dx + c * dy
    z_hat = np.array([hx, hy, R])
    H_pose = np.array([[-c, -s, hy], [s, -c, -hx], [0.0, 0.0, 0.0]])
    H_circle = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
    return z_hat, H_pose, H_circle


def inverse_observe_circle(
    pose: ArrayLike, z: ArrayLike
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """The circle (3,) ``(c_x, c_y, R)`` (m, world) seen at ``z`` (3,) (m, robot frame).

    Also returns the Jacobians ``J_pose`` (3, 3) and ``J_z`` (3, 3) (module docstring).
    """
    x, y, theta = np.asarray(pose, dtype=np.float64)
    zx, zy, R = np.asarray(z, dtype=np.float64)
    c, s = np.cos(theta), np.sin(theta)
    wx, wy = c * zx - s * zy, s * zx + c * zy
    circle = np.array([x + wx, y + wy, R])
    J_pose = np.array([[1.0, 0.0, -wy], [0.0, 1.0, wx], [0.0, 0.0, 0.0]])
    J_z = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    return circle, J_pose, J_z


@dataclass
class _Tentative:
    """A circle seen fewer than ``min_views`` times: its world circles (3,) and last update."""

    views: list[FloatArray]
    last_seen: int

    @property
    def centre(self) -> FloatArray:
        """Mean world centre (2,) of the views (m)."""
        return np.mean(self.views, axis=0)[:2]


class CircleSlam:
    """EKF SLAM over the robot pose and circles (module docstring for the model and the rules).

    ``pose`` (3,) ``(x, y, theta)`` (m, m, rad, world) and ``pose_cov`` (3, 3) start the filter,
    as :meth:`reset`. Call :meth:`predict` with each odometry increment and :meth:`update` with
    each scan's circles.
    """

    def __init__(
        self,
        config: CircleSlamConfig,
        pose: ArrayLike = (0.0, 0.0, 0.0),
        pose_cov: ArrayLike | None = None,
    ) -> None:
        if not isinstance(config, CircleSlamConfig):
            raise InvalidTypeError(
                f"config must be a CircleSlamConfig, got {type(config).__name__}"
            )
        self._config = config
        self._gate = config.gate_threshold
        self._new_gate = config.new_circle_threshold
        self._mu = np.zeros(_POSE)
        self._sigma = np.zeros((_POSE, _POSE))
        self._tentative: list[_Tentative] = []
        self._ids: list[int] = []  # per mapped circle: its id, in the order circles were added
        self._next_id = 0
        self._hits: list[int] = []  # per mapped circle: sightings fused, its first included
        self._last_seen: list[int] = []  # per mapped circle: the update that last fused it
        self._updates = 0
        self.reset(pose, pose_cov)

    def reset(self, pose: ArrayLike, pose_cov: ArrayLike | None = None) -> None:
        """Forget the map; start again at ``pose`` (3,) (m, m, rad, world).

        ``pose_cov`` (3, 3), symmetric positive semidefinite; None: ``diag(initial_pose_std)²``.
        """
        mu = finite_vector(pose, "pose", _POSE)
        mu[2] = wrap_angle(mu[2])
        if pose_cov is None:
            sigma = np.diag(np.square(np.asarray(self._config.initial_pose_std, dtype=np.float64)))
        else:
            sigma = check_covariance(pose_cov, "pose_cov", _POSE, singular_ok=True)
        self._mu, self._sigma = mu, sigma
        self._tentative = []
        self._ids, self._hits, self._last_seen = [], [], []
        self._next_id = 0
        self._updates = 0

    @property
    def config(self) -> CircleSlamConfig:
        """The configuration the filter was built with."""
        return self._config

    @property
    def mean(self) -> FloatArray:
        """``mu`` (3 + 3K,), a copy."""
        return self._mu.copy()

    @property
    def cov(self) -> FloatArray:
        """``Sigma`` (3 + 3K, 3 + 3K), a copy."""
        return self._sigma.copy()

    @property
    def pose(self) -> FloatArray:
        """``(x, y, theta)`` (3,) (m, m, rad, world), a copy."""
        return self._mu[:_POSE].copy()

    @property
    def pose_cov(self) -> FloatArray:
        """The pose's covariance (3, 3), a copy."""
        return self._sigma[:_POSE, :_POSE].copy()

    @property
    def circles(self) -> FloatArray:
        """The mapped circles (K, 3) ``(c_x, c_y, R)`` (m, world), in the order they entered."""
        return self._mu[_POSE:].reshape(-1, _CIRCLE).copy()

    @property
    def circle_covs(self) -> FloatArray:
        """Their covariances (K, 3, 3) (m²)."""
        blocks = _POSE + _CIRCLE * np.arange(self.n_circles)[:, None] + np.arange(_CIRCLE)
        return self._sigma[blocks[:, :, None], blocks[:, None, :]]

    @property
    def n_circles(self) -> int:
        """K, the number of mapped circles."""
        return (len(self._mu) - _POSE) // _CIRCLE

    @property
    def circle_ids(self) -> IntArray:
        """Per mapped circle (K,): its id, 0, 1, ... in the order circles entered the map; it
        stays with the circle when provisional circles before it leave the state."""
        return np.array(self._ids, dtype=np.intp)

    @property
    def hits(self) -> IntArray:
        """Per mapped circle (K,): the sightings fused into it (with the one that added it)."""
        return np.array(self._hits, dtype=np.intp)

    @property
    def confirmed(self) -> NDArray[np.bool_]:
        """Per mapped circle (K,): whether it is confirmed (``hits >= min_views``; every
        circle of the ``"buffered"`` admission, which maps circles only then)."""
        if self._config.admission == "buffered":
            return np.ones(self.n_circles, dtype=bool)
        return self.hits >= self._config.min_views

    @property
    def tentative_circles(self) -> FloatArray:
        """Circles (T, 3) (m, world) seen fewer than ``min_views`` times: their mean sighting."""
        means = [np.mean(t.views, axis=0) for t in self._tentative]
        return np.array(means).reshape(-1, _CIRCLE)

    def predict(self, increment: ArrayLike, increment_cov: ArrayLike | None = None) -> None:
        """Move the pose by the odometry increment ``(dx, dy, dtheta)`` (3,) (m, m, rad).

        The increment is in the frame of the previous pose; ``increment_cov`` (3, 3) is its
        covariance ``M`` (symmetric positive semidefinite), None: ``config.odometry_cov``.
        """
        delta = finite_vector(increment, "increment", 3)
        if increment_cov is None:
            M = self._config.odometry_cov(delta)
        else:
            M = check_covariance(increment_cov, "increment_cov", 3, singular_ok=True)
        pose, G, V = motion(self._mu[:_POSE], delta)
        sigma = self._sigma
        pose_cov = G @ sigma[:_POSE, :_POSE] @ G.T + V @ M @ V.T
        sigma[:_POSE, :_POSE] = 0.5 * (pose_cov + pose_cov.T)
        sigma[:_POSE, _POSE:] = G @ sigma[:_POSE, _POSE:]
        sigma[_POSE:, :_POSE] = sigma[:_POSE, _POSE:].T
        self._mu[:_POSE] = pose

    def update(self, observations: Sequence[CircleObservation]) -> CircleUpdateResult:
        """Associate, fuse and map the circles of one scan (module docstring, steps 1-4).

        Returns what became of each observation. All observations are checked before any is
        used, so a bad one leaves the filter unchanged.
        """
        checked = _checked_observations(observations)
        self._start_update()
        outcome = _Outcome()
        self._fuse_fits(list(enumerate(checked)), outcome)
        return outcome.result()

    def update_scan(
        self, arcs: Sequence[ArcObservation], mount_x_m: float, range_sigma_m: float
    ) -> CircleUpdateResult:
        """Fuse one scan's segments by their ranges (module docstring, "Ranges").

        ``arcs``: the segments; ``mount_x_m`` (m): the scanner ahead of the robot origin;
        ``range_sigma_m`` (m, > 0): the range noise. Returns what became of each arc (indices
        into ``arcs``): ``matched`` for those fused by their ranges or their fit, ``dropped``
        for arcs without a fit that met no circle. All arcs are checked before any is used.
        """
        checked = checked_arcs(arcs)
        check_finite("", "mount_x_m", mount_x_m)
        check_positive("", "range_sigma_m", range_sigma_m)
        mount, sigma_r = float(mount_x_m), float(range_sigma_m)
        self._start_update()
        outcome = _Outcome()
        cost = np.full((self.n_circles, len(checked)), np.inf)
        for k in range(self.n_circles):
            for j, arc in enumerate(checked):
                if arc.circular:
                    cost[k, j] = self._arc_cost(k, arc, mount, sigma_r)
        association = global_nearest_neighbour(cost, 1.0)
        for k, j in association.matches.tolist():
            if self._correct_arc(k, checked[j], mount, sigma_r):
                self._fused(k)
                outcome.matched.append((k, j))
            else:
                outcome.refused.append(j)
        rest = association.unmatched_measurements.tolist()
        fits = [(j, fit) for j in rest if (fit := checked[j].fit) is not None]
        outcome.dropped += [j for j in rest if checked[j].fit is None]
        self._fuse_fits(fits, outcome)
        return outcome.result()

    def _start_update(self) -> None:
        """Count the update; remove the provisional circles unseen for ``min_views_max_age``
        updates from the state (marginalised)."""
        self._updates += 1
        if self._config.admission != "provisional":
            return
        cfg = self._config
        expired = [
            k
            for k in range(self.n_circles)
            if self._hits[k] < cfg.min_views
            and self._updates - self._last_seen[k] > cfg.min_views_max_age
        ]
        if not expired:
            return
        keep = [k for k in range(self.n_circles) if k not in expired]
        rows = np.r_[
            np.arange(_POSE),
            (_POSE + _CIRCLE * np.array(keep, dtype=np.intp)[:, None] + np.arange(_CIRCLE)).ravel(),
        ]
        self._mu = self._mu[rows]
        self._sigma = self._sigma[np.ix_(rows, rows)]
        self._ids = [self._ids[k] for k in keep]
        self._hits = [self._hits[k] for k in keep]
        self._last_seen = [self._last_seen[k] for k in keep]

    def _fused(self, index: int) -> None:
        """Count a sighting fused into circle ``index``."""
        self._hits[index] += 1
        self._last_seen[index] = self._updates

    def _fuse_fits(self, indexed: list[tuple[int, CircleObservation]], outcome: _Outcome) -> None:
        """Steps 1-4 of the module docstring on circle fits, (index, observation) pairs; what
        became of each index is added to ``outcome``."""
        low, high = self._config.radius_bounds_m
        usable = [(j, obs) for j, obs in indexed if low <= obs.R <= high]
        outcome.refused += [j for j, obs in indexed if not low <= obs.R <= high]
        cost = self._cost_matrix([obs for _, obs in usable])
        association = global_nearest_neighbour(cost, self._gate)
        for k, u in association.matches.tolist():
            j, obs = usable[u]
            if self._correct(k, obs):
                self._fused(k)
                outcome.matched.append((k, j))
            else:
                outcome.refused.append(j)
        unpaired = association.unmatched_measurements.tolist()
        new = {u for u in unpaired if bool((cost[:, u] > self._new_gate).all())}
        outcome.ambiguous += [usable[u][0] for u in unpaired if u not in new]
        added, buffered = self._sight_new([usable[u] for u in unpaired if u in new])
        outcome.added += added
        outcome.buffered += buffered

    def measurement(self, index: int) -> tuple[FloatArray, FloatArray, FloatArray]:
        """``z_hat`` (3,), the nonzero block of ``H`` (3, 6) and its state indices (6,) for
        mapped circle ``index``, at the current estimate."""
        check_int("", "index", index, 0)
        if index >= self.n_circles:
            raise ValueError(
                f"index must be below the {self.n_circles} mapped circles, got {index}"
            )
        column = _POSE + _CIRCLE * index
        z_hat, H_pose, H_circle = observe_circle(
            self._mu[:_POSE], self._mu[column : column + _CIRCLE]
        )
        state_index = np.r_[np.arange(_POSE), column + np.arange(_CIRCLE)]
        return z_hat, np.hstack([H_pose, H_circle]), state_index

    def _arc_cost(self, index: int, arc: ArcObservation, mount: float, sigma_r: float) -> float:
        """The arc's pairing cost with circle ``index`` (:func:`arc_cost`)."""
        where = ArcCircle(_POSE + _CIRCLE * index)
        return arc_cost(
            self._mu, self._sigma, where, arc, mount, sigma_r, self._config.gate_probability
        )

    def _correct_arc(self, index: int, arc: ArcObservation, mount: float, sigma_r: float) -> bool:
        """Fuse the arc's ranges into circle ``index`` (:func:`fuse_arc`); whether the update was
        made (refused: fewer than three beams meet the circle, or a radius out of bounds)."""
        fused = fuse_arc(
            self._mu, self._sigma, ArcCircle(_POSE + _CIRCLE * index), arc, mount, sigma_r
        )
        if fused is None:
            return False
        mu, sigma = fused
        low, high = self._config.radius_bounds_m
        radii = mu[_POSE + 2 :: _CIRCLE]
        if not ((radii >= low) & (radii <= high)).all():
            return False
        self._mu, self._sigma = mu, sigma
        return True

    def _cost_matrix(self, observations: list[CircleObservation]) -> FloatArray:
        """Squared Mahalanobis distances (K, M) of the observations to the mapped circles.

        Each observation has its own ``Q``, so ``S = H Sigma H^T + Q`` differs per pair: one
        column of :func:`mahalanobis_cost_matrix` per observation.
        """
        linearised = [self.measurement(k) for k in range(self.n_circles)]
        z_hat = np.array([z for z, _, _ in linearised]).reshape(-1, _DOF)
        HPH = np.array(
            [
                innovation_covariance(self._sigma, H, np.zeros((_DOF, _DOF)), i)
                for _, H, i in linearised
            ]
        ).reshape(-1, _DOF, _DOF)
        cost = np.empty((self.n_circles, len(observations)))
        for j, obs in enumerate(observations):
            cost[:, j] = mahalanobis_cost_matrix(z_hat, HPH + obs.cov, obs.z[None])[:, 0]
        return cost

    def _correct(self, index: int, obs: CircleObservation) -> bool:
        """Fuse an observation of circle ``index`` (Joseph form); whether it was not refused."""
        z_hat, H, state_index = self.measurement(index)
        mu, sigma = joseph_update(self._mu, self._sigma, obs.z - z_hat, H, obs.cov, state_index)
        low, high = self._config.radius_bounds_m
        radii = mu[_POSE + 2 :: _CIRCLE]
        if not ((radii >= low) & (radii <= high)).all():
            return False
        mu[2] = wrap_angle(mu[2])
        self._mu, self._sigma = mu, sigma
        return True

    def _sight_new(
        self, sightings: list[tuple[int, CircleObservation]]
    ) -> tuple[list[tuple[int, int]], list[int]]:
        """Count sightings of new circles towards ``min_views``; add the circles that reach it.

        ``sightings``: (observation index, observation) pairs. Returns the (circle, observation)
        pairs added and the observation indices buffered.
        """
        if self._config.admission == "provisional":
            added = [(self.n_circles + i, j) for i, (j, _) in enumerate(sightings)]
            for _, obs in sightings:
                self._add_circle(obs)
            return added, []
        pose = self._mu[:_POSE]
        worlds = [inverse_observe_circle(pose, obs.z)[0] for _, obs in sightings]
        holders = self._tentatives_for(worlds)
        added, buffered = [], []
        for (j, obs), tentative in zip(sightings, holders, strict=True):
            if len(tentative.views) >= self._config.min_views:
                added.append((self.n_circles, j))
                self._add_circle(obs)
            else:
                buffered.append(j)
        full = {id(t) for t in holders if len(t.views) >= self._config.min_views}
        max_age = self._config.min_views_max_age
        self._tentative = [
            t
            for t in self._tentative
            if id(t) not in full and self._updates - t.last_seen < max_age
        ]
        return added, buffered

    def _tentatives_for(self, worlds: list[FloatArray]) -> list[_Tentative]:
        """The tentative circle each world circle (3,) joins (a new one if none is near)."""
        if not worlds:
            return []
        radius = self._config.min_views_radius_m
        centres = np.array([t.centre for t in self._tentative]).reshape(-1, 2)
        points = np.array(worlds).reshape(-1, _CIRCLE)[:, :2]
        cost = np.sum((centres[:, None, :] - points[None, :, :]) ** 2, axis=-1) / radius**2
        pairs = global_nearest_neighbour(cost, 1.0).matches
        joined = {int(w): self._tentative[int(t)] for t, w in pairs}
        holders = []
        for w, world in enumerate(worlds):
            tentative = joined.get(w)
            if tentative is None:
                tentative = _Tentative([], self._updates)
                self._tentative.append(tentative)
            tentative.views.append(world)
            tentative.last_seen = self._updates
            holders.append(tentative)
        return holders

    def _add_circle(self, obs: CircleObservation) -> None:
        """Append a circle from an observation, with its full first-order covariance."""
        circle, J_pose, J_z = inverse_observe_circle(self._mu[:_POSE], obs.z)
        n = len(self._mu)
        cross = J_pose @ self._sigma[:_POSE, :]  # Cov(circle, state) (3, n)
        sigma_mm = cross[:, :_POSE] @ J_pose.T + J_z @ obs.cov @ J_z.T
        sigma = np.empty((n + _CIRCLE, n + _CIRCLE))
        sigma[:n, :n] = self._sigma
        sigma[n:, :n] = cross
        sigma[:n, n:] = cross.T
        sigma[n:, n:] = 0.5 * (sigma_mm + sigma_mm.T)
        self._sigma = sigma
        self._mu = np.concatenate([self._mu, circle])
        self._ids.append(self._next_id)
        self._next_id += 1
        self._hits.append(1)
        self._last_seen.append(self._updates)


def _checked_observations(observations: object) -> list[CircleObservation]:
    """``observations`` as a list, after checking it is a sequence of CircleObservation."""
    if isinstance(observations, CircleObservation) or not isinstance(observations, Sequence):
        raise InvalidTypeError(
            "observations must be a sequence of CircleObservation, "
            f"got {type(observations).__name__}"
        )
    for i, obs in enumerate(observations):
        if not isinstance(obs, CircleObservation):
            raise InvalidTypeError(
                f"observations[{i}] must be a CircleObservation, got {type(obs).__name__}"
            )
    return list(observations)


def _check_tuple(owner: str, name: str, value: object, size: int, meaning: str) -> None:
    """Raise unless ``value`` is a tuple of ``size`` finite numbers >= 0."""
    if not (
        isinstance(value, tuple)
        and len(value) == size
        and all(is_finite_real(v) and v >= 0 for v in value)
    ):
        raise ValueError(
            f"{owner}.{name} must be a tuple of {size} finite values >= 0 {meaning}, got {value!r}"
        )
