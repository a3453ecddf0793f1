"""A change detector: ``SPL/ActiveVision-v0`` reproduces recorded rollouts bit for bit.

Not evidence of correctness (the reference is a run of this code, recorded again whenever a
deliberate change moved it; the independent checks of rewards, geometry and NEES live in the
other tests): it catches any change to the step loop, the sensors or the perception that was
meant to leave rollouts alone.

``reference/active_vision_v0_reference.npz`` was written by this module's :func:`main`
(``python tests/spl_env/test_reference_rollouts.py PATH``) at the commit before the reshaping
(``SplSimulation`` and the old pipeline, commit b95a6d7), and the reshaped env matched it to
1e-9 through commit 76aec20. It was recorded again when the sonar's rays began to pass through
our own robot's body (which until then stopped some of them while the torso swayed): what the
sonar hears changed, and with it the random stream. For the same seed and actions, today's
observations, rewards, SLAM poses and true poses must match it to 1e-9. The default (CNN)
front end runs a torch network whose float32 kernels round differently on different CPU
instruction sets (AVX2 / AVX-512): that case is held to 1e-6, a few float32 ulps.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import pytest

import spl_env  # noqa: F401

REFERENCE = Path(__file__).parent / "reference" / "active_vision_v0_reference.npz"
CASES: dict[str, dict[str, Any]] = {
    "rendered": {},
    "rendered_colour_lighting": {
        "frontend": "colour",
        "randomise_lighting": True,
        "body_behaviour": "square",
    },
    "geometric": {"camera_mode": "geometric", "frontend": "colour"},
}
ABSOLUTE_TOLERANCE = {"rendered": 1e-6, "rendered_colour_lighting": 1e-9, "geometric": 1e-9}
SEED, STEPS = 11, 40


def rollout(kwargs: dict[str, Any], actions: np.ndarray) -> dict[str, np.ndarray]:
    """Observations (T+1, K) with keys in sorted order, rewards (T,), SLAM and true poses
    (T+1, 3) of one episode from ``reset(seed=SEED)`` with ``actions`` (T, 2)."""
    env = gym.make("SPL/ActiveVision-v0", **kwargs)
    obs, info = env.reset(seed=SEED)
    rows: dict[str, list[Any]] = {"observations": [], "pose": [], "true_pose": [], "rewards": []}

    def record(obs: dict[str, np.ndarray], info: dict[str, Any]) -> None:
        rows["observations"].append(np.concatenate([obs[k] for k in sorted(obs)]))
        rows["pose"].append(info["perception"]["pose"])
        rows["true_pose"].append(info["ground_truth"]["robot_pose"])

    record(obs, info)
    for action in actions:
        obs, reward, _, _, info = env.step(action)
        record(obs, info)
        rows["rewards"].append(reward)
    env.close()
    return {name: np.array(values) for name, values in rows.items()}


@pytest.mark.parametrize("case", sorted(CASES))
def test_rollout_matches_the_recorded_reference(case: str) -> None:
    ref = np.load(REFERENCE)
    got = rollout(CASES[case], ref[f"{case}__actions"])
    for name, values in got.items():
        np.testing.assert_allclose(
            values, ref[f"{case}__{name}"], rtol=0, atol=ABSOLUTE_TOLERANCE[case], err_msg=name
        )


def main(path: str) -> None:
    """Record every case with seeded random head actions to ``path`` (npz)."""
    out: dict[str, np.ndarray] = {}
    for case, kwargs in CASES.items():
        actions = np.random.default_rng(7).uniform(-1, 1, size=(STEPS, 2)).astype(np.float32)
        out[f"{case}__actions"] = actions
        for name, values in rollout(kwargs, actions).items():
            out[f"{case}__{name}"] = values
    np.savez_compressed(path, **out)


if __name__ == "__main__":
    main(sys.argv[1])
