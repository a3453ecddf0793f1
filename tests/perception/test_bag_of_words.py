"""Bag-of-words retrieval (:mod:`perception.landmarks.bag_of_words`): eq. 9 tf-idf by hand,
cosines through the inverted index, geometric verification and query expansion."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from perception.landmarks.bag_of_words import (
    ImageDatabase,
    RetrievalConfig,
    tf_idf,
    word_counts,
)
from perception.landmarks.matching import RansacConfig
from perception.landmarks.vocabulary import Vocabulary

LN3, LN1_5 = 1.0986122886681098, 0.4054651081081644  # ln 3, ln 1.5
COLUMNS = 10.0 + 25.0 * np.arange(12)  # 12 features spread over a 320 px image
SCRAMBLE = [7, 2, 10, 0, 5, 11, 3, 8, 1, 9, 4, 6]  # no admissible line holds 8 of them


def vocabulary(k: int, stopped: list[int] | None = None) -> Vocabulary:
    """K words on a line (only their number and stop list matter here)."""
    mask = np.zeros(k, dtype=bool)
    mask[stopped or []] = True
    return Vocabulary(words=np.arange(k, dtype=float)[:, None], stopped=mask)


def rng() -> np.random.Generator:
    return np.random.default_rng(0)


def test_tf_idf_of_three_images_by_hand() -> None:
    """Words 0-3. A = {0, 0, 1}, B = {1, 2}, C = {2, 3, 3, 3}: word 0 is in 1 image, 1 in 2,
    2 in 2, 3 in 1 of N = 3, so idf = (ln 3, ln 1.5, ln 1.5, ln 3)."""
    database = ImageDatabase(vocabulary(4), RetrievalConfig())
    for words in ([0, 0, 1], [1, 2], [2, 3, 3, 3]):
        database.add(words, np.zeros(len(words)), label=1)
    np.testing.assert_array_equal(database.document_frequency, [1, 2, 2, 1])
    counts = np.array([[2, 1, 0, 0], [0, 1, 1, 0], [0, 0, 1, 3]])
    expected = np.array(
        [
            [2 / 3 * LN3, 1 / 3 * LN1_5, 0.0, 0.0],
            [0.0, 1 / 2 * LN1_5, 1 / 2 * LN1_5, 0.0],
            [0.0, 0.0, 1 / 4 * LN1_5, 3 / 4 * LN3],
        ]
    )
    np.testing.assert_allclose(tf_idf(counts, database.document_frequency, 3), expected)

    # query A: it shares words with A and B only; cos(A, A) = 1, cos(A, B) by hand
    images, cosine = database.cosines(counts[0])
    np.testing.assert_array_equal(images, [0, 1])
    cos_ab = (1 / 3 * LN1_5 * 1 / 2 * LN1_5) / (
        math.hypot(2 / 3 * LN3, 1 / 3 * LN1_5) * math.hypot(1 / 2 * LN1_5, 1 / 2 * LN1_5)
    )
    np.testing.assert_allclose(cosine, [1.0, cos_ab], rtol=1e-12)


def test_the_inverted_index_scores_only_images_sharing_a_word() -> None:
    database = ImageDatabase(vocabulary(10), RetrievalConfig())
    for words in ([0, 1], [2, 3], [4, 5], [1, 4]):
        database.add(words, [0.0, 0.0], label=1)
    images, _ = database.cosines(word_counts([1, 9], database.vocabulary))
    np.testing.assert_array_equal(images, [0, 3])
    images, cosine = database.cosines(word_counts([9], database.vocabulary))
    assert len(images) == 0 and len(cosine) == 0


def test_images_are_counted_by_label() -> None:
    database = ImageDatabase(vocabulary(10), RetrievalConfig())
    for label in (1, -1, 1, 1):
        database.add([0, 1], [0.0, 0.0], label=label)
    assert (database.count(1), database.count(-1), database.count(2)) == (3, 1, 0)
    database.clear()
    assert database.count(1) == 0


def test_a_single_image_database_retrieves_nothing() -> None:
    """Every word of the only image is in every image: idf ln(1 / 1) = 0."""
    database = ImageDatabase(vocabulary(20), RetrievalConfig())
    database.add(np.arange(12), COLUMNS, label=1)
    _, cosine = database.cosines(word_counts(np.arange(12), database.vocabulary))
    np.testing.assert_array_equal(cosine, [0.0])
    assert database.query(np.arange(12), COLUMNS, rng()) == ()


def two_views() -> ImageDatabase:
    """Images 0 (words 0-11, label +1) and 1 (words 12-23, label -1) at COLUMNS."""
    database = ImageDatabase(vocabulary(30), RetrievalConfig())
    database.add(np.arange(12), COLUMNS, label=1)
    database.add(np.arange(12, 24), COLUMNS, label=-1)
    return database


def test_geometric_verification_accepts_a_shifted_copy() -> None:
    database = two_views()
    [hit] = database.query(np.arange(12), COLUMNS + 20.0, rng())
    assert (hit.image, hit.label, hit.inliers) == (0, 1, 12)
    assert hit.cosine == pytest.approx(1.0)
    assert hit.model.beta_s == pytest.approx(1.0)
    assert hit.model.beta_d == pytest.approx(20.0)


def test_geometric_verification_rejects_inconsistent_columns() -> None:
    """The same words at scrambled columns: cosine 1, but no line x_query = beta_s x_stored +
    beta_d with beta_s in [1/3, 3] holds 8 of the 12 pairs within 8 px (checked
    exhaustively over the lines through two pairs)."""
    scrambled = COLUMNS[SCRAMBLE]
    ransac = RansacConfig()
    most = 0
    for i, j in itertools.combinations(range(12), 2):
        beta_s = (scrambled[j] - scrambled[i]) / (COLUMNS[j] - COLUMNS[i])
        if ransac.min_scale <= beta_s <= ransac.max_scale:
            beta_d = scrambled[i] - beta_s * COLUMNS[i]
            residual = np.abs(scrambled - (beta_s * COLUMNS + beta_d))
            most = max(most, int((residual <= ransac.inlier_tolerance_px).sum()))
    assert most < RetrievalConfig().min_inliers
    database = two_views()
    _, cosine = database.cosines(word_counts(np.arange(12), database.vocabulary))
    assert cosine[0] == pytest.approx(1.0)
    for seed in range(5):
        assert database.query(np.arange(12), scrambled, np.random.default_rng(seed)) == ()


def test_a_repeated_word_counts_once_per_feature() -> None:
    """Word 0 at 4 columns 2 px apart in both images makes 16 pairs, all within 8 px of the
    identity line: 16 inlier pairs, but 4 matched features, too few for a hit of 8."""
    database = ImageDatabase(vocabulary(30), RetrievalConfig())
    words = np.array([0, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8])
    columns = np.array([10.0, 12.0, 14.0, 16.0, *COLUMNS[4:]])
    database.add(words, columns, label=1)
    database.add(np.arange(20, 30), COLUMNS[:10], label=-1)
    [hit] = database.query(words, columns, rng())
    assert hit.inliers == 12
    _, cosine = database.cosines(word_counts(words[:4], database.vocabulary))
    assert cosine[0] > RetrievalConfig().min_cosine
    assert database.query(words[:4], columns[:4], rng()) == ()  # the word-0 features alone


def test_hits_are_ranked_by_cosine_and_capped() -> None:
    config = RetrievalConfig(min_cosine=0.1, max_results=2)
    database = ImageDatabase(vocabulary(60), config)
    stored = [
        (np.arange(12), COLUMNS),  # all 12 words of the query
        (np.r_[np.arange(10), 40, 41], COLUMNS),  # 10 of them
        (np.r_[np.arange(9), 42, 43, 44], COLUMNS),  # 9 of them
        (np.arange(30, 42), COLUMNS),  # none
    ]
    for words, columns in stored:
        database.add(words, columns, label=1)
    hits = database.query(np.arange(12), COLUMNS, rng())
    assert [hit.image for hit in hits] == [0, 1]
    assert hits[0].cosine > hits[1].cosine
    uncapped = ImageDatabase(database.vocabulary, RetrievalConfig(min_cosine=0.1))
    for image in range(4):
        uncapped.add(*stored[image], label=1)
    hits = uncapped.query(np.arange(12), COLUMNS, rng())
    assert [hit.image for hit in hits] == [0, 1, 2]
    assert hits[1].cosine > hits[2].cosine > 0.1


def test_stopped_words_are_dropped_from_counts_and_verification() -> None:
    stopped_vocabulary = vocabulary(30, stopped=[0, 1, 2, 3, 4])
    np.testing.assert_array_equal(
        word_counts([0, 5, 5, 6], stopped_vocabulary)[:7], [0, 0, 0, 0, 0, 2, 1]
    )
    database = ImageDatabase(stopped_vocabulary, RetrievalConfig())
    database.add(np.arange(12), COLUMNS, label=1)  # 7 unstopped features
    database.add(np.arange(12, 24), COLUMNS, label=-1)
    assert database.query(np.arange(12), COLUMNS, rng()) == ()  # 7 < 8 matched features
    np.testing.assert_array_equal(database.document_frequency[:5], 0)


def test_query_expansion_sums_counts_but_verifies_this_frame() -> None:
    """The previous frame (image 1's words) lifts image 1's cosine, but this frame's features
    (image 0's words) share no word with image 1: only image 0 is a hit."""
    database = two_views()
    v = database.vocabulary
    counts = word_counts(np.arange(12), v) + word_counts(np.arange(12, 24), v)
    images, cosine = database.cosines(counts)
    np.testing.assert_array_equal(images, [0, 1])
    np.testing.assert_allclose(cosine, [1 / math.sqrt(2), 1 / math.sqrt(2)])
    hits = database.query(np.arange(12), COLUMNS, rng(), counts=counts)
    assert [hit.image for hit in hits] == [0]


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"min_cosine": 1.5}, "RetrievalConfig.min_cosine"),
        ({"min_inliers": 1}, "RetrievalConfig.min_inliers"),
        ({"min_inliers": 3, "ransac": RansacConfig(min_inliers=4)}, "RetrievalConfig.min_inliers"),
        ({"max_results": 0}, "RetrievalConfig.max_results"),
    ],
)
def test_bad_configs_are_named(kwargs: dict[str, object], field: str) -> None:
    with pytest.raises(ValueError, match=field):
        RetrievalConfig(**kwargs)  # type: ignore[arg-type]


def test_bad_inputs_are_refused() -> None:
    database = two_views()
    with pytest.raises(ValueError, match="words must be ids"):
        database.add([0, 30], [0.0, 1.0], label=1)
    with pytest.raises(ValueError, match="x must be finite"):
        database.add([0, 1], [0.0], label=1)
    with pytest.raises(ValueError, match="counts must be"):
        database.query([0], [0.0], rng(), counts=np.zeros(29, dtype=int))
    with pytest.raises(TypeError, match="label"):
        database.add([0], [0.0], label=1.0)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="rng"):
        database.query([0], [0.0], 0)  # type: ignore[arg-type]
