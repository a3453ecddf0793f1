"""Which provider each emulator stands in for, and the emulators of an env's configuration.

In the geometric camera mode nothing is rendered; a representation whose configured provider
has an emulator here is delivered by that emulator instead (truth plus noise fitted to the
rendered pipeline). A provider that reads images and has no emulator cannot run in that mode.
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Mapping

from perception.field.field_map import shared_field_map
from perception.pipeline import PipelineConfig
from perception.representations import (
    BALL_SIGHTINGS,
    FIELD_FEATURES,
    POLE_SIGHTINGS,
    ROBOT_SIGHTINGS,
)
from perception.vision.colour_filter import ColourPoleDetector
from spl_env.robots.nao import NaoRobot
from spl_env.scenes.spl_field import SplFieldScene
from spl_env.sensors.emulation.ball import GeometricBallSightings
from spl_env.sensors.emulation.field import GeometricFieldFeatures
from spl_env.sensors.emulation.poles import GeometricPoleCamera, GeometricPoleSightings
from spl_env.sensors.emulation.robots import GeometricRobotSightings
from spl_env.sensors.rig import Emulator, RigConfig

EmulatorFactory = Callable[[SplFieldScene, list[NaoRobot], RigConfig, PipelineConfig], Emulator]


def _colour_pole_sightings(
    scene: SplFieldScene, robots: list[NaoRobot], sensors: RigConfig, perception: PipelineConfig
) -> GeometricPoleSightings:
    model, geometry = sensors.camera.model, scene.config.poles.geometry
    camera = GeometricPoleCamera.for_scene(scene, sensors.geometric_camera, model)
    detector = ColourPoleDetector(perception.colour_filter, model, scene.codes, geometry)
    return GeometricPoleSightings(camera, detector)


def _cnn_robot_sightings(
    scene: SplFieldScene, robots: list[NaoRobot], sensors: RigConfig, perception: PipelineConfig
) -> GeometricRobotSightings:
    return GeometricRobotSightings(sensors.geometric_robots_cnn, sensors.camera.model, robots)


def _vision_robot_sightings(
    scene: SplFieldScene, robots: list[NaoRobot], sensors: RigConfig, perception: PipelineConfig
) -> GeometricRobotSightings:
    return GeometricRobotSightings(
        sensors.geometric_robots_vision,
        sensors.camera.model,
        robots,
        sensors.sonar,
        perception.sonar_filter,
    )


def _cnn_ball_sightings(bottom: bool) -> EmulatorFactory:
    """The emulator of the top camera's ball sightings, and the bottom one's with ``bottom``."""

    def build(
        scene: SplFieldScene, robots: list[NaoRobot], sensors: RigConfig, perception: PipelineConfig
    ) -> GeometricBallSightings:
        radius = scene.dimensions.ball_diameter_m / 2
        return GeometricBallSightings(
            sensors.geometric_ball,
            sensors.camera.model,
            scene.bodies.ball,
            radius,
            bottom=sensors.geometric_ball_bottom if bottom else None,
        )

    return build


def _field_features(bottom: bool) -> EmulatorFactory:
    """The emulator of the top camera's field features, and the bottom one's with ``bottom``."""

    def build(
        scene: SplFieldScene, robots: list[NaoRobot], sensors: RigConfig, perception: PipelineConfig
    ) -> GeometricFieldFeatures:
        field_map = shared_field_map(scene.dimensions)
        model, view = sensors.camera.model, perception.feature_view
        return GeometricFieldFeatures(
            field_map,
            model,
            view,
            bottom=bottom,
            detector=perception.field_detector,
            post_bodies=scene.goal_post_body_ids(),
        )

    return build


# (representation, the provider it emulates) -> how to build the emulator
EMULATORS: Mapping[tuple[str, str], EmulatorFactory] = {
    (POLE_SIGHTINGS, "colour"): _colour_pole_sightings,
    (ROBOT_SIGHTINGS, "cnn"): _cnn_robot_sightings,
    (ROBOT_SIGHTINGS, "vision"): _vision_robot_sightings,
    (BALL_SIGHTINGS, "cnn"): _cnn_ball_sightings(bottom=False),
    (BALL_SIGHTINGS, "cnn_both_cameras"): _cnn_ball_sightings(bottom=True),
    (FIELD_FEATURES, "vision"): _field_features(bottom=False),
    (FIELD_FEATURES, "vision_both_cameras"): _field_features(bottom=True),
}


def emulated_representations(sensors: RigConfig, perception: PipelineConfig) -> tuple[str, ...]:
    """The representations whose configured provider has an emulator here, in the geometric
    camera mode (none in the rendered mode): what a pipeline may take from emulators."""
    if sensors.camera_mode != "geometric":
        return ()
    return tuple(
        representation
        for representation, provider in EMULATORS
        if perception.provider_name(representation) == provider
    )


def emulators_for(
    representations: Collection[str],
    scene: SplFieldScene,
    robots: list[NaoRobot],
    sensors: RigConfig,
    perception: PipelineConfig,
) -> dict[str, Emulator]:
    """Representation -> emulator for each of ``representations`` (of
    :func:`emulated_representations`; those a pipeline reads, so that one it does not read is
    never built), in sorted order; ``robots`` are the world's robots."""
    return {
        name: EMULATORS[name, perception.provider_name(name)](scene, robots, sensors, perception)
        for name in sorted(representations)
    }
