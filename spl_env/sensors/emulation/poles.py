"""The fast "geometric" camera mode's pole sightings: where the poles' bands fall, no pixels.

Instead of rendering a frame and segmenting it, each pole's two band centres are projected
through the true camera pose (gait sway included, which the robot does not sense), kept if the
whole pole outline lies inside the image and no other body blocks the line of sight (ray casts),
and disturbed as the rendered pipeline is: a detection is missed with a chance that grows with
the motion blur across the pole, and each centre gets Gaussian pixel noise, separately along
columns and rows. The ids are those of the true poles: this mode makes no false detections.
Range and bearing are then measured with the colour filter's own model
(:meth:`perception.vision.ColourPoleDetector.observe_band_centres`), so the emulator delivers
the ``pole_sightings`` representation of the same type as the rendered front ends.

``recall_by_smear`` and the pixel noise are fitted to the rendered pipeline by
``benchmarks/fit_geometric_camera.py``, which writes ``benchmarks/results/geometric_camera.json``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from perception.geometry import FloatArray, project_points
from perception.types import CameraModel, CameraState, LandmarkObservation, PoleGeometry
from perception.validation import check_in_interval, check_positive, check_reals
from perception.vision.colour_filter import ColourPoleDetector
from spl_env.robots.nao import NaoRobot
from spl_env.scenes.spl_field import SplFieldScene
from spl_env.sim.world import BulletWorld

# The band centroid of a lit cylinder sits pi/4 radius in front of its axis, as the detector
# assumes when it steps back to the axis.
CENTROID_DEPTH_FACTOR = 0.25 * math.pi
WHITE_BASE_SEEN_M = 0.05  # the detector checks this much of the white base below the bands


@dataclass(frozen=True, kw_only=True)
class BandCentres:
    """Where a pole's two colour bands appear in the image.

    ``upper`` and ``lower`` are (2,) ``(u, v)`` band centres (px); ``box`` is (4,)
    ``(u0, v0, u1, v1)``.
    """

    landmark_id: int
    upper: FloatArray
    lower: FloatArray
    box: FloatArray


@dataclass(frozen=True, kw_only=True)
class GeometricCameraConfig:
    """Noise of the geometric camera mode, fitted to the rendered colour-filter pipeline.

    A pole is lost mostly to motion blur: ``recall_by_smear`` gives the chance that a fully
    visible pole is detected against its smear, the blur length over the pole's width in pixels
    (both as the rendered camera would show them).
    """

    # Fitted by benchmarks/fit_geometric_camera.py on 1684 visible poles under fixed, scanning
    # and random heads (benchmarks/results/geometric_camera.json): rendered recall 0.98, 0.97,
    # 0.91, 0.35 and 0 for smear below 0.25, 0.5, 1, 2 and beyond; rendered RMS errors 0.130 m
    # and 0.0022 rad, which these pixel noises reproduce (0.138 m, 0.0022 rad).
    # (upper bound of blur px / pole width px, detection chance below it); beyond the last: 0
    recall_by_smear: tuple[tuple[float, float], ...] = (
        (0.25, 0.98),
        (0.5, 0.97),
        (1.0, 0.91),
        (2.0, 0.35),
    )
    pixel_std_u_px: float = 0.6  # Gaussian noise on each band centre's column (px)
    pixel_std_v_px: float = 0.25  # Gaussian noise on each band centre's row (px)
    max_range_m: float = 8.0  # no detection beyond (as ColourFilterConfig.max_range_m)
    border_margin_px: float = 1.0  # the outline must stay this far inside the image

    def __post_init__(self) -> None:
        owner = "GeometricCameraConfig"
        if not isinstance(self.recall_by_smear, tuple) or not self.recall_by_smear:
            raise ValueError(
                f"{owner}.recall_by_smear needs a tuple of (bound, recall) pairs, at least one, "
                f"got {self.recall_by_smear!r}"
            )
        previous = 0.0
        for k, pair in enumerate(self.recall_by_smear):
            check_reals(owner, f"recall_by_smear[{k}]", pair, 2)
            bound, recall = pair
            # bounds finite, positive and increasing: each in (the previous bound, inf)
            check_in_interval(owner, f"recall_by_smear[{k}] bound", bound, previous, math.inf)
            check_in_interval(
                owner,
                f"recall_by_smear[{k}] recall",
                recall,
                0.0,
                1.0,
                low_inclusive=True,
                high_inclusive=True,
            )
            previous = bound
        for name in ("pixel_std_u_px", "pixel_std_v_px", "border_margin_px"):
            check_positive(owner, name, getattr(self, name), allow_zero=True)
        check_positive(owner, "max_range_m", self.max_range_m)

    def recall(self, smear: FloatArray) -> FloatArray:
        """Detection chance (N,) of fully visible poles with ``smear`` (N,) blur / width."""
        bounds = np.array([b for b, _ in self.recall_by_smear])
        recalls = np.array([r for _, r in self.recall_by_smear] + [0.0])
        return recalls[np.searchsorted(bounds, smear, side="right")]


def smear(bands: list[BandCentres], blur_px: float) -> FloatArray:
    """Blur length over each pole's width in the image (N,), from the bands' boxes (px)."""
    widths = np.array([max(b.box[2] - b.box[0], 1e-6) for b in bands])
    return blur_px / widths


class GeometricPoleCamera:
    """Band centres of the poles a camera sees, without rendering.

    ``positions`` (L, 2) are the poles' field positions, ``ids`` (L,) their landmark ids and
    ``body_ids`` (L,) their PyBullet bodies (for the occlusion test).
    """

    def __init__(
        self,
        config: GeometricCameraConfig,
        model: CameraModel,
        pole: PoleGeometry,
        positions: FloatArray,
        ids: tuple[int, ...],
        body_ids: tuple[int, ...],
    ) -> None:
        self.config = config
        self.model = model
        self.pole = pole
        self.positions = np.asarray(positions, dtype=np.float64).reshape(-1, 2)
        self.ids = ids
        self.body_ids = np.asarray(body_ids, dtype=np.int64)

    @classmethod
    def for_scene(
        cls, scene: SplFieldScene, config: GeometricCameraConfig, model: CameraModel
    ) -> GeometricPoleCamera:
        """The pole camera of ``scene``'s poles for a camera with intrinsics ``model``."""
        return cls(
            config,
            model,
            scene.config.poles.geometry,
            scene.landmarks,
            tuple(int(i) for i in scene.landmark_ids),
            scene.pole_body_ids(),
        )

    def visible(
        self, world: BulletWorld, position: FloatArray, rotation: FloatArray
    ) -> list[BandCentres]:
        """Noise-free band centres of every pole fully in view and unoccluded.

        ``position`` (3,) and ``rotation`` (3, 3) are the true camera pose in the field frame.
        """
        m, pole = self.model, self.pole
        offset = self.positions - position[:2]
        distance = np.hypot(offset[:, 0], offset[:, 1])
        near = np.flatnonzero((distance > pole.radius_m) & (distance <= self.config.max_range_m))
        if not near.size:
            return []
        heights = (
            pole.upper_centre_m,
            pole.lower_centre_m,
            pole.top_m,
            pole.base_top_m - WHITE_BASE_SEEN_M,
        )
        towards = offset[near] / distance[near, None]
        surface = self.positions[near] - CENTROID_DEPTH_FACTOR * pole.radius_m * towards
        # (K, 4, 3): each near pole's band centres, top and white base on its lit surface
        points = np.empty((len(near), len(heights), 3))
        points[:, :, :2] = surface[:, None, :]
        points[:, :, 2] = heights
        cam = (points - position) @ rotation
        uv, front = project_points(cam.reshape(-1, 3), m.fx, m.fy, m.cx, m.cy)
        uv = uv.reshape(len(near), len(heights), 2)
        in_front = front.reshape(len(near), len(heights)).all(axis=1)
        nearest = cam[:, :, 0].min(axis=1)  # depth of each pole's nearest point (m)
        half_width = m.fx * pole.radius_m / np.where(in_front, nearest, 1.0)
        boxes = np.column_stack(
            [
                uv[:, :, 0].min(axis=1) - half_width,
                uv[:, 2, 1],
                uv[:, :, 0].max(axis=1) + half_width,
                uv[:, 3, 1],
            ]
        )
        margin = self.config.border_margin_px
        inside = (
            (boxes[:, 0] >= margin)
            & (boxes[:, 1] >= margin)
            & (boxes[:, 2] <= m.width - margin)
            & (boxes[:, 3] <= m.height - margin)
        )
        kept = np.flatnonzero(in_front & inside)
        seen = [
            BandCentres(landmark_id=self.ids[near[k]], upper=uv[k, 0], lower=uv[k, 1], box=boxes[k])
            for k in kept
        ]
        if not seen:
            return []
        # line of sight to both band centres: the first body each ray meets must be the pole
        targets = points[kept, :2].reshape(-1, 3)
        starts = np.repeat(position[None, :], len(targets), axis=0)
        _, hit = world.ray_test(starts, starts + (targets - starts) * 1.001)
        bodies = self.body_ids[near[kept]]
        unblocked = np.all(hit.reshape(-1, 2) == bodies[:, None], axis=1)
        return [b for b, ok in zip(seen, unblocked, strict=True) if ok]

    def observe(
        self,
        world: BulletWorld,
        position: FloatArray,
        rotation: FloatArray,
        rng: np.random.Generator,
        blur_px: float = 0.0,
    ) -> tuple[BandCentres, ...]:
        """The band centres a detector would report: the visible poles, each kept with its
        detection chance under ``blur_px`` of horizontal motion blur, with pixel noise."""
        seen = self.visible(world, position, rotation)
        keep = rng.uniform(size=len(seen)) < self.config.recall(smear(seen, blur_px))
        std = np.array([self.config.pixel_std_u_px, self.config.pixel_std_v_px])
        noise = rng.normal(0.0, 1.0, size=(len(seen), 2, 2)) * std
        return tuple(
            BandCentres(
                landmark_id=b.landmark_id, upper=b.upper + n[0], lower=b.lower + n[1], box=b.box
            )
            for b, k, n in zip(seen, keep, noise, strict=True)
            if k
        )


class GeometricPoleSightings:
    """Emulates the colour front end's ``pole_sightings``: the band centres of
    :class:`GeometricPoleCamera` measured with ``detector``'s model (range from the two band
    elevations, bearing from the column and the head angles)."""

    def __init__(self, camera: GeometricPoleCamera, detector: ColourPoleDetector) -> None:
        self.camera = camera
        self.detector = detector

    def observe(
        self,
        world: BulletWorld,
        robot: NaoRobot,
        camera_state: CameraState,
        rng: np.random.Generator,
        blur_px: float,
    ) -> tuple[LandmarkObservation, ...]:
        """This frame's pole sightings (robot frame), at most one per pole, in id order."""
        position, rotation = robot.camera_pose_world()
        found = (
            self.detector.observe_band_centres(b.landmark_id, b.upper, b.lower, b.box, camera_state)
            for b in self.camera.observe(world, position, rotation, rng, blur_px=blur_px)
        )
        return tuple(obs for obs in found if obs is not None)
