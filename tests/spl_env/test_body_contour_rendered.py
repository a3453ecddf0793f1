"""Perception's model of our own body (:data:`perception.vision.body_contour.NAO_BODY`) against
the simulated Nao: the same boxes, and in a rendered frame with the head turned to its right
limit and pitched down, our grey arm exactly where the silhouettes say.

The truth is the renderer's image: the robot stands still (no gait sway, so the camera state
its joints report is exact) on an empty field, where its view to the right holds no painted
line; pixels well inside a silhouette (3 px in from
its edge) must show the body's grey, pixels well outside (3 px out) the carpet's green. The
renderer draws the image a row higher than the camera model says, which the 3 px band covers.
"""

from __future__ import annotations

import cv2
import numpy as np

from perception.vision.body_contour import NAO_BODY, BodyContourConfig, body_silhouettes
from spl_env.robots.nao import NAO_GREY, NaoRobot, RobotConfig, _body_parts
from spl_env.scenes.spl_field import SceneConfig, build_scene
from spl_env.sensors.camera import Camera, CameraConfig, EpisodeLighting
from spl_env.sim.world import BulletWorld

BAND_PX = 3


def test_the_body_model_is_the_simulated_naos_boxes() -> None:
    parts = _body_parts(team=0, team_colours=True)
    assert all(p.shape == "box" and p.yaw == 0.0 for p in parts)
    simulated = sorted((tuple(p.position), tuple(p.size)) for p in parts)
    modelled = sorted((b.centre_m, b.half_extents_m) for b in NAO_BODY)
    assert simulated == modelled


def test_our_arm_shows_where_its_silhouette_says() -> None:
    world = BulletWorld(time_step_s=0.01)
    try:
        build_scene(world, SceneConfig(), np.random.default_rng(0))
        robot = NaoRobot(world, "self", team=0, config=RobotConfig())
        robot.place(np.array([1.5, -0.5, 0.0]), head=np.array([-1.55, 0.46]))
        world.set_pose("ball", (-4.6, 3.6, 0.05), 0.0)
        camera = Camera(CameraConfig())
        position, rotation = robot.camera_pose_world()
        image, _ = camera.render(
            world, position, rotation, EpisodeLighting.default(), np.random.default_rng(0)
        )
        model = camera.config.model
        mask = np.zeros((model.height, model.width), dtype=np.uint8)
        for silhouette in body_silhouettes(BodyContourConfig(), model, robot.camera_state()):
            polygon = np.clip(silhouette, -1e4, 1e4).round().astype(np.int32)
            cv2.fillPoly(mask, [polygon.reshape(-1, 1, 2)], 1)
    finally:
        world.close()
    kernel = np.ones((2 * BAND_PX + 1, 2 * BAND_PX + 1), dtype=np.uint8)
    inside = cv2.erode(mask, kernel).astype(bool)
    outside = ~cv2.dilate(mask, kernel).astype(bool)
    outside[: model.height // 2] = False  # the image's lower half: only carpet beside the arm
    assert inside.sum() > 2000  # the arm fills much of the image's lower part
    grey = 255 * np.array(NAO_GREY[:3])
    colour_gap = np.abs(image.astype(float) - grey).max(axis=2)
    assert np.median(colour_gap[inside]) < 25
    assert (colour_gap[inside] < 60).mean() > 0.99
    assert (colour_gap[outside] > 60).mean() > 0.99
