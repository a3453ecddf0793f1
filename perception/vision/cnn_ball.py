"""Ball sightings from the CNN's ``ball`` detections.

The CNN (:mod:`perception.vision.cnn_detector`) boxes the ball it sees; a sphere's silhouette
is a disc centred (to well under a pixel at the ball's sizes in our images) on the projection of
its centre, so the box centre shows the ball's centre, which lies ``radius_m`` above the ground.
Per ``ball`` detection scoring at least ``score_threshold`` (:func:`ball_sightings`):

1. a box within ``border_margin_px`` of an image edge is dropped: the ball is cut off there and
   the box centre is not the ball's;
2. the ray through the box centre (moved ``row_offset_px`` down: a renderer's row offset)
   meets the plane ``z = radius_m`` (:func:`perception.vision.ground_point.height_point`): the
   range and bearing of the ball's centre; none when the box centre lies above the horizon
   (the ray never descends to it);
3. a box whose width says the ball is much nearer or farther than that (the apparent diameter
   ``2 r f / d`` off by more than ``size_tolerance`` of itself) is dropped: something round and
   white that is not the ball on the ground (a robot's part, a ball in the air);
4. a box whose centre lies on our own body's silhouette (``body``,
   :mod:`perception.vision.body_contour`) is dropped: the head turned to the side and pitched
   down shows the top camera its own grey shoulder, which the CNN can take for the ball (and a
   ball there would be hidden behind it);
5. a box whose middle is flat (:func:`middle_shading`: the luminance of its middle half varies
   with a std under ``min_shading_std`` grey levels) is dropped: a lit sphere shades from its
   lit side to its dark one, a painted penalty mark (the bottom camera at the feet takes it
   for the ball) or a flat grey plate does not; boxes under ``min_judged_px`` across (too
   small to judge) and over-exposed middles (``clipped_luminance``: flat because clipped)
   are kept;
6. the covariance propagates an independent pixel noise of std
   ``hypot(pixel_std_px * downscale, pixel_std_per_size * box width)`` on the centre's ``u``
   and ``v`` (``downscale``: the image was read at that fraction of its resolution), and on
   ``v`` also ``fy * camera_tilt_std_rad``: the walk's sway tilts the camera in a way the
   camera state does not know, which moves the whole image up and down
   (:func:`perception.vision.ground_point.range_bearing_cov`).

Sightings come best score first; the fitted numbers and where they come from are in
:class:`CnnBallConfig`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from perception.geometry import FloatArray
from perception.types import BallSighting, CameraModel, CameraState
from perception.validation import (
    check_in_interval,
    check_int,
    check_nested_configs,
    check_positive,
    check_probability,
    check_rgb_image,
    finite_vector,
)
from perception.vision.body_contour import BodyContourConfig, body_silhouettes, on_body
from perception.vision.field_pixels import GroundProjection
from perception.vision.ground_point import height_point, range_bearing_cov

if TYPE_CHECKING:
    from perception.vision.cnn_detector import Detection

BALL_CLASS = "ball"  # the CNN's class of the ball (perception.vision.cnn_detector.OBJECT_CLASSES)
_OWNER = "CnnBallConfig"


@dataclass(frozen=True, kw_only=True)
class CnnBallConfig:
    """Thresholds, the ball's size and the noise model of :func:`ball_sightings` (module doc).

    The noise numbers were fitted on the CNN's boxes of the ball in rendered frames of the
    tuning seeds (``python benchmarks/ball_detection.py``, seeds 0-4).
    """

    score_threshold: float = 0.4  # the detector's own threshold (CnnDetectorConfig)
    radius_m: float = 0.05  # SPL ball: 0.1 m across (perception.field.dimensions)
    border_margin_px: float = 1.0  # a box this close (px) to an image edge is cut off
    # Std (px) of the box centre: a floor plus a part proportional to the box width
    # (maximum-likelihood fit on 543 boxes of the tuning seeds: 1.15 px and 0.0475).
    pixel_std_px: float = 1.15
    pixel_std_per_size: float = 0.0475
    # Std (rad) of the camera's pitch that its state misses (the gait's sway); 0: none. The
    # maximum-likelihood fit to the range errors of the top camera's sightings of the ball
    # while walking (rendered striker, tuning seeds 0-15, 1781 sightings within 5 m,
    # benchmarks/ball_sighting_noise.py): range NEES 2.0-6.8 by band without it, 0.8-1.4 with
    # it. Measured together with the ball filter's start_confirm_s (docs/measurements.md).
    camera_tilt_std_rad: float = 0.008
    # A box whose width is off the width the ball would have at the range read from its
    # centre by more than this fraction of it is not the ball on the ground.
    size_tolerance: float = 0.6
    # The image shows this many rows higher than the camera model says (PyBullet's tiny
    # renderer: 1.0, perception.vision.field_features); 0 for a camera that obeys the model.
    row_offset_px: float = 0.0
    # The bottom camera's images are read at 1/bottom_downscale of their resolution (the
    # ball near the feet is larger than any the CNN saw in training: at full resolution it
    # finds 5 % of the balls nearer than 0.3 m, at half 82 %; rendered bottom-camera frames)
    bottom_downscale: int = 2
    # Our own body's boxes, whose silhouettes no ball sighting may lie on; None: not checked
    body: BodyContourConfig | None = field(default_factory=BodyContourConfig)
    # A box's middle half whose luminance (mean of R, G, B; 0-255) varies less than this (std)
    # is flat, not the ball; None: not checked. Fitted on the CNN's ball boxes in the rendered
    # striker without the check, tuning seeds 0-15 (benchmarks/ball_flatness.py): the bottom
    # camera's 452 of the penalty mark at most 1.2 in 95 % (the camera's noise), 4.9 at most;
    # its 277 of the ball at least 12.5 in 99 % (one of 1.1: a flat robot part beside the
    # ball); the top camera's 1189 judged of the ball at least 7.2. Under randomised lighting a
    # ball lit mostly by ambient light shades less (benchmarks/ball_detection.py, tuning seeds
    # 0-4: 1 % of the visible balls' judged boxes under 5.8 top, 5.6 bottom).
    min_shading_std: float | None = 3.0
    # Boxes narrower or lower than this (px) are not judged: a smaller ball's middle shades too
    # little to tell (judged from 8 px, the top camera's recall at 2-3 m fell 2.3 points on the
    # tuning frames of benchmarks/ball_detection.py, 4.7 on its held-out ones, which this
    # choice therefore saw; the marks at the feet box 50-90 px)
    min_judged_px: float = 16.0
    # A middle whose median luminance reaches this is over-exposed (flat because clipped at
    # 255, ball or mark): not judged
    clipped_luminance: float = 250.0

    def __post_init__(self) -> None:
        check_nested_configs(self)
        check_probability(_OWNER, "score_threshold", self.score_threshold, float_only=True)
        check_positive(_OWNER, "radius_m", self.radius_m)
        check_positive(_OWNER, "border_margin_px", self.border_margin_px, allow_zero=True)
        check_positive(_OWNER, "pixel_std_px", self.pixel_std_px)
        check_positive(_OWNER, "pixel_std_per_size", self.pixel_std_per_size, allow_zero=True)
        check_positive(_OWNER, "camera_tilt_std_rad", self.camera_tilt_std_rad, allow_zero=True)
        check_positive(_OWNER, "size_tolerance", self.size_tolerance)
        check_in_interval(_OWNER, "row_offset_px", self.row_offset_px, -5.0, 5.0)
        check_int(_OWNER, "bottom_downscale", self.bottom_downscale, 1)
        if self.min_shading_std is not None:
            check_positive(_OWNER, "min_shading_std", self.min_shading_std)
        check_positive(_OWNER, "min_judged_px", self.min_judged_px)
        check_positive(
            _OWNER, "clipped_luminance", self.clipped_luminance, upper=255.0, upper_inclusive=True
        )

    def pixel_std(self, box: FloatArray, downscale: int = 1) -> float:
        """Std (px) of the centre of a box (4,) ``(u0, v0, u1, v1)`` found in the image read at
        1/``downscale`` resolution (the floor scales with it: fitted on the bottom camera at
        half resolution, 2.2 px and 0.06)."""
        floor = self.pixel_std_px * downscale
        return math.hypot(floor, self.pixel_std_per_size * float(box[2] - box[0]))


def ball_sightings(
    detections: Sequence[Detection],
    camera: CameraModel,
    state: CameraState,
    config: CnnBallConfig,
    downscale: int = 1,
    *,
    image: NDArray[np.uint8] | None,
) -> tuple[BallSighting, ...]:
    """Sightings (robot frame) of the ball among ``detections`` (the CNN's, any classes) in
    ``image`` (H, W, 3) uint8 RGB, a frame of ``camera`` taken from ``state`` and read at
    1/``downscale`` resolution (boxes in ``image``'s pixels): one per ``ball`` detection
    scoring at least ``config.score_threshold`` that the module doc's steps keep, best score
    first. ``image`` may be None only where ``config.min_shading_std`` is None (nothing to
    look at).

    Raises ValueError if such a detection's box is not 4 finite numbers, or if ``image`` is
    needed and None or not of the camera's size.
    """
    if config.min_shading_std is not None:  # the flat-box check looks at the frame
        check_rgb_image(image, camera.height, camera.width)
    found = []
    body: list[FloatArray] | None = None  # our body's silhouettes, made at the first ball box
    for k, detection in enumerate(detections):
        if detection.class_name != BALL_CLASS or detection.score < config.score_threshold:
            continue
        box = finite_vector(detection.box, f"detections[{k}].box", 4)
        sighting = _box_sighting(box, float(detection.score), camera, state, config, downscale)
        if sighting is None:
            continue
        if image is not None and config.min_shading_std is not None:
            shading = middle_shading(image, box, config)
            if shading is not None and shading < config.min_shading_std:
                continue
        if config.body is not None:
            if body is None:
                body = body_silhouettes(config.body, camera, state)
            if on_body(_box_centre(box, config), body, config.body.margin_px):
                continue
        found.append(sighting)
    return tuple(sorted(found, key=lambda s: -s.score))


def middle_shading(
    image: NDArray[np.uint8], box: FloatArray, config: CnnBallConfig
) -> float | None:
    """The std of the luminance (the mean of R, G and B, 0-255) over the middle half (in width
    and height) of ``box`` (4,) ``(u0, v0, u1, v1)`` px in ``image`` (H, W, 3) uint8 RGB: the
    pixels whose centres (pixel ``i`` at ``i``) lie within ``[u0 + w/4, u1 - w/4]`` and
    ``[v0 + h/4, v1 - h/4]`` and inside the image; None where there is nothing to judge: a box
    narrower or lower than ``config.min_judged_px``, a middle outside the image, or one whose
    median luminance reaches ``config.clipped_luminance`` (over-exposed, as flat as a mark)."""
    u0, v0, u1, v1 = (float(x) for x in box)
    if u1 - u0 < config.min_judged_px or v1 - v0 < config.min_judged_px:
        return None
    height, width = image.shape[:2]
    du, dv = (u1 - u0) / 4, (v1 - v0) / 4
    cols = _centres_within(u0 + du, u1 - du, width)
    rows = _centres_within(v0 + dv, v1 - dv, height)
    if cols is None or rows is None:
        return None
    middle = image[rows, cols]
    luminance = middle.mean(axis=2, dtype=np.float64)
    if np.median(luminance) >= config.clipped_luminance:
        return None
    return float(luminance.std())


def _centres_within(low: float, high: float, size: int) -> slice | None:
    """The pixels (pixel ``i`` centred at ``i``) of ``0 .. size - 1`` whose centres lie in
    ``[low, high]``; None if none do."""
    first, last = max(math.ceil(low), 0), min(math.floor(high), size - 1)
    return slice(first, last + 1) if first <= last else None


def ball_in_view(
    point: FloatArray, camera: CameraModel, state: CameraState, radius_m: float, margin: float
) -> bool:
    """Whether a ball lying at ``point`` (2,) (m, robot frame; its centre ``radius_m`` above
    the ground) shows in the image of ``camera`` taken from ``state``, at least ``margin`` (a
    share of the image's width and height) inside its edges."""
    centre = np.array([[point[0], point[1], radius_m]])
    pixel, front = GroundProjection(camera, state).project(centre)
    if not front[0]:
        return False
    u, v = pixel[0]
    du, dv = margin * camera.width, margin * camera.height
    return bool(du <= u <= camera.width - du and dv <= v <= camera.height - dv)


def _box_sighting(
    box: FloatArray,
    score: float,
    camera: CameraModel,
    state: CameraState,
    config: CnnBallConfig,
    downscale: int,
) -> BallSighting | None:
    """Steps 1-3 and 6 of the module doc for one ball box (4,)."""
    if not (box[2] > box[0] and box[3] > box[1]) or _cut_off(box, camera, config):
        return None
    centre = _box_centre(box, config)
    point = height_point(centre, config.radius_m, camera, state)
    if point is None:
        return None
    range_m, bearing_rad = point
    camera_distance = math.dist(
        (range_m * math.cos(bearing_rad), range_m * math.sin(bearing_rad), config.radius_m),
        tuple(state.position),
    )
    expected_width = 2 * config.radius_m * camera.fx / camera_distance
    if abs(float(box[2] - box[0]) - expected_width) > config.size_tolerance * expected_width:
        return None
    std = config.pixel_std(box, downscale)
    row_std = math.hypot(std, camera.fy * config.camera_tilt_std_rad)
    cov = range_bearing_cov(centre, camera, state, (std, row_std), config.radius_m)
    if cov is None:
        return None
    return BallSighting(
        range_m=range_m, bearing_rad=bearing_rad, cov=cov, box=box.copy(), score=score
    )


def _box_centre(box: FloatArray, config: CnnBallConfig) -> FloatArray:
    """The centre (2,) px of a box (4,) in the camera model's pixels: moved
    ``config.row_offset_px`` down (the renderer draws rows that much higher)."""
    return np.array([(box[0] + box[2]) / 2, (box[1] + box[3]) / 2 + config.row_offset_px])


def _cut_off(box: FloatArray, camera: CameraModel, config: CnnBallConfig) -> bool:
    """Whether a box (4,) lies within ``config.border_margin_px`` of an image edge (pixel
    centres run from 0 to width - 1 and height - 1; the image's edges are half a pixel out)."""
    margin = config.border_margin_px - 0.5
    return bool(
        box[0] < margin
        or box[1] < margin
        or box[2] > camera.width - 1 - margin
        or box[3] > camera.height - 1 - margin
    )
