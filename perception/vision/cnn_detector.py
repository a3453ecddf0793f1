"""Seed 000's CNN front end (§3.4): a small single-shot detector of poles, goal posts, ball, robots.

The network (:mod:`perception.vision.cnn_model`, loaded lazily with torch) finds each object's
keypoint, class and box in a (240, 320, 3) uint8 RGB frame; a pole's keypoint is the junction
of its two colour bands. Seed eqs. 3.3/3.4, refitted to this camera, turn a pole's extent in
pixels into the horizontal distance d from the camera to the pole axis, ``d = a * extent **
-b`` with one fitted law per extent. Extents are *upright* (:func:`pole_extents`): what a
level camera turned to face the pole would see, since a pitched head makes the image of a
vertical pole lean and stretch (seed 000 fits a rotated box to its segmentation for the same
reason). The extent used (:meth:`PoleRangeModel.branch`):

- the box height while the box is as tall as its width says it should be (seed eq. 3.4);
- when the box is wider than expected for its height (``log(width / height)`` more than
  ``aspect_margin`` above the fitted ``log(c * height ** -k)``: the height cut by an
  occluder) or the box touches the bottom border: the extent from the junction to the top;
  when it touches the top border: the extent from the junction to the bottom. The seed takes
  the width here (eq. 3.3), but the network's box widths (3-30 px) are off by about 13 %
  (median) against about 4 % for these extents;
- the width (eq. 3.3) when the box touches both the top and the bottom border; if its sides
  touch the left or right border too, every size is cut and the smaller of the height's and
  the width's distance is taken.

Where at least three of the pole's band edges (top, junction, base, bottom) are found in the
image and agree, the distance comes from them instead (:mod:`perception.vision.pole_edges`:
sub-pixel edge rows on a known ruler), with the relative variance their least-squares fit
implies; failing that, a near pole is measured across its width. On held-out frames the edges
give 1.2 % mean relative range error against 4.2 % for the extents on the same poles, and
nearer than 1 m the width cuts gross errors (over 25 %) from 19 % of sightings to 4 %.

The bearing follows the colour filter's route (:mod:`perception.vision.colour_filter`): the ray
through the box centre, turned into the robot frame by the camera state, gives the heading;
the pole axis lies ``d`` along it from the camera, and its range and bearing from the robot
origin are the measurement. The covariance is diagonal: relative range variance
``c0 + c1 / extent_px ** 2`` per extent and bearing std ``bearing_std_px / fx``, all fitted on
the training set by ``training.train_detector`` and stored with the weights.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from perception.geometry import FloatArray, pixel_rays
from perception.types import (
    CameraModel,
    CameraState,
    LandmarkObservation,
    PoleCode,
    PoleGeometry,
    pole_ids_by_colours,
)
from perception.validation import (
    check_bool,
    check_int,
    check_nested_configs,
    check_probability,
    check_rgb_image,
)
from perception.vision.colour_filter import ColourFilterConfig
from perception.vision.pole_colours import band_colours, colours_contradict, paint_hues
from perception.vision.pole_edges import (
    PoleEdgeConfig,
    cross_section_px,
    expected_rows,
    pole_edge_distance,
    pole_width_distance,
)

if TYPE_CHECKING:
    from torch import nn

    from perception.vision.cnn_model import PoleNet

OBJECT_CLASSES: tuple[str, ...] = ("goal_post", "ball", "robot")
WEIGHTS_FORMAT = "spl-env-pole-detector-1"
POLE_OVERLAP_IOU = 0.4  # a pole detection overlapping a better one by more is the same pole
# Pole detections with the band junction nearer the top or bottom border are dropped: too
# little of a band shows to trust the class (3 px let class confusions through).
JUNCTION_BORDER_PX = 10.0
_BORDER_PX = 8.0  # a box edge this close to the image border (px) is cut by it
_MIN_EXTENT_PX = 0.5  # extents below this (a keypoint regressed past a box edge) count as this


def cut_sides(box: FloatArray, camera: CameraModel) -> tuple[bool, bool, bool, bool]:
    """Whether a box (4,) pixel edges ``(u0, v0, u1, v1)`` is cut by the image's left, top,
    right and bottom border: its edge lies within ``_BORDER_PX`` of it."""
    return (
        bool(box[0] < _BORDER_PX - 0.5),
        bool(box[1] < _BORDER_PX - 0.5),
        bool(box[2] > camera.width - 0.5 - _BORDER_PX),
        bool(box[3] > camera.height - 0.5 - _BORDER_PX),
    )


def pole_class_name(code: PoleCode) -> str:
    """The detector class of a pole: ``pole_<top>_<bottom>``, e.g. ``pole_pink_yellow``."""
    return f"pole_{code.top}_{code.bottom}"


def default_weights() -> Path:
    """The packaged weights file ``perception/vision/weights/pole_detector.pt``."""
    return Path(str(resources.files("perception.vision") / "weights" / "pole_detector.pt"))


@dataclass(frozen=True, kw_only=True)
class CnnDetectorConfig:
    """Weights file and detection thresholds of :class:`CnnPoleDetector`."""

    weights: Path = field(default_factory=default_weights)
    # Minimum heatmap peak probability of a detection. 0.4 balances precision and recall on
    # the tuning frames of ``benchmarks/front_ends.py --protocol random --seed 2`` (98.8 % /
    # 98.5 % within 5 m; 0.35: 98.2 / 99.0, 0.45: 99.0 / 97.8). Seed 000 used 0.85 / 0.875.
    score_threshold: float = 0.4
    max_detections: int = 20  # per frame, all classes
    # Distance from the band edges (perception.vision.pole_edges) where they are found; None:
    # from the box extents only.
    edges: PoleEdgeConfig | None = field(default_factory=PoleEdgeConfig)
    # Drop a pole detection whose band colours contradict its class (perception.vision.
    # pole_colours); needs the image.
    check_colours: bool = True
    # Also drop one unless both band colours are seen and named (with check_colours): a pole
    # whose other band is hidden cannot be told from its neighbours. Off for detection; the
    # env's SLAM front end turns it on (perception.pipeline.PipelineConfig).
    require_both_colours: bool = False

    def __post_init__(self) -> None:
        check_nested_configs(self)
        if not isinstance(self.weights, Path):
            raise TypeError(
                f"CnnDetectorConfig.weights must be a pathlib.Path, got {type(self.weights)}"
            )
        check_probability(
            "CnnDetectorConfig", "score_threshold", self.score_threshold, float_only=True
        )
        check_int("CnnDetectorConfig", "max_detections", self.max_detections, 1)
        for name in ("check_colours", "require_both_colours"):
            check_bool("CnnDetectorConfig", name, getattr(self, name))


@dataclass(frozen=True)
class Detection:
    """One detected object: ``class_name`` and ``class_id``, ``box`` (4,) pixel edges
    ``(u0, v0, u1, v1)`` (pixel i centred at u = i), ``score`` in (0, 1) and ``keypoint`` (2,)
    ``(u, v)`` px (a pole's band junction, else the box centre)."""

    class_name: str
    class_id: int
    box: FloatArray
    score: float
    keypoint: FloatArray


@dataclass(frozen=True, kw_only=True)
class PowerLaw:
    """``y = a * x ** -b`` for x > 0 (seed 000 eqs. 3.2-3.4)."""

    a: float
    b: float

    def __call__(self, x: float) -> float:
        return self.a * x ** (-self.b)


NETWORK_STRIDE = 32  # an input's height and width must be multiples of this
BRANCHES: tuple[str, ...] = ("height", "top", "bottom", "width")
"""The extents a pole's distance can come from, in the order of preference (module doc)."""


@dataclass(frozen=True)
class PoleExtents:
    """Upright extents (px) of a pole's image (see :func:`pole_extents`): the box's ``width``
    and ``height``, and from the band junction to the box's ``top`` and ``bottom`` edges."""

    width: float
    height: float
    top: float
    bottom: float


@dataclass(frozen=True, kw_only=True)
class PoleRangeModel:
    """Distance of a pole from its extents, and the measurement noise (see the module doc).

    ``laws`` maps each of :data:`BRANCHES` to the power law giving the horizontal
    camera-to-axis distance (m) from that upright extent (px); ``aspect_law`` gives the
    expected width / height from the height, with ``aspect_margin`` the log ratio beyond which
    the height counts as cut. ``rel_var`` maps each branch to ``(c0, c1)`` of the relative range
    variance ``c0 + c1 / extent ** 2``; ``bearing_std_px`` is the bearing noise in pixels.
    """

    laws: dict[str, PowerLaw]
    aspect_law: PowerLaw
    aspect_margin: float
    rel_var: dict[str, tuple[float, float]]
    bearing_std_px: float

    def __post_init__(self) -> None:
        check_nested_configs(self)
        for name in ("laws", "rel_var"):
            if set(getattr(self, name)) != set(BRANCHES):
                raise ValueError(
                    f"PoleRangeModel.{name} must have the keys {BRANCHES}, "
                    f"got {tuple(getattr(self, name))}"
                )

    @staticmethod
    def from_dict(data: dict[str, Any]) -> PoleRangeModel:
        """Inverse of :func:`dataclasses.asdict`."""
        return PoleRangeModel(
            laws={k: PowerLaw(**v) for k, v in data["laws"].items()},
            aspect_law=PowerLaw(**data["aspect_law"]),
            aspect_margin=float(data["aspect_margin"]),
            rel_var={k: (float(v[0]), float(v[1])) for k, v in data["rel_var"].items()},
            bearing_std_px=float(data["bearing_std_px"]),
        )

    def branch(self, extents: PoleExtents, box: FloatArray, camera: CameraModel) -> str:
        """Which extent of a pole with box (4,) pixel edges gives its distance: the height if
        whole, else the part on the uncut side of the junction, else the width."""
        _, top_cut, _, bottom_cut = cut_sides(box, camera)
        expected = math.log(self.aspect_law(extents.height))
        if top_cut and bottom_cut:
            return "width"
        if top_cut:
            return "bottom"
        if bottom_cut or math.log(extents.width / extents.height) > expected + self.aspect_margin:
            return "top"
        return "height"

    def distance(
        self, extents: PoleExtents, box: FloatArray, camera: CameraModel
    ) -> tuple[float, float, str]:
        """Camera-to-axis distance (m) of a pole with ``extents`` and box (4,) pixel edges, the
        relative variance of the range measured with it, and the branch used."""
        branch = self.branch(extents, box, camera)
        size = max(getattr(extents, branch), _MIN_EXTENT_PX)
        distance = self.laws[branch](size)
        left_cut, _, right_cut, _ = cut_sides(box, camera)
        if branch == "width" and (left_cut or right_cut):
            # cut on every side: each size only bounds the distance from above
            distance = min(distance, self.laws["height"](extents.height))
        c0, c1 = self.rel_var[branch]
        return distance, c0 + c1 / size**2, branch


def vertical_lean(box: FloatArray, camera: CameraModel, rotation: FloatArray) -> float:
    """Image slope ``du/dv`` of a vertical line through the centre of ``box`` (4,) pixel edges
    seen by a camera with camera-to-robot ``rotation`` (3, 3): the derivative of the pinhole
    projection along the vertical, whose camera-frame direction is ``rotation``'s last row
    (0 if the vertical does not point up in the image)."""
    uc, vc = (float(box[0]) + float(box[2])) / 2, (float(box[1]) + float(box[3])) / 2
    up = rotation[2]
    du = camera.fx * (up[1] - up[0] * (camera.cx - uc) / camera.fx)
    dv = camera.fy * (up[2] - up[0] * (camera.cy - vc) / camera.fy)
    return du / dv if dv > 0 else 0.0


def _pole_rays(
    box: FloatArray, keypoint: FloatArray, camera: CameraModel, rotation: FloatArray
) -> FloatArray:
    """Unit rays (6, 3) in the robot frame through points of a vertical pole's box (4,) pixel
    edges: its centre, the pole's top and bottom ends, its band junction ``keypoint`` (2,) and
    the ends of its horizontal cross-section at the centre row; ``rotation`` (3, 3) is
    camera-to-robot.

    The image of the vertical through the centre leans by ``s = du/dv``
    (:func:`vertical_lean`); the pole's ends lie on that line at the box's top and bottom rows,
    and its cross-section is the box width less ``|s|`` x its height.
    """
    u0, v0, u1, v1 = (float(x) for x in box)
    uc, vc = (u0 + u1) / 2, (v0 + v1) / 2
    lean = vertical_lean(box, camera, rotation)
    half = 0.5 * cross_section_px(box, lean)
    points = np.array(
        [
            [uc, vc],
            [uc + lean * (v0 - vc), v0],
            [uc + lean * (v1 - vc), v1],
            keypoint,
            [uc - half, vc],
            [uc + half, vc],
        ]
    )
    return pixel_rays(points, camera.fx, camera.fy, camera.cx, camera.cy) @ rotation.T


def _extents_from_rays(rays: FloatArray, camera: CameraModel) -> PoleExtents:
    """Upright extents from the (6, 3) rays of :func:`_pole_rays`: with the elevations ``e``
    of the top, bottom and junction rays and the azimuths ``a`` of the cross-section's, the
    vertical extents are ``fx`` times differences of ``tan e`` and the width is
    ``2 fx tan(|a_left - a_right| / 2)``."""
    top, bottom, junction = camera.fx * rays[1:4, 2] / np.hypot(rays[1:4, 0], rays[1:4, 1])
    left, right = np.arctan2(rays[4:, 1], rays[4:, 0])
    return PoleExtents(
        width=2 * camera.fx * math.tan(abs(left - right) / 2),
        height=float(top - bottom),
        top=float(top - junction),
        bottom=float(junction - bottom),
    )


def pole_extents(
    box: FloatArray, keypoint: FloatArray, camera: CameraModel, state: CameraState
) -> PoleExtents:
    """Extents (px) of a vertical pole with box (4,) pixel edges and band junction
    ``keypoint`` (2,) px, seen from ``state``, as a level camera at the same place turned to
    face the pole would see them (see :func:`_pole_rays` and :func:`_extents_from_rays`)."""
    return _extents_from_rays(_pole_rays(box, keypoint, camera, state.rotation()), camera)


def _axis_range_bearing(
    ray: FloatArray, distance: float, camera_xy: FloatArray
) -> tuple[float, float]:
    """Range (m) and bearing (rad) from the robot origin of the pole axis ``distance`` m from
    the camera at ``camera_xy`` (2,) along the horizontal heading of robot-frame ``ray`` (3,)."""
    heading = ray[:2] / math.hypot(ray[0], ray[1])
    axis = camera_xy + distance * heading
    return math.hypot(axis[0], axis[1]), math.atan2(axis[1], axis[0])


def box_iou(a: FloatArray, b: FloatArray) -> float:
    """Intersection over union of two (4,) pixel-edge boxes ``(u0, v0, u1, v1)``."""
    w = max(0.0, min(a[2], b[2]) - max(a[0], b[0]))
    h = max(0.0, min(a[3], b[3]) - max(a[1], b[1]))
    inter = w * h
    union = (a[2] - a[0]) * (a[3] - a[1]) + (b[2] - b[0]) * (b[3] - b[1]) - inter
    return float(inter / union) if union > 0 else 0.0


def pole_range_bearing(
    pixel: FloatArray, distance: float, camera: CameraModel, state: CameraState
) -> tuple[float, float]:
    """Range (m) and bearing (rad, robot frame) of a pole axis seen at ``pixel`` (2,) ``(u, v)``
    px, ``distance`` m horizontally from the camera (the colour filter's route: the ray through
    the pixel, turned into the robot frame, gives the heading from the camera)."""
    ray = pixel_rays(pixel, camera.fx, camera.fy, camera.cx, camera.cy)[0] @ state.rotation().T
    return _axis_range_bearing(ray, distance, state.position[:2])


class CnnPoleDetector:
    """Detects poles, goal posts, the ball and robots with the CNN; poles become landmark
    sightings in the robot frame.

    ``camera`` must match the camera the weights were trained for; ``codes`` map pole classes
    to landmark ids; ``pole`` is the pole geometry (the heights of its band edges; the range
    laws encode it for the extents).
    Raises ``ValueError`` if the weights file is not a detector file of this format, was
    trained for another camera or lacks a class of ``codes``, or if ``codes`` repeat a colour
    pair or an id.
    """

    def __init__(
        self,
        config: CnnDetectorConfig,
        camera: CameraModel,
        codes: Sequence[PoleCode],
        pole: PoleGeometry,
    ) -> None:
        import torch

        self.config = config
        self.camera = camera
        self.pole = pole
        data = torch.load(config.weights, map_location="cpu", weights_only=True)
        if not isinstance(data, dict) or data.get("format") != WEIGHTS_FORMAT:
            raise ValueError(f"{config.weights} is not a {WEIGHTS_FORMAT!r} weights file")
        trained = data["camera"]
        if (trained["width"], trained["height"], trained["hfov_deg"]) != (
            camera.width,
            camera.height,
            camera.hfov_deg,
        ):
            raise ValueError(f"camera must match the weights' camera {trained}, got {camera}")
        self.classes: tuple[str, ...] = tuple(data["classes"])
        self._landmark_of: dict[int, int] = {}
        self._colours_of: dict[int, tuple[str, str]] = {}
        self._paint_hues = paint_hues(ColourFilterConfig())
        for (top, bottom), landmark_id in pole_ids_by_colours(codes).items():
            name = pole_class_name(PoleCode(landmark_id=landmark_id, top=top, bottom=bottom))
            if name not in self.classes:
                raise ValueError(f"codes: class {name!r} is not among the weights' {self.classes}")
            self._landmark_of[self.classes.index(name)] = landmark_id
            self._colours_of[landmark_id] = (top, bottom)
        self.range_model = PoleRangeModel.from_dict(data["range_model"])
        self._net = load_network(data)

    @property
    def network(self) -> nn.Module:
        """The inference network: (N, 3, H, W) float RGB in [0, 1] to raw outputs."""
        return self._net

    def detect_objects(self, image: NDArray[np.uint8]) -> list[Detection]:
        """All detections in ``image`` (H, W, 3) uint8 RGB, best score first."""
        import torch

        from perception.vision.cnn_model import decode, image_tensor

        self._check_image(image)
        with torch.inference_mode():
            output = self._net(image_tensor(image[None]))[0].numpy()
        found = decode(
            output, len(self.classes), self.config.score_threshold, self.config.max_detections
        )
        return [
            Detection(
                class_name=self.classes[c],
                class_id=int(c),
                box=found.boxes[k].astype(np.float64),
                score=float(found.scores[k]),
                keypoint=found.keypoints[k].astype(np.float64),
            )
            for k, c in enumerate(found.class_ids)
        ]

    def detect_objects_downscaled(self, image: NDArray[np.uint8], factor: int) -> list[Detection]:
        """:meth:`detect_objects` on ``image`` (H, W, 3) uint8 RGB shrunk ``factor`` times (area
        averaging, the bottom rows repeated up to a multiple of the network's stride), boxes and
        keypoints mapped back to ``image``'s pixels (``u = factor * u_small + (factor - 1) / 2``
        where ``factor`` divides the image's size; else by the true scale of each axis).
        For objects nearer, and so larger, than the network saw in training: B-Human reads the
        Nao's lower camera at half the upper one's resolution."""
        import cv2
        import torch

        from perception.vision.cnn_model import decode, image_tensor

        self._check_image(image)
        check_int("", "factor", factor, 1)
        height, width = image.shape[0] // factor, image.shape[1] // factor
        shrunk = cv2.resize(image, (width, height), interpolation=cv2.INTER_AREA)
        pad = ((0, -height % NETWORK_STRIDE), (0, -width % NETWORK_STRIDE), (0, 0))
        small: NDArray[np.uint8] = np.pad(shrunk, pad, mode="edge").astype(np.uint8, copy=False)
        with torch.inference_mode():
            output = self._net(image_tensor(small[None]))[0].numpy()
        found = decode(
            output, len(self.classes), self.config.score_threshold, self.config.max_detections
        )
        # pixel centres: u = s (u_small + 1/2) - 1/2 with s the true scale on each axis (the
        # image's size over the shrunk one's: factor where it divides the size)
        scale = np.array([image.shape[1] / width, image.shape[0] / height])
        return [
            Detection(
                class_name=self.classes[c],
                class_id=int(c),
                box=np.tile(scale, 2) * (found.boxes[k].astype(np.float64) + 0.5) - 0.5,
                score=float(found.scores[k]),
                keypoint=scale * (found.keypoints[k].astype(np.float64) + 0.5) - 0.5,
            )
            for k, c in enumerate(found.class_ids)
        ]

    def detect(
        self, image: NDArray[np.uint8], camera_state: CameraState
    ) -> list[LandmarkObservation]:
        """Landmark sightings in ``image`` (H, W, 3) uint8 RGB taken from ``camera_state``.

        At most one per landmark id (the highest score), in id order. Same contract as
        :meth:`perception.vision.ColourPoleDetector.detect`.
        """
        return self.observations(self.detect_objects(image), camera_state, image)

    def observations(
        self,
        detections: Sequence[Detection],
        camera_state: CameraState,
        image: NDArray[np.uint8] | None = None,
    ) -> list[LandmarkObservation]:
        """The sightings of :meth:`detect` from :meth:`detect_objects`' ``detections`` in
        ``image`` (H, W, 3) uint8 RGB (None: distances from the box extents only).

        Pole detections are taken best score first; one is dropped if its band junction lies
        within ``JUNCTION_BORDER_PX`` of the top or bottom border (a band then hardly shows:
        neither code nor extents can be trusted), if its landmark was already seen or if its box
        overlaps an earlier one's by more than ``POLE_OVERLAP_IOU`` (one pole taken for two
        codes).
        """
        best: dict[int, LandmarkObservation] = {}
        taken: list[FloatArray] = []
        lowest = self.camera.height - 1 - JUNCTION_BORDER_PX
        for detection in sorted(detections, key=lambda d: -d.score):
            landmark_id = self._landmark_of.get(detection.class_id)
            if (
                landmark_id is None
                or not JUNCTION_BORDER_PX <= detection.keypoint[1] <= lowest
                or landmark_id in best
                or any(box_iou(detection.box, box) > POLE_OVERLAP_IOU for box in taken)
            ):
                continue
            observation = self.observe_pole(landmark_id, detection, camera_state, image)
            if observation is not None:
                best[landmark_id] = observation
                taken.append(detection.box)
        return [best[i] for i in sorted(best)]

    def observe_pole(
        self,
        landmark_id: int,
        detection: Detection,
        state: CameraState,
        image: NDArray[np.uint8] | None = None,
    ) -> LandmarkObservation | None:
        """The sighting of pole ``landmark_id`` from its ``detection`` in ``image`` (H, W, 3)
        uint8 RGB, or None if its box is degenerate.

        If ``config.edges`` is set and ``image`` given, the distance comes from the pole's band
        edges (:func:`perception.vision.pole_edges.pole_edge_distance`) or else, for a pole at
        least ``edges.width_min_px`` wide, from its width
        (:func:`perception.vision.pole_edges.pole_width_distance`); a pole that near (that
        wide, or as tall as a pole that wide) whose box touches the image border and that
        is measured by neither gives no sighting (the box extents of such near, cut poles are
        off by more than 25 % for one sighting in five).
        Otherwise the distance comes from the box extents (:class:`PoleRangeModel`).
        """
        box = detection.box
        if not (box[2] - box[0] > 0.5 and box[3] - box[1] > 0.5):
            return None
        rotation = state.rotation()
        lean = vertical_lean(box, self.camera, rotation)
        if self.config.check_colours and image is not None:
            rows = expected_rows(box, detection.keypoint, self.pole)
            seen = band_colours(
                image, box, detection.keypoint, lean, rows[2] - rows[1], self._paint_hues
            )
            if colours_contradict(seen, self._colours_of[landmark_id]):
                return None
            if self.config.require_both_colours and None in seen:
                return None
        rays = _pole_rays(box, detection.keypoint, self.camera, rotation)
        extents = _extents_from_rays(rays, self.camera)
        distance, rel_var, _ = self.range_model.distance(extents, box, self.camera)
        if self.config.edges is not None and image is not None:
            measured = self._ruler_distance(image, detection, lean, rotation, state)
            if measured is not None:
                distance, rel_var = measured
            elif any(cut_sides(box, self.camera)) and self._near(extents, self.config.edges):
                return None  # a near, cut pole measured by neither: its extents mislead
        range_m, bearing = _axis_range_bearing(rays[0], distance, state.position[:2])
        var_bearing = (self.range_model.bearing_std_px / self.camera.fx) ** 2
        return LandmarkObservation(
            landmark_id=landmark_id,
            range_m=range_m,
            bearing_rad=bearing,
            cov=np.diag([rel_var * range_m**2, var_bearing]),
            pixel=np.array([(box[0] + box[2]) / 2, (box[1] + box[3]) / 2]),
            box=np.asarray(box, dtype=np.float64),
            score=detection.score,
        )

    def _ruler_distance(
        self,
        image: NDArray[np.uint8],
        detection: Detection,
        lean: float,
        rotation: FloatArray,
        state: CameraState,
    ) -> tuple[float, float] | None:
        """Camera-to-axis distance (m) and its relative variance from the pole's band edges,
        else from its width; None if neither measures it (``config.edges`` must be set)."""
        edges = self.config.edges
        assert edges is not None
        box, keypoint = detection.box, detection.keypoint
        height = float(state.position[2])
        fit = pole_edge_distance(
            image, box, keypoint, lean, self.camera, rotation, height, self.pole, edges
        )
        if fit is not None:
            variance = fit.relative_variance(edges.row_std_px, self.camera.fx, edges.rel_std_floor)
            return fit.distance_m, variance
        across = pole_width_distance(
            image, box, keypoint, lean, self.camera, rotation, self.pole, edges
        )
        if across is not None:
            return across.distance_m, across.relative_variance(edges.row_std_px)
        return None

    def _near(self, extents: PoleExtents, edges: PoleEdgeConfig) -> bool:
        """Whether a pole is at least ``edges.width_min_px`` wide, or as tall as a pole that
        wide (its width may be cut by the border)."""
        aspect = self.pole.top_m / (2 * self.pole.radius_m)
        return max(extents.width, extents.height / aspect) >= edges.width_min_px

    def _check_image(self, image: NDArray[np.uint8]) -> None:
        """Raise ``ValueError`` unless ``image`` is an (H, W, 3) uint8 array of the camera."""
        check_rgb_image(image, self.camera.height, self.camera.width)


def network_from_weights(data: dict[str, Any]) -> PoleNet:
    """The network of a weights dict, as trained (train mode, batch norms apart)."""
    from perception.vision.cnn_model import NetConfig, PoleNet

    net = PoleNet(
        NetConfig(
            channels=tuple(data["net"]["channels"]),
            head_channels=int(data["net"]["head_channels"]),
            n_classes=int(data["net"]["n_classes"]),
        )
    )
    net.load_state_dict(data["state_dict"])
    return net


def load_network(data: dict[str, Any]) -> nn.Module:
    """The inference network from a weights dict: eval mode, batch norms folded, channels-last."""
    import torch

    from perception.vision.cnn_model import fuse_batch_norms

    net = network_from_weights(data)
    net.eval()
    return fuse_batch_norms(net).to(memory_format=torch.channels_last)  # type: ignore[call-overload]
