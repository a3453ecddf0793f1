"""Natural landmarks on the horizon (seed 004 chapters 3-5): the horizon band of an image, its
1-D SURF features and their matching to stored landmark views, the visual vocabulary and
bag-of-words recognition of the field's ends, and visual heading odometry."""

from perception.landmarks.bag_of_words import ImageDatabase, RetrievalConfig, tf_idf
from perception.landmarks.field_end import (
    AWAY,
    HOME,
    FieldEndBelief,
    FieldEndConfig,
    FieldEndRecogniser,
)
from perception.landmarks.horizon import HorizonBand, HorizonConfig, horizon_band, horizon_rows
from perception.landmarks.horizon_features import (
    HorizonFeatureConfig,
    HorizonFeatures,
    horizon_features,
)
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
from perception.landmarks.visual_odometry import (
    CollisionDetector,
    VisualHeadingOdometry,
    VisualOdometryConfig,
)
from perception.landmarks.vocabulary import Vocabulary, default_vocabulary, learn_vocabulary

__all__ = [
    "AWAY",
    "HOME",
    "CollisionDetector",
    "FieldEndBelief",
    "FieldEndConfig",
    "FieldEndRecogniser",
    "HorizonBand",
    "HorizonConfig",
    "HorizonFeatureConfig",
    "HorizonFeatures",
    "ImageDatabase",
    "LineModel",
    "Matches",
    "MatchingConfig",
    "RansacConfig",
    "RansacResult",
    "RetrievalConfig",
    "Surf1dConfig",
    "Surf1dFeatures",
    "VisualHeadingOdometry",
    "VisualOdometryConfig",
    "Vocabulary",
    "default_vocabulary",
    "extract_features",
    "horizon_band",
    "horizon_features",
    "horizon_rows",
    "learn_vocabulary",
    "match_features",
    "ransac_line",
    "tf_idf",
]
