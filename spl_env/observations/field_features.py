"""What a head policy needs about field features: how long ago a feature of each kind was seen
(the localisation's std is the self-pose encoder's)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from gymnasium import spaces

from perception.field.features import FEATURE_KINDS
from perception.geometry import FloatArray
from perception.representations import FIELD_FEATURE_LAST_SEEN
from spl_env.observations.base import EncoderInput, box, squash

SINCE_SEEN_SCALE_S = 2.0  # squashing scale of the time since a kind was seen (s)


@dataclass(frozen=True)
class FieldFeatureEncoder:
    """``field_features_since_seen`` (K,): per kind of
    :data:`perception.field.features.FEATURE_KINDS` (in that order), the time t since one
    was seen as t / (t + 2 s), 1 if never this episode."""

    requires: tuple[str, ...] = (FIELD_FEATURE_LAST_SEEN,)

    def spaces(self) -> dict[str, spaces.Box]:
        return {"field_features_since_seen": box(0.0, 1.0, len(FEATURE_KINDS))}

    def encode(self, data: EncoderInput) -> dict[str, FloatArray]:
        since = np.ones(len(FEATURE_KINDS))
        time_s = data.output.time_s
        for kind, seen_s in data.output[FIELD_FEATURE_LAST_SEEN].items():
            since[FEATURE_KINDS.index(kind)] = squash(time_s - seen_s, SINCE_SEEN_SCALE_S)
        return {"field_features_since_seen": since}
