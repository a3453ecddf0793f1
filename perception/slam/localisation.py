"""Seed 001's localisation filters (§5.3.2, §5.3.3): a GPS EKF and an odometry + landmark EKF.

Dead reckoning (§5.3.1, eqs. 5.3-5.5) is :func:`spl_env.robots.diff_drive.dead_reckoning_increment`
composed onto the pose; the two filters here correct it.

Frames and units: the world (field) frame has x, y in m and the heading θ in rad,
counter-clockwise, wrapped to [-π, π); the robot frame has x forward and y to the left. A
pose is (3,) ``(x, y, θ)``.

**GPS EKF** (§5.3.2, after Sakai's PythonRobotics): state (4,) ``(x, y, θ, v)`` (eq. 5.6),
``v`` the forward speed (m/s). Each :meth:`GpsEkf.predict` drives the robot for ``dt`` s at its
speed ``v`` while it turns at the measured turn rate ``ω`` (rad/s, from a gyro or odometry); a
GPS fix (2,) measures ``(x, y)`` with ``H = [I₂ 0]`` and ``R = σ_gps² I₂`` (Fig. 5.6:
``σ_gps`` = 0.06 m and 1 m). Departures from the seed:

- Speed. The seed's control input is ``u = (v, ω)`` with ``B`` = ``[[cos φ dt, 0], [sin φ dt,
  0], [0, dt], [1, 0]]``, which writes the speed sensor's ``v`` over the state's ``v``
  (Sakai's code has ``F[3, 3] = 0``), yet its Jacobian ``J_F`` moves the position with the
  state's ``v`` (``∂x/∂v = cos φ dt``) and keeps it (``∂v/∂v = 1``): the two disagree
  (PythonRobotics pull request #63). Here the state's ``v`` is what ``J_F`` says it is, a
  speed estimated from the GPS fixes that only white acceleration noise changes, and ``ω`` is
  the only input; the seed's ``J_F`` is then the exact Jacobian (up to the next point). With
  no speed input, ``(θ, v)`` and ``(θ + π, -v)`` explain the GPS fixes and turn rates equally
  well: the initial heading must be known to within π/2.
- Integration. The seed's ``B`` moves the robot along the step's initial heading. Here it
  moves along the exact arc of constant ``v`` and ``ω``: the chord ``v dt sinc(ω dt / 2)``
  along the mid-step heading ``φ = θ + ω dt / 2`` (eq. 5.3's heading with the exact chord,
  like the dead reckoning), so ``J_F`` is the seed's with ``φ`` at mid-step and ``dt``
  scaled by ``sinc(ω dt / 2)``.
- Process noise. The seed's ``Q = [0.4, 0.4, 0.01, 1]ᵀ`` (a diagonal) is added per step, so
  the noise it assumes per second grows with the step rate. Here ``Q`` is the exact
  discretisation over ``dt`` of the linearised continuous model with two white noises of
  given densities, acceleration ``σ_a`` and turn rate ``σ_ω``
  (:meth:`GpsEkfConfig.process_cov`), so the filter does not depend on ``dt``.
- ``R``: the seed prints ``0.1² I``; here ``σ_gps² I`` with ``σ_gps`` the simulated GPS noise
  of Fig. 5.6, a filter that knows its sensor. ``P₀`` = ``I₄`` as in the seed.

**Landmark EKF** (§5.3.3, after Pinheiro & Cardozo 2014): state (3,) ``(x, y, θ)``. It
predicts with the robot-frame odometry increment ``δ = (dx, dy, dθ)`` (the dead reckoning's)
through :func:`perception.slam.ekf_slam.motion`, ``P ← G P Gᵀ + V M Vᵀ`` (eq. 5.8), and
corrects with the range and bearing (2,) of one known landmark ``L`` through
:func:`perception.slam.ekf_slam.observe` (eq. 5.9), the bearing's residual wrapped, in
Joseph form. Departures from the seed:

- Eq. 5.7's ``F`` prints ``Δθ_t / ∂_t`` for ``Δθ_t / 2``; the pose Jacobian ``G`` of
  ``motion`` is that ``F`` for the exact arc.
- Odometry noise (eq. 5.8's ``M``) is per wheel, as the seed's ``M`` over the wheel inputs:
  each wheel's travel has variance ``k² |Δs_wheel|`` (a random walk in the distance
  travelled, so the result does not depend on how finely the motion is sliced), mapped to
  the increment by the Jacobian of eq. 5.3 (:meth:`LandmarkEkfConfig.odometry_cov`). The
  seed's ``V`` has the right first two rows; its last row is garbled (``1 / (2 D)`` and
  ``-cos(...) / (2 D)``): with ``Δθ = (Δs_r - Δs_l) / D`` it is ``(1 / D, -1 / D)``.
- Eq. 5.9's ``arctan2((L_y - y) / (L_x - x))`` is ``atan2(L_y - y, L_x - x)``, the bearing
  wrapped to [-π, π). The seed's ``J_h`` pose block is right: it is ``observe``'s ``H_pose``.
- ``R``: the seed's ``diag(0.2, 0.01)`` as variances, i.e. ``σ_range`` = √0.2 m,
  ``σ_bearing`` = 0.1 rad; the landmark sits at the seed's ``(L_x, L_y) = (2, 2)`` m
  (Fig. 5.8). The seed's ``x₀ = (0, 0, π, 0)`` has four entries for a three-entry state.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from perception.estimation.kalman import joseph_update, predict, wrapped_residual
from perception.geometry import FloatArray, wrap_angle
from perception.slam.ekf_slam import motion, observe
from perception.validation import (
    check_covariance,
    check_finite,
    check_positive,
    finite_vector,
    is_finite_real,
)

_GPS_H = np.eye(2, 4)  # a GPS fix measures (x, y): the seed's H
_BEARING = (1,)  # index of the angle in a (range, bearing) measurement


def _check_tuple(owner: str, name: str, value: object, size: int, *, nonnegative: bool) -> None:
    """Raise unless ``value`` is a tuple of ``size`` finite real numbers (>= 0 if asked)."""
    if not (
        isinstance(value, tuple)
        and len(value) == size
        and all(is_finite_real(v) and (v >= 0 or not nonnegative) for v in value)
    ):
        expected = f"a tuple of {size} finite values" + (" >= 0" if nonnegative else "")
        raise ValueError(f"{owner}.{name} must be {expected}, got {value!r}")


@dataclass(frozen=True, kw_only=True)
class GpsEkfConfig:
    """Noise model of :class:`GpsEkf`.

    - ``gps_std_m`` (m): std of each coordinate of a GPS fix (seed Fig. 5.6: 0.06 m, and 1 m).
    - ``acceleration_noise_m_per_s2_per_sqrt_hz`` (m/s²/√Hz): density ``σ_a`` of the white
      acceleration that changes the speed: ``v`` random-walks by ``σ_a`` m/s per √s. The
      default, 0.3, lets a robot driving at about constant speed change it by 0.3 m/s in a
      second (one sigma); a plausible setting, not a fit to data.
    - ``turn_rate_noise_rad_per_s_per_sqrt_hz`` (rad/s/√Hz): density ``σ_ω`` of the white
      error of the measured turn rate: the heading random-walks by ``σ_ω`` rad per √s (a
      gyro's angle random walk). The default, 0.02, is a plausible odometric turn rate, not a
      fit to data.
    - ``initial_std`` (m, m, rad, m/s): std of the initial state; the seed's ``P₀ = I₄``.
    """

    gps_std_m: float = 0.06
    acceleration_noise_m_per_s2_per_sqrt_hz: float = 0.3
    turn_rate_noise_rad_per_s_per_sqrt_hz: float = 0.02
    initial_std: tuple[float, float, float, float] = (1.0, 1.0, 1.0, 1.0)

    def __post_init__(self) -> None:
        owner = "GpsEkfConfig"
        check_positive(owner, "gps_std_m", self.gps_std_m)
        for name in (
            "acceleration_noise_m_per_s2_per_sqrt_hz",
            "turn_rate_noise_rad_per_s_per_sqrt_hz",
        ):
            check_positive(owner, name, getattr(self, name), allow_zero=True)
        _check_tuple(owner, "initial_std", self.initial_std, 4, nonnegative=True)

    @property
    def measurement_cov(self) -> FloatArray:
        """``R`` (2, 2) (m²): covariance of a GPS fix ``(x, y)``, ``gps_std_m² I``."""
        return self.gps_std_m**2 * np.eye(2)

    def process_cov(self, state: ArrayLike, dt: float, turn_rate: float) -> FloatArray:
        """``Q`` (4, 4): the covariance a :meth:`GpsEkf.predict` of ``dt`` s adds at ``state``.

        The continuous model ``ẋ = v cos θ, ẏ = v sin θ, θ̇ = ω + n_ω, v̇ = n_a``, linearised
        at ``state`` (4,) with the heading held at the mid-step ``φ = θ + ω dt / 2``
        (``turn_rate`` ``ω``, rad/s), has ``A² = 0``, so ``e^{Aτ} = I + Aτ`` and Van Loan's
        ``Q = ∫₀^dt e^{Aτ} L Qc Lᵀ e^{Aτᵀ} dτ`` is, with ``u = (cos φ, sin φ)``,
        ``n = (-sin φ, cos φ)``, ``q_a = σ_a²`` and ``q_ω = σ_ω²``::

            Q_pp = q_a dt³/3 u uᵀ + q_ω v² dt³/3 n nᵀ     Q_pθ = q_ω v dt²/2 n
            Q_pv = q_a dt²/2 u                              Q_θθ = q_ω dt,  Q_vv = q_a dt
        """
        _, _, theta, v = np.asarray(state, dtype=np.float64)
        phi = theta + turn_rate * dt / 2
        u = np.array([math.cos(phi), math.sin(phi)])
        n = np.array([-u[1], u[0]])
        q_a = self.acceleration_noise_m_per_s2_per_sqrt_hz**2
        q_w = self.turn_rate_noise_rad_per_s_per_sqrt_hz**2
        Q = np.zeros((4, 4))
        Q[:2, :2] = dt**3 / 3 * (q_a * np.outer(u, u) + q_w * v * v * np.outer(n, n))
        Q[:2, 2] = Q[2, :2] = q_w * v * dt**2 / 2 * n
        Q[:2, 3] = Q[3, :2] = q_a * dt**2 / 2 * u
        Q[2, 2] = q_w * dt
        Q[3, 3] = q_a * dt
        return Q


def gps_motion(state: ArrayLike, dt: float, turn_rate: float) -> tuple[FloatArray, FloatArray]:
    """The GPS EKF's motion model: the state (4,) after ``dt`` s, and its Jacobian ``F`` (4, 4).

    ``state`` (4,) ``(x, y, θ, v)`` drives at constant speed ``v`` (m/s) turning at
    ``turn_rate`` ``ω`` (rad/s): the robot-frame increment is the arc's chord ``v dt sinc(h)``
    along ``h = ω dt / 2``, turning by ``ω dt``; ``v`` is unchanged. ``F`` is ``[[G, ∂p/∂v],
    [0, 0, 0, 1]]`` with ``G`` from :func:`perception.slam.ekf_slam.motion` and
    ``∂(x, y)/∂v = dt sinc(h) (cos(θ + h), sin(θ + h))``.
    """
    x = np.asarray(state, dtype=np.float64)
    half_turn = turn_rate * dt / 2
    chord_per_speed = dt * (math.sin(half_turn) / half_turn if half_turn else 1.0)
    along = chord_per_speed * np.array([math.cos(half_turn), math.sin(half_turn), 0.0])
    pose, G, V = motion(x[:3], x[3] * along + [0.0, 0.0, 2 * half_turn])
    F = np.eye(4)
    F[:3, :3] = G
    F[:3, 3] = V @ along
    return np.concatenate([pose, x[3:]]), F


class GpsEkf:
    """EKF of the pose and speed from turn rates and GPS fixes (seed §5.3.2, module docstring).

    ``initial_state`` (4,) is ``(x, y, θ, v)`` (m, m, rad, m/s) in the world frame, with
    covariance ``diag(config.initial_std)²``; the seed starts at ``(0, 0, π, 0)``. Call
    :meth:`predict` every step and :meth:`update_gps` with every fix.
    """

    def __init__(self, config: GpsEkfConfig, initial_state: ArrayLike) -> None:
        if not isinstance(config, GpsEkfConfig):
            raise TypeError(f"config must be a GpsEkfConfig, got {type(config).__name__}")
        self._config = config
        self._x = finite_vector(initial_state, "initial_state", 4)
        self._x[2] = wrap_angle(self._x[2])
        self._P = np.diag(np.square(np.asarray(config.initial_std, dtype=np.float64)))

    @property
    def config(self) -> GpsEkfConfig:
        """The configuration the filter was built with."""
        return self._config

    @property
    def state(self) -> FloatArray:
        """``(x, y, θ, v)`` (4,) (m, m, rad, m/s), a copy."""
        return self._x.copy()

    @property
    def pose(self) -> FloatArray:
        """``(x, y, θ)`` (3,) (m, m, rad), a copy."""
        return self._x[:3].copy()

    @property
    def cov(self) -> FloatArray:
        """``P`` (4, 4): covariance of :attr:`state`, a copy."""
        return self._P.copy()

    def predict(self, dt: float, turn_rate: float) -> None:
        """Drive for ``dt`` s (> 0) at the estimated speed, turning at ``turn_rate`` (rad/s)."""
        check_positive("", "dt", dt)
        check_finite("", "turn_rate", turn_rate)
        x, F = gps_motion(self._x, dt, turn_rate)
        Q = self._config.process_cov(self._x, dt, turn_rate)
        _, self._P = predict(self._x, self._P, F, Q)
        self._x = x

    def update_gps(self, xy: ArrayLike) -> None:
        """Fuse a GPS fix ``xy`` (2,) (m, world frame)."""
        z = finite_vector(xy, "xy", 2)
        x, self._P = joseph_update(
            self._x, self._P, z - self._x[:2], _GPS_H, self._config.measurement_cov
        )
        x[2] = wrap_angle(x[2])
        self._x = x


@dataclass(frozen=True, kw_only=True)
class LandmarkEkfConfig:
    """The landmark and the noise model of :class:`LandmarkEkf`.

    - ``landmark_xy_m`` (m, world frame): the known landmark, the seed's ``(2, 2)`` (Fig. 5.8).
    - ``range_std_m`` (m), ``bearing_std_rad`` (rad): std of a sighting's range and bearing;
      the seed's ``R = diag(0.2, 0.01)`` (m², rad²).
    - ``axle_length_m`` (m): the wheel separation ``D``, the seed's 0.381 m.
    - ``wheel_noise_m_per_sqrt_m`` (m/√m): std ``k`` of a wheel's travel per √m it travels,
      white (see :meth:`odometry_cov`). The default, 0.01, is a plausible uncalibrated robot:
      a heading random walk of ``k √2 / D`` = 0.037 rad per √m driven straight, which covers
      the systematic drift of :class:`spl_env.robots.diff_drive.DiffDriveConfig`'s default
      encoders (0.019 rad/m in std) over the first few metres.
    - ``initial_pose_std`` (m, m, rad): std of the initial pose.
    """

    landmark_xy_m: tuple[float, float] = (2.0, 2.0)
    range_std_m: float = math.sqrt(0.2)
    bearing_std_rad: float = 0.1
    axle_length_m: float = 0.381
    wheel_noise_m_per_sqrt_m: float = 0.01
    initial_pose_std: tuple[float, float, float] = (0.01, 0.01, 0.01)

    def __post_init__(self) -> None:
        owner = "LandmarkEkfConfig"
        _check_tuple(owner, "landmark_xy_m", self.landmark_xy_m, 2, nonnegative=False)
        for name in ("range_std_m", "bearing_std_rad", "axle_length_m"):
            check_positive(owner, name, getattr(self, name))
        check_positive(
            owner, "wheel_noise_m_per_sqrt_m", self.wheel_noise_m_per_sqrt_m, allow_zero=True
        )
        _check_tuple(owner, "initial_pose_std", self.initial_pose_std, 3, nonnegative=True)

    @property
    def measurement_cov(self) -> FloatArray:
        """``R`` (2, 2) (m², rad²): covariance of a sighting ``(range, bearing)``."""
        return np.diag([self.range_std_m**2, self.bearing_std_rad**2])

    def odometry_cov(self, odometry_delta: ArrayLike) -> FloatArray:
        """``M`` (3, 3): covariance of a robot-frame increment ``(dx, dy, dθ)`` (m, m, rad).

        The wheels' travels are recovered from the increment: ``Δs`` (m), the chord along the
        mid-step heading ``h = dθ / 2`` (``dx cos h + dy sin h``, short of the arc by a factor
        ``sinc(h)``, > 0.95 for ``|dθ|`` < 1 rad, which a noise model need not resolve), and
        ``Δs_r, Δs_l = Δs ± D dθ / 2``. Each has variance ``k² |Δs_wheel|``, independently;
        with eq. 5.3 (``dx = Δs cos h``, ``dy = Δs sin h``, ``Δs = (Δs_r + Δs_l) / 2``,
        ``dθ = (Δs_r - Δs_l) / D``) their Jacobian is::

            J = [[cos h / 2 - Δs sin h / (2D),  cos h / 2 + Δs sin h / (2D)],
                 [sin h / 2 + Δs cos h / (2D),  sin h / 2 - Δs cos h / (2D)],
                 [1 / D,                        -1 / D                      ]]

        and ``M = J diag(var_r, var_l) Jᵀ``. The seed's ``V`` (world frame) is ``V_motion J``
        with ``V_motion`` from :func:`perception.slam.ekf_slam.motion`, so its
        ``V diag(var_r, var_l) Vᵀ`` is ``V_motion M V_motionᵀ``. A turn in place has
        ``var(dθ) = k² |dθ| / D``.
        """
        dx, dy, dtheta = finite_vector(odometry_delta, "odometry_delta", 3)
        D = self.axle_length_m
        c, s = math.cos(dtheta / 2), math.sin(dtheta / 2)
        distance = dx * c + dy * s
        wheels = np.abs([distance + D * dtheta / 2, distance - D * dtheta / 2])
        a, b = distance * s / (2 * D), distance * c / (2 * D)
        J = np.array([[c / 2 - a, c / 2 + a], [s / 2 + b, s / 2 - b], [1 / D, -1 / D]])
        M: FloatArray = (J * (self.wheel_noise_m_per_sqrt_m**2 * wheels)) @ J.T
        return M


class LandmarkEkf:
    """EKF of the pose from odometry and sightings of one known landmark (seed §5.3.3).

    ``initial_pose`` (3,) is ``(x, y, θ)`` (m, m, rad) in the world frame, with covariance
    ``diag(config.initial_pose_std)²``. Call :meth:`predict` with every odometry increment and
    :meth:`update` with every sighting of the landmark ``config.landmark_xy_m``.
    """

    def __init__(self, config: LandmarkEkfConfig, initial_pose: ArrayLike) -> None:
        if not isinstance(config, LandmarkEkfConfig):
            raise TypeError(f"config must be a LandmarkEkfConfig, got {type(config).__name__}")
        self._config = config
        self._landmark = np.array(config.landmark_xy_m, dtype=np.float64)
        self._x = finite_vector(initial_pose, "initial_pose", 3)
        self._x[2] = wrap_angle(self._x[2])
        self._P = np.diag(np.square(np.asarray(config.initial_pose_std, dtype=np.float64)))

    @property
    def config(self) -> LandmarkEkfConfig:
        """The configuration the filter was built with."""
        return self._config

    @property
    def pose(self) -> FloatArray:
        """``(x, y, θ)`` (3,) (m, m, rad), a copy."""
        return self._x.copy()

    @property
    def cov(self) -> FloatArray:
        """``P`` (3, 3): covariance of :attr:`pose`, a copy."""
        return self._P.copy()

    def predict(self, odometry_delta: ArrayLike, odometry_cov: ArrayLike | None = None) -> None:
        """Move by the robot-frame increment ``(dx, dy, dθ)`` (3,) (m, m, rad) (eq. 5.8).

        ``odometry_cov`` (3, 3): its covariance ``M`` (positive semidefinite), or None for
        :meth:`LandmarkEkfConfig.odometry_cov`.
        """
        delta = finite_vector(odometry_delta, "odometry_delta", 3)
        M = (
            self._config.odometry_cov(delta)
            if odometry_cov is None
            else check_covariance(odometry_cov, "odometry_cov", 3, singular_ok=True)
        )
        pose, G, V = motion(self._x, delta)
        _, self._P = predict(self._x, self._P, G, V @ M @ V.T)
        self._x = pose

    def update(self, range_bearing: ArrayLike) -> None:
        """Fuse a sighting ``(range m, bearing rad)`` (2,) of the landmark (robot frame)."""
        z = finite_vector(range_bearing, "range_bearing", 2)
        check_positive("range_bearing", "range", z[0])
        z_hat, H_pose, _ = observe(self._x, self._landmark)
        y = wrapped_residual(z, z_hat, _BEARING)
        x, self._P = joseph_update(self._x, self._P, y, H_pose, self._config.measurement_cov)
        x[2] = wrap_angle(x[2])
        self._x = x
