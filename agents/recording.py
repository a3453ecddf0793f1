"""Record an episode's odometry, every front end's sightings and the ground truth.

The recording (:class:`perception.replay.SightingLog`) is what seed 000's experiments replay
through each back end: rendering happens once, and every front end reads the same frames.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping

import gymnasium as gym
import numpy as np

from agents.evaluate import Policy
from perception.pipeline import FrontEnd, make_frontend
from perception.replay import SightingLog
from perception.types import LandmarkObservation
from spl_env.envs.active_vision import ActiveVisionEnv


def frontends_for(env: gym.Env, names: tuple[str, ...]) -> dict[str, FrontEnd]:
    """Front ends ``names`` (see :data:`perception.pipeline.FRONTENDS`) for ``env``'s camera,
    configured as ``env``'s perception config configures them."""
    core = _core(env)
    config = core.config
    return {
        name: make_frontend(
            dataclasses.replace(config.perception, frontend=name),
            config.sim.camera.model,
            core.codes,
            config.sim.scene.poles.geometry,
        )
        for name in names
    }


def record_episode(
    env: gym.Env, policy: Policy, seed: int, frontends: Mapping[str, FrontEnd]
) -> SightingLog:
    """Run one episode of ``policy`` on ``env`` and record what each of ``frontends`` saw."""
    core = _core(env)
    obs, info = env.reset(seed=seed)
    believed_start = core.perception.initial_pose.copy()
    times, deltas, poses = [], [], []
    seen: dict[str, list[tuple[LandmarkObservation, ...]]] = {name: [] for name in frontends}

    def record(info: dict) -> None:
        frame = core.sensor_frame
        times.append(frame.time_s)
        deltas.append(np.asarray(frame.odometry_delta, dtype=np.float64))
        poses.append(np.asarray(info["ground_truth"]["robot_pose"], dtype=np.float64))
        for name, frontend in frontends.items():
            seen[name].append(frontend.sightings(frame))

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


def _core(env: gym.Env) -> ActiveVisionEnv:
    core = env.unwrapped
    if not isinstance(core, ActiveVisionEnv):
        raise TypeError(f"env must wrap an ActiveVisionEnv, got {type(core).__name__}")
    return core
