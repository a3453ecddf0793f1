"""The field features a camera could see from a known pose: the map's features inside the image,
as :class:`~perception.field.features.FieldFeature` s in the robot frame, with Gaussian noise.

The oracle provider of field features (truth plus configured noise) and the sensor model's
benchmark on ideal detections read them. A ground point is in view when it projects inside the
image (``margin_px`` from its border) within ``max_range_m`` of the robot; robots and other
bodies hide nothing here. A line or field edge is seen as the longest stretch of it in view
(sampled every ``sample_m``) when that stretch is ``min_line_m`` long or more; a junction, a
mark or a post (its foot) when its point is in view; the centre circle when a
``min_circle_fraction`` of its rim is, with its direction when an X junction is in view too.

Noise: each point moves by an isotropic Gaussian of standard deviation
``point_std_m + point_std_per_m * d`` at distance ``d`` (m) from the robot, its reported
covariance; a direction by ``direction_std_rad``. Not fitted to a detector: a configuration.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from perception.field.features import SEGMENT_KINDS, FieldFeature
from perception.field.field_map import FieldMap, MapFeature
from perception.geometry import FloatArray, project_points
from perception.types import CameraModel, CameraState
from perception.validation import check_positive, finite_vector


@dataclass(frozen=True, kw_only=True)
class FeatureViewConfig:
    """Settings of :func:`visible_features` (module docstring; m, px, rad; all > 0 but
    ``margin_px`` >= 0; ``min_circle_fraction`` in (0, 1])."""

    max_range_m: float = 4.0
    min_line_m: float = 0.3
    sample_m: float = 0.02
    margin_px: float = 2.0
    min_circle_fraction: float = 0.25
    point_std_m: float = 0.02
    point_std_per_m: float = 0.02
    direction_std_rad: float = 0.03

    def __post_init__(self) -> None:
        owner = "FeatureViewConfig"
        for name in (
            "max_range_m",
            "min_line_m",
            "sample_m",
            "point_std_m",
            "point_std_per_m",
            "direction_std_rad",
        ):
            check_positive(owner, name, getattr(self, name))
        check_positive(owner, "margin_px", self.margin_px, allow_zero=True)
        check_positive(
            owner, "min_circle_fraction", self.min_circle_fraction, upper=1.0, upper_inclusive=True
        )


def visible_features(
    field_map: FieldMap,
    pose: FloatArray,
    camera: CameraModel,
    state: CameraState,
    config: FeatureViewConfig,
    rng: np.random.Generator | None = None,
) -> tuple[FieldFeature, ...]:
    """The features of ``field_map`` in view of ``camera`` at ``state`` on a robot at ``pose``
    (3,) (m, m, rad, field frame), in map order; noisy when ``rng`` is given (module
    docstring), else exact with the same covariances."""
    robot = finite_vector(pose, "pose", 3)
    view = _View(robot, camera, state, config)
    found = []
    for feature in field_map.features:
        if feature.kind in SEGMENT_KINDS:
            stretch = view.longest_stretch(feature.points)
            if stretch is not None:
                found.append(view.feature(feature, stretch, rng))
        elif feature.kind == "centre_circle":
            circle = view.centre_circle(feature, field_map, rng)
            if circle is not None:
                found.append(circle)
        elif view.sees(feature.points)[0]:
            found.append(view.feature(feature, feature.points, rng))
    return tuple(found)


class _View:
    """One camera pose's visibility test and noise."""

    def __init__(
        self, pose: FloatArray, camera: CameraModel, state: CameraState, config: FeatureViewConfig
    ) -> None:
        self.pose, self.camera, self.state, self.config = pose, camera, state, config
        c, s = math.cos(pose[2]), math.sin(pose[2])
        self.to_robot = np.array([[c, -s], [s, c]])  # rows: field -> robot via points @ this

    def robot_points(self, points: FloatArray) -> FloatArray:
        """Field-frame ``points`` (N, 2) in the robot frame."""
        return (points - self.pose[:2]) @ self.to_robot

    def sees(self, points: FloatArray) -> NDArray[np.bool_]:
        """Which field-frame ground ``points`` (N, 2) are in view (N,) bool."""
        robot = self.robot_points(np.atleast_2d(points))
        ground = np.column_stack([robot, np.zeros(len(robot))])
        in_camera = (ground - self.state.position) @ self.state.rotation()
        cam = self.camera
        uv, front = project_points(in_camera, cam.fx, cam.fy, cam.cx, cam.cy)
        m = self.config.margin_px
        with np.errstate(invalid="ignore"):
            inside = (
                front
                & (uv[:, 0] >= m)
                & (uv[:, 0] <= cam.width - 1 - m)
                & (uv[:, 1] >= m)
                & (uv[:, 1] <= cam.height - 1 - m)
            )
        return inside & (np.hypot(robot[:, 0], robot[:, 1]) <= self.config.max_range_m)

    def longest_stretch(self, segment: FloatArray) -> FloatArray | None:
        """The ends (2, 2) (field frame) of the longest stretch of ``segment`` in view, or
        None when it is shorter than ``min_line_m``."""
        length = float(np.linalg.norm(segment[1] - segment[0]))
        n = max(2, math.ceil(length / self.config.sample_m) + 1)
        t = np.linspace(0.0, 1.0, n)
        samples = segment[0] + t[:, None] * (segment[1] - segment[0])
        seen = self.sees(samples)
        best, start = (0, 0), None
        for i, flag in enumerate([*seen.tolist(), False]):
            if flag and start is None:
                start = i
            elif not flag and start is not None:
                if i - start > best[1] - best[0]:
                    best = (start, i)
                start = None
        if best[1] - best[0] < 2:
            return None
        ends = samples[[best[0], best[1] - 1]]
        if float(np.linalg.norm(ends[1] - ends[0])) < self.config.min_line_m:
            return None
        return ends

    def centre_circle(
        self, feature: MapFeature, field_map: FieldMap, rng: np.random.Generator | None
    ) -> FieldFeature | None:
        """The centre circle when enough of its rim is in view (module docstring)."""
        radius = field_map.dims.centre_circle_diameter_m / 2
        angles = np.linspace(0.0, 2 * math.pi, 180, endpoint=False)
        rim = feature.points[0] + radius * np.column_stack([np.cos(angles), np.sin(angles)])
        if self.sees(rim).mean() < self.config.min_circle_fraction:
            return None
        crossings = [x.points for x in field_map.of_kind("x_junction")]
        directed = any(self.sees(points)[0] for points in crossings)
        seen = feature if directed else MapFeature("centre_circle", feature.points, feature.name)
        return self.feature(seen, feature.points, rng)

    def feature(
        self, feature: MapFeature, points: FloatArray, rng: np.random.Generator | None
    ) -> FieldFeature:
        """``feature`` seen at the field-frame ``points``, in the robot frame with noise."""
        cfg = self.config
        robot = self.robot_points(points)
        std = cfg.point_std_m + cfg.point_std_per_m * np.hypot(robot[:, 0], robot[:, 1])
        direction = None if feature.direction is None else feature.direction - self.pose[2]
        if rng is not None:
            robot = robot + rng.normal(0.0, 1.0, robot.shape) * std[:, None]
            if direction is not None:
                direction += float(rng.normal(0.0, cfg.direction_std_rad))
        cov = np.einsum("n,ij->nij", std**2, np.eye(2))
        direction_std = math.nan if direction is None else cfg.direction_std_rad
        return FieldFeature(feature.kind, robot, cov, direction, direction_std)
