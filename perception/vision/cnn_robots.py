"""Robot sightings from the CNN's ``robot`` detections (seed 004 §6.2, with the CNN for the
field-edge indents).

The CNN (:mod:`perception.vision.cnn_detector`) boxes each robot it sees: a box's edges are the
extremes of the robot's silhouette, so the box's bottom row shows the robot's nearest foot on
the ground and its centre column the robot's centre. Per ``robot`` detection scoring at least
``score_threshold`` (:func:`robot_sightings`):

1. a box whose bottom lies within ``border_margin_px`` of the image's bottom edge is dropped:
   the feet may be cut off, and the box bottom then shows a point above the ground that reads
   as a far robot. The seed projects the waistband of such a robot at its known height
   instead, but the CNN finds no waistband: a step that finds the waistband row in the box
   (by its colour) can call :func:`waistband_sighting`. The other part of known height the
   box shows, its top (the head top, about 0.57 m up), is useless: the camera is at about the
   same height, so the ray through the top hardly descends. On 650 whole, unoccluded robots
   1-3.6 m away in rendered frames, the head-top model gave a relative range error of 40-90 %
   (std) and up to 10x, against 3-4.5 % for the ground point;
2. the ground point of the box's bottom centre ``((u0 + u1) / 2, v1)``
   (:func:`perception.vision.ground_point.ground_point`), moved ``centre_beyond_m`` further
   from the camera (the robot's centre lies behind its nearest foot), gives range and bearing;
   none if the bottom centre lies above the horizon;
3. a box wider on the ground at that point than ``max_width_m`` is dropped: no single robot is
   that wide, but a near robot whose feet are cut off and whose box the CNN ends early, above
   the image's edge, reads as a far, wide one (seed 004's check that a sighting is not too
   narrow to be a robot, the other way round); this drops about half of those;
4. the covariance propagates an independent pixel noise of std
   ``hypot(pixel_std_px, pixel_std_per_height * box height)`` on the bottom centre's ``u``
   and ``v`` (:func:`perception.vision.ground_point.range_bearing_cov`): the CNN regresses
   log edge distances, so its edges err in proportion to the box's size.

Sightings carry no team (the CNN does not tell the teams apart; the waistband colour in the box
does) and are not sonar-confirmed. Measured on rendered frames of whole, unoccluded robots 1-3 m
away (``tests/spl_env/test_cnn_robots_rendered.py``, 382 robots): 94 % sighted (the CNN scores
the rest below 0.4); relative range error mean -0.3 %, std 4.3 %, 97 % within 10 %, largest
15 %; bearing error std 0.65 degrees, 99 % within 2 degrees, largest 2.2 degrees; the
normalised squared error of (range, bearing) averages 1.6 (2 if the covariance were exact:
it is a little wide at 2-3 m, a little narrow nearer than 1.5 m). The sway of a walking
robot's camera, which its joints do not report, is not in the covariance.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from perception.geometry import FloatArray
from perception.types import CameraModel, CameraState, RobotSighting
from perception.validation import check_positive, check_probability, finite_vector
from perception.vision.ground_point import height_point, range_bearing_cov

if TYPE_CHECKING:
    from perception.vision.cnn_detector import Detection

ROBOT_CLASS = "robot"  # the CNN's class of robots (perception.vision.cnn_detector.OBJECT_CLASSES)
_OWNER = "CnnRobotConfig"


@dataclass(frozen=True, kw_only=True)
class CnnRobotConfig:
    """Thresholds, body numbers and noise model of :func:`robot_sightings` (module doc).

    The noise numbers and ``centre_beyond_m`` were fitted, and ``border_margin_px`` and
    ``max_width_m`` chosen, on the CNN's boxes of 1675 robots in 600 rendered frames (ours
    anywhere on the field, head yaw ±0.6 rad and pitch -0.2-0.45 rad; three others 0.6-3.5 m
    ahead, turned any way).
    """

    # Minimum CNN score of a robot detection: the detector's own threshold (CnnDetectorConfig).
    score_threshold: float = 0.4
    # Std (px) of the box's bottom centre: the floor, and the part proportional to the box
    # height (maximum-likelihood fit over u and v: 0.8 px and 0.038; the box bottom's error is
    # 2 px at 60 px tall boxes, 5 px at 125 px, 11 px above 150 px).
    pixel_std_px: float = 1.0
    pixel_std_per_height: float = 0.04
    # A box bottom this close (px) to the image's bottom edge may be cut by it: no sighting.
    # Of the robots whose feet the image cuts off, the CNN ends 6 % of the boxes more than
    # 12 px above the edge (8 px: 11 %), their ranges then too far by up to 4x.
    border_margin_px: float = 12.0
    # The robot's centre lies this far (m) behind the ground point of its box bottom: the
    # nearest foot's edge is 0.045-0.085 m in front of the centre by the robot's turn
    # (spl_env/robots/nao.py _body_parts: legs 0.09 m deep at y = ±0.05 m, 0.07 m wide);
    # 0.05 m zeroes the mean range error of the CNN's boxes.
    centre_beyond_m: float = 0.05
    # A box wider than this on the ground (m) at its bottom is not one robot (a Nao is 0.27 m
    # across the arms; whole robots' boxes measured up to 0.41 m, boxes of cut-off near robots
    # read as 0.14-0.96 m wide).
    max_width_m: float = 0.45
    # Height (m) of the waistband's centre on a standing Nao: spl_env/robots/nao.py
    # _body_parts puts the waistband box (0.04 m tall) centred at 0.28 m (not imported:
    # perception must not depend on the simulator).
    waistband_height_m: float = 0.28

    def __post_init__(self) -> None:
        check_probability(_OWNER, "score_threshold", self.score_threshold, float_only=True)
        check_positive(_OWNER, "pixel_std_px", self.pixel_std_px)
        check_positive(_OWNER, "pixel_std_per_height", self.pixel_std_per_height, allow_zero=True)
        check_positive(_OWNER, "border_margin_px", self.border_margin_px, allow_zero=True)
        check_positive(_OWNER, "centre_beyond_m", self.centre_beyond_m, allow_zero=True)
        check_positive(_OWNER, "max_width_m", self.max_width_m)
        check_positive(_OWNER, "waistband_height_m", self.waistband_height_m)

    def pixel_std(self, box: FloatArray) -> float:
        """Std (px) of the bottom centre of a box (4,) ``(u0, v0, u1, v1)``."""
        return math.hypot(self.pixel_std_px, self.pixel_std_per_height * float(box[3] - box[1]))


def robot_sightings(
    detections: Sequence[Detection],
    camera: CameraModel,
    state: CameraState,
    config: CnnRobotConfig,
) -> tuple[RobotSighting, ...]:
    """Sightings (robot frame) of the robots among ``detections`` (the CNN's, any classes) in a
    frame of ``camera`` taken from ``state``: one per ``robot`` detection scoring at least
    ``config.score_threshold`` that the module doc's steps keep, in the detections' order.

    Raises ValueError if such a detection's box is not 4 finite numbers.
    """
    found = []
    for k, detection in enumerate(detections):
        if detection.class_name != ROBOT_CLASS or detection.score < config.score_threshold:
            continue
        box = finite_vector(detection.box, f"detections[{k}].box", 4)
        sighting = _box_sighting(box, float(detection.score), camera, state, config)
        if sighting is not None:
            found.append(sighting)
    return tuple(found)


def box_bottom_cut(box: FloatArray, camera: CameraModel, config: CnnRobotConfig) -> bool:
    """Whether a box (4,) ``(u0, v0, u1, v1)`` ends within ``config.border_margin_px`` of the
    image's bottom edge (row ``camera.height - 0.5``), so the robot's feet may be cut off."""
    return bool(box[3] > camera.height - 0.5 - config.border_margin_px)


def waistband_sighting(
    box: FloatArray,
    waistband_v: float,
    camera: CameraModel,
    state: CameraState,
    config: CnnRobotConfig,
    score: float = 1.0,
) -> RobotSighting | None:
    """The sighting of a standing robot in box (4,) ``(u0, v0, u1, v1)`` whose waistband's
    centre was found at image row ``waistband_v`` (px): seed 004 §6.2's model for a robot
    whose feet are cut off. The ray through ``((u0 + u1) / 2, waistband_v)`` meets the plane
    ``z = config.waistband_height_m``; the centre lies ``config.centre_beyond_m`` behind (the
    waistband's front is as far in front of it as the feet's). None if the ray does not
    reach that plane (a camera above the waistband sees it below the horizon only)."""
    box = finite_vector(box, "box", 4)
    pixel = np.array([(box[0] + box[2]) / 2, float(waistband_v)])
    return _sighting(pixel, config.waistband_height_m, box, score, camera, state, config)


def _box_sighting(
    box: FloatArray,
    score: float,
    camera: CameraModel,
    state: CameraState,
    config: CnnRobotConfig,
) -> RobotSighting | None:
    """Steps 1-4 of the module doc for one robot box (4,)."""
    if not (box[2] > box[0] and box[3] > box[1]) or box_bottom_cut(box, camera, config):
        return None
    left = height_point(np.array([box[0], box[3]]), 0.0, camera, state)
    right = height_point(np.array([box[2], box[3]]), 0.0, camera, state)
    if left is None or right is None:
        return None
    if _distance(left, right) > config.max_width_m:
        return None
    pixel = np.array([(box[0] + box[2]) / 2, box[3]])
    return _sighting(pixel, 0.0, box, score, camera, state, config)


def _sighting(
    pixel: FloatArray,
    height_m: float,
    box: FloatArray,
    score: float,
    camera: CameraModel,
    state: CameraState,
    config: CnnRobotConfig,
) -> RobotSighting | None:
    """The sighting of a robot whose centre lies ``config.centre_beyond_m`` behind the point
    at ``height_m`` seen at ``pixel`` (2,), or None if that point is not seen."""
    beyond = config.centre_beyond_m
    point = height_point(pixel, height_m, camera, state, beyond)
    cov = range_bearing_cov(pixel, camera, state, config.pixel_std(box), height_m, beyond)
    if point is None or cov is None:
        return None
    return RobotSighting(
        range_m=point[0], bearing_rad=point[1], cov=cov, team=None, box=box.copy(), score=score
    )


def _distance(a: tuple[float, float], b: tuple[float, float]) -> float:
    """Distance (m) between two points given as (range, bearing)."""
    return math.dist(
        (a[0] * math.cos(a[1]), a[0] * math.sin(a[1])),
        (b[0] * math.cos(b[1]), b[0] * math.sin(b[1])),
    )
