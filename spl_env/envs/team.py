"""``spl_env.team_v0``: N against N Naos (PettingZoo ``ParallelEnv``), every one perceiving.

One world (the SPL field of :mod:`spl_env.scenes.spl_field`, a :class:`NaoRobot` per player,
:class:`Placement` for walking and collisions) and one step loop for all players; each player
has its own sensors (:class:`spl_env.sensors.rig.NaoRig`: camera or the geometric mode's
emulators, walk odometry, and the sonar where its pipeline reads it) and its own
:class:`perception.pipeline.PerceptionPipeline` (pose SLAM, robot tracker, ball filter). The
pieces are the single-agent soccer envs' (:mod:`spl_env.envs.soccer`): the action table and
the scripted head of :func:`spl_env.tasks.soccer.soccer_command`, the observation encoders of
:meth:`spl_env.tasks.soccer.SoccerTask.encoders`, the goal and out rules of
:mod:`spl_env.tasks.soccer` and the ``info`` of :mod:`spl_env.envs.info`.

Step, as data (every list in agent order)::

    actions ─► soccer_command per player (its head scripted on its own last belief)
            ─► heads and walks in agent order (collisions), kicks in a random order
            ─► physics ─► WorldState ─► per player: rig.sense ─► pipeline.step ─► encoders
            ─► team 1's observation mirrored ─► rewards per team, termination for all

Random draws: ``reset(seed)`` seeds the env's generator; each episode spawns from it one
generator for the placement and the kicks, and one per player for its sensors and perception
(:meth:`PerceptionPipeline.reset` spawns the providers' from that), so no player's draws
depend on what another saw or did.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import cv2
import gymnasium as gym
import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray
from pettingzoo import ParallelEnv

from perception.geometry import FloatArray, wrap_angle
from perception.pipeline import FIELD_FEATURE_POSES, PerceptionPipeline
from perception.representations import (
    BALL,
    SELF_POSE,
    PerceptionOutput,
)
from perception.types import SensorFrame, SlamEstimate
from perception.validation import check_int, check_positive
from spl_env.envs.actions import checked_action
from spl_env.envs.core import (
    check_buildable,
    field_world_state,
    info_layout,
    perception_context,
    perception_outputs,
)
from spl_env.envs.info import (
    ground_truth_info,
    perception_info,
)
from spl_env.envs.soccer import SOCCER_ALIASES, SoccerConfig
from spl_env.field import FieldDimensions
from spl_env.observations.ball import BallEncoder
from spl_env.observations.base import (
    EncoderInput,
    ObservationEncoder,
    compose_space,
    encode_all,
    frame_reads,
)
from spl_env.observations.body import EpisodeClockEncoder, HeadEncoder
from spl_env.observations.field_features import FieldFeatureEncoder
from spl_env.observations.robots import RobotTracksEncoder
from spl_env.observations.self_pose import SelfPoseEncoder
from spl_env.overrides import apply_overrides
from spl_env.rendering import SLAM_BGR, TEAM_BGR, TopDownView, draw_ellipse, draw_robot
from spl_env.robots.nao import NaoCommand, NaoRobot, kick_intent
from spl_env.scenes.spl_field import SplFieldScene
from spl_env.sensors.emulation.registry import emulated_representations, emulators_for
from spl_env.sensors.rig import SONAR_FIELDS, NaoRig
from spl_env.sim.placement import Placement
from spl_env.sim.world import BulletWorld
from spl_env.tasks.soccer import (
    SoccerTaskConfig,
    ball_in_goal,
    ball_out,
    goal_centre,
    soccer_command,
)
from spl_env.world_state import WorldState

TEAMS = ("blue", "red")  # team 0 attacks +x, team 1 attacks -x
MAX_PLAYERS_PER_SIDE = 5
START_MARGIN_M = 0.5  # players start this far inside the field lines and the centre line

# the soccer envs' names, a team's size instead of the scripted opponents
TEAM_ALIASES: dict[str, str] = {
    **{k: v for k, v in SOCCER_ALIASES.items() if k != "n_other_robots"},
    "players_per_side": "task.players_per_side",
}


@dataclass(frozen=True, kw_only=True)
class TeamTaskConfig(SoccerTaskConfig):
    """The team game: ``players_per_side`` (1-5) a side, the reward weights, the kick-off.

    The head and observation fields are :class:`SoccerTaskConfig`'s (every player's head is
    scripted the same way); ``n_other_robots`` is derived (the ``2 N - 1`` robots any player
    shares the field with) and ``other_walker`` is unused (no scripted robots).
    """

    players_per_side: int = 2
    n_other_robots: int = field(default=3, init=False)  # 2 * players_per_side - 1
    progress_weight: float = 1.0  # reward per metre the ball comes nearer the opponent goal
    time_cost: float = 0.01  # reward -time_cost per step
    out_penalty: float = 1.0  # reward -out_penalty to the last kicker's team: ball out
    ball_spread_m: float = 0.3  # the ball starts within ± this of the centre mark, x and y (m)

    def __post_init__(self) -> None:
        owner = type(self).__name__
        check_int(owner, "players_per_side", self.players_per_side, 1)
        if self.players_per_side > MAX_PLAYERS_PER_SIDE:
            raise ValueError(
                f"{owner}.players_per_side must be an int in [1, {MAX_PLAYERS_PER_SIDE}], "
                f"got {self.players_per_side}"
            )
        object.__setattr__(self, "n_other_robots", 2 * self.players_per_side - 1)
        super().__post_init__()
        for name in ("progress_weight", "time_cost", "out_penalty"):
            check_positive(owner, name, getattr(self, name), allow_zero=True)
        check_positive(
            owner,
            "ball_spread_m",
            self.ball_spread_m,
            allow_zero=True,
            upper=1.0,
            upper_inclusive=True,
        )


@dataclass(frozen=True, kw_only=True)
class TeamConfig(SoccerConfig):
    """:class:`spl_env.envs.soccer.SoccerConfig` (both cameras see the ball) with the team
    game; every player has ``sensors`` and ``perception``. No laser (a Nao has none)."""

    task: TeamTaskConfig = field(default_factory=TeamTaskConfig)

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.sensors.laser is not None:
            raise ValueError("TeamConfig.sensors.laser must be None: the team's Naos have none")


def mirror_observation(obs: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """``obs`` as seen by a player attacking +x of a field turned by π about its centre:
    ``(x, y, θ) -> (-x, -y, θ + π)``. Only ``self_pose_field`` (x, y, cos θ, sin θ) is in the
    field frame, so it alone changes (every entry negated); the std of x, y and θ is unchanged
    and every other key is relative to the robot. Returns a new dict (the arrays it keeps are
    shared)."""
    return {**obs, "self_pose_field": -obs["self_pose_field"]}


class Player:
    """One robot with its own sensors (``rig``), perception (``pipeline``) and encoders: the
    per-step state the loop keeps for it (the last frame and belief, the walk engine's
    increment, the kick it meant, the camera's turn rate) and its episode generator."""

    def __init__(
        self,
        name: str,
        robot: NaoRobot,
        rig: NaoRig,
        pipeline: PerceptionPipeline,
        encoders: tuple[ObservationEncoder, ...],
    ) -> None:
        self.name = name
        self.robot = robot
        self.team = robot.team
        self.rig = rig
        self.pipeline = pipeline
        self.encoders = encoders
        self.observation_space = compose_space(encoders)
        self.truth_input = "truth" in pipeline.frame_inputs  # an oracle provider reads truth
        self.rng = np.random.default_rng(0)  # replaced at every reset
        self.frame: SensorFrame | None = None
        self.output: PerceptionOutput | None = None
        self.engine_delta = np.zeros(3)  # the walk engine's increment of the last step
        self.kick_velocity = np.zeros(2)  # the ball velocity its kick meant (robot frame)
        self.yaw_rate_rps = 0.0  # its camera's turn rate in the last step (rad/s)

    def reset(self, rng: np.random.Generator) -> None:
        """Forget the last episode; draw from ``rng`` from now on."""
        self.rng = rng
        self.frame = self.output = None
        self.engine_delta = np.zeros(3)
        self.kick_velocity = np.zeros(2)
        self.yaw_rate_rps = 0.0

    def observation(self) -> dict[str, np.ndarray]:
        """The encoded belief, mirrored for team 1 (:func:`mirror_observation`)."""
        if self.frame is None or self.output is None:
            raise RuntimeError("call reset() first")
        obs = encode_all(self.encoders, EncoderInput(output=self.output, frame=self.frame))
        return mirror_observation(obs) if self.team == 1 else obs


class TeamEnv(ParallelEnv[str, dict[str, np.ndarray], np.ndarray]):
    """N against N Naos on the SPL field, every one perceiving (PettingZoo ``ParallelEnv``).

    ``from spl_env import team_v0; env = team_v0.parallel_env(camera_mode="geometric",
    frontend="colour")``. Keyword arguments override :class:`TeamConfig` fields by dotted path,
    top-level name or alias (:data:`TEAM_ALIASES`: those of the soccer envs, and
    ``players_per_side``); ``config`` passes a whole one.

    **Agents**: ``blue_0`` ... ``blue_{N-1}`` (team 0, attacks the goal at +x) and ``red_0`` ...
    (team 1, attacks -x); N = ``players_per_side`` (1-5, default 2). Kick-off: each player
    starts in its own half (at least 0.5 m inside the lines, facing within ±90° of the
    opponent goal), clear of the others; the ball within ±``ball_spread_m`` of the centre mark.

    **Action** (per agent): ``Box(-1, 1, (5,), float32)`` (``(7,)`` with
    ``head_control="action"``), the soccer envs' table (:mod:`spl_env.tasks.soccer`): walk
    ``(vx, vy, omega)``, kick strength, kick direction; in the agent's own robot frame, so the
    mirroring needs no change to it. Without the head in the action each head is scripted on
    that player's own believed ball. Heads and walks apply in agent order (a walk is blocked by
    the robots already moved); the kicks then in a random order, the first whose ball lies in
    its kick zone taking it. A NaN (or out-of-range, or missing) action is a ValueError naming
    the agent.

    **Observation** (per agent): the keys, spaces and meaning of ``SPL/Striker-v0``'s
    (:mod:`spl_env.envs.soccer`): ``self_pose_field``, ``self_pose_std``, ``head_angles``, the
    ``ball_*`` keys, the ``robots_*`` keys (``robots_team`` +1 for a teammate, -1 for an
    opponent) and ``time_fraction``; plus ``field_features_since_seen`` with a self pose that
    reads the field features (``"field_features"``, ``"ekf_slam_field_features"``). Each is
    that player's own perception. **Mirroring**: a red player's observation reads as if it
    attacked +x, the field turned by π about its centre, ``(x, y, θ) -> (-x, -y, θ + π)``:
    ``self_pose_field`` ``(x, y, cos θ, sin θ)`` is negated (:func:`mirror_observation`); every
    other key is robot-relative and unchanged. One policy can then play both sides.

    **Reward** (per agent, its team's): ``goal`` +10 when the team scores, -10 when it concedes;
    ``progress`` the metres the ball came nearer the opponent goal's centre this step; ``time``
    -0.01 per step; ``out`` -1 to the team that kicked the ball last when it leaves the field
    other than through a goal. Terminated (every agent) on a goal or the ball out; truncated
    after ``episode_s`` (60 s); ``agents`` is then empty until :meth:`reset`.

    **info** (per agent; fixed shapes, so vector-safe): ``team`` (0 or 1) and ``reward_terms``;
    at ``info_level="full"`` also ``perception`` and ``ground_truth`` as in the single-agent
    soccer envs, of that player (its believed pose, tracks and ball; its true pose and head,
    the other robots (2N - 1 rows, in agent order without it) and their teams, the ball), all in
    the world's field frame, **not** mirrored; ``timing`` with ``info_timing``, the step's
    seconds (physics; render, sensors and perception summed over the players).
    """

    metadata: dict[str, Any] = {  # noqa: RUF012  (PettingZoo reads it from the instance)
        "name": "spl_team_v0",
        "render_modes": ["rgb_array"],
        "render_fps": 10,
        "is_parallelizable": True,
    }

    def __init__(
        self, config: TeamConfig | None = None, render_mode: str | None = None, **overrides: Any
    ) -> None:
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(
                f"render_mode must be one of {self.metadata['render_modes']} or None, "
                f"got {render_mode!r}"
            )
        if config is not None and not isinstance(config, TeamConfig):
            raise TypeError(f"config must be a TeamConfig, got {type(config).__name__}")
        self.config: TeamConfig = apply_overrides(config or TeamConfig(), overrides, TEAM_ALIASES)
        self.render_mode = render_mode
        self.metadata = {**self.metadata, "render_fps": round(1.0 / self.config.control_dt_s)}
        self.world = BulletWorld(time_step_s=self.config.physics_dt_s)
        try:
            self._build()
        except BaseException:  # refused: no env to close() comes back, so free the world here
            self.world.close()
            raise
        self._initial_state = self.world.save_state()
        self.agents: list[str] = []
        self._rng: np.random.Generator | None = None  # seeded by reset()
        self._episode_rng = np.random.default_rng(0)  # replaced at every reset
        self._state: WorldState | None = None
        self._time_s = 0.0
        self._steps = 0
        self._last_distance = np.zeros(2)  # each team's ball distance to its target goal (m)
        self._last_kicker_team = -1  # the team that kicked the ball last (-1: none yet)
        self._blocked = np.zeros(len(self.players), dtype=bool)
        self._closed = False
        self.step_times: dict[str, float] = {}  # wall-clock seconds of the last step's parts

    def _build(self) -> None:
        """The scene, one robot, rig, pipeline and encoder set per player, the spaces."""
        cfg = self.config
        n = cfg.task.players_per_side
        self.scene = SplFieldScene(self.world, cfg.scene)
        names = [f"{TEAMS[team]}_{i}" for team in (0, 1) for i in range(n)]
        robots = [
            NaoRobot(self.world, name, team=k // n, config=cfg.robot)
            for k, name in enumerate(names)
        ]
        self.placement = Placement(
            self.scene.dimensions, self.scene.obstacles, cfg.robot.body_radius_m
        )
        encoders = [self._encoders(team) for team in (0, 1)]
        requires = {name for encoder in encoders[0] for name in encoder.requires} | {BALL}
        outputs = perception_outputs(cfg, requires)
        context = perception_context(cfg, self.scene)  # shared: the CNN is loaded once
        self.players: list[Player] = []
        emulable = emulated_representations(cfg.sensors, cfg.perception)
        for name, robot in zip(names, robots, strict=True):
            pipeline = PerceptionPipeline(cfg.perception, context, sorted(outputs), emulable)
            # a rig measures no sonar that neither perception nor an encoder reads (the
            # geometric mode emulates the robot sightings' sonar check from the sonar's model)
            read = pipeline.frame_inputs | frame_reads(encoders[robot.team])
            sensors = (
                cfg.sensors if read & SONAR_FIELDS else dataclasses.replace(cfg.sensors, sonar=None)
            )
            emulators = emulators_for(
                pipeline.emulated, self.scene, robots, cfg.sensors, cfg.perception
            )
            rig = NaoRig(sensors, robot, emulators)
            self.players.append(Player(name, robot, rig, pipeline, encoders[robot.team]))
        check_buildable(cfg, self.players[0].pipeline, encoders[0])
        inputs = self.players[0].pipeline.frame_inputs
        rendered = cfg.sensors.camera_mode == "rendered"
        self._render_image = rendered and "image" in inputs
        self._render_bottom = rendered and "bottom_image" in inputs  # only where it is read
        self.robots = robots
        self.possible_agents = names
        self._by_name = {p.name: p for p in self.players}
        self._observation_spaces = {p.name: p.observation_space for p in self.players}
        self._action_spaces = {
            name: spaces.Box(-1.0, 1.0, shape=(self._action_size,), dtype=np.float32)
            for name in names
        }
        self._info_layout = info_layout(cfg, self.scene)
        self._top_down = TopDownView(self.scene.dimensions)
        self._names = tuple(names)
        self._teams = np.array([r.team for r in robots], dtype=np.int64)

    @property
    def _action_size(self) -> int:
        """5: walk, kick strength and direction; 7 with the head in the action."""
        return 7 if self.config.task.head_control == "action" else 5

    def _encoders(self, team: int) -> tuple[ObservationEncoder, ...]:
        """Team ``team``'s encoders: :meth:`spl_env.tasks.soccer.SoccerTask.encoders`' with
        ``robots_team`` relative to ``team``, and the field features' with a self pose that
        reads them (as :class:`spl_env.envs.core.SplEnv`)."""
        cfg = self.config
        encoders: tuple[ObservationEncoder, ...] = (
            SelfPoseEncoder(self.scene.dimensions),
            HeadEncoder(cfg.robot),
            BallEncoder(),
            RobotTracksEncoder(cfg.task.max_tracked_robots, our_team=team),
            EpisodeClockEncoder(cfg.task.episode_s),
        )
        if cfg.perception.self_pose in FIELD_FEATURE_POSES:
            encoders += (FieldFeatureEncoder(),)
        return encoders

    # ----- PettingZoo API -----------------------------------------------------------------
    def observation_space(self, agent: str) -> spaces.Space[Any]:
        """The agent's ``Dict`` of float32 boxes (the same object every call)."""
        return self._observation_spaces[agent]

    def action_space(self, agent: str) -> spaces.Space[Any]:
        """The agent's ``Box`` in [-1, 1] (its own object, seeded on its own)."""
        return self._action_spaces[agent]

    def reset(
        self, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, dict[str, np.ndarray]], dict[str, dict[str, Any]]]:
        """Kick-off; ``seed`` seeds the env's generator (without one it goes on drawing from
        the last seeded, or a fresh one). ``options`` are accepted and ignored."""
        if self._closed:
            raise RuntimeError("the env is closed")
        if seed is not None:
            check_int("", "seed", seed, 0)
        if seed is not None or self._rng is None:
            self._rng = np.random.default_rng(seed)
        self._episode_rng, *player_rngs = self._rng.spawn(1 + len(self.players))
        self.world.restore_state(self._initial_state)
        self._time_s, self._steps = 0.0, 0
        self._blocked[:] = False
        self._last_kicker_team = -1
        self.agents = list(self.possible_agents)
        starts = self._kick_off(self._episode_rng)
        slam_std = np.asarray(self.config.perception.slam.initial_pose_std)
        for player, start, rng in zip(self.players, starts, player_rngs, strict=True):
            player.reset(rng)
            player.rig.reset(rng)
            # the filter's start belief: the true start off by a draw from its own prior
            player.pipeline.reset(start + rng.normal(0.0, slam_std), rng)
        if self.scene.spectators.names:
            self.scene.spectators.reset(self._episode_rng)
        self._state = self._world_state()
        times = self._sense(physics_s=0.0)
        self._last_distance = self._ball_distances(self._state.ball)
        terms = self._reward_terms(self._state, goal=0, out=False)
        observations = {p.name: p.observation() for p in self.players}
        return observations, self._infos(terms, times)

    def step(
        self, actions: dict[str, np.ndarray]
    ) -> tuple[
        dict[str, dict[str, np.ndarray]],
        dict[str, float],
        dict[str, bool],
        dict[str, bool],
        dict[str, dict[str, Any]],
    ]:
        """One control step of every player (see the class doc)."""
        if self._state is None or not self.agents:
            raise RuntimeError("call reset() before step(), and again once the episode ended")
        checked = self._checked_actions(actions)
        t0 = time.perf_counter()
        self._act(checked, self._state)
        self.world.step(self.config.substeps)
        self._time_s += self.config.control_dt_s
        self._state = state = self._world_state()
        times = self._sense(physics_s=time.perf_counter() - t0)
        self._steps += 1
        dims = self.scene.dimensions
        goal = ball_in_goal(state.ball, dims)
        out = ball_out(state.ball, dims)
        terms = self._reward_terms(state, goal=goal, out=out and goal == 0)
        terminated = out  # a goal is out too
        truncated = self._steps >= self.config.max_steps
        names = self.agents
        observations = {p.name: p.observation() for p in self.players}
        rewards = {p.name: float(sum(terms[p.team].values())) for p in self.players}
        infos = self._infos(terms, times)
        if terminated or truncated:
            self.agents = []
        return (
            observations,
            rewards,
            dict.fromkeys(names, terminated),
            dict.fromkeys(names, truncated),
            infos,
        )

    def render(self) -> NDArray[np.uint8] | None:
        """``rgb_array``: (H, W, 3) uint8, the field from above: every robot's true pose in its
        team's colour, every player's believed pose (orange, with its 95 % ellipse) joined to
        its truth by a thin line, and the ball (white)."""
        if self.render_mode is None:
            gym.logger.warn("render() called with render_mode=None; pass render_mode='rgb_array'")
            return None
        if self._state is None:
            raise RuntimeError("call reset() before render()")
        view = self._top_down
        img = view.background.copy()
        for player, pose in zip(self.players, self._state.poses, strict=True):
            assert player.output is not None  # sensed in reset() and every step
            slam = player.output.get_as(SELF_POSE, SlamEstimate)
            cv2.line(img, view.px(pose[:2]), view.px(slam.pose[:2]), SLAM_BGR, 1)
            draw_ellipse(img, view.px, slam.pose[:2], slam.pose_cov[:2, :2], SLAM_BGR)
            draw_robot(img, view.px, slam.pose, SLAM_BGR)
            draw_robot(img, view.px, pose, TEAM_BGR[player.team])
        cv2.circle(img, view.px(self._state.ball), 4, (255, 255, 255), -1)
        return np.ascontiguousarray(cv2.cvtColor(img, cv2.COLOR_BGR2RGB))

    def close(self) -> None:
        if not self._closed:
            self.world.close()
            self._closed = True

    # ----- inspection ---------------------------------------------------------------------
    @property
    def world_state(self) -> WorldState:
        """The ground truth after the last step (``agent`` 0: ``blue_0``)."""
        if self._state is None:
            raise RuntimeError("call reset() first")
        return self._state

    def player(self, agent: str) -> Player:
        """The agent's player: its robot, rig, pipeline and last frame and belief."""
        return self._by_name[agent]

    # ----- the loop's pieces --------------------------------------------------------------
    def _kick_off(self, rng: np.random.Generator) -> list[FloatArray]:
        """Place every player in its own half (class doc) and the ball near the centre mark;
        returns the start poses (P, 3) in agent order."""
        dims = self.scene.dimensions
        placed: list[NaoRobot] = []
        starts = []
        for robot in self.robots:
            pose = self._start_pose(rng, robot.team, dims, placed)
            robot.place(pose)
            placed.append(robot)
            starts.append(pose)
        spread = self.config.task.ball_spread_m
        self.scene.place_ball(rng.uniform(-spread, spread, size=2))
        return starts

    def _start_pose(
        self,
        rng: np.random.Generator,
        team: int,
        dims: FieldDimensions,
        placed: list[NaoRobot],
    ) -> FloatArray:
        """A pose (3,) in ``team``'s half, facing the opponent goal within ±90°, 0.3 m clear
        of the ``placed`` robots, the posts and the poles."""
        side = 1.0 if team == 0 else -1.0  # team 0's half is x < 0
        for _ in range(200):
            x = -side * rng.uniform(START_MARGIN_M, dims.half_length_m - START_MARGIN_M)
            y = rng.uniform(-dims.half_width_m + START_MARGIN_M, dims.half_width_m - START_MARGIN_M)
            heading = rng.uniform(-math.pi / 2, math.pi / 2) + (0.0 if team == 0 else math.pi)
            if not self.placement.collides(np.array([x, y]), placed, clearance=0.3):
                return np.array([x, y, wrap_angle(heading)])
        raise RuntimeError("could not place a player: the half is too crowded")

    def _checked_actions(self, actions: dict[str, np.ndarray]) -> list[FloatArray]:
        """Every player's action as float64, in agent order (:func:`checked_action`); TypeError
        for ``actions`` that are not a dict, ValueError naming the agent for a missing or
        unknown one."""
        if not isinstance(actions, Mapping):
            raise TypeError(
                f"actions must be a dict of agent name to action, got {type(actions).__name__}"
            )
        unknown = sorted(set(actions) - set(self.agents), key=repr)  # keys of any type
        if unknown:
            raise ValueError(f"actions for agents not in the episode: {unknown}")
        high = np.ones(self._action_size)
        checked = []
        for name in self.possible_agents:
            if name not in actions:
                raise ValueError(f"no action for agent {name!r}")
            checked.append(checked_action(actions[name], -high, high, f"action of {name!r}"))
        return checked

    def _act(self, actions: list[FloatArray], state: WorldState) -> None:
        """Every player's command: heads and walks in agent order (collisions), then the kicks
        in a random order, the first to reach the ball taking it; keeps each player's walk
        increment, kick intent and camera turn rate for its sensors."""
        cfg = self.config
        dt, dims = cfg.control_dt_s, self.scene.dimensions
        commands: list[NaoCommand] = []
        for k, (player, action) in enumerate(zip(self.players, actions, strict=True)):
            command = soccer_command(action, cfg.task, cfg.robot, dims, player.output, state.time_s)
            commands.append(command)
            robot = player.robot
            yaw_before = robot.pose[2] + robot.head[0]
            if command.head is not None:
                robot.move_head(command.head, dt)
            others = [r for r in self.robots if r is not robot]
            player.engine_delta, self._blocked[k] = self.placement.walk(
                robot, command.walk, dt, others
            )
            player.yaw_rate_rps = float(wrap_angle(robot.pose[2] + robot.head[0] - yaw_before)) / dt
            player.kick_velocity = (  # its motion knows the kick it made, hit or miss
                kick_intent(cfg.robot, command.kick_angle_rad, command.kick_strength)
                if command.kick
                else np.zeros(2)
            )
        rng = self._episode_rng
        for k in rng.permutation(len(self.players)):
            command = commands[k]
            if not command.kick:
                continue
            ball, _ = self.scene.ball_state()
            robot = self.players[k].robot
            velocity = robot.kick_velocity(ball, rng, command.kick_angle_rad, command.kick_strength)
            if velocity is not None:
                self.scene.place_ball(ball, velocity)
                self._last_kicker_team = robot.team
                break
        self.scene.spectators.move(dt)

    def _sense(self, physics_s: float) -> dict[str, float]:
        """Every player's frame and perception of it; returns the step's timings (s), render,
        sensors and perception summed over the players."""
        state = self._state
        assert state is not None  # set by reset() and step() before sensing
        totals = {"physics": physics_s, "render": 0.0, "sensors": 0.0, "perception": 0.0}
        for k, player in enumerate(self.players):
            player.frame, sensed = player.rig.sense(
                self.world,
                self._time_s,
                player.engine_delta,
                player.yaw_rate_rps,
                player.rng,
                render=self._render_image,
                render_bottom=self._render_bottom,
                truth=state.truth_for(k) if player.truth_input else None,
                kick_velocity=player.kick_velocity,
            )
            t0 = time.perf_counter()
            player.output = player.pipeline.step(player.frame)
            totals["perception"] += time.perf_counter() - t0
            totals["render"] += sensed["render"]
            totals["sensors"] += sensed["sensors"]
        self.step_times = totals
        return totals

    def _world_state(self) -> WorldState:
        """The ground truth now (``agent`` 0)."""
        return field_world_state(
            self._time_s, self.scene, self.robots, self._names, self._teams, self._blocked, 0
        )

    def _ball_distances(self, ball: FloatArray) -> FloatArray:
        """The ball's distance (2,) (m) to each team's target goal centre (team 0: +x)."""
        dims = self.scene.dimensions
        return np.array([math.dist(ball, goal_centre(dims, side)) for side in (1, -1)])

    def _reward_terms(self, state: WorldState, *, goal: int, out: bool) -> list[dict[str, float]]:
        """Each team's reward terms (class doc) for a ``goal`` at +x (+1), -x (-1) or none (0)
        and the ball ``out`` elsewhere; updates the progress's last distances."""
        c = self.config.task
        distance = self._ball_distances(state.ball)
        progress, self._last_distance = self._last_distance - distance, distance
        return [
            {
                "goal": c.goal_reward * (goal if team == 0 else -goal),
                "progress": c.progress_weight * float(progress[team]),
                "time": -c.time_cost,
                "out": -c.out_penalty if out and self._last_kicker_team == team else 0.0,
            }
            for team in (0, 1)
        ]

    def _infos(
        self, terms: list[dict[str, float]], times: dict[str, float]
    ) -> dict[str, dict[str, Any]]:
        """Every agent's ``info`` (class doc)."""
        cfg, state = self.config, self._state
        assert state is not None
        infos: dict[str, dict[str, Any]] = {}
        for k, player in enumerate(self.players):
            info: dict[str, Any] = {"team": player.team, "reward_terms": dict(terms[player.team])}
            if cfg.info_level == "full":
                assert player.output is not None
                info["perception"] = perception_info(player.output, self._info_layout)
                info["ground_truth"] = ground_truth_info(dataclasses.replace(state, agent=k))
            if cfg.info_timing:
                info["timing"] = dict(times)
            infos[player.name] = info
        return infos
