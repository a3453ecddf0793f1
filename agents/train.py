"""Train a head policy with stable-baselines3 PPO (``MultiInputPolicy``).

    python -m agents.train --timesteps 20000 --out runs/ppo_active_vision
    python -m agents.train --timesteps 2048 --progress-bar --tensorboard runs/tb
    python -m agents.train --timesteps 4096 --set camera_mode=geometric frontend=colour episode_s=20

Hyper-parameters come from ``agents/configs/<env id with / as _>.json`` (plain values) and can be
changed with ``--set`` (env config keys as in ``agents.evaluate``) or by editing a copy passed
with ``--config``. A config may set ``n_envs`` (default 1): that many envs step in parallel
processes (SB3's ``SubprocVecEnv``); and ``warm_start``
(:class:`agents.imitation.WarmStartConfig` fields): the policy first imitates a scripted one,
which plays seeds ``10 000 (seed + 1) + k``; or ``options``: the policy picks among scripted
primitives (:data:`OPTIONS`: ``"head"`` what to look at, :mod:`agents.head_options`, instead of
head angles; ``"striker"`` where to kick and how hard, :mod:`agents.striker_options`, instead of
walk speeds and kicks). Training envs run with
``info_level="light"`` (training reads only rewards). Saves ``model.zip``, the resolved
``config.json`` (with the warm start's losses per epoch) and each env's episode returns
(``monitor/*.monitor.csv``, SB3's ``Monitor``; :mod:`agents.learning_curves` plots them) to
``--out``.
"""

from __future__ import annotations

import argparse
import json
from collections.abc import Callable
from functools import partial
from importlib import resources
from pathlib import Path
from typing import Any

import gymnasium as gym

import spl_env  # registers the env ids
from agents.evaluate import USER_ERRORS, add_overrides_argument, parse_overrides
from agents.head_options import HeadOptions
from agents.imitation import WarmStartConfig, imitate, record_teacher
from agents.options import OptionsWrapper
from agents.striker_options import StrikerOptions
from spl_env import HEAD_CONTROL_ENV_IDS

OPTIONS: dict[str, Callable[[gym.Env], OptionsWrapper]] = {
    "head": HeadOptions,
    "striker": StrikerOptions,
}


def default_config_path(env_id: str) -> Path:
    """The shipped config for ``env_id``: its own, or for a ``-NoPoles`` id without one, its
    pole env's (the id's registration adds the no-poles settings). ValueError naming the
    shipped configs when there is none."""
    configs = Path(str(resources.files("agents") / "configs"))
    for candidate in dict.fromkeys([env_id, spl_env.pole_env_id(env_id)]):
        path = configs / (candidate.replace("/", "_") + ".json")
        if path.exists():
            return path
    shipped = sorted(p.name for p in configs.glob("*.json"))
    raise ValueError(
        f"no training config is shipped for env {env_id!r} (shipped: {shipped}); "
        "pass one with --config"
    )


def load_config(path: Path) -> dict[str, Any]:
    """Read a training config (JSON; :func:`check_config`); ValueError naming ``path`` when it
    is not valid JSON."""
    try:
        config = json.loads(path.read_text())
    except json.JSONDecodeError as error:
        raise ValueError(f"training config {path} is not valid JSON: {error}") from None
    check_config(config, f"training config {path}")
    return config


def check_config(config: Any, source: str = "training config") -> None:
    """Refuse a training config that lacks ``policy``, ``env_kwargs`` or ``ppo``, or whose
    optional ``n_envs`` (int >= 1), ``options`` (a key of :data:`OPTIONS`) or ``warm_start``
    (:class:`agents.imitation.WarmStartConfig` fields; not with ``options``) is wrong."""
    if not isinstance(config, dict):
        raise TypeError(f"{source} must be a JSON object, got {type(config).__name__}")
    missing = {"policy", "env_kwargs", "ppo"} - set(config)
    if missing:
        raise ValueError(f"{source} lacks keys {sorted(missing)}")
    if "head_options" in config:
        raise ValueError(f'{source}: head_options is now "options": "head"')
    if "options" in config and config["options"] not in OPTIONS:
        raise ValueError(
            f"{source}: options must be one of {sorted(OPTIONS)}, got {config['options']!r}"
        )
    n_envs = config.get("n_envs", 1)
    if isinstance(n_envs, bool) or not isinstance(n_envs, int) or n_envs < 1:
        raise ValueError(f"{source}: n_envs must be an int >= 1, got {n_envs!r}")
    if "warm_start" in config:
        if "options" in config:
            raise ValueError(f"{source} takes options or warm_start, not both")
        WarmStartConfig(**config["warm_start"])


TEACHER_SEED0 = 10_000  # a warm start's teacher plays seeds 10 000 (seed + 1) + k


def make_training_env(
    env_id: str, env_kwargs: dict[str, Any], options: str | None = None
) -> gym.Env:
    """One training env: ``env_kwargs`` with ``info_level="light"`` unless they say otherwise,
    wrapped in ``OPTIONS[options]`` unless ``options`` is None (a module-level function, so
    that ``SubprocVecEnv`` workers import ``spl_env`` with it)."""
    env = gym.make(env_id, **{"info_level": "light", **env_kwargs})
    return env if options is None else OPTIONS[options](env)


def train(
    env_id: str,
    config: dict[str, Any],
    timesteps: int,
    out: Path,
    seed: int,
    progress_bar: bool = False,
    tensorboard: Path | None = None,
) -> Path:
    """Train PPO on ``env_id``; returns the saved model's path."""
    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv

    if timesteps < 1:
        raise ValueError(f"timesteps must be >= 1, got {timesteps}")
    check_config(config)
    if "warm_start" in config and env_id not in HEAD_CONTROL_ENV_IDS:
        raise ValueError(
            f"warm_start imitates a scripted head policy, so it needs an env whose action is "
            f"the head (one of {list(HEAD_CONTROL_ENV_IDS)}), got {env_id!r}"
        )
    out.mkdir(parents=True, exist_ok=True)
    n_envs, options = config.get("n_envs", 1), config.get("options")
    # the envs take the cores: a second torch thread only spins against them (a 2-core
    # machine ran 3x slower with torch's default threads beside busy env workers)
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    env = make_vec_env(
        partial(make_training_env, env_id, config["env_kwargs"], options),
        n_envs=n_envs,
        seed=seed,
        monitor_dir=str(out / "monitor"),
        vec_env_cls=SubprocVecEnv if n_envs > 1 else DummyVecEnv,
    )
    try:
        model = PPO(
            config["policy"],
            env,
            seed=seed,
            device="cpu",
            verbose=0,
            tensorboard_log=str(tensorboard) if tensorboard else None,
            **config["ppo"],
        )
        resolved: dict[str, Any] = {
            **config,
            "env_id": env_id,
            "timesteps": timesteps,
            "seed": seed,
        }
        if "warm_start" in config:
            warm = WarmStartConfig(**config["warm_start"])
            teacher_env = make_training_env(env_id, config["env_kwargs"])
            demos = record_teacher(teacher_env, warm, model.gamma, TEACHER_SEED0 * (seed + 1))
            teacher_env.close()
            resolved["warm_start_losses"] = imitate(model, demos, warm, seed)
        model.learn(total_timesteps=timesteps, progress_bar=progress_bar)
        resolved["timesteps_trained"] = model.num_timesteps  # whole rollouts: n_steps x n_envs
        model.save(out / "model.zip")
        (out / "config.json").write_text(json.dumps(resolved, indent=2))
    finally:
        env.close()
        torch.set_num_threads(threads)
    return out / "model.zip"


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument(
        "--env",
        default="SPL/ActiveVision-v0",
        help="env id; its shipped training config is agents/configs/<id with / as _>.json",
    )
    parser.add_argument("--config", type=Path, default=None, help="training config JSON")
    parser.add_argument(
        "--timesteps",
        type=int,
        default=20_000,
        help="env steps to train (>= 1; PPO trains whole rollouts of n_steps x n_envs)",
    )
    parser.add_argument("--seed", type=int, default=0, help="PPO's and the envs' seed (>= 0)")
    parser.add_argument(
        "--out",
        type=Path,
        default=Path("runs/ppo_active_vision"),
        help="folder for model.zip, config.json and monitor/",
    )
    parser.add_argument("--progress-bar", action="store_true", help="needs the 'train' extra")
    parser.add_argument("--tensorboard", type=Path, default=None, help="log dir; needs tensorboard")
    add_overrides_argument(parser)
    args = parser.parse_args(argv)
    if args.timesteps < 1:
        parser.error(f"--timesteps must be >= 1, got {args.timesteps}")
    if args.seed < 0:
        parser.error(f"--seed must be >= 0, got {args.seed}")
    try:
        if args.env not in gym.registry:
            raise ValueError(f"no env {args.env!r} is registered")
        config = load_config(args.config or default_config_path(args.env))
        config["env_kwargs"] = {**config["env_kwargs"], **parse_overrides(args.set)}
        # one env here first: a config mistake is told in one line, not by the workers
        make_training_env(args.env, config["env_kwargs"], config.get("options")).close()
        args.out.mkdir(parents=True, exist_ok=True)
    except USER_ERRORS as error:
        parser.error(str(error))
    path = train(
        args.env, config, args.timesteps, args.out, args.seed, args.progress_bar, args.tensorboard
    )
    print(f"saved {path}")


if __name__ == "__main__":
    main()
