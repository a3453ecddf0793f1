"""Vision front ends: turn camera images into landmark sightings."""

from perception.vision.colour_filter import ColourFilterConfig, ColourPoleDetector

__all__ = ["ColourFilterConfig", "ColourPoleDetector"]
