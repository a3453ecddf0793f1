"""The CNN of the pole detector and its target encoding and decoding (CenterNet-style).

A single-shot keypoint detector (Zhou et al., "Objects as Points", 2019) sized for one CPU
thread: four stride-2 stages (8, 16, 32, 48 channels by default) and one top-down merge give
a grid at output stride :data:`STRIDE` = 8 (30 x 40 cells for a 240 x 320 frame) with, per
cell,

- ``C`` heatmap logits, one per class: the probability that the cell holds an object's
  keypoint;
- 2 sub-cell offsets of the keypoint (cells);
- 4 log distances from the keypoint to the box's left, top, right and bottom edges, each
  ``log(distance_px / STRIDE)``.

Keypoints: a pole's is the junction of its two colour bands on the pole axis (what seed 000
calls a pole's centre, and locally visible even when the pole is cut by the image border);
every other object's is its box centre. Pixel (column i, row j) is centred at ``(u, v) =
(i, j)``; boxes are pixel edges ``(u0, v0, u1, v1)``, so a box spanning label pixels 3..5
runs from 2.5 to 5.5. A keypoint ``(u, v)`` lies in cell ``(floor((v + 0.5) / 8), floor((u +
0.5) / 8))`` at offset ``((u + 0.5) / 8, (v + 0.5) / 8)`` minus the cell index.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import torch
from numpy.typing import NDArray
from torch import nn
from torch.nn import functional

STRIDE = 8  # output stride (px per cell)
N_REGRESSION = 6  # offset (2) + log edge distances (4)
_PRIOR = 0.05  # initial heatmap probability (bias of the heatmap logits)


@dataclass(frozen=True, kw_only=True)
class NetConfig:
    """Channel counts of :class:`PoleNet` and its number of classes."""

    channels: tuple[int, int, int, int] = (8, 16, 32, 48)  # per stride-2 stage
    head_channels: int = 24
    n_classes: int = 9

    def __post_init__(self) -> None:
        values = (*self.channels, self.head_channels, self.n_classes)
        if len(self.channels) != 4 or not all(
            isinstance(c, int) and not isinstance(c, bool) and c >= 1 for c in values
        ):
            raise ValueError(
                "NetConfig needs 4 channel counts, head_channels and n_classes, all ints >= 1; "
                f"got channels={self.channels!r}, head_channels={self.head_channels!r}, "
                f"n_classes={self.n_classes!r}"
            )


def _conv(c_in: int, c_out: int, stride: int = 1, dilation: int = 1) -> nn.Sequential:
    """3 x 3 convolution, batch norm and ReLU."""
    return nn.Sequential(
        nn.Conv2d(c_in, c_out, 3, stride, padding=dilation, dilation=dilation, bias=False),
        nn.BatchNorm2d(c_out),
        nn.ReLU(inplace=True),
    )


class PoleNet(nn.Module):
    """Maps (N, 3, H, W) float RGB in [0, 1] to (N, C + 6, H / 8, W / 8) raw outputs.

    Channels: ``C`` heatmap logits, then 2 offsets and 4 log edge distances (module doc).
    H and W must be multiples of 16.
    """

    def __init__(self, config: NetConfig) -> None:
        super().__init__()
        self.config = config
        c1, c2, c3, c4 = config.channels
        self.stem = nn.Sequential(_conv(3, c1, 2), _conv(c1, c2, 2))
        self.stage3 = nn.Sequential(_conv(c2, c3, 2), _conv(c3, c3))
        self.stage4 = nn.Sequential(_conv(c3, c4, 2), _conv(c4, c4, dilation=2))
        self.lateral = nn.Conv2d(c4, c3, 1)
        self.head = nn.Sequential(
            _conv(c3, config.head_channels),
            nn.Conv2d(config.head_channels, config.n_classes + N_REGRESSION, 1),
        )
        out = self.head[-1]
        assert isinstance(out, nn.Conv2d) and out.bias is not None
        with torch.no_grad():
            out.bias.zero_()
            out.bias[: config.n_classes] = math.log(_PRIOR / (1 - _PRIOR))

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        fine = self.stage3(self.stem(x))
        coarse = self.lateral(self.stage4(fine))
        return self.head(fine + functional.interpolate(coarse, scale_factor=2.0, mode="nearest"))


def fuse_batch_norms(module: nn.Module) -> nn.Module:
    """Fold every conv + batch-norm pair of an eval-mode ``module`` into one conv, in place.

    Returns ``module``; its outputs are unchanged up to float rounding, one op fewer per pair.
    """
    for name, child in module.named_children():
        if isinstance(child, nn.Sequential):
            layers = list(child)
            for i in range(len(layers) - 1):
                conv, norm = layers[i], layers[i + 1]
                if isinstance(conv, nn.Conv2d) and isinstance(norm, nn.BatchNorm2d):
                    layers[i] = torch.nn.utils.fusion.fuse_conv_bn_eval(conv, norm)
                    layers[i + 1] = nn.Identity()
            setattr(
                module, name, nn.Sequential(*(m for m in layers if not isinstance(m, nn.Identity)))
            )
        fuse_batch_norms(getattr(module, name))
    return module


def image_tensor(images: NDArray[np.uint8]) -> torch.Tensor:
    """(N, H, W, 3) uint8 RGB (any strides: a flipped view is copied) -> (N, 3, H, W) float32
    in [0, 1], channels-last in memory."""
    pixels = np.ascontiguousarray(images)  # torch takes no negative strides
    return torch.from_numpy(pixels).permute(0, 3, 1, 2).float().mul_(1.0 / 255.0)


@dataclass(frozen=True)
class Decoded:
    """Decoded detections of one image, best first (K of them).

    ``class_ids`` (K,) int, ``scores`` (K,) in (0, 1), ``keypoints`` (K, 2) ``(u, v)`` px,
    ``boxes`` (K, 4) pixel edges ``(u0, v0, u1, v1)``.
    """

    class_ids: NDArray[np.int64]
    scores: NDArray[np.float32]
    keypoints: NDArray[np.float32]
    boxes: NDArray[np.float32]


def decode(
    output: NDArray[np.float32], n_classes: int, score_threshold: float, max_detections: int
) -> Decoded:
    """Detections in one image's raw output (C + 6, h, w) (see :class:`PoleNet`).

    Peaks: cells whose heatmap probability is at least ``score_threshold`` and the maximum of
    their 3 x 3 neighbourhood in their class; at most ``max_detections``, best first. Works on
    the logits (sigmoid is monotonic) and only around the cells above the threshold.
    """
    logits = np.ascontiguousarray(output[:n_classes])
    flat = np.flatnonzero(logits >= math.log(score_threshold / (1.0 - score_threshold)))
    cells = np.unravel_index(flat, logits.shape)
    peaks = [
        (c, r, q)
        for c, r, q in zip(*(axis.tolist() for axis in cells), strict=True)
        if logits[c, r, q] >= logits[c, max(r - 1, 0) : r + 2, max(q - 1, 0) : q + 2].max()
    ]
    peaks.sort(key=lambda cell: -logits[cell])
    c, r, q = np.array(peaks[:max_detections], dtype=np.int64).reshape(-1, 3).T
    reg = output[n_classes:, r, q]  # (6, K)
    u = (q + reg[0]) * STRIDE - 0.5
    v = (r + reg[1]) * STRIDE - 0.5
    dist = np.exp(reg[2:]) * STRIDE  # (4, K) left, top, right, bottom
    return Decoded(
        class_ids=c,
        scores=(1.0 / (1.0 + np.exp(-logits[c, r, q]))).astype(np.float32),
        keypoints=np.column_stack([u, v]).astype(np.float32),
        boxes=np.column_stack([u - dist[0], v - dist[1], u + dist[2], v + dist[3]]).astype(
            np.float32
        ),
    )


@dataclass(frozen=True)
class Targets:
    """Training targets of one image on an (h, w) grid.

    ``heatmap`` (C, h, w) in [0, 1] (1 exactly at keypoint cells), ``weight`` (C, h, w) 0 where
    the heatmap loss is ignored, ``cells`` (K, 3) int ``(class, row, col)`` of the keypoints and
    ``regression`` (K, 6) their offsets and log edge distances.
    """

    heatmap: NDArray[np.float32]
    weight: NDArray[np.float32]
    cells: NDArray[np.int64]
    regression: NDArray[np.float32]


def encode(
    class_ids: Sequence[int],
    keypoints: NDArray[np.float64],
    boxes: NDArray[np.float64],
    ignore: Sequence[tuple[int, NDArray[np.float64]]],
    n_classes: int,
    grid: tuple[int, int],
    sigma_fraction: float = 0.15,
) -> Targets:
    """Targets for objects with ``class_ids`` (K,), ``keypoints`` (K, 2) px and ``boxes``
    (K, 4) pixel edges on a ``grid`` (h, w) of cells.

    Each keypoint spreads a Gaussian of std ``sigma_fraction`` x the box's smaller side (at least
    half a cell, at most two); ``ignore`` lists ``(class, box)`` regions where that class's
    heatmap is not trained (objects too hidden to be found, or to be missed). Keypoints outside
    the grid are dropped.
    """
    h, w = grid
    heatmap = np.zeros((n_classes, h, w), np.float32)
    weight = np.ones((n_classes, h, w), np.float32)
    for c, box in ignore:
        c0, r0 = np.floor((box[:2] + 0.5) / STRIDE).astype(int)
        c1, r1 = np.floor((box[2:] + 0.5) / STRIDE).astype(int)
        weight[c, max(r0, 0) : r1 + 1, max(c0, 0) : c1 + 1] = 0.0
    cells, regression = [], []
    ys, xs = np.arange(h)[:, None], np.arange(w)[None, :]
    for c, (u, v), box in zip(class_ids, keypoints, boxes, strict=True):
        x, y = (u + 0.5) / STRIDE, (v + 0.5) / STRIDE
        col, row = math.floor(x), math.floor(y)
        if not (0 <= col < w and 0 <= row < h):
            continue
        side = min(box[2] - box[0], box[3] - box[1]) / STRIDE
        sigma = min(max(sigma_fraction * side, 0.5), 2.0)
        blob = np.exp(-((xs - col) ** 2 + (ys - row) ** 2) / (2 * sigma**2))
        np.maximum(heatmap[c], blob, out=heatmap[c])
        weight[c, row, col] = 1.0
        edges = np.array([u - box[0], v - box[1], box[2] - u, box[3] - v])
        cells.append((c, row, col))
        regression.append([x - col, y - row, *np.log(np.maximum(edges, 0.5) / STRIDE)])
    return Targets(
        heatmap=heatmap,
        weight=weight,
        cells=np.array(cells, np.int64).reshape(-1, 3),
        regression=np.array(regression, np.float32).reshape(-1, N_REGRESSION),
    )


def focal_loss(logits: torch.Tensor, target: torch.Tensor, weight: torch.Tensor) -> torch.Tensor:
    """CenterNet's penalty-reduced focal loss (alpha 2, beta 4), summed over all cells.

    ``logits``, ``target`` and ``weight`` are (N, C, h, w); positives are cells with target 1.
    Divide by the number of positives outside.
    """
    log_p = functional.logsigmoid(logits)
    log_not_p = functional.logsigmoid(-logits)
    p = log_p.exp()
    positive = target >= 1.0
    pos = -log_p * (1 - p) ** 2
    neg = -log_not_p * p**2 * (1 - target) ** 4
    return (weight * torch.where(positive, pos, neg)).sum()
