"""The perception stack of one robot: the configured providers, run in dependency order.

A :class:`PerceptionPipeline` is asked for the representations a consumer reads (an env's
observation, reward and info) and builds just the providers those need, transitively: an
unused provider costs nothing. Each step feeds the :class:`perception.types.SensorFrame`'s
inputs through the providers once and returns a
:class:`perception.representations.PerceptionOutput`. The pipeline is built once (the CNN is
loaded then) and :meth:`~PerceptionPipeline.reset` per episode.

Provider choice, by representation (:data:`PROVIDERS`; the defaults of
:class:`PipelineConfig` in brackets)::

    image  ──► image_detections [cnn] ──► pole_sightings [cnn | colour | oracle]
                                              │             └──► pole_last_seen [history]
    odometry ─────────────────────────────────┴──► self_pose [ekf_slam | oracle] ──┐
    odometry, pole_sightings, field_features ─► self_pose [ekf_slam_field_features]│
    odometry, laser ──► self_pose [circle_slam]                                    │
    image (+ bottom_image) ──► field_features [vision | vision_both_cameras | oracle]
                                  ├──► self_pose [field_features] (with odometry)  │
                                  └──► field_feature_last_seen [history]           │
    image, sonar_observations ──► robot_sightings [vision] ──┐                     │
    image ──► robot_sightings [vision_only]                  ├──► robot_tracks [tracker]
    image_detections ──► robot_sightings [cnn | oracle] ─────┘
    sonar ──► sonar_observations [filter]
    laser, self_pose ──► circle_map [laser]
    self_pose (circle_slam) ──► circle_map [slam]
    image, robot_sightings ──► horizon_features [surf1d]
    odometry_delta ──► odometry [reported]
    odometry_delta, horizon_features ──► odometry [visual]
    odometry ──► odometry_pose [dead_reckoning]
    horizon_features, field_features, self_pose (the last frame's)
                                  ──► field_end [none | bag_of_words] ──► self_pose [field_features]
    image_detections (+ bottom_image) ──► ball_sightings [cnn | cnn_both_cameras | oracle]
                                  ──► ball [filter | oracle] (with odometry, self_pose)

A representation an emulator delivers (``emulated``: the geometric camera mode's pole
sightings) is read from :attr:`perception.types.SensorFrame.emulated` instead of a provider.
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from perception.circles.circle_map import CircleMapConfig
from perception.circles.scan_circles import ScanCirclesConfig
from perception.field.pose_filter import PoseFilterConfig
from perception.field.sensor_model import SensorModelConfig
from perception.field.visibility import FeatureViewConfig
from perception.geometry import FloatArray
from perception.landmarks.horizon_features import HorizonFeatureConfig
from perception.providers.ball import CnnBallSightings, TrackedBall, TwoCameraCnnBallSightings
from perception.providers.base import PREVIOUS, PerceptionContext, Provider
from perception.providers.circle_slam import CircleSlamProvider, SlamCircleMap
from perception.providers.circles import LaserCircleMap
from perception.providers.field import (
    FieldFeatureHistory,
    FieldFeaturePose,
    OracleFieldFeatures,
    RelocalisationConfig,
    TwoCameraFieldFeatures,
    VisionFieldFeatures,
)
from perception.providers.field_end import (
    FieldEndProviderConfig,
    NaturalLandmarkFieldEnd,
    UnknownFieldEnd,
)
from perception.providers.landmarks import (
    HorizonFeatureProvider,
    VisualOdometry,
    VisualOdometryProviderConfig,
    WalkOdometry,
)
from perception.providers.odometry import DeadReckoning
from perception.providers.oracles import (
    OracleBall,
    OracleBallSightings,
    OracleConfig,
    OraclePoleSightings,
    OracleRobotSightings,
    OracleSelfPose,
)
from perception.providers.poles import (
    CnnDetections,
    CnnPoleSightings,
    ColourPoleSightings,
    PoleSightingHistory,
)
from perception.providers.robots import (
    CnnRobotSightings,
    FilteredSonar,
    TrackedRobots,
    VisionOnlyRobotSightings,
    VisionRobotSightings,
)
from perception.providers.slam import EkfSlamFieldPose, EkfSlamProvider, FieldFusionConfig
from perception.representations import (
    BALL,
    BALL_SIGHTINGS,
    CIRCLE_MAP,
    FIELD_END,
    FIELD_FEATURE_LAST_SEEN,
    FIELD_FEATURES,
    FRAME_INPUTS,
    HORIZON_FEATURES,
    IMAGE_DETECTIONS,
    ODOMETRY,
    ODOMETRY_POSE,
    POLE_LAST_SEEN,
    POLE_SIGHTINGS,
    REPRESENTATIONS,
    ROBOT_SIGHTINGS,
    ROBOT_TRACKS,
    SELF_POSE,
    SONAR_OBSERVATIONS,
    PerceptionOutput,
    Prior,
)
from perception.slam import EkfSlamConfig
from perception.slam.circle_slam import CircleSlamConfig
from perception.tracking.ball_filter import BallFilterConfig
from perception.tracking.robot_tracker import RobotTrackerConfig
from perception.tracking.sonar_filter import SonarFilterConfig
from perception.types import SensorFrame
from perception.validation import (
    check_choice,
    check_finite,
    check_in_interval,
    check_instance,
    check_nested_configs,
)
from perception.vision.cnn_ball import CnnBallConfig
from perception.vision.cnn_detector import CnnDetectorConfig
from perception.vision.cnn_robots import CnnRobotConfig
from perception.vision.colour_filter import ColourFilterConfig
from perception.vision.field_features import FieldFeatureConfig
from perception.vision.robots import RobotDetectorConfig

ProviderFactory = Callable[["PipelineConfig", PerceptionContext], Provider]

# representation -> provider name -> how to build it
PROVIDERS: Mapping[str, Mapping[str, ProviderFactory]] = {
    ODOMETRY: {
        "reported": lambda c, ctx: WalkOdometry(),
        "visual": lambda c, ctx: VisualOdometry(c.visual_odometry),
    },
    ODOMETRY_POSE: {"dead_reckoning": lambda c, ctx: DeadReckoning()},
    HORIZON_FEATURES: {"surf1d": lambda c, ctx: HorizonFeatureProvider(c.horizon, ctx)},
    FIELD_END: {
        "none": lambda c, ctx: UnknownFieldEnd(),
        "bag_of_words": lambda c, ctx: NaturalLandmarkFieldEnd(c.natural_landmarks, ctx),
    },
    IMAGE_DETECTIONS: {"cnn": lambda c, ctx: CnnDetections(c.cnn, ctx)},
    POLE_SIGHTINGS: {
        "cnn": lambda c, ctx: CnnPoleSightings(c.cnn, c.cnn_pole_score_threshold, ctx),
        "colour": lambda c, ctx: ColourPoleSightings(c.colour_filter, ctx),
        "oracle": lambda c, ctx: OraclePoleSightings(c.oracle, ctx),
    },
    POLE_LAST_SEEN: {"history": lambda c, ctx: PoleSightingHistory()},
    SELF_POSE: {
        "ekf_slam": lambda c, ctx: EkfSlamProvider(c.slam),
        "ekf_slam_field_features": lambda c, ctx: EkfSlamFieldPose(
            c.slam, c.sensor_model, c.field_fusion, ctx
        ),
        "oracle": lambda c, ctx: OracleSelfPose(c.oracle),
        "circle_slam": lambda c, ctx: CircleSlamProvider(c.circle_slam, c.scan_circles),
        "field_features": lambda c, ctx: FieldFeaturePose(
            c.sensor_model, c.pose_filter, c.relocalisation, ctx
        ),
    },
    ROBOT_SIGHTINGS: {
        "vision": lambda c, ctx: VisionRobotSightings(c.vision_robots, c.sonar_filter, ctx),
        "vision_only": lambda c, ctx: VisionOnlyRobotSightings(c.vision_robots, ctx),
        "cnn": lambda c, ctx: CnnRobotSightings(c.cnn_robots),
        "oracle": lambda c, ctx: OracleRobotSightings(c.oracle, ctx),
    },
    SONAR_OBSERVATIONS: {"filter": lambda c, ctx: FilteredSonar(c.sonar_filter)},
    ROBOT_TRACKS: {"tracker": lambda c, ctx: TrackedRobots(c.robot_tracker)},
    FIELD_FEATURE_LAST_SEEN: {"history": lambda c, ctx: FieldFeatureHistory()},
    FIELD_FEATURES: {
        "vision": lambda c, ctx: VisionFieldFeatures(c.field_detector, ctx),
        "vision_both_cameras": lambda c, ctx: TwoCameraFieldFeatures(c.field_detector, ctx),
        "oracle": lambda c, ctx: OracleFieldFeatures(c.feature_view, ctx),
    },
    BALL_SIGHTINGS: {
        "cnn": lambda c, ctx: CnnBallSightings(c.cnn_ball),
        "cnn_both_cameras": lambda c, ctx: TwoCameraCnnBallSightings(c.cnn_ball, c.cnn, ctx),
        "oracle": lambda c, ctx: OracleBallSightings(c.oracle, ctx),
    },
    BALL: {
        "filter": lambda c, ctx: TrackedBall(c.ball_filter, c.cnn_ball.radius_m),
        "oracle": lambda c, ctx: OracleBall(c.oracle),
    },
    CIRCLE_MAP: {
        "laser": lambda c, ctx: LaserCircleMap(c.circle_mapper),
        "slam": lambda c, ctx: _slam_circle_map(c),
    },
}

# self poses that read the field features (their observation keys join the envs')
FIELD_FEATURE_POSES = ("field_features", "ekf_slam_field_features")
# self poses that map the poles (they need a field with poles)
POLE_MAPPING_POSES = ("ekf_slam", "ekf_slam_field_features")


def _slam_circle_map(config: PipelineConfig) -> SlamCircleMap:
    """The circle map of circle SLAM; ValueError unless the self pose is circle SLAM."""
    if config.self_pose != "circle_slam":
        raise ValueError(
            "PipelineConfig.circle_map='slam' reads the map of self_pose='circle_slam', "
            f"got self_pose={config.self_pose!r}"
        )
    return SlamCircleMap()


@dataclass(frozen=True, kw_only=True)
class PipelineConfig:
    """Which provider computes each representation, and each provider's configuration."""

    # The CNN with the gated back end: the best measured combination that never diverged
    # (README, "Choosing the defaults"). On the tuning walks (seeds 1300-1304) it maps as well
    # as the classic filter (0.060 m robot / 0.099 m landmarks; classic 0.060 / 0.095, FEJ
    # 0.062 / 0.107; the colour filter's best 0.085 / 0.155), and on one-minute patrols under
    # default lighting (seeds 100-104) the classic and FEJ filters were thrown 4.4 / 3.7 m off
    # by one confused sighting that the gate refused. The geometric camera mode emulates the
    # colour filter and needs pole_sightings="colour".
    pole_sightings: str = "cnn"  # one of PROVIDERS["pole_sightings"]
    self_pose: str = "ekf_slam"  # one of PROVIDERS["self_pose"]
    colour_filter: ColourFilterConfig = field(default_factory=ColourFilterConfig)
    # The CNN's image detections (every class; read by every consumer) at the detector's own
    # threshold, 0.4 (its precision/recall balance on the tuning frames). Pole sightings for
    # SLAM need both band colours seen, and a score of cnn_pole_score_threshold.
    cnn: CnnDetectorConfig = field(
        default_factory=lambda: CnnDetectorConfig(require_both_colours=True)
    )
    # SLAM takes CNN pole detections scoring 0.6 or more, stricter than the detector's 0.4: on
    # the tuning walks the class confusions that pass at 0.3-0.5 start a landmark in the wrong
    # place (0.11-1.3 m landmark error), and on a patrol (seed 101) a pole whose lower band a
    # robot hid was taken for its neighbour. At least cnn.score_threshold.
    cnn_pole_score_threshold: float = 0.6
    # The seed's 0.4 m / pi/3 gate. It can lock a badly started landmark out of every
    # correction (seed 000 §4.1); EkfSlamConfig() alone is seed 000's classic Algorithm 5.
    slam: EkfSlamConfig = field(default_factory=lambda: EkfSlamConfig(backend="gated"))
    # Seed 004's detector with its sonar check: within 3 m on the held-out walking frames it
    # finds 99.5 % of the robots at 98.4 % precision, the CNN's robot class 96.7 % at 93.6 %
    # (benchmarks/robot_detection.py, default lighting), for about 9 ms more per frame.
    robot_sightings: str = "vision"  # one of PROVIDERS["robot_sightings"]
    cnn_robots: CnnRobotConfig = field(default_factory=CnnRobotConfig)
    vision_robots: RobotDetectorConfig = field(default_factory=RobotDetectorConfig)
    sonar_filter: SonarFilterConfig = field(default_factory=SonarFilterConfig)
    robot_tracker: RobotTrackerConfig = field(default_factory=RobotTrackerConfig)
    circle_map: str = "laser"  # one of PROVIDERS["circle_map"]
    circle_mapper: CircleMapConfig = field(default_factory=CircleMapConfig)
    # self_pose="circle_slam": EKF SLAM over circles from wheel odometry and laser circles
    circle_slam: CircleSlamConfig = field(default_factory=CircleSlamConfig)
    scan_circles: ScanCirclesConfig = field(default_factory=ScanCirclesConfig)
    oracle: OracleConfig = field(default_factory=OracleConfig)
    # self_pose="field_features": the pose filter on the unified sensor model's observations
    # of the frame's field features (seed 004 ch. 2), the map being the known field
    field_features: str = "vision"  # one of PROVIDERS["field_features"]
    # PyBullet draws its images one row above the pinhole model (CameraModel's docstring,
    # tests/spl_env/test_world.py): unmoved, every ground point reads too far (5 cm at 3 m)
    field_detector: FieldFeatureConfig = field(
        default_factory=lambda: FieldFeatureConfig(row_offset_px=1.0)
    )
    feature_view: FeatureViewConfig = field(default_factory=FeatureViewConfig)
    sensor_model: SensorModelConfig = field(default_factory=SensorModelConfig)
    # A tenth of each frame's information: on rendered one-minute patrols (seeds 0-2) the full
    # information gave pose NEES 9-800 and lost one episode (0.88 m); 0.3 gave 4.8-5.2, 0.1
    # gave 2.0-3.4 (consistent, 3 dof) and 0.035-0.044 m (the errors of views shared by
    # successive frames, which the filter takes as independent)
    pose_filter: PoseFilterConfig = field(
        default_factory=lambda: PoseFilterConfig(observation_weight=0.1)
    )
    relocalisation: RelocalisationConfig = field(default_factory=RelocalisationConfig)
    # self_pose="ekf_slam_field_features": SLAM over the poles fusing the field features'
    # pose observations. A fifth of each observation's information: on the striker's tuning
    # seeds 0-39 (geometric, centre kick, inflating after 8 refusals) weights 0.1 / 0.2 / 0.3 /
    # 1 gave mean pose errors 0.077 / 0.064 / 0.066 / 0.075 m (SLAM alone 0.160 m) and heading
    # errors 3.0 / 2.1 / 2.0 / 1.7 deg; on rendered patrols (seeds 0-2) pose NEES 3.3 / 3.9 /
    # 4.5 at 0.1 / 0.2 / 0.3 (0.039-0.042 m; SLAM alone 0.074 m, NEES 3.6). Without the
    # inflation, 0.1 gave 0.146 m (seeds 0-19): blocked walks ran the heading off.
    field_fusion: FieldFusionConfig = field(default_factory=FieldFusionConfig)
    # The odometry every pose estimator (and dead reckoning) uses: the robot's report
    # (walk engine, wheel encoders), or its heading change replaced by the visual heading
    # odometry of the horizon's 1D SURF features (seed 004 ch. 5; needs rendered images)
    odometry: str = "reported"  # one of PROVIDERS["odometry"]
    horizon: HorizonFeatureConfig = field(default_factory=HorizonFeatureConfig)
    visual_odometry: VisualOdometryProviderConfig = field(
        default_factory=VisualOdometryProviderConfig
    )
    # Which end of the (symmetric) field the robot faces, for self_pose="field_features":
    # unknown, or recognised from natural landmarks on the horizon (seed 004 ch. 4)
    field_end: str = "none"  # one of PROVIDERS["field_end"]
    natural_landmarks: FieldEndProviderConfig = field(default_factory=FieldEndProviderConfig)
    # The ball: sightings from the CNN's ball boxes (the renderer's row offset taken out, as
    # for the field features), and the ball's filter in the field frame (ball="filter" reads
    # the robot tracks too: beside a robot the camera's misses of the ball do not lose it)
    ball_sightings: str = "cnn"  # one of PROVIDERS["ball_sightings"]
    cnn_ball: CnnBallConfig = field(default_factory=lambda: CnnBallConfig(row_offset_px=1.0))
    ball: str = "filter"  # one of PROVIDERS["ball"]
    ball_filter: BallFilterConfig = field(default_factory=BallFilterConfig)

    def __post_init__(self) -> None:
        check_nested_configs(self)
        for representation in PROVIDERS:
            if hasattr(self, representation):
                check_choice(
                    "PipelineConfig",
                    representation,
                    getattr(self, representation),
                    tuple(PROVIDERS[representation]),
                )
        check_in_interval(
            "PipelineConfig",
            "cnn_pole_score_threshold",
            self.cnn_pole_score_threshold,
            self.cnn.score_threshold,
            1.0,
            low_inclusive=True,
        )

    def provider_name(self, representation: str) -> str:
        """The provider of ``representation``: the field of that name where the choice is the
        config's, else the only registered one."""
        if hasattr(self, representation):
            return str(getattr(self, representation))
        (only,) = PROVIDERS[representation]
        return only


class PerceptionPipeline:
    """The providers that compute ``outputs`` (representation names) from sensor frames.

    ``emulated`` names representations a frame delivers ready-made (in
    :attr:`perception.types.SensorFrame.emulated`). Raises ValueError for an unknown
    representation or a dependency cycle.
    """

    def __init__(
        self,
        config: PipelineConfig,
        context: PerceptionContext,
        outputs: Collection[str],
        emulated: Collection[str] = (),
    ) -> None:
        check_instance("config", config, PipelineConfig)
        check_instance("context", context, PerceptionContext)
        self.config = config
        self._providers: dict[str, Provider] = {}  # in dependency order
        self._previous: dict[str, Any] = {}  # the last frame's representations
        inputs: set[str] = set()
        reached: set[str] = set()  # of the emulated representations, those something reads
        visiting: list[str] = []

        def resolve(name: str) -> None:
            if name in emulated:
                reached.add(name)
                return
            if name in self._providers or name in inputs:
                return
            if name in FRAME_INPUTS:
                inputs.add(name)
                return
            if name not in PROVIDERS:
                raise ValueError(
                    f"unknown representation {name!r}; known: {sorted(PROVIDERS)} and the "
                    f"sensor inputs {FRAME_INPUTS}"
                )
            if name in visiting:
                raise ValueError(f"provider dependency cycle: {[*visiting, name]}")
            visiting.append(name)
            provider = PROVIDERS[name][config.provider_name(name)](config, context)
            for required in provider.requires:
                resolve(required)
            visiting.pop()
            self._providers[name] = provider
            later.extend(provider.requires_previous)

        later: list[str] = []  # read one frame late: resolved after everything else
        for name in outputs:
            resolve(name)
        while later:
            resolve(later.pop(0))
        self.frame_inputs = frozenset(inputs)  # the SensorFrame fields the providers read
        self._frame_input_order = tuple(sorted(inputs))  # read in this order: errors repeat
        self._emulated_order = tuple(sorted(reached))
        self.emulated = frozenset(reached)  # the emulated representations it reads

    @property
    def representations(self) -> tuple[str, ...]:
        """Names of the representations each step computes, in the order they run."""
        return tuple(self._providers)

    def provider(self, representation: str) -> Provider:
        """The provider computing ``representation``; KeyError if none in this pipeline."""
        return self._providers[representation]

    def reset(self, pose: FloatArray, rng: np.random.Generator) -> None:
        """Start an episode from the believed start ``pose`` (3,): every provider forgets the last
        one. Each gets its own generator spawned from ``rng`` (one per known representation, in a
        fixed order, whether or not it runs), so which providers run changes no draw of another
        and ``rng``'s own stream is not advanced."""
        self._previous = {}
        generators = dict(zip(REPRESENTATIONS, rng.spawn(len(REPRESENTATIONS)), strict=True))
        for name, provider in self._providers.items():
            provider.reset(Prior(pose=pose, rng=generators[name]))

    def step(self, frame: SensorFrame) -> PerceptionOutput:
        """Run every provider once on ``frame``; ValueError if it lacks an input they read or
        its time is not finite."""
        if not isinstance(frame, SensorFrame):
            raise TypeError(f"frame must be a SensorFrame, got {type(frame).__name__}")
        check_finite("PerceptionPipeline.step", "frame.time_s", frame.time_s)
        values: dict[str, Any] = {}
        for name in self._frame_input_order:
            value = getattr(frame, name)
            if value is None:
                readers = [r for r, p in self._providers.items() if name in p.requires]
                raise ValueError(f"frame.{name} is None, but the providers of {readers} read it")
            values[name] = value
        for name in self._emulated_order:
            if name not in frame.emulated:
                raise ValueError(f"frame.emulated lacks {name!r}, which this pipeline emulates")
            values[name] = frame.emulated[name]
        computed: dict[str, Any] = {}
        for name, provider in self._providers.items():
            needed = {r: values[r] for r in provider.requires}
            for r in provider.requires_previous:
                needed[PREVIOUS + r] = self._previous.get(r)
            values[name] = computed[name] = provider.update(needed, frame.time_s)
        for name in self._emulated_order:
            computed[name] = values[name]
        self._previous = computed
        return PerceptionOutput(time_s=frame.time_s, representations=computed)
