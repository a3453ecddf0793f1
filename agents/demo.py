"""The demo episode: one minute of ``SPL/ActiveVision-v0`` with the scripted head scan.

    python -m agents.demo --out outputs/demo
    python -m agents.demo --out outputs/demo_short --set episode_s=10 body_behaviour=square

Writes ``frames.png`` (a strip of rendered views: top-down truth and belief beside the camera
image with detections), ``trajectory.png`` and ``metrics.json`` to ``--out``.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import cv2
import gymnasium as gym
import numpy as np

import spl_env  # noqa: F401  (registers the env ids)
from agents.evaluate import (
    add_overrides_argument,
    env_kwargs_for,
    episode_metrics,
    load_policy,
    parse_overrides,
    run_episode,
    trajectory_plot,
)


def frame_strip(frames: list[np.ndarray], columns: int = 2, width_px: int = 1400) -> np.ndarray:
    """RGB frames tiled row by row into one BGR image about ``width_px`` wide."""
    h, w = frames[0].shape[:2]
    scale = width_px / (columns * w)
    tiles = [
        cv2.resize(cv2.cvtColor(f, cv2.COLOR_RGB2BGR), (int(w * scale), int(h * scale)))
        for f in frames
    ]
    while len(tiles) % columns:
        tiles.append(np.zeros_like(tiles[0]))
    rows = [np.hstack(tiles[i : i + columns]) for i in range(0, len(tiles), columns)]
    return np.vstack(rows)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--out", type=Path, default=Path("outputs/demo"))
    parser.add_argument("--policy", default="scan", help="a baseline name or a model .zip")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--frames", type=int, default=6, help="views in the strip")
    add_overrides_argument(parser)
    args = parser.parse_args(argv)
    if args.frames < 1:
        parser.error(f"--frames must be >= 1, got {args.frames}")
    env = gym.make(
        "SPL/ActiveVision-v0",
        render_mode="rgb_array",
        **env_kwargs_for(args.policy, parse_overrides(args.set)),
    )
    steps = env.get_wrapper_attr("config").max_steps
    record = run_episode(
        env,
        load_policy(args.policy, env.get_wrapper_attr("config")),
        seed=args.seed,
        frame_every=max(1, steps // args.frames),
    )
    args.out.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(str(args.out / "frames.png"), frame_strip(record.frames[: args.frames]))
    cv2.imwrite(
        str(args.out / "trajectory.png"),
        trajectory_plot(env.get_wrapper_attr("config").scene.dimensions, record),
    )
    metrics = episode_metrics(record)
    (args.out / "metrics.json").write_text(json.dumps(metrics, indent=2))
    env.close()
    print(json.dumps(metrics, indent=2))
    print(f"wrote frames.png, trajectory.png and metrics.json to {args.out}")


if __name__ == "__main__":
    main()
