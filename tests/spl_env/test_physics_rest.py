"""BulletWorld skips the physics only while a step would change nothing (a resting ball)."""

from __future__ import annotations

from collections.abc import Iterator

import gymnasium as gym
import numpy as np
import pybullet as p
import pytest

import spl_env  # noqa: F401  (registers the env ids)
from spl_env.sim.world import REST_CLEARANCE_M, BulletWorld, VisualPart

RADIUS = 0.05
GREY = (0.5, 0.5, 0.5, 1.0)


def make_world(gravity_mps2: float = 9.81) -> BulletWorld:
    """A 10 m floor slab, a ball on it at the origin and a box robot (mass 0) 2 m away."""
    world = BulletWorld(time_step_s=0.01, gravity_mps2=gravity_mps2)
    slab = VisualPart(shape="box", size=(5.0, 5.0, 0.01), position=(0.0, 0.0, -0.01), rgba=GREY)
    world.add_static("floor", [slab])
    world.add_sphere(
        "ball",
        radius_m=RADIUS,
        mass_kg=0.044,
        position=(0.0, 0.0, RADIUS),
        rgba=GREY,
        rolling_friction=0.0015,
        restitution=0.3,
    )
    box = VisualPart(shape="box", size=(0.1, 0.1, 0.2), position=(0.0, 0.0, 0.2), rgba=GREY)
    world.add_static("mover", [box])
    world.set_pose("mover", (2.0, 0.0, 0.0), 0.0)
    return world


def ball_state(world: BulletWorld) -> np.ndarray:
    """Position (3,), orientation (4,), linear and angular velocity (6,) of the ball."""
    body = world.body("ball")
    pos, orn = p.getBasePositionAndOrientation(body, physicsClientId=world.client)
    linear, angular = p.getBaseVelocity(body, physicsClientId=world.client)
    return np.array([*pos, *orn, *linear, *angular])


@pytest.fixture
def world() -> Iterator[BulletWorld]:
    world = make_world()
    yield world
    world.close()


def test_a_placed_ball_is_simulated_until_it_settles_then_stepping_would_change_nothing(
    world: BulletWorld,
) -> None:
    assert not world.at_rest()  # just placed: it must settle on the floor first
    world.step(10)
    assert world.at_rest()
    settled = ball_state(world)
    world.step(10)  # skipped
    np.testing.assert_array_equal(ball_state(world), settled)
    for _ in range(100):  # what the skipped steps would have done: nothing measurable
        p.stepSimulation(physicsClientId=world.client)
    np.testing.assert_allclose(ball_state(world), settled, atol=1e-12)


def test_a_rolling_ball_is_simulated(world: BulletWorld) -> None:
    world.step(10)
    world.set_velocity("ball", (1.0, 0.0, 0.0))
    assert not world.at_rest()
    world.step(10)
    assert not world.at_rest()
    x, _ = world.position("ball")[:2]
    assert 0.05 < x < 0.1  # rolled about 0.1 s at a little under 1 m/s


def test_a_body_moved_near_the_ball_is_simulated_and_pushes_it(world: BulletWorld) -> None:
    world.step(10)
    world.set_pose("mover", (0.5, 0.0, 0.0), 0.0)  # 0.35 m between the box and the ball
    assert world.at_rest()
    gap = 0.8 * REST_CLEARANCE_M
    world.set_pose("mover", (0.1 + RADIUS + gap, 0.0, 0.0), 0.0)
    assert not world.at_rest()
    world.set_pose("mover", (0.1 + RADIUS - 0.02, 0.0, 0.0), 0.0)  # into the ball
    world.step(10)
    assert world.position("ball")[0] < -0.01  # pushed away from the box


def test_a_resting_body_out_of_contact_is_simulated() -> None:
    world = make_world(gravity_mps2=0.0)
    world.set_pose("ball", (0.0, 0.0, 1.0), 0.0)  # floating, still: nothing holds it there
    world.step(1)
    assert np.allclose(world.velocity("ball"), 0.0) and not world.at_rest()
    world.close()


def test_a_body_created_behind_the_worlds_back_is_simulated(world: BulletWorld) -> None:
    world.step(10)
    assert world.at_rest()
    shape = p.createCollisionShape(p.GEOM_SPHERE, radius=0.1, physicsClientId=world.client)
    p.createMultiBody(
        baseMass=1.0,
        baseCollisionShapeIndex=shape,
        basePosition=[3.0, 3.0, 1.0],
        physicsClientId=world.client,
    )
    assert not world.at_rest()


def test_a_restored_state_is_simulated(world: BulletWorld) -> None:
    snapshot = world.save_state()
    world.step(10)
    assert world.at_rest()
    world.restore_state(snapshot)
    assert not world.at_rest()


def test_penalty_episodes_match_those_stepped_throughout(monkeypatch: pytest.MonkeyPatch) -> None:
    """A geometric penalty (the scripted striker walks up, kicks, the ball rolls and stops):
    the same observations and ball with the resting skip as with every physics step taken,
    and the skip did skip steps."""
    import gymnasium as gym

    from agents.soccer_baselines import CentreKickStriker

    def episode() -> tuple[np.ndarray, int]:
        env = gym.make("SPL/PenaltyShootout-v0", camera_mode="geometric", frontend="colour")
        player = CentreKickStriker.from_config(env.unwrapped.config)
        obs, _ = env.reset(seed=4)
        rows, skipped = [], 0
        for _ in range(60):
            skipped += env.unwrapped.world.at_rest()
            obs, _, terminated, truncated, info = env.step(player.act(obs))
            rows.append(
                np.concatenate([*(obs[k] for k in sorted(obs)), info["ground_truth"]["ball"]])
            )
            if terminated or truncated:
                break
        env.close()
        return np.array(rows), skipped

    skipping, skipped = episode()
    monkeypatch.setattr(BulletWorld, "at_rest", lambda self: False)
    stepped, _ = episode()
    assert skipped > 5
    assert skipping.shape == stepped.shape
    np.testing.assert_allclose(skipping, stepped, atol=1e-6)


def test_the_same_seed_and_actions_replay_the_ball_whatever_ran_before() -> None:
    """In SPL/ActiveVision-v1 the walking robots push the ball about; the second episode of
    one env from the same seed must move it as the first did (a contact Bullet cached in the
    first episode had made it creep by about 2e-7 m a step in the second)."""
    env = gym.make("SPL/ActiveVision-v1", camera_mode="geometric", frontend="colour")
    rng = np.random.default_rng(42)
    actions = rng.uniform(-1.0, 1.0, (300, *env.action_space.shape)).astype(np.float32)

    def balls() -> np.ndarray:
        env.reset(seed=7)
        out = []
        for action in actions:
            env.step(action)
            out.append(env.unwrapped.world_state.ball.copy())  # type: ignore[attr-defined]
        return np.array(out)

    try:
        np.testing.assert_array_equal(balls(), balls())
    finally:
        env.close()
