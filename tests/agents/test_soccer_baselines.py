"""The scripted soccer players run in their envs and act inside the action space; the
goalie-aware striker's aim on known geometry."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import spl_env  # noqa: F401  (registers the ids)
from agents.soccer_baselines import SOCCER_BASELINES, wider_gap_middle

PLAYERS = [
    ("SPL/PenaltyShootout-v0", "centre_kick"),
    ("SPL/PenaltyShootout-v0", "goalie_aware"),
    ("SPL/Striker-v0", "goalie_aware"),
    ("SPL/Goalie-v0", "goalie"),
]


@pytest.mark.parametrize(("env_id", "player"), PLAYERS)
def test_players_act_inside_the_action_space(env_id: str, player: str) -> None:
    env = gym.make(env_id, camera_mode="geometric", frontend="colour", episode_s=5.0)
    policy = SOCCER_BASELINES[player].from_config(env.get_wrapper_attr("config"))
    obs, _ = env.reset(seed=0)
    moved = False
    for step in range(50):
        action, _ = policy.predict(obs, episode_start=np.array([step == 0]))
        assert env.action_space.contains(action), action
        moved |= bool(np.any(action[:3] != 0))
        obs, _, terminated, truncated, _ = env.step(action)
        if terminated or truncated:
            break
    assert moved
    env.close()


def test_the_penalty_taker_walks_up_and_kicks() -> None:
    """From 1.2 m behind the ball the centre-kicking striker kicks within 20 s: the ball leaves
    the mark faster than 1 m/s."""
    env = gym.make("SPL/PenaltyShootout-v0", camera_mode="geometric", frontend="colour")
    policy = SOCCER_BASELINES["centre_kick"].from_config(env.get_wrapper_attr("config"))
    obs, info = env.reset(seed=5)
    fastest, done = 0.0, False
    while not done:
        action, _ = policy.predict(obs)
        obs, _, terminated, truncated, info = env.step(action)
        fastest = max(fastest, float(np.hypot(*info["ground_truth"]["ball_velocity"])))
        done = terminated or truncated
    assert fastest > 1.0
    env.close()


@pytest.mark.parametrize(
    ("goalie_y", "expected"),
    [
        (0.3, (-0.7 + 0.1) / 2),  # gaps [0.5, 0.7] and [-0.7, 0.1]: the right one
        (-0.3, (-0.1 + 0.7) / 2),  # the mirror image
        (0.0, (0.2 + 0.7) / 2),  # equal gaps: the left (the first) one
        (0.9, 0.0),  # a goalie beyond the post: the left gap is empty, the right one whole
    ],
)
def test_the_goalie_aware_aim_is_the_middle_of_the_wider_gap(
    goalie_y: float, expected: float
) -> None:
    """Posts at ±0.7 m, a goalie blocking 0.2 m to either side, gaps worked out by hand."""
    assert wider_gap_middle(goalie_y, 0.7, 0.2) == pytest.approx(expected)
