"""Record an episode's odometry, every front end's sightings and the ground truth.

The recording (:class:`perception.replay.SightingLog`) is what seed 000's experiments replay
through each back end: rendering happens once, and every front end reads the same frames.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any

import gymnasium as gym
import numpy as np

from agents.evaluate import Policy
from perception.pipeline import PerceptionPipeline
from perception.replay import SightingLog
from perception.representations import POLE_SIGHTINGS
from perception.types import LandmarkObservation
from spl_env.envs.core import SplEnv

# SensorFrame fields an env fills only when its own pipeline reads them
_CONDITIONAL_INPUTS = frozenset({"image", "truth"})


def frontends_for(env: gym.Env, names: tuple[str, ...]) -> dict[str, PerceptionPipeline | None]:
    """What records each front end of ``names`` (the providers of
    :data:`perception.pipeline.PROVIDERS` ``[POLE_SIGHTINGS]``) on ``env``'s frames: ``None``
    for the front end ``env`` itself runs (its own sightings are recorded, so it sees exactly
    what the env's SLAM saw), else a pipeline computing only pole sightings, configured as
    ``env``'s perception config configures them and sharing its context (one CNN).

    Raises ValueError for a front end that reads what ``env``'s frames do not carry (an image
    in the geometric camera mode, the ground truth when the env runs no oracle).
    """
    core = _core(env)
    frontends: dict[str, PerceptionPipeline | None] = {}
    for name in names:
        if name == core.config.perception.pole_sightings:
            frontends[name] = None
            continue
        pipeline = PerceptionPipeline(
            dataclasses.replace(core.config.perception, pole_sightings=name),
            core.perception_context,
            outputs=[POLE_SIGHTINGS],
        )
        missing = (pipeline.frame_inputs & _CONDITIONAL_INPUTS) - core.pipeline.frame_inputs
        if missing:
            raise ValueError(
                f"front end {name!r} reads frame.{sorted(missing)}, which this env's frames do "
                "not carry (an image needs camera_mode='rendered'; the truth an oracle in the "
                "env's own perception)"
            )
        frontends[name] = pipeline
    return frontends


def record_episode(
    env: gym.Env, policy: Policy, seed: int, frontends: Mapping[str, PerceptionPipeline | None]
) -> SightingLog:
    """Run one episode of ``policy`` on ``env`` (``info_level="full"``) and record what each
    of ``frontends`` (see :func:`frontends_for`) saw."""
    core = _core(env)
    obs, info = env.reset(seed=seed)
    # dead reckoning's pose at reset: the filter's start belief (reset's odometry is zero)
    believed_start = np.asarray(info["perception"]["odometry_pose"], dtype=np.float64).copy()
    for pipeline in frontends.values():
        if pipeline is not None:
            pipeline.reset(believed_start, np.random.default_rng(seed))
    times, deltas, poses = [], [], []
    seen: dict[str, list[tuple[LandmarkObservation, ...]]] = {name: [] for name in frontends}

    def record(info: dict[str, Any]) -> None:
        frame = core.sensor_frame
        times.append(frame.time_s)
        deltas.append(np.asarray(frame.odometry_delta, dtype=np.float64))
        poses.append(np.asarray(info["ground_truth"]["robot_pose"], dtype=np.float64))
        for name, pipeline in frontends.items():
            output = core.perception_output if pipeline is None else pipeline.step(frame)
            seen[name].append(output[POLE_SIGHTINGS])

    record(info)
    done, step = False, 0
    while not done:
        action, _ = policy.predict(obs, episode_start=np.array([step == 0]), deterministic=True)
        obs, _, terminated, truncated, info = env.step(action)
        record(info)
        done, step = terminated or truncated, step + 1
    gt = info["ground_truth"]
    return SightingLog(
        times_s=np.array(times),
        odometry_deltas=np.array(deltas),
        sightings={name: tuple(per_step) for name, per_step in seen.items()},
        true_poses=np.array(poses),
        believed_start=believed_start,
        landmark_ids=np.asarray(gt["landmark_ids"]),
        landmarks=np.asarray(gt["landmarks"], dtype=np.float64),
    )


def _core(env: gym.Env) -> SplEnv:
    """The SPL env ``env`` wraps; TypeError for any other env."""
    core = env.unwrapped
    if not isinstance(core, SplEnv):
        raise TypeError(f"env must wrap an SplEnv, got {type(core).__name__}")
    return core
