"""Both front ends run inside the env on rendered frames, and both agree with the truth."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import spl_env  # noqa: F401  (registers the env ids)
from perception.metrics import landmark_range_bearing
from perception.representations import POLE_SIGHTINGS


@pytest.mark.parametrize("frontend", ["colour", "cnn"])
def test_front_end_sightings_in_the_env_match_the_truth(frontend: str) -> None:
    env = gym.make("SPL/ActiveVision-v0", frontend=frontend, backend="classic", episode_s=3.0)
    _, info = env.reset(seed=3)
    matched, near = 0, 0
    for step in range(30):
        yaw = 0.8 * np.sin(2 * np.pi * step / 30)
        _, _, _, _, info = env.step(np.array([yaw, 0.0], dtype=np.float32))
        gt = info["ground_truth"]
        truth = landmark_range_bearing(gt["robot_pose"], gt["landmark_ids"], gt["landmarks"])
        per = info["perception"]
        assert per["sightings"].shape == (6, 2) and per["sighted"].shape == (6,)
        assert np.all(per["sightings"][~per["sighted"]] == 0.0)  # unseen rows are zero
        sightings = env.unwrapped.perception_output[POLE_SIGHTINGS]
        assert per["landmark_ids"][per["sighted"]].tolist() == [s.landmark_id for s in sightings]
        for row in np.flatnonzero(per["sighted"]):
            landmark_id = int(per["landmark_ids"][row])
            range_m, bearing = per["sightings"][row]
            true_range, true_bearing = truth[landmark_id]
            if true_range < 5.0:  # the detectors' stated working range
                near += 1
                good_range = abs(range_m - true_range) < 0.25 * true_range
                matched += good_range and abs(bearing - true_bearing) < 0.05
    env.close()
    assert near >= 5 and matched >= 0.9 * near, (matched, near)
    assert np.all(np.isfinite(info["perception"]["pose"]))
