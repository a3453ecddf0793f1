"""Seed 004's sonar filter and the sonar check of its robot detection (Ch. 6.2, Algorithm 2).

**The filter.** :class:`SonarFilter` keeps a rolling window of the echoes of each of the sonar's
three sectors (left, middle, right; :class:`perception.sensor_models.SonarModel`). Each
:meth:`SonarFilter.update` clusters a sector's windowed echo distances bottom up by hierarchical
agglomerative clustering (:func:`cluster_ranges`, ``scipy.cluster.hierarchy``), merging clusters
while the difference in range stays within ``cluster_cutoff_m`` (seed: 5 cm). Clusters of at
least ``min_cluster_size`` echoes are reliable observations, their range the mean of their
echoes: no binning, so no loss of accuracy, and a stray echo never reaches the size.

Linkage: ``"centroid"`` by default, the seed's rule read literally. A cluster's range is the
mean of its echoes, and two clusters merge while the difference of their ranges is within the
cut-off (in one dimension this linkage never inverts, so the cut-off is a clean threshold).
``"single"`` (nearest echoes within the cut-off) chains: two robots 7 cm apart, or a noisy
cloud, become one cluster whose mean lies between them. ``"complete"`` (every pair within the
cut-off) cannot chain, but splits an object whose echoes spread over more than 5 cm (1 cm noise
over a window, or the robot walking towards it) into fragments that may each miss the size, and
so lose it. The centroid rule sits between them: clusters more than 5 cm apart in range stay
apart, and an object's spread of a few centimetres stays one cluster. ``"average"`` is offered
too.

**Algorithm 2, lines 14-17.** :func:`confirm_with_sonar` gives a robot sighting whose bearing
lies in a sector's cone, and whose range is close to one of that sector's filtered ranges, the
sonar's range (and the sonar's range noise), and marks it ``sonar_confirmed``; a sighting with
neither a team colour nor a sonar confirmation is dropped as a likely false positive.

Frames and units: robot frame as in :mod:`perception.sensor_models` (x along the heading, y to
the left, angles in rad, + = left); distances in m, times in s. Sonar distances are measured
from the transducers, ``SonarModel.mount_x_m`` ahead of the robot origin; a sighting's range and
bearing are from the robot origin to the centre of the robot seen.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.cluster.hierarchy import fcluster, linkage

from perception.geometry import FloatArray, wrap_angle
from perception.sensor_models import N_SONAR_SECTORS, SonarModel
from perception.tracking.checked_inputs import TIME_ROUNDING_S, checked_sightings
from perception.types import RobotSighting
from perception.validation import (
    InvalidTypeError,
    check_choice,
    check_finite,
    check_instance,
    check_int,
    check_positive,
    real_array,
)

SECTOR_NAMES: tuple[str, str, str] = ("left", "middle", "right")  # row order of a reading
LINKAGES: tuple[str, ...] = ("centroid", "single", "complete", "average")
# Slack on the cut-off so that "within" survives rounding: 1.05 - 1.00 is 0.05000000000000004.
_CUTOFF_SLACK_M = 1e-9


@dataclass(frozen=True, kw_only=True)
class SonarFilterConfig:
    """Settings of :class:`SonarFilter` and :func:`confirm_with_sonar`.

    The window (an echo is used while both limits hold):

    - ``window_frames``: the last this many updates (int >= 1). Default 5, 0.5 s at the env's
      10 Hz: long enough for ``min_cluster_size`` hits of a static object, short enough that
      walking at 0.25 m/s moves an object only about 10 cm in range over the window.
    - ``window_s``: only echoes of updates less than this many seconds before the latest
      (s, > 0), or None for no time limit (default).

    The clusters:

    - ``cluster_cutoff_m``: clusters merge while their difference in range is within this
      (m, > 0; seed 004: 5 cm).
    - ``linkage``: one of :data:`LINKAGES`, the difference in range between two clusters:
      of their means (``"centroid"``, default; see the module docstring), of their nearest
      (``"single"``) or farthest (``"complete"``) echoes, or the mean over pairs (``"average"``).
    - ``min_cluster_size``: echoes a cluster needs to be a reliable observation (int >= 1,
      <= ``window_frames``: the sonar merges echoes within 5 cm of each other in one reading,
      so an object gives at most about one echo per update). Default 3: heard in most of the
      last 5 updates (rUNSWift's released filter used 3 of its 4-ping window).

    Algorithm 2's match and range replacement:

    - ``match_abs_m`` (m, >= 0) and ``match_rel`` (>= 0): a sighting whose predicted echo
      distance is ``d`` matches a filtered range ``s`` when
      ``|s - d| <= match_abs_m + match_rel * d``. Defaults 0.10 m + 10 %: vision's range is
      the weak part, and its error grows with range (a pixel of ground-contact row is worth
      about ``r^2 / (h f)`` metres), hence the relative term; the absolute floor covers close
      range, where a cropped foot or the target's body depth (below) dominate. At 1 m that is
      +-0.20 m, at 2 m +-0.30 m: about twice the field-edge detector's range error std
      (3.5-6.8 % within 3 m on the tuning seeds 0-9 of ``benchmarks/robot_detection.py``).
      Seed 004's vision was worse (first sightings of a goalie 2 m away 42-58 cm off); the
      first default, 0.10 m + 20 %, let the echo of another robot confirm 3 % of the
      sightings there (confirmed ranges up to 26 % short).
    - ``target_depth_m`` (m, >= 0): a sonar echo comes from the near surface of a robot, a
      sighting locates its centre; the echo is expected this much nearer than the centre, and a
      confirmed range is the echo plus this. Default 0.10 m: on the tuning seeds 0-3 the
      nearest echo of a simulated Nao came 0.107 m before its centre (10-90 %: 0.08-0.135 m;
      its torso is 0.10-0.11 m deep, but its arms stick out when it stands turned).
    - ``min_range_std_m`` (m, > 0): floor of a confirmed range's standard deviation, which is
      otherwise the sonar's ``range_noise_std_m``; keeps the covariance positive definite for a
      noise-free sonar model. Default 1 mm.

    Bad fields raise ``ValueError`` (``InvalidTypeError`` for a wrong type) naming
    ``SonarFilterConfig.<field>``.
    """

    window_frames: int = 5
    window_s: float | None = None
    cluster_cutoff_m: float = 0.05  # seed 004: 5 cm
    linkage: str = "centroid"
    min_cluster_size: int = 3
    match_abs_m: float = 0.10
    match_rel: float = 0.10
    target_depth_m: float = 0.10
    min_range_std_m: float = 1e-3

    def __post_init__(self) -> None:
        owner = "SonarFilterConfig"
        check_int(owner, "window_frames", self.window_frames, 1)
        if self.window_s is not None:
            check_positive(owner, "window_s", self.window_s)
        check_positive(owner, "cluster_cutoff_m", self.cluster_cutoff_m)
        check_choice(owner, "linkage", self.linkage, LINKAGES)
        check_int(owner, "min_cluster_size", self.min_cluster_size, 1)
        if self.min_cluster_size > self.window_frames:
            raise ValueError(
                f"{owner}.min_cluster_size must be <= window_frames ({self.window_frames}), "
                f"got {self.min_cluster_size}"
            )
        for name in ("match_abs_m", "match_rel", "target_depth_m"):
            check_positive(owner, name, getattr(self, name), allow_zero=True)
        check_positive(owner, "min_range_std_m", self.min_range_std_m)

    def confirmed_range_std_m(self, model: SonarModel) -> float:
        """Range std (m) given to a sonar-confirmed sighting: the sonar ``model``'s range noise,
        floored at ``min_range_std_m``."""
        return max(model.range_noise_std_m, self.min_range_std_m)

    def match_tolerance_m(self, predicted_m: float) -> float:
        """Largest ``|sonar range - predicted_m|`` (m) that still matches a sighting whose
        predicted echo distance is ``predicted_m`` (m)."""
        return self.match_abs_m + self.match_rel * abs(predicted_m)


@dataclass(frozen=True, kw_only=True)
class SonarObservation:
    """One filtered sonar observation: something ``range_m`` (m) from the transducers in
    sector ``sector`` (0 left, 1 middle, 2 right; :data:`SECTOR_NAMES`), the mean of ``count``
    windowed echoes. Bad fields raise ``ValueError`` / ``InvalidTypeError``."""

    sector: int
    range_m: float
    count: int

    def __post_init__(self) -> None:
        check_int("SonarObservation", "sector", self.sector, 0)
        if self.sector >= N_SONAR_SECTORS:
            raise ValueError(
                f"SonarObservation.sector must be < {N_SONAR_SECTORS}, got {self.sector}"
            )
        check_positive("SonarObservation", "range_m", self.range_m)
        check_int("SonarObservation", "count", self.count, 1)


def cluster_ranges(
    ranges: ArrayLike, *, cutoff_m: float = 0.05, method: str = "centroid"
) -> tuple[FloatArray, NDArray[np.int64]]:
    """Hierarchical agglomerative clustering of 1-D distances with a distance cut-off.

    ``ranges`` (N,) finite distances (m; no NaN). Clusters merge bottom up while the
    ``method`` linkage (one of :data:`LINKAGES`, as ``scipy.cluster.hierarchy.linkage``) puts
    them within ``cutoff_m`` (inclusive, to 1 nm) of each other. Returns the clusters' mean
    distances (K,) (m), ascending, and their sizes (K,) (int64, summing to N). Bad arguments
    raise ValueError naming them. Exactly as one SciPy linkage over all of them, but run by
    run (:func:`_gap_runs`), and a run no wider than ``cutoff_m`` is one cluster without
    SciPy (the usual case: a few echoes of each object; 0.31 to 0.19 ms a step).
    """
    x = np.asarray(ranges, dtype=np.float64)
    if x.ndim != 1 or not np.isfinite(x).all():
        raise ValueError(f"ranges must be a finite (N,) array, got {x.tolist()}")
    check_positive("", "cutoff_m", cutoff_m, allow_zero=True)
    check_choice("", "method", method, LINKAGES)
    x = np.sort(x)
    if len(x) < 2:
        return x, np.ones(len(x), dtype=np.int64)
    labels = np.empty(len(x), dtype=np.intp)
    cutoff = cutoff_m + _CUTOFF_SLACK_M
    count = 0  # of the clusters labelled so far
    for lo, hi in _gap_runs(x, cutoff):
        if x[hi - 1] - x[lo] <= cutoff:  # every linkage's distance within it is at most this
            labels[lo:hi] = count
            count += 1
            continue
        Z = linkage(x[lo:hi, None], method=method, metric="euclidean")
        run_labels = fcluster(Z, t=cutoff, criterion="distance") - 1  # 0, 1, ... in some order
        labels[lo:hi] = count + run_labels
        count += int(run_labels.max()) + 1
    counts = np.bincount(labels).astype(np.int64)
    means = np.bincount(labels, weights=x) / counts
    order = np.argsort(means, kind="stable")
    return means[order], counts[order]


def _gap_runs(x: FloatArray, cutoff: float) -> list[tuple[int, int]]:
    """``(start, end)`` (end exclusive) of the runs of the sorted ``x`` (N,) whose neighbours
    lie within ``cutoff`` of each other. No linkage joins two runs below the cut-off: every
    distance across a gap wider than it (nearest, farthest, mean over pairs, or of the means)
    is wider too, so each run is clustered alone."""
    cuts = (np.flatnonzero(np.diff(x) > cutoff) + 1).tolist()
    return list(zip([0, *cuts], [*cuts, len(x)], strict=True))


class SonarFilter:
    """Rolling window of sonar echoes per sector, clustered into reliable observations.

    ``update(time_s, echoes)`` adds one reading and returns the filtered observations of the
    window; ``reset()`` forgets everything (call it when a new episode starts, or when time
    jumps back).
    """

    def __init__(self, config: SonarFilterConfig | None = None) -> None:
        check_instance("config", config, SonarFilterConfig, optional=True)
        self.config = SonarFilterConfig() if config is None else config
        # Per update: its time (s) and each sector's valid echoes (E_k,) (m).
        self._window: deque[tuple[float, tuple[FloatArray, ...]]] = deque(
            maxlen=self.config.window_frames
        )
        self._observations: tuple[SonarObservation, ...] = ()

    @property
    def observations(self) -> tuple[SonarObservation, ...]:
        """The observations returned by the latest :meth:`update` (empty after a reset)."""
        return self._observations

    def reset(self) -> None:
        """Forget all echoes and observations."""
        self._window.clear()
        self._observations = ()

    def update(self, time_s: float, echoes: ArrayLike) -> tuple[SonarObservation, ...]:
        """Add one sonar reading and return the filtered observations of the window.

        ``time_s`` (s) must be finite and not before the previous update's. ``echoes`` (3, E)
        are the echo distances (m) from the transducers of the left, middle and right sectors
        (a ``SensorFrame.sonar``), NaN-padded, any E >= 0; NaN means no echo, other values
        must be finite and > 0. The window then holds the last ``window_frames`` readings
        (within ``window_s`` of ``time_s`` when set). Returns one :class:`SonarObservation` per
        reliable cluster, ordered by sector (left, middle, right) and then by range.
        """
        check_finite("SonarFilter.update", "time_s", time_s)
        t = float(time_s)
        if self._window and t < self._window[-1][0]:
            raise ValueError(
                f"SonarFilter.update: time_s must not go back (previous {self._window[-1][0]}), "
                f"got {time_s}; call reset() first"
            )
        readings = _echo_array(echoes)
        self._window.append((t, tuple(row[~np.isnan(row)] for row in readings)))
        window_s = self.config.window_s
        if window_s is not None:
            while t - self._window[0][0] >= window_s - TIME_ROUNDING_S:
                self._window.popleft()
        self._observations = self._cluster()
        return self._observations

    def _cluster(self) -> tuple[SonarObservation, ...]:
        """The window's reliable clusters, by sector and range."""
        config = self.config
        out: list[SonarObservation] = []
        for sector in range(N_SONAR_SECTORS):
            ranges = np.concatenate([frame[sector] for _, frame in self._window])
            means, counts = cluster_ranges(
                ranges, cutoff_m=config.cluster_cutoff_m, method=config.linkage
            )
            out += [
                SonarObservation(sector=sector, range_m=float(m), count=int(c))
                for m, c in zip(means, counts, strict=True)
                if c >= config.min_cluster_size
            ]
        return tuple(out)


def _echo_array(echoes: ArrayLike) -> FloatArray:
    """``echoes`` as a (3, E) float64 array; raise unless every entry is NaN or finite > 0."""
    array = real_array(
        echoes, "SonarFilter.update: echoes", f"a ({N_SONAR_SECTORS}, E) array of distances"
    )
    if array.ndim != 2 or array.shape[0] != N_SONAR_SECTORS:
        raise ValueError(
            f"SonarFilter.update: echoes must have shape ({N_SONAR_SECTORS}, E), "
            f"got shape {array.shape}"
        )
    valid = array[~np.isnan(array)]
    if not (np.isfinite(valid).all() and (valid > 0).all()):
        raise ValueError(
            f"SonarFilter.update: echoes must be NaN (no echo) or finite and > 0, got {array}"
        )
    return array


def sonar_polar(range_m: float, bearing_rad: float, mount_x_m: float) -> tuple[float, float]:
    """A robot-frame point at ``range_m`` (m) and ``bearing_rad`` (rad) from the robot origin,
    seen from the sonar ``mount_x_m`` (m) ahead of the origin: its (distance (m), bearing
    (rad, in (-pi, pi])) from the transducers."""
    x = range_m * math.cos(bearing_rad) - mount_x_m
    y = range_m * math.sin(bearing_rad)
    return math.hypot(x, y), math.atan2(y, x)


def sonar_cones(
    model: SonarModel, range_m: float, bearing_rad: float
) -> tuple[float, NDArray[np.bool_]]:
    """A robot-frame point at ``range_m`` (m) and ``bearing_rad`` (rad) from the robot origin:
    its distance (m) from ``model``'s transducers and which of the sectors' cones (3,) hold it,
    seen from the transducers (within half a sector's width of its centre; sectors overlap)."""
    distance, bearing = sonar_polar(range_m, bearing_rad, model.mount_x_m)
    off_axis = np.abs(wrap_angle(bearing - model.sector_centres_rad()))
    return distance, off_axis <= 0.5 * model.sector_widths_rad()


def audible(model: SonarModel, range_m: float, bearing_rad: float) -> bool:
    """Whether ``model``'s sonar can hear an object whose centre lies at ``range_m`` (m) and
    ``bearing_rad`` (rad) from the robot origin: in one of its cones at a distance from the
    transducers within its range (:func:`sonar_cones`)."""
    distance, in_cone = sonar_cones(model, range_m, bearing_rad)
    return bool(in_cone.any()) and model.min_range_m <= distance <= model.max_range_m


def origin_range(
    sonar_range_m: float, bearing_rad: float, mount_x_m: float, near_m: float
) -> tuple[float, float] | None:
    """Where the ray from the robot origin along ``bearing_rad`` (rad) meets the circle of
    radius ``sonar_range_m`` (m) about the sonar, ``mount_x_m`` (m) ahead of the origin.

    Returns (range (m) from the origin, d range / d sonar_range), taking the crossing nearest
    ``near_m`` (m) when the ray meets the circle twice (an origin outside the circle), or None
    when it does not meet it (or only touches it).
    """
    # |r u - m e_x| = s  <=>  r^2 - 2 r m cos(b) + m^2 - s^2 = 0
    along = mount_x_m * math.cos(bearing_rad)
    disc = sonar_range_m**2 - (mount_x_m * math.sin(bearing_rad)) ** 2
    if disc <= 0.0:
        return None
    root = math.sqrt(disc)
    crossings = [r for r in (along + root, along - root) if r > 0.0]
    if not crossings:
        return None
    r = min(crossings, key=lambda c: abs(c - near_m))
    return r, sonar_range_m / root


def confirm_with_sonar(
    sightings: Sequence[RobotSighting],
    observations: Sequence[SonarObservation],
    model: SonarModel,
    config: SonarFilterConfig | None = None,
) -> tuple[RobotSighting, ...]:
    """Algorithm 2, lines 14-17 (seed 004): check robot sightings against filtered sonar ranges.

    ``sightings`` are robot-frame vision sightings (range and bearing from the robot origin to
    the seen robot's centre); ``observations`` filtered sonar ranges
    (:meth:`SonarFilter.update`); ``model`` the sonar's geometry and noise.

    The sonar sits ``model.mount_x_m`` ahead of the robot origin, so each sighting is first
    seen from the transducers (:func:`sonar_polar`; at 1 m and 30° the 5 cm offset shortens the
    distance by 4.3 cm and widens the bearing by 1.5°, as large as the cluster cut-off). A
    sighting is in a sector's cone when its bearing from the transducers lies within half the
    sector's width of its centre (sectors overlap; every sector whose cone holds it counts). Its
    predicted echo distance is its distance from the transducers less ``target_depth_m``; an
    in-cone observation within :meth:`SonarFilterConfig.match_tolerance_m` of that matches it.
    Each observation confirms at most one sighting and each sighting takes at most one
    observation: matches are taken nearest first (greedy on the range difference), so one
    echo cannot lend its range to every sighting in its cone. The confirmed sighting keeps its
    bearing and takes the range, from the robot origin along that bearing, of the point
    ``echo + target_depth_m`` from the transducers (:func:`origin_range`); its range variance
    becomes the sonar's (``range_noise_std_m``, floored at ``min_range_std_m``, through that
    map's slope, within 1.5 % of 1 beyond 0.3 m), the range-bearing covariance 0 (the range
    is now the sonar's, independent of vision's bearing), and ``sonar_confirmed`` True. Team,
    box, score and bearing variance are kept.

    Then a sighting with no team (``team is None``) that is not sonar confirmed (now, or
    already on input) is dropped; every other sighting passes, unchanged when unconfirmed.
    Returns the kept sightings in input order.
    """
    config = SonarFilterConfig() if config is None else config
    check_instance("config", config, SonarFilterConfig)
    if not isinstance(model, SonarModel):
        raise InvalidTypeError(f"model must be a SonarModel, got {type(model).__name__}")
    checked_sightings(sightings, RobotSighting)  # what the tracker it feeds would refuse
    if not isinstance(observations, Sequence):
        raise InvalidTypeError(
            f"observations must be a sequence, got {type(observations).__name__}"
        )
    for k, obs in enumerate(observations):
        if not isinstance(obs, SonarObservation):
            raise InvalidTypeError(
                f"observations[{k}] must be a SonarObservation, got {type(obs).__name__}"
            )
    pairs = sorted(
        (abs(observations[j].range_m - predicted), k, j)
        for k, sighting in enumerate(sightings)
        for predicted, j in _matches(sighting, observations, model, config)
    )
    taken: dict[int, int] = {}  # sighting -> observation
    used: set[int] = set()
    for _, k, j in pairs:
        if k not in taken and j not in used:
            taken[k] = j
            used.add(j)
    sonar_std = config.confirmed_range_std_m(model)
    kept: list[RobotSighting] = []
    for k, sighting in enumerate(sightings):
        confirmed = (
            _confirmed(sighting, observations[taken[k]], model, config, sonar_std)
            if k in taken
            else None
        )
        if confirmed is not None:
            kept.append(confirmed)
        elif sighting.team is not None or sighting.sonar_confirmed:
            kept.append(sighting)
    return tuple(kept)


def _matches(
    sighting: RobotSighting,
    observations: Sequence[SonarObservation],
    model: SonarModel,
    config: SonarFilterConfig,
) -> list[tuple[float, int]]:
    """``(predicted echo distance, index)`` of each observation in ``observations`` that matches
    ``sighting``: in one of its sector's cones and within the match tolerance."""
    distance, in_cone = sonar_cones(model, sighting.range_m, sighting.bearing_rad)
    predicted = distance - config.target_depth_m
    tolerance = config.match_tolerance_m(predicted)
    return [
        (predicted, j)
        for j, obs in enumerate(observations)
        if in_cone[obs.sector] and abs(obs.range_m - predicted) <= tolerance
    ]


def _confirmed(
    sighting: RobotSighting,
    observation: SonarObservation,
    model: SonarModel,
    config: SonarFilterConfig,
    sonar_std: float,
) -> RobotSighting | None:
    """``sighting`` with ``observation``'s range and the sonar's range noise, or None when the
    echo's circle does not cross the sighting's bearing."""
    crossing = origin_range(
        observation.range_m + config.target_depth_m,
        sighting.bearing_rad,
        model.mount_x_m,
        sighting.range_m,
    )
    if crossing is None:
        return None
    range_m, slope = crossing
    cov = np.asarray(sighting.cov, dtype=np.float64)
    new_cov = np.array([[(slope * sonar_std) ** 2, 0.0], [0.0, float(cov[1, 1])]])
    return replace(sighting, range_m=range_m, cov=new_cov, sonar_confirmed=True)
