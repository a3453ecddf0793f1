"""Vision front ends: turn camera images into landmark sightings.

The CNN detector imports torch only when one is built.
"""

from perception.vision.cnn_detector import CnnDetectorConfig, CnnPoleDetector, Detection
from perception.vision.colour_filter import ColourFilterConfig, ColourPoleDetector

__all__ = [
    "CnnDetectorConfig",
    "CnnPoleDetector",
    "ColourFilterConfig",
    "ColourPoleDetector",
    "Detection",
]
