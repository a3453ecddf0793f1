"""Train the CNN pole detector on frames from ``python -m spl_env.datasets``.

``python -m training.train_detector --data data/poles --val data/poles_val --out
perception/vision/weights/pole_detector.pt --epochs 24 --seed 0 --minutes 18``

1. Loads every image into memory and turns its labels into targets: a pole whose band junction
   is visible (and at least ``MIN_PIXELS`` pixels seen) is trained on its junction, every other
   object of ``MIN_PIXELS`` pixels on its box centre; a pole whose junction is well out of the
   image is background; other objects too hidden for that are ignored regions of their
   class's heatmap (neither to be found nor to be missed).
2. Trains :class:`perception.vision.cnn_model.PoleNet` with AdamW (cosine learning rate over the
   planned epochs or the time budget, whichever runs out first), CenterNet's focal loss on the
   heatmaps and L1 on offsets and log edge distances, on images augmented as in seed 000
   §3.4.1: rotation ±15°, shear ±11° (both axes) and per box rotation ±5°, each with
   probability ``GEOMETRIC_PROBABILITY`` (rarely: the poles the robot sees stand upright, and
   a leaning pole's box is wider than an upright one's), saturation ±10 %, brightness ±20 %,
   and per box brightness ±15 % and blur up to 1.5 px, each with ``AUGMENT_PROBABILITY``;
   plus horizontal flips. Poles' regression losses weigh ``POLE_REGRESSION_WEIGHT`` times
   more (their box sizes give the range). All draws come from one generator seeded by
   ``--seed``.
3. Fits the range laws (seed eqs. 3.3/3.4: camera-to-axis distance against the boxes'
   upright height and width, log-log least squares) and the expected aspect ratio on the
   un-augmented training labels of unoccluded poles, then on the network's own detections in
   the un-augmented training images the aspect margin, a rescaling of each law to the
   network's extents (:func:`calibrate_laws`) and the noise model; saves weights and metadata
   (one ``torch.save`` dict). ``--refit`` redoes this step alone for the weights at ``--out``.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import os
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import scipy.optimize
import torch
from numpy.typing import NDArray

from perception.geometry import FloatArray, wrap_angle
from perception.types import CameraModel, CameraState, PoleCode, PoleGeometry
from perception.vision.cnn_detector import (
    BRANCHES,
    WEIGHTS_FORMAT,
    CnnDetectorConfig,
    CnnPoleDetector,
    Detection,
    PoleRangeModel,
    PowerLaw,
    network_from_weights,
    pole_extents,
)
from perception.vision.cnn_model import STRIDE, NetConfig, PoleNet, Targets, encode, focal_loss

MIN_PIXELS = 20  # an object with fewer labelled pixels is an ignored region, not a target
JUNCTION_MARGIN_PX = 4.0  # poles with the band junction farther out of the image: background
AUGMENT_PROBABILITY = 0.3  # of each photometric augmentation, per image (box-level: per box)
GEOMETRIC_PROBABILITY = 0.15  # of each geometric one (rotations, shear): poles stand upright
POLE_REGRESSION_WEIGHT = 2.0  # poles' offset and size losses count this much more
CLEAN_OCCLUSION = 0.02  # poles with at most this occluded fraction fit the range laws
MIN_NOISE_SIGHTINGS = 10  # per noise-model branch
MARGIN_QUANTILE = 0.99  # of clean poles' detected aspect residuals: the aspect margin
_MATCH_PX = 6.0  # a detection's keypoint within this of a label's (or 1/3 its width) matches


@dataclass(frozen=True)
class Sample:
    """One training image's objects: targets (class ids (K,), keypoints (K, 2) px, boxes
    (K, 4) pixel edges) and ignored regions (class ids (J,), boxes (J, 4))."""

    class_ids: NDArray[np.int64]
    keypoints: FloatArray
    boxes: FloatArray
    ignore_ids: NDArray[np.int64]
    ignore_boxes: FloatArray


def edges(box: list[float]) -> FloatArray:
    """Label box (min..max pixel indices) -> pixel edges (4,)."""
    return np.asarray(box, dtype=np.float64) + np.array([-0.5, -0.5, 0.5, 0.5])


def to_sample(record: dict[str, Any], image_size: tuple[int, int]) -> Sample:
    """Targets and ignored regions of one ``labels.jsonl`` record of (width, height) images.

    A pole whose band junction lies more than ``JUNCTION_MARGIN_PX`` outside the image is
    background: one band and the base must not make a detection, whose range would be a guess.
    """
    width, height = image_size
    ids, keypoints, boxes, ignore_ids, ignore_boxes = [], [], [], [], []
    for obj in record["objects"]:
        box = edges(obj["box"])
        is_pole = obj["landmark_id"] is not None
        if obj["pixels"] >= MIN_PIXELS and (not is_pole or obj["keypoint_visible"]):
            ids.append(obj["class_id"])
            keypoints.append(
                obj["keypoint"] if is_pole else [(box[0] + box[2]) / 2, (box[1] + box[3]) / 2]
            )
            boxes.append(box)
        elif is_pole and _outside_px(obj["keypoint"], width, height) > JUNCTION_MARGIN_PX:
            continue
        else:
            ignore_ids.append(obj["class_id"])
            ignore_boxes.append(box)
    return Sample(
        class_ids=np.array(ids, np.int64),
        keypoints=np.array(keypoints, np.float64).reshape(-1, 2),
        boxes=np.array(boxes, np.float64).reshape(-1, 4),
        ignore_ids=np.array(ignore_ids, np.int64),
        ignore_boxes=np.array(ignore_boxes, np.float64).reshape(-1, 4),
    )


def _outside_px(point: list[float], width: int, height: int) -> float:
    """How far (px) ``point`` ``(u, v)`` lies outside a (width, height) image; 0 inside."""
    u, v = point
    return max(-0.5 - u, u - (width - 0.5), -0.5 - v, v - (height - 0.5), 0.0)


def load_dataset(folder: Path) -> tuple[NDArray[np.uint8], list[dict[str, Any]], dict[str, Any]]:
    """Images (N, H, W, 3) uint8 RGB, label records and ``meta.json`` of a dataset folder."""
    meta = json.loads((folder / "meta.json").read_text())
    records = [json.loads(line) for line in (folder / "labels.jsonl").read_text().splitlines()]
    images = np.empty(
        (len(records), meta["camera"]["height"], meta["camera"]["width"], 3), np.uint8
    )
    for i, record in enumerate(records):
        bgr = cv2.imread(str(folder / "images" / record["image"]))
        if bgr is None or bgr.shape != images.shape[1:]:
            raise ValueError(f"{folder}: image {record['image']} is missing or not of the camera")
        images[i] = bgr[:, :, ::-1]
    return images, records, meta


# ----- augmentation ---------------------------------------------------------------------------
def _affine_points(matrix: FloatArray, points: FloatArray) -> FloatArray:
    """Apply a (2, 3) affine ``matrix`` to (N, 2) points."""
    return points @ matrix[:, :2].T + matrix[:, 2]


def _affine_boxes(matrix: FloatArray, boxes: FloatArray) -> FloatArray:
    """Axis-aligned (N, 4) boxes around the images of the (N, 4) boxes' corners."""
    corners = np.stack(
        [boxes[:, [0, 1]], boxes[:, [2, 1]], boxes[:, [0, 3]], boxes[:, [2, 3]]], axis=1
    )
    moved = _affine_points(matrix, corners.reshape(-1, 2)).reshape(-1, 4, 2)
    return np.concatenate([moved.min(axis=1), moved.max(axis=1)], axis=1)


def augment(
    image: NDArray[np.uint8], sample: Sample, rng: np.random.Generator
) -> tuple[NDArray[np.uint8], Sample]:
    """One augmented copy of ``image`` (H, W, 3) and its ``sample`` (see module doc)."""
    h, w = image.shape[:2]
    img = image.astype(np.float32)
    keypoints, boxes, ignore = sample.keypoints, sample.boxes, sample.ignore_boxes
    for k in range(len(boxes)):  # box-level operations, on the box's pixels
        u0, v0 = np.maximum(np.floor(boxes[k, :2] + 0.5).astype(int), 0)
        u1, v1 = np.minimum(np.ceil(boxes[k, 2:] + 0.5).astype(int), (w, h))
        if u1 - u0 < 2 or v1 - v0 < 2:
            continue
        crop = img[v0:v1, u0:u1]
        if rng.uniform() < AUGMENT_PROBABILITY:
            crop *= rng.uniform(0.85, 1.15)
        if rng.uniform() < AUGMENT_PROBABILITY:
            crop[:] = cv2.GaussianBlur(crop, (0, 0), rng.uniform(0.3, 1.5))
        if rng.uniform() < GEOMETRIC_PROBABILITY:
            middle = ((u1 - u0 - 1) / 2, (v1 - v0 - 1) / 2)
            turn = cv2.getRotationMatrix2D(middle, rng.uniform(-5.0, 5.0), 1.0)
            crop[:] = cv2.warpAffine(
                crop, turn, (u1 - u0, v1 - v0), borderMode=cv2.BORDER_REPLICATE
            ).reshape(crop.shape)
    matrix: FloatArray = np.eye(2, 3)
    if rng.uniform() < GEOMETRIC_PROBABILITY:
        matrix = np.asarray(
            cv2.getRotationMatrix2D(((w - 1) / 2, (h - 1) / 2), rng.uniform(-15, 15), 1.0)
        )
    if rng.uniform() < GEOMETRIC_PROBABILITY:
        sx, sy = np.tan(np.radians(rng.uniform(-11.0, 11.0, size=2)))
        shear = np.array([[1.0, sx], [sy, 1.0]])
        centre = np.array([(w - 1) / 2, (h - 1) / 2])
        matrix = np.column_stack([shear @ matrix[:, :2], shear @ (matrix[:, 2] - centre) + centre])
    if rng.uniform() < 0.5:  # horizontal flip: u -> W - 1 - u
        matrix = np.array([[-1.0, 0.0, w - 1.0], [0.0, 1.0, 0.0]]) @ np.vstack([matrix, [0, 0, 1]])
    if not np.allclose(matrix, np.eye(2, 3)):
        fill = float(rng.uniform(0.0, 255.0))
        img = np.asarray(
            cv2.warpAffine(img, matrix, (w, h), borderValue=(fill, fill, fill)), np.float32
        )
        keypoints = _affine_points(matrix, keypoints)
        boxes, ignore = _affine_boxes(matrix, boxes), _affine_boxes(matrix, ignore)
    if rng.uniform() < AUGMENT_PROBABILITY:
        img *= rng.uniform(0.8, 1.2)
    if rng.uniform() < AUGMENT_PROBABILITY:
        gray = img.mean(axis=2, keepdims=True)
        img = gray + np.float32(rng.uniform(0.9, 1.1)) * (img - gray)
    limit = np.array([-0.5, -0.5, w - 0.5, h - 0.5])
    boxes = np.clip(boxes, limit[:2].tolist() * 2, limit[2:].tolist() * 2)
    ignore = np.clip(ignore, limit[:2].tolist() * 2, limit[2:].tolist() * 2)
    inside = np.all((keypoints > limit[:2]) & (keypoints < limit[2:]), axis=1)
    out = Sample(
        class_ids=sample.class_ids[inside],
        keypoints=keypoints[inside],
        boxes=boxes[inside],
        ignore_ids=np.concatenate([sample.ignore_ids, sample.class_ids[~inside]]),
        ignore_boxes=np.concatenate([ignore, boxes[~inside]]),
    )
    return np.clip(img, 0, 255).astype(np.uint8), out


def targets(sample: Sample, n_classes: int, grid: tuple[int, int]) -> Targets:
    """The network's targets for ``sample``."""
    return encode(
        sample.class_ids.tolist(),
        sample.keypoints,
        sample.boxes,
        list(zip(sample.ignore_ids.tolist(), sample.ignore_boxes, strict=True)),
        n_classes,
        grid,
    )


def batch_loss(
    net: PoleNet,
    images: NDArray[np.uint8],
    batch: list[Targets],
    class_weights: NDArray[np.float32],
) -> tuple[torch.Tensor, dict[str, float]]:
    """Mean loss of a batch: focal heatmap loss per keypoint plus L1 of offsets and log edge
    distances at the keypoint cells, weighted by ``class_weights`` (C,); also its parts."""
    n_classes = net.config.n_classes
    x = torch.from_numpy(images).permute(0, 3, 1, 2).float().mul_(1.0 / 255.0)
    out = net(x)
    heat = torch.from_numpy(np.stack([t.heatmap for t in batch]))
    weight = torch.from_numpy(np.stack([t.weight for t in batch]))
    n_pos = max(sum(len(t.cells) for t in batch), 1)
    heat_loss = focal_loss(out[:, :n_classes], heat, weight) / n_pos
    index = np.concatenate(
        [np.column_stack([np.full(len(t.cells), i), t.cells]) for i, t in enumerate(batch)]
    )
    if len(index):
        b, _, r, c = torch.from_numpy(index).T
        predicted = out[b, n_classes:, r, c]  # (K, 6)
        goal = torch.from_numpy(np.concatenate([t.regression for t in batch]))
        l1 = (predicted - goal).abs() * torch.from_numpy(class_weights[index[:, 1]])[:, None]
        offset_loss, size_loss = l1[:, :2].sum() / n_pos, l1[:, 2:].sum() / n_pos
    else:
        offset_loss = size_loss = out.sum() * 0.0
    loss = heat_loss + offset_loss + size_loss
    parts = {"heat": heat_loss.item(), "offset": offset_loss.item(), "size": size_loss.item()}
    return loss, parts


# ----- range laws and noise ------------------------------------------------------------------
def fit_power_law(x: FloatArray, y: FloatArray) -> PowerLaw:
    """Log-log least squares ``y = a x ** -b`` over (N,) positive ``x`` and ``y``."""
    slope, intercept = np.polyfit(np.log(x), np.log(y), 1)
    return PowerLaw(a=float(np.exp(intercept)), b=float(-slope))


def camera_state(record: dict[str, Any]) -> CameraState:
    """The camera state (as the joints report it) of a ``labels.jsonl`` record."""
    cs = record["camera_state"]
    return CameraState(
        position=np.asarray(cs["position"], dtype=np.float64),
        head_yaw=cs["head_yaw"],
        head_pitch=cs["head_pitch"],
        tilt=cs["tilt"],
    )


def camera_distance(obj: dict[str, Any], state: CameraState) -> float:
    """Horizontal distance (m) from the camera (as the joints report it) to a pole's axis."""
    axis = obj["range_m"] * np.array([math.cos(obj["bearing_rad"]), math.sin(obj["bearing_rad"])])
    return float(np.linalg.norm(axis - state.position[:2]))


def fit_range_laws(records: list[dict[str, Any]], camera: CameraModel) -> dict[str, Any]:
    """Range laws per branch and the aspect law, on the upright extents of the labels of
    unoccluded poles whose band junction is in view.

    Each law uses the poles whose extent is whole: the height law those clear of the top and
    bottom border, the top and bottom laws those clear of that border, the width law those
    clear of the left and right border, the aspect law those clear of every border.
    """
    rows = []
    for record in records:
        state = camera_state(record)
        for obj in record["objects"]:
            if (
                obj["landmark_id"] is None
                or not obj["keypoint_visible"]
                or obj["pixels"] < MIN_PIXELS
                or obj["occluded_fraction"] is None
                or obj["occluded_fraction"] > CLEAN_OCCLUSION
            ):
                continue
            box = edges(obj["box"])
            extents = pole_extents(box, np.asarray(obj["keypoint"]), camera, state)
            cuts = (box[1] < 0, box[3] > camera.height - 1, box[0] < 0 or box[2] > camera.width - 1)
            rows.append((*dataclasses.astuple(extents), camera_distance(obj, state), *cuts))
    width, height, top, bottom, distance, top_cut, bottom_cut, side_cut = (
        np.array(rows, np.float64).reshape(-1, 8).T
    )
    whole = {
        "height": (top_cut == 0) & (bottom_cut == 0),
        "top": top_cut == 0,
        "bottom": bottom_cut == 0,
        "width": side_cut == 0,
    }
    extent = {"height": height, "top": top, "bottom": bottom, "width": width}
    clean = whole["height"] & whole["width"]
    return {
        "laws": {
            name: fit_power_law(extent[name][whole[name]], distance[whole[name]])
            for name in BRANCHES
        },
        "aspect_law": fit_power_law(height[clean], width[clean] / height[clean]),
        "fit_poles": {name: int(whole[name].sum()) for name in BRANCHES},
    }


@dataclass(frozen=True)
class Sighting:
    """A ``detection`` matched to a labelled pole ``obj``, with the frame's camera ``state``."""

    obj: dict[str, Any]
    detection: Detection
    state: CameraState


def match_sightings(
    detector: CnnPoleDetector,
    images: NDArray[np.uint8],
    records: list[dict[str, Any]],
) -> list[Sighting]:
    """The best-scoring detection of each labelled pole (junction visible, ``MIN_PIXELS``
    seen) in un-augmented images, if one of its class lies near its keypoint."""
    out = []
    for image, record in zip(images, records, strict=True):
        labelled = [
            o
            for o in record["objects"]
            if o["landmark_id"] is not None and o["keypoint_visible"] and o["pixels"] >= MIN_PIXELS
        ]
        if not labelled:
            continue
        state = camera_state(record)
        detections = detector.detect_objects(image)
        for obj in labelled:
            box = edges(obj["box"])
            reach = max(_MATCH_PX, (box[2] - box[0]) / 3)
            near = [
                d
                for d in detections
                if d.class_id == obj["class_id"]
                and np.linalg.norm(d.keypoint - obj["keypoint"]) <= reach
            ]
            if near:
                out.append(Sighting(obj, near[0], state))
    return out


def fit_aspect_margin(
    sightings: list[Sighting], model: PoleRangeModel, camera: CameraModel
) -> float:
    """The ``MARGIN_QUANTILE`` quantile of the detected boxes' log aspect residual (upright
    extents, against ``model``'s aspect law) over unoccluded poles clear of the image border:
    the rule then takes another extent than the height for few poles whose height is whole."""
    residuals = []
    for s in sightings:
        occluded = s.obj["occluded_fraction"]
        if s.obj["truncated"] or occluded is None or occluded > CLEAN_OCCLUSION:
            continue
        e = pole_extents(s.detection.box, s.detection.keypoint, camera, s.state)
        residuals.append(math.log(e.width / e.height) - math.log(model.aspect_law(e.height)))
    if len(residuals) < MIN_NOISE_SIGHTINGS:
        raise RuntimeError(
            f"only {len(residuals)} clean sightings to fit the aspect margin on "
            f"(need {MIN_NOISE_SIGHTINGS}); train longer or on more images"
        )
    return float(np.quantile(residuals, MARGIN_QUANTILE))


def calibrate_laws(detector: CnnPoleDetector, sightings: list[Sighting]) -> dict[str, PowerLaw]:
    """``detector``'s range laws rescaled to the network's own extents.

    The laws are fitted on label extents; the network's boxes differ from them by a few per
    cent on average, which would bias every range. Per branch, the law's ``a`` is divided by
    ``exp`` of the median log ratio of its distance to the true camera distance over matched
    sightings of unoccluded poles (gross errors of 25 % or more left out); a branch with fewer
    than ``MIN_NOISE_SIGHTINGS`` such sightings keeps its law.
    """
    camera = detector.camera
    logs: dict[str, list[float]] = {name: [] for name in BRANCHES}
    for s in sightings:
        occluded = s.obj["occluded_fraction"]
        if occluded is None or occluded > CLEAN_OCCLUSION:
            continue
        extents = pole_extents(s.detection.box, s.detection.keypoint, camera, s.state)
        distance, _, branch = detector.range_model.distance(extents, s.detection.box, camera)
        ratio = distance / camera_distance(s.obj, s.state)
        if abs(ratio - 1.0) < 0.25:
            logs[branch].append(math.log(ratio))
    laws = dict(detector.range_model.laws)
    for name, values in logs.items():
        if len(values) >= MIN_NOISE_SIGHTINGS:
            law = laws[name]
            laws[name] = PowerLaw(a=law.a * math.exp(-float(np.median(values))), b=law.b)
    return laws


def fit_noise(detector: CnnPoleDetector, sightings: list[Sighting]) -> dict[str, Any]:
    """Noise model of ``detector``'s range model from matched ``sightings``.

    Returns ``rel_var``: per branch ``(c0, c1)`` fitted by non-negative least squares of the
    squared relative range error on ``[1, 1 / extent ** 2]`` (gross errors of 25 % or more
    left out), ``bearing_std_px`` (RMS bearing error times fx) and the sightings per branch.
    """
    camera = detector.camera
    errors: dict[str, list[tuple[float, float]]] = {name: [] for name in BRANCHES}
    bearing_errors = []
    for s in sightings:
        observation = detector.observe_pole(s.obj["landmark_id"], s.detection, s.state)
        if observation is None:
            continue
        extents = pole_extents(s.detection.box, s.detection.keypoint, camera, s.state)
        branch = detector.range_model.branch(extents, s.detection.box, camera)
        error = observation.range_m / s.obj["range_m"] - 1.0
        errors[branch].append((error, max(getattr(extents, branch), 0.5)))
        bearing_errors.append(float(wrap_angle(observation.bearing_rad - s.obj["bearing_rad"])))
    rel_var: dict[str, tuple[float, float]] = {}
    counts: dict[str, int] = {}
    for name in BRANCHES:
        e, size = np.array(errors[name]).reshape(-1, 2).T
        keep = np.abs(e) < 0.25  # gross errors are outliers, not noise
        if keep.sum() < MIN_NOISE_SIGHTINGS:
            raise RuntimeError(
                f"branch {name}: only {keep.sum()} matched sightings to fit the noise on "
                f"(need {MIN_NOISE_SIGHTINGS}); train longer or on more images"
            )
        design = np.column_stack([np.ones(keep.sum()), 1.0 / size[keep] ** 2])
        coeffs, _ = scipy.optimize.nnls(design, e[keep] ** 2)
        rel_var[name] = (float(coeffs[0]), float(coeffs[1]))
        counts[name] = int(keep.sum())
    bearing = np.array(bearing_errors)
    bearing = bearing[np.abs(bearing) < math.radians(5.0)]
    return {
        "rel_var": rel_var,
        "bearing_std_px": float(np.sqrt(np.mean(bearing**2)) * camera.fx),
        "sightings": counts,
    }


# ----- training -------------------------------------------------------------------------------
@dataclass(frozen=True, kw_only=True)
class TrainConfig:
    """Optimisation settings of :func:`train`."""

    epochs: int = 24
    minutes: float = 25.0  # wall-clock budget; training stops when it is spent
    batch_size: int = 32
    learning_rate: float = 3e-3
    weight_decay: float = 1e-4
    seed: int = 0
    threads: int = 2  # torch intra-op threads while training
    channels: tuple[int, int, int, int] = NetConfig.channels  # of the network's four stages
    head_channels: int = NetConfig.head_channels

    def __post_init__(self) -> None:
        for name in ("epochs", "batch_size", "threads"):
            value = getattr(self, name)
            if not (isinstance(value, int) and value >= 1):
                raise ValueError(f"TrainConfig.{name} must be an int >= 1, got {value!r}")
        for name in ("minutes", "learning_rate"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"TrainConfig.{name} must be finite and > 0, got {value!r}")
        NetConfig(channels=self.channels, head_channels=self.head_channels)  # raises if bad
        if not (math.isfinite(self.weight_decay) and self.weight_decay >= 0):
            raise ValueError(
                f"TrainConfig.weight_decay must be finite and >= 0, got {self.weight_decay!r}"
            )


def evaluate_loss(
    net: PoleNet,
    images: NDArray[np.uint8],
    samples: list[Sample],
    batch_size: int,
    class_weights: NDArray[np.float32],
) -> float:
    """Mean loss over un-augmented ``images`` in eval mode."""
    grid = (images.shape[1] // STRIDE, images.shape[2] // STRIDE)
    net.eval()
    total = 0.0
    with torch.no_grad():
        for lo in range(0, len(images), batch_size):
            batch = [targets(s, net.config.n_classes, grid) for s in samples[lo : lo + batch_size]]
            loss, _ = batch_loss(net, images[lo : lo + batch_size], batch, class_weights)
            total += float(loss) * len(batch)
    net.train()
    return total / len(images)


def train(
    config: TrainConfig,
    images: NDArray[np.uint8],
    samples: list[Sample],
    classes: list[str],
    validation: tuple[NDArray[np.uint8], list[Sample]] | None,
) -> tuple[PoleNet, list[dict[str, float]]]:
    """Train a :class:`PoleNet` for ``classes``; returns it (train mode) and the epoch log."""
    n_classes = len(classes)
    class_weights = np.array(
        [POLE_REGRESSION_WEIGHT if name.startswith("pole_") else 1.0 for name in classes],
        np.float32,
    )
    torch.manual_seed(config.seed)
    rng = np.random.default_rng(config.seed)
    torch.set_num_threads(config.threads)
    net = PoleNet(
        NetConfig(channels=config.channels, head_channels=config.head_channels, n_classes=n_classes)
    )
    optimiser = torch.optim.AdamW(
        net.parameters(), lr=config.learning_rate, weight_decay=config.weight_decay
    )
    grid = (images.shape[1] // STRIDE, images.shape[2] // STRIDE)
    batches_per_epoch = math.ceil(len(images) / config.batch_size)
    budget_s = 60.0 * config.minutes
    start = time.perf_counter()
    log = []
    progress = 0.0
    for epoch in range(config.epochs):
        order = rng.permutation(len(images))
        sums = {"loss": 0.0, "heat": 0.0, "offset": 0.0, "size": 0.0}
        done = 0
        for k in range(batches_per_epoch):
            # cosine schedule over the planned epochs or the time budget, whichever ends first
            progress = max(
                (epoch + k / batches_per_epoch) / config.epochs,
                (time.perf_counter() - start) / budget_s,
            )
            if progress >= 1.0:
                break
            for group in optimiser.param_groups:
                group["lr"] = config.learning_rate * 0.5 * (1 + math.cos(math.pi * progress))
            chosen = order[k * config.batch_size : (k + 1) * config.batch_size]
            pairs = [augment(images[i], samples[i], rng) for i in chosen]
            batch = [targets(s, n_classes, grid) for _, s in pairs]
            loss, parts = batch_loss(net, np.stack([im for im, _ in pairs]), batch, class_weights)
            optimiser.zero_grad()
            loss.backward()
            optimiser.step()
            sums["loss"] += loss.item()
            for name, value in parts.items():
                sums[name] += value
            done += 1
        entry = {name: value / max(done, 1) for name, value in sums.items()}
        entry |= {"epoch": epoch + 1, "minutes": (time.perf_counter() - start) / 60.0}
        if validation is not None:
            entry["val_loss"] = evaluate_loss(net, *validation, config.batch_size, class_weights)
        log.append(entry)
        print(json.dumps({k: round(v, 4) for k, v in entry.items()}), flush=True)
        if progress >= 1.0:
            break
    return net, log


def save(path: Path, data: dict[str, Any]) -> None:
    """Write a weights dict (see :func:`main`) to ``path`` whole or not at all (a file beside
    it, then renamed over it)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    partial = path.with_name(path.name + ".partial")
    try:
        torch.save(data, partial)
        os.replace(partial, path)
    finally:
        partial.unlink(missing_ok=True)


def fit_measurement(
    net: PoleNet,
    images: NDArray[np.uint8],
    records: list[dict[str, Any]],
    meta: dict[str, Any],
) -> tuple[dict[str, Any], dict[str, Any]]:
    """Fit the range laws on the labels and the noise on ``net``'s detections.

    Returns the weights dict to save and the fits' sample counts. Writes nothing the caller
    keeps: the detector that the noise is fitted on reads a provisional copy in a temporary
    folder, so a fit that fails leaves the weights file of an earlier run as it was.
    """
    camera = CameraModel(**meta["camera"])
    laws = fit_range_laws(records, camera)
    provisional = PoleRangeModel(
        laws=laws["laws"],
        aspect_law=laws["aspect_law"],
        aspect_margin=0.0,  # fitted below on the detections, which it does not affect
        rel_var={name: (0.0, 0.0) for name in BRANCHES},
        bearing_std_px=1.0,
    )
    data: dict[str, Any] = {
        "format": WEIGHTS_FORMAT,
        "net": dataclasses.asdict(net.config),
        "state_dict": net.state_dict(),
        "classes": list(meta["classes"]),
        "camera": meta["camera"],
        "range_model": dataclasses.asdict(provisional),
    }
    codes = [PoleCode(**code) for code in meta["pole_codes"]]
    with tempfile.TemporaryDirectory() as folder:
        provisional_path = Path(folder) / "provisional.pt"
        save(provisional_path, data)
        weights = CnnDetectorConfig(weights=provisional_path)
        detector = CnnPoleDetector(weights, camera, codes, PoleGeometry())
    sightings = match_sightings(detector, images, records)
    margin = fit_aspect_margin(sightings, provisional, camera)
    detector.range_model = dataclasses.replace(provisional, aspect_margin=margin)
    label_laws = detector.range_model.laws
    detector.range_model = dataclasses.replace(
        detector.range_model, laws=calibrate_laws(detector, sightings)
    )
    calibration = {k: detector.range_model.laws[k].a / label_laws[k].a for k in BRANCHES}
    noise = fit_noise(detector, sightings)
    model = dataclasses.replace(
        detector.range_model, rel_var=noise["rel_var"], bearing_std_px=noise["bearing_std_px"]
    )
    data["range_model"] = dataclasses.asdict(model)
    fits = {
        "fit_poles": laws["fit_poles"],
        "law_calibration": calibration,
        "noise_sightings": noise["sightings"],
    }
    return data, fits


def refit(path: Path, data_folder: Path) -> None:
    """Refit the range laws and noise of the weights at ``path`` on ``data_folder`` (the
    network is kept, and its training record with the refit command added)."""
    old = torch.load(path, map_location="cpu", weights_only=True)
    net = network_from_weights(old)
    images, records, meta = load_dataset(data_folder)
    data, fits = fit_measurement(net, images, records, meta)
    command = " ".join(["python -m training.train_detector", *sys.argv[1:]])
    data["training"] = {**old.get("training", {}), "refit": {"command": command, **fits}}
    save(path, data)
    print(json.dumps({"range_model": data["range_model"], "refit": fits}, indent=1))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--data", type=Path, required=True, help="training dataset folder")
    parser.add_argument("--val", type=Path, default=None, help="validation dataset folder")
    parser.add_argument("--out", type=Path, required=True, help="weights file to write")
    parser.add_argument("--epochs", type=int, default=TrainConfig.epochs)
    parser.add_argument("--seed", type=int, default=TrainConfig.seed)
    parser.add_argument("--minutes", type=float, default=TrainConfig.minutes)
    parser.add_argument("--threads", type=int, default=TrainConfig.threads)
    parser.add_argument("--channels", type=int, nargs=4, default=list(TrainConfig.channels))
    parser.add_argument("--head-channels", type=int, default=TrainConfig.head_channels)
    parser.add_argument(
        "--refit",
        action="store_true",
        help="keep the network of --out and refit only its range laws and noise on --data",
    )
    args = parser.parse_args()
    config = TrainConfig(
        epochs=args.epochs,
        seed=args.seed,
        minutes=args.minutes,
        threads=args.threads,
        channels=tuple(args.channels),
        head_channels=args.head_channels,
    )
    start = time.perf_counter()
    if args.refit:
        refit(args.out, args.data)
        return
    images, records, meta = load_dataset(args.data)
    size = (meta["camera"]["width"], meta["camera"]["height"])
    samples = [to_sample(r, size) for r in records]
    validation = None
    if args.val is not None:
        val_images, val_records, _ = load_dataset(args.val)
        validation = (val_images, [to_sample(r, size) for r in val_records])
    print(f"loaded {len(images)} images in {time.perf_counter() - start:.0f} s", flush=True)
    classes = list(meta["classes"])
    net, log = train(config, images, samples, classes, validation)
    data, fits = fit_measurement(net, images, records, meta)
    data["training"] = {
        "command": " ".join(["python -m training.train_detector", *sys.argv[1:]]),
        "config": dataclasses.asdict(config),
        "dataset": {k: meta[k] for k in ("images", "seed", "scenes")},
        "log": log,
        **fits,
        "wall_minutes": (time.perf_counter() - start) / 60.0,
    }
    save(args.out, data)
    summary = {k: v for k, v in data["training"].items() if k != "log"}
    print(json.dumps({"range_model": data["range_model"], **summary}, indent=1))


if __name__ == "__main__":
    main()
