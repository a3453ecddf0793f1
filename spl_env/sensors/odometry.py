"""Walk-engine odometry: the robot-frame motion increments a Nao's walk reports, with errors.

Errors are of two kinds (the usual split of odometry error, e.g. Borenstein & Feng's
systematic/non-systematic errors):

- systematic, drawn once per episode by :meth:`WalkOdometry.reset` (a robot walks a little long or
  short, veers to one side, over- or under-turns, consistently for a while): a translation scale
  error, a heading drift per metre walked and a rotation scale error, each Gaussian around the
  config's mean with the config's spread;
- random, fresh on every increment: a random walk whose variance grows with the distance walked
  and the angle turned (std per sqrt(m), per sqrt(rad)), so the accumulated error does not
  depend on how finely the motion is sliced into increments.

For a true increment ``(dx, dy, dθ)`` with ``d = hypot(dx, dy)`` the reported increment is::

    dx' = (1 + s_t) dx + n_x,   dy' = (1 + s_t) dy + n_y,      n_x, n_y ~ N(0, k_t² d)
    dθ' = (1 + s_r) dθ + h d + n_θ,                            n_θ ~ N(0, k_h² d + k_r² |dθ|)

with the episode's ``s_t`` (translation scale error), ``h`` (heading drift, rad/m) and ``s_r``
(rotation scale error).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from perception.geometry import FloatArray
from perception.validation import check_finite, check_in_interval, check_positive


@dataclass(frozen=True, kw_only=True)
class OdometryConfig:
    """Error model of walk odometry. The defaults are calibrated on a Nao square walk.

    Calibration (``python benchmarks/odometry_drift.py --seeds 1000``): a one-minute square walk
    (1.78 m sides at 0.15 m/s, 90° turns in place at 0.5 rad/s, increments every 0.1 s) gives a
    dead-reckoning position error over the minute of mean 0.504 m (its std over time 0.336 m),
    final position error 1.02 m and final heading error 0.80 rad, averaged over 1000 seeds (50
    seeds: 0.504 m, 0.337 m, 1.03 m, 0.81 rad). Seed 000's Nao v6 dataset had mean 0.5039 m, std
    0.2030 m, with the bearing growing increasingly wrong: here too the heading errors (drift per
    metre, rotation scale) dominate. The std over time is larger than seed 000's: the error starts
    at zero and grows, and every error term of this model on its own gives a std over time of at
    least 0.47 times the mean (0.47 for translation noise, 0.64 to 0.85 for the heading terms).
    """

    # Systematic errors, drawn per episode as mean + std * N(0, 1).
    translation_scale_error: float = 0.0  # mean fractional error of the walked distance (1)
    translation_scale_error_std: float = 0.05  # its spread across episodes (1)
    heading_drift_rad_per_m: float = 0.0  # mean heading error per metre walked (rad/m), + = left
    heading_drift_std_rad_per_m: float = 0.105  # its spread across episodes (rad/m)
    rotation_scale_error: float = 0.0  # mean fractional error of the turned angle (1)
    rotation_scale_error_std: float = 0.10  # its spread across episodes (1)
    # Random errors, fresh on every increment.
    translation_noise_m_per_sqrt_m: float = 0.03  # std of each of dx, dy per sqrt(m walked)
    heading_noise_rad_per_sqrt_m: float = 0.07  # std of dθ per sqrt(m walked)
    rotation_noise_rad_per_sqrt_rad: float = 0.05  # std of dθ per sqrt(rad turned)

    def __post_init__(self) -> None:
        owner = "odometry"
        for name in ("translation_scale_error", "rotation_scale_error"):
            check_in_interval(owner, name, getattr(self, name), -0.5, 0.5)
        for name in ("translation_scale_error_std", "rotation_scale_error_std"):
            check_positive(
                owner, name, getattr(self, name), allow_zero=True, upper=0.2, upper_inclusive=True
            )
        check_finite(owner, "heading_drift_rad_per_m", self.heading_drift_rad_per_m)
        for name in (
            "heading_drift_std_rad_per_m",
            "translation_noise_m_per_sqrt_m",
            "heading_noise_rad_per_sqrt_m",
            "rotation_noise_rad_per_sqrt_rad",
        ):
            check_positive(owner, name, getattr(self, name), allow_zero=True)


@dataclass(frozen=True, kw_only=True)
class OdometryErrors:
    """One episode's systematic odometry errors (see the module docstring)."""

    translation_scale_error: float  # s_t (1)
    heading_drift_rad_per_m: float  # h (rad/m)
    rotation_scale_error: float  # s_r (1)


class WalkOdometry:
    """Turns true robot-frame increments into the noisy ones the walk engine reports.

    Call :meth:`reset` at the start of every episode; it draws the episode's systematic errors
    and keeps ``rng`` for the random errors of every later :meth:`measure`.
    """

    def __init__(self, config: OdometryConfig) -> None:
        self.config = config
        self._episode: tuple[np.random.Generator, OdometryErrors] | None = None

    def reset(self, rng: np.random.Generator) -> None:
        """Draw this episode's systematic errors from ``rng`` and use ``rng`` from now on."""
        c = self.config
        z = rng.standard_normal(3)
        errors = OdometryErrors(
            translation_scale_error=c.translation_scale_error
            + c.translation_scale_error_std * float(z[0]),
            heading_drift_rad_per_m=c.heading_drift_rad_per_m
            + c.heading_drift_std_rad_per_m * float(z[1]),
            rotation_scale_error=c.rotation_scale_error + c.rotation_scale_error_std * float(z[2]),
        )
        self._episode = (rng, errors)

    def _current(self) -> tuple[np.random.Generator, OdometryErrors]:
        if self._episode is None:
            raise RuntimeError("WalkOdometry.reset(rng) must be called first")
        return self._episode

    @property
    def errors(self) -> OdometryErrors:
        """The systematic errors drawn by the last :meth:`reset`."""
        return self._current()[1]

    def measure(self, true_delta: ArrayLike) -> FloatArray:
        """Reported increment (3,) ``(dx, dy, dθ)`` for the true robot-frame increment (3,).

        Both are in the frame of the robot at the previous call (m, m, rad).
        """
        rng, errors = self._current()
        delta = np.asarray(true_delta, dtype=np.float64)
        if delta.shape != (3,) or not np.all(np.isfinite(delta)):
            raise ValueError(f"true_delta must be a finite (3,) increment, got {delta!r}")
        c = self.config
        dist = math.hypot(delta[0], delta[1])
        turn = abs(delta[2])
        z = rng.standard_normal(3)
        xy = (1.0 + errors.translation_scale_error) * delta[:2]
        xy += c.translation_noise_m_per_sqrt_m * math.sqrt(dist) * z[:2]
        theta_std = math.sqrt(
            c.heading_noise_rad_per_sqrt_m**2 * dist + c.rotation_noise_rad_per_sqrt_rad**2 * turn
        )
        theta = (
            (1.0 + errors.rotation_scale_error) * delta[2]
            + errors.heading_drift_rad_per_m * dist
            + theta_std * z[2]
        )
        return np.array([xy[0], xy[1], theta])
