"""Field features and the pose from them (seed 004 ch. 2) as providers.

``field_features``: :class:`VisionFieldFeatures` (detected in the camera image,
:mod:`perception.vision.field_features`) or :class:`OracleFieldFeatures` (the map's features in
view of the camera at the true pose, with configured noise). ``self_pose``:
:class:`FieldFeaturePose`, the pose filter (:mod:`perception.field.pose_filter`) predicting
with the odometry (the walk's, or with the visual heading) and fusing each frame's pose
observation from the unified sensor model (:mod:`perception.field.sensor_model`), started at
the episode's prior pose, relocalising when lost and told the field's end by natural landmarks.
"""

from __future__ import annotations

import dataclasses
import math
from collections import deque
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
from numpy.typing import ArrayLike

from perception.field.features import FieldFeature
from perception.field.field_map import FieldMap
from perception.field.pose_filter import PoseFilter, PoseFilterConfig
from perception.field.sensor_model import SensorModelConfig, observe_pose
from perception.field.visibility import FeatureViewConfig, visible_features
from perception.geometry import FloatArray
from perception.landmarks.field_end import AWAY, HOME, FieldEndBelief
from perception.providers.base import PerceptionContext, Provider
from perception.representations import (
    FIELD_END,
    FIELD_FEATURE_LAST_SEEN,
    FIELD_FEATURES,
    ODOMETRY,
    SELF_POSE,
    Prior,
)
from perception.types import CameraModel, GroundTruth, TrackedPoseEstimate
from perception.validation import check_in_interval, check_int, check_positive
from perception.vision.field_features import FieldFeatureConfig, detect_field_features


class VisionFieldFeatures(Provider):
    """The field features of the frame's image
    (:func:`~perception.vision.field_features.detect_field_features`)."""

    provides = FIELD_FEATURES
    requires: ClassVar[tuple[str, ...]] = ("image", "camera_state")

    def __init__(self, config: FieldFeatureConfig, context: PerceptionContext) -> None:
        self.config = config
        self.camera: CameraModel = context.require_camera("the field-feature detector")

    def update(self, inputs: Mapping[str, Any], time_s: float) -> tuple[FieldFeature, ...]:
        image = inputs["image"]
        if image is None:
            raise ValueError("VisionFieldFeatures needs a rendered image, got None")
        return detect_field_features(image, self.camera, inputs["camera_state"], self.config)


class TwoCameraFieldFeatures(VisionFieldFeatures):
    """The field features of the top and the bottom camera's images, the top camera's first
    (seed 004 uses both; the bottom one sees the ground at the robot's feet)."""

    requires = ("image", "camera_state", "bottom_image", "bottom_camera_state")

    def update(self, inputs: Mapping[str, Any], time_s: float) -> tuple[FieldFeature, ...]:
        bottom = detect_field_features(
            inputs["bottom_image"], self.camera, inputs["bottom_camera_state"], self.config
        )
        return super().update(inputs, time_s) + bottom


class OracleFieldFeatures(Provider):
    """The map's features in view of the camera at the true pose
    (:func:`~perception.field.visibility.visible_features`), with noise drawn from the
    episode's generator; robots hide nothing."""

    provides = FIELD_FEATURES
    requires = ("truth", "camera_state")

    def __init__(self, config: FeatureViewConfig, context: PerceptionContext) -> None:
        self.config = config
        self.camera: CameraModel = context.require_camera("the field-feature oracle")
        self.field_map: FieldMap = context.field_map
        self._rng: np.random.Generator | None = None

    def reset(self, prior: Prior) -> None:
        self._rng = prior.rng

    def update(self, inputs: Mapping[str, Any], time_s: float) -> tuple[FieldFeature, ...]:
        if self._rng is None:
            raise RuntimeError("OracleFieldFeatures.reset() must be called first")
        truth: GroundTruth = inputs["truth"]
        return visible_features(
            self.field_map,
            truth.robot_pose,
            self.camera,
            inputs["camera_state"],
            self.config,
            self._rng,
        )


class FieldFeatureHistory(Provider):
    """When a feature of each kind was last seen: kind -> time (s)."""

    provides = FIELD_FEATURE_LAST_SEEN
    requires = (FIELD_FEATURES,)

    def __init__(self) -> None:
        self._last_seen: dict[str, float] = {}

    def reset(self, prior: Prior) -> None:
        self._last_seen = {}

    def update(self, inputs: Mapping[str, Any], time_s: float) -> dict[str, float]:
        for feature in inputs[FIELD_FEATURES]:
            self._last_seen[feature.kind] = time_s
        return dict(self._last_seen)


@dataclass(frozen=True, kw_only=True)
class RelocalisationConfig:
    """When the field-feature pose filter starts again.

    Lost: after ``after_refused_frames`` frames in a row whose pose observation the gate
    refused (a kidnap, a fall, a filter that drifted off), the frame's features are placed from
    a start per candidate (:class:`perception.field.sensor_model.SensorModelConfig` ``starts=
    "hypotheses"``, ``order="candidates"``) and, when that fixes all three components, the
    filter restarts there, its covariance the observation's (the share the filter fuses of it:
    ``PoseFilterConfig.observation_weight``), at that pose or its twin, whichever lies nearer
    the filter's pose: the features cannot tell the two apart, and a filter that lost track
    without being moved keeps the end its field-end evidence chose. A restart within
    ``same_place_m`` of the old pose keeps that evidence too; a farther one (a kidnap) clears
    it. 0 never relocalises.

    Mirrored: the field is symmetric end to end, so the features alone may place the filter on
    the twin of the true pose. Each natural-landmark observation of the end the camera faces
    (:attr:`perception.landmarks.field_end.FieldEndBelief.observation`) agrees or disagrees
    with the end the filter's heading faces, and likewise each observation of the side board
    the camera faces (``side_observation``, not the seed's: the sides swap under the same
    half turn) with the side the heading faces; over the last ``end_window_frames`` frames, with
    ``d`` disagreeing and ``a`` agreeing, the chance the filter is mirrored is the mean of
    Beta(1 + d, 1 + a), and above ``end_confidence`` the filter is turned through the centre
    spot, and the window with it (each disagreeing view now agrees), so that as much evidence
    is needed to turn it back. (Seed 004 re-initialises the filter facing the end its belief
    is certain of; counted in the field frame, as here, the evidence survives the robot turning
    round within the window.)

    (b) Chosen on the kidnap benchmark's tuning seeds 0-4 (``benchmarks/kidnaps.py``, 50
    kidnaps): its observations and relocalisations replayed through this rule ended 40, 38
    and 35 kidnaps on the correct end at ``end_confidence`` 0.65, 0.7 and 0.75; most
    intervals lost at 0.7 had no observation at all, two a single right one. Matches may want
    more (the seed: a false turn costs more there than a late one).
    """

    after_refused_frames: int = 8
    end_window_frames: int = 100
    end_confidence: float = 0.65  # one disagreeing view, none agreeing (P = 2/3), turns it (b)
    # a restart nearer the old pose keeps the evidence (judgement: a few times a lost filter's
    # drift, far below the kidnaps' moves; not tuned)
    same_place_m: float = 0.5

    def __post_init__(self) -> None:
        owner = "RelocalisationConfig"
        check_int(owner, "after_refused_frames", self.after_refused_frames, 0)
        check_int(owner, "end_window_frames", self.end_window_frames, 1)
        check_in_interval(owner, "end_confidence", self.end_confidence, 0.5, 1.0)
        check_positive(owner, "same_place_m", self.same_place_m, allow_zero=True)


class FieldFeaturePose(Provider):
    """The robot pose from odometry and field features: one pose-filter prediction per
    odometry increment and one update per frame whose features the sensor model places
    consistently (a refused observation, or a gated one, changes nothing); a relocalisation
    when lost, and a half turn through the centre spot, ``(x, y, theta) -> (-x, -y, theta +
    pi)``, when the natural landmarks (``field_end``, seed 004 ch. 4) say it is mirrored
    (:class:`RelocalisationConfig`). The estimate holds no landmarks: the field's map is
    known."""

    provides = SELF_POSE
    requires = (ODOMETRY, FIELD_FEATURES, FIELD_END, "camera_state")

    def __init__(
        self,
        model: SensorModelConfig,
        config: PoseFilterConfig,
        relocalisation: RelocalisationConfig,
        context: PerceptionContext,
    ) -> None:
        self.model = model
        self.config = config
        self.relocalisation = relocalisation
        self.global_model = dataclasses.replace(model, starts="hypotheses", order="candidates")
        self.field_map = context.field_map
        self._filter: PoseFilter | None = None
        self._refused = 0  # frames in a row whose observation the gate refused
        # per frame: +1 the field end seen agrees with the filter's heading, -1 not, 0 no view
        self._agreement: deque[int] = deque(maxlen=relocalisation.end_window_frames)
        self.relocalisations = 0  # restarts from one frame's features since the reset
        self.half_turns = 0  # turns through the centre spot since the reset

    @property
    def filter(self) -> PoseFilter:
        """The episode's pose filter (after :meth:`reset`)."""
        if self._filter is None:
            raise RuntimeError("FieldFeaturePose.reset() must be called before reading the filter")
        return self._filter

    def reset(self, prior: Prior) -> None:
        self._filter = PoseFilter(self.config, prior.pose)
        self._refused = 0
        self._agreement.clear()
        self.relocalisations = self.half_turns = 0

    def update(self, inputs: Mapping[str, Any], time_s: float) -> TrackedPoseEstimate:
        pose_filter = self.filter
        restarts = self.relocalisations + self.half_turns
        pose_filter.predict(inputs[ODOMETRY].delta)
        self._weigh_the_field_end(inputs[FIELD_END], inputs["camera_state"].head_yaw)
        features = inputs[FIELD_FEATURES]
        accepted = False
        if features:
            result = observe_pose(features, pose_filter.pose, self.field_map, self.model)
            if result.observation is not None:
                accepted = pose_filter.update(result.observation)
                self._refused = 0 if accepted else self._refused + 1
            limit = self.relocalisation.after_refused_frames
            if limit and self._refused >= limit:
                self._relocalise(features)
        return TrackedPoseEstimate(
            pose=pose_filter.pose,
            pose_cov=pose_filter.cov,
            landmark_ids=np.zeros(0, dtype=np.int64),
            landmarks=np.zeros((0, 2)),
            landmark_covs=np.zeros((0, 2, 2)),
            accepted=accepted,
            restarted=self.relocalisations + self.half_turns > restarts,
        )

    def _weigh_the_field_end(self, belief: FieldEndBelief, head_yaw: float) -> None:
        """Count this frame's field-end observation (or, failing one, its side-board
        observation) against the filter's heading; turn the filter through the centre spot
        when it is likely mirrored (RelocalisationConfig)."""
        heading = self.filter.pose[2] + head_yaw
        if belief.observation:
            facing = AWAY if math.cos(heading) > 0 else HOME
            self._agreement.append(1 if belief.observation == facing else -1)
        elif belief.side_observation:
            side = 1 if math.sin(heading) > 0 else -1
            self._agreement.append(1 if belief.side_observation == side else -1)
        else:
            self._agreement.append(0)
        disagree = sum(1 for a in self._agreement if a < 0)
        agree = sum(1 for a in self._agreement if a > 0)
        if (1 + disagree) / (2 + disagree + agree) > self.relocalisation.end_confidence:
            self._half_turn()
            self.half_turns += 1

    def _half_turn(self) -> None:
        """Turn the filter through the centre spot, ``(x, y, theta) -> (-x, -y, theta + pi)``
        with its covariance, and the field-end evidence with it: a view that disagreed with
        the old heading agrees with the new one."""
        pose_filter = self.filter
        pose_filter.reset(*_half_turn(pose_filter.pose, pose_filter.cov))
        turned = [-a for a in self._agreement]
        self._agreement.clear()
        self._agreement.extend(turned)

    def _relocalise(self, features: tuple[FieldFeature, ...]) -> None:
        """Restart the filter where this frame's features alone put the robot, if they fix
        the whole pose: at that pose or its twin, whichever lies nearer the filter's pose
        (:class:`RelocalisationConfig`)."""
        pose_filter = self.filter
        result = observe_pose(features, pose_filter.pose, self.field_map, self.global_model)
        observation = result.observation
        if observation is None or np.linalg.matrix_rank(observation.information) < 3:
            return
        information = self.config.observation_weight * observation.information
        pose, cov = observation.pose, np.linalg.inv(information)
        old = pose_filter.pose
        if np.hypot(*(pose[:2] + old[:2])) < np.hypot(*(pose[:2] - old[:2])):
            pose, cov = _half_turn(pose, cov)
        pose_filter.reset(pose, cov)
        self._refused = 0
        if np.hypot(*(pose[:2] - old[:2])) > self.relocalisation.same_place_m:
            self._agreement.clear()  # a kidnap: the evidence was about the old pose
        self.relocalisations += 1


def _half_turn(pose: ArrayLike, cov: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """The field's twin of ``pose`` (3,) (m, m, rad, field frame) through the centre spot,
    ``(-x, -y, theta + pi)``, and of its covariance ``cov`` (3, 3)."""
    flip = np.diag([-1.0, -1.0, 1.0])
    x, y, theta = np.asarray(pose, dtype=np.float64)
    return np.array([-x, -y, theta + math.pi]), flip @ np.asarray(cov, dtype=np.float64) @ flip
