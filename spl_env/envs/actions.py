"""The check every env makes of an action before it acts on it."""

from __future__ import annotations

from typing import Any

import numpy as np

from perception.geometry import FloatArray

BOUND_TOLERANCE = 1e-6  # an action this far outside its box counts as on its bound (rounding)


def checked_action(
    action: Any, low: FloatArray, high: FloatArray, name: str = "action"
) -> FloatArray:
    """``action`` as a float64 array of the shape of ``low`` and ``high`` (the action box's
    bounds), within them: values within :data:`BOUND_TOLERANCE` outside a bound are moved onto
    it (float32 and float64 rounding of a value on the bound).

    TypeError, naming ``name``, for anything but real numbers (strings, booleans, complex
    numbers, objects); ValueError for a wrong shape, a value that is not finite or one further
    outside the box.
    """
    try:
        values = np.asarray(action)
    except ValueError as error:  # ragged nesting: numpy's own words name no argument
        raise ValueError(
            f"{name} must be an array of shape {low.shape}, got {action!r} ({error})"
        ) from None
    if values.dtype.kind not in "iuf":
        raise TypeError(
            f"{name} must be an array of real numbers, got {type(action).__name__} of "
            f"dtype {values.dtype}"
        )
    a = values.astype(np.float64)
    if a.shape != low.shape:
        raise ValueError(f"{name} must have shape {low.shape}, got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be finite, got {a.tolist()}")
    if np.any(a < low - BOUND_TOLERANCE) or np.any(a > high + BOUND_TOLERANCE):
        raise ValueError(f"{name} must lie in [{low.min():g}, {high.max():g}], got {a.tolist()}")
    return np.clip(a, low, high)
