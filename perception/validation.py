"""Checks of constructor arguments and config fields, shared by the perception modules.

Each check names the value as ``owner.name`` (``name`` alone when ``owner`` is ""), e.g.
``EkfSlamConfig.gate_range_m`` or ``observations[2].range_m``, and says what was expected and
what came::

    ValueError: EkfSlamConfig.gate_range_m must be finite and in (0, inf), got -1

A value of the wrong type raises :class:`InvalidTypeError`, one of the right type outside its
domain ValueError. A bool is not a number here, although Python's ``bool`` subclasses ``int``.
The ``check_*`` functions only raise; :func:`finite_vector` and :func:`check_covariance` also
return the value as a new float64 array.
"""

from __future__ import annotations

import dataclasses
import math
import types
import typing
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from perception.geometry import FloatArray

_REAL = (int, float, np.integer, np.floating)  # a bool is excluded separately
_INT = (int, np.integer)
_SYMMETRY_RTOL = 1e-9  # covariance entries (i, j) and (j, i) may differ by this relative amount
_PSD_RTOL = 1e-12  # a semidefinite covariance's eigenvalues may dip this far below zero
_SYMMETRY_ATOL = 1e-15  # ... plus this absolute amount (entries near zero)


class InvalidTypeError(TypeError, ValueError):
    """A value of the wrong type.

    A TypeError, and also a ValueError: before these checks were shared, several configs
    raised ValueError for any bad value, wrong types included, and code catching ValueError
    keeps working (as numpy's ``AxisError`` is both a ValueError and an IndexError).
    """


def is_finite_real(value: object) -> bool:
    """Whether ``value`` is a finite real number (a Python or numpy int or float, not a bool)."""
    return isinstance(value, _REAL) and not isinstance(value, bool) and math.isfinite(value)


def check_real(owner: str, name: str, value: object) -> None:
    """Raise unless ``value`` is a real number (NaN and the infinities included: for a field
    where NaN means "none")."""
    _check_real(owner, name, value, float_only=False)


def check_finite(owner: str, name: str, value: object) -> None:
    """Raise unless ``value`` is a finite real number."""
    _check_real(owner, name, value, float_only=False)
    if not math.isfinite(value):  # type: ignore[arg-type]
        raise ValueError(f"{_label(owner, name)} must be finite, got {value!r}")


def check_reals(owner: str, name: str, value: object, length: int) -> None:
    """Raise unless ``value`` is a tuple or list of ``length`` finite real numbers (a bad one is
    named ``name[k]``)."""
    if not isinstance(value, tuple | list) or len(value) != length:
        raise InvalidTypeError(
            f"{_label(owner, name)} must be a tuple of {length} real numbers, got {_got(value)}"
        )
    for k, item in enumerate(value):
        check_finite(owner, f"{name}[{k}]", item)


def check_in_interval(
    owner: str,
    name: str,
    value: object,
    low: float,
    high: float,
    *,
    low_inclusive: bool = False,
    high_inclusive: bool = False,
    float_only: bool = False,
) -> None:
    """Raise unless ``value`` is a finite real number in the interval from ``low`` to ``high``.

    The interval is open at each end unless ``low_inclusive`` / ``high_inclusive``; either
    bound may be infinite. ``float_only``: ints (and numpy scalars other than float64) are of
    the wrong type.
    """
    _check_real(owner, name, value, float_only=float_only)
    v: float = value  # type: ignore[assignment]
    above = v >= low if low_inclusive else v > low
    below = v <= high if high_inclusive else v < high
    if not (math.isfinite(v) and above and below):
        opening, closing = "[" if low_inclusive else "(", "]" if high_inclusive else ")"
        interval = f"{opening}{low:g}, {high:g}{closing}"
        raise ValueError(f"{_label(owner, name)} must be finite and in {interval}, got {value!r}")


def check_positive(
    owner: str,
    name: str,
    value: object,
    *,
    allow_zero: bool = False,
    upper: float = math.inf,
    upper_inclusive: bool = False,
    float_only: bool = False,
) -> None:
    """Raise unless ``value`` is a finite real number > 0 (>= 0 with ``allow_zero``).

    ``upper`` bounds it from above, itself allowed when ``upper_inclusive``. ``float_only`` as
    in :func:`check_in_interval`.
    """
    check_in_interval(
        owner,
        name,
        value,
        0.0,
        upper,
        low_inclusive=allow_zero,
        high_inclusive=upper_inclusive,
        float_only=float_only,
    )


def check_probability(owner: str, name: str, value: object, *, float_only: bool = False) -> None:
    """Raise unless ``value`` is a real number strictly between 0 and 1.

    For levels of quantiles and score thresholds, where 0 and 1 are degenerate. ``float_only``
    as in :func:`check_in_interval`.
    """
    check_in_interval(owner, name, value, 0.0, 1.0, float_only=float_only)


def check_int(
    owner: str, name: str, value: object, minimum: int | None = None, *, optional: bool = False
) -> None:
    """Raise unless ``value`` is an int (Python or numpy, not a bool) >= ``minimum``.

    ``minimum`` None: any int. ``optional``: None is allowed too.
    """
    if value is None and optional:
        return
    expected = "an int" + ("" if minimum is None else f" >= {minimum}")
    expected += " or None" if optional else ""
    if isinstance(value, bool) or not isinstance(value, _INT):
        raise InvalidTypeError(f"{_label(owner, name)} must be {expected}, got {_got(value)}")
    if minimum is not None and value < minimum:
        raise ValueError(f"{_label(owner, name)} must be {expected}, got {value!r}")


def check_bool(owner: str, name: str, value: object) -> None:
    """Raise unless ``value`` is a bool."""
    if not isinstance(value, bool):
        raise InvalidTypeError(f"{_label(owner, name)} must be a bool, got {_got(value)}")


def check_instance(name: str, value: object, expected: type, *, optional: bool = False) -> None:
    """InvalidTypeError unless ``value`` (the argument ``name``) is an ``expected`` (or None,
    with ``optional``): a config or context of the wrong class fails here, by name, and not as
    an AttributeError deep inside."""
    if not (isinstance(value, expected) or (optional and value is None)):
        wanted = expected.__name__ + (" or None" if optional else "")
        raise InvalidTypeError(f"{name} must be a {wanted}, got {type(value).__name__}")


def check_nested_configs(config: object) -> None:
    """InvalidTypeError unless every field of the dataclass ``config`` whose declared type is a
    dataclass (a nested config: ``sensors: RigConfig``, ``laser: LaserConfig | None``) holds an
    instance of that class (or None where the type allows it): ``EnvConfig.robot=None`` fails
    here, by name, and not as an AttributeError when the env is built."""
    owner = type(config).__name__
    hints = typing.get_type_hints(type(config))
    for f in dataclasses.fields(config):  # type: ignore[arg-type]
        expected, optional = _nested_config_type(hints[f.name])
        if expected is not None:
            check_instance(
                f"{owner}.{f.name}", getattr(config, f.name), expected, optional=optional
            )


def _nested_config_type(hint: object) -> tuple[type | None, bool]:
    """The dataclass a field's type ``hint`` names, and whether None is allowed too; (None,
    False) for any other type."""
    if isinstance(hint, type) and dataclasses.is_dataclass(hint):
        return hint, False
    if isinstance(hint, types.UnionType) or typing.get_origin(hint) is typing.Union:
        members = typing.get_args(hint)
        classes = [m for m in members if m is not type(None)]
        if len(classes) == 1 and len(members) == 2:
            expected, _ = _nested_config_type(classes[0])
            return expected, expected is not None
    return None, False


def check_generator(name: str, value: object) -> None:
    """InvalidTypeError unless ``value`` (the argument ``name``) is a numpy Generator: every
    random draw comes from one the caller seeded."""
    if not isinstance(value, np.random.Generator):
        raise InvalidTypeError(
            f"{name} must be a numpy.random.Generator, got {type(value).__name__}"
        )


def check_choice(
    owner: str, name: str, value: object, choices: Sequence[str], *, optional: bool = False
) -> None:
    """Raise unless ``value`` is one of the strings ``choices`` (or None when ``optional``)."""
    if value is None and optional:
        return
    if not isinstance(value, str):
        raise InvalidTypeError(
            f"{_label(owner, name)} must be a str{' or None' if optional else ''}, "
            f"got {_got(value)}"
        )
    if value not in choices:
        raise ValueError(f"{_label(owner, name)} must be one of {tuple(choices)}, got {value!r}")


def real_array(value: ArrayLike, name: str, expected: str) -> FloatArray:
    """``value`` as a new float64 array, or InvalidTypeError naming the argument ``name`` (which
    must be ``expected``) when it is not an array of real numbers: strings, bools, complex
    numbers and objects are refused rather than converted."""
    try:
        raw = np.asarray(value)
    except (TypeError, ValueError) as error:
        raise InvalidTypeError(f"{name} must be {expected}, got {value!r}") from error
    if raw.dtype.kind not in "iuf":
        raise InvalidTypeError(f"{name} must be {expected}, got {value!r}")
    return np.array(raw, dtype=np.float64)


def finite_vector(value: ArrayLike, name: str, size: int) -> FloatArray:
    """``value`` as a new finite float64 array of shape (size,); errors name the argument."""
    array = real_array(value, name, f"{size} numbers")
    if array.shape != (size,):
        raise ValueError(f"{name} must have shape ({size},), got shape {array.shape}")
    if not np.isfinite(array).all():
        raise ValueError(f"{name} must be finite, got {array}")
    return array


def finite_points(value: ArrayLike, name: str, minimum: int = 0) -> FloatArray:
    """``value`` as a new finite float64 (N, 2) array of points with N >= ``minimum``; errors
    name the argument and, for NaN or infinity, the rows holding them."""
    points = real_array(value, name, "an (N, 2) array of numbers")
    if points.ndim != 2 or points.shape[1] != 2 or len(points) < minimum:
        raise ValueError(
            f"{name} must have shape (N, 2) with N >= {minimum}, got shape {points.shape}"
        )
    if not np.isfinite(points).all():
        rows = np.flatnonzero(~np.isfinite(points).all(axis=1)).tolist()
        raise ValueError(f"{name} must be finite, got NaN or infinity in rows {rows}")
    return points


def check_covariance(
    matrix: ArrayLike, name: str, size: int, *, singular_ok: bool = False
) -> FloatArray:
    """``matrix`` as a new float64 (size, size) array; raise unless it is a covariance.

    A covariance here is finite, symmetric (entries (i, j) and (j, i) agree to a relative 1e-9
    of the larger of them and of ``sqrt(C_ii C_jj)``: :func:`is_symmetric`) and positive
    definite, or with ``singular_ok`` positive semidefinite (its eigenvalues may
    dip a relative 1e-12 below zero; the returned array is then symmetrised). Errors name the
    argument ``name``.
    """
    try:
        C = np.array(matrix, dtype=np.float64)
    except (TypeError, ValueError) as error:
        expected = f"a ({size}, {size}) array"
        raise InvalidTypeError(f"{name} must be {expected}, got {matrix!r}") from error
    if C.shape != (size, size) or not np.isfinite(C).all():
        raise ValueError(f"{name} must be a finite ({size}, {size}) array, got {C!r}")
    if singular_ok and size == 2:  # plain floats, as below: the eigenvalues in closed form
        (a, b), (c, d) = C.tolist()
        if abs(b - c) > _symmetry_tolerance(a, b, c, d):
            raise ValueError(f"{name} must be symmetric, got {C.tolist()}")
        s = 0.5 * (b + c)
        lowest = 0.5 * (a + d) - math.hypot(0.5 * (a - d), s)
        if lowest < -_PSD_RTOL * max(abs(a), abs(s), abs(d)):
            raise ValueError(f"{name} must be positive semidefinite, got {C.tolist()}")
        return np.array([[a, s], [s, d]])
    if singular_ok:
        if not is_symmetric(C):
            raise ValueError(f"{name} must be symmetric, got {C.tolist()}")
        C = 0.5 * (C + C.T)
        if float(np.linalg.eigvalsh(C).min()) < -_PSD_RTOL * float(np.abs(C).max()):
            raise ValueError(f"{name} must be positive semidefinite, got {C.tolist()}")
        return C
    if size == 2:  # plain floats: much faster than numpy for the many 2 x 2 measurement checks
        (a, b), (c, d) = C.tolist()
        symmetric = abs(b - c) <= _symmetry_tolerance(a, b, c, d)
        positive = a > 0.0 and a * d - b * c > 0.0  # Sylvester's criterion
    else:
        symmetric = is_symmetric(C)
        positive = symmetric and _has_cholesky(C)
    if not symmetric:
        raise ValueError(f"{name} must be symmetric, got {C.tolist()}")
    if not positive:
        raise ValueError(f"{name} must be positive definite, got {C.tolist()}")
    return C


def is_symmetric(C: FloatArray) -> bool:
    """Whether the square ``C`` is symmetric to rounding: entries (i, j) and (j, i) agree to a
    relative ``_SYMMETRY_RTOL`` of the larger of them and of ``sqrt(|C_ii C_jj|)`` (an entry
    near zero beside large variances is rounding of their scale), plus ``_SYMMETRY_ATOL``."""
    if np.array_equal(C, C.T):  # the usual case, a symmetrised filter covariance: cheap
        return True
    diagonal = np.sqrt(np.abs(np.diag(C)))
    scale = np.maximum(np.maximum(np.abs(C), np.abs(C.T)), np.outer(diagonal, diagonal))
    return bool((np.abs(C - C.T) <= _SYMMETRY_RTOL * scale + _SYMMETRY_ATOL).all())


def _symmetry_tolerance(a: float, b: float, c: float, d: float) -> float:
    """:func:`is_symmetric`'s tolerance for ``|b - c|`` of the 2 x 2 ``[[a, b], [c, d]]``."""
    return _SYMMETRY_RTOL * max(abs(b), abs(c), math.sqrt(abs(a * d))) + _SYMMETRY_ATOL


def _has_cholesky(C: FloatArray) -> bool:
    """Whether the symmetric ``C`` (n, n) has a Cholesky factor, i.e. is positive definite."""
    try:
        np.linalg.cholesky(C)
    except np.linalg.LinAlgError:
        return False
    return True


def _check_real(owner: str, name: str, value: object, *, float_only: bool) -> None:
    """Raise :class:`InvalidTypeError` unless ``value`` is a real number (a float if asked)."""
    if isinstance(value, bool) or not isinstance(value, float if float_only else _REAL):
        expected = "a float" if float_only else "a real number"
        raise InvalidTypeError(f"{_label(owner, name)} must be {expected}, got {_got(value)}")


def _label(owner: str, name: str) -> str:
    """``owner.name``, or ``name`` when there is no owner."""
    return f"{owner}.{name}" if owner else name


def _got(value: object) -> str:
    """A value for an error message, with its type: ``str '0.4'``."""
    return f"{type(value).__name__} {value!r}"


def check_rgb_image(image: object, height: int, width: int, name: str = "image") -> None:
    """Raise ValueError unless ``image`` is an (``height``, ``width``, 3) uint8 (RGB) array."""
    shape = (height, width, 3)
    if not (isinstance(image, np.ndarray) and image.dtype == np.uint8 and image.shape == shape):
        got = (
            f"{image.shape} {image.dtype}"
            if isinstance(image, np.ndarray)
            else type(image).__name__
        )
        raise ValueError(f"{name} must be a {shape} uint8 RGB array, got {got}")
