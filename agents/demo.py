"""The demo episode: one minute of ``SPL/ActiveVision-v0`` with the scripted head scan (or
of the env and policy given, as in ``agents.evaluate``).

    python -m agents.demo --out outputs/demo
    python -m agents.demo --out outputs/demo_short --set episode_s=10 body_behaviour=square
    python -m agents.demo --out outputs/demo_kick --env SPL/Striker-v0

Writes ``frames.png`` (a strip of rendered views: top-down truth and belief beside the camera
image with detections), ``trajectory.png`` and ``metrics.json`` to ``--out``.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import cv2
import numpy as np

import spl_env  # noqa: F401  (registers the env ids)
from agents.evaluate import (
    add_env_and_policy_arguments,
    add_overrides_argument,
    episode_metrics,
    prepare_run,
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
    parser.add_argument(
        "--out", type=Path, default=Path("outputs/demo"), help="folder for the outputs"
    )
    add_env_and_policy_arguments(parser)
    parser.add_argument("--seed", type=int, default=0, help="the episode's reset seed (>= 0)")
    parser.add_argument(
        "--frames", type=int, default=6, help="views in the strip, spread over the episode"
    )
    add_overrides_argument(parser)
    args = parser.parse_args(argv)
    if args.frames < 1:
        parser.error(f"--frames must be >= 1, got {args.frames}")
    if args.seed < 0:
        parser.error(f"--seed must be >= 0, got {args.seed}")
    env, policy, _, _ = prepare_run(
        parser, args.env, args.policy, args.set, args.out, render_mode="rgb_array"
    )
    steps = env.get_wrapper_attr("config").max_steps
    frames = min(args.frames, steps)  # at most one view a step
    record = run_episode(env, policy, seed=args.seed, frame_every=max(1, steps // frames))
    cv2.imwrite(str(args.out / "frames.png"), frame_strip(record.frames[:frames]))
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
