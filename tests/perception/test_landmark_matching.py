"""NN matching, recognition score and RANSAC of 1-D SURF features (seed 004 §3.2)."""

from __future__ import annotations

import numpy as np
import pytest

from perception.landmarks.matching import (
    Matches,
    MatchingConfig,
    RansacConfig,
    match_features,
    ransac_line,
)
from perception.landmarks.surf1d import Surf1dConfig, Surf1dFeatures, extract_features

MATCHING = MatchingConfig()
RANSAC = RansacConfig()


def horizon(x: np.ndarray, seed: int = 0) -> np.ndarray:
    """A smooth random signal: 30 Gaussian bumps of 1.5 to 6 samples on a level of 2000."""
    rng = np.random.default_rng(seed)
    centres, widths = rng.uniform(0, 400, 30), rng.uniform(1.5, 6.0, 30)
    heights = rng.uniform(-400.0, 400.0, 30)
    return 2000.0 + np.exp(-0.5 * ((x[:, None] - centres) / widths) ** 2) @ heights


def features(
    descriptors: np.ndarray | list[list[float]], signs: list[int] | None = None
) -> Surf1dFeatures:
    """Hand-made features at columns 0, 10, 20, ... with the given descriptors."""
    d = np.asarray(descriptors, dtype=np.float64)
    n = len(d)
    return Surf1dFeatures(
        index=np.arange(n, dtype=np.int64),
        x=np.arange(n, dtype=np.float64) * 10.0,
        scale=np.full(n, 1.2),
        filter_size=np.full(n, 9, dtype=np.int64),
        laplacian=np.asarray(signs if signs is not None else [1] * n, dtype=np.int8),
        response=np.ones(n),
        descriptors=d,
    )


def line_matches(
    stored_x: np.ndarray, test_x: np.ndarray, distance: np.ndarray | None = None
) -> Matches:
    """Matches of given columns, with descriptor distance 0.1 unless given."""
    m = len(stored_x)
    d = np.full(m, 0.1) if distance is None else distance
    return Matches(
        test_index=np.arange(m, dtype=np.int64),
        stored_index=np.arange(m, dtype=np.int64),
        test_x=np.asarray(test_x, dtype=np.float64),
        stored_x=np.asarray(stored_x, dtype=np.float64),
        distance=d,
        weight=1.0 / np.maximum(d, MATCHING.distance_floor),
    )


def outlier_scene(seed: int, outlier_fraction: float = 0.3):
    """40 matches on ``x_test = 1.2 x_stored - 30`` (+-1 px noise) with a fraction moved at
    least 40 px off the line; returns the matches and the true inlier mask."""
    rng = np.random.default_rng(seed)
    xs = rng.uniform(0.0, 320.0, 40)
    xt = 1.2 * xs - 30.0 + rng.uniform(-1.0, 1.0, 40)
    outlier = rng.random(40) < outlier_fraction
    xt[outlier] += rng.choice([-1.0, 1.0], outlier.sum()) * rng.uniform(40.0, 200.0, outlier.sum())
    return line_matches(xs, xt, rng.uniform(0.05, 0.5, 40)), ~outlier


# --- configuration -----------------------------------------------------------------------


@pytest.mark.parametrize(
    ("cls", "field", "value", "error"),
    [
        (MatchingConfig, "ratio", 0.0, ValueError),
        (MatchingConfig, "ratio", 1.5, ValueError),
        (MatchingConfig, "same_sign_only", 1, TypeError),
        (MatchingConfig, "distance_floor", 0.0, ValueError),
        (RansacConfig, "iterations", 0, ValueError),
        (RansacConfig, "iterations", 10.0, TypeError),
        (RansacConfig, "inlier_tolerance_px", -1.0, ValueError),
        (RansacConfig, "min_inliers", 1, ValueError),
        (RansacConfig, "min_scale", 0.0, ValueError),
        (RansacConfig, "max_scale", 0.2, ValueError),  # below min_scale 1/3
    ],
)
def test_configs_reject_bad_fields(cls: type, field: str, value: object, error: type) -> None:
    with pytest.raises(error, match=f"{cls.__name__}.{field}"):
        cls(**{field: value})


# --- NN matching -------------------------------------------------------------------------


def test_matching_a_set_to_itself_matches_everything() -> None:
    found = extract_features(horizon(np.arange(400.0)), Surf1dConfig())
    assert len(found) > 20
    matches = match_features(found, found, MATCHING)
    n = len(found)
    np.testing.assert_array_equal(matches.test_index, np.arange(n))
    np.testing.assert_array_equal(matches.stored_index, np.arange(n))
    np.testing.assert_array_equal(matches.test_x, matches.stored_x)
    assert matches.distance.max() == 0.0
    assert matches.score == pytest.approx(n / MATCHING.distance_floor)  # the floor, not inf


def test_shifted_view_matches_shifted_features() -> None:
    x = np.arange(400.0)
    stored = extract_features(horizon(x), Surf1dConfig(), columns=2 * np.arange(400))
    test = extract_features(horizon(x - 16), Surf1dConfig(), columns=2 * np.arange(400))
    matches = match_features(test, stored, MATCHING)
    assert len(matches) > 20
    moved = np.isclose(matches.test_x - matches.stored_x, 32.0)  # 16 samples of 2 px
    assert moved.mean() > 0.8
    result = ransac_line(matches, RANSAC, np.random.default_rng(0))
    assert result.model is not None
    assert result.model.beta_s == pytest.approx(1.0, abs=0.01)
    assert result.model.beta_d == pytest.approx(32.0, abs=1.0)
    assert result.inliers[moved].all()
    assert 0.0 < result.score <= matches.score


def test_ratio_test_rejects_ambiguous_nearest_neighbours() -> None:
    stored = features([[1, 0, 0, 0, 0, 0], [0.8, 0.6, 0, 0, 0, 0], [0, 0, 0, 0, 0, 1]])
    test = features([[0.9, 0.35, 0, 0, 0, 0], [0, 0, 0, 0, 0.1, 0.995]])
    matches = match_features(test, stored, MATCHING)
    # test 0 lies between stored 0 and 1 (distance ratio 0.74): rejected
    np.testing.assert_array_equal(matches.test_index, [1])
    np.testing.assert_array_equal(matches.stored_index, [2])
    expected = np.linalg.norm(test.descriptors[1] - stored.descriptors[2])
    assert matches.distance[0] == pytest.approx(expected)
    assert matches.score == pytest.approx(1.0 / expected)
    loose = match_features(test, stored, MatchingConfig(ratio=1.0))
    np.testing.assert_array_equal(loose.stored_index, [1, 2])


def test_same_sign_only_skips_opposite_laplacian() -> None:
    stored = features([[1, 0, 0, 0, 0, 0], [0.6, 0.8, 0, 0, 0, 0]], signs=[-1, 1])
    test = features([[0.99, 0.141, 0, 0, 0, 0]], signs=[1])
    assert match_features(test, stored, MATCHING).stored_index.tolist() == [0]
    signed = match_features(test, stored, MatchingConfig(same_sign_only=True))
    assert signed.stored_index.tolist() == [1]  # the only candidate of its sign


def test_empty_feature_sets_give_no_matches() -> None:
    empty = features(np.zeros((0, 6)))
    some = features([[1, 0, 0, 0, 0, 0]])
    for test, stored in ((empty, some), (some, empty), (empty, empty)):
        matches = match_features(test, stored, MATCHING)
        assert len(matches) == 0
        assert matches.score == 0.0


# --- RANSAC ------------------------------------------------------------------------------


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_ransac_recovers_line_despite_outliers(seed: int) -> None:
    matches, truth = outlier_scene(seed)
    result = ransac_line(matches, RANSAC, np.random.default_rng(seed))
    assert result.model is not None
    assert result.model.beta_s == pytest.approx(1.2, abs=0.01)
    assert result.model.beta_d == pytest.approx(-30.0, abs=1.5)
    np.testing.assert_array_equal(result.inliers, truth)
    assert result.score == pytest.approx(matches.weight[truth].sum())
    assert result.score < matches.score


def test_ransac_is_deterministic_for_a_seed() -> None:
    matches, _ = outlier_scene(5, outlier_fraction=0.5)
    config = RansacConfig(iterations=20)
    a = ransac_line(matches, config, np.random.default_rng(42))
    b = ransac_line(matches, config, np.random.default_rng(42))
    assert a.model == b.model
    np.testing.assert_array_equal(a.inliers, b.inliers)
    assert a.score == b.score


def test_ransac_without_consistent_matches_has_no_model() -> None:
    rng = np.random.default_rng(0)
    few = line_matches(np.array([10.0, 50.0]), np.array([12.0, 52.0]))
    result = ransac_line(few, RANSAC, rng)  # 2 < min_inliers 3
    assert result.model is None
    assert result.score == 0.0
    assert result.inliers.tolist() == [False, False]
    xs = np.linspace(0.0, 300.0, 10)
    mirrored = ransac_line(line_matches(xs, 320.0 - xs), RANSAC, rng)  # beta_s = -1
    assert mirrored.model is None
    same_column = ransac_line(line_matches(np.full(5, 40.0), np.arange(5.0)), RANSAC, rng)
    assert same_column.model is None


def test_ransac_requires_a_generator() -> None:
    matches, _ = outlier_scene(0)
    with pytest.raises(TypeError, match=r"rng must be a numpy\.random\.Generator"):
        ransac_line(matches, RANSAC, 0)  # type: ignore[arg-type]


def test_a_missing_config_or_features_is_a_type_error_naming_it() -> None:
    features = extract_features(np.sin(np.linspace(0, 20, 160)), Surf1dConfig())
    with pytest.raises(TypeError, match="config must be a Surf1dConfig, got NoneType"):
        extract_features(np.zeros(160), None)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="stored must be a Surf1dFeatures, got NoneType"):
        match_features(features, None, MatchingConfig())  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="config must be a MatchingConfig, got dict"):
        match_features(features, features, {})  # type: ignore[arg-type]
