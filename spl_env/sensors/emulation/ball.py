"""The fast geometric camera mode's ball sightings: the CNN front end's, without pixels.

The ball is sighted when its centre projects at least ``edge_margin_radii`` of its own image
radius inside the image (the CNN front end drops boxes cut by the image's edge), it lies within
``max_range_m``, and a ray from the camera to its centre first meets the ball (not a robot or a
post in front of it); then with the chance ``recall`` of its range band (``band_edges_m``), its
range and bearing disturbed by Gaussian noise: that band's relative range noise
``range_std_fraction`` and bearing noise ``bearing_std_rad``, which the sighting's covariance
reports. No false sightings, and no motion blur's effect.

The fitted model :data:`CNN_BALL` says where its numbers come from.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from perception.geometry import FloatArray, project_points, range_bearing, wrap_angle
from perception.types import BallSighting, CameraModel, CameraState
from perception.validation import check_positive
from spl_env.robots.nao import NaoRobot
from spl_env.sensors.emulation.bands import RangeBands
from spl_env.sim.world import BulletWorld

_OWNER = "GeometricBallConfig"


@dataclass(frozen=True, kw_only=True)
class GeometricBallConfig(RangeBands):
    """Detection chance and noise per range band (:class:`RangeBands`) of the emulated ball
    sightings, the range beyond which none, and how far inside the image the ball must show
    (module doc)."""

    recall: tuple[float, ...] = (0.9,)
    range_std_fraction: tuple[float, ...] = (0.03,)
    bearing_std_rad: tuple[float, ...] = (0.005,)
    max_range_m: float = 6.0  # no sighting beyond
    edge_margin_radii: float = 1.0  # the centre must lie this many image radii inside

    def __post_init__(self) -> None:
        super().__post_init__()
        check_positive(_OWNER, "max_range_m", self.max_range_m)
        check_positive(_OWNER, "edge_margin_radii", self.edge_margin_radii, allow_zero=True)


# The CNN front end (perception.vision.cnn_ball) on 1500 rendered frames of the tuning seeds
# 0-4 (python benchmarks/ball_detection.py, "tuning"): balls showing at least 12 pixels, bands
# 0-1, 1-2, 2-3, 3-4, 4-5 and beyond 5 m; errors of the sightings of the ball (0-1.6 % of the
# sightings were of something else up to 5 m, 18 % beyond: not emulated), 0.005 false
# sightings per frame (not emulated). Fitted before the flat-box check (CnnBallConfig.
# min_shading_std), which changes none of these numbers on the tuning frames.
CNN_BALL = GeometricBallConfig(
    band_edges_m=(1.0, 2.0, 3.0, 4.0, 5.0),
    recall=(0.71, 0.80, 0.86, 0.82, 0.52, 0.19),
    range_std_fraction=(0.010, 0.009, 0.014, 0.019, 0.033, 0.032),
    bearing_std_rad=(0.0040, 0.0023, 0.0021, 0.0030, 0.0026, 0.0030),
)


# The CNN front end on the bottom camera's images read at half resolution, 1500 rendered frames
# of the tuning seeds 0-4 (python benchmarks/ball_detection.py --camera bottom, "tuning"):
# bands 0-0.3, 0.3-0.6, 0.6-1 m and beyond (measured to 1.5 m); 1-2.4 % of the sightings were
# of something else, 0.003 false sightings per frame (neither emulated; 0.001 and recalls at
# most 1.0 point lower with the flat-box check).
CNN_BALL_BOTTOM = GeometricBallConfig(
    band_edges_m=(0.3, 0.6, 1.0),
    recall=(0.40, 0.67, 0.62, 0.65),
    range_std_fraction=(0.019, 0.012, 0.014, 0.020),
    bearing_std_rad=(0.011, 0.0069, 0.0056, 0.0079),
    max_range_m=1.5,
)


class GeometricBallSightings:
    """Emulates the CNN front end's ``ball_sightings`` (module doc) of the ball body ``ball``
    (its name in the world) with radius ``radius_m``: the top camera's with ``config``, and
    with ``bottom`` also the bottom camera's (``ball_sightings="cnn_both_cameras"``)."""

    def __init__(
        self,
        config: GeometricBallConfig,
        model: CameraModel,
        ball: str,
        radius_m: float,
        bottom: GeometricBallConfig | None = None,
    ) -> None:
        check_positive("GeometricBallSightings", "radius_m", radius_m)
        self.cameras: tuple[tuple[Literal["top", "bottom"], GeometricBallConfig], ...] = (
            ("top", config),
            *((("bottom", bottom),) if bottom is not None else ()),
        )
        self.model = model
        self.ball = ball
        self.radius_m = radius_m

    def observe(
        self,
        world: BulletWorld,
        robot: NaoRobot,
        camera_state: CameraState,
        rng: np.random.Generator,
        blur_px: float,
    ) -> tuple[BallSighting, ...]:
        """This frame's sightings of the ball (robot frame) by each camera, top first."""
        centre = world.position(self.ball)
        sightings = []
        for camera, config in self.cameras:
            # the same draws every frame, seen or not: the stream does not depend on the view
            sighted_draw, noise = rng.uniform(), rng.normal(0.0, 1.0, size=2)
            if not self._visible(world, robot, camera, config, centre):
                continue
            range_m, bearing_rad = range_bearing(robot.pose, centre[None, :2])[0]
            band = config.band(float(range_m))
            if sighted_draw >= config.recall[band]:
                continue
            std = np.array(
                [config.range_std_fraction[band] * range_m, config.bearing_std_rad[band]]
            )
            sightings.append(
                BallSighting(
                    range_m=max(float(range_m + std[0] * noise[0]), 1e-3),
                    bearing_rad=float(wrap_angle(bearing_rad + std[1] * noise[1])),
                    cov=np.diag(std**2),
                )
            )
        return tuple(sightings)

    def _visible(
        self,
        world: BulletWorld,
        robot: NaoRobot,
        camera: Literal["top", "bottom"],
        config: GeometricBallConfig,
        centre: FloatArray,
    ) -> bool:
        """Whether the ball centred at ``centre`` (3,) shows inside ``camera``'s image, within
        range and unhidden."""
        m = self.model
        position, rotation = robot.camera_pose_world(camera)
        camera_frame = (centre - position) @ rotation
        uv, front = project_points(camera_frame[None], m.fx, m.fy, m.cx, m.cy)
        if not front[0]:
            return False
        margin = (
            config.edge_margin_radii * m.fx * self.radius_m / float(np.linalg.norm(camera_frame))
        )
        u, v = uv[0]
        if not (margin <= u <= m.width - 1 - margin and margin <= v <= m.height - 1 - margin):
            return False
        if math.dist(robot.pose[:2], centre[:2]) > config.max_range_m:
            return False
        _, hit = world.ray_test(position[None], centre[None])
        return bool(hit[0] == world.body(self.ball))
