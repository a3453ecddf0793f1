"""Visual vocabulary (:mod:`perception.landmarks.vocabulary`): nearest-word quantisation,
k-means with random and subset-furthest-first initialisation, the stop list, files."""

from __future__ import annotations

from pathlib import Path
from typing import Literal

import numpy as np
import pytest

from perception.landmarks.vocabulary import (
    Vocabulary,
    default_vocabulary,
    learn_vocabulary,
    with_stop_list,
)

Init = Literal["random", "sff"]
BLOB_CENTRES = 10.0 * np.vstack([np.eye(6)[:4], -np.eye(6)[:1]])  # 5 blobs, >= 14 apart


def blobs(per_blob: int = 40, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Points (5 * per_blob, 6) of Gaussian blobs (sigma 0.3) about BLOB_CENTRES, and the blob
    of each point."""
    rng = np.random.default_rng(seed)
    blob = np.repeat(np.arange(len(BLOB_CENTRES)), per_blob)
    return BLOB_CENTRES[blob] + 0.3 * rng.standard_normal((len(blob), 6)), blob


def blob_of(points: np.ndarray) -> np.ndarray:
    """The blob whose centre is nearest each point (all within 3 of it here)."""
    distance = np.linalg.norm(points[:, None, :] - BLOB_CENTRES[None], axis=2)
    assert (distance.min(axis=1) < 3.0).all()
    return distance.argmin(axis=1)


def test_quantise_gives_the_nearest_word() -> None:
    rng = np.random.default_rng(1)
    words = rng.standard_normal((30, 6))
    descriptors = rng.standard_normal((200, 6))
    vocabulary = Vocabulary(words=words, stopped=np.zeros(30, dtype=bool))
    brute = [int(np.argmin([np.linalg.norm(d - w) for w in words])) for d in descriptors]
    np.testing.assert_array_equal(vocabulary.quantise(descriptors), brute)
    np.testing.assert_array_equal(vocabulary.quantise(words), np.arange(30))


def test_save_and_load_round_trip(tmp_path: Path) -> None:
    rng = np.random.default_rng(2)
    stopped = np.zeros(12, dtype=bool)
    stopped[[3, 7]] = True
    vocabulary = Vocabulary(words=rng.standard_normal((12, 6)), stopped=stopped)
    vocabulary.save(tmp_path / "words.npz")
    loaded = Vocabulary.load(tmp_path / "words.npz")
    np.testing.assert_array_equal(loaded.words, vocabulary.words)
    np.testing.assert_array_equal(loaded.stopped, stopped)


def test_the_shipped_vocabulary_has_200_words_and_10_stopped() -> None:
    vocabulary = default_vocabulary()
    assert vocabulary.words.shape == (200, 6)
    assert np.isfinite(vocabulary.words).all()
    assert int(vocabulary.stopped.sum()) == 10  # bottom 5 % of 200
    assert default_vocabulary() is vocabulary  # cached
    assert not vocabulary.words.flags.writeable


def test_sff_initial_words_cover_every_blob_where_random_ones_need_not() -> None:
    """Furthest-first on a subset holding every blob picks one point per blob: any point of
    another blob is further from the chosen ones than any point of a chosen blob. Random
    draws of 5 of the 200 points cover the 5 blobs with probability about 4 %."""
    points, _ = blobs()
    covering: dict[str, list[bool]] = {"sff": [], "random": []}
    inits: tuple[Init, ...] = ("sff", "random")
    for init in inits:
        for seed in range(5):
            initial = learn_vocabulary(
                points, 5, rng=np.random.default_rng(seed), init=init, iterations=0, subset_size=60
            )
            assert all((points == word).all(axis=1).any() for word in initial.words)  # data
            covering[init].append(sorted(blob_of(initial.words).tolist()) == [0, 1, 2, 3, 4])
    assert all(covering["sff"])
    assert not all(covering["random"])


@pytest.mark.parametrize("init", ["random", "sff"])
def test_k_means_recovers_the_blob_means(init: Init) -> None:
    """From words covering every blob Lloyd's iterations end at the blobs' sample means. Seed 29
    is one whose random draw covers every blob (checked here: random draws need not)."""
    points, blob = blobs()
    rng_seed, k = 29, len(BLOB_CENTRES)
    initial = learn_vocabulary(
        points, k, rng=np.random.default_rng(rng_seed), init=init, iterations=0, subset_size=60
    )
    assert sorted(blob_of(initial.words).tolist()) == list(range(k))
    learned = learn_vocabulary(
        points, k, rng=np.random.default_rng(rng_seed), init=init, subset_size=60
    )
    means = np.array([points[blob == b].mean(axis=0) for b in range(k)])
    np.testing.assert_allclose(learned.words[np.argsort(blob_of(learned.words))], means, atol=1e-12)
    assert not learned.stopped.any()


def test_random_initialisation_draws_distinct_descriptors() -> None:
    points = np.array([[0.0], [0.0], [0.0], [0.0], [1.0], [2.0]])
    for seed in range(10):
        initial = learn_vocabulary(
            points, 3, rng=np.random.default_rng(seed), init="random", iterations=0
        )
        assert sorted(initial.words[:, 0].tolist()) == [0.0, 1.0, 2.0]
    with pytest.raises(ValueError, match="3 distinct"):
        learn_vocabulary(points[:4], 3, rng=np.random.default_rng(0), init="random")


def test_learning_is_reproducible_from_the_seed() -> None:
    points, _ = blobs(per_blob=10, seed=4)
    a = learn_vocabulary(points, 8, rng=np.random.default_rng(5))
    b = learn_vocabulary(points, 8, rng=np.random.default_rng(5))
    np.testing.assert_array_equal(a.words, b.words)


def test_stop_list_fractions_by_training_frequency() -> None:
    """Word i (at i on a line) occurs i + 1 times: the least frequent words are the lowest."""
    k = 20
    vocabulary = Vocabulary(words=np.arange(k, dtype=float)[:, None], stopped=np.zeros(k, bool))
    descriptors = np.repeat(np.arange(k, dtype=float), np.arange(1, k + 1))[:, None]
    stopped = with_stop_list(vocabulary, descriptors, bottom=0.1, top=0.05).stopped
    np.testing.assert_array_equal(np.flatnonzero(stopped), [0, 1, 19])  # 2 bottom, 1 top
    default = with_stop_list(vocabulary, descriptors).stopped  # bottom 5 %: 1 word of 20
    np.testing.assert_array_equal(np.flatnonzero(default), [0])
    np.testing.assert_array_equal(with_stop_list(vocabulary, descriptors, bottom=0.0).stopped, 0)


def test_stop_list_ties_are_taken_in_word_order() -> None:
    vocabulary = Vocabulary(words=np.arange(4, dtype=float)[:, None], stopped=np.zeros(4, bool))
    descriptors = np.array([[0.0], [1.0], [2.0], [3.0], [3.0]])  # words 0, 1, 2 once each
    stopped = with_stop_list(vocabulary, descriptors, bottom=0.5).stopped
    np.testing.assert_array_equal(np.flatnonzero(stopped), [0, 1])


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"k": 0}, "learn_vocabulary.k"),
        ({"init": "kmeans++"}, "learn_vocabulary.init"),
        ({"iterations": -1}, "learn_vocabulary.iterations"),
        ({"subset_size": 2}, "learn_vocabulary.subset_size"),
    ],
)
def test_bad_learning_arguments_are_named(kwargs: dict[str, object], field: str) -> None:
    points, _ = blobs(per_blob=4)
    arguments: dict[str, object] = {"k": 4, "init": "sff", "iterations": 10} | kwargs
    with pytest.raises(ValueError, match=field):
        learn_vocabulary(points, rng=np.random.default_rng(0), **arguments)  # type: ignore[arg-type]


def test_bad_vocabularies_and_stop_fractions_are_named() -> None:
    with pytest.raises(ValueError, match=r"Vocabulary\.stopped"):
        Vocabulary(words=np.zeros((3, 6)), stopped=np.zeros(2, dtype=bool))
    with pytest.raises(ValueError, match=r"Vocabulary\.words"):
        Vocabulary(words=np.full((3, 6), np.nan), stopped=np.zeros(3, dtype=bool))
    vocabulary = Vocabulary(words=np.zeros((4, 1)), stopped=np.zeros(4, dtype=bool))
    with pytest.raises(ValueError, match=r"with_stop_list\.bottom"):
        with_stop_list(vocabulary, np.zeros((2, 1)), bottom=1.0)
    with pytest.raises(ValueError, match="bottom \\+ top"):
        with_stop_list(vocabulary, np.zeros((2, 1)), bottom=0.5, top=0.5)
    with pytest.raises(ValueError, match="descriptors must have shape"):
        vocabulary.quantise(np.zeros((2, 6)))
    with pytest.raises(TypeError, match="rng"):
        learn_vocabulary(np.zeros((4, 1)), 1, rng=0)  # type: ignore[arg-type]
