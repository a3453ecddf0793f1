"""Visual heading odometry on rendered frames: a robot with a turn bias walks and turns in
place; the horizon's heading changes follow the true ones, the walk's do not."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np

import spl_env  # noqa: F401  (registers the env ids)


def test_visual_heading_follows_the_true_turns_of_a_veering_robot() -> None:
    env = gym.make(
        "SPL/ActiveVision-v1",
        frontend="colour",
        self_pose="oracle",
        body_behaviour="square",
        square_side_m=0.6,
        n_other_robots=0,
        **{
            "scene.poles_enabled": False,
            "perception.odometry": "visual",
            "robot.turn_bias_rad_per_m": 0.3,
        },
    )
    _, info = env.reset(seed=7)
    previous = info["ground_truth"]["robot_pose"][2]
    visual_errors, walk_sum, visual_sum, true_sum = [], 0.0, 0.0, 0.0
    for _ in range(60):  # straight legs and a corner turned in place
        _, _, _, _, info = env.step(np.zeros(2, dtype=np.float32))
        heading = info["ground_truth"]["robot_pose"][2]
        true_turn = math.remainder(heading - previous, math.tau)
        previous = heading
        odometry = info["perception"]
        if odometry["visual_heading"]:
            visual_errors.append(odometry["odometry_delta"][2] - true_turn)
        walk_sum += odometry["walk_odometry_delta"][2]
        visual_sum += odometry["odometry_delta"][2]
        true_sum += true_turn
    env.close()
    assert len(visual_errors) >= 40  # most frames' votes are confident
    assert np.sqrt(np.mean(np.square(visual_errors))) < math.radians(0.5)
    assert abs(true_sum) > math.radians(60)  # it did turn a corner
    assert abs(visual_sum - true_sum) < math.radians(3)
    assert abs(walk_sum - true_sum) > 2 * abs(visual_sum - true_sum)
