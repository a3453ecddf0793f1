"""Whether a second thread makes a frame's image detectors cheaper: field features and robots.

The two detectors of a no-poles frame are independent (each reads only the image and the camera
pose), so one could run in a worker thread while the other runs in the caller. Python's GIL lets
that help only where the work releases it (OpenCV's calls, NumPy's loops over large arrays);
this measures what it gives.

Plays ``--steps`` steps of ``--env`` (``SPL/ActiveVision-NoPoles-v1``, rendered) with the head
scan from ``reset(seed=--seed)`` and keeps each step's image and camera pose
(``env.unwrapped.sensor_frame``). Then, ``--repeats`` passes each after a warm-up pass, times
per frame (ms, mean over the frames of the fastest pass):

- ``field_features``: :func:`perception.vision.field_features.detect_field_features` alone;
- ``robots``: :meth:`perception.vision.robots.RobotDetector.detect` alone;
- ``sequential``: both, one after the other (what the pipeline does);
- ``two_threads``: the robot detector submitted to a one-worker thread pool, the field
  features run meanwhile in the caller, then the worker's result awaited;

and ``python_calls_per_frame``: the Python-level function calls (cProfile's count, NumPy's and
OpenCV's wrappers included) of one pass of each detector, over the frames.

    python benchmarks/perception_threads.py      # about 1 min

Writes ``--out`` (``benchmarks/results/perception_threads.json``).
"""

from __future__ import annotations

import argparse
import cProfile
import json
import os
import platform
import pstats
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

import spl_env  # noqa: F401  (registers the env ids)
from agents.evaluate import load_policy
from perception.types import CameraModel, CameraState
from perception.vision.field_features import detect_field_features
from perception.vision.robots import RobotDetector, RobotDetectorConfig

RESULTS = Path("benchmarks/results")
Frame = tuple[np.ndarray, CameraModel, CameraState]


def recorded_frames(env_id: str, steps: int, seed: int) -> list[Frame]:
    """The image, camera and camera pose of each of ``steps`` steps of ``env_id`` played by the
    head scan from ``reset(seed=seed)``."""
    env = gym.make(env_id)
    policy = load_policy("scan", env.get_wrapper_attr("config"))
    obs, _ = env.reset(seed=seed)
    frames: list[Frame] = []
    for _ in range(steps):
        obs, _, terminated, truncated, _ = env.step(policy.predict(obs)[0])
        frame = env.unwrapped.sensor_frame  # type: ignore[attr-defined]
        frames.append((frame.image.copy(), frame.camera, frame.camera_state))
        if terminated or truncated:
            obs, _ = env.reset()
    env.close()
    return frames


def fastest_pass_ms(run: Callable[[Frame], object], frames: list[Frame], repeats: int) -> float:
    """Mean ms per frame of ``run`` over ``frames``, the fastest of ``repeats`` passes after a
    warm-up pass."""
    for frame in frames:
        run(frame)
    best = np.inf
    for _ in range(repeats):
        start = time.perf_counter()
        for frame in frames:
            run(frame)
        best = min(best, time.perf_counter() - start)
    return float(1e3 * best / len(frames))


def calls_per_frame(run: Callable[[Frame], object], frames: list[Frame]) -> float:
    """Python-level function calls (cProfile's count) per frame of ``run`` over ``frames``."""
    profile = cProfile.Profile()
    profile.enable()
    for frame in frames:
        run(frame)
    profile.disable()
    return float(pstats.Stats(profile).total_calls / len(frames))  # type: ignore[attr-defined]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--env", default="SPL/ActiveVision-NoPoles-v1")
    parser.add_argument("--steps", type=int, default=300)
    parser.add_argument("--seed", type=int, default=100)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--out", type=Path, default=RESULTS / "perception_threads.json")
    args = parser.parse_args()
    frames = recorded_frames(args.env, args.steps, args.seed)
    robots = RobotDetector(RobotDetectorConfig(), frames[0][1])

    def field_features(frame: Frame) -> object:
        return detect_field_features(*frame)

    def robot_sightings(frame: Frame) -> object:
        return robots.detect(frame[0], frame[2])

    def sequential(frame: Frame) -> object:
        return field_features(frame), robot_sightings(frame)

    with ThreadPoolExecutor(max_workers=1) as worker:

        def two_threads(frame: Frame) -> object:
            pending = worker.submit(robot_sightings, frame)
            return field_features(frame), pending.result()

        runs = {
            "field_features": field_features,
            "robots": robot_sightings,
            "sequential": sequential,
            "two_threads": two_threads,
        }
        ms = {name: fastest_pass_ms(run, frames, args.repeats) for name, run in runs.items()}
    report: dict[str, Any] = {
        "env_id": args.env,
        "frames": len(frames),
        "seed": args.seed,
        "repeats": args.repeats,
        "cpu_count": len(os.sched_getaffinity(0)),
        "python": platform.python_version(),
        "ms_per_frame": ms,
        "two_threads_over_sequential": ms["two_threads"] / ms["sequential"],
        "python_calls_per_frame": {
            "field_features": calls_per_frame(field_features, frames),
            "robots": calls_per_frame(robot_sightings, frames),
        },
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(report, indent=1) + "\n")
    print(json.dumps(report, indent=1))


if __name__ == "__main__":
    main()
