"""The geometric mode's field features are hidden where a body stands between the camera and
the ground, as in a rendered frame: the emulator's occlusion rays in the SPL scene."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import pytest

from perception.field.field_map import FieldMap
from perception.field.visibility import FeatureViewConfig, visible_features
from perception.types import CameraModel
from spl_env.robots.nao import NaoRobot, RobotConfig
from spl_env.scenes.spl_field import SceneConfig, build_scene
from spl_env.sensors.emulation.field import occlusion
from spl_env.sim.world import BulletWorld

FIELD = FieldMap()
CAMERA = CameraModel()
VIEW = FeatureViewConfig()
POSE = np.array([-1.5, 0.0, 0.0])  # 1.5 m before the halfway line, facing it
NAO_ARMS_WIDTH_M = 0.27  # a Nao across its arms (perception.vision.robots' robot_width_m notes)


@pytest.fixture(scope="module")
def scene() -> Iterator[tuple[BulletWorld, NaoRobot, NaoRobot]]:
    world = BulletWorld(time_step_s=0.01)
    build_scene(world, SceneConfig(), np.random.default_rng(0))
    ours = NaoRobot(world, "self", team=0, config=RobotConfig())
    other = NaoRobot(world, "other", team=1, config=RobotConfig())
    ours.place(POSE, head=np.array([0.0, 0.35]))  # looking down at the halfway line
    world.set_pose("ball", (-4.6, 3.6, 0.05), 0.0)  # off the carpet's far corner
    yield world, ours, other
    world.close()


def halfway_line(world: BulletWorld, ours: NaoRobot) -> tuple[float, float]:
    """The halfway line's seen stretch as (low, high) robot-frame y (m)."""
    camera = ours.camera_pose_world()[0]
    features = visible_features(
        FIELD, ours.pose, CAMERA, ours.camera_state(), VIEW, occluded=occlusion(world, camera)
    )
    (line,) = [f for f in features if f.kind == "line" and abs(f.points[0, 0] - 1.5) < 0.01]
    low, high = sorted(line.points[:, 1])
    return low, high


def test_a_robot_between_camera_and_line_hides_the_stretch_behind_it(scene) -> None:
    world, ours, other = scene
    other.place(np.array([-5.0, 3.6, 0.0]))  # out of view: the whole line is seen
    low, high = halfway_line(world, ours)
    assert low < -0.5 and high > 0.5
    # 0.9 m ahead of us, 0.4 m to the left: taller than the camera is high, it hides the
    # ground behind it to the horizon, on the line around y = 0.4 * 1.5 / 0.9 = 0.67 m
    other.place(np.array([-0.6, 0.4, 0.0]))
    hidden_low, hidden_high = halfway_line(world, ours)
    assert hidden_low == pytest.approx(low, abs=1e-9)  # the longer clear stretch: the right
    shadow_centre = 0.4 * 1.5 / 0.9
    half_shadow = 0.5 * NAO_ARMS_WIDTH_M * 1.5 / 0.9  # the widest part, the arms, on the line
    assert shadow_centre - half_shadow - 0.05 < hidden_high < shadow_centre


def test_the_carpet_and_our_own_robot_hide_nothing(scene) -> None:
    world, ours, other = scene
    other.place(np.array([-5.0, 3.6, 0.0]))
    camera = ours.camera_pose_world()[0]
    ground = np.array([[-1.3, 0.0], [-1.0, 0.2], [0.0, -0.4], [1.0, 0.5]])
    assert not occlusion(world, camera)(ground).any()


def test_the_ball_on_the_penalty_mark_hides_it_and_a_post_does_not_hide_itself(scene) -> None:
    world, ours, other = scene
    posts = tuple(world.body(f"goal_post_{i}") for i in range(4))
    other.place(np.array([-5.0, 3.6, 0.0]))
    (mark,) = [f.points[0] for f in FIELD.of_kind("penalty_mark") if f.points[0, 0] > 0]
    ours.place(np.array([mark[0] - 1.2, 0.0, 0.0]), head=np.array([0.0, 0.35]))
    camera = ours.camera_pose_world()[0]
    occluded = occlusion(world, camera, posts)
    try:
        assert not occluded(mark[None])[0]
        world.set_pose("ball", (mark[0], mark[1], 0.05), 0.0)  # the ball on the mark
        assert occluded(mark[None])[0]
        # facing the goal, the posts' own points (inside them) are not hidden by the posts
        ours.place(np.array([mark[0] - 0.5, 0.0, 0.0]), head=np.array([0.0, 0.0]))
        feet = np.array([f.points[0] for f in FIELD.of_kind("goal_post") if f.points[0, 0] > 0])
        assert not occlusion(world, ours.camera_pose_world()[0], posts)(feet).any()
    finally:
        world.set_pose("ball", (-4.6, 3.6, 0.05), 0.0)
        ours.place(POSE, head=np.array([0.0, 0.35]))
