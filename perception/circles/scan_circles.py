"""The circles of one laser scan, as observations for circle SLAM (seed 001 §5.4.3-5.4.4).

Per scan: breakpoint segmentation (:func:`~perception.circles.segmentation.segment_breakpoints`);
each segment that stands clear of its surroundings (:func:`stands_clear`) becomes a
:class:`~perception.slam.circle_slam.ArcObservation` (its beams, which the SLAM fuses by their
ranges into a mapped circle they meet) and is classified
(:func:`~perception.circles.classification.classify_segment`): a circle segment's geometric
fit becomes the arc's :class:`~perception.slam.circle_slam.CircleObservation` in the robot
frame, what may start a new circle. Its covariance is the KCR bound of the fit's points
(:func:`kcr_covariance` at the range noise) times ``covariance_scale``: the bound holds for
unbiased fits of isotropic noise, while a short arc's fit is biased towards a smaller radius
(and kept only when it looks curved enough not to be a line) and laser noise lies along the
beams. The ranges themselves carry no such bias, hence the arcs.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from perception.circles.classification import ClassificationConfig, classify_segment
from perception.circles.fits import angles_around_centre, kcr_covariance
from perception.circles.segmentation import BreakpointConfig, Segment, segment_breakpoints
from perception.geometry import FloatArray
from perception.slam.circle_observations import ArcObservation, CircleObservation
from perception.validation import (
    check_finite,
    check_nested_configs,
    check_positive,
)


def stands_clear(segment: Segment, ranges: FloatArray, jump_m: float) -> bool:
    """Whether ``segment`` of the scan ``ranges`` (B,) (m, NaN = no return) is whole: not cut by
    the field of view, and each beam beside it reads farther than its end by more than
    ``jump_m`` (m) or nothing (else something nearer may hide part of it, or it touches what
    lies beside it)."""
    before, after = segment.start - 1, segment.stop
    if before < 0 or after >= len(ranges):
        return False
    return all(
        not (math.isfinite(ranges[side]) and ranges[side] < end + jump_m)
        for side, end in ((before, segment.ranges[0]), (after, segment.ranges[-1]))
    )


@dataclass(frozen=True, kw_only=True)
class ScanCirclesConfig:
    """Settings of :func:`scan_circles`.

    - ``segmentation``: the breakpoint segmenter (default: 0.15 m jumps, 5 beams at least);
    - ``classification``: line, circle or other (default: the chi-square rule at seed 001's
      0.02 m noise, circles up to 1 m);
    - ``covariance_scale``: the observations' covariance is this times the KCR bound (> 0);
      default 4 (twice the standard deviation), not fitted to data.
    """

    segmentation: BreakpointConfig = field(default_factory=BreakpointConfig)
    classification: ClassificationConfig = field(default_factory=ClassificationConfig)
    covariance_scale: float = 4.0

    def __post_init__(self) -> None:
        check_nested_configs(self)
        check_positive("ScanCirclesConfig", "covariance_scale", self.covariance_scale)


def scan_arcs(
    angles: ArrayLike, ranges: ArrayLike, mount_x_m: float, config: ScanCirclesConfig
) -> tuple[ArcObservation, ...]:
    """The segments of one scan that may be circles, in scan order: beam ``angles`` (B,) (rad,
    robot frame) and ``ranges`` (B,) (m, NaN for no return) from a scanner ``mount_x_m`` (m)
    ahead of the robot origin. Every segment that stands clear is an arc; its ``fit`` is its
    circle (centre in the robot frame) when it is classified as one and does not hold the
    sensor; it is ``circular`` when classified as a circle or a line (not "other").
    ``mount_x_m`` must be a finite number, else TypeError or ValueError naming it."""
    check_finite("", "mount_x_m", mount_x_m)
    scan = np.asarray(ranges, dtype=np.float64)
    beam_angles = np.asarray(angles, dtype=np.float64)
    jump = config.segmentation.jump_threshold_m
    sigma = config.classification.sigma_m
    found = []
    for segment in segment_breakpoints(beam_angles, scan, config.segmentation):
        if not stands_clear(segment, scan, jump):
            continue
        model = classify_segment(segment, config.classification)
        fit = model.circle if model.kind == "circle" else None  # the geometric fit
        observation = None
        if fit is not None and float(np.hypot(*fit.centre)) > fit.R:
            # (a fit holding the sensor is no object seen from outside)
            cov = kcr_covariance(angles_around_centre(model.points, fit.centre), sigma)
            observation = CircleObservation(
                centre=fit.centre + np.array([mount_x_m, 0.0]),
                R=fit.R,
                cov=config.covariance_scale * cov,
            )
        circular = model.kind != "other"
        found.append(ArcObservation(segment.angles, segment.ranges, observation, circular))
    return tuple(found)


def scan_circles(
    angles: ArrayLike, ranges: ArrayLike, mount_x_m: float, config: ScanCirclesConfig
) -> tuple[CircleObservation, ...]:
    """The circle fits of :func:`scan_arcs`, in scan order: each observation's centre is in the
    robot frame."""
    return tuple(
        arc.fit for arc in scan_arcs(angles, ranges, mount_x_m, config) if arc.fit is not None
    )
