"""Colour-filter pole detector on frames rendered from the full scene, against the labels.

The truth is independent of the detector: which poles are in view comes from the renderer's
body-id labels, their range and bearing from the field layout and the robot's placed pose.

The scene's posters are drawn with ``POSTER_SEED``, which hangs none of ``poster_01`` (its
background is the poles' own pink) and no pink poster area right behind a pole's pink band: a
pink band seen against the same pink cannot be told apart by colour, a blind spot of colour
filtering whose cost over many poster draws is measured by
``benchmarks/colour_filter_accuracy.py``, not asserted here.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
import pytest

from perception.geometry import FloatArray, range_bearing, wrap_angle
from perception.types import LandmarkObservation
from perception.vision import ColourFilterConfig, ColourPoleDetector
from spl_env.robots.nao import NaoRobot, RobotConfig
from spl_env.scenes.spl_field import SceneBodies, SceneConfig, build_scene
from spl_env.sensors.camera import Camera, CameraConfig, EpisodeLighting, LightingRandomisation
from spl_env.sim.world import BulletWorld

NEAR_M = 5.0  # every fully visible pole nearer than this must be found, within these errors:
RANGE_REL_TOL = 0.10
BEARING_TOL_RAD = math.radians(2.0)
FAR_RANGE_REL_TOL = 0.25  # beyond NEAR_M the bands' spacing is ~10 px: 1 px is 10 % of range
POSTER_SEED = 0


@dataclass
class Rig:
    """World with the scene, the observing robot, its camera and the detector."""

    world: BulletWorld
    scene: SceneConfig
    bodies: SceneBodies
    robot: NaoRobot
    camera: Camera
    detector: ColourPoleDetector
    poles: FloatArray  # (6, 2) field positions, id order

    def look(
        self,
        pose: FloatArray,
        head: FloatArray,
        lighting: EpisodeLighting,
        rng: np.random.Generator,
    ) -> tuple[list[LandmarkObservation], np.ndarray]:
        """Place the robot, render, detect: observations and the (H, W) body-id labels."""
        self.robot.place(pose, head=head)
        position, rotation = self.robot.camera_pose_world()
        image, labels = self.camera.render(self.world, position, rotation, lighting, rng)
        return self.detector.detect(image, self.robot.camera_state()), labels


@pytest.fixture(scope="module")
def rig() -> Iterator[Rig]:
    world = BulletWorld(time_step_s=0.01)
    scene = SceneConfig()
    bodies = build_scene(world, scene, np.random.default_rng(POSTER_SEED))
    robot = NaoRobot(world, "self", team=0, config=RobotConfig())
    NaoRobot(world, "other", team=0, config=RobotConfig()).place(np.array([-1.5, -1.2, 0.5]))
    camera = Camera(CameraConfig())
    layout = scene.poles
    detector = ColourPoleDetector(
        ColourFilterConfig(), camera.config.model, layout.codes(), layout.geometry
    )
    yield Rig(world, scene, bodies, robot, camera, detector, layout.positions(scene.dimensions))
    world.close()


def pole_visibility(rig: Rig, labels: np.ndarray) -> dict[int, tuple[bool, bool]]:
    """Per pole id: (any pixel in view, both bands and the base's top 5 cm fully visible).

    Fully visible: points across the pole's side facing the camera over those heights all
    project inside the image, and at least 90 % of those off the outline show the pole's body.
    """
    model = rig.camera.config.model
    geometry = rig.scene.poles.geometry
    eye, rotation = rig.robot.camera_pose_world()
    lateral = np.linspace(-1.0, 1.0, 9)
    heights = np.linspace(geometry.base_top_m - 0.05, geometry.top_m, 25)
    s, z = (a.ravel() for a in np.meshgrid(lateral, heights))
    out = {}
    for landmark_id, name in rig.bodies.poles.items():
        xy = rig.poles[landmark_id]
        view = (xy - eye[:2]) / np.linalg.norm(xy - eye[:2])
        side = np.array([-view[1], view[0]])
        across = s[:, None] * side - np.sqrt(1.0 - s[:, None] ** 2) * view
        points = np.column_stack([xy + geometry.radius_m * across, z])
        cam = (points - eye) @ rotation
        depth = np.where(cam[:, 0] > 1e-6, cam[:, 0], np.nan)
        u = model.cx - model.fx * cam[:, 1] / depth
        v = model.cy - model.fy * cam[:, 2] / depth
        inside = (u >= 1) & (u < model.width - 1) & (v >= 1) & (v < model.height - 1)
        body = rig.world.body(name)
        inner = inside & (np.abs(s) < 1.0)
        seen = labels[v[inner].astype(int), u[inner].astype(int)] == body
        fully = bool(inside.all() and seen.mean() >= 0.9)
        out[landmark_id] = (bool(np.any(labels == body)), fully)
    return out


def check_frame(
    rig: Rig,
    observations: list[LandmarkObservation],
    labels: np.ndarray,
) -> set[int]:
    """Assert the sightings of a frame; returns the poles that had to be found.

    Those are the fully visible poles within NEAR_M. Every sighting must be of a pole in view,
    within the range and bearing tolerances.
    """
    truth = range_bearing(rig.robot.pose, rig.poles)
    visibility = pole_visibility(rig, labels)
    must = {i for i, (_, fully) in visibility.items() if fully and truth[i, 0] <= NEAR_M}
    found = {o.landmark_id for o in observations}
    assert must <= found, f"missed poles {must - found}"
    for obs in observations:
        true_range, true_bearing = truth[obs.landmark_id]
        assert visibility[obs.landmark_id][0], f"pole {obs.landmark_id} is not in view"
        tolerance = RANGE_REL_TOL if true_range <= NEAR_M else FAR_RANGE_REL_TOL
        assert abs(obs.range_m - true_range) < tolerance * true_range
        assert abs(wrap_angle(obs.bearing_rad - true_bearing)) < BEARING_TOL_RAD
    return must


def facing_pose(
    rig: Rig, landmark_id: int, distance_m: float, approach_rad: float, offset_rad: float
) -> FloatArray:
    """Robot pose ``distance_m`` from a pole, seeing it at bearing ``offset_rad``.

    ``approach_rad`` turns the line from the pole to the robot away from the field's inward
    normal at the pole.
    """
    xy = rig.poles[landmark_id]
    inward = -math.copysign(1.0, xy[1]) * math.pi / 2 + approach_rad
    position = xy + distance_m * np.array([math.cos(inward), math.sin(inward)])
    heading = math.atan2(xy[1] - position[1], xy[0] - position[0]) - offset_rad
    return np.array([position[0], position[1], heading])


@pytest.mark.parametrize("distance_m", [1.0, 2.0, 3.0, 4.0])
@pytest.mark.parametrize("landmark_id", range(6))
def test_finds_the_visible_poles(rig: Rig, landmark_id: int, distance_m: float) -> None:
    rng = np.random.default_rng(landmark_id)
    required: set[int] = set()
    for approach, offset, head in (
        (0.0, 0.0, (0.0, -0.05)),
        (-0.5, 0.25, (0.0, 0.05)),
        (0.5, -0.2, (0.3, 0.1)),
    ):
        pose = facing_pose(rig, landmark_id, distance_m, approach, offset + head[0])
        observations, labels = rig.look(pose, np.array(head), EpisodeLighting.default(), rng)
        required |= check_frame(rig, observations, labels)
    assert landmark_id in required, "test setup: the pole must be fully visible at least once"


@pytest.mark.parametrize(
    ("pose", "head"),
    [
        ((0.0, 0.0, 0.0), (0.0, 0.45)),  # centre circle, looking down
        ((-1.0, 0.0, math.pi), (0.0, 0.3)),
        ((3.5, 0.0, 0.0), (0.0, 0.2)),  # towards a goal: white posts, poster boards
    ],
)
def test_empty_field_gives_nothing(
    rig: Rig, pose: tuple[float, ...], head: tuple[float, float]
) -> None:
    observations, labels = rig.look(
        np.array(pose), np.array(head), EpisodeLighting.default(), np.random.default_rng(0)
    )
    assert not any(in_view for in_view, _ in pole_visibility(rig, labels).values())
    assert observations == []


@pytest.mark.parametrize("seed", range(8))
def test_randomised_lighting_finds_and_measures(rig: Rig, seed: int) -> None:
    """Under randomised lighting (glare included) the poles must still be found and measured."""
    rng = np.random.default_rng(seed)
    lighting = EpisodeLighting.sample(LightingRandomisation(), rng)
    dimensions = SceneConfig().dimensions
    half_length, half_width = dimensions.half_length_m, dimensions.half_width_m
    while True:  # a view from the field (a draw behind the goal line may not see the pole)
        pose = facing_pose(
            rig, seed % 6, rng.uniform(1.0, 4.0), rng.uniform(-0.6, 0.6), rng.uniform(-0.3, 0.3)
        )
        if abs(pose[0]) <= half_length and abs(pose[1]) <= half_width:
            break
    observations, labels = rig.look(pose, np.zeros(2), lighting, rng)
    assert seed % 6 in check_frame(rig, observations, labels), "the pole must be found"
