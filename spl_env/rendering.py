"""Pictures for people: a top-down field with truth and belief beside the camera image, and a
room of circular objects from above with its circle map.

Colours (BGR internally, RGB out): true pose green, SLAM estimate orange with its 95 %
covariance ellipse, odometry-only pose grey; true poles as filled discs in their colours,
estimated poles as crosses with ellipses; other robots by team colour.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import cv2
import numpy as np
from numpy.typing import NDArray

from perception.geometry import FloatArray
from perception.representations import CIRCLE_MAP, ODOMETRY_POSE, SELF_POSE, PerceptionOutput
from perception.types import LandmarkObservation, PoleCode, SlamEstimate
from spl_env.field import FieldDimensions
from spl_env.scenes.rooms import RoomLayout
from spl_env.scenes.spl_field import POLE_BAND_RGBA
from spl_env.world_state import RoomState, WorldState

PX_PER_M = 40
CHI2_2DOF_95 = 5.991  # 95 % quantile of chi-square with 2 dof
TRUE_BGR = (60, 200, 60)
SLAM_BGR = (0, 140, 255)
ODOM_BGR = (150, 150, 150)
TEAM_BGR = ((200, 60, 30), (40, 40, 210))


def _bgr(colour: str) -> tuple[int, int, int]:
    r, g, b, _ = POLE_BAND_RGBA[colour]
    return int(255 * b), int(255 * g), int(255 * r)


class TopDownView:
    """Draws the field from above at :data:`PX_PER_M` pixels per metre."""

    def __init__(self, dims: FieldDimensions) -> None:
        self.dims = dims
        carpet_l, carpet_w = dims.carpet_size_m
        self.size = (int(carpet_w * PX_PER_M), int(carpet_l * PX_PER_M))  # rows, cols
        self.background = self._draw_field()

    def px(self, xy: FloatArray) -> tuple[int, int]:
        """Pixel (col, row) of field point ``xy`` (2,)."""
        rows, cols = self.size
        return round(cols / 2 + xy[0] * PX_PER_M), round(rows / 2 - xy[1] * PX_PER_M)

    def _draw_field(self) -> NDArray[np.uint8]:
        img = np.zeros((*self.size, 3), np.uint8)
        img[:] = (40, 120, 45)
        w = max(1, round(self.dims.line_width_m * PX_PER_M))
        for x0, y0, x1, y1 in self.dims.line_segments():
            cv2.line(
                img, self.px(np.array([x0, y0])), self.px(np.array([x1, y1])), (240, 240, 240), w
            )
        radius = round(self.dims.centre_circle_diameter_m / 2 * PX_PER_M)
        cv2.circle(img, self.px(np.zeros(2)), radius, (240, 240, 240), w)
        for post in self.dims.goal_posts():
            cv2.circle(img, self.px(post), 3, (255, 255, 255), -1)
        # legend in the field's top-left corner, clear of the poles in the border strip
        corner = self.px(np.array([-self.dims.half_length_m, self.dims.half_width_m]))
        for k, (label, bgr) in enumerate(
            (("true", TRUE_BGR), ("SLAM", SLAM_BGR), ("odometry", ODOM_BGR))
        ):
            cv2.putText(
                img,
                label,
                (corner[0] + 6 + 48 * k, corner[1] + 16),
                cv2.FONT_HERSHEY_SIMPLEX,
                0.4,
                bgr,
                1,
                cv2.LINE_AA,
            )
        return img

    def draw(
        self, state: WorldState, output: PerceptionOutput, codes: tuple[PoleCode, ...]
    ) -> NDArray[np.uint8]:
        """(H, W, 3) BGR top-down picture of the truth and the belief (what of ``self_pose``
        and ``odometry_pose`` the output holds)."""
        img = self.background.copy()
        colour_of = {c.landmark_id: c for c in codes}
        for lid, xy in zip(state.landmark_ids, state.landmarks, strict=True):
            code = colour_of[int(lid)]
            cv2.circle(img, self.px(xy), 7, _bgr(code.top), -1)
            cv2.circle(img, self.px(xy), 3, _bgr(code.bottom), -1)
        for pose, team in zip(state.robots, state.robot_teams, strict=True):
            self._robot(img, pose, TEAM_BGR[int(team)])
        cv2.circle(img, self.px(state.ball), 4, (255, 255, 255), -1)
        if ODOMETRY_POSE in output:
            self._robot(img, output[ODOMETRY_POSE], ODOM_BGR)
        if SELF_POSE in output:
            slam = output.get_as(SELF_POSE, SlamEstimate)
            for lid, xy, cov in zip(
                slam.landmark_ids, slam.landmarks, slam.landmark_covs, strict=True
            ):
                self._ellipse(img, xy, cov, SLAM_BGR)
                c = self.px(xy)
                cv2.drawMarker(img, c, _bgr(colour_of[int(lid)].top), cv2.MARKER_CROSS, 10, 2)
            self._ellipse(img, slam.pose[:2], slam.pose_cov[:2, :2], SLAM_BGR)
            self._robot(img, slam.pose, SLAM_BGR)
        self._robot(img, state.robot_pose, TRUE_BGR)
        return img

    def _robot(self, img: NDArray[np.uint8], pose: FloatArray, bgr: tuple[int, int, int]) -> None:
        draw_robot(img, self.px, pose, bgr)

    def _ellipse(
        self, img: NDArray[np.uint8], xy: FloatArray, cov: FloatArray, bgr: tuple[int, int, int]
    ) -> None:
        draw_ellipse(img, self.px, xy, cov, bgr)


Pixel = Callable[[FloatArray], tuple[int, int]]  # field point (2,) -> pixel (col, row)


def draw_robot(
    img: NDArray[np.uint8], px: Pixel, pose: FloatArray, bgr: tuple[int, int, int]
) -> None:
    """A robot at ``pose`` (3,): a ring with a 0.3 m heading line."""
    c = px(pose[:2])
    tip = px(pose[:2] + 0.3 * np.array([math.cos(pose[2]), math.sin(pose[2])]))
    cv2.circle(img, c, 6, bgr, 2)
    cv2.line(img, c, tip, bgr, 2)


def draw_ellipse(
    img: NDArray[np.uint8],
    px: Pixel,
    xy: FloatArray,
    cov: FloatArray,
    bgr: tuple[int, int, int],
) -> None:
    """The 95 % ellipse of a position ``xy`` (2,) with covariance ``cov`` (2, 2) (m²)."""
    values, vectors = np.linalg.eigh(0.5 * (cov + cov.T))
    axes = np.sqrt(np.clip(values, 0.0, None) * CHI2_2DOF_95) * PX_PER_M
    angle = -math.degrees(math.atan2(vectors[1, 1], vectors[0, 1]))
    size = (int(min(axes[1], 1e4)), int(min(axes[0], 1e4)))
    cv2.ellipse(img, px(xy), size, angle, 0, 360, bgr, 1)


def draw_detections(
    image: NDArray[np.uint8], observations: tuple[LandmarkObservation, ...]
) -> NDArray[np.uint8]:
    """Copy of an RGB camera image (H, W, 3) with each detection's box, id and range."""
    out = image.copy()
    for obs in observations:
        if np.all(np.isfinite(obs.box)):
            u0, v0, u1, v1 = (round(v) for v in obs.box)
            cv2.rectangle(out, (u0, v0), (u1, v1), (255, 255, 0), 1)
            cv2.putText(
                out,
                f"{obs.landmark_id}:{obs.range_m:.1f}m",
                (u0, max(v0 - 3, 8)),
                cv2.FONT_HERSHEY_PLAIN,
                0.8,
                (255, 255, 0),
                1,
            )
    return out


def side_by_side(
    top_down_bgr: NDArray[np.uint8], camera_rgb: NDArray[np.uint8]
) -> NDArray[np.uint8]:
    """(H, W, 3) uint8 RGB: the top-down view left, the camera image scaled to its height right."""
    rows = top_down_bgr.shape[0]
    scale = rows / camera_rgb.shape[0]
    cam = cv2.resize(
        camera_rgb, (round(camera_rgb.shape[1] * scale), rows), interpolation=cv2.INTER_NEAREST
    )
    return np.ascontiguousarray(np.hstack([cv2.cvtColor(top_down_bgr, cv2.COLOR_BGR2RGB), cam]))


class RoomView:
    """Draws a room of circular objects from above: walls, the objects' true outlines (grey),
    the laser's returns (red), the mapped circles (orange, 95 % centre ellipses), the believed
    pose (orange) and the true one (green)."""

    def __init__(self, layout: RoomLayout, wall_segments: FloatArray) -> None:
        hx, hy = layout.half_size_m
        self.half = (hx + 0.2, hy + 0.2)
        self.size = (round(2 * self.half[1] * PX_PER_M), round(2 * self.half[0] * PX_PER_M))
        img = np.full((*self.size, 3), 235, np.uint8)
        for a, b in wall_segments:
            cv2.line(img, self.px(a), self.px(b), (60, 60, 60), 3)
        for obj in layout.objects:
            outline = np.array([self.px(p) for p in obj.outline()], dtype=np.int32)
            cv2.fillPoly(img, [outline], (170, 170, 170))
        self.background = img

    def px(self, xy: FloatArray) -> tuple[int, int]:
        """Pixel (col, row) of room point ``xy`` (2,)."""
        return round((xy[0] + self.half[0]) * PX_PER_M), round((self.half[1] - xy[1]) * PX_PER_M)

    def draw(
        self, state: RoomState, output: PerceptionOutput, scan_points: FloatArray
    ) -> NDArray[np.uint8]:
        """(H, W, 3) RGB picture; ``scan_points`` (N, 2) the laser's returns (field frame, from
        the true pose)."""
        img = self.background.copy()
        for point in scan_points:
            cv2.circle(img, self.px(point), 1, (40, 40, 220), -1)
        if CIRCLE_MAP in output:
            for circle in output[CIRCLE_MAP]:
                if circle.confirmed:
                    centre, radius = circle.state[:2], circle.state[2]
                    cv2.circle(img, self.px(centre), round(radius * PX_PER_M), SLAM_BGR, 2)
                    draw_ellipse(img, self.px, centre, circle.cov[:2, :2], SLAM_BGR)
        if SELF_POSE in output:
            slam = output.get_as(SELF_POSE, SlamEstimate)
            draw_ellipse(img, self.px, slam.pose[:2], slam.pose_cov[:2, :2], SLAM_BGR)
            draw_robot(img, self.px, slam.pose, SLAM_BGR)
        draw_robot(img, self.px, state.robot_pose, TRUE_BGR)
        return np.ascontiguousarray(cv2.cvtColor(img, cv2.COLOR_BGR2RGB))
