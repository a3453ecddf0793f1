"""Evaluate a saved SB3 model or a scripted baseline on an SPL env.

    python -m agents.evaluate --policy scan --episodes 3 --out outputs/eval_scan
    python -m agents.evaluate --policy runs/ppo/model.zip --episodes 3 --out outputs/eval_ppo
    python -m agents.evaluate --env SPL/LookAround-v0 --policy look_at_stalest --set frontend=colour
    python -m agents.evaluate --policy pretrained:active_vision --video --out outputs/eval_av
    python -m agents.evaluate --env SPL/Striker-v0 --policy centre_kick --out outputs/eval_kick

Writes ``metrics.json`` (per episode and mean: return, mean SLAM position error, mean
odometry-only error, mean pose NEES, landmark error, ``null`` where no landmark was mapped, the
robot awareness (share of the robots within 3 m tracked within 0.3 m, ``null`` without robot
tracks), whether the episode ended in a goal for us (``scored``: in the opponent's goal;
always 0 in ``SPL/Goalie-v0`` and its ``-NoPoles`` id, ``null`` in envs without goals),
mean wall-clock milliseconds per step) and ``trajectory.png`` (the first episode: true
path green, SLAM orange, odometry grey, on the field); with ``--video`` also ``episode.mp4``, the
first episode's ``env.render()`` frames at the control rate.

``--set key=value`` overrides the env config: a key is a dotted path
(``sensors.camera.noise_std``), a top-level name (``control_dt_s``) or an alias of the env
(``episode_s``, ``frontend``, ``backend``, ``body_behaviour``, ...; see
:data:`spl_env.envs.active_vision.ACTIVE_VISION_ALIASES`). A model ``.zip`` saved by
``agents.train`` has its ``config.json`` beside it: its ``env_kwargs`` configure the env the
model is evaluated on, and ``--set`` overrides them; a shipped model (``pretrained:<name>``,
:func:`pretrained_names`) has its training config beside it as ``<name>.json``, whose
``env_id`` is the default ``--env``. The env must keep ``info_level="full"``:
the metrics read perception and ground truth from ``info``.
"""

from __future__ import annotations

import argparse
import json
from collections.abc import Iterator
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any, NamedTuple, Protocol

import cv2
import gymnasium as gym
import numpy as np
from gymnasium import spaces

import spl_env  # noqa: F401  (registers the env ids)
from agents.baselines import BASELINES
from agents.head_options import HeadPrimitives, pole_count
from agents.options import OptionPolicy, Primitives
from agents.soccer_baselines import SOCCER_BASELINES
from agents.striker_options import KICK_GEOMETRY, StrikerPrimitives
from agents.video import write_video
from perception.metrics import landmark_errors, pose_nees, position_error
from spl_env.config import EnvConfig
from spl_env.field import FieldDimensions
from spl_env.rendering import ODOM_BGR, SLAM_BGR, TRUE_BGR, TopDownView
from spl_env.tasks.goalie import GoalieTaskConfig
from spl_env.tasks.head_control import HeadControlTaskConfig
from spl_env.tasks.robot_awareness import RobotAwarenessTaskConfig, awareness_share
from spl_env.tasks.soccer import SoccerTaskConfig

AWARENESS = RobotAwarenessTaskConfig()  # the robots issue's measure: its radius and match


class Policy(Protocol):
    """Anything with SB3's ``predict``."""

    def predict(
        self, obs: Any, state: Any = None, episode_start: Any = None, deterministic: bool = True
    ) -> tuple[np.ndarray, Any]: ...


@dataclass
class EpisodeRecord:
    """What one episode produced, step by step (T steps incl. the reset).

    ``step_seconds`` holds each step's wall-clock seconds (physics, rendering, sensors and
    perception; 0 for the reset); ``awareness`` the robot awareness of each step with a robot
    within 3 m (:func:`spl_env.tasks.robot_awareness.awareness_share`, envs with robot tracks).
    """

    episode_return: float = 0.0
    true_poses: list[np.ndarray] = field(default_factory=list)
    slam_poses: list[np.ndarray] = field(default_factory=list)
    odometry_poses: list[np.ndarray] = field(default_factory=list)
    pose_covs: list[np.ndarray] = field(default_factory=list)
    step_seconds: list[float] = field(default_factory=list)
    awareness: list[float] = field(default_factory=list)
    frames: list[np.ndarray] = field(default_factory=list)
    final_info: dict[str, Any] = field(default_factory=dict)

    def add(self, info: dict[str, Any], step_s: float) -> None:
        """Keep one step's ``info`` (``info_level="full"``) and its wall-clock seconds."""
        self.true_poses.append(info["ground_truth"]["robot_pose"])
        self.slam_poses.append(info["perception"]["pose"])
        self.odometry_poses.append(info["perception"]["odometry_pose"])
        self.pose_covs.append(info["perception"]["pose_cov"])
        self.step_seconds.append(step_s)
        if "robots_tracked" in info["perception"]:
            share = awareness_share(
                info["ground_truth"]["robot_pose"][:2],
                info["ground_truth"]["robots"][:, :2],
                info["perception"]["robots"][info["perception"]["robots_tracked"]],
                AWARENESS.awareness_radius_m,
                AWARENESS.awareness_match_m,
            )
            if share is not None:
                self.awareness.append(share)
        self.final_info = info


PRETRAINED = "pretrained:"  # policy specs naming a shipped model: pretrained:<name>


def pretrained_folder() -> Path:
    """``agents/pretrained``: the shipped models."""
    return Path(str(resources.files("agents") / "pretrained"))


def pretrained_names() -> list[str]:
    """Names of the models shipped in :func:`pretrained_folder` (``<name>.zip`` beside
    ``<name>.json``, the config it was trained with)."""
    folder = pretrained_folder()
    return sorted(p.stem for p in folder.glob("*.zip") if p.with_suffix(".json").is_file())


def model_files(spec: str) -> tuple[Path, Path | None] | None:
    """The model ``.zip`` a policy spec names and the training config beside it (``None`` if
    there is none), or ``None`` when ``spec`` names no model (a baseline).

    ``pretrained:<name>`` is a shipped model with ``<name>.json``; a ``.zip`` path a model
    saved by ``agents.train``, with its ``config.json`` in the same folder."""
    if spec.startswith(PRETRAINED):
        name = spec[len(PRETRAINED) :]
        if name not in pretrained_names():
            raise ValueError(
                f"policy {spec!r}: no shipped model of that name; shipped: {pretrained_names()}"
            )
        return pretrained_folder() / f"{name}.zip", pretrained_folder() / f"{name}.json"
    if spec.endswith(".zip"):
        if not Path(spec).is_file():
            raise ValueError(f"policy {spec!r}: no such model file")
        config = Path(spec).with_name("config.json")
        return Path(spec), config if config.is_file() else None
    return None


def load_policy(
    spec: str, config: EnvConfig, observation_space: spaces.Space | None = None
) -> Policy:
    """A baseline by name (a head's, :data:`agents.baselines.BASELINES`, or a soccer
    player's, :data:`agents.soccer_baselines.SOCCER_BASELINES`) for an env built from
    ``config`` (the env's ``config_class``, e.g.
    :class:`spl_env.envs.active_vision.ActiveVisionConfig`), a shipped model
    (``pretrained:<name>``) or an SB3 PPO ``.zip``.

    ValueError for a baseline of the other kind than the env (a head policy on a soccer env,
    a soccer player on a head env or on one whose head is in the action), for an env that is
    neither (the Circles envs: :mod:`agents.drivers` drives them, from Python) and, given the
    env's ``observation_space``, for a model trained on other observations."""
    if not isinstance(config.task, HeadControlTaskConfig | SoccerTaskConfig):
        raise ValueError(
            f"no policy here plays this env ({type(config.task).__name__}): these tools play "
            "the SPL envs; drive a Circles env from Python with agents.drivers.WaypointDriver "
            "(README, 'Circles/Office-v0')"
        )
    if spec in BASELINES:
        if not isinstance(config.task, HeadControlTaskConfig):
            raise ValueError(
                f"policy {spec!r} moves the head, but this env ({type(config.task).__name__}) "
                f"takes another action: pick one of {sorted(SOCCER_BASELINES)} or a model"
            )
        return BASELINES[spec].from_config(config)
    if spec in SOCCER_BASELINES:
        if not isinstance(config.task, SoccerTaskConfig) or config.task.head_control == "action":
            raise ValueError(
                f"policy {spec!r} plays soccer with a scripted head, but this env "
                f"({type(config.task).__name__}) takes another action: pick one of "
                f"{sorted(BASELINES)} for a head env, or a soccer env without "
                "head_control='action'"
            )
        return SOCCER_BASELINES[spec].from_config(config)
    files = model_files(spec)
    if files is None:
        raise ValueError(
            f"policy must be one of {sorted(BASELINES)} (head), {sorted(SOCCER_BASELINES)} "
            f"(soccer), pretrained:<name> (shipped: "
            f"{pretrained_names()}) or an existing .zip path, got {spec!r}"
        )
    from stable_baselines3 import PPO

    model = PPO.load(files[0], device="cpu")
    policy: Policy = model
    expected = observation_space
    if isinstance(model.action_space, spaces.Discrete):  # trained on options (ours, the Zoo's)
        primitives = option_primitives(model.observation_space, config)
        policy = OptionPolicy(model, primitives)
        if isinstance(observation_space, spaces.Dict):
            expected = primitives.observation_space(observation_space)
    if expected is not None:
        check_observation_space(spec, model.observation_space, expected)
    return policy


def check_observation_space(spec: str, trained: spaces.Space, env: spaces.Space) -> None:
    """ValueError naming them when the observations the model ``spec`` was trained on
    (``trained``) and the env's (``env``) differ in their keys or shapes (a v0 model on a v1
    env, one trained with other overrides): SB3 reads every key of an observation."""
    if isinstance(trained, spaces.Dict) and isinstance(env, spaces.Dict):
        missing = sorted(set(trained.spaces) - set(env.spaces))
        extra = sorted(set(env.spaces) - set(trained.spaces))
        shaped = sorted(
            k
            for k in set(trained.spaces) & set(env.spaces)
            if trained.spaces[k].shape != env.spaces[k].shape
        )
    else:
        missing, extra = [], []
        shaped = [] if trained.shape == env.shape else ["the observation"]
    if missing or extra or shaped:
        raise ValueError(
            f"policy {spec!r} was trained on other observations than this env gives (keys the "
            f"env lacks: {missing}; keys the model never saw: {extra}; of another shape: "
            f"{shaped}): evaluate it on the env and overrides it was trained on"
        )


def default_policy(config: EnvConfig) -> str:
    """The scripted policy an env plays when none is named: the goalie in a goal, the
    centre-kicking striker in the other soccer envs, the head scan elsewhere."""
    if isinstance(config.task, GoalieTaskConfig):
        return "goalie"
    if isinstance(config.task, SoccerTaskConfig):
        return "centre_kick"
    return "scan"


def option_primitives(observation_space: spaces.Space, config: EnvConfig) -> Primitives:
    """The primitives a model trained on options (whose observation space is
    ``observation_space``) picks from: the striker's for a soccer env (its task config a
    :class:`spl_env.tasks.soccer.SoccerTaskConfig`), the head's otherwise; refused when the
    model was trained on the other kind (``kick_geometry`` in its observations or not)."""
    soccer = isinstance(config.task, SoccerTaskConfig)
    striker_model = isinstance(observation_space, spaces.Dict) and KICK_GEOMETRY in (
        observation_space.spaces
    )
    if soccer != striker_model:
        trained, env = ("striker", "head") if striker_model else ("head", "soccer")
        raise ValueError(
            f"the model was trained on {trained} options; it cannot play this {env} env "
            f"({type(config.task).__name__})"
        )
    if soccer:
        return StrikerPrimitives(config)
    return HeadPrimitives(config, pole_count(observation_space))


def training_config(spec: str) -> dict[str, Any]:
    """The training config saved with the model ``spec`` names (``{}`` for a baseline or a
    model saved without one)."""
    files = model_files(spec)
    if files is None or files[1] is None:
        return {}
    try:
        config = json.loads(files[1].read_text())
    except json.JSONDecodeError as error:
        raise ValueError(f"{files[1]} is not valid JSON: {error}") from None
    if not isinstance(config, dict) or not isinstance(config.get("env_kwargs"), dict):
        raise ValueError(f"{files[1]} has no 'env_kwargs' object: not a training config")
    return config


def played_steps(env: gym.Env, policy: Policy, seed: int) -> Iterator[tuple[float, dict[str, Any]]]:
    """The steps of one episode of ``policy`` (deterministic) on ``env`` from
    ``reset(seed=seed)``: each step's reward and ``info``, until it terminates or truncates."""
    obs, _ = env.reset(seed=seed)
    done, first = False, True
    while not done:
        action, _ = policy.predict(obs, episode_start=np.array([first]), deterministic=True)
        first = False
        obs, reward, terminated, truncated, info = env.step(action)
        done = terminated or truncated
        yield float(reward), info


def run_episode(env: gym.Env, policy: Policy, seed: int, frame_every: int = 0) -> EpisodeRecord:
    """One episode of ``policy`` on the SPL env ``env``; with ``frame_every > 0`` keeps
    ``env.render()`` every that many steps."""
    record = EpisodeRecord()
    obs, info = env.reset(seed=seed)
    if "perception" not in info or "ground_truth" not in info:
        raise ValueError(
            "evaluation reads info['perception'] and info['ground_truth']: make the env with "
            "info_level='full' (the default)"
        )
    record.add(info, 0.0)
    done, step = False, 0
    while not done:
        action, _ = policy.predict(obs, episode_start=np.array([step == 0]), deterministic=True)
        obs, reward, terminated, truncated, info = env.step(action)
        record.episode_return += float(reward)
        record.add(info, sum(env.get_wrapper_attr("step_times").values()))
        step += 1
        if frame_every and step % frame_every == 0:
            record.frames.append(np.asarray(env.render()))
        done = terminated or truncated
    return record


def episode_metrics(record: EpisodeRecord) -> dict[str, float | None]:
    """Summary numbers of one episode (SI units); the landmark error is ``None`` (JSON ``null``)
    when no landmark was mapped, ``scored`` (1 when the episode ended in a goal for us, in the
    opponent's goal, else 0) ``None`` in envs without a ``goal`` reward term."""
    slam_err = [
        position_error(t, e) for t, e in zip(record.true_poses, record.slam_poses, strict=True)
    ]
    odom_err = [
        position_error(t, e) for t, e in zip(record.true_poses, record.odometry_poses, strict=True)
    ]
    nees = [
        pose_nees(t, e, c)
        for t, e, c in zip(record.true_poses, record.slam_poses, record.pose_covs, strict=True)
    ]
    gt, goal = record.final_info["ground_truth"], record.final_info["reward_terms"].get("goal")
    ids, landmarks = mapped_landmarks(record.final_info["perception"])
    lm = landmark_errors(gt["landmark_ids"], gt["landmarks"], ids, landmarks)
    return {
        "return": record.episode_return,
        "mean_position_error_m": float(np.mean(slam_err)),
        "final_position_error_m": float(slam_err[-1]),
        "mean_odometry_error_m": float(np.mean(odom_err)),
        "final_odometry_error_m": float(odom_err[-1]),
        "mean_pose_nees": float(np.mean(nees)),
        "mean_landmark_error_m": float(np.mean(lm)) if len(lm) else None,
        "landmarks_mapped": len(lm),
        "robot_awareness": float(np.mean(record.awareness)) if record.awareness else None,
        "scored": None if goal is None else float(goal > 0),
        "mean_step_ms": 1000.0 * float(np.mean(record.step_seconds[1:])),
        "steps": len(record.true_poses) - 1,
    }


def mapped_landmarks(perception: dict[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    """Ids (K,) and estimates (K, 2) of the landmarks SLAM mapped, from ``info["perception"]``
    (whose rows follow the env's landmark order, masked by ``landmarks_mapped``)."""
    mapped = np.asarray(perception["landmarks_mapped"], dtype=bool)
    ids = np.asarray(perception["landmark_ids"])[mapped]
    return ids, np.asarray(perception["landmarks"], dtype=np.float64)[mapped]


def trajectory_plot(dims: FieldDimensions, record: EpisodeRecord) -> np.ndarray:
    """(H, W, 3) BGR picture of the true, SLAM and odometry paths and the final map."""
    view = TopDownView(dims)
    img = view.background.copy()
    for xy in record.final_info["ground_truth"]["landmarks"]:
        cv2.circle(img, view.px(xy), 6, TRUE_BGR, 2)
    for xy in mapped_landmarks(record.final_info["perception"])[1]:
        cv2.drawMarker(img, view.px(xy), SLAM_BGR, cv2.MARKER_CROSS, 12, 2)
    for poses, colour in (
        (record.odometry_poses, ODOM_BGR),
        (record.slam_poses, SLAM_BGR),
        (record.true_poses, TRUE_BGR),
    ):
        pts = np.array([view.px(p) for p in poses], dtype=np.int32)
        cv2.polylines(img, [pts], False, colour, 2)
    return img


def summarise(per_episode: list[dict[str, float | None]]) -> dict[str, float | None]:
    """Mean of each metric over the episodes that have it (not ``None``); ``None`` if none has."""
    out: dict[str, float | None] = {}
    for key in per_episode[0]:
        values = [v for m in per_episode if (v := m[key]) is not None]
        out[key] = float(np.mean(values)) if values else None
    return out


def add_env_and_policy_arguments(parser: argparse.ArgumentParser) -> None:
    """``--env`` and ``--policy`` on ``parser``, as :func:`prepare_run` reads them."""
    parser.add_argument(
        "--env",
        default=None,
        help=f"env id (default: the model's, else {DEFAULT_ENV_ID}); "
        "python -c 'import gymnasium, spl_env; print(list(gymnasium.registry))' lists them",
    )
    parser.add_argument(
        "--policy",
        default=None,
        help=f"{sorted(BASELINES)} (head envs), {sorted(SOCCER_BASELINES)} (soccer envs), "
        f"pretrained:<name> ({pretrained_names()}) or a model .zip; default: the goalie in "
        "SPL/Goalie-v0, the centre kick in the other soccer envs, the head scan elsewhere",
    )


def add_overrides_argument(parser: argparse.ArgumentParser) -> None:
    """``--set KEY=VALUE ...`` on ``parser`` (several after one ``--set``, or ``--set`` again):
    env config overrides, read by :func:`parse_overrides`."""
    parser.add_argument(
        "--set",
        action="extend",
        nargs="+",
        default=[],
        metavar="KEY=VALUE",
        help="env config overrides by dotted path, top-level name or alias (values as JSON), "
        "e.g. --set episode_s=30 self_pose=field_features sensors.camera.noise_std=0",
    )


def parse_overrides(pairs: list[str]) -> dict[str, Any]:
    """``key=value`` strings to env kwargs; values are JSON (numbers, strings in quotes, true),
    else the string. ValueError for a pair without ``=``, an empty key or a key set twice."""
    out: dict[str, Any] = {}
    for pair in pairs:
        key, sep, value = pair.partition("=")
        if not sep or not key:
            raise ValueError(f"--set takes key=value, got {pair!r}")
        if key in out:
            raise ValueError(f"--set gives {key!r} twice")
        try:
            out[key] = json.loads(value)
        except json.JSONDecodeError:
            out[key] = value
    return out


USER_ERRORS = (ValueError, TypeError, OSError, gym.error.Error)  # what a bad argument raises
DEFAULT_ENV_ID = "SPL/ActiveVision-v0"


class PreparedRun(NamedTuple):
    """A command-line run's env and policy, with the env id and policy spec they came from."""

    env: gym.Env
    policy: Policy
    env_id: str
    policy_spec: str


def prepare_run(
    parser: argparse.ArgumentParser,
    env_id: str | None,
    policy_spec: str | None,
    overrides: list[str],
    out: Path,
    render_mode: str | None = None,
) -> PreparedRun:
    """The env and the policy of a command-line run, and its output folder made. The env is
    ``env_id``, else the model's (its training config's ``env_id``), else
    :data:`DEFAULT_ENV_ID`; the policy ``policy_spec``, else the env's
    :func:`default_policy`. A mistake in them (an unknown env id, policy or config key, a bad
    value, a policy that does not fit the env, a folder that cannot be made) ends the run
    with ``parser.error`` and its message, one line, before any episode."""
    try:
        saved = training_config(policy_spec) if policy_spec else {}
        env_id = env_id or saved.get("env_id", DEFAULT_ENV_ID)
        env = made_env(env_id, render_mode, policy_spec, parse_overrides(overrides))
        config = env.get_wrapper_attr("config")
        if config.info_level != "full":
            raise ValueError(
                f"info_level must stay 'full' here (the metrics read perception and ground "
                f"truth from info), got {config.info_level!r}"
            )
        spec = policy_spec or default_policy(config)
        policy = load_policy(spec, config, env.observation_space)
        out.mkdir(parents=True, exist_ok=True)
    except USER_ERRORS as error:
        parser.error(str(error))
    return PreparedRun(env, policy, env_id, spec)


def made_env(
    env_id: str, render_mode: str | None, policy_spec: str | None, overrides: dict[str, Any]
) -> gym.Env:
    """``env_id`` made with :func:`env_kwargs_for` the policy and ``overrides``; ValueError
    saying so when the settings of the model's training config are what this env refuses (a
    model of another env: a head policy's settings on a soccer env)."""
    try:
        return gym.make(env_id, render_mode=render_mode, **env_kwargs_for(policy_spec, overrides))
    except USER_ERRORS as error:
        saved = training_config(policy_spec) if policy_spec else {}
        trained_on = saved.get("env_id")
        if trained_on is None or trained_on == env_id:
            raise
        try:  # is it the model's settings that this env refuses?
            gym.make(env_id, **overrides).close()
        except USER_ERRORS:
            raise error from None
        reason = str(error).split(" was raised from the environment creator")[0]
        raise ValueError(
            f"policy {policy_spec!r} was trained on {trained_on} and carries its settings, "
            f"which {env_id} refuses ({reason}): evaluate it on {trained_on}"
        ) from None


def env_kwargs_for(policy: str | None, overrides: dict[str, Any]) -> dict[str, Any]:
    """Env kwargs to evaluate ``policy`` with: the ``env_kwargs`` of the training config saved
    with its model (if there is one; :func:`training_config`), updated by ``overrides``."""
    saved = training_config(policy) if policy else {}
    return {**saved.get("env_kwargs", {}), **overrides}


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    add_env_and_policy_arguments(parser)
    parser.add_argument(
        "--video", action="store_true", help="also write the first episode as episode.mp4"
    )
    parser.add_argument("--episodes", type=int, default=3, help="episodes to play (>= 1)")
    parser.add_argument(
        "--seed", type=int, default=0, help="episode k is reset with seed + k (>= 0)"
    )
    parser.add_argument(
        "--out", type=Path, default=Path("outputs/eval"), help="folder for the outputs"
    )
    add_overrides_argument(parser)
    args = parser.parse_args(argv)
    if args.episodes < 1:
        parser.error(f"--episodes must be >= 1, got {args.episodes}")
    if args.seed < 0:
        parser.error(f"--seed must be >= 0, got {args.seed}")
    env, policy, env_id, spec = prepare_run(
        parser, args.env, args.policy, args.set, args.out, "rgb_array" if args.video else None
    )
    per_episode = []
    for k in range(args.episodes):
        record = run_episode(
            env, policy, seed=args.seed + k, frame_every=int(args.video and k == 0)
        )
        if record.frames:
            write_video(
                record.frames,
                args.out / "episode.mp4",
                fps=1.0 / env.get_wrapper_attr("config").control_dt_s,
            )
        per_episode.append(episode_metrics(record))
        print(f"episode {k}: {json.dumps(per_episode[-1])}")
        if k == 0:
            cv2.imwrite(
                str(args.out / "trajectory.png"),
                trajectory_plot(env.get_wrapper_attr("config").scene.dimensions, record),
            )
    env.close()
    result = {
        "env": env_id,
        "policy": spec,
        "episodes": per_episode,
        "mean": summarise(per_episode),
    }
    (args.out / "metrics.json").write_text(json.dumps(result, indent=2))
    print(json.dumps(result["mean"], indent=2))


if __name__ == "__main__":
    main()
