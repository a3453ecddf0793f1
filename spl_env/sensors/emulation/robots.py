"""The fast geometric camera mode's robot sightings: a robot front end's, without pixels.

Each other robot whose body centre (``CENTRE_HEIGHT_M`` up) projects inside the image through
the true camera pose, lies within ``max_range_m`` and is not hidden (a ray from the camera to
that centre first meets the robot itself) is sighted with the chance ``recall`` of its range
band (``band_edges_m``), its range and bearing disturbed by Gaussian noise: that band's
relative range noise ``range_std_fraction`` and bearing noise ``bearing_std_rad``. Its team
colour is seen with chance ``team_probability`` (never on a robot without team colours); no
false sightings.

With ``sonar_check`` (the ``vision`` front end, seed 004's Algorithm 2 lines 14-17), a sighted
robot inside one of the sonar's cones and range (the rig's :class:`SonarModel`, bearing and
distance from the transducers) is sonar confirmed with chance ``sonar_confirm_probability``:
its relative range noise is then ``sonar_range_std_fraction`` and its reported range std
the sonar's. A sighting with neither a team colour nor a confirmation is dropped, as the
provider does.

Two fitted models (:data:`CNN_ROBOTS`, :data:`VISION_ROBOTS`); where their numbers come from is
said beside each.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from perception.geometry import project_points, range_bearing, wrap_angle
from perception.sensor_models import SonarModel
from perception.tracking.sonar_filter import SonarFilterConfig, audible
from perception.types import CameraModel, CameraState, RobotSighting
from perception.validation import check_in_interval, check_positive
from spl_env.robots.nao import NaoRobot
from spl_env.sensors.emulation.bands import RangeBands
from spl_env.sim.world import BulletWorld

CENTRE_HEIGHT_M = 0.3  # a standing Nao's body centre above the ground (jersey, waistband)
_OWNER = "GeometricRobotConfig"


@dataclass(frozen=True, kw_only=True)
class GeometricRobotConfig(RangeBands):
    """Detection chance and noise per range band (:class:`RangeBands`) of one front end's
    emulated robot sightings (module doc). ``sonar_range_std_fraction``: range noise std /
    range of a sonar-confirmed sighting.
    """

    recall: tuple[float, ...] = (0.94,)
    range_std_fraction: tuple[float, ...] = (0.043,)
    bearing_std_rad: tuple[float, ...] = (math.radians(0.65),)
    max_range_m: float = 4.0  # no sighting beyond
    team_probability: float = 0.0  # chance that a sighted robot's team colour is seen
    sonar_check: bool = False  # Algorithm 2's sonar check (module doc)
    sonar_confirm_probability: float = 0.0  # chance of a confirmation inside the sonar's reach
    sonar_range_std_fraction: float = 0.01

    def __post_init__(self) -> None:
        super().__post_init__()
        for name in ("team_probability", "sonar_confirm_probability"):
            check_in_interval(
                _OWNER, name, getattr(self, name), 0, 1, low_inclusive=True, high_inclusive=True
            )
        for name in ("max_range_m", "sonar_range_std_fraction"):
            check_positive(_OWNER, name, getattr(self, name))
        if not isinstance(self.sonar_check, bool):
            raise TypeError(
                f"{_OWNER}.sonar_check must be a bool, got {type(self.sonar_check).__name__}"
            )


# The CNN front end on rendered frames of whole, unoccluded robots 1-3 m away
# (tests/spl_env/test_cnn_robots_rendered.py, 382 robots, held-out seeds: 94 % sighted, range
# error std 4.3 %, bearing error std 0.65°; the CNN's robots were measured to 3.6 m). It sees no
# team and has no sonar check.
CNN_ROBOTS = GeometricRobotConfig()

# The vision front end with the sonar check on walking frames of SPL/ActiveVision-v0, robots in
# view, both lightings pooled, fitted on the tuning seeds 0-9 ("emulator_fit" of
# benchmarks/robot_detection.py --seeds 0-9): bands 0-1, 1-2, 2-3, 3-5 m; a team in 99.7 % of
# the sightings (the 0.3 % with the wrong team are emulated as none); 96 % of those the sonar can
# hear confirmed (85 % while the sonar still heard our own swaying legs), their range error std
# 3.1 %. Not measured beyond 5 m; no false sightings (0.043 per frame measured).
VISION_ROBOTS = GeometricRobotConfig(
    band_edges_m=(1.0, 2.0, 3.0),
    recall=(1.0, 1.0, 0.998, 0.965),
    range_std_fraction=(0.036, 0.045, 0.065, 0.093),
    bearing_std_rad=tuple(math.radians(d) for d in (0.60, 0.48, 0.26, 0.18)),
    max_range_m=5.0,
    team_probability=0.997,
    sonar_check=True,
    sonar_confirm_probability=0.96,
    sonar_range_std_fraction=0.031,
)


class GeometricRobotSightings:
    """Emulates one front end's ``robot_sightings`` (``config``) for the robot ``robot`` among
    ``robots`` (module doc); ``sonar`` is the rig's sonar, needed with ``config.sonar_check``,
    and ``sonar_filter`` the sonar check's settings (default ``SonarFilterConfig()``)."""

    def __init__(
        self,
        config: GeometricRobotConfig,
        model: CameraModel,
        robots: list[NaoRobot],
        sonar: SonarModel | None = None,
        sonar_filter: SonarFilterConfig | None = None,
    ) -> None:
        if config.sonar_check and sonar is None:
            raise ValueError(
                "this robot front end checks its sightings with the sonar (sonar_check), but "
                "the rig has no sonar (RigConfig.sonar=None)"
            )
        self.config = config
        self.model = model
        self.robots = robots
        self.sonar = sonar
        # the range std the provider reports for a confirmed sighting
        self._confirmed_std_m = (
            (sonar_filter or SonarFilterConfig()).confirmed_range_std_m(sonar)
            if sonar is not None
            else 0.0
        )

    def observe(
        self,
        world: BulletWorld,
        robot: NaoRobot,
        camera_state: CameraState,
        rng: np.random.Generator,
        blur_px: float,
    ) -> tuple[RobotSighting, ...]:
        """This frame's sightings (robot frame) of the robots other than ``robot``."""
        others = [r for r in self.robots if r is not robot]
        if not others:
            return ()
        c, m = self.config, self.model
        position, rotation = robot.camera_pose_world()
        centres = np.array([[*r.pose[:2], CENTRE_HEIGHT_M] for r in others])
        uv, front = project_points((centres - position) @ rotation, m.fx, m.fy, m.cx, m.cy)
        rb = range_bearing(robot.pose, centres[:, :2])
        inside = front & (uv[:, 0] >= 0) & (uv[:, 0] <= m.width - 1)
        inside &= (uv[:, 1] >= 0) & (uv[:, 1] <= m.height - 1) & (rb[:, 0] <= c.max_range_m)
        candidates = np.flatnonzero(inside)
        if len(candidates) == 0:
            return ()
        starts = np.repeat(position[None, :], len(candidates), axis=0)
        _, hit = world.ray_test(starts, centres[candidates])
        bodies = np.array([world.body(others[k].name) for k in candidates])
        unhidden = candidates[hit == bodies]
        draws = rng.uniform(size=(len(unhidden), 3))  # sighted, team seen, sonar confirmed
        noise = rng.normal(0.0, 1.0, size=(len(unhidden), 2))
        sightings = []
        for k, draw, (n_range, n_bearing) in zip(unhidden, draws, noise, strict=True):
            range_m, bearing_rad = float(rb[k, 0]), float(rb[k, 1])
            band = c.band(range_m)
            if draw[0] >= c.recall[band]:
                continue
            seen = others[k].team_colours and draw[1] < c.team_probability
            team = others[k].team if seen else None
            confirmed = (
                self.sonar is not None
                and c.sonar_check
                and audible(self.sonar, range_m, bearing_rad)
                and draw[2] < c.sonar_confirm_probability
            )
            if c.sonar_check and team is None and not confirmed:
                continue
            bearing_std = c.bearing_std_rad[band]
            if confirmed:
                std = np.array([c.sonar_range_std_fraction * range_m, bearing_std])
                cov = np.diag([self._confirmed_std_m**2, bearing_std**2])
            else:
                std = np.array([c.range_std_fraction[band] * range_m, bearing_std])
                cov = np.diag(std**2)
            sightings.append(
                RobotSighting(
                    range_m=max(range_m + float(std[0] * n_range), 1e-3),
                    bearing_rad=float(wrap_angle(bearing_rad + std[1] * n_bearing)),
                    cov=cov,
                    team=team,
                    sonar_confirmed=confirmed,
                )
            )
        return tuple(sightings)
