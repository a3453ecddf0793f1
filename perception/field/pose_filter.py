"""An EKF of the robot pose that fuses odometry and the unified sensor model's pose observations
(seed 004 §2.1: the sensor model turns all of one frame's field features into one pose
observation, so that the filter makes a single update per frame).

The state is the robot pose in the field frame, ``x = (x, y, theta)`` (3,) (m, m, rad, theta
wrapped to [-pi, pi) as :func:`perception.geometry.wrap_angle` does). Symbols, as in
:mod:`perception.estimation.kalman` and :mod:`perception.slam.ekf_slam`:

- ``x``, ``P``: pose mean (3,) and covariance (3, 3);
- ``G``, ``V``: (3, 3) Jacobians of the odometry motion model w.r.t. the pose and the
  robot-frame increment ``delta = (dx, dy, dtheta)``; ``M`` (3, 3) the covariance of ``delta``
  (:func:`perception.slam.ekf_slam.motion`, :meth:`EkfSlamConfig.odometry_cov`);
- ``z`` (3,), ``L`` (3, 3): the pose and the information (inverse covariance) of a
  :class:`~perception.field.pose_observation.PoseObservation`; ``L`` is positive
  semidefinite and may be singular (a single field line says nothing about where along it the
  robot stands);
- ``e`` (3,): the pose residual ``z - x``, its heading wrapped;
- ``H``, ``R``, ``y``, ``S``, ``K``: the linear measurement the update fuses (below).

**Update in information form.** The posterior is ``P+ = (P^-1 + L)^-1`` and
``x+ = x + P+ L e``, which needs neither ``P^-1`` nor ``L^-1``: with the symmetric square root
``L^(1/2)`` the observation is the linear measurement ``y = H e`` with ``H = L^(1/2)`` and
``R = I`` (``H^T R^-1 H = L``), so ``S = L^(1/2) P L^(1/2) + I`` is positive definite
whatever the rank of ``L`` (or of ``P``), and the Joseph-form update of
:func:`perception.estimation.kalman.joseph_update` gives ``P+``, symmetric and positive
semidefinite under rounding. Along a direction ``L`` does not inform, ``H`` is zero and
nothing changes.

**Gate.** ``d² = y^T S^-1 y`` is the squared Mahalanobis distance of the residual in the
subspace ``L`` informs (``e^T (P + L^-1)^-1 e`` when ``L`` is invertible); for a correct
observation it is chi-square distributed with ``rank(L)`` degrees of freedom, so an
observation is refused when ``d²`` exceeds that chi-square quantile at
``PoseFilterConfig.gate_probability``. ``L`` here is the information fused, the observation's
own scaled by ``observation_weight`` (``w``): the distance is against ``P + (w L)^-1``, so the
gate is as much looser than one on the observation's own covariance as ``1 / w`` in variance
(10x at the pipeline's 0.1: it refuses a correct observation less often than
``1 - gate_probability``, and an inconsistent one only when it lies far off). A residual
along an uninformed direction (the position along a seen line) neither moves the estimate nor
counts against the gate. A gate refuses most often when the estimate is far off, so it leaves
the filter slightly overconfident: at p = 0.99 the mean NEES of the tests' simulation is about
3 % above its 3 dof.

**The field's half-turn symmetry** (seed 004 §2.3-2.4: field features cannot tell one end of
the field from the other) is not modelled here. The sensor model converges to the pose, or to
its mirror ``(-x, -y, theta + pi)``, that is nearer its prior (the filter's pose), so a
hypothesis at the mirror would be judged by observations produced from the other hypothesis's
prior: the mirror would lose weight to every observation whichever end the robot is at. Field
features carry no evidence for either end; a provider of a non-symmetric cue (goal colours,
natural landmarks: the seed's chapter 4) has to resolve it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from perception.estimation.gating import chi2_threshold
from perception.estimation.kalman import (
    innovation_covariance,
    joseph_update,
    predict,
)
from perception.field.pose_observation import PoseObservation, whitened_measurement
from perception.geometry import FloatArray, wrap_angle
from perception.slam.ekf_slam import EkfSlamConfig, motion
from perception.validation import (
    check_covariance,
    check_int,
    check_positive,
    check_probability,
    finite_vector,
    is_finite_real,
)

_R = np.eye(3)  # covariance of the whitened measurement y = L^(1/2) e (unitless)
_R.flags.writeable = False
_ODOMETRY_DEFAULTS = EkfSlamConfig()  # the odometry noise model is EKF SLAM's, defaults too
_ODOMETRY_FIELDS = (
    "translation_noise_m_per_sqrt_m",
    "translation_noise_m_per_sqrt_rad",
    "heading_noise_rad_per_sqrt_m",
    "rotation_noise_rad_per_sqrt_rad",
)


@dataclass(frozen=True, kw_only=True)
class PoseFilterConfig:
    """Noise model and gate of :class:`PoseFilter`.

    - The four odometry noise fields are those of :class:`EkfSlamConfig` (same meaning, units
      and defaults; see :meth:`EkfSlamConfig.odometry_cov`): the std of the increment's
      ``dx``, ``dy`` and ``dtheta`` grows with the square root of the distance walked and of
      the angle turned (a random walk).
    - ``initial_pose_std`` (m, m, rad): std of the pose given to the constructor or to
      :meth:`PoseFilter.reset` without a covariance; EKF SLAM's default.
    - ``gate_probability``: a pose observation is refused when its squared Mahalanobis
      distance in the subspace it informs exceeds the chi-square quantile at this probability,
      in (0, 1), with ``rank(information)`` degrees of freedom; None fuses every observation.
      The distance is against ``P + (observation_weight L)^-1`` (module docstring, "Gate").
    - ``observation_weight`` in (0, 1]: the share of an observation's information fused. The
      sensor model's information takes one frame's feature errors as independent, and this
      filter takes successive frames' as independent; a walking robot sees the same lines
      frame after frame with errors they share (sway, the camera model), so the full
      information makes the filter overconfident. 1 fuses it all.
    """

    translation_noise_m_per_sqrt_m: float = _ODOMETRY_DEFAULTS.translation_noise_m_per_sqrt_m
    translation_noise_m_per_sqrt_rad: float = _ODOMETRY_DEFAULTS.translation_noise_m_per_sqrt_rad
    heading_noise_rad_per_sqrt_m: float = _ODOMETRY_DEFAULTS.heading_noise_rad_per_sqrt_m
    rotation_noise_rad_per_sqrt_rad: float = _ODOMETRY_DEFAULTS.rotation_noise_rad_per_sqrt_rad
    initial_pose_std: tuple[float, float, float] = _ODOMETRY_DEFAULTS.initial_pose_std
    gate_probability: float | None = 0.99  # refuses beyond this chi-square(rank L) quantile
    observation_weight: float = 1.0

    def __post_init__(self) -> None:
        owner = "PoseFilterConfig"
        for name in _ODOMETRY_FIELDS:
            check_positive(owner, name, getattr(self, name), allow_zero=True)
        std = self.initial_pose_std
        if not (
            isinstance(std, tuple)
            and len(std) == 3
            and all(is_finite_real(s) and s >= 0 for s in std)
        ):
            raise ValueError(
                f"{owner}.initial_pose_std must be a tuple of 3 finite values >= 0 "
                f"(m, m, rad), got {std!r}"
            )
        if self.gate_probability is not None:
            check_probability(owner, "gate_probability", self.gate_probability)
        check_positive(
            owner, "observation_weight", self.observation_weight, upper=1.0, upper_inclusive=True
        )

    @property
    def initial_cov(self) -> FloatArray:
        """``diag(initial_pose_std)²`` (3, 3) (m², m², rad²)."""
        return np.diag(np.square(np.asarray(self.initial_pose_std, dtype=np.float64)))

    def odometry_model(self) -> EkfSlamConfig:
        """An :class:`EkfSlamConfig` with these odometry noise fields (its others default)."""
        return EkfSlamConfig(**{name: getattr(self, name) for name in _ODOMETRY_FIELDS})

    def odometry_cov(self, odometry_delta: ArrayLike) -> FloatArray:
        """``M`` (3, 3): covariance of the increment ``(dx, dy, dtheta)`` (robot frame), by
        :meth:`EkfSlamConfig.odometry_cov` with these noise fields."""
        return self.odometry_model().odometry_cov(odometry_delta)


class PoseFilter:
    """EKF of the robot pose ``(x, y, theta)`` (m, m, rad, field frame); module docstring.

    ``initial_pose`` (3,) starts it with covariance ``config.initial_cov``. Call
    :meth:`predict` with each odometry increment and :meth:`update` with each frame's
    :class:`PoseObservation`; :attr:`pose` and :attr:`cov` are the estimate.
    """

    def __init__(self, config: PoseFilterConfig, initial_pose: ArrayLike) -> None:
        if not isinstance(config, PoseFilterConfig):
            raise TypeError(f"config must be a PoseFilterConfig, got {type(config).__name__}")
        self._config = config
        self._odometry = config.odometry_model()
        self._x = _pose(initial_pose, "initial_pose")
        self._P = config.initial_cov
        self._rejected = 0

    @property
    def config(self) -> PoseFilterConfig:
        """The configuration the filter was built with."""
        return self._config

    @property
    def pose(self) -> FloatArray:
        """``x`` (3,): ``(x, y, theta)`` (m, m, rad, field frame), a copy."""
        return self._x.copy()

    @property
    def cov(self) -> FloatArray:
        """``P`` (3, 3): covariance of :attr:`pose` (m², m², rad² and products), a copy."""
        return self._P.copy()

    @property
    def rejected(self) -> int:
        """How many observations the gate has refused since the last :meth:`reset`."""
        return self._rejected

    def reset(self, pose: ArrayLike, cov: ArrayLike | None = None) -> None:
        """Restart at ``pose`` (3,) with ``cov`` (3, 3), or ``config.initial_cov`` when None.

        ``cov`` must be symmetric positive semidefinite (a zero variance pins that component);
        the heading is wrapped. Also zeroes :attr:`rejected`. A bad argument leaves the filter
        unchanged.
        """
        x = _pose(pose, "pose")
        P = (
            self._config.initial_cov
            if cov is None
            else check_covariance(cov, "cov", 3, singular_ok=True)
        )
        self._x, self._P, self._rejected = x, P, 0

    def predict(self, odometry_delta: ArrayLike) -> None:
        """Move by the odometry increment ``(dx, dy, dtheta)`` (3,) (m, m, rad).

        The increment is in the frame of the previous pose:
        ``x <- motion(x, delta)``, ``P <- G P G^T + V M V^T``
        (:func:`perception.slam.ekf_slam.motion`, :meth:`PoseFilterConfig.odometry_cov`).
        """
        delta = finite_vector(odometry_delta, "odometry_delta", 3)
        pose, G, V = motion(self._x, delta)
        M = self._odometry.odometry_cov(delta)
        _, self._P = predict(self._x, self._P, G, V @ M @ V.T)
        self._x = pose

    def mahalanobis(self, observation: PoseObservation) -> tuple[float, int]:
        """``d²`` (unitless) of an observation and its degrees of freedom, ``rank(L)``.

        ``d²`` is what :meth:`update` gates on (module docstring); 0 with 0 dof when the
        observation carries no information. Leaves the filter unchanged.
        """
        y, H, rank = self._linearise(observation, "observation")
        S = innovation_covariance(self._P, H, _R)
        return float(y @ np.linalg.solve(S, y)), rank

    def gate_threshold(self, dof: int) -> float:
        """The largest ``d²`` the gate lets through with ``dof`` (1 to 3) degrees of freedom:
        the chi-square quantile at ``config.gate_probability`` (inf without a gate)."""
        check_int("", "dof", dof, 1)
        if dof > 3:
            raise ValueError(f"dof must be an int in [1, 3], got {dof!r}")
        probability = self._config.gate_probability
        if probability is None:
            return math.inf
        return chi2_threshold(probability, int(dof))

    def update(self, observation: PoseObservation) -> bool:
        """Fuse a pose observation in information form; return whether it was fused.

        Returns False, leaving the filter unchanged, when the gate refuses the observation
        (counted in :attr:`rejected`) or when it carries no information (``L = 0``).
        """
        y, H, rank = self._linearise(observation, "observation")
        if rank == 0:
            return False
        S = innovation_covariance(self._P, H, _R)
        if float(y @ np.linalg.solve(S, y)) > self.gate_threshold(rank):
            self._rejected += 1
            return False
        # Joseph form: P stays symmetric PSD under rounding (kalman.joseph_update).
        x, self._P = joseph_update(self._x, self._P, y, H, _R, S=S)
        x[2] = wrap_angle(x[2])
        self._x = x
        return True

    def _linearise(self, observation: object, name: str) -> tuple[FloatArray, FloatArray, int]:
        """``y = H e`` (3,), ``H = L^(1/2)`` (3, 3) and ``rank(L)`` of an observation, checked
        (:func:`~perception.field.pose_observation.whitened_measurement`)."""
        return whitened_measurement(observation, self._x, self._config.observation_weight, name)


def _pose(value: ArrayLike, name: str) -> FloatArray:
    """``value`` as a new finite (3,) pose with its heading wrapped; errors name ``name``."""
    x = finite_vector(value, name, 3)
    x[2] = wrap_angle(x[2])
    return x
