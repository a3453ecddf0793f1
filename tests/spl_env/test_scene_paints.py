"""The simulated scene's pole paints are the colours perception's colour check names (split from
``tests/perception/test_pole_colours.py``, so that perception's tests need no simulator)."""

from __future__ import annotations

import numpy as np
import pytest

from perception.vision import ColourFilterConfig
from perception.vision.pole_colours import name_colour, paint_hues
from spl_env.scenes.spl_field import POLE_BAND_RGBA

HUES = paint_hues(ColourFilterConfig())


@pytest.mark.parametrize("colour", ["pink", "yellow", "blue", "green"])
def test_scene_paints_are_named(colour: str) -> None:
    rgb = 255 * np.array(POLE_BAND_RGBA[colour][:3])
    assert name_colour(rgb, HUES) == colour
    assert name_colour(0.6 * rgb, HUES) == colour  # darker: the same hue
