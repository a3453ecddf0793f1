"""EKF SLAM over the poles (seed 000) as the provider of the robot's pose and landmark map, on
its own or with the field features' pose observations (seed 004 ch. 2) fused in."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from perception.estimation.kalman import wrapped_residual
from perception.field.pose_observation import PoseObservation
from perception.field.sensor_model import SensorModelConfig, observe_pose
from perception.providers.base import PerceptionContext, Provider
from perception.representations import FIELD_FEATURES, ODOMETRY, POLE_SIGHTINGS, SELF_POSE, Prior
from perception.slam import EkfSlam, EkfSlamConfig
from perception.types import SlamEstimate
from perception.validation import check_int, check_positive, check_probability


class EkfSlamProvider(Provider):
    """Predicts with each frame's odometry increment, then fuses the frame's pole sightings.

    The back end (classic, gated, minimal view, FEJ) is ``config.backend``; the filter starts
    at the prior's pose with ``config.initial_pose_std``.
    """

    provides = SELF_POSE
    requires: ClassVar[tuple[str, ...]] = (ODOMETRY, POLE_SIGHTINGS)

    def __init__(self, config: EkfSlamConfig) -> None:
        self.config = config
        self._slam: EkfSlam | None = None

    @property
    def slam(self) -> EkfSlam:
        """The episode's filter (after :meth:`reset`)."""
        if self._slam is None:
            raise RuntimeError(
                f"{type(self).__name__}.reset() must be called before reading the filter"
            )
        return self._slam

    def reset(self, prior: Prior) -> None:
        self._slam = EkfSlam(self.config, prior.pose)

    def update(self, inputs: Mapping[str, Any], time_s: float) -> SlamEstimate:
        self._predict_and_sight(inputs)
        return self.slam.estimate()

    def _predict_and_sight(self, inputs: Mapping[str, Any]) -> None:
        """Predict with the frame's odometry increment, then fuse its pole sightings."""
        slam = self.slam
        slam.predict(inputs[ODOMETRY].delta)
        slam.update(inputs[POLE_SIGHTINGS])


_HEADING = (2,)  # index of the angle in a pose (x, y, theta)


@dataclass(frozen=True, kw_only=True)
class FieldFusionConfig:
    """How :class:`EkfSlamFieldPose` fuses the field features' pose observations into SLAM.

    - ``observation_weight`` in (0, 1]: the share of an observation's information fused (as
      :class:`~perception.field.pose_filter.PoseFilterConfig`'s: successive frames see the
      same lines with errors they share, which the filter takes as independent);
    - ``gate_probability`` in (0, 1): an observation is refused when its squared Mahalanobis
      distance exceeds the chi-square quantile with ``rank(information)`` degrees of freedom;
      None fuses every observation. The distance is against ``Sigma_pose + (weight L)^-1``,
      so the gate is as much looser than one on the observation's own covariance as
      ``1 / weight`` (5x in variance at 0.2);
    - ``after_refused_observations`` (int >= 0): after this many observations in a row
      refused by the gate, the pose covariance is inflated (:class:`EkfSlamFieldPose`); frames
      without an observation (no features, or the sensor model's refusal) neither count nor
      break the run; 0 never inflates.
    """

    observation_weight: float = 0.2
    gate_probability: float | None = 0.99
    after_refused_observations: int = 8

    def __post_init__(self) -> None:
        owner = "FieldFusionConfig"
        check_positive(
            owner, "observation_weight", self.observation_weight, upper=1.0, upper_inclusive=True
        )
        if self.gate_probability is not None:
            check_probability(owner, "gate_probability", self.gate_probability)
        check_int(owner, "after_refused_observations", self.after_refused_observations, 0)


class EkfSlamFieldPose(EkfSlamProvider):
    """EKF SLAM over the poles that also fuses, each frame, the pose observation of the frame's
    field features (lines, junctions, the centre circle, posts: the unified sensor model of
    seed 004 ch. 2, :func:`~perception.field.sensor_model.observe_pose`, started from the SLAM
    pose after the frame's pole sightings) with :meth:`perception.slam.EkfSlam.update_pose`,
    as ``fusion`` (:class:`FieldFusionConfig`) says.

    The poles keep the field's two ends apart (they are coloured differently at either end),
    so the field features' symmetry needs no natural landmarks here; the lines give the pose,
    the heading above all, where no pole is in view (facing a goal).

    **Refused in a row.** A robot whose walk is blocked stays put while its odometry reports
    the steps (and turns) it commanded. SLAM follows the odometry and its covariance does not
    grow with the error, so its gate comes to refuse the very observations that would correct
    it. When the gate has refused ``fusion.after_refused_observations`` field observations in a
    row, the pose block of the covariance grows by ``e e^T``, ``e`` (3,) the residual of the
    frame's observation from the SLAM pose (the disagreement, in its own direction), and that
    observation is fused at once, ungated. (``e`` with its part along directions the
    observation does not inform projected out measured worse on the striker's tuning seeds
    0-39: mean pose error 0.117 against 0.064 m.) Nothing checks that the refused observations
    agree with one another: a wrong match the sensor model makes eight times in a row is taken,
    and the poles must pull the pose back.
    """

    requires = (ODOMETRY, POLE_SIGHTINGS, FIELD_FEATURES)

    def __init__(
        self,
        config: EkfSlamConfig,
        model: SensorModelConfig,
        fusion: FieldFusionConfig,
        context: PerceptionContext,
    ) -> None:
        super().__init__(config)
        self.model = model
        self.fusion = fusion
        self.field_map = context.field_map
        self._refused = 0  # field observations in a row the gate refused
        self.inflations = 0  # covariance inflations since the reset

    def reset(self, prior: Prior) -> None:
        super().reset(prior)
        self._refused = self.inflations = 0

    def update(self, inputs: Mapping[str, Any], time_s: float) -> SlamEstimate:
        self._predict_and_sight(inputs)
        slam, features = self.slam, inputs[FIELD_FEATURES]
        if features:
            result = observe_pose(features, slam.mean[:3], self.field_map, self.model)
            if result.observation is not None:
                self._fuse(result.observation)
        return slam.estimate()

    def _fuse(self, observation: PoseObservation) -> None:
        """Fuse a field observation; after too many refused in a row, inflate and fuse it.
        One without information is neither fused nor refused: the count stays."""
        slam, fusion = self.slam, self.fusion
        refused = slam.rejected_poses
        if slam.update_pose(
            observation,
            weight=fusion.observation_weight,
            gate_probability=fusion.gate_probability,
        ):
            self._refused = 0
            return
        if slam.rejected_poses == refused:
            return
        self._refused += 1
        limit = fusion.after_refused_observations
        if limit and self._refused >= limit:
            e = wrapped_residual(observation.pose, slam.mean[:3], _HEADING)
            slam.inflate_pose(np.outer(e, e))
            slam.update_pose(observation, weight=fusion.observation_weight)
            self._refused = 0
            self.inflations += 1
