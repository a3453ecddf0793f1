"""The one step loop of every env, and the SPL world on it (panda-gym's robot/task/env split).

:class:`RobotEnv` is the loop: each control step it checks the action, lets the world act on it,
advances the physics, senses, runs the perception pipeline, encodes the observation and scores
the step::

    action ─► _act (the task's command for every body) ─► physics ─► _world_state (truth)
    _sense_frame ─► SensorFrame ─► pipeline.step ─► PerceptionOutput ─► encoders ─► observation
    task.reward_terms(truth, PerceptionOutput) ─► reward, info

A world kind fills in its hooks once: :class:`SplEnv` (Naos on an SPL field, the scene of
:mod:`spl_env.scenes.spl_field`, the Nao rig) here, :class:`spl_env.envs.circles.CirclesEnv`
(a differential-drive robot in a room of circular objects). A new env is a task
(:mod:`spl_env.tasks`) plus a subclass naming it and its config, and a registration; it adds no
step loop of its own.
"""

from __future__ import annotations

import dataclasses
import time
from abc import abstractmethod
from collections.abc import Iterable, Mapping
from typing import Any, ClassVar, Generic, Protocol, TypeVar

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from perception.geometry import FloatArray, wrap_angle
from perception.pipeline import FIELD_FEATURE_POSES, PerceptionPipeline
from perception.providers.base import PerceptionContext
from perception.representations import (
    CIRCLE_MAP,
    FIELD_FEATURES,
    POLE_SIGHTINGS,
    PerceptionOutput,
)
from perception.types import SensorFrame
from spl_env.config import SPL_ALIASES, CoreConfig, EnvConfig
from spl_env.envs.actions import checked_action
from spl_env.envs.info import (
    FULL_INFO_REQUIRES,
    InfoLayout,
    ground_truth_info,
    perception_info,
)
from spl_env.observations.base import (
    EncoderInput,
    ObservationEncoder,
    compose_space,
    encode_all,
    frame_reads,
)
from spl_env.observations.circles import CircleMapEncoder
from spl_env.observations.field_features import FieldFeatureEncoder
from spl_env.observations.robots import RobotTracksEncoder
from spl_env.overrides import apply_overrides
from spl_env.rendering import TopDownView, draw_detections, side_by_side
from spl_env.robots.nao import NaoCommand, NaoRobot, kick_intent
from spl_env.scenes.spl_field import SplFieldScene
from spl_env.sensors.emulation.registry import (
    EMULATORS,
    emulated_representations,
    emulators_for,
)
from spl_env.sensors.rig import LASER_FIELDS, SONAR_FIELDS, NaoRig
from spl_env.sim.placement import Placement
from spl_env.sim.world import BulletWorld
from spl_env.tasks.base import Task, TaskContext
from spl_env.world_state import WorldState

StateT = TypeVar("StateT")

AGENT = 0  # index of our robot among the world's robots


class EnvTask(Protocol):
    """What the loop asks of a task (:class:`spl_env.tasks.base.Task` for the SPL envs)."""

    @property
    def action_space(self) -> spaces.Box:
        """The action space, a ``Box``."""
        ...

    def encoders(self) -> tuple[ObservationEncoder, ...]:
        """The observation's encoders, in key order."""
        ...

    def reward_requires(self) -> tuple[str, ...]:
        """Representations the reward reads beyond the encoders'."""
        ...

    def reward_terms(self, state: Any, output: PerceptionOutput) -> dict[str, float]:
        """Each reward term of this step (the reward is their sum)."""
        ...

    def terminated(self, state: Any, output: PerceptionOutput) -> bool:
        """Whether the episode ended in a terminal state."""
        ...


class RobotEnv(gym.Env[dict[str, Any], np.ndarray], Generic[StateT]):
    """The step loop; a world kind sets the hooks (``_build`` ... ``_picture``), an env sets
    :attr:`task_class`, :attr:`config_class` and :attr:`aliases` and carries the documentation.

    Keyword arguments override config fields by dotted path, top-level name or alias
    (:func:`spl_env.overrides.apply_overrides`). ``StateT`` is the world's ground-truth type
    (:class:`spl_env.world_state.WorldState` on the SPL field).
    """

    metadata: dict[str, Any] = {"render_modes": ["rgb_array"], "render_fps": 10}  # noqa: RUF012
    task_class: ClassVar[type[Any]]
    config_class: ClassVar[type[CoreConfig]]
    aliases: ClassVar[Mapping[str, str]] = {}

    # set by _build
    task: EnvTask
    encoders: tuple[ObservationEncoder, ...]
    pipeline: PerceptionPipeline
    _info_layout: InfoLayout

    def __init__(
        self, config: CoreConfig | None = None, render_mode: str | None = None, **overrides: Any
    ) -> None:
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(
                f"render_mode must be one of {self.metadata['render_modes']} or None, "
                f"got {render_mode!r}"
            )
        if config is not None and not isinstance(config, self.config_class):
            raise TypeError(
                f"config must be a {self.config_class.__name__}, got {type(config).__name__}"
            )
        self.config: Any = apply_overrides(config or self.config_class(), overrides, self.aliases)
        self.render_mode = render_mode
        self.metadata = {**self.metadata, "render_fps": round(1.0 / self.config.control_dt_s)}
        self.world = BulletWorld(time_step_s=self.config.physics_dt_s)
        try:
            self._build()
        except BaseException:  # refused: no env to close() comes back, so free the world here
            self.world.close()
            raise
        self.observation_space = compose_space(self.encoders)
        box = self.task.action_space
        self.action_space = box
        self._action_bounds = (box.low.astype(np.float64), box.high.astype(np.float64))
        self._initial_state = self.world.save_state()
        self._state: StateT | None = None
        self._frame: SensorFrame | None = None
        self._output: PerceptionOutput | None = None
        self._time_s = 0.0
        self._steps = 0
        self._closed = False
        self.step_times: dict[str, float] = {}  # wall-clock seconds of the last step's parts

    # ----- the world kind's hooks ---------------------------------------------------------
    @abstractmethod
    def _build(self) -> None:
        """Build the world's bodies, the task, :attr:`encoders`, :attr:`pipeline` and the
        ``info`` layout (once per env)."""

    @abstractmethod
    def _start_episode(self, rng: np.random.Generator) -> FloatArray:
        """Place every body, reset the sensors; return perception's believed start pose (3,)."""

    @abstractmethod
    def _act(self, action: FloatArray, state: StateT) -> None:
        """Apply this step's commands (ours from the checked ``action``) before the physics."""

    @abstractmethod
    def _world_state(self) -> StateT:
        """The ground truth now."""

    @abstractmethod
    def _sense_frame(self) -> tuple[SensorFrame, dict[str, float]]:
        """Our robot's sensor frame of this step and the seconds its parts took."""

    @abstractmethod
    def _ground_truth_info(self, state: StateT) -> dict[str, Any]:
        """``info["ground_truth"]`` (fixed shapes)."""

    @abstractmethod
    def _picture(self) -> NDArray[np.uint8]:
        """The ``rgb_array`` frame of :meth:`render`."""

    # ----- gymnasium API ------------------------------------------------------------------
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        super().reset(seed=seed)
        rng = self.np_random
        self.world.restore_state(self._initial_state)
        self._time_s, self._steps = 0.0, 0
        prior = self._start_episode(rng)
        self.pipeline.reset(prior, rng)
        self._state = self._world_state()
        times = self._sense(physics_s=0.0)
        return self._observation(), self._info(
            self.task.reward_terms(*self._truth_and_belief()), times
        )

    def step(
        self, action: np.ndarray
    ) -> tuple[dict[str, np.ndarray], float, bool, bool, dict[str, Any]]:
        if self._state is None:
            raise RuntimeError("call reset() before step()")
        a = self._checked_action(action)
        t0 = time.perf_counter()
        self._act(a, self._state)
        self.world.step(self.config.substeps)
        self._time_s += self.config.control_dt_s
        self._state = self._world_state()
        times = self._sense(physics_s=time.perf_counter() - t0)
        self._steps += 1
        terms = self.task.reward_terms(*self._truth_and_belief())
        terminated = self.task.terminated(*self._truth_and_belief())
        truncated = self._steps >= self.config.max_steps
        return (
            self._observation(),
            float(sum(terms.values())),
            terminated,
            truncated,
            self._info(terms, times),
        )

    def render(self) -> NDArray[np.uint8] | None:
        """``rgb_array``: (H, W, 3) uint8, the world kind's picture of this step."""
        if self.render_mode is None:
            gym.logger.warn("render() called with render_mode=None; pass render_mode='rgb_array'")
            return None
        return self._picture()

    def close(self) -> None:
        if not self._closed:
            self.world.close()
            self._closed = True

    # ----- inspection ---------------------------------------------------------------------
    @property
    def sensor_frame(self) -> SensorFrame:
        """What our robot's sensors delivered in the last step (for testing perception): the
        sonar only where perception or the observation reads it."""
        return self._current()[1]

    @property
    def perception_output(self) -> PerceptionOutput:
        """What perception believed after the last step."""
        return self._current()[2]

    @property
    def world_state(self) -> StateT:
        """The ground truth after the last step."""
        return self._current()[0]

    # ----- the loop's pieces --------------------------------------------------------------
    def _checked_action(self, action: np.ndarray) -> FloatArray:
        """``action`` as float64 within the action space (:func:`checked_action`)."""
        return checked_action(action, *self._action_bounds)

    def _sense(self, physics_s: float) -> dict[str, float]:
        """Our robot's frame and perception of it; returns the step's timings (s)."""
        self._frame, sensed = self._sense_frame()
        t0 = time.perf_counter()
        self._output = self.pipeline.step(self._frame)
        self.step_times = {"physics": physics_s, **sensed, "perception": time.perf_counter() - t0}
        return self.step_times

    def _current(self) -> tuple[StateT, SensorFrame, PerceptionOutput]:
        """This step's truth, sensor frame and perception output."""
        if self._state is None or self._frame is None or self._output is None:
            raise RuntimeError("call reset() first")
        return self._state, self._frame, self._output

    def _truth_and_belief(self) -> tuple[StateT, PerceptionOutput]:
        state, _, output = self._current()
        return state, output

    def _observation(self) -> dict[str, np.ndarray]:
        _, frame, output = self._current()
        return encode_all(self.encoders, EncoderInput(output=output, frame=frame))

    def _info(self, terms: dict[str, float], times: Mapping[str, float]) -> dict[str, Any]:
        state, _, output = self._current()
        info: dict[str, Any] = {"reward_terms": terms}
        if self.config.info_level == "full":
            info["perception"] = perception_info(output, self._info_layout)
            info["ground_truth"] = self._ground_truth_info(state)
        if self.config.info_timing:
            info["timing"] = dict(times)
        return info


def perception_outputs(config: EnvConfig, requires: set[str]) -> set[str]:
    """The representations an SPL env's pipeline computes: what its observation and reward
    read (``requires``), plus at ``info_level="full"`` what the full ``info`` shows."""
    outputs = set(requires)
    if config.info_level == "full":
        outputs |= set(FULL_INFO_REQUIRES)
        if not config.scene.poles_enabled:
            outputs.discard(POLE_SIGHTINGS)
        if config.sensors.laser is not None:
            outputs.add(CIRCLE_MAP)
        if config.perception.self_pose in FIELD_FEATURE_POSES:
            outputs.add(FIELD_FEATURES)
    return outputs


def perception_context(config: EnvConfig, scene: SplFieldScene) -> PerceptionContext:
    """What an SPL robot's providers are built from (one per env: it loads the CNN once)."""
    return PerceptionContext(
        config.sensors.camera.model, scene.codes, config.scene.poles.geometry, scene.dimensions
    )


def check_buildable(
    config: EnvConfig, pipeline: PerceptionPipeline, encoders: Iterable[ObservationEncoder]
) -> None:
    """ValueError, before an episode, for a robot whose ``pipeline`` and observation
    ``encoders`` cannot run as ``config`` says: an image reader in the geometric camera mode, a
    reader of a switched-off sensor, more robot-track rows than the tracker keeps."""
    _check_camera_mode(config, pipeline)
    _check_sensors(config, pipeline)
    _check_track_rows(config, encoders)


def _check_camera_mode(config: EnvConfig, pipeline: PerceptionPipeline) -> None:
    """ValueError when the geometric camera mode (no images) meets a provider that reads
    images and has no emulator."""
    if config.sensors.camera_mode == "rendered" or "image" not in pipeline.frame_inputs:
        return
    readers = [
        name for name in pipeline.representations if "image" in pipeline.provider(name).requires
    ]
    emulated = ", ".join(f"{r}={p!r}" for r, p in EMULATORS)
    hint = "pass frontend='colour' with it, " if POLE_SIGHTINGS in readers else ""
    raise ValueError(
        "camera_mode='geometric' renders no image, but the providers of "
        f"{readers} read images and have no emulator; {hint}choose providers the geometric "
        f"mode emulates ({emulated}) or camera_mode='rendered'"
    )


def _check_sensors(config: EnvConfig, pipeline: PerceptionPipeline) -> None:
    """ValueError when a provider reads a sensor (the laser, the sonar) that the rig's
    configuration switches off."""
    for sensor, fields in (("laser", LASER_FIELDS), ("sonar", SONAR_FIELDS)):
        if getattr(config.sensors, sensor) is not None or not pipeline.frame_inputs & fields:
            continue
        readers = [
            name
            for name in pipeline.representations
            if fields & set(pipeline.provider(name).requires)
        ]
        raise ValueError(
            f"the providers of {readers} read the {sensor}, but {sensor}=None: pass "
            f"{sensor}={{}} (the default {sensor}) or choose providers that do not read it"
        )


def _check_track_rows(config: EnvConfig, encoders: Iterable[ObservationEncoder]) -> None:
    """ValueError when an observation asks for more robot-track rows than the tracker ever
    keeps tracks (the rows past them would always be empty)."""
    tracks = config.perception.robot_tracker.max_tracks
    for encoder in encoders:
        if isinstance(encoder, RobotTracksEncoder) and encoder.max_robots > tracks:
            raise ValueError(
                f"task.max_tracked_robots must be <= perception.robot_tracker.max_tracks "
                f"({tracks}; rows past it are always empty), got {encoder.max_robots}"
            )


def field_world_state(
    time_s: float,
    scene: SplFieldScene,
    robots: list[NaoRobot],
    names: tuple[str, ...],
    teams: NDArray[np.int64],
    blocked: NDArray[np.bool_],
    agent: int,
) -> WorldState:
    """The ground truth now on the SPL field ``scene`` with ``robots`` (named ``names``, of
    ``teams``, ``blocked`` this step), robot ``agent`` the one a policy drives."""
    ball, ball_velocity = scene.ball_state()
    return WorldState(
        time_s=time_s,
        names=names,
        kinds=tuple("nao" for _ in robots),
        teams=teams,
        poses=np.array([r.pose for r in robots]),
        heads=np.array([r.head for r in robots]),
        blocked=blocked.copy(),
        agent=agent,
        ball=ball,
        ball_velocity=ball_velocity,
        landmarks=scene.landmarks,
        landmark_ids=scene.landmark_ids,
        circles=scene.obstacles,
    )


def info_layout(config: EnvConfig, scene: SplFieldScene) -> InfoLayout:
    """The fixed sizes of an SPL env's ``info``."""
    return InfoLayout(
        landmark_ids=scene.landmark_ids,
        max_robots=config.perception.robot_tracker.max_tracks,
        max_circles=config.perception.circle_mapper.max_circles,
    )


class SplEnv(RobotEnv[WorldState]):
    """Naos on an SPL field: the env core's SPL world; subclasses set :attr:`task_class`,
    :attr:`config_class` and :attr:`aliases` and carry the env's documentation."""

    task_class: ClassVar[type[Task]]
    config_class: ClassVar[type[EnvConfig]]
    aliases: ClassVar[Mapping[str, str]] = SPL_ALIASES
    config: EnvConfig
    task: Task

    def _build(self) -> None:
        cfg = self.config
        self.scene = SplFieldScene(self.world, cfg.scene)
        self.robots = [NaoRobot(self.world, "self", team=0, config=cfg.robot)] + [
            NaoRobot(self.world, f"robot_{i}", team=team, config=cfg.robot)
            for i, team in enumerate(cfg.task.other_robot_teams)
        ]
        self.placement = Placement(
            self.scene.dimensions, self.scene.obstacles, cfg.robot.body_radius_m
        )
        self.task = self.task_class(
            cfg.task,
            TaskContext(
                dimensions=self.scene.dimensions,
                robot=cfg.robot,
                control_dt_s=cfg.control_dt_s,
                n_landmarks=len(self.scene.codes),
                placement=self.placement,
            ),
        )
        self.encoders = self.task.encoders()
        if cfg.sensors.laser is not None:  # the laser maps circles
            self.encoders += (CircleMapEncoder(cfg.observed_circles),)
        if cfg.perception.self_pose in FIELD_FEATURE_POSES:
            self.encoders += (FieldFeatureEncoder(),)
        requires = {name for encoder in self.encoders for name in encoder.requires}
        outputs = perception_outputs(cfg, requires | set(self.task.reward_requires()))
        self.perception_context = perception_context(cfg, self.scene)
        self.pipeline = PerceptionPipeline(
            cfg.perception,
            self.perception_context,
            sorted(outputs),
            emulated=emulated_representations(cfg.sensors, cfg.perception),
        )
        check_buildable(cfg, self.pipeline, self.encoders)
        rendered = cfg.sensors.camera_mode == "rendered"
        self._render_image = rendered and "image" in self.pipeline.frame_inputs
        # the bottom camera is rendered only for a provider that reads it
        self._render_bottom = rendered and "bottom_image" in self.pipeline.frame_inputs
        # the rig measures no sonar that neither perception nor an encoder reads (the
        # geometric mode emulates the robot sightings' sonar check from the sonar's model)
        read = self.pipeline.frame_inputs | frame_reads(self.encoders)
        sensors = (
            cfg.sensors if read & SONAR_FIELDS else dataclasses.replace(cfg.sensors, sonar=None)
        )
        emulators = emulators_for(
            self.pipeline.emulated, self.scene, self.robots, cfg.sensors, cfg.perception
        )
        self.rig = NaoRig(sensors, self.robots[AGENT], emulators)
        self._info_layout = info_layout(cfg, self.scene)
        self._top_down = TopDownView(self.scene.dimensions)
        self._blocked = np.zeros(len(self.robots), dtype=bool)
        self._names = tuple(r.name for r in self.robots)
        self._teams = np.array([r.team for r in self.robots], dtype=np.int64)
        self._engine_delta = np.zeros(3)  # our walk engine's increment in the last step
        self._kick_velocity = np.zeros(2)  # the ball velocity our kick meant to give (robot)
        self.camera_yaw_rate_rps = 0.0  # our camera's turn rate in the last step (rad/s)

    def _start_episode(self, rng: np.random.Generator) -> FloatArray:
        self._blocked[:] = False
        self._engine_delta = np.zeros(3)
        self._kick_velocity = np.zeros(2)
        self.camera_yaw_rate_rps = 0.0
        start = self.task.start_pose(rng)
        # the filter's start belief: the true start off by a draw from its own prior
        prior = start + rng.normal(0.0, self.config.perception.slam.initial_pose_std)
        ours, others = self.robots[AGENT], self.robots[AGENT + 1 :]
        ours.place(start)
        ball = self.task.place_scripted(rng, others, [ours])
        self.scene.place_ball(ball)
        self.rig.reset(rng)
        if self.scene.spectators.names:  # drawn last: without spectators no draw moves
            self.scene.spectators.reset(rng)
        return prior

    def _act(self, action: FloatArray, state: WorldState) -> None:
        """Every robot's command in order (head, walk with collisions, kick); keeps our walk
        engine's increment and our camera's turn rate for the sensors."""
        commands = [self.task.command(action, state), *self.task.scripted_commands(state)]
        ours = self.robots[AGENT]
        yaw_before = ours.pose[2] + ours.head[0]
        self._engine_delta = self._move(commands)
        self.scene.spectators.move(self.config.control_dt_s)
        yaw_rate = float(wrap_angle(ours.pose[2] + ours.head[0] - yaw_before))
        self.camera_yaw_rate_rps = yaw_rate / self.config.control_dt_s

    def _move(self, commands: list[NaoCommand]) -> FloatArray:
        """Apply each robot's command in order (head, walk with collisions, kick); returns our
        walk engine's increment (3,)."""
        dt = self.config.control_dt_s
        engine_delta = np.zeros(3)
        self._kick_velocity = np.zeros(2)
        for k, (robot, command) in enumerate(zip(self.robots, commands, strict=True)):
            if command.head is not None:
                robot.move_head(command.head, dt)
            others = [r for r in self.robots if r is not robot]
            increment, self._blocked[k] = self.placement.walk(robot, command.walk, dt, others)
            if k == AGENT:
                engine_delta = increment
            if command.kick and k == AGENT:  # our motion knows the kick it made
                self._kick_velocity = kick_intent(
                    robot.config, command.kick_angle_rad, command.kick_strength
                )
            if command.kick:
                ball, _ = self.scene.ball_state()
                velocity = robot.kick_velocity(
                    ball, self.np_random, command.kick_angle_rad, command.kick_strength
                )
                if velocity is not None:
                    self.scene.place_ball(ball, velocity)
        return engine_delta

    def _sense(self, physics_s: float) -> dict[str, float]:
        times = super()._sense(physics_s)
        self.task.perceived(self.perception_output)
        return times

    def _sense_frame(self) -> tuple[SensorFrame, dict[str, float]]:
        state = self._state
        assert state is not None  # set by reset() and step() before sensing
        truth = state.truth_for(AGENT) if "truth" in self.pipeline.frame_inputs else None
        return self.rig.sense(
            self.world,
            self._time_s,
            self._engine_delta,
            self.camera_yaw_rate_rps,
            self.np_random,
            render=self._render_image,
            render_bottom=self._render_bottom,
            truth=truth,
            kick_velocity=self._kick_velocity,
        )

    def _world_state(self) -> WorldState:
        return field_world_state(
            self._time_s, self.scene, self.robots, self._names, self._teams, self._blocked, AGENT
        )

    def _ground_truth_info(self, state: WorldState) -> dict[str, Any]:
        return ground_truth_info(state)

    def _picture(self) -> NDArray[np.uint8]:
        """The top-down field beside the camera image with its pole detections."""
        state, frame, output = self._current()
        top = self._top_down.draw(state, output, self.scene.codes)
        image = frame.image if frame.image is not None else self.rig.camera_view(self.world)[0]
        sightings = output.get(POLE_SIGHTINGS, ())
        return side_by_side(top, draw_detections(image, sightings))
