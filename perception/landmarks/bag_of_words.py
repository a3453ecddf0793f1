"""Bag-of-words image retrieval with geometric verification (seed 004 §4.1-4.2).

An image's features, quantised to words of a :class:`perception.landmarks.vocabulary.Vocabulary`,
become its word-count vector (K,) (stopped words dropped). Images are compared by the cosine
of their tf-idf vectors (eq. 9; Sivic & Zisserman 2003), for image ``d`` and word ``i``::

    t_i = (n_id / n_d) log(N / n_i)

``n_id``: occurrences of word ``i`` in ``d``; ``n_d``: words in ``d``; ``N``: images in the
database; ``n_i``: database images that hold word ``i`` (the document frequency, Sivic &
Zisserman's definition; the seed's text says "occurrences of word i in the whole database",
which can exceed ``N`` and make the log negative). A word no database image holds has weight 0
(it can match nothing), as has every word of an image without words. With a single image in
the database every word it holds has ``n_i = N`` and weight 0: nothing can be retrieved yet.

:class:`ImageDatabase` keeps each image's count vector, the image columns (px) of its
(unstopped) features and their words, and an inverted index word -> images holding it. A query
scores, through the inverted index, only the images sharing a word with it, ranks them by
cosine, and verifies them in rank order: every pair of a query feature and a stored feature of
the same word is a possible match, and RANSAC fits eq. 8 ``x_query = beta_s x_stored +
beta_d`` through them (:func:`perception.landmarks.matching.ransac_line`). A hit needs cosine
>= ``min_cosine`` and >= ``min_inliers`` matched features among the inlier pairs: the fewer of
their distinct query and distinct stored features (a word repeated in both images makes several
pairs of one feature; counting pairs passed more views of the other goal in tuning).

Query expansion (Algorithm 1 lines 5, 7, 10): the count vector queried (or stored) is this
frame's plus the previous frame's; pass it as ``counts``, the sum of two :func:`word_counts`.
Geometric verification always uses this frame's features ``words`` and ``x``.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from perception.geometry import FloatArray
from perception.landmarks.matching import LineModel, Matches, RansacConfig, ransac_line
from perception.landmarks.vocabulary import Vocabulary
from perception.validation import (
    InvalidTypeError,
    check_generator,
    check_in_interval,
    check_int,
    check_nested_configs,
)

IntArray = NDArray[np.int64]


@dataclass(frozen=True, kw_only=True)
class RetrievalConfig:
    """When a database image is a hit for a query, and how many hits a query returns.

    (a) The seed gives no values; these were chosen on rendered goal-area views of scenes
    1030-1035 (:mod:`perception.landmarks.field_end`).
    """

    min_cosine: float = 0.3  # tf-idf cosine of a hit, at least (a)
    min_inliers: int = 8  # matched features on the RANSAC line of a hit, at least (a)
    ransac: RansacConfig = field(default_factory=RansacConfig)  # eq. 8 over same-word pairs
    max_results: int = 10  # hits returned, best cosine first

    def __post_init__(self) -> None:
        check_nested_configs(self)
        check_in_interval(
            "RetrievalConfig", "min_cosine", self.min_cosine, 0.0, 1.0, high_inclusive=True
        )
        check_int("RetrievalConfig", "min_inliers", self.min_inliers, 2)
        if self.min_inliers < self.ransac.min_inliers:
            raise ValueError(
                f"RetrievalConfig.min_inliers must be >= ransac.min_inliers "
                f"{self.ransac.min_inliers}, got {self.min_inliers}"
            )
        check_int("RetrievalConfig", "max_results", self.max_results, 1)


@dataclass(frozen=True)
class Hit:
    """A verified database image: its ``image`` index (order of adding), ``label``, tf-idf
    ``cosine``, ``inliers`` (matched features on the RANSAC line, module docstring) and the
    fitted eq. 8 ``model``."""

    image: int
    label: int
    cosine: float
    inliers: int
    model: LineModel


def word_counts(words: ArrayLike, vocabulary: Vocabulary) -> IntArray:
    """The word-count vector (K,) of an image's feature words (N,), stopped words dropped."""
    ids = _word_ids(words, len(vocabulary))
    counts = np.bincount(ids, minlength=len(vocabulary)).astype(np.int64)
    counts[vocabulary.stopped] = 0
    return counts


def tf_idf(counts: ArrayLike, document_frequency: ArrayLike, n_images: int) -> FloatArray:
    """Eq. 9 weights of count vectors ``counts`` (..., K) in a database of ``n_images`` images
    where ``document_frequency`` (K,) images hold each word (module docstring). ValueError
    unless ``n_images`` >= 1 and the counts and frequencies are finite and >= 0, frequencies at
    most ``n_images``."""
    check_int("tf_idf", "n_images", n_images, 1)
    n = np.asarray(counts, dtype=np.float64)
    held = np.asarray(document_frequency, dtype=np.float64)
    if held.ndim != 1 or n.shape[-1:] != held.shape:
        raise ValueError(
            f"tf_idf: counts (..., K) and document_frequency (K,) must share K, got shapes "
            f"{n.shape} and {held.shape}"
        )
    for name, values in (("counts", n), ("document_frequency", held)):
        if not (np.isfinite(values).all() and (values >= 0).all()):
            raise ValueError(f"tf_idf: {name} must be finite and >= 0, got {values.tolist()}")
    if (held > n_images).any():
        raise ValueError(f"tf_idf: document_frequency must be <= n_images ({n_images})")
    total = n.sum(axis=-1, keepdims=True)
    with np.errstate(divide="ignore", invalid="ignore"):
        tf = np.where(total > 0, n / total, 0.0)
        idf = np.where(held > 0, np.log(n_images / held), 0.0)
    return tf * idf


def same_word_matches(
    query_words: IntArray, query_x: FloatArray, stored_words: IntArray, stored_x: FloatArray
) -> Matches:
    """Every pair of a query feature and a stored feature with the same word, as
    :class:`perception.landmarks.matching.Matches` (query = test) of distance 0 and weight 1,
    so that a RANSAC score counts inlier pairs. Inputs: (Nq,) and (Ns,) words and columns."""
    test_index, stored_index = np.nonzero(query_words[:, None] == stored_words[None, :])
    m = len(test_index)
    matches = Matches(
        test_index=test_index.astype(np.int64),
        stored_index=stored_index.astype(np.int64),
        test_x=query_x[test_index],
        stored_x=stored_x[stored_index],
        distance=np.zeros(m),
        weight=np.ones(m),
    )
    for array in vars(matches).values():
        array.flags.writeable = False
    return matches


@dataclass(frozen=True, eq=False)
class _Image:
    """One stored image: count vector (K,), unstopped feature words (n,) and columns (n,)."""

    counts: IntArray
    words: IntArray
    x: FloatArray
    label: int


class ImageDatabase:
    """Labelled images as bags of words, with an inverted index (module docstring)."""

    def __init__(self, vocabulary: Vocabulary, config: RetrievalConfig) -> None:
        if not isinstance(vocabulary, Vocabulary):
            raise InvalidTypeError(
                f"vocabulary must be a Vocabulary, got {type(vocabulary).__name__}"
            )
        if not isinstance(config, RetrievalConfig):
            raise InvalidTypeError(f"config must be a RetrievalConfig, got {type(config).__name__}")
        self.vocabulary = vocabulary
        self.config = config
        self._images: list[_Image] = []
        self._postings: list[list[int]] = [[] for _ in range(len(vocabulary))]
        self._document_frequency = np.zeros(len(vocabulary), dtype=np.int64)
        self._labels: Counter[int] = Counter()  # stored images per label

    def __len__(self) -> int:
        return len(self._images)

    @property
    def document_frequency(self) -> IntArray:
        """(K,) the number of stored images holding each word (a copy)."""
        return self._document_frequency.copy()

    def count(self, label: int) -> int:
        """How many stored images carry ``label``."""
        return self._labels[label]

    def clear(self) -> None:
        """Forget every image."""
        self._images.clear()
        self._labels.clear()
        for posting in self._postings:
            posting.clear()
        self._document_frequency[:] = 0

    def add(
        self, words: ArrayLike, x: ArrayLike, label: int, counts: ArrayLike | None = None
    ) -> int:
        """Store an image: its features' words (N,) and columns ``x`` (N,) (px), an int
        ``label`` and its count vector ``counts`` (K,) (default ``word_counts(words)``; query
        expansion passes the sum with the previous frame's). Returns its image index."""
        check_int("ImageDatabase.add", "label", label)
        ids, columns = self._features(words, x)
        vector = word_counts(ids, self.vocabulary) if counts is None else self._counts(counts)
        image = len(self._images)
        self._images.append(_Image(counts=vector, words=ids, x=columns, label=int(label)))
        self._labels[int(label)] += 1
        for word in np.flatnonzero(vector).tolist():
            self._postings[word].append(image)
        self._document_frequency += vector > 0
        return image

    def cosines(self, counts: ArrayLike) -> tuple[IntArray, FloatArray]:
        """The images sharing a word with the count vector ``counts`` (K,), found through the
        inverted index, in index order (M,), and their tf-idf cosines (M,) with it (0 where
        either tf-idf vector is zero)."""
        vector = self._counts(counts)
        shared: set[int] = set()
        for word in np.flatnonzero(vector).tolist():
            shared.update(self._postings[word])
        images = np.array(sorted(shared), dtype=np.int64)
        if len(images) == 0:
            return images, np.zeros(0)
        stored = np.stack([self._images[i].counts for i in images.tolist()])
        q = tf_idf(vector, self._document_frequency, len(self))
        d = tf_idf(stored, self._document_frequency, len(self))
        norms = np.linalg.norm(d, axis=1) * np.linalg.norm(q)
        with np.errstate(divide="ignore", invalid="ignore"):
            cosine = np.where(norms > 0.0, (d @ q) / norms, 0.0)
        return images, cosine

    def query(
        self,
        words: ArrayLike,
        x: ArrayLike,
        rng: np.random.Generator,
        counts: ArrayLike | None = None,
    ) -> tuple[Hit, ...]:
        """The hits (at most ``max_results``, best cosine first; ties: lower index) for a frame
        with features' words (N,) and columns ``x`` (N,) (px), querying the count vector
        ``counts`` (K,) (default ``word_counts(words)``). RANSAC draws from ``rng``."""
        check_generator("rng", rng)
        ids, columns = self._features(words, x)
        vector = word_counts(ids, self.vocabulary) if counts is None else self._counts(counts)
        images, cosine = self.cosines(vector)
        hits: list[Hit] = []
        for k in np.lexsort((images, -cosine)).tolist():
            if cosine[k] < self.config.min_cosine or len(hits) == self.config.max_results:
                break
            image = int(images[k])
            stored = self._images[image]
            matches = same_word_matches(ids, columns, stored.words, stored.x)
            result = ransac_line(matches, self.config.ransac, rng)
            inliers = _matched_features(matches, result.inliers)
            if result.model is not None and inliers >= self.config.min_inliers:
                hits.append(Hit(image, stored.label, float(cosine[k]), inliers, result.model))
        return tuple(hits)

    def _features(self, words: ArrayLike, x: ArrayLike) -> tuple[IntArray, FloatArray]:
        """Validated words (N,) and columns (N,) less the features of stopped words."""
        ids = _word_ids(words, len(self.vocabulary))
        columns = np.array(x, dtype=np.float64)
        if columns.shape != ids.shape or not np.isfinite(columns).all():
            raise ValueError(
                f"x must be finite with the words' shape {ids.shape}, got {columns.shape}"
            )
        keep = ~self.vocabulary.stopped[ids]
        return ids[keep], columns[keep]

    def _counts(self, counts: ArrayLike) -> IntArray:
        """``counts`` as a validated (K,) int64 count vector, stopped words zeroed."""
        vector = np.asarray(counts)
        k = len(self.vocabulary)
        if vector.shape != (k,) or not np.issubdtype(vector.dtype, np.integer):
            raise ValueError(
                f"counts must be an int array of shape ({k},), got {vector.dtype} {vector.shape}"
            )
        if (vector < 0).any():
            raise ValueError(f"counts must be >= 0, got {vector.min()}")
        vector = vector.astype(np.int64)
        vector[self.vocabulary.stopped] = 0
        return vector


def _matched_features(matches: Matches, inliers: NDArray[np.bool_]) -> int:
    """Features matched by the ``inliers`` (M,) among same-word pairs: the fewer of the
    distinct query and distinct stored features they hold (a word repeated in both images
    makes several pairs of one feature, which count once)."""
    return min(
        len(np.unique(matches.test_index[inliers])), len(np.unique(matches.stored_index[inliers]))
    )


def _word_ids(words: ArrayLike, k: int) -> IntArray:
    """``words`` as a (N,) int64 array of ids in [0, k)."""
    ids = np.asarray(words)
    if ids.ndim != 1 or not (ids.size == 0 or np.issubdtype(ids.dtype, np.integer)):
        raise ValueError(f"words must be a 1-D int array, got {ids.dtype} of shape {ids.shape}")
    ids = ids.astype(np.int64)
    if ids.size and (ids.min() < 0 or ids.max() >= k):
        raise ValueError(f"words must be ids in [0, {k}), got {ids.min()} .. {ids.max()}")
    return ids
