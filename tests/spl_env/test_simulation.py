"""The simulation loop: motion blur rate, collisions, config overrides."""

from __future__ import annotations

import math

import numpy as np
import pytest

from spl_env.config import EnvConfig, with_overrides
from spl_env.simulation import SimConfig, SplSimulation


def test_camera_turn_rate_is_wrapped_across_pi(monkeypatch: pytest.MonkeyPatch) -> None:
    sim = SplSimulation(SimConfig(n_other_robots=0))
    rates: list[float] = []
    render = sim.camera.render

    def spy(*args, yaw_rate_rps: float = 0.0, **kwargs):
        rates.append(yaw_rate_rps)
        return render(*args, yaw_rate_rps=yaw_rate_rps, **kwargs)

    monkeypatch.setattr(sim.camera, "render", spy)
    sim.reset(np.random.default_rng(0), np.array([0.0, 0.0, math.pi - 0.02]))
    for _ in range(10):  # turn left in place through +pi
        sim.step(np.array([0.0, 0.0, 0.5]), np.zeros(2))
    sim.close()
    assert sim.robot.pose[2] < 0  # it did cross
    assert max(abs(r) for r in rates) <= 0.5 + 1e-9


def test_robots_never_overlap() -> None:
    sim = SplSimulation(SimConfig(n_other_robots=4))
    sim.reset(np.random.default_rng(3), np.array([0.0, 0.0, 0.0]))
    r = sim.config.robot.body_radius_m
    for _ in range(100):
        state, _, _ = sim.step(np.array([0.25, 0.0, 0.2]), np.zeros(2))
        xy = np.vstack([state.robot_pose[:2], state.robots[:, :2]])
        d = np.hypot(*(xy[:, None, :] - xy[None, :, :]).transpose(2, 0, 1))
        assert d[np.triu_indices(len(xy), 1)].min() >= 2 * r - 1e-9
    sim.close()


def test_overrides_apply_together_in_any_order() -> None:
    a = with_overrides(EnvConfig(), physics_dt_s=0.05, control_dt_s=0.2, episode_s=2.0)
    b = with_overrides(EnvConfig(), episode_s=2.0, control_dt_s=0.2, physics_dt_s=0.05)
    assert a == b and a.sim.control_dt_s == 0.2 and a.max_steps == 10
    assert with_overrides(EnvConfig(), noise_std=0).sim.camera.noise_std == 0.0


@pytest.mark.parametrize(
    "overrides, match",
    [
        ({"episode_s": "30"}, "episode_s.*float.*str"),
        ({"n_other_robots": 2.5}, "n_other_robots.*int"),
        ({"randomise_lighting": 1}, "randomise_lighting.*bool"),
        ({"no_such_field": 1}, "unknown"),
        ({"noise_std": 0.0, "sim.camera": None}, "both whole and by sub-field"),
    ],
)
def test_bad_overrides_raise_type_errors(overrides: dict, match: str) -> None:
    with pytest.raises(TypeError, match=match):
        with_overrides(EnvConfig(), **overrides)


@pytest.mark.parametrize(
    "overrides, match",
    [
        ({"episode_s": 0.15}, "whole number"),
        ({"poles_enabled": False}, "poles_enabled"),
        ({"physics_dt_s": 0.2, "control_dt_s": 0.4}, "physics_dt_s"),
        ({"offset_outside_m": 0.69}, "border strip"),
    ],
)
def test_bad_values_raise_value_errors(overrides: dict, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        with_overrides(EnvConfig(), **overrides)
