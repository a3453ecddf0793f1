"""Train a head policy with stable-baselines3 PPO (``MultiInputPolicy``).

    python -m agents.train --timesteps 20000 --out runs/ppo_active_vision
    python -m agents.train --timesteps 2048 --progress-bar --tensorboard runs/tb
    python -m agents.train --timesteps 4096 --set camera_mode=geometric frontend=colour episode_s=20

Hyper-parameters come from ``agents/configs/<env id with / as _>.json`` (plain values) and can be
changed with ``--set`` (env config keys as in ``agents.evaluate``) or by editing a copy passed
with ``--config``. Saves ``model.zip`` and the resolved ``config.json`` to ``--out``.
"""

from __future__ import annotations

import argparse
import json
from importlib import resources
from pathlib import Path
from typing import Any

import gymnasium as gym

import spl_env  # noqa: F401  (registers the env ids)
from agents.evaluate import parse_overrides


def default_config_path(env_id: str) -> Path:
    """The shipped config for ``env_id``."""
    name = env_id.replace("/", "_") + ".json"
    return Path(str(resources.files("agents") / "configs" / name))


def load_config(path: Path) -> dict[str, Any]:
    """Read a training config (JSON with ``policy``, ``env_kwargs`` and ``ppo`` keys)."""
    config = json.loads(path.read_text())
    missing = {"policy", "env_kwargs", "ppo"} - set(config)
    if missing:
        raise ValueError(f"training config {path} lacks keys {sorted(missing)}")
    return config


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
    from stable_baselines3 import PPO

    if timesteps < 1:
        raise ValueError(f"timesteps must be >= 1, got {timesteps}")
    env = gym.make(env_id, **config["env_kwargs"])
    model = PPO(
        config["policy"],
        env,
        seed=seed,
        device="cpu",
        verbose=0,
        tensorboard_log=str(tensorboard) if tensorboard else None,
        **config["ppo"],
    )
    model.learn(total_timesteps=timesteps, progress_bar=progress_bar)
    out.mkdir(parents=True, exist_ok=True)
    model.save(out / "model.zip")
    resolved = {**config, "env_id": env_id, "timesteps": timesteps, "seed": seed}
    (out / "config.json").write_text(json.dumps(resolved, indent=2))
    env.close()
    return out / "model.zip"


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--env", default="SPL/ActiveVision-v0")
    parser.add_argument("--config", type=Path, default=None, help="training config JSON")
    parser.add_argument("--timesteps", type=int, default=20_000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=Path("runs/ppo_active_vision"))
    parser.add_argument("--progress-bar", action="store_true", help="needs the 'train' extra")
    parser.add_argument("--tensorboard", type=Path, default=None, help="log dir; needs tensorboard")
    parser.add_argument(
        "--set",
        nargs="*",
        default=[],
        metavar="KEY=VALUE",
        help="env config overrides by dotted path, top-level name or alias, as agents.evaluate",
    )
    args = parser.parse_args(argv)
    config = load_config(args.config or default_config_path(args.env))
    config["env_kwargs"] = {**config["env_kwargs"], **parse_overrides(args.set)}
    path = train(
        args.env, config, args.timesteps, args.out, args.seed, args.progress_bar, args.tensorboard
    )
    print(f"saved {path}")


if __name__ == "__main__":
    main()
