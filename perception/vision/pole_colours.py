"""The colours of a detected pole's two bands, to check the class the CNN gave it.

A pole's class is its colour pair (pink over yellow, yellow over pink, ...). The network
sometimes names a pole by its neighbour's pair, which puts a landmark metres off in the map.
This check reads the mean colour of a strip along the pole axis in the middle of each band
(rows 30-70 % of a band height above and below the band junction), takes its OpenCV hue and
saturation, and names it by the nearest of the colour filter's paint hues (the centres of the
hue ranges of :class:`perception.vision.colour_filter.ColourFilterConfig`). A band too pale
(glare, a white background) or too far from every paint hue is not named and cannot contradict.
"""

from __future__ import annotations

import math

import cv2
import numpy as np
from numpy.typing import NDArray

from perception.geometry import FloatArray
from perception.vision.colour_filter import ColourFilterConfig
from perception.vision.pole_edges import cross_section_px

BAND_COLOURS: tuple[str, ...] = ("pink", "yellow", "blue", "green")
MIN_SATURATION = 60  # OpenCV S (0-255) below which a band's colour is not named
MAX_HUE_DISTANCE = 15  # OpenCV H units (0-179, circular) from the nearest paint hue


def paint_hues(config: ColourFilterConfig) -> dict[str, float]:
    """OpenCV hue of each band colour: the centre of its range in ``config``."""
    return {c: 0.5 * (config.hsv_range(c)[0][0] + config.hsv_range(c)[1][0]) for c in BAND_COLOURS}


def name_colour(rgb: FloatArray, hues: dict[str, float]) -> str | None:
    """The band colour of a mean ``rgb`` (3,) in 0-255, or None if too pale or no paint hue
    lies within ``MAX_HUE_DISTANCE``."""
    pixel = np.clip(np.rint(rgb), 0, 255).astype(np.uint8).reshape(1, 1, 3)
    hue, saturation, _ = (int(x) for x in cv2.cvtColor(pixel, cv2.COLOR_RGB2HSV)[0, 0])
    if saturation < MIN_SATURATION:
        return None
    distance = {c: min(abs(hue - h), 180 - abs(hue - h)) for c, h in hues.items()}
    best = min(distance, key=lambda c: distance[c])
    return best if distance[best] <= MAX_HUE_DISTANCE else None


def band_colours(
    image: NDArray[np.uint8],
    box: FloatArray,
    keypoint: FloatArray,
    lean: float,
    band_px: float,
    hues: dict[str, float],
) -> tuple[str | None, str | None]:
    """Named colours of the upper and lower band of a detection (box (4,) pixel edges, band
    junction ``keypoint`` (2,), image slope ``lean`` = du/dv of the pole axis, band height
    ``band_px``) in ``image`` (H, W, 3) uint8 RGB; None where a band is out of the image or
    its colour cannot be named."""
    height, width = image.shape[:2]
    uc, vc = (box[0] + box[2]) / 2.0, (box[1] + box[3]) / 2.0
    half_width = int(0.25 * cross_section_px(box, lean))
    named: list[str | None] = []
    for sign in (-1.0, 1.0):
        lo = keypoint[1] + sign * 0.3 * band_px
        hi = keypoint[1] + sign * 0.7 * band_px
        first, last = math.ceil(min(lo, hi)), math.floor(max(lo, hi))
        if first < 0 or last > height - 1 or last < first:
            named.append(None)
            continue
        rows = np.arange(first, last + 1)
        cols = np.rint(uc + lean * (rows - vc)).astype(np.int64)[:, None] + np.arange(
            -half_width, half_width + 1
        )
        if cols.min() < 0 or cols.max() > width - 1:
            named.append(None)
            continue
        mean = image[rows[:, None], cols].reshape(-1, 3).mean(axis=0)
        named.append(name_colour(mean, hues))
    return named[0], named[1]


def colours_contradict(seen: tuple[str | None, str | None], expected: tuple[str, str]) -> bool:
    """Whether named band colours ``seen`` (upper, lower) contradict a class's ``expected``
    (top, bottom) pair: a band named and different."""
    return any(s is not None and s != e for s, e in zip(seen, expected, strict=True))
