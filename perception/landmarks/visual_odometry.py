"""Visual heading odometry and collision detection from horizon features (seed 004 ch. 5).

Each frame's 1D SURF features are matched to those of the three previous frames (nearest
neighbours with the distance ratio test); every match's change of bearing is a vote for how
far the camera turned. The mode of the votes is the camera's turn (the static background is
the largest contributor; independently moving objects make a second mode), less the head's
own yaw change: the body's heading change. The confidence of a frame pair is the count of the
first mode less that of the second (high when the votes are uni-modal). Of the three previous
frames the one maximising ``min(reliability_k, confidence_k,t)`` is the reference (eq. 10),
and the frame's reliability is that minimum (eq. 11; the episode's first frame has infinite
reliability, eq. 12). Ties go to the oldest frame: fewer links, less accumulated error. When
the best confidence is below ``min_confidence`` the heading change is the walk engine's, and
that frame starts a new chain (infinite reliability, as eq. 12's first frame): its heading is
the walk's, not a visual link's, and without the restart one unmatched frame would pin every
later reliability at its confidence (eq. 11 never rises) and the visual heading would stop.
A frame pair whose visual heading change lies further than ``max_disagreement_rad`` from the
walk's is not a candidate (not in the seed): a confident wrong mode (a poster repeated along
the boards) turns the heading by tens of degrees in one frame, which no walk, slip or push
does.

Collisions: an exponential moving average of the visual minus the walk heading change per
frame against symmetric bounds; beyond the upper bound the body is turning left of what the
walk believes (a push or a catch on its right), beyond the lower one right.

Bearings are in radians, positive to the left of the optical axis; headings in radians,
counter-clockwise, as in the field frame.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from perception.geometry import FloatArray, wrap_scalar
from perception.landmarks.horizon_features import HorizonFeatures
from perception.landmarks.matching import MatchingConfig, match_features
from perception.validation import check_finite, check_instance, check_int, check_positive

# (earlier frame, later frame) -> index pairs (M, 2): column 0 into the earlier frame's
# features, column 1 into the later one's
Matcher = Callable[[HorizonFeatures, HorizonFeatures], NDArray[np.int64]]


def nearest_neighbours(config: MatchingConfig) -> Matcher:
    """The seed's matcher: each later feature's nearest earlier one by descriptor distance,
    when it passes the distance ratio test (:func:`~perception.landmarks.match_features`)."""

    def match(earlier: HorizonFeatures, later: HorizonFeatures) -> NDArray[np.int64]:
        matches = match_features(later.features, earlier.features, config)
        return np.stack([matches.stored_index, matches.test_index], axis=1)

    return match


@dataclass(frozen=True, kw_only=True)
class VisualOdometryConfig:
    """Settings of :class:`VisualHeadingOdometry` and :class:`CollisionDetector` (rad unless
    named otherwise; all > 0).

    ``bin_rad`` is the width of a histogram bin of bearing changes (a little more than one
    horizon sample's angle); votes within ``mode_halfwidth_bins`` bins of the first mode
    count for it and its heading is their mean; the second mode is the fullest window of
    ``2 * mode_halfwidth_bins + 1`` bins (its votes counted as the first mode's are) lying
    outside that many bins of the first. ``min_confidence`` (votes) is the least
    confidence for which the visual heading is used, ``max_disagreement_rad`` the most it may
    differ from the walk's in a frame; ``history`` previous frames are tried (the seed's 3).
    ``collision_smoothing`` is the moving average's weight of a new frame,
    ``collision_bound_rad`` its bound (rad per frame).
    """

    bin_rad: float = math.radians(0.8)
    mode_halfwidth_bins: int = 1
    min_confidence: int = 4
    history: int = 3
    collision_smoothing: float = 0.2
    collision_bound_rad: float = math.radians(1.0)
    max_disagreement_rad: float = math.radians(10.0)

    def __post_init__(self) -> None:
        owner = "VisualOdometryConfig"
        check_positive(owner, "bin_rad", self.bin_rad)
        check_int(owner, "mode_halfwidth_bins", self.mode_halfwidth_bins, 0)
        check_int(owner, "min_confidence", self.min_confidence, 1)
        check_int(owner, "history", self.history, 1)
        check_positive(
            owner, "collision_smoothing", self.collision_smoothing, upper=1.0, upper_inclusive=True
        )
        check_positive(owner, "collision_bound_rad", self.collision_bound_rad)
        check_positive(owner, "max_disagreement_rad", self.max_disagreement_rad)


@dataclass(frozen=True)
class ShiftModes:
    """The two fullest modes of a frame pair's bearing changes: ``turn`` (rad) from the first
    (NaN when there are no votes), ``first`` and ``second`` their vote counts."""

    turn: float
    first: int
    second: int

    @property
    def confidence(self) -> int:
        """Votes of the first mode less those of the second (eq. 10's confidence)."""
        return self.first - self.second


def shift_modes(shifts: FloatArray, config: VisualOdometryConfig) -> ShiftModes:
    """The modes of ``shifts`` (M,) (rad), the bearing changes of a frame pair's matches;
    ValueError unless they are finite and 1-D."""
    shifts = np.asarray(shifts, dtype=np.float64)
    if shifts.ndim != 1 or not np.isfinite(shifts).all():
        raise ValueError(f"shifts must be a finite (M,) array, got {shifts.tolist()}")
    if shifts.size == 0:
        return ShiftModes(turn=math.nan, first=0, second=0)
    bins = np.floor(shifts / config.bin_rad).astype(np.int64)
    lo = int(bins.min())
    counts = np.bincount(bins - lo)
    h = config.mode_halfwidth_bins
    window = np.convolve(counts, np.ones(2 * h + 1, dtype=np.int64), mode="same")
    peak = int(np.argmax(window))
    near = np.abs(bins - lo - peak) <= h
    outside = window.copy()
    outside[max(0, peak - 2 * h - 1) : peak + 2 * h + 2] = 0
    return ShiftModes(
        turn=float(np.mean(shifts[near])), first=int(window[peak]), second=int(outside.max())
    )


@dataclass(frozen=True)
class HeadingStep:
    """One frame of :class:`VisualHeadingOdometry`: the body's heading change since the last
    frame ``delta_rad`` (rad), whether it is ``visual`` (else the walk's), the reference
    frame's age ``reference`` (1-3 frames back; 0 when the walk's), its ``confidence``
    (votes) and the frame's ``reliability`` (eq. 11)."""

    delta_rad: float
    visual: bool
    reference: int
    confidence: int
    reliability: float


@dataclass(frozen=True)
class _Frame:
    """A remembered frame: its horizon features, heading (rad, the odometry's own frame) and
    reliability (eq. 11)."""

    features: HorizonFeatures
    heading: float
    reliability: float


class VisualHeadingOdometry:
    """The body's heading from horizon features, frame to frame (module docstring).

    ``match`` pairs two frames' features (:func:`nearest_neighbours` is the seed's).
    """

    def __init__(self, config: VisualOdometryConfig, match: Matcher) -> None:
        check_instance("config", config, VisualOdometryConfig)
        if not callable(match):
            raise TypeError(f"match must be a function of two frames' features, got {match!r}")
        self.config = config
        self.match = match
        self._frames: deque[_Frame] = deque(maxlen=config.history)

    def reset(self) -> None:
        """Forget every frame: the next one starts a chain (infinite reliability, eq. 12)."""
        self._frames.clear()

    def update(self, features: HorizonFeatures, walk_delta_rad: float) -> HeadingStep:
        """Take a frame's ``features`` with the walk engine's heading change since the last
        frame ``walk_delta_rad`` (rad, finite); return the body's heading change."""
        check_finite("VisualHeadingOdometry.update", "walk_delta_rad", walk_delta_rad)
        if not self._frames:
            self._frames.append(_Frame(features, 0.0, math.inf))
            return HeadingStep(0.0, False, 0, 0, math.inf)
        last = self._frames[-1]
        best: tuple[float, int, float, int] | None = None  # score, age, delta, confidence
        most_votes = 0  # the best confidence of any frame pair, for the report
        for age, frame in enumerate(reversed(self._frames), start=1):
            pairs = self.match(frame.features, features)
            shifts = frame.features.bearings[pairs[:, 0]] - features.bearings[pairs[:, 1]]
            modes = shift_modes(shifts, self.config)
            most_votes = max(most_votes, modes.confidence)
            head_turn = features.head_yaw - frame.features.head_yaw
            delta = wrap_scalar(frame.heading + modes.turn - head_turn - last.heading)
            usable = modes.confidence >= self.config.min_confidence and math.isfinite(delta)
            if not usable or abs(delta - walk_delta_rad) > self.config.max_disagreement_rad:
                continue
            score = min(frame.reliability, float(modes.confidence))
            if best is None or score >= best[0]:  # ties: the oldest frame
                best = (score, age, delta, modes.confidence)
        if best is None:
            self._frames.append(_Frame(features, last.heading + walk_delta_rad, math.inf))
            return HeadingStep(walk_delta_rad, False, 0, most_votes, math.inf)
        score, age, delta, confidence = best
        self._frames.append(_Frame(features, last.heading + delta, score))
        return HeadingStep(delta, True, age, confidence, score)


class CollisionDetector:
    """Seed 004 §5.2's collision test: an exponential moving average of the visual minus the
    walk heading change per frame (rad) against ``±collision_bound_rad``."""

    def __init__(self, config: VisualOdometryConfig) -> None:
        self.config = config
        self.average = 0.0

    def reset(self) -> None:
        """Start from no difference."""
        self.average = 0.0

    def update(self, visual_delta_rad: float, walk_delta_rad: float) -> int:
        """Fold in one frame's heading changes (rad); 1 when the body turns left of the walk
        (the average is above the bound), -1 right (below minus the bound), else 0.
        ValueError, before the average changes, unless both are finite."""
        check_finite("", "visual_delta_rad", visual_delta_rad)
        check_finite("", "walk_delta_rad", walk_delta_rad)
        a = self.config.collision_smoothing
        self.average = (1 - a) * self.average + a * wrap_scalar(visual_delta_rad - walk_delta_rad)
        bound = self.config.collision_bound_rad
        return 1 if self.average > bound else -1 if self.average < -bound else 0
