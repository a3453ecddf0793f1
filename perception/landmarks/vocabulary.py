"""A visual vocabulary of 1D SURF descriptors: k-means words and a stop list (seed 004 §4.1-4.2).

A vocabulary is K words, points in descriptor space (D = 6 for 1D SURF,
:class:`perception.landmarks.surf1d.Surf1dFeatures`); a feature maps to its nearest word
(Euclidean), so an image becomes a bag of words (:mod:`perception.landmarks.bag_of_words`).

:func:`learn_vocabulary` clusters training descriptors with Lloyd's k-means. K-means is only
locally optimal and the seed finds random initialisation over-segments the dense regions of
descriptor space, so it initialises by subset-furthest-first (SFF, Turnbull & Elkan 2005):

- ``"random"``: K distinct descriptors drawn uniformly without replacement;
- ``"sff"``: a subset of ``ceil(2 K ln K)`` descriptors drawn uniformly without replacement
  (``subset_size`` overrides; at most all of them), one random point of it as the first word,
  then repeatedly the subset point furthest from its nearest chosen word. Furthest-first on
  all descriptors picks outliers; on a random subset the outliers are rarely drawn.

Lloyd's iterations alternate assigning every descriptor to its nearest word (exact ties: the
lower word index) and moving each word to the mean of its descriptors, until no assignment changes
or ``iterations`` have run. A word left with no descriptor is re-seeded at a descriptor drawn
uniformly from ``rng``.

:func:`with_stop_list` marks words as stopped by their frequency in training descriptors: the
seed stops the bottom 5 % with SFF (K = 200: 10 words); Sivic & Zisserman (2003) stopped the
top 5 % and the bottom 10 % with random initialisation.

:func:`default_vocabulary` loads the shipped vocabulary (``vocabulary/horizon_words.npz`` next
to this module), learned by ``python -m training.learn_vocabulary``.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from perception.geometry import FloatArray
from perception.validation import (
    InvalidTypeError,
    check_choice,
    check_generator,
    check_in_interval,
    check_int,
)

INITIALISATIONS = ("random", "sff")
SFF_SUBSET_PER_K_LN_K = 2.0  # SFF subset size ceil(2 K ln K)
_CHUNK_ROWS = 4096  # descriptors per block when finding nearest words (bounds memory)
_SHIPPED_FOLDER, _SHIPPED_FILE = "words", "horizon_words.npz"  # under this package


@dataclass(frozen=True, eq=False)
class Vocabulary:
    """K visual words. Arrays read-only copies.

    - ``words`` (K, D): the words (cluster centres) in descriptor space;
    - ``stopped`` (K,) bool: words on the stop list, ignored in bags of words.
    """

    words: FloatArray
    stopped: NDArray[np.bool_]

    def __post_init__(self) -> None:
        words = _finite_matrix(self.words, "Vocabulary.words")
        if len(words) == 0:
            raise ValueError("Vocabulary.words must hold at least one word, got shape (0, D)")
        stopped = np.array(self.stopped)
        if stopped.dtype != np.bool_ or stopped.shape != (len(words),):
            raise ValueError(
                f"Vocabulary.stopped must be a bool array of shape ({len(words)},), "
                f"got {stopped.dtype} of shape {stopped.shape}"
            )
        for array in (words, stopped):
            array.flags.writeable = False
        object.__setattr__(self, "words", words)
        object.__setattr__(self, "stopped", stopped)

    def __len__(self) -> int:
        return len(self.words)

    @property
    def dimension(self) -> int:
        """D, the descriptors' length."""
        return int(self.words.shape[1])

    def quantise(self, descriptors: ArrayLike) -> NDArray[np.int64]:
        """The word id (N,) of each descriptor (N, D): its nearest word (Euclidean, to within
        rounding; exact ties: the lower id). Stopped words are returned too: bags of words drop
        them."""
        points = _finite_matrix(descriptors, "descriptors", self.dimension)
        return _nearest(points, self.words)

    def save(self, path: str | Path) -> None:
        """Write ``words`` and ``stopped`` to the ``.npz`` file ``path`` (numpy appends
        ``.npz`` to a path without it)."""
        np.savez(Path(path), words=self.words, stopped=self.stopped)

    @classmethod
    def load(cls, path: str | Path) -> Vocabulary:
        """The vocabulary saved by :meth:`save` at ``path``."""
        with np.load(Path(path)) as data:
            missing = {"words", "stopped"} - set(data.files)
            if missing:
                raise ValueError(f"{path} is not a vocabulary: it lacks {sorted(missing)}")
            return cls(words=data["words"], stopped=data["stopped"])


@functools.cache
def default_vocabulary() -> Vocabulary:
    """The shipped 200-word vocabulary of horizon features (loaded once, then cached)."""
    shipped = resources.files("perception.landmarks") / _SHIPPED_FOLDER / _SHIPPED_FILE
    with resources.as_file(shipped) as path:
        return Vocabulary.load(path)


def learn_vocabulary(
    descriptors: ArrayLike,
    k: int,
    *,
    rng: np.random.Generator,
    init: Literal["random", "sff"] = "sff",
    iterations: int = 300,
    subset_size: int | None = None,
) -> Vocabulary:
    """K words clustering ``descriptors`` (N, D) by k-means (module docstring); none stopped.

    ``iterations``: at most this many Lloyd iterations; 0 returns the initial words.
    ``subset_size``: SFF's subset (default ``ceil(2 k ln k)``, at most N); ignored by
    ``"random"``. Every draw comes from ``rng``. Raises ValueError when the descriptors (or the
    SFF subset) hold fewer than ``k`` distinct points.
    """
    points = _finite_matrix(descriptors, "descriptors")
    check_int("learn_vocabulary", "k", k, 1)
    check_choice("learn_vocabulary", "init", init, INITIALISATIONS)
    check_int("learn_vocabulary", "iterations", iterations, 0)
    check_int("learn_vocabulary", "subset_size", subset_size, k, optional=True)
    check_generator("rng", rng)
    if len(points) < k:
        raise ValueError(f"learn_vocabulary needs at least k={k} descriptors, got {len(points)}")
    if init == "random":
        centres = _random_centres(points, k, rng)
    else:
        size = _sff_subset_size(k) if subset_size is None else subset_size
        centres = _sff_centres(points, k, min(size, len(points)), rng)
    assignment = np.full(len(points), -1, dtype=np.int64)
    for _ in range(iterations):
        previous, assignment = assignment, _nearest(points, centres)
        if np.array_equal(assignment, previous):
            break
        centres = _means(points, assignment, k, rng)
    return Vocabulary(words=centres, stopped=np.zeros(k, dtype=bool))


def with_stop_list(
    vocabulary: Vocabulary, descriptors: ArrayLike, bottom: float = 0.05, top: float = 0.0
) -> Vocabulary:
    """``vocabulary`` with the ``bottom`` fraction of its words by frequency among
    ``descriptors`` (N, D) stopped, and the ``top`` fraction.

    ``round(fraction * K)`` words each; words of equal frequency are taken in id order (the
    lower ids first, least and most frequent alike). Replaces any earlier stop list.
    """
    check_in_interval("with_stop_list", "bottom", bottom, 0.0, 1.0, low_inclusive=True)
    check_in_interval("with_stop_list", "top", top, 0.0, 1.0, low_inclusive=True)
    if bottom + top >= 1.0:
        raise ValueError(f"with_stop_list needs bottom + top < 1, got {bottom} + {top}")
    k = len(vocabulary)
    counts = np.bincount(vocabulary.quantise(descriptors), minlength=k)
    n_bottom, n_top = round(bottom * k), round(top * k)
    stopped = np.zeros(k, dtype=bool)
    stopped[np.argsort(counts, kind="stable")[:n_bottom]] = True
    stopped[np.argsort(-counts, kind="stable")[:n_top]] = True
    return Vocabulary(words=vocabulary.words, stopped=stopped)


def _sff_subset_size(k: int) -> int:
    """SFF's default subset size ``ceil(2 k ln k)``, at least ``k``."""
    return max(k, math.ceil(SFF_SUBSET_PER_K_LN_K * k * math.log(k)))


def _random_centres(points: FloatArray, k: int, rng: np.random.Generator) -> FloatArray:
    """``k`` distinct rows of ``points`` (N, D) drawn uniformly without replacement."""
    shuffled = points[rng.permutation(len(points))]
    _, first = np.unique(shuffled, axis=0, return_index=True)  # first copy of each value
    if len(first) < k:
        raise ValueError(f"learn_vocabulary needs k={k} distinct descriptors, got {len(first)}")
    return shuffled[np.sort(first)[:k]].copy()


def _sff_centres(
    points: FloatArray, k: int, subset_size: int, rng: np.random.Generator
) -> FloatArray:
    """Subset-furthest-first: ``k`` rows of a random ``subset_size`` subset of ``points``."""
    subset = points[rng.choice(len(points), size=subset_size, replace=False)]
    chosen = [int(rng.integers(subset_size))]
    nearest = np.linalg.norm(subset - subset[chosen[0]], axis=1)  # to the nearest chosen word
    for _ in range(k - 1):
        furthest = int(np.argmax(nearest))
        if nearest[furthest] == 0.0:
            raise ValueError(
                f"learn_vocabulary: the SFF subset of {subset_size} descriptors holds fewer than "
                f"k={k} distinct points; pass a larger subset_size"
            )
        chosen.append(furthest)
        nearest = np.minimum(nearest, np.linalg.norm(subset - subset[furthest], axis=1))
    return subset[chosen].copy()


def _means(
    points: FloatArray, assignment: NDArray[np.int64], k: int, rng: np.random.Generator
) -> FloatArray:
    """The mean (k, D) of each cluster's points; an empty cluster gets a random point."""
    sizes = np.bincount(assignment, minlength=k)
    sums = np.stack(
        [np.bincount(assignment, weights=column, minlength=k) for column in points.T], axis=1
    )
    centres = sums / np.maximum(sizes, 1)[:, None]
    empty = np.flatnonzero(sizes == 0)
    centres[empty] = points[rng.integers(len(points), size=len(empty))]
    return centres


def _nearest(points: FloatArray, centres: FloatArray) -> NDArray[np.int64]:
    """Index (N,) of the nearest row of ``centres`` (K, D) to each row of ``points`` (N, D).

    ``|x - c|^2 = |x|^2 - 2 x.c + |c|^2`` and ``|x|^2`` is the same for every ``c``, so the
    nearest centre minimises ``|c|^2 - 2 x.c``: one matrix product per block of rows (exact
    up to rounding, about 1e-16 of the squared norms).
    """
    squared = np.einsum("kd,kd->k", centres, centres)
    out = np.empty(len(points), dtype=np.int64)
    for start in range(0, len(points), _CHUNK_ROWS):
        block = points[start : start + _CHUNK_ROWS]
        out[start : start + len(block)] = np.argmin(squared - 2.0 * block @ centres.T, axis=1)
    return out


def _finite_matrix(value: ArrayLike, name: str, columns: int | None = None) -> FloatArray:
    """``value`` as a new finite float64 (N, D) array (D = ``columns`` when given)."""
    try:
        matrix = np.array(value, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise InvalidTypeError(
            f"{name} must be an (N, D) array of numbers, got {value!r}"
        ) from error
    wanted = "D" if columns is None else str(columns)
    if matrix.ndim != 2 or (columns is not None and matrix.shape[1] != columns):
        raise ValueError(f"{name} must have shape (N, {wanted}), got shape {matrix.shape}")
    if matrix.shape[1] == 0:
        raise ValueError(f"{name} must have at least one column, got shape {matrix.shape}")
    if not np.isfinite(matrix).all():
        rows = np.flatnonzero(~np.isfinite(matrix).all(axis=1)).tolist()
        raise ValueError(f"{name} must be finite, got NaN or infinity in rows {rows}")
    return matrix
