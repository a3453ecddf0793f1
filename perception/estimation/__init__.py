"""Estimation kernel shared by the filters: Kalman steps, chi-square gates, data association.

- :mod:`~perception.estimation.kalman`: prediction, innovation covariance, Joseph-form update
  (dense or sparse ``H``), angle-wrapped residuals;
- :mod:`~perception.estimation.gating`: chi-square thresholds and Mahalanobis gates;
- :mod:`~perception.estimation.association`: global nearest-neighbour association.

Pure numpy and scipy (scipy is imported only when a threshold or an assignment is computed).
"""

from perception.estimation.association import (
    Association,
    global_nearest_neighbour,
    mahalanobis_cost_matrix,
)
from perception.estimation.gating import chi2_threshold, mahalanobis_squared, within_gate
from perception.estimation.kalman import (
    innovation_covariance,
    joseph_update,
    predict,
    wrapped_residual,
)

__all__ = [
    "Association",
    "chi2_threshold",
    "global_nearest_neighbour",
    "innovation_covariance",
    "joseph_update",
    "mahalanobis_cost_matrix",
    "mahalanobis_squared",
    "predict",
    "within_gate",
    "wrapped_residual",
]
