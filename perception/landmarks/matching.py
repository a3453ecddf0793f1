"""Natural landmark recognition by matching 1-D SURF features (seed 004 §3.2).

NN matching: each test feature is matched to its nearest stored feature (Euclidean distance of
the descriptors) when that distance is below ``ratio`` (0.7, Lowe 2004) times the distance to
the second nearest. The recognition score is the sum over the matches of the inverse
descriptor distance; a distance below ``distance_floor`` counts as the floor, so that an exact
match adds ``1 / distance_floor`` rather than infinity.

NN with RANSAC: the matches must agree on a straight-line map of image columns (eq. 8)::

    x_test = beta_s * x_stored + beta_d

(a landmark seen at another scale, ``beta_s``, and displaced, ``beta_d`` px). Each hypothesis
is the line through two matches drawn at random; the one with the most matches within
``inlier_tolerance_px`` wins (ties: the smaller sum of inlier residuals), is refitted by least
squares to its inliers, and the score is recomputed over the inliers only. Scales outside
``[min_scale, max_scale]`` are not hypotheses: in particular no mirror image (``beta_s < 0``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from perception.geometry import FloatArray
from perception.landmarks.surf1d import Surf1dFeatures
from perception.validation import (
    InvalidTypeError,
    check_bool,
    check_generator,
    check_in_interval,
    check_int,
    check_positive,
)


@dataclass(frozen=True, kw_only=True)
class MatchingConfig:
    """Nearest-neighbour matching of descriptors (unit vectors: distances in [0, 2])."""

    ratio: float = 0.7  # seed 004 §3.2 (Lowe): nearest / second-nearest distance below this
    same_sign_only: bool = False  # match only features of the same Laplacian sign (SURF)
    distance_floor: float = 0.01  # distances below count as this in the score: <= 100 a match

    def __post_init__(self) -> None:
        check_in_interval("MatchingConfig", "ratio", self.ratio, 0.0, 1.0, high_inclusive=True)
        check_bool("MatchingConfig", "same_sign_only", self.same_sign_only)
        check_positive("MatchingConfig", "distance_floor", self.distance_floor)


@dataclass(frozen=True, kw_only=True)
class RansacConfig:
    """RANSAC of the line model ``x_test = beta_s * x_stored + beta_d`` (eq. 8)."""

    iterations: int = 100  # two-match hypotheses drawn
    inlier_tolerance_px: float = 8.0  # |x_test - model(x_stored)| of an inlier (px)
    min_inliers: int = 3  # fewer inliers: no landmark pose (2 always fit a line exactly)
    min_scale: float = 1.0 / 3.0  # smallest beta_s accepted
    max_scale: float = 3.0  # largest beta_s accepted

    def __post_init__(self) -> None:
        check_int("RansacConfig", "iterations", self.iterations, 1)
        check_positive("RansacConfig", "inlier_tolerance_px", self.inlier_tolerance_px)
        check_int("RansacConfig", "min_inliers", self.min_inliers, 2)
        check_positive("RansacConfig", "min_scale", self.min_scale)
        check_positive("RansacConfig", "max_scale", self.max_scale)
        if self.max_scale < self.min_scale:
            raise ValueError(
                f"RansacConfig.max_scale must be >= min_scale {self.min_scale!r}, "
                f"got {self.max_scale!r}"
            )


@dataclass(frozen=True, eq=False)
class Matches:
    """M matches of test features to stored ones. Arrays read-only.

    ``test_index`` / ``stored_index`` (M,) int index the two feature sets; ``test_x`` /
    ``stored_x`` (M,) are the matched features' columns (px); ``distance`` (M,) the descriptor
    distances and ``weight`` (M,) their score terms ``1 / max(distance, distance_floor)``.
    """

    test_index: NDArray[np.int64]
    stored_index: NDArray[np.int64]
    test_x: FloatArray
    stored_x: FloatArray
    distance: FloatArray
    weight: FloatArray

    def __len__(self) -> int:
        return len(self.test_index)

    @property
    def score(self) -> float:
        """The recognition score: the sum of :attr:`weight`."""
        return float(self.weight.sum())


@dataclass(frozen=True)
class LineModel:
    """``x_test = beta_s * x_stored + beta_d`` (px): scale (1) and displacement (px)."""

    beta_s: float
    beta_d: float


@dataclass(frozen=True, eq=False)
class RansacResult:
    """The landmark pose of :func:`ransac_line` (None when no hypothesis had
    ``min_inliers``), its (M,) read-only inlier mask over the matches and the recognition
    score over the inliers (0 without a model)."""

    model: LineModel | None
    inliers: NDArray[np.bool_]
    score: float


def match_features(test: Surf1dFeatures, stored: Surf1dFeatures, config: MatchingConfig) -> Matches:
    """NN matches of the ``test`` features to the ``stored`` ones, in test order.

    A test feature with a single candidate (one stored feature, or one of its sign with
    ``same_sign_only``) passes the ratio test: there is no second neighbour to confuse it
    with. Equal nearest and second-nearest distances fail it.
    """
    for name, value, kind in (
        ("test", test, Surf1dFeatures),
        ("stored", stored, Surf1dFeatures),
        ("config", config, MatchingConfig),
    ):
        if not isinstance(value, kind):
            raise InvalidTypeError(f"{name} must be a {kind.__name__}, got {type(value).__name__}")
    difference = test.descriptors[:, None, :] - stored.descriptors[None, :, :]
    distance = np.linalg.norm(difference, axis=2)  # (Nt, Ns)
    if config.same_sign_only:
        same = test.laplacian[:, None] == stored.laplacian[None, :]
        distance = np.where(same, distance, np.inf)
    if distance.shape[1] == 0:
        distance = np.full((len(test), 1), np.inf)
    rows = np.arange(len(test))
    nearest = np.argmin(distance, axis=1)
    d1 = distance[rows, nearest]
    distance[rows, nearest] = np.inf
    d2 = distance.min(axis=1)
    matched = np.isfinite(d1) & (d1 < config.ratio * d2)
    test_index, stored_index = rows[matched].astype(np.int64), nearest[matched].astype(np.int64)
    d = d1[matched]
    matches = Matches(
        test_index=test_index,
        stored_index=stored_index,
        test_x=test.x[test_index],
        stored_x=stored.x[stored_index],
        distance=d,
        weight=1.0 / np.maximum(d, config.distance_floor),
    )
    for array in vars(matches).values():
        array.flags.writeable = False
    return matches


def ransac_line(matches: Matches, config: RansacConfig, rng: np.random.Generator) -> RansacResult:
    """Fit eq. 8 to ``matches`` by RANSAC (module docstring) with draws from ``rng``."""
    check_generator("rng", rng)
    m = len(matches)
    xs, xt = matches.stored_x, matches.test_x
    if m < config.min_inliers:
        return _result(None, np.zeros(m, dtype=bool), matches)
    first = rng.integers(0, m, size=config.iterations)
    second = (first + rng.integers(1, m, size=config.iterations)) % m  # never the first
    run = xs[second] - xs[first]
    with np.errstate(divide="ignore", invalid="ignore"):
        beta_s = (xt[second] - xt[first]) / run
    possible = (run != 0.0) & (beta_s >= config.min_scale) & (beta_s <= config.max_scale)
    beta_s, first = beta_s[possible], first[possible]
    beta_d = xt[first] - beta_s * xs[first]
    residual = np.abs(xt[None, :] - (beta_s[:, None] * xs[None, :] + beta_d[:, None]))  # (H, M)
    inlier = residual <= config.inlier_tolerance_px
    count = inlier.sum(axis=1)
    if len(count) == 0 or count.max() < config.min_inliers:
        return _result(None, np.zeros(m, dtype=bool), matches)
    best = int(np.lexsort((np.where(inlier, residual, 0.0).sum(axis=1), -count))[0])
    model, mask = LineModel(float(beta_s[best]), float(beta_d[best])), inlier[best]
    refit = _least_squares(xs[mask], xt[mask])
    if refit is not None and config.min_scale <= refit.beta_s <= config.max_scale:
        refit_mask = np.abs(xt - (refit.beta_s * xs + refit.beta_d)) <= config.inlier_tolerance_px
        if refit_mask.sum() >= mask.sum():
            model, mask = refit, refit_mask
    return _result(model, mask, matches)


def _least_squares(xs: FloatArray, xt: FloatArray) -> LineModel | None:
    """Least-squares line ``xt = beta_s xs + beta_d`` through (n,) points; None if all ``xs``
    are equal."""
    centred = xs - xs.mean()
    spread = float(centred @ centred)
    if spread == 0.0:
        return None
    beta_s = float(centred @ (xt - xt.mean())) / spread
    return LineModel(beta_s, float(xt.mean() - beta_s * xs.mean()))


def _result(model: LineModel | None, mask: NDArray[np.bool_], matches: Matches) -> RansacResult:
    """A :class:`RansacResult` with a read-only ``mask`` and the score over it."""
    mask = mask.copy()
    mask.flags.writeable = False
    return RansacResult(model=model, inliers=mask, score=float(matches.weight[mask].sum()))
