"""Our own body in our own camera's image (the "body contour" of SPL code such as B-Human's).

With the head turned far to one side and pitched down, the top camera sees the robot's own
shoulder and arm: light grey, which the CNN can take for the ball (a "ball" at a fixed place
beside the robot, found again in every such frame). The robot knows where its body is: each
part is a box in the robot frame (x forward, y left, z up from the ground; m), fixed to the
torso as the camera's pose (:class:`~perception.types.CameraState`, from the head joints) is,
so the torso's sway moves both alike. :func:`body_silhouettes` projects the boxes for one camera
pose (a box's silhouette is the convex hull of its corners; the part of a box behind the camera
is clipped at ``NEAR_M`` in front of it, which puts its silhouette's edge far outside the
image); :func:`on_body` tells whether an image point lies on one (``margin_px`` outside its
edge still counts).

:data:`NAO_BODY` is the simulated Nao's body (``spl_env.robots.nao``: legs, waistband, jersey
and upper arms; ``tests/spl_env/test_body_contour_rendered.py`` holds the two to each other); a real
robot's contour would be measured on it.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import cv2
import numpy as np

from perception.geometry import FloatArray, project_points
from perception.types import CameraModel, CameraState
from perception.validation import InvalidTypeError, check_positive

NEAR_M = 0.01  # a box's part behind the camera is clipped this far (m) in front of it
# the 12 edges of a box as pairs of corner indices (corners differing in one axis's bit)
_EDGES: tuple[tuple[int, int], ...] = tuple(
    (a, a | (1 << axis)) for axis in range(3) for a in range(8) if not a & (1 << axis)
)


@dataclass(frozen=True)
class BodyBox:
    """One part of our body: a box of ``half_extents_m`` (3,) (> 0) about ``centre_m`` (3,),
    axis-aligned in the robot frame (m)."""

    centre_m: tuple[float, float, float]
    half_extents_m: tuple[float, float, float]

    def __post_init__(self) -> None:
        for name in ("centre_m", "half_extents_m"):
            value = getattr(self, name)
            if not isinstance(value, tuple) or not all(
                isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, bool)
                for v in value
            ):
                raise InvalidTypeError(
                    f"BodyBox.{name} must be a tuple of 3 numbers, got {type(value).__name__} "
                    f"{value!r}"
                )
            if len(value) != 3 or not all(math.isfinite(v) for v in value):
                raise ValueError(f"BodyBox.{name} must be 3 finite numbers, got {value!r}")
        if min(self.half_extents_m) <= 0:
            raise ValueError(f"BodyBox.half_extents_m must be > 0, got {self.half_extents_m}")

    def corners(self) -> FloatArray:
        """The box's 8 corners (8, 3) (robot frame, m); corner ``k`` has bit ``i`` of ``k``
        set where it lies on the + side of axis ``i``."""
        signs = np.array(list(itertools.product((-1.0, 1.0), repeat=3)))[:, ::-1]
        return np.asarray(self.centre_m) + signs * np.asarray(self.half_extents_m)


# the simulated Nao (spl_env.robots.nao._body_parts): its legs, waistband, jersey and arms
NAO_BODY: tuple[BodyBox, ...] = (
    BodyBox((0.0, -0.05, 0.13), (0.045, 0.035, 0.13)),
    BodyBox((0.0, 0.05, 0.13), (0.045, 0.035, 0.13)),
    BodyBox((0.0, 0.0, 0.28), (0.055, 0.085, 0.02)),
    BodyBox((0.0, 0.0, 0.37), (0.05, 0.08, 0.07)),
    BodyBox((0.0, -0.11, 0.34), (0.03, 0.025, 0.1)),
    BodyBox((0.0, 0.11, 0.34), (0.03, 0.025, 0.1)),
)


@dataclass(frozen=True, kw_only=True)
class BodyContourConfig:
    """Our body's ``boxes`` (robot frame) and the ``margin_px`` (>= 0) beyond a silhouette's
    edge that still counts as on the body (the renderer's edge pixels, the gait's jitter)."""

    boxes: tuple[BodyBox, ...] = NAO_BODY
    margin_px: float = 2.0

    def __post_init__(self) -> None:
        if not isinstance(self.boxes, tuple) or not all(isinstance(b, BodyBox) for b in self.boxes):
            raise InvalidTypeError(
                "BodyContourConfig.boxes must be a tuple of BodyBox, got "
                f"{type(self.boxes).__name__}"
            )
        check_positive("BodyContourConfig", "margin_px", self.margin_px, allow_zero=True)


def body_silhouettes(
    config: BodyContourConfig, camera: CameraModel, state: CameraState
) -> list[FloatArray]:
    """Per box with a part in front of the camera, its silhouette (K, 2) px in the image of
    ``camera`` taken from ``state``: a convex polygon (module docstring), which may reach far
    outside the image."""
    rotation = state.rotation()
    out = []
    for box in config.boxes:
        corners = (box.corners() - np.asarray(state.position)) @ rotation  # camera frame
        depth = corners[:, 0]
        if depth.max() <= NEAR_M:
            continue  # wholly behind the camera
        points = [corners[depth > NEAR_M]]
        for a, b in _EDGES:  # where an edge crosses the near plane
            if (depth[a] > NEAR_M) != (depth[b] > NEAR_M):
                t = (NEAR_M - depth[a]) / (depth[b] - depth[a])
                points.append((corners[a] + t * (corners[b] - corners[a]))[None])
        pixels, _ = project_points(
            np.concatenate(points), camera.fx, camera.fy, camera.cx, camera.cy
        )
        hull = cv2.convexHull(pixels.astype(np.float32))
        out.append(np.asarray(hull, dtype=np.float64).reshape(-1, 2))
    return out


def on_body(pixel: FloatArray, silhouettes: list[FloatArray], margin_px: float) -> bool:
    """Whether the image point ``pixel`` (2,) px lies on one of ``silhouettes`` (K, 2) or
    within ``margin_px`` of one."""
    point = (float(pixel[0]), float(pixel[1]))
    return any(
        cv2.pointPolygonTest(s.astype(np.float32).reshape(-1, 1, 2), point, True) >= -margin_px
        for s in silhouettes
    )
