"""Kinematic placement (:class:`spl_env.sim.placement.Placement`): collisions with robots,
posts, poles and the carpet's edge, free poses, and one walking step that may be blocked."""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
import pytest

from spl_env.robots.nao import NaoRobot, RobotConfig
from spl_env.scenes.spl_field import SceneConfig, SplFieldScene
from spl_env.sim.placement import Placement
from spl_env.sim.world import BulletWorld

R = RobotConfig().body_radius_m


@dataclass
class Field:
    world: BulletWorld
    scene: SplFieldScene
    placement: Placement
    robots: list[NaoRobot]


@pytest.fixture(scope="module")
def field() -> Iterator[Field]:
    world = BulletWorld(time_step_s=0.01)
    scene = SplFieldScene(world, SceneConfig())
    robots = [NaoRobot(world, f"r{i}", team=i % 2, config=RobotConfig()) for i in range(3)]
    yield Field(world, scene, Placement(scene.dimensions, scene.obstacles, R), robots)
    world.close()


def test_obstacles_are_the_goal_posts_and_poles(field: Field) -> None:
    obstacles = field.placement.obstacles
    assert obstacles.shape == (4 + 6, 3)
    poles = obstacles[-6:]
    np.testing.assert_allclose(poles[:, :2], field.scene.landmarks)
    np.testing.assert_allclose(poles[:, 2], SceneConfig().poles.geometry.radius_m)
    dims = field.scene.dimensions
    np.testing.assert_allclose(np.abs(obstacles[:4, 0]), dims.half_length_m, atol=0.1)


def test_collides_with_the_carpet_edge_robots_and_obstacles(field: Field) -> None:
    placement, robots = field.placement, field.robots
    carpet_l, carpet_w = field.scene.dimensions.carpet_size_m
    robots[0].place(np.array([1.0, 1.0, 0.0]))
    free = np.array([-1.0, -1.0])
    assert not placement.collides(free, robots[:1], clearance=0.0)
    # the carpet's edge, less the robot's radius
    assert not placement.collides(np.array([carpet_l / 2 - R - 1e-6, 0.0]), [], clearance=0.0)
    assert placement.collides(np.array([carpet_l / 2 - R + 1e-6, 0.0]), [], clearance=0.0)
    assert placement.collides(np.array([0.0, -(carpet_w / 2 - R + 1e-6)]), [], clearance=0.0)
    # robots: two discs of radius R, plus the clearance asked for
    beside = np.array([1.0 + 2 * R + 0.01, 1.0])
    assert not placement.collides(beside, robots[:1], clearance=0.0)
    assert placement.collides(beside, robots[:1], clearance=0.02)
    assert placement.collides(np.array([1.0 + 2 * R - 0.01, 1.0]), robots[:1], clearance=0.0)
    # a pole: its radius plus ours
    x, y, radius = placement.obstacles[-1]
    towards_field = np.array([0.0, -math.copysign(1.0, y)])
    near = np.array([x, y]) + (R + radius - 0.01) * towards_field
    clear = np.array([x, y]) + (R + radius + 0.01) * towards_field
    assert placement.collides(near, [], clearance=0.0)
    assert not placement.collides(clear, [], clearance=0.0)


def test_free_poses_are_inside_the_field_and_clear(field: Field) -> None:
    placement, robots = field.placement, field.robots
    dims = field.scene.dimensions
    robots[0].place(np.array([0.0, 0.0, 0.0]))
    rng = np.random.default_rng(3)
    poses = np.array([placement.free_pose(rng, robots[:1]) for _ in range(200)])
    assert np.all(np.abs(poses[:, 0]) <= dims.half_length_m - 0.5)
    assert np.all(np.abs(poses[:, 1]) <= dims.half_width_m - 0.5)
    assert np.all(np.abs(poses[:, 2]) <= math.pi)
    assert np.all(np.hypot(poses[:, 0], poses[:, 1]) >= 2 * R + 0.3)  # clear of the placed one
    for pose in poses:
        assert not placement.collides(pose[:2], robots[:1], clearance=0.3)
    again = np.array([placement.free_pose(np.random.default_rng(3), robots[:1])])
    np.testing.assert_array_equal(again[0], poses[0])  # the draws come from the rng alone


def test_a_crowded_field_refuses_to_place() -> None:
    world = BulletWorld(time_step_s=0.01)
    scene = SplFieldScene(world, SceneConfig())
    giant = Placement(scene.dimensions, scene.obstacles, robot_radius_m=4.0)
    with pytest.raises(RuntimeError, match="too crowded"):
        giant.free_pose(np.random.default_rng(0), [])
    world.close()


def test_walk_moves_by_the_engine_increment_unless_blocked(field: Field) -> None:
    placement, (ours, other, _) = field.placement, field.robots
    ours.place(np.array([0.0, -2.0, 0.0]))
    other.place(np.array([3.0, -2.0, math.pi]))
    command = np.array([0.25, 0.0, 0.2])
    for _ in range(5):
        before = ours.pose.copy()
        increment, blocked = placement.walk(ours, command, 0.1, [other])
        assert not blocked
        x, y, th = before
        c, s = math.cos(th), math.sin(th)
        moved = [x + c * increment[0] - s * increment[1], y + s * increment[0] + c * increment[1]]
        np.testing.assert_allclose(ours.pose[:2], moved, atol=1e-12)
        assert ours.pose[2] == pytest.approx(th + increment[2])
    # now right in front of the other robot: the step would overlap, so the body stays
    ours.place(np.array([3.0 - 2 * R - 0.005, -2.0, 0.0]))
    ours.velocity = np.array([0.25, 0.0, 0.0])
    increment, blocked = placement.walk(ours, np.array([0.25, 0.0, 0.0]), 0.1, [other])
    assert blocked and increment[0] > 0.02  # the engine stepped...
    np.testing.assert_allclose(ours.pose, [3.0 - 2 * R - 0.005, -2.0, 0.0])  # ...the body did not
    np.testing.assert_array_equal(ours.velocity, np.zeros(3))  # and it stopped
    # the physics world follows the robot's pose
    np.testing.assert_allclose(field.world.position(ours.name)[:2], ours.pose[:2], atol=1e-9)


def test_obstruction_names_what_a_step_would_hit(field: Field) -> None:
    placement, robots = field.placement, field.robots
    robots[0].place(np.array([1.0, 1.0, 0.0]))
    assert placement.obstruction(np.array([-1.0, -1.0]), robots[:1], clearance=0.0) is None
    hit = placement.obstruction(np.array([1.0 + 2 * R - 0.01, 1.0]), robots[:1], clearance=0.0)
    np.testing.assert_allclose(hit, [1.0, 1.0])  # the other robot's centre
    carpet_l = field.scene.dimensions.carpet_size_m[0]
    edge = placement.obstruction(np.array([carpet_l / 2 - R + 0.01, 0.3]), [], clearance=0.0)
    np.testing.assert_allclose(edge, [carpet_l / 2, 0.3])  # the edge point beside it


def test_a_turn_bias_veers_the_body_but_not_the_engine() -> None:
    world = BulletWorld(time_step_s=0.01)
    bias = 0.2  # rad per metre
    robot = NaoRobot(world, "veering", team=0, config=RobotConfig(turn_bias_rad_per_m=bias))
    robot.place(np.array([0.0, 0.0, 0.0]))
    walked = 0.0
    for _ in range(30):
        increment = robot.walk_step(np.array([0.2, 0.0, 0.0]), 0.1)
        assert increment[2] == 0.0  # the engine believes it walks straight
        robot.commit_motion(increment)
        walked += float(np.hypot(increment[0], increment[1]))
    assert robot.pose[2] == pytest.approx(bias * walked, rel=1e-9)
    assert robot.pose[1] > 0.0  # veering left
    world.close()


def test_a_blocked_robot_pivots_away_from_what_it_hit(field: Field) -> None:
    world = BulletWorld(time_step_s=0.01)
    rate = 0.6
    robot = NaoRobot(world, "bumped", team=0, config=RobotConfig(bump_turn_rps=rate))
    other = NaoRobot(world, "wall", team=1, config=RobotConfig())
    placement = field.placement
    for side, turn in ((0.1, -1.0), (-0.1, 1.0)):  # contact to the left turns right
        robot.place(np.array([0.0, 0.0, 0.0]))
        other.place(np.array([2 * R - 0.01, side, 0.0]))
        robot.velocity = np.array([0.25, 0.0, 0.0])
        increment, blocked = placement.walk(robot, np.array([0.25, 0.0, 0.0]), 0.1, [other])
        assert blocked and increment[0] > 0.0
        np.testing.assert_allclose(robot.pose, [0.0, 0.0, turn * rate * 0.1], atol=1e-12)
    world.close()


def test_a_position_that_is_not_finite_is_refused_not_taken_as_clear(field: Field) -> None:
    with pytest.raises(ValueError, match="xy must be a finite"):
        field.placement.obstruction(np.array([math.nan, 0.0]), [], clearance=0.0)
