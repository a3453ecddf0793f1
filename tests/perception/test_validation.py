"""The shared validators: what they accept, what they reject, and what their messages say."""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from perception.validation import (
    InvalidTypeError,
    check_bool,
    check_choice,
    check_covariance,
    check_finite,
    check_generator,
    check_in_interval,
    check_int,
    check_nested_configs,
    check_positive,
    check_probability,
    check_real,
    check_reals,
    check_rgb_image,
    finite_points,
    finite_vector,
    is_finite_real,
    real_array,
)

NOT_NUMBERS = [True, False, np.bool_(True), "1.0", None, [1.0], 1j]


def test_a_type_error_is_also_a_value_error() -> None:
    assert issubclass(InvalidTypeError, TypeError)
    assert issubclass(InvalidTypeError, ValueError)


@pytest.mark.parametrize("value", [0, 1.5, -2, np.float32(0.5), np.int64(3), np.float64(-1e300)])
def test_finite_reals(value: object) -> None:
    assert is_finite_real(value)
    check_finite("Config", "field", value)


@pytest.mark.parametrize("value", [math.nan, math.inf, -math.inf, *NOT_NUMBERS])
def test_not_finite_reals(value: object) -> None:
    assert not is_finite_real(value)


@pytest.mark.parametrize("value", [math.nan, math.inf, np.float64(-np.inf)])
def test_check_finite_message(value: object) -> None:
    expected = f"Config.field must be finite, got {value!r}"
    with pytest.raises(ValueError, match=f"^{re.escape(expected)}$"):
        check_finite("Config", "field", value)


@pytest.mark.parametrize("value", NOT_NUMBERS)
def test_wrong_types_raise_type_errors_naming_the_argument(value: object) -> None:
    kind = type(value).__name__
    for check in (check_finite, check_positive, check_probability):
        with pytest.raises(TypeError, match=rf"^Config\.field must be a real number, got {kind} "):
            check("Config", "field", value)
    with pytest.raises(TypeError, match=rf"^Config\.count must be an int, got {kind} "):
        check_int("Config", "count", value)


def test_the_message_of_the_brief() -> None:
    with pytest.raises(ValueError) as info:
        check_positive("EkfSlamConfig", "gate_range_m", -1)
    assert str(info.value) == "EkfSlamConfig.gate_range_m must be finite and in (0, inf), got -1"
    assert not isinstance(info.value, TypeError)


def test_without_an_owner_the_name_stands_alone() -> None:
    with pytest.raises(ValueError, match=r"^probability must be finite and in \(0, 1\), got 2$"):
        check_probability("", "probability", 2)


@pytest.mark.parametrize(
    ("kwargs", "good", "bad", "interval"),
    [
        ({}, [1e-300, 1, 5.0], [0, -1.0, math.inf, math.nan], "(0, inf)"),
        ({"allow_zero": True}, [0, 0.0, 2.0], [-1e-300, math.inf], "[0, inf)"),
        ({"upper": math.pi, "upper_inclusive": True}, [math.pi, 1.0], [3.2, 0.0], "(0, 3.14159]"),
        ({"upper": 1.0}, [0.5, 1 - 1e-16], [1.0, 1.5], "(0, 1)"),
    ],
)
def test_check_positive(
    kwargs: dict[str, object], good: list[float], bad: list[float], interval: str
) -> None:
    for value in good:
        check_positive("Config", "field", value, **kwargs)  # type: ignore[arg-type]
    for value in bad:
        expected = f"Config.field must be finite and in {interval}, got {value!r}"
        with pytest.raises(ValueError, match=f"^{re.escape(expected)}$"):
            check_positive("Config", "field", value, **kwargs)  # type: ignore[arg-type]


@given(
    value=st.floats(allow_nan=True, allow_infinity=True),
    low=st.floats(-10.0, 10.0),
    width=st.floats(0.0, 10.0),
    low_inclusive=st.booleans(),
    high_inclusive=st.booleans(),
)
def test_check_in_interval_agrees_with_the_definition(
    value: float, low: float, width: float, low_inclusive: bool, high_inclusive: bool
) -> None:
    high = low + width
    inside = (
        math.isfinite(value)
        and (low <= value if low_inclusive else low < value)
        and (value <= high if high_inclusive else value < high)
    )
    kwargs = {"low_inclusive": low_inclusive, "high_inclusive": high_inclusive}
    if inside:
        check_in_interval("Config", "field", value, low, high, **kwargs)
    else:
        with pytest.raises(ValueError, match=r"^Config\.field must be finite and in "):
            check_in_interval("Config", "field", value, low, high, **kwargs)


def test_float_only_refuses_ints() -> None:
    check_positive("Config", "field", np.float64(2.0), float_only=True)
    for value in (2, np.int64(2), np.float32(2.0)):
        with pytest.raises(InvalidTypeError, match=r"^Config\.field must be a float, got "):
            check_positive("Config", "field", value, float_only=True)
    with pytest.raises(InvalidTypeError, match="must be a float"):
        check_probability("Config", "field", 0, float_only=True)


@pytest.mark.parametrize("value", [1e-12, 0.5, 1 - 1e-12])
def test_probabilities(value: float) -> None:
    check_probability("Config", "p", value)


@pytest.mark.parametrize("value", [0, 0.0, 1.0, -0.1, 1.1, math.nan])
def test_not_probabilities(value: float) -> None:
    with pytest.raises(ValueError, match=r"^Config\.p must be finite and in \(0, 1\), got "):
        check_probability("Config", "p", value)


def test_check_int() -> None:
    for value in (1, np.int64(5), np.uint8(2), -3):
        check_int("Config", "n", value)
    check_int("Config", "n", 1, 1)
    check_int("Config", "n", None, 1, optional=True)
    with pytest.raises(ValueError, match=r"^Config\.n must be an int >= 1, got 0$"):
        check_int("Config", "n", 0, 1)
    with pytest.raises(ValueError, match=r"^Config\.n must be an int >= 1 or None, got -2$"):
        check_int("Config", "n", -2, 1, optional=True)
    with pytest.raises(TypeError, match=r"^Config\.n must be an int >= 2, got float 2\.0$"):
        check_int("Config", "n", 2.0, 2)
    with pytest.raises(TypeError, match=r"^Config\.n must be an int >= 1, got bool True$"):
        check_int("Config", "n", True, 1)
    with pytest.raises(TypeError, match=r"^Config\.n must be an int, got NoneType None$"):
        check_int("Config", "n", None)


def test_check_bool() -> None:
    check_bool("Config", "flag", False)
    for value in (1, 0, np.bool_(True), "True", None):
        with pytest.raises(TypeError, match=r"^Config\.flag must be a bool, got "):
            check_bool("Config", "flag", value)


def test_check_choice() -> None:
    choices = ("a", "b")
    check_choice("Config", "mode", "a", choices)
    check_choice("Config", "mode", None, choices, optional=True)
    with pytest.raises(ValueError, match=r"^Config\.mode must be one of \('a', 'b'\), got 'A'$"):
        check_choice("Config", "mode", "A", choices)
    with pytest.raises(TypeError, match=r"^Config\.mode must be a str, got NoneType None$"):
        check_choice("Config", "mode", None, choices)
    with pytest.raises(TypeError, match=r"^Config\.mode must be a str or None, got int 1$"):
        check_choice("Config", "mode", 1, ["a", "b"], optional=True)


def test_finite_points() -> None:
    source = [[0, 1], [2.5, -3]]
    points = finite_points(source, "p", 2)
    assert points.dtype == np.float64 and points.shape == (2, 2)
    np.testing.assert_array_equal(points, source)
    assert finite_points(np.zeros((0, 2)), "p").shape == (0, 2)
    with pytest.raises(
        ValueError, match=r"^p must have shape \(N, 2\) with N >= 3, got shape \(2, 2\)$"
    ):
        finite_points(source, "p", 3)
    with pytest.raises(
        ValueError, match=r"^p must have shape \(N, 2\) with N >= 0, got shape \(4,\)$"
    ):
        finite_points([1, 2, 3, 4], "p")
    with pytest.raises(
        ValueError, match=r"^p must be finite, got NaN or infinity in rows \[0, 2\]$"
    ):
        finite_points([[math.nan, 0], [1, 1], [2, math.inf]], "p")
    with pytest.raises(InvalidTypeError, match=r"^p must be an \(N, 2\) array of numbers"):
        finite_points([["a", "b"]], "p")


def test_finite_vector() -> None:
    source = [1, 2.5, -3]
    vector = finite_vector(source, "v", 3)
    assert vector.dtype == np.float64
    np.testing.assert_array_equal(vector, source)
    array = np.zeros(2)
    assert finite_vector(array, "v", 2) is not array  # a new array
    with pytest.raises(ValueError, match=r"^v must have shape \(3,\), got shape \(2,\)$"):
        finite_vector([1.0, 2.0], "v", 3)
    with pytest.raises(ValueError, match=r"^v must have shape \(2,\), got shape \(1, 2\)$"):
        finite_vector([[1.0, 2.0]], "v", 2)
    with pytest.raises(ValueError, match=r"^v must be finite"):
        finite_vector([1.0, math.inf], "v", 2)
    with pytest.raises(TypeError, match=r"^v must be 2 numbers, got 'ab'$"):
        finite_vector("ab", "v", 2)


@pytest.mark.parametrize("size", [1, 2, 3, 5])
def test_check_covariance_accepts_covariances(size: int) -> None:
    rng = np.random.default_rng(size)
    A = rng.normal(size=(size, size))
    C = A @ A.T + 1e-3 * np.eye(size)
    C[0, -1] *= 1 + 1e-12  # rounding-level asymmetry is tolerated
    checked = check_covariance(C.tolist(), "C", size)
    assert checked.dtype == np.float64
    np.testing.assert_array_equal(checked, C)


@pytest.mark.parametrize("size", [2, 3])
def test_check_covariance_rejects_what_is_not_one(size: int) -> None:
    eye = np.eye(size)
    asymmetric = eye.copy()
    asymmetric[0, 1] = 0.1
    indefinite = eye.copy()
    indefinite[-1, -1] = -1.0
    singular = eye.copy()
    singular[0, 0] = 0.0
    cases = [
        (asymmetric, "symmetric"),
        (indefinite, "positive definite"),
        (singular, "positive definite"),
        (np.where(eye > 0, math.nan, 0.0), rf"a finite \({size}, {size}\) array"),
        (np.eye(size + 1), rf"a finite \({size}, {size}\) array"),
        (np.ones(size), rf"a finite \({size}, {size}\) array"),
    ]
    for matrix, what in cases:
        with pytest.raises(ValueError, match=rf"^C must be {what}"):
            check_covariance(matrix, "C", size)
    with pytest.raises(TypeError, match=rf"^C must be a \({size}, {size}\) array, got 'x'$"):
        check_covariance("x", "C", size)


def test_semidefinite_2x2_check_agrees_with_the_eigenvalues() -> None:
    """The 2 x 2 semidefinite check (closed-form eigenvalues) against numpy's eigenvalues: it
    accepts what they call semidefinite, singular ones included, refuses the rest, and
    returns the matrix symmetrised."""
    rng = np.random.default_rng(5)
    for _ in range(2000):
        a, d = rng.uniform(-0.2, 1.0, size=2)
        b = rng.uniform(-1.0, 1.0) * math.sqrt(max(a * d, 0.0)) * rng.choice([0.5, 1.0, 1.2])
        C = np.array([[a, b], [b * (1 + 1e-12), d]])
        lowest = float(np.linalg.eigvalsh(0.5 * (C + C.T)).min())
        scale = float(np.abs(C).max())
        if lowest >= -1e-13 * scale:  # semidefinite within the documented 1e-12
            np.testing.assert_allclose(
                check_covariance(C, "C", 2, singular_ok=True), 0.5 * (C + C.T), rtol=0, atol=0
            )
        elif lowest < -1e-11 * scale:
            with pytest.raises(ValueError, match=r"^C must be positive semidefinite"):
                check_covariance(C, "C", 2, singular_ok=True)
    singular = np.array([[1.0, 2.0], [2.0, 4.0]])  # rank one
    np.testing.assert_array_equal(check_covariance(singular, "C", 2, singular_ok=True), singular)
    with pytest.raises(ValueError, match=r"^C must be symmetric"):
        check_covariance([[1.0, 0.1], [0.0, 1.0]], "C", 2, singular_ok=True)


def test_check_generator_takes_only_a_numpy_generator() -> None:
    check_generator("rng", np.random.default_rng(0))
    for bad in (np.random.RandomState(0), 0, None):
        with pytest.raises(InvalidTypeError, match=r"rng must be a numpy\.random\.Generator"):
            check_generator("rng", bad)


def test_check_rgb_image_accepts_the_frame_and_names_what_came() -> None:
    check_rgb_image(np.zeros((4, 6, 3), dtype=np.uint8), 4, 6)
    cases = [
        (np.zeros((6, 4, 3), dtype=np.uint8), r"got \(6, 4, 3\) uint8"),
        (np.zeros((4, 6, 3), dtype=np.float32), r"got \(4, 6, 3\) float32"),
        (np.zeros((4, 6), dtype=np.uint8), r"got \(4, 6\) uint8"),
        ([[0]], "got list"),
        (None, "got NoneType"),
    ]
    for image, got in cases:
        with pytest.raises(
            ValueError, match=r"frame must be a \(4, 6, 3\) uint8 RGB array, " + got
        ):
            check_rgb_image(image, 4, 6, "frame")


@dataclass(frozen=True)
class _Inner:
    size: float = 1.0


@dataclass(frozen=True)
class _Outer:
    inner: _Inner = field(default_factory=_Inner)
    maybe: _Inner | None = None
    label: str = "x"  # not a config: left alone


def test_nested_configs_must_be_of_their_declared_class() -> None:
    check_nested_configs(_Outer())
    check_nested_configs(_Outer(maybe=_Inner()))
    check_nested_configs(_Outer(label=None))  # type: ignore[arg-type]
    with pytest.raises(InvalidTypeError, match=r"^_Outer\.inner must be a _Inner, got NoneType$"):
        check_nested_configs(_Outer(inner=None))  # type: ignore[arg-type]
    with pytest.raises(
        InvalidTypeError, match=r"^_Outer\.maybe must be a _Inner or None, got str$"
    ):
        check_nested_configs(_Outer(maybe="bogus"))  # type: ignore[arg-type]


def test_check_reals_takes_a_tuple_or_list_of_finite_reals() -> None:
    check_reals("C", "pair", (0.5, 2), 2)
    check_reals("C", "pair", [0.5, np.float64(2.0)], 2)
    for bad in (None, "ab", (1.0,), (1.0, 2.0, 3.0), 1.0):
        with pytest.raises(
            InvalidTypeError, match=r"^C\.pair must be a tuple of 2 real numbers, got"
        ):
            check_reals("C", "pair", bad, 2)
    with pytest.raises(InvalidTypeError, match=r"^C\.pair\[1\] must be a real number, got str"):
        check_reals("C", "pair", (1.0, "x"), 2)
    with pytest.raises(ValueError, match=r"^C\.pair\[0\] must be finite, got nan"):
        check_reals("C", "pair", (math.nan, 1.0), 2)


@pytest.mark.parametrize(
    "value", [["0.1", "0", "0"], [True, False, True], np.array([0.1 + 1j, 0, 0])]
)
def test_arrays_of_strings_bools_or_complex_numbers_are_not_converted(value: object) -> None:
    with pytest.raises(InvalidTypeError, match=r"^v must be 3 numbers, got"):
        finite_vector(value, "v", 3)  # type: ignore[arg-type]
    with pytest.raises(InvalidTypeError, match=r"^v must be numbers, got"):
        real_array(value, "v", "numbers")  # type: ignore[arg-type]


def test_check_real_allows_nan_but_not_other_types() -> None:
    check_real("F", "std", math.nan)
    check_real("F", "std", math.inf)
    with pytest.raises(InvalidTypeError, match=r"^F\.std must be a real number, got NoneType"):
        check_real("F", "std", None)
