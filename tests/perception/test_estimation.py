"""The estimation kernel against independent truths: hand-computed scalar Kalman steps, the
textbook forms of the update written out here, closed-form chi-square quantiles and brute-force
optimal assignments."""

from __future__ import annotations

import functools
import itertools
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.stats import norm

from perception.estimation import (
    chi2_threshold,
    global_nearest_neighbour,
    innovation_covariance,
    joseph_update,
    mahalanobis_cost_matrix,
    mahalanobis_squared,
    predict,
    within_gate,
    wrapped_residual,
)
from perception.geometry import FloatArray

SEEDS = st.integers(0, 2**32 - 1)


def _spd(rng: np.random.Generator, n: int) -> FloatArray:
    """A random symmetric positive definite (n, n) matrix."""
    A = rng.normal(size=(n, n))
    return A @ A.T + 0.1 * np.eye(n)


def _problem(
    seed: int, n: int, m: int
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
    """A random x (n,), P (n, n), y (m,), dense H (m, n) and R (m, m)."""
    rng = np.random.default_rng(seed)
    x, P, y, H = rng.normal(size=n), _spd(rng, n), rng.normal(size=m), rng.normal(size=(m, n))
    return x, P, y, H, _spd(rng, m)


# --- kalman -------------------------------------------------------------------------------------


def test_scalar_predict_by_hand() -> None:
    # x = 2, P = 3, F = 1.5, Q = 0.5: F x = 3, F P F + Q = 1.5 * 3 * 1.5 + 0.5 = 7.25
    x, P = predict([2.0], [[3.0]], [[1.5]], [[0.5]])
    np.testing.assert_allclose(x, [3.0], rtol=1e-15)
    np.testing.assert_allclose(P, [[7.25]], rtol=1e-15)


def test_scalar_update_by_hand() -> None:
    # x = 1, P = 2, H = 2, R = 1, z = 5: y = 5 - 2 = 3, S = 2 * 2 * 2 + 1 = 9, K = 2 * 2 / 9 =
    # 4/9, x + K y = 1 + 4/3 = 7/3, P (1 - K H) = 2 / 9 (Joseph: 2 (1/9)² + (4/9)² = 2/9).
    y = np.array([5.0 - 2.0])
    S = innovation_covariance([[2.0]], [[2.0]], [[1.0]])
    np.testing.assert_allclose(S, [[9.0]], rtol=1e-15)
    x, P = joseph_update([1.0], [[2.0]], y, [[2.0]], [[1.0]])
    np.testing.assert_allclose(x, [7.0 / 3.0], rtol=1e-15)
    np.testing.assert_allclose(P, [[2.0 / 9.0]], rtol=1e-14)


def test_predict_of_a_constant_velocity_model() -> None:
    # position 1 m, velocity 2 m/s, dt 0.5 s: position 2 m; P = F P F^T + Q written out
    dt = 0.5
    F = np.array([[1.0, dt], [0.0, 1.0]])
    P0 = np.array([[0.3, 0.1], [0.1, 0.2]])
    Q = np.diag([0.01, 0.02])
    x, P = predict([1.0, 2.0], P0, F, Q)
    np.testing.assert_allclose(x, [2.0, 2.0])
    p00 = 0.3 + 2 * dt * 0.1 + dt**2 * 0.2 + 0.01
    p01 = 0.1 + dt * 0.2
    np.testing.assert_allclose(P, [[p00, p01], [p01, 0.2 + 0.02]], rtol=1e-14)
    np.testing.assert_array_equal(P, P.T)


@settings(max_examples=60, deadline=None)
@given(seed=SEEDS, n=st.integers(1, 7), m=st.integers(1, 3))
def test_joseph_update_is_the_textbook_update(seed: int, n: int, m: int) -> None:
    x0, P0, y, H, R = _problem(seed, n, m)
    x, P = joseph_update(x0, P0, y, H, R)
    S = H @ P0 @ H.T + R
    K = P0 @ H.T @ np.linalg.inv(S)
    I_KH = np.eye(n) - K @ H
    np.testing.assert_allclose(x, x0 + K @ y, rtol=1e-9, atol=1e-9)
    # with the optimal gain the Joseph form equals the short form (I - K H) P ...
    np.testing.assert_allclose(P, I_KH @ P0, rtol=1e-8, atol=1e-9)
    # ... and is the Joseph form written out
    np.testing.assert_allclose(P, I_KH @ P0 @ I_KH.T + K @ R @ K.T, rtol=1e-8, atol=1e-9)
    np.testing.assert_array_equal(P, P.T)
    assert np.linalg.eigvalsh(P).min() >= -1e-9 * np.abs(P).max()
    # information is gained, never lost: P0 - P is PSD
    assert np.linalg.eigvalsh(P0 - P).min() >= -1e-9 * np.abs(P0).max()


@settings(max_examples=60, deadline=None)
@given(seed=SEEDS, n=st.integers(1, 9), m=st.integers(1, 3), data=st.data())
def test_sparse_index_update_equals_the_zero_padded_dense_one(
    seed: int, n: int, m: int, data: st.DataObject
) -> None:
    x0, P0, y, _, R = _problem(seed, n, m)
    index = np.array(data.draw(st.permutations(range(n)))[: data.draw(st.integers(1, n))])
    H_block = np.random.default_rng(seed + 1).normal(size=(m, len(index)))
    H = np.zeros((m, n))
    H[:, index] = H_block
    np.testing.assert_allclose(
        innovation_covariance(P0, H_block, R, index), innovation_covariance(P0, H, R), rtol=1e-12
    )
    x_sparse, P_sparse = joseph_update(x0, P0, y, H_block, R, index)
    x_dense, P_dense = joseph_update(x0, P0, y, H, R)
    np.testing.assert_allclose(x_sparse, x_dense, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(P_sparse, P_dense, rtol=1e-10, atol=1e-12)


def test_a_given_innovation_covariance_is_used() -> None:
    x0, P0, y, H, R = _problem(3, 4, 2)
    S = innovation_covariance(P0, H, R)
    for a, b in zip(
        joseph_update(x0, P0, y, H, R, S=S), joseph_update(x0, P0, y, H, R), strict=True
    ):
        np.testing.assert_array_equal(a, b)
    # the gain is taken from the S given, not recomputed
    S_wide = S + 10.0 * np.eye(2)
    x_wide, _ = joseph_update(x0, P0, y, H, R, S=S_wide)
    np.testing.assert_allclose(x_wide, x0 + P0 @ H.T @ np.linalg.solve(S_wide, y), rtol=1e-12)


def test_the_inputs_are_not_modified() -> None:
    x0, P0, y, H, R = _problem(4, 5, 2)
    copies = [a.copy() for a in (x0, P0, y, H, R)]
    joseph_update(x0, P0, y, H[:, :3], R, [0, 2, 4])
    predict(x0, P0, np.eye(5), P0)
    for a, b in zip((x0, P0, y, H, R), copies, strict=True):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("name", ["x", "P", "F", "Q"])
def test_predict_refuses_a_nan_naming_the_argument(name: str) -> None:
    args = {"x": np.zeros(2), "P": np.eye(2), "F": np.eye(2), "Q": np.eye(2)}
    args[name] = np.full_like(args[name], np.nan)
    with pytest.raises(ValueError, match=f"{name} must be finite"):
        predict(**args)


def test_wrapped_residual_wraps_only_the_angles() -> None:
    z = np.array([1.0, math.pi - 0.1])
    z_hat = np.array([0.5, -math.pi + 0.1])
    np.testing.assert_allclose(wrapped_residual(z, z_hat, (1,)), [0.5, -0.2], atol=1e-12)
    np.testing.assert_allclose(wrapped_residual(z, z_hat, ()), [0.5, 2 * math.pi - 0.2])
    # broadcasts: (3, 2) measurements against one prediction
    Z = np.array([[1.0, 3.0], [2.0, -3.0], [0.0, 0.0]])
    y = wrapped_residual(Z, [0.0, 3.1], (1,))
    np.testing.assert_allclose(y[:, 0], Z[:, 0])
    np.testing.assert_allclose(y[:, 1], [-0.1, 2 * math.pi - 6.1, -3.1], atol=1e-12)
    with pytest.raises(ValueError, match=r"^z must be finite"):
        wrapped_residual([math.nan, 1.0], [0.0, 0.0], (1,))
    with pytest.raises(ValueError, match=r"^z_hat must be finite"):
        wrapped_residual([0.0, 1.0], [0.0, math.inf], (1,))


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"y": [1.0]}, r"y must have shape \(2,\)"),
        ({"y": [np.nan, 0.0]}, "y must be finite"),
        ({"H": np.ones((2, 3))}, r"H must have shape \(2, 4\)"),
        ({"R": np.eye(3)}, r"R must have shape \(2, 2\)"),
        ({"P": np.eye(3)}, r"P must have shape \(4, 4\)"),
        ({"x": np.zeros((4, 1))}, r"x must have shape \(n,\)"),
        ({"S": [[1.0, 0.5], [0.0, 1.0]]}, "S must be symmetric"),
        ({"S": [[1.0, 0.0], [0.0, -1.0]]}, "S must be positive definite"),
        ({"S": np.eye(3)}, r"S must be a finite \(2, 2\) array"),
        ({"H": np.ones((2, 2)), "index": [0, 4]}, r"index must hold distinct state indices"),
        ({"H": np.ones((2, 2)), "index": [1, 1]}, r"index must hold distinct state indices"),
        ({"H": np.ones((2, 2)), "index": [-1, 1]}, r"index must hold distinct state indices"),
        ({"H": np.ones((2, 2)), "index": [0, 1, 2]}, "index must be 2 ints"),
        ({"H": np.ones((2, 2)), "index": [0.0, 1.0]}, "index must be 2 ints"),
        ({"x": [np.nan, 0.0, 0.0, 0.0]}, "x must be finite"),
        ({"P": np.full((4, 4), np.inf)}, "P must be finite"),
        ({"H": np.full((2, 4), np.nan)}, "H must be finite"),
        ({"R": -0.1 * np.eye(2)}, "R must be positive semidefinite"),
        ({"R": [[1.0, 0.5], [0.0, 1.0]]}, "R must be symmetric"),
    ],
)
def test_bad_update_input_raises_naming_the_argument(kwargs: dict[str, object], match: str) -> None:
    args: dict[str, object] = {
        "x": np.zeros(4),
        "P": np.eye(4),
        "y": np.zeros(2),
        "H": np.ones((2, 4)),
        "R": np.eye(2),
    }
    with pytest.raises(ValueError, match=match):
        joseph_update(**{**args, **kwargs})  # type: ignore[arg-type]


def test_bad_predict_input_raises_naming_the_argument() -> None:
    with pytest.raises(ValueError, match=r"F must have shape \(2, 2\)"):
        predict(np.zeros(2), np.eye(2), np.eye(3), np.eye(2))
    with pytest.raises(ValueError, match=r"Q must have shape \(2, 2\)"):
        predict(np.zeros(2), np.eye(2), np.eye(2), np.eye(1))


# --- gating -------------------------------------------------------------------------------------


@pytest.mark.parametrize("p", [1e-6, 0.1, 0.5, 0.9, 0.95, 0.99, 0.999999])
def test_chi2_threshold_closed_forms(p: float) -> None:
    assert chi2_threshold(p, 2) == pytest.approx(-2.0 * math.log(1.0 - p), rel=1e-12)
    assert chi2_threshold(p, 1) == pytest.approx(norm.ppf((1.0 + p) / 2.0) ** 2, rel=1e-9)


def test_chi2_threshold_grows_with_the_degrees_of_freedom() -> None:
    thresholds = [chi2_threshold(0.99, dof) for dof in range(1, 8)]
    assert thresholds == sorted(thresholds)
    assert chi2_threshold(0.5, 100) == pytest.approx(99.33, abs=0.01)  # median ~ k (1 - 2/9k)^3


@pytest.mark.parametrize(
    ("probability", "dof", "error", "match"),
    [
        (0.0, 2, ValueError, r"probability must be finite and in \(0, 1\), got 0.0"),
        (1.0, 2, ValueError, "probability must be"),
        (math.nan, 2, ValueError, "probability must be"),
        (-0.5, 2, ValueError, "probability must be"),
        ("0.9", 2, TypeError, "probability must be a real number, got str"),
        (True, 2, TypeError, "probability must be a real number, got bool"),
        (0.9, 0, ValueError, "dof must be an int >= 1, got 0"),
        (0.9, 1.5, TypeError, "dof must be an int >= 1, got float"),
        (0.9, True, TypeError, "dof must be an int"),
    ],
)
def test_chi2_threshold_rejects_bad_input(
    probability: object, dof: object, error: type[Exception], match: str
) -> None:
    with pytest.raises(error, match=match):
        chi2_threshold(probability, dof)  # type: ignore[arg-type]


def test_mahalanobis_squared_by_hand() -> None:
    # S^-1 = [[2, -1], [-1, 2]] / 3, so y = (1, 1) gives (2 - 1 - 1 + 2) / 3 = 2/3
    S = np.array([[2.0, 1.0], [1.0, 2.0]])
    assert float(mahalanobis_squared([1.0, 1.0], S)) == pytest.approx(2.0 / 3.0, rel=1e-15)
    # several innovations against one S: (N, m) -> (N,)
    Y = np.array([[1.0, 1.0], [1.0, -1.0], [0.0, 0.0]])
    np.testing.assert_allclose(mahalanobis_squared(Y, S), [2.0 / 3.0, 2.0, 0.0], rtol=1e-15)
    assert mahalanobis_squared(np.zeros((0, 2)), S).shape == (0,)


@pytest.mark.parametrize("scale", [1.0 - 1e-9, 1.0 + 1e-9])
def test_gate_boundary(scale: float) -> None:
    threshold = chi2_threshold(0.99, 2)
    S = np.diag([4.0, 9.0])
    # y = (2 a, 3 b) has y^T S^-1 y = a² + b²: put it on the circle of radius^2 = threshold
    angle = 0.3
    radius = math.sqrt(threshold * scale)
    y = np.array([2.0 * radius * math.cos(angle), 3.0 * radius * math.sin(angle)])
    assert within_gate(y, S, threshold) == (scale < 1.0)


def test_gate_threshold_is_inclusive() -> None:
    assert within_gate([2.0, 0.0], np.diag([4.0, 1.0]), 1.0)  # y^T S^-1 y = 1 exactly
    assert not within_gate([2.0, 0.0], np.diag([4.0, 1.0]), math.nextafter(1.0, 0.0))


@pytest.mark.parametrize(
    ("y", "S", "threshold", "error", "match"),
    [
        ([np.nan, 0.0], np.eye(2), 1.0, ValueError, "y must be finite"),
        ([1.0, 0.0], [[1.0, 0.2], [0.0, 1.0]], 1.0, ValueError, "S must be symmetric"),
        ([1.0, 0.0], [[1.0, 2.0], [2.0, 1.0]], 1.0, ValueError, "S must be positive definite"),
        ([1.0, 0.0], np.eye(3), 1.0, ValueError, r"S must be a finite \(2, 2\) array"),
        ([1.0, 0.0, 0.0], np.diag([1.0, 1.0, -1.0]), 1.0, ValueError, "S must be positive"),
        ([[1.0, 0.0]], np.eye(2), 1.0, ValueError, r"y must have shape \(m,\)"),
        ([1.0, 0.0], np.eye(2), -1.0, ValueError, r"threshold must be finite and in \[0, inf\)"),
        ([1.0, 0.0], np.eye(2), math.inf, ValueError, "threshold must be finite"),
        ([1.0, 0.0], np.eye(2), "9", TypeError, "threshold must be a real number"),
        ([1.0, 0.0], "S", 1.0, TypeError, r"S must be a \(2, 2\) array"),
    ],
)
def test_bad_gate_input_raises_naming_the_argument(
    y: object, S: object, threshold: object, error: type[Exception], match: str
) -> None:
    with pytest.raises(error, match=match):
        within_gate(y, S, threshold)  # type: ignore[arg-type]


def test_mahalanobis_squared_rejects_a_scalar() -> None:
    with pytest.raises(ValueError, match="y must have shape"):
        mahalanobis_squared(1.0, np.eye(1))


# --- association --------------------------------------------------------------------------------


def _pairs(cost: FloatArray, threshold: float) -> set[tuple[int, int]]:
    return {(int(t), int(j)) for t, j in global_nearest_neighbour(cost, threshold).matches}


def test_association_beats_greedy_nearest_neighbour() -> None:
    # Greedy: track 0 takes its nearest, measurement 0 (cost 1), leaving track 1 measurement 1
    # (cost 100): total 101. The optimal assignment crosses over: 2 + 2 = 4.
    cost = np.array([[1.0, 2.0], [2.0, 100.0]])
    result = global_nearest_neighbour(cost, 1000.0)
    np.testing.assert_array_equal(result.matches, [[0, 1], [1, 0]])
    assert result.unmatched_tracks.size == 0
    assert result.unmatched_measurements.size == 0


def test_association_prefers_more_in_gate_pairs() -> None:
    cost = np.array([[1.0, 3.0], [9.0, 50.0]])
    # gate 10: (0, 1) + (1, 0) pairs both tracks; (0, 0) alone would leave track 1 unpaired
    assert _pairs(cost, 10.0) == {(0, 1), (1, 0)}
    # gate 5: track 1 has no measurement in its gate; track 0 takes its cheapest
    result = global_nearest_neighbour(cost, 5.0)
    np.testing.assert_array_equal(result.matches, [[0, 0]])
    np.testing.assert_array_equal(result.unmatched_tracks, [1])
    np.testing.assert_array_equal(result.unmatched_measurements, [1])


def test_out_of_gate_and_infinite_pairs_are_never_matched() -> None:
    cost = np.array([[20.0, math.inf, 0.5], [30.0, 40.0, math.inf], [math.inf, 0.1, 9.0]])
    result = global_nearest_neighbour(cost, 10.0)
    np.testing.assert_array_equal(result.matches, [[0, 2], [2, 1]])
    np.testing.assert_array_equal(result.unmatched_tracks, [1])
    np.testing.assert_array_equal(result.unmatched_measurements, [0])
    empty = global_nearest_neighbour(np.full((2, 3), 11.0), 10.0)
    assert empty.matches.shape == (0, 2)
    np.testing.assert_array_equal(empty.unmatched_tracks, [0, 1])
    np.testing.assert_array_equal(empty.unmatched_measurements, [0, 1, 2])


@pytest.mark.parametrize("shape", [(0, 3), (2, 0), (0, 0)])
def test_association_of_empty_inputs(shape: tuple[int, int]) -> None:
    result = global_nearest_neighbour(np.zeros(shape), 5.0)
    assert result.matches.shape == (0, 2)
    np.testing.assert_array_equal(result.unmatched_tracks, np.arange(shape[0]))
    np.testing.assert_array_equal(result.unmatched_measurements, np.arange(shape[1]))


def _brute_force(cost: FloatArray, threshold: float) -> tuple[int, float]:
    """Most in-gate pairs of any one-to-one pairing, and the least total cost among those."""
    n_tracks, n_meas = cost.shape
    best = (0, -0.0)  # (pairs, -total cost): the lexicographic maximum is the best pairing
    for k in range(1, min(n_tracks, n_meas) + 1):
        for tracks in itertools.combinations(range(n_tracks), k):
            for meas in itertools.permutations(range(n_meas), k):
                costs = [cost[t, j] for t, j in zip(tracks, meas, strict=True)]
                if all(c <= threshold for c in costs):
                    best = max(best, (k, -sum(costs)))
    return best[0], -best[1]


@settings(max_examples=80, deadline=None)
@given(
    seed=SEEDS,
    n_tracks=st.integers(0, 4),
    n_meas=st.integers(0, 4),
    threshold=st.floats(0.0, 12.0),
)
def test_association_is_optimal_one_to_one_and_gated(
    seed: int, n_tracks: int, n_meas: int, threshold: float
) -> None:
    rng = np.random.default_rng(seed)
    cost = rng.chisquare(2, size=(n_tracks, n_meas)) * rng.uniform(0.5, 3.0)
    result = global_nearest_neighbour(cost, threshold)
    tracks, meas = result.matches.T
    assert len(set(tracks)) == len(tracks) and len(set(meas)) == len(meas)
    assert all(cost[t, j] <= threshold for t, j in result.matches)
    assert sorted([*tracks, *result.unmatched_tracks]) == list(range(n_tracks))
    assert sorted([*meas, *result.unmatched_measurements]) == list(range(n_meas))
    count, total = _brute_force(cost, threshold)
    assert len(result.matches) == count
    assert cost[tracks, meas].sum() == pytest.approx(total, rel=1e-12, abs=1e-12)


@pytest.mark.parametrize(
    ("cost", "threshold", "error", "match"),
    [
        ([[1.0, math.nan]], 5.0, ValueError, "cost must hold squared distances"),
        ([[1.0, -1.0]], 5.0, ValueError, "cost must hold squared distances"),
        ([1.0, 2.0], 5.0, ValueError, r"cost must be a \(tracks, measurements\) matrix"),
        ([[1.0]], -1.0, ValueError, "threshold must be"),
        ([[1.0]], math.nan, ValueError, "threshold must be"),
        ([[1.0]], None, TypeError, "threshold must be a real number"),
    ],
)
def test_bad_association_input_raises(
    cost: object, threshold: object, error: type[Exception], match: str
) -> None:
    with pytest.raises(error, match=match):
        global_nearest_neighbour(cost, threshold)  # type: ignore[arg-type]


def test_cost_matrix_is_the_mahalanobis_distance_of_each_pair() -> None:
    rng = np.random.default_rng(7)
    z_hat = rng.normal(size=(3, 2))
    S = np.stack([_spd(rng, 2) for _ in range(3)])
    z = rng.normal(size=(4, 2))
    cost = mahalanobis_cost_matrix(z_hat, S, z)
    assert cost.shape == (3, 4)
    for t, j in itertools.product(range(3), range(4)):
        y = z[j] - z_hat[t]
        assert cost[t, j] == pytest.approx(y @ np.linalg.inv(S[t]) @ y, rel=1e-12)


def test_cost_matrix_with_a_wrapped_bearing() -> None:
    # a (range, bearing) track behind the robot at bearing ~pi and a measurement at ~-pi
    z_hat = np.array([[2.0, math.pi - 0.01]])
    S = np.diag([0.01, 0.01])[None]
    z = np.array([[2.0, -math.pi + 0.01]])
    residual = functools.partial(wrapped_residual, angles=(1,))
    wrapped = mahalanobis_cost_matrix(z_hat, S, z, residual)
    assert wrapped[0, 0] == pytest.approx(0.02**2 / 0.01, rel=1e-9)
    assert mahalanobis_cost_matrix(z_hat, S, z)[0, 0] > 3000.0  # without wrapping: 2 pi apart
    assert _pairs(wrapped, chi2_threshold(0.99, 2)) == {(0, 0)}


@pytest.mark.parametrize(("n_tracks", "n_meas"), [(0, 3), (2, 0), (0, 0)])
def test_cost_matrix_of_empty_inputs(n_tracks: int, n_meas: int) -> None:
    cost = mahalanobis_cost_matrix(
        np.zeros((n_tracks, 2)), np.tile(np.eye(2), (n_tracks, 1, 1)), np.zeros((n_meas, 2))
    )
    assert cost.shape == (n_tracks, n_meas)
    assert global_nearest_neighbour(cost, 1.0).matches.shape == (0, 2)
    if n_tracks == 0:  # no tracks may come as plain empty lists too
        assert mahalanobis_cost_matrix([], [], np.zeros((n_meas, 2))).shape == (0, n_meas)


@pytest.mark.parametrize(
    ("z_hat", "S", "z", "match"),
    [
        (np.zeros((2, 2)), np.tile(np.eye(2), (2, 1, 1)), np.zeros(2), r"z must have shape"),
        (np.zeros((2, 3)), np.tile(np.eye(2), (2, 1, 1)), np.zeros((1, 2)), "z_hat must have"),
        (np.zeros((2, 2)), np.tile(np.eye(2), (3, 1, 1)), np.zeros((1, 2)), "z_hat must have"),
        (np.zeros((1, 2)), [[[1.0, 0.5], [0.0, 1.0]]], np.zeros((1, 2)), "S must be symmetric"),
        (np.zeros((1, 2)), np.eye(2)[None], [[np.nan, 0.0]], "y must be finite"),
    ],
)
def test_bad_cost_matrix_input_raises(z_hat: object, S: object, z: object, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        mahalanobis_cost_matrix(z_hat, S, z)  # type: ignore[arg-type]
