"""Matching a circle map to the true circles (perception.metrics.match_circles) on hand-made
cases whose optimal one-to-one assignment is worked out by hand, and against a brute-force
search over every assignment."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from numpy.typing import ArrayLike

from perception.metrics import CircleMatch, match_circles

TRUTH = np.array([[0.0, 0.0, 0.2], [3.0, 0.0, 0.3], [0.0, 4.0, 0.1]])  # (x, y, R) (m)
GATE_M = 0.5


def test_a_perfect_map_matches_every_circle_exactly() -> None:
    mapped = TRUTH[[2, 0, 1]]  # the same circles in another order
    match = match_circles(mapped, TRUTH, GATE_M)
    assert isinstance(match, CircleMatch)
    np.testing.assert_array_equal(match.mapped_index, [1, 2, 0])
    np.testing.assert_array_equal(match.centre_error_m, [0.0, 0.0, 0.0])
    np.testing.assert_array_equal(match.radius_error_m, [0.0, 0.0, 0.0])
    np.testing.assert_array_equal(match.spurious, [False, False, False])
    np.testing.assert_array_equal(match.missed, [False, False, False])


def test_errors_are_the_centre_distance_and_the_absolute_radius_difference() -> None:
    # offsets of a 3-4-5 triangle: centre errors 0.05 and 0.25 m
    mapped = np.array([[0.03, -0.04, 0.15], [3.15, 0.2, 0.42], [0.0, 4.0, 0.1]])
    match = match_circles(mapped, TRUTH, GATE_M)
    np.testing.assert_array_equal(match.mapped_index, [0, 1, 2])
    np.testing.assert_allclose(match.centre_error_m, [0.05, 0.25, 0.0], atol=1e-12)
    # 0.15 for 0.2 (too small) and 0.42 for 0.3 (too large): both errors positive
    np.testing.assert_allclose(match.radius_error_m, [0.05, 0.12, 0.0], atol=1e-12)


def test_a_missed_circle_has_no_match_and_nan_errors() -> None:
    mapped = np.array([[0.1, 0.0, 0.2], [0.0, 4.1, 0.1]])  # the circle at (3, 0) is missing
    match = match_circles(mapped, TRUTH, GATE_M)
    np.testing.assert_array_equal(match.mapped_index, [0, -1, 1])
    np.testing.assert_array_equal(match.missed, [False, True, False])
    assert math.isnan(match.centre_error_m[1]) and math.isnan(match.radius_error_m[1])
    np.testing.assert_allclose(match.centre_error_m[[0, 2]], [0.1, 0.1], atol=1e-12)
    np.testing.assert_array_equal(match.spurious, [False, False])


def test_a_spurious_circle_is_matched_to_nothing() -> None:
    mapped = np.vstack([TRUTH, [[6.0, 6.0, 0.2]]])
    match = match_circles(mapped, TRUTH, GATE_M)
    np.testing.assert_array_equal(match.mapped_index, [0, 1, 2])
    np.testing.assert_array_equal(match.spurious, [False, False, False, True])
    np.testing.assert_array_equal(match.missed, [False, False, False])


def test_two_mapped_circles_near_one_true_circle_match_it_once() -> None:
    truth = np.array([[1.0, 1.0, 0.2]])
    # both within the gate; the second lies nearer (0.05 m against 0.1 m)
    mapped = np.array([[1.1, 1.0, 0.2], [1.0, 0.95, 0.26]])
    match = match_circles(mapped, truth, GATE_M)
    np.testing.assert_array_equal(match.mapped_index, [1])
    np.testing.assert_allclose(match.centre_error_m, [0.05], atol=1e-12)
    np.testing.assert_allclose(match.radius_error_m, [0.06], atol=1e-12)
    np.testing.assert_array_equal(match.spurious, [True, False])


def test_the_optimal_assignment_beats_the_greedy_one_on_the_total_distance() -> None:
    # On a line: truth T1 at 0, T2 at 1; mapped A at 0.55, B at 1.6 (gate 2 m: all pairs in)
    # Greedy takes the nearest pair first, T2-A (0.45 m), leaving T1-B (1.6 m): 2.05 m.
    # The optimum is T1-A (0.55 m) + T2-B (0.6 m) = 1.15 m.
    truth = np.array([[0.0, 0.0, 0.1], [1.0, 0.0, 0.1]])
    mapped = np.array([[1.6, 0.0, 0.1], [0.55, 0.0, 0.1]])  # B, A
    match = match_circles(mapped, truth, 2.0)
    np.testing.assert_array_equal(match.mapped_index, [1, 0])  # T1-A, T2-B
    np.testing.assert_allclose(match.centre_error_m, [0.55, 0.6], atol=1e-12)
    np.testing.assert_array_equal(match.spurious, [False, False])


def test_the_optimal_assignment_keeps_both_pairs_inside_the_gate() -> None:
    # On a line: T1 at 0, T2 at 2.5; mapped A at 1, B at -2 (gate 3 m).
    # Greedy: T1-A (1 m) first, leaving T2-B at 4.5 m, outside the gate: T2 missed.
    # The optimum pairs T1-B (2 m) and T2-A (1.5 m): both inside.
    truth = np.array([[0.0, 0.0, 0.1], [2.5, 0.0, 0.1]])
    mapped = np.array([[1.0, 0.0, 0.1], [-2.0, 0.0, 0.1]])  # A, B
    match = match_circles(mapped, truth, 3.0)
    np.testing.assert_array_equal(match.mapped_index, [1, 0])
    np.testing.assert_allclose(match.centre_error_m, [2.0, 1.5], atol=1e-12)
    np.testing.assert_array_equal(match.missed, [False, False])
    np.testing.assert_array_equal(match.spurious, [False, False])


def test_the_gate_is_strict() -> None:
    truth = np.array([[0.0, 0.0, 0.2]])
    mapped = np.array([[0.5, 0.0, 0.2]])  # exactly 0.5 m off
    assert match_circles(mapped, truth, 0.5).mapped_index.tolist() == [-1]
    assert match_circles(mapped, truth, 0.5).spurious.tolist() == [True]
    assert match_circles(mapped, truth, 0.5 + 1e-9).mapped_index.tolist() == [0]


def test_a_far_mapped_circle_is_not_matched_even_alone() -> None:
    match = match_circles([[5.0, 5.0, 0.2]], [[0.0, 0.0, 0.2]], GATE_M)
    np.testing.assert_array_equal(match.mapped_index, [-1])
    np.testing.assert_array_equal(match.spurious, [True])
    assert np.isnan(match.centre_error_m).all() and np.isnan(match.radius_error_m).all()


def test_an_empty_map_misses_every_true_circle() -> None:
    empties: tuple[ArrayLike, ...] = (np.zeros((0, 3)), [])
    for empty in empties:
        match = match_circles(empty, TRUTH, GATE_M)
        np.testing.assert_array_equal(match.mapped_index, [-1, -1, -1])
        np.testing.assert_array_equal(match.missed, [True, True, True])
        assert np.isnan(match.centre_error_m).all() and np.isnan(match.radius_error_m).all()
        assert match.spurious.shape == (0,)


def test_a_map_of_nothing_true_is_all_spurious() -> None:
    match = match_circles(TRUTH, np.zeros((0, 3)), GATE_M)
    assert match.mapped_index.shape == (0,)
    assert match.centre_error_m.shape == (0,) and match.radius_error_m.shape == (0,)
    np.testing.assert_array_equal(match.spurious, [True, True, True])
    both = match_circles([], [], GATE_M)
    assert both.mapped_index.shape == (0,) and both.spurious.shape == (0,)


def test_a_single_circle_may_be_given_flat() -> None:
    match = match_circles([0.1, 0.0, 0.25], [0.0, 0.0, 0.2], GATE_M)
    np.testing.assert_array_equal(match.mapped_index, [0])
    np.testing.assert_allclose(match.centre_error_m, [0.1], atol=1e-12)
    np.testing.assert_allclose(match.radius_error_m, [0.05], atol=1e-12)


def best_by_brute_force(mapped: np.ndarray, truth: np.ndarray, gate: float) -> tuple[int, float]:
    """The most pairs closer than ``gate`` of any one-to-one assignment, and the least sum of
    their centre distances among assignments with that many: every partial injection tried."""
    best = (0, 0.0)
    for k in range(1, min(len(mapped), len(truth)) + 1):
        for rows in itertools.combinations(range(len(truth)), k):
            for cols in itertools.permutations(range(len(mapped)), k):
                d = [
                    math.dist(truth[r, :2], mapped[c, :2]) for r, c in zip(rows, cols, strict=True)
                ]
                if max(d) < gate and (k > best[0] or sum(d) < best[1]):
                    best = (k, sum(d))
    return best


@pytest.mark.parametrize("seed", range(12))
def test_the_assignment_is_the_brute_force_optimum(seed: int) -> None:
    rng = np.random.default_rng(seed)
    truth = np.column_stack([rng.uniform(0, 2, (4, 2)), rng.uniform(0.1, 0.3, 4)])
    n_mapped = int(rng.integers(1, 5))
    mapped = np.column_stack([rng.uniform(0, 2, (n_mapped, 2)), rng.uniform(0.1, 0.3, n_mapped)])
    gate = 0.8
    match = match_circles(mapped, truth, gate)
    pairs, total = best_by_brute_force(mapped, truth, gate)
    found = match.mapped_index >= 0
    assert found.sum() == pairs
    assert float(np.sum(match.centre_error_m[found])) == pytest.approx(total, abs=1e-12)
    # one to one, each within the gate, errors as the geometry says
    matched = match.mapped_index[found]
    assert len(set(matched.tolist())) == len(matched)
    expected = np.hypot(*(truth[found, :2] - mapped[matched, :2]).T)
    np.testing.assert_allclose(match.centre_error_m[found], expected, rtol=1e-12)
    assert np.all(match.centre_error_m[found] < gate)
    np.testing.assert_allclose(
        match.radius_error_m[found], np.abs(truth[found, 2] - mapped[matched, 2]), rtol=1e-12
    )
    spurious = np.ones(n_mapped, dtype=bool)
    spurious[matched] = False
    np.testing.assert_array_equal(match.spurious, spurious)
