"""Observation encoders: one per representation, composed per task into a flat ``Dict``.

Nothing here reads ground truth: an encoder turns what perception believes (and the robot's
own joint and sonar readings) into bounded float32 boxes. Unbounded quantities are squashed
with ``q / (q + scale)`` into [0, 1); positions are divided by the carpet's half size and
saturate at ±1.5.
"""

from spl_env.observations.base import EncoderInput, ObservationEncoder, compose_space, encode_all

__all__ = ["EncoderInput", "ObservationEncoder", "compose_space", "encode_all"]
