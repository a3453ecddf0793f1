"""Warm-start a PPO policy by imitating a scripted one (behaviour cloning), before PPO proper.

The teacher (a baseline of :data:`agents.baselines.BASELINES`) plays ``episodes`` episodes of the
training env; the policy's action mean is fitted to its actions and the value head to the
discounted returns that followed (mean squared errors, Adam). PPO then starts from the teacher's
behaviour instead of from a random head, which the per-step reward alone takes long to leave.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import gymnasium as gym
import numpy as np

from agents.baselines import BASELINES
from perception.validation import check_choice, check_int, check_positive


@dataclass(frozen=True)
class WarmStartConfig:
    """What to imitate and how long (``warm_start`` in a training config)."""

    teacher: str = "greedy_information"  # a name in agents.baselines.BASELINES
    episodes: int = 20  # teacher episodes recorded (seeds ``seed .. seed + episodes - 1``)
    epochs: int = 30  # passes over the recorded steps
    batch_size: int = 256
    learning_rate: float = 1e-3
    value_weight: float = 0.5  # weight of the value loss beside the action loss

    def __post_init__(self) -> None:
        owner = "WarmStartConfig"
        check_choice(owner, "teacher", self.teacher, tuple(BASELINES))
        for name in ("episodes", "epochs", "batch_size"):
            check_int(owner, name, getattr(self, name), 1)
        check_positive(owner, "learning_rate", self.learning_rate)
        check_positive(owner, "value_weight", self.value_weight, allow_zero=True)


@dataclass(frozen=True)
class Demonstrations:
    """N recorded steps: observations by key (N, ...), the teacher's actions (N, A), the
    discounted return from each step on (N,) and whether that return is a value target (N,):
    not within 3 / (1 - γ) steps of a time limit, where the rewards it would sum go on past
    the episode's end (PPO bootstraps there; a recorded return cannot)."""

    observations: dict[str, np.ndarray]
    actions: np.ndarray
    returns: np.ndarray
    value_mask: np.ndarray


def record_teacher(
    env: gym.Env, config: WarmStartConfig, gamma: float, seed: int
) -> Demonstrations:
    """Play ``config.episodes`` episodes of the teacher on ``env`` (seeds from ``seed``)."""
    teacher = BASELINES[config.teacher].from_config(env.get_wrapper_attr("config"))
    observations: list[dict[str, np.ndarray]] = []
    actions: list[np.ndarray] = []
    returns: list[np.ndarray] = []
    masks: list[np.ndarray] = []
    horizon = round(3.0 / (1.0 - gamma)) if gamma < 1.0 else 0
    for episode in range(config.episodes):
        obs, _ = env.reset(seed=seed + episode)
        rewards: list[float] = []
        done, first = False, True
        while not done:
            action, _ = teacher.predict(obs, episode_start=np.array([first]))
            observations.append(obs)
            actions.append(action)
            obs, reward, terminated, truncated, _ = env.step(action)
            rewards.append(float(reward))
            done, first = terminated or truncated, False
        returns.append(discounted_returns(np.array(rewards), gamma))
        mask = np.ones(len(rewards), dtype=bool)
        if truncated and not terminated:
            mask[max(len(rewards) - horizon, 0) :] = False
        masks.append(mask)
    return Demonstrations(
        observations={k: np.stack([o[k] for o in observations]) for k in observations[0]},
        actions=np.stack(actions).astype(np.float32),
        returns=np.concatenate(returns).astype(np.float32),
        value_mask=np.concatenate(masks),
    )


def discounted_returns(rewards: np.ndarray, gamma: float) -> np.ndarray:
    """G_t = r_t + γ G_{t+1} (T,) of one episode's rewards (T,), zero after its end."""
    out = np.zeros(len(rewards))
    following = 0.0
    for t in range(len(rewards) - 1, -1, -1):
        following = rewards[t] + gamma * following
        out[t] = following
    return out


def imitate(model: Any, demos: Demonstrations, config: WarmStartConfig, seed: int) -> list[float]:
    """Fit ``model``'s (an SB3 PPO with a Gaussian policy) action mean to the teacher's actions
    and its value to the returns; returns the mean loss of each epoch."""
    import torch
    from gymnasium import spaces

    if not isinstance(model.action_space, spaces.Box):
        raise TypeError(f"imitate needs a model with a Box action space, got {model.action_space}")
    policy = model.policy
    optimiser = torch.optim.Adam(policy.parameters(), lr=config.learning_rate)
    n = len(demos.actions)
    rng = np.random.default_rng(seed)
    obs_tensors = {k: torch.as_tensor(v) for k, v in demos.observations.items()}
    actions = torch.as_tensor(demos.actions)
    returns = torch.as_tensor(demos.returns)
    value_mask = torch.as_tensor(demos.value_mask, dtype=torch.float32)
    losses: list[float] = []
    policy.set_training_mode(True)
    for _ in range(config.epochs):
        order = rng.permutation(n)
        total = 0.0
        for start in range(0, n, config.batch_size):
            batch = torch.as_tensor(order[start : start + config.batch_size])
            obs = {k: v[batch] for k, v in obs_tensors.items()}
            mean = policy.get_distribution(obs).distribution.mean
            value = policy.predict_values(obs).squeeze(-1)
            weights = value_mask[batch]
            value_loss = torch.sum(weights * (value - returns[batch]) ** 2) / torch.clamp(
                torch.sum(weights), min=1.0
            )
            loss = torch.mean((mean - actions[batch]) ** 2) + config.value_weight * value_loss
            optimiser.zero_grad()
            loss.backward()
            optimiser.step()
            total += loss.item() * len(batch)
        losses.append(total / n)
    policy.set_training_mode(False)
    return losses
