"""Band colours of a detected pole against its class: pale bands, drawn poles, and the detector
dropping a detection whose class the colours contradict (the simulated scene's paints are named
in ``tests/spl_env/test_scene_paints.py``)."""

from __future__ import annotations

import numpy as np
import pytest
from drawn_poles import CAMERA, COLOURS, POLE, detection_of, draw_pole

from perception.types import CameraState, PoleCode
from perception.vision import CnnDetectorConfig, CnnPoleDetector, ColourFilterConfig, Detection
from perception.vision.pole_colours import (
    band_colours,
    colours_contradict,
    name_colour,
    paint_hues,
)

HUES = paint_hues(ColourFilterConfig())


def test_pale_and_off_hue_colours_are_not_named() -> None:
    assert name_colour(np.array([235.0, 230.0, 232.0]), HUES) is None  # nearly white
    assert name_colour(np.array([120.0, 40.0, 200.0]), HUES) is None  # violet: no paint near


def test_drawn_pole_bands_and_contradiction() -> None:
    surface, height = 3.0, 0.52
    image = draw_pole(surface, height)  # pink over blue
    box, keypoint = detection_of(surface, height)
    band = CAMERA.fy * POLE.band_height_m / surface
    seen = band_colours(image, box, keypoint, 0.0, band, HUES)
    assert seen == ("pink", "blue")
    assert not colours_contradict(seen, ("pink", "blue"))
    assert colours_contradict(seen, ("pink", "yellow"))
    assert colours_contradict(seen, ("blue", "pink"))  # the mirrored pole
    assert not colours_contradict((None, "blue"), ("pink", "blue"))
    assert not colours_contradict((None, None), ("yellow", "pink"))
    assert COLOURS["pink"] != COLOURS["blue"]


def test_detector_drops_a_class_its_colours_contradict() -> None:
    codes = [
        PoleCode(landmark_id=2, top="pink", bottom="blue"),
        PoleCode(landmark_id=5, top="blue", bottom="pink"),
    ]
    surface, height = 3.0, 0.52
    image = draw_pole(surface, height)
    box, keypoint = detection_of(surface, height)
    state = CameraState(position=np.array([0.0, 0.0, height]), head_yaw=0.0, head_pitch=0.0)
    detector = CnnPoleDetector(CnnDetectorConfig(), CAMERA, codes, POLE)

    def detection(name: str) -> Detection:
        class_id = detector.classes.index(name)
        return Detection(class_name=name, class_id=class_id, box=box, score=0.9, keypoint=keypoint)

    assert detector.observe_pole(2, detection("pole_pink_blue"), state, image) is not None
    assert detector.observe_pole(5, detection("pole_blue_pink"), state, image) is None
    unchecked = CnnPoleDetector(CnnDetectorConfig(check_colours=False), CAMERA, codes, POLE)
    assert unchecked.observe_pole(5, detection("pole_blue_pink"), state, image) is not None
    with pytest.raises(TypeError, match="check_colours"):
        CnnDetectorConfig(check_colours=1)  # type: ignore[arg-type]


def test_slam_setting_needs_both_band_colours() -> None:
    codes = [PoleCode(landmark_id=2, top="pink", bottom="blue")]
    surface, height = 3.0, 0.52
    image = draw_pole(surface, height)
    box, keypoint = detection_of(surface, height)
    hidden = image.copy()  # a grey robot in front of the lower band
    hidden[int(keypoint[1]) + 2 :, int(box[0]) - 3 : int(box[2]) + 4] = (128, 128, 128)
    state = CameraState(position=np.array([0.0, 0.0, height]), head_yaw=0.0, head_pitch=0.0)
    detection = Detection(
        class_name="pole_pink_blue", class_id=2, box=box, score=0.9, keypoint=keypoint
    )
    both = CnnDetectorConfig(require_both_colours=True)
    strict = CnnPoleDetector(both, CAMERA, codes, POLE)
    lenient = CnnPoleDetector(CnnDetectorConfig(), CAMERA, codes, POLE)
    band = CAMERA.fy * POLE.band_height_m / surface
    assert band_colours(hidden, box, keypoint, 0.0, band, HUES) == ("pink", None)
    assert strict.observe_pole(2, detection, state, image) is not None
    assert strict.observe_pole(2, detection, state, hidden) is None
    assert lenient.observe_pole(2, detection, state, hidden) is not None
