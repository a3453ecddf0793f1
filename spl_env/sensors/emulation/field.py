"""The fast geometric camera mode's field features: what the rendered ``vision`` provider
(:mod:`perception.vision.field_features`) would report, without rendering.

Per camera and frame:

1. **In view**: the map's features in view of the camera the joints report, at the robot's
   true pose (:func:`perception.field.visibility.visible_features`, exact), out to the
   detector model's range (``FeatureViewConfig.detector.max_range_m``; the other view settings
   are the pipeline's ``feature_view``), where nothing stands between the true camera and the
   ground (:func:`occlusion`: a ray to each ground point must meet no body: a robot, the ball,
   a goal; a goal post only well short of its own point, which lies inside it), and a goal
   post only where the detector's ``min_cut_post_height_m`` of it shows in the image (it needs
   that much of a post; looking down at the ball, the image cuts it).
2. **Sway**: the rendered image comes from the true camera, which sways with the gait in a way
   the joints do not sense, while the detector places what it sees on the ground with the
   joints' camera. Each point is moved to where the joints' camera puts the pixel at which
   the true camera sees it (:func:`reproject`), a direction with it (whether a feature is in
   view still goes by the joints' camera). On walking patrols this is most of the detector's
   error, the same for all of a frame's features (lines: median 9 cm, 5 mm with the sway
   taken out; ``benchmarks/results/geometric_field_features.json``); it is reproduced
   exactly.
3. **Misses and noise**: :func:`perception.field.visibility.detect` with the fitted
   :class:`~perception.field.visibility.DetectorModel` (``feature_view.detector``): the
   recall per kind and range band, and the detector's remaining error (the image's, a few
   mm) per kind as ``a + b * range``. False detections are not emulated (0.13 per frame in
   all, most of them field edges, which the sensor model drops; per kind in
   ``benchmarks/results/geometric_field_features.json``).
4. **Reported uncertainty**: each point gets the covariance the detector would report at that
   point (:func:`detector_covariances`, the detector's own model: ``pixel_std_px`` through
   the ground projection plus ``floor_std_m + range_std_fraction * range``), each direction
   the detector model's ``reported_direction_std_rad``; so the sensor model weighs emulated
   features as it weighs detected ones.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from perception.field.features import FeatureKind, FieldFeature
from perception.field.field_map import FieldMap
from perception.field.visibility import FeatureViewConfig, detect, visible_features
from perception.geometry import FloatArray, pixel_rays, project_points, ray_ground_intersection
from perception.types import CameraModel, CameraState
from perception.vision.field_features import FieldFeatureConfig, detection_covariances
from perception.vision.field_pixels import GroundProjection, row_shifted
from spl_env.robots.nao import NaoRobot, camera_state_for
from spl_env.sim.world import BulletWorld

CameraPose = tuple[FloatArray, FloatArray]  # position (3,) and rotation (3, 3), robot frame
DIRECTION_ARM_M = 0.1  # a direction is moved as the point this far along it is
OCCLUSION_CLEARANCE_M = 0.01  # occlusion rays end this high above a ground point (m)
POST_SLACK_M = 0.1  # ... and count a goal post they meet this near the point as its own (m)


def true_camera(robot: NaoRobot, which: str = "top") -> CameraPose:
    """Where ``robot``'s top or bottom camera truly is (sway included), in the robot frame
    (the frame of its pose on the ground)."""
    position, rotation = robot.camera_pose_world("bottom" if which == "bottom" else "top")
    x, y, heading = robot.pose
    c, s = math.cos(heading), math.sin(heading)
    to_robot = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
    return to_robot @ (position - np.array([x, y, 0.0])), to_robot @ rotation


def joints_camera(state: CameraState) -> CameraPose:
    """The camera pose ``state`` reports (robot frame)."""
    return np.asarray(state.position, dtype=np.float64), state.rotation()


def reproject(
    points: FloatArray, seen_by: CameraPose, placed_by: CameraPose, camera: CameraModel
) -> FloatArray:
    """Ground points (N, 2) (robot frame) as ``placed_by`` puts the pixels at which camera
    ``seen_by`` sees them; NaN where either misses (behind the camera, above the horizon)."""
    xyz = np.column_stack([points, np.zeros(len(points))]) - seen_by[0]
    uv, _ = project_points(xyz @ seen_by[1], camera.fx, camera.fy, camera.cx, camera.cy)
    out = np.full((len(points), 2), np.nan)
    ok = np.isfinite(uv).all(axis=1)
    if ok.any():
        rays = pixel_rays(uv[ok], camera.fx, camera.fy, camera.cx, camera.cy) @ placed_by[1].T
        out[ok] = ray_ground_intersection(placed_by[0], rays)[0]
    return out


def reprojected(
    feature: FieldFeature, seen_by: CameraPose, placed_by: CameraPose, camera: CameraModel
) -> FieldFeature | None:
    """``feature`` moved by :func:`reproject` (its direction as the point ``DIRECTION_ARM_M``
    along it), same covariances; None where a point misses the ground."""
    moved = reproject(_with_arm(feature), seen_by, placed_by, camera)
    if not np.isfinite(moved).all():
        return None
    if feature.direction is None:
        return dataclasses.replace(feature, points=moved)
    along = moved[1] - moved[0]
    direction = math.atan2(float(along[1]), float(along[0]))
    return dataclasses.replace(feature, points=moved[:1], direction=direction)


def detector_covariances(
    points: FloatArray, camera: CameraModel, state: CameraState, config: FieldFeatureConfig
) -> FloatArray:
    """(N, 2, 2) covariances the detector with ``config`` reports for ground ``points`` (N, 2)
    seen at their own pixels (``perception.vision.field_features``' covariance model, step 6)."""
    projection = GroundProjection(row_shifted(camera, config.row_offset_px), state)
    return detection_covariances(projection, projection.pixels_of(points), points, config)


class GeometricFieldFeatures:
    """Emulates the ``vision`` field-feature provider without rendering (module docstring;
    with ``bottom``, the ``vision_both_cameras`` one: the bottom camera's features after the
    top one's). ``config`` is the pipeline's ``feature_view`` (its ``detector`` model and view
    settings); ``detector`` the detector's configuration, for its covariance model (default:
    :class:`~perception.vision.field_features.FieldFeatureConfig`'s, as the pipeline's);
    ``post_bodies`` the goal posts' PyBullet bodies (:func:`occlusion`)."""

    def __init__(
        self,
        field_map: FieldMap,
        camera: CameraModel,
        config: FeatureViewConfig,
        bottom: bool = False,
        detector: FieldFeatureConfig | None = None,
        post_bodies: tuple[int, ...] = (),
    ) -> None:
        self.field_map = field_map
        self.post_bodies = post_bodies
        self.camera = camera
        self.config = config
        self.bottom = bottom
        self.detector = FieldFeatureConfig() if detector is None else detector
        self._view = dataclasses.replace(
            config,
            max_range_m=config.detector.max_range_m,
            post_seen_height_m=self.detector.min_cut_post_height_m,
        )

    def observe(
        self,
        world: BulletWorld,
        robot: NaoRobot,
        camera_state: CameraState,
        rng: np.random.Generator,
        blur_px: float,
    ) -> tuple[FieldFeature, ...]:
        """This frame's field features (robot frame) from ``robot``'s true pose and camera."""
        features = self._camera(world, robot, camera_state, "top", rng)
        if not self.bottom:
            return features
        bottom = camera_state_for(robot.config, robot.head, "bottom")
        return features + self._camera(world, robot, bottom, "bottom", rng)

    def _camera(
        self,
        world: BulletWorld,
        robot: NaoRobot,
        state: CameraState,
        which: Literal["top", "bottom"],
        rng: np.random.Generator,
    ) -> tuple[FieldFeature, ...]:
        """:meth:`emulate` for ``robot``'s ``which`` camera at the joints' ``state``, hidden
        where bodies of ``world`` stand in front of the true camera."""
        position = robot.camera_pose_world(which)[0]
        hidden = occlusion(world, position, self.post_bodies)
        return self.emulate(robot.pose, state, true_camera(robot, which), rng, hidden)

    def emulate(
        self,
        pose: FloatArray,
        state: CameraState,
        seen_by: CameraPose,
        rng: np.random.Generator,
        occluded: Callable[[FloatArray], NDArray[np.bool_]] | None = None,
    ) -> tuple[FieldFeature, ...]:
        """One camera's features: in view of ``state`` at the true ``pose`` (and not
        ``occluded``, field-frame ground points (N, 2) -> (N,) bool, when given), seen by the
        true camera ``seen_by`` (robot frame) and placed by ``state``, missed, noisy and
        reported as the detector would (module docstring); the same as :func:`reprojected`,
        then :func:`~perception.field.visibility.detect`, each feature in turn, but with the
        projections of all of them at once."""
        exact = visible_features(
            self.field_map, pose, self.camera, state, self._view, occluded=occluded
        )
        if not exact:
            return ()
        moved = reproject(
            np.concatenate([_with_arm(f) for f in exact]),
            seen_by,
            joints_camera(state),
            self.camera,
        )
        model = self.config.detector
        found: list[tuple[FeatureKind, FloatArray, float | None]] = []
        start = 0
        for f in exact:
            size = len(f.points) + (f.direction is not None)
            points, start = moved[start : start + size], start + size
            if not np.isfinite(points).all():
                continue
            direction = None
            if f.direction is not None:
                points, arm = points[:-1], points[-1] - points[0]
                direction = math.atan2(float(arm[1]), float(arm[0]))
            detected = detect(f.kind, points, direction, model, rng)
            if detected is not None:
                found.append((f.kind, *detected))
        if not found:
            return ()
        covs = detector_covariances(
            np.concatenate([p for _, p, _ in found]), self.camera, state, self.detector
        )
        # finite points (checked above) and the detector's own positive definite covariances:
        # built as the detector builds its features, unchecked
        out, start = [], 0
        for kind, points, direction in found:
            cov, start = covs[start : start + len(points)], start + len(points)
            if direction is None:
                out.append(FieldFeature.trusted(kind, points, cov))
            else:
                std = model.reported_direction_std_rad[kind]
                out.append(FieldFeature.trusted(kind, points, cov, direction, std))
        return tuple(out)


def occlusion(
    world: BulletWorld, camera_position: FloatArray, post_bodies: tuple[int, ...] = ()
) -> Callable[[FloatArray], NDArray[np.bool_]]:
    """Which field-frame ground points (N, 2) a body hides from a camera at
    ``camera_position`` (3,) (field frame): a ray from it towards each point, stopped
    ``OCCLUSION_CLEARANCE_M`` above the carpet (so the carpet itself never stops it), meets a
    body first; one of ``post_bodies`` (the goal posts, whose own map point lies at their
    centre, inside them) only when more than ``POST_SLACK_M`` short of the point."""
    posts = np.asarray(post_bodies, dtype=np.int64)

    def occluded(points: FloatArray) -> NDArray[np.bool_]:
        ground = np.column_stack([points, np.full(len(points), OCCLUSION_CLEARANCE_M)])
        starts = np.ascontiguousarray(np.broadcast_to(camera_position, ground.shape))
        fractions, bodies = world.ray_test(starts, ground)
        length = np.linalg.norm(ground - starts, axis=1)
        own_post = np.isin(bodies, posts) & (fractions * length >= length - POST_SLACK_M)
        return np.asarray((bodies >= 0) & ~own_post)

    return occluded


def _with_arm(feature: FieldFeature) -> FloatArray:
    """``feature``'s points, and the point ``DIRECTION_ARM_M`` along its direction if any."""
    if feature.direction is None:
        return feature.points
    d = feature.direction
    arm = DIRECTION_ARM_M * np.array([math.cos(d), math.sin(d)])
    return np.vstack([feature.points, feature.points[0] + arm])
