"""Expected information about our pose from range-bearing sightings of mapped landmarks.

Used by the greedy head planner (:class:`agents.baselines.GreedyInformation`): a sighting of a
landmark at range r along field direction α has the Jacobian H (2 x 3) of (range, bearing) with
respect to our pose (x, y, θ); sightings with noise R shrink a Gaussian pose belief with
covariance P by ``log det(P⁻¹ + Σ Hᵢᵀ Rᵢ⁻¹ Hᵢ) / 2 - log det(P⁻¹) / 2`` nats.
"""

from __future__ import annotations

import numpy as np

from perception.geometry import FloatArray


def range_bearing_jacobian(direction_rad: FloatArray, range_m: FloatArray) -> FloatArray:
    """(N, 2, 3) Jacobians of (range, bearing) of N landmarks with respect to our pose
    (x, y, θ), for landmarks at ``range_m`` (N,) along field directions ``direction_rad`` (N,)."""
    c, s = np.cos(direction_rad), np.sin(direction_rad)
    zero = np.zeros_like(c)
    return np.stack(
        [
            np.stack([-c, -s, zero], axis=-1),
            np.stack([s / range_m, -c / range_m, -np.ones_like(c)], axis=-1),
        ],
        axis=-2,
    )


def information_gain(prior_cov: FloatArray, jacobians: FloatArray, noise_covs: FloatArray) -> float:
    """Nats the sightings with ``jacobians`` (N, 2, 3) and noise ``noise_covs`` (N, 2, 2) take
    from the entropy of a Gaussian pose with covariance ``prior_cov`` (3, 3)."""
    prior_info = np.linalg.inv(prior_cov)
    info = prior_info + np.einsum(
        "nji,njk,nkl->il", jacobians, np.linalg.inv(noise_covs), jacobians
    )
    return 0.5 * float(np.linalg.slogdet(info)[1] - np.linalg.slogdet(prior_info)[1])
