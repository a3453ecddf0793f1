"""Robot sightings from the packaged CNN on rendered frames, against the robots' placed poses.

Each frame places our robot on the field with a random head pose and the three others 1-3 m
away at three bearings spread across the view, turned any way; a placement counts only if the
whole robot (its silhouette's box, from the corners of its body parts) lies inside the image,
its feet at least ``FEET_CLEARANCE_PX`` above the bottom edge, and its label box shows nothing
hides it. A robot is sighted when a sighting's box overlaps its label box.

Measured with this protocol on held-out seeds 1-16 (16 x 12 frames, 382 robots; this test runs
seed 0), the packaged CNN falls short of 10 % and 2 degrees for every robot:

- 94 % of the robots sighted (at least 83 % per seed): the CNN scores the others 0.18-0.39,
  below the detector's threshold of 0.4 (lower thresholds let in many more false robots);
- relative range error: mean -0.3 %, std 4.3 %, 97 % within 10 % (at least 92 % per seed),
  largest 15 %; the CNN's box bottom is off by 2-5 px on such robots;
- bearing error: std 0.65 degrees, 99 % within 2 degrees (at least 95 % per seed), largest
  2.2 degrees.

The bounds below sit just outside these numbers.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass

import gymnasium as gym
import numpy as np
import pytest

import spl_env  # noqa: F401  (registers the ids)
from perception.geometry import project_points, relative, transform_points, wrap_angle
from perception.providers.base import PerceptionContext
from perception.types import RobotSighting
from perception.vision.cnn_detector import box_iou
from perception.vision.cnn_robots import CnnRobotConfig, robot_sightings
from spl_env.envs.core import SplEnv
from spl_env.robots.nao import RobotConfig, _body_parts

N_OTHERS = 3
FRAMES = 24  # the held-out measurement drew 12 per seed
FEET_CLEARANCE_PX = 20.0  # true feet this far above the image bottom: clear of the cut rule
SLOTS_RAD = (-0.3, 0.0, 0.3)  # bearings of the others off the camera heading: apart in the image
# The label box of an unhidden robot lies this far (px) inside its silhouette's projected box
# (u0, v0, u1, v1): labelled pixel centres lie half a pixel inside, and the renderer's rows sit
# up to one pixel higher (perception.types.CameraModel). Within UNOCCLUDED_PX of that, nothing
# hides the robot.
LABEL_OFFSET_PX = np.array([0.5, -0.5, -0.5, -1.5])
UNOCCLUDED_PX = 1.0
MATCH_IOU = 0.3  # a sighting's box overlapping a robot's label box this much is of that robot
NAO = RobotConfig()


def body_corners() -> np.ndarray:
    """(N, 3) corners of every box of a standing Nao with its head straight (robot frame): its
    silhouette's extremes in any view are among them."""
    head_z = NAO.head_yaw_joint_height_m + NAO.head_pitch_joint_offset_m + 0.045
    head = (0.05, 0.065, 0.06), (0.0, 0.0, head_z)  # spl_env/robots/nao.py NaoRobot: the head
    boxes = [(part.size, part.position) for part in _body_parts(0, True)] + [head]
    signs = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)])
    return np.vstack([np.asarray(c) + signs * np.asarray(h) for h, c in boxes])


CORNERS = body_corners()


@dataclass(frozen=True)
class Seen:
    """One placed robot: its true range (m) and bearing (rad) and its sighting, if any."""

    range_m: float
    bearing_rad: float
    sighting: RobotSighting | None


@pytest.fixture(scope="module")
def env() -> Iterator[SplEnv]:
    made = gym.make("SPL/LookAround-v0", n_other_robots=N_OTHERS, episode_s=1.0)
    made.reset(seed=0)
    yield made.unwrapped  # type: ignore[misc]
    made.close()


def body_pixels(env: SplEnv, pose: np.ndarray) -> np.ndarray:
    """(N, 2) pixels in our camera of the body corners of a Nao at field ``pose`` (3,) with
    its head straight (NaN behind the camera)."""
    world = np.column_stack([transform_points(pose, CORNERS[:, :2]), CORNERS[:, 2]])
    position, rotation = env.robots[0].camera_pose_world()
    cam = env.rig.config.camera.model
    pixels, _ = project_points((world - position) @ rotation, cam.fx, cam.fy, cam.cx, cam.cy)
    return pixels


def projected_box(pixels: np.ndarray) -> np.ndarray:
    """(4,) box ``(u0, v0, u1, v1)`` around (N, 2) pixels."""
    return np.concatenate([pixels.min(axis=0), pixels.max(axis=0)])


def whole_in_view(env: SplEnv, box: np.ndarray) -> bool:
    """Whether a projected box (4,) lies inside the image, its bottom clear of the edge."""
    cam = env.rig.config.camera.model
    return bool(
        np.isfinite(box).all()
        and box[0] > 1.0
        and box[1] > 1.0
        and box[2] < cam.width - 2.0
        and box[3] < cam.height - 1.0 - FEET_CLEARANCE_PX
    )


def place_frame(env: SplEnv, rng: np.random.Generator) -> list[int]:
    """Place our robot and the others for one frame; returns the indices of the others placed
    whole in view (the rest stand far off the field)."""
    ours = np.array([rng.uniform(-3.0, 3.0), rng.uniform(-2.0, 2.0), rng.uniform(-np.pi, np.pi)])
    head = np.array([rng.uniform(-0.5, 0.5), rng.uniform(0.1, 0.45)])
    env.robots[0].place(ours, head=head)
    placed = []
    for k, slot in enumerate(SLOTS_RAD, start=1):
        env.robots[k].place(np.array([40.0 + 2 * k, 40.0, 0.0]))
        for _ in range(50):
            distance = rng.uniform(1.0, 3.0)
            heading = ours[2] + head[0] + slot + rng.uniform(-0.05, 0.05)
            xy = ours[:2] + distance * np.array([math.cos(heading), math.sin(heading)])
            pose = np.array([xy[0], xy[1], rng.uniform(-np.pi, np.pi)])
            if whole_in_view(env, projected_box(body_pixels(env, pose))):
                env.robots[k].place(pose)
                placed.append(k)
                break
    return placed


def measure(env: SplEnv, seed: int, frames: int) -> list[Seen]:
    """Sightings of every robot placed whole in view and unoccluded, over ``frames`` frames
    drawn from ``seed``."""
    rng = np.random.default_rng(seed)
    cam = env.rig.config.camera.model
    context = PerceptionContext(cam, env.scene.codes, env.config.scene.poles.geometry)
    detector = context.cnn_detector(env.config.perception.cnn)
    config = CnnRobotConfig()
    seen = []
    for _ in range(frames):
        placed = place_frame(env, rng)
        image, labels = env.rig.camera_view(env.world)
        state = env.robots[0].camera_state()
        sightings = robot_sightings(detector.detect_objects(image), cam, state, config)
        for k in placed:
            rows, cols = np.nonzero(labels == env.world.body(env.robots[k].name))
            if len(rows) == 0:
                continue
            label_box = np.array([cols.min(), rows.min(), cols.max(), rows.max()], np.float64)
            expected = projected_box(body_pixels(env, env.robots[k].pose))
            if np.max(np.abs(label_box - expected - LABEL_OFFSET_PX)) > UNOCCLUDED_PX:
                continue  # partly hidden (by another robot, a post, the ball)
            truth = relative(env.robots[0].pose, env.robots[k].pose)
            overlaps = [box_iou(s.box, label_box) for s in sightings]
            best = int(np.argmax(overlaps)) if overlaps else -1
            sighting = sightings[best] if best >= 0 and overlaps[best] >= MATCH_IOU else None
            seen.append(
                Seen(math.hypot(truth[0], truth[1]), math.atan2(truth[1], truth[0]), sighting)
            )
    return seen


def errors(seen: list[Seen]) -> tuple[np.ndarray, np.ndarray]:
    """Relative range errors and bearing errors (rad) of the sighted robots."""
    found = [s for s in seen if s.sighting is not None]
    rel = np.array([s.sighting.range_m / s.range_m - 1.0 for s in found])  # type: ignore[union-attr]
    bearing = np.array(
        [float(wrap_angle(s.sighting.bearing_rad - s.bearing_rad)) for s in found]  # type: ignore[union-attr]
    )
    return rel, bearing


def test_robots_in_view_are_sighted_at_their_range_and_bearing(env: SplEnv) -> None:
    seen = measure(env, seed=0, frames=FRAMES)
    assert len(seen) >= 20  # enough whole, unoccluded placements to mean something
    found = sum(s.sighting is not None for s in seen)
    assert found >= 0.8 * len(seen)
    rel, bearing = errors(seen)
    assert np.max(np.abs(rel)) < 0.18
    assert np.max(np.abs(bearing)) < math.radians(2.5)
    assert np.mean(np.abs(rel) < 0.10) >= 0.9
    assert np.mean(np.abs(bearing) < math.radians(2.0)) >= 0.95
    assert abs(float(np.mean(rel))) < 0.03  # no range bias: the centre offset is right
    for s in seen:
        if s.sighting is not None:
            assert s.sighting.team is None and not s.sighting.sonar_confirmed
