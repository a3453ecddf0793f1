"""``Circles/Office-v0`` and ``Circles/Backyard-v0``: map a room's columns or trees with a laser
from a differential-drive robot (seed 001), on the env core's step loop."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from perception.geometry import FloatArray, transform_points
from perception.pipeline import PerceptionPipeline, PipelineConfig
from perception.providers.base import PerceptionContext
from perception.representations import CIRCLE_MAP, ODOMETRY_POSE, SELF_POSE
from perception.slam.circle_slam import CircleSlamConfig
from perception.types import PoleGeometry, SensorFrame
from perception.validation import check_int
from spl_env.config import CoreConfig
from spl_env.envs.core import RobotEnv
from spl_env.envs.info import InfoLayout
from spl_env.observations.base import ObservationEncoder
from spl_env.observations.body import EpisodeClockEncoder
from spl_env.observations.circles import CircleMapEncoder
from spl_env.observations.ranges import ScanEncoder, SonarRingEncoder
from spl_env.observations.self_pose import SelfPoseEncoder
from spl_env.rendering import RoomView
from spl_env.robots.diff_drive import DiffDriveConfig, DiffDriveRobot, wheel_speeds_from_action
from spl_env.scenes.backyard import BACKYARD
from spl_env.scenes.office import OFFICE
from spl_env.scenes.rooms import RoomLayout, RoomScene
from spl_env.sensors.diff_drive_rig import DiffDriveRig, DiffDriveRigConfig
from spl_env.sim.placement import Placement, RectangleArea
from spl_env.tasks.circle_mapping import CircleMappingTask, CircleMappingTaskConfig
from spl_env.world_state import RoomState

CIRCLES_ALIASES: dict[str, str] = {
    "episode_s": "task.episode_s",
    "self_pose": "perception.self_pose",
    "circle_map": "perception.circle_map",
    "laser": "sensors.laser",
    "sonar_ring": "sensors.sonar_ring",
}


def _circle_slam_perception() -> PipelineConfig:
    """Circle SLAM from odometry and laser alone, its map the circle map. The filter starts
    certain of its start pose: a SLAM map's frame is where the robot started, and the room's
    frame is taken to be known there (seed 001's robot starts at a known pose too); with an
    uncertain start the whole map would be off by the start's error (0.02 rad is 8 cm at 4 m).
    For the same reason new circles enter the state at their first sighting (provisional until
    their third): held back until the third, they were anchored to a pose that dead reckoning
    had already turned by 0.002-0.006 rad (office seeds 0-9, the tuning seeds)."""
    return PipelineConfig(
        self_pose="circle_slam",
        circle_map="slam",
        circle_slam=CircleSlamConfig(initial_pose_std=(0.0, 0.0, 0.0), admission="provisional"),
    )


@dataclass(frozen=True, kw_only=True)
class CirclesConfig(CoreConfig):
    """A room (``layout``), the differential-drive robot and its sensors, perception (default:
    circle SLAM and its map) and the circle-mapping task; :class:`CoreConfig`'s fields besides.

    ``observed_circles``: circle-map rows of the observation; ``scan_bins``: the downsampled
    scan's length (it must divide the laser's beams).
    """

    layout: RoomLayout = OFFICE
    robot: DiffDriveConfig = field(default_factory=DiffDriveConfig)
    sensors: DiffDriveRigConfig = field(default_factory=DiffDriveRigConfig)
    perception: PipelineConfig = field(default_factory=_circle_slam_perception)
    task: CircleMappingTaskConfig = field(default_factory=CircleMappingTaskConfig)
    physics_dt_s: float = 0.1  # nothing moves by physics: one physics step per control step
    observed_circles: int = 8
    scan_bins: int = 36

    def __post_init__(self) -> None:
        super().__post_init__()
        check_int("CirclesConfig", "observed_circles", self.observed_circles, 1)
        check_int("CirclesConfig", "scan_bins", self.scan_bins, 1)
        if self.sensors.laser.n_beams % self.scan_bins:
            raise ValueError(
                f"CirclesConfig.scan_bins must divide the laser's {self.sensors.laser.n_beams} "
                f"beams, got {self.scan_bins}"
            )
        if self.perception.self_pose == "circle_slam" and self.sensors.laser.range_noise_std_m <= 0:
            raise ValueError(
                "CirclesConfig.sensors.laser.range_noise_std_m must be > 0 with "
                "perception.self_pose='circle_slam' (its scan update weighs ranges by it), got "
                f"{self.sensors.laser.range_noise_std_m}"
            )


@dataclass(frozen=True, kw_only=True)
class BackyardConfig(CirclesConfig):
    """:class:`CirclesConfig` in the backyard, for seed 001's 180 s."""

    layout: RoomLayout = BACKYARD
    task: CircleMappingTaskConfig = field(
        default_factory=lambda: CircleMappingTaskConfig(episode_s=180.0)
    )


AGENT_NAME = "pioneer"


class CirclesEnv(RobotEnv[RoomState]):
    """Circle mapping in a room of columns (``Circles/Office-v0``) or trees
    (``Circles/Backyard-v0``): seed 001's world on the env core.

    A Pioneer 3-DX-like differential-drive robot (wheel radius 0.0975 m, axle 0.381 m, top speed
    1.2 m/s; :mod:`spl_env.robots.diff_drive`) drives among the layout's objects
    (:mod:`spl_env.scenes.office`, :mod:`spl_env.scenes.backyard`) with noisy wheel encoders,
    16 sonars and seed 001's laser (180 beams over 180°, σ = 0.02 m, 10 m) on top, at 10 Hz.
    Perception (default ``self_pose="circle_slam"``, ``circle_map="slam"``) is EKF SLAM over
    the circles each scan shows (:mod:`perception.circles.scan_circles`), fused by their
    ranges, from odometry and laser alone, new circles entering the state at their first
    sighting (``admission="provisional"``, :mod:`perception.slam.circle_slam`);
    ``circle_map="laser"`` maps with :mod:`perception.circles.circle_map` on the believed pose
    instead, and with it ``self_pose="oracle"`` believes the true pose with configured noise
    (``circle_map="slam"`` reads the circle SLAM's own map, so it needs
    ``self_pose="circle_slam"``).

    **Action**: ``Box(-1, 1, (2,), float32)``: the left and right wheel speeds as fractions of
    the top speed (12.3 rad/s). NaN or out-of-range actions raise ``ValueError``. The body
    stops where it would touch a wall or an object (its wheels slip: the encoders count on).

    **Observation** (``Dict`` of float32 ``Box``; C = ``observed_circles``):

    =======================  ======  =========================================================
    key                      shape   content
    =======================  ======  =========================================================
    ``self_pose_field``      (4,)    believed x, y over the room's inner half length and
                                     width (saturating at ±1.5), cos θ, sin θ
    ``self_pose_std``        (3,)    std of x, y (m) and θ (rad), each as s / (s + 0.5)
    ``circles_*``            (C,)    the C nearest mapped circles from the believed pose:
                                     cos / sin bearing, range r / (r + 3 m), radius
                                     R / (R + 0.25 m), std, mask
    ``scan``                 (36,)   the laser scan in 36 runs of 5 beams, right to left,
                                     nearest return / 10 m; 1 for no return
    ``sonar_ring``           (16,)   each sonar's range d / (d + 1 m); 1 for no echo
    ``time_fraction``        (1,)    elapsed time / episode length
    =======================  ======  =========================================================

    **Reward** (:mod:`spl_env.tasks.circle_mapping`): ``map_improvement``, the change of the
    map's quality against the true circles (1 per circle mapped exactly, less with its error,
    0 beyond 0.25 m; -0.5 per spurious circle), and ``collision``, -0.1 per blocked step.

    **Episode**: truncated after ``episode_s`` (office 60 s, backyard 180 s, as seed 001).

    **info**: ``perception``: ``pose`` (3,), ``pose_cov`` (3, 3), ``odometry_pose`` (3,)
    (dead reckoning), the circle map ``circles`` (64, 3), ``circle_covs`` (64, 3, 3),
    ``circle_ids`` (64,), ``circles_mapped`` (64,); ``ground_truth``: ``robot_pose`` (3,),
    ``circles`` (K, 3) the objects' true circles, ``blocked``; ``reward_terms``.
    ``info_level="light"`` keeps only ``reward_terms``.

    **Scripted baselines**: :class:`agents.drivers.WaypointDriver` (the layout's route,
    seed 001 §5.2.2, with Braitenberg avoidance) and :class:`agents.drivers.BraitenbergDriver`.
    """

    task_class: ClassVar[type[CircleMappingTask]] = CircleMappingTask
    config_class: ClassVar[type[CirclesConfig]] = CirclesConfig
    aliases = CIRCLES_ALIASES
    config: CirclesConfig
    task: CircleMappingTask

    def _build(self) -> None:
        cfg = self.config
        self.scene = RoomScene(self.world, cfg.layout)
        self.robot = DiffDriveRobot(self.world, AGENT_NAME, config=cfg.robot)
        self.area = RectangleArea(*cfg.layout.half_size_m)
        self.placement = Placement(self.area, self.scene.obstacles, cfg.robot.body_radius_m)
        self.rig = DiffDriveRig(cfg.sensors, self.robot)
        laser = self.rig.laser.model
        encoders: tuple[ObservationEncoder, ...] = (
            SelfPoseEncoder(self.area),
            CircleMapEncoder(cfg.observed_circles),
            ScanEncoder(laser.n_beams, cfg.scan_bins, laser.max_range_m),
        )
        if cfg.sensors.sonar_ring is not None:
            encoders += (SonarRingEncoder(len(cfg.robot.sonar_ring)),)
        encoders += (EpisodeClockEncoder(cfg.task.episode_s),)
        self.task = self.task_class(cfg.task, np.array(cfg.layout.start_pose), encoders)
        self.encoders = encoders
        outputs = {name for encoder in encoders for name in encoder.requires}
        outputs |= set(self.task.reward_requires())
        if cfg.info_level == "full":
            outputs |= {SELF_POSE, ODOMETRY_POSE, CIRCLE_MAP}
        self.pipeline = PerceptionPipeline(
            cfg.perception, PerceptionContext(None, (), PoleGeometry()), sorted(outputs)
        )
        self._info_layout = InfoLayout(
            landmark_ids=np.zeros(0, dtype=np.int64),
            max_robots=0,
            max_circles=cfg.perception.circle_mapper.max_circles,
        )
        self._view = RoomView(cfg.layout, self.scene.wall_segments())
        self._blocked = False
        self._wheel_rotations = np.zeros(2)  # the wheels' turn in the last step (rad)

    def _start_episode(self, rng: np.random.Generator) -> FloatArray:
        self._blocked = False
        self._wheel_rotations = np.zeros(2)
        start = self.task.start_pose(rng)
        prior = start + rng.normal(0.0, self.config.perception.circle_slam.initial_pose_std)
        prior[2] = math.remainder(prior[2], 2 * math.pi)
        self.robot.place(start)
        self.rig.reset(rng)
        return prior

    def _act(self, action: FloatArray, state: RoomState) -> None:
        """Drive the wheels for a control step; the body stops where it would collide."""
        dt = self.config.control_dt_s
        speeds = wheel_speeds_from_action(action, self.config.robot)
        _, self._blocked = self.placement.walk(self.robot, speeds, dt, [])
        self._wheel_rotations = self.robot.wheel_rotations(dt)

    def _world_state(self) -> RoomState:
        return RoomState(
            time_s=self._time_s,
            robot_pose=self.robot.pose.copy(),
            blocked=self._blocked,
            circles=self.scene.obstacles,
            object_names=tuple(obj.name for obj in self.config.layout.objects),
        )

    def _sense_frame(self) -> tuple[SensorFrame, dict[str, float]]:
        state = self._state
        assert state is not None  # set by reset() and step() before sensing
        truth = state.truth_for_agent() if "truth" in self.pipeline.frame_inputs else None
        return self.rig.sense(
            self.world, self._time_s, self._wheel_rotations, self.np_random, truth=truth
        )

    def _ground_truth_info(self, state: RoomState) -> dict[str, Any]:
        return {
            "robot_pose": state.robot_pose.copy(),
            "circles": state.circles.copy(),
            "blocked": np.array(state.blocked),
        }

    def _picture(self) -> NDArray[np.uint8]:
        state, frame, output = self._current()
        laser = self.rig.laser.model
        assert frame.laser is not None  # the rig always scans
        hit = np.isfinite(frame.laser)
        angles = laser.beam_angles()[hit]
        local = frame.laser[hit, None] * np.column_stack([np.cos(angles), np.sin(angles)])
        local[:, 0] += laser.mount_x_m
        return self._view.draw(state, output, transform_points(state.robot_pose, local))


class OfficeEnv(CirclesEnv):
    """``Circles/Office-v0``: the office of :mod:`spl_env.scenes.office`, 60 s
    (:class:`CirclesEnv` for the whole documentation)."""


class BackyardEnv(CirclesEnv):
    """``Circles/Backyard-v0``: the backyard of :mod:`spl_env.scenes.backyard` (five trunks with
    a flat side), 180 s (:class:`CirclesEnv` for the whole documentation)."""

    config_class = BackyardConfig
