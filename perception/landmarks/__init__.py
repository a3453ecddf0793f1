"""Natural landmarks on the horizon (seed 004 chapter 3): the horizon band of an image, its
1-D SURF features and their matching to stored landmark views."""

from perception.landmarks.horizon import HorizonBand, HorizonConfig, horizon_band, horizon_rows
from perception.landmarks.matching import (
    LineModel,
    Matches,
    MatchingConfig,
    RansacConfig,
    RansacResult,
    match_features,
    ransac_line,
)
from perception.landmarks.surf1d import Surf1dConfig, Surf1dFeatures, extract_features

__all__ = [
    "HorizonBand",
    "HorizonConfig",
    "LineModel",
    "Matches",
    "MatchingConfig",
    "RansacConfig",
    "RansacResult",
    "Surf1dConfig",
    "Surf1dFeatures",
    "extract_features",
    "horizon_band",
    "horizon_rows",
    "match_features",
    "ransac_line",
]
