"""The simulation loop: motion blur rate, collisions, config overrides."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from spl_env.config import EnvConfig, with_overrides
from spl_env.simulation import SimConfig, SplSimulation


def test_camera_turn_rate_is_wrapped_across_pi(monkeypatch: pytest.MonkeyPatch) -> None:
    sim = SplSimulation(SimConfig(n_other_robots=0))
    rates: list[float] = []
    render = sim.camera.render

    def spy(
        world: Any, position: Any, rotation: Any, lighting: Any, rng: Any, yaw_rate_rps: float = 0.0
    ) -> Any:
        rates.append(yaw_rate_rps)
        return render(world, position, rotation, lighting, rng, yaw_rate_rps=yaw_rate_rps)

    monkeypatch.setattr(sim.camera, "render", spy)
    sim.reset(np.random.default_rng(0), np.array([0.0, 0.0, math.pi - 0.02]))
    for _ in range(10):  # turn left in place through +pi
        sim.step(np.array([0.0, 0.0, 0.5]), np.zeros(2))
    sim.close()
    assert sim.robot.pose[2] < 0  # it did cross
    assert max(abs(r) for r in rates) <= 0.5 + 1e-9
    # reset, then the 2 rad/s^2 acceleration limit ramps 0.2, 0.4 up to the commanded 0.5 rad/s
    assert rates[:4] == pytest.approx([0.0, 0.2, 0.4, 0.5])
    assert rates[-1] == pytest.approx(0.5)


def test_walking_into_a_robot_blocks_without_overlap_while_odometry_slips() -> None:
    sim = SplSimulation(SimConfig(n_other_robots=1))
    sim.reset(np.random.default_rng(0), np.array([0.0, 0.0, 0.0]))
    sim.others[0].place(np.array([0.4, 0.0, math.pi]))  # 0.4 m straight ahead, facing us
    r = sim.config.robot.body_radius_m
    blocked_steps, odometry_forward_while_blocked = 0, 0.0
    for _ in range(20):
        before = sim.robot.pose.copy()
        state, frame, _ = sim.step(np.array([0.25, 0.0, 0.0]), np.zeros(2))
        assert math.dist(state.robot_pose[:2], state.robots[0, :2]) >= 2 * r - 1e-9
        if state.blocked:
            blocked_steps += 1
            np.testing.assert_allclose(state.robot_pose, before)  # the body did not move...
            odometry_forward_while_blocked += float(frame.odometry_delta[0])
    sim.close()
    assert blocked_steps >= 5  # 0.1 m of gap closes within ~7 steps at <= 0.25 m/s
    # ...but the walk engine believes it stepped, so odometry keeps reporting forward motion
    assert odometry_forward_while_blocked > 0.02


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
