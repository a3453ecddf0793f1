"""The encoder interface and the composition of encoders into one observation."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np
from gymnasium import spaces

from perception.geometry import FloatArray
from perception.representations import PerceptionOutput
from perception.types import SensorFrame


def squash(q: FloatArray | float, scale: float) -> FloatArray:
    """Map q >= 0 to [0, 1) as q / (q + scale)."""
    q = np.asarray(q, dtype=np.float64)
    return q / (q + scale)


def unsquash(q: FloatArray | float, scale: float) -> FloatArray:
    """The inverse of :func:`squash`: ``scale q / (1 - q)``."""
    q = np.asarray(q, dtype=np.float64)
    return scale * q / np.maximum(1.0 - q, 1e-6)


def box(low: float, high: float, size: int) -> spaces.Box:
    """A 1-D float32 box of ``size`` entries in [low, high]."""
    return spaces.Box(low=low, high=high, shape=(size,), dtype=np.float32)


@dataclass(frozen=True)
class EncoderInput:
    """What an encoder may read: one step's perception ``output`` and sensor ``frame``."""

    output: PerceptionOutput
    frame: SensorFrame


class ObservationEncoder(Protocol):
    """Encodes one representation (or sensor reading) as a few observation keys."""

    @property
    def requires(self) -> tuple[str, ...]:
        """Representations it reads from the perception output."""
        ...

    def spaces(self) -> dict[str, spaces.Box]:
        """Its keys and their boxes."""
        ...

    def encode(self, data: EncoderInput) -> dict[str, FloatArray]:
        """Its keys' values (float64; :func:`encode_all` casts them)."""
        ...


def frame_reads(encoders: Sequence[ObservationEncoder]) -> frozenset[str]:
    """The optional :class:`SensorFrame` fields the ``encoders`` read themselves, beside those
    perception reads: an encoder reading a field that a rig measures only when something reads
    it (the sonar) names it in a ``frame_reads`` class attribute (a tuple of field names)."""
    return frozenset(name for e in encoders for name in getattr(e, "frame_reads", ()))


def compose_space(encoders: Sequence[ObservationEncoder]) -> spaces.Dict:
    """The ``Dict`` of every encoder's boxes; ValueError if two encoders share a key."""
    merged: dict[str, spaces.Space[Any]] = {}
    for encoder in encoders:
        for key, space in encoder.spaces().items():
            if key in merged:
                raise ValueError(f"observation key {key!r} comes from two encoders")
            merged[key] = space
    return spaces.Dict(merged)


def encode_all(encoders: Sequence[ObservationEncoder], data: EncoderInput) -> dict[str, np.ndarray]:
    """The observation: every encoder's keys, as float32; FloatingPointError when a value is not
    finite (perception diverged), rather than passing NaN on to a policy."""
    obs: dict[str, FloatArray] = {}
    for encoder in encoders:
        obs.update(encoder.encode(data))
    values = [np.ravel(v) for v in obs.values()]
    if values and not np.isfinite(np.concatenate(values)).all():
        diverged = sorted(k for k, v in obs.items() if not np.all(np.isfinite(v)))
        raise FloatingPointError(f"observation {diverged} not finite: perception diverged")
    return {k: v.astype(np.float32) for k, v in obs.items()}
