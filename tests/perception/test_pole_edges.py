"""Pole distance from band edges: exact on drawn poles, sub-pixel on blended edges, rejection of
edges off the line (on rendered frames against the labels' true range:
``tests/spl_env/test_pole_edges_rendered.py``)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from drawn_poles import CAMERA, COLOURS, POLE, detection_of, draw_band_across, draw_pole

from perception.types import CameraState, PoleCode
from perception.vision import CnnDetectorConfig, CnnPoleDetector, Detection
from perception.vision.pole_edges import (
    EdgeFit,
    PoleEdgeConfig,
    edge_heights,
    expected_rows,
    pole_edge_distance,
    pole_width_distance,
)

CONFIG = PoleEdgeConfig()
LEVEL = np.eye(3)  # a level camera looking along the robot's x axis


def fit(image: np.ndarray, box: np.ndarray, keypoint: np.ndarray, height: float) -> EdgeFit | None:
    return pole_edge_distance(image, box, keypoint, 0.0, CAMERA, LEVEL, height, POLE, CONFIG)


def test_edges_on_pixel_boundaries_give_the_exact_distance() -> None:
    # bands of exactly 25 px whose edges fall between rows: the fit has no quantisation error
    surface = CAMERA.fy * POLE.band_height_m / 25.0
    height = 0.564  # puts the top edge at row 90.5
    image = draw_pole(surface, height)
    box, keypoint = detection_of(surface, height, error_px=1.5)
    result = fit(image, box, keypoint, height)
    assert result is not None
    assert result.edges == ("top", "junction", "base", "bottom")
    np.testing.assert_allclose(result.rows, [90.5, 115.5, 140.5, 190.5], atol=1e-9)
    assert result.distance_m == pytest.approx(surface + POLE.radius_m, rel=1e-9)
    assert result.rms_px == pytest.approx(0.0, abs=1e-9)


@pytest.mark.parametrize("surface_m", [1.7, 2.6, 3.9, 5.3])
def test_blended_edges_give_sub_pixel_distance(surface_m: float) -> None:
    height = 0.53
    image = draw_pole(surface_m, height)
    box, keypoint = detection_of(surface_m, height, error_px=-1.2)
    result = fit(image, box, keypoint, height)
    assert result is not None
    band_px = CAMERA.fy * POLE.band_height_m / surface_m
    # the bottom edge is searched only where bands span 20 px or more
    near = band_px >= CONFIG.bottom_min_band_px
    assert result.edges == ("top", "junction", "base", "bottom")[: 4 if near else 3]
    z = edge_heights(POLE)[: len(result.edges)]
    truth = CAMERA.cy - CAMERA.fy * (z - height) / surface_m
    # a parabola through a split edge is off by less than a third of a pixel
    assert np.max(np.abs(result.rows - truth)) < 0.3
    # rows within 0.3 px over two band heights or more bound the distance's relative error
    bound = 0.3 / band_px
    assert abs(result.distance_m - (surface_m + POLE.radius_m)) / surface_m < bound


def test_an_edge_off_the_line_is_refused() -> None:
    surface, height = 3.0, 0.52
    image = draw_pole(surface, height)
    box, keypoint = detection_of(surface, height)
    # paint the lower band's lowest 30 % white: the base edge, still inside its search window,
    # now lies 6 px above the line through the other two
    rows = expected_rows(box, keypoint, POLE)
    cut = round(rows[2] - 0.3 * (rows[2] - rows[1]))
    image[cut : int(rows[2]) + 2, int(box[0]) : int(box[2]) + 1] = COLOURS["white"]
    assert fit(image, box, keypoint, height) is None  # three edges are needed, two agree
    # the same pole with its own edges is measured
    assert fit(draw_pole(surface, height), box, keypoint, height) is not None


def test_wrong_camera_height_is_refused() -> None:
    surface, height = 3.0, 0.52
    image = draw_pole(surface, height)
    box, keypoint = detection_of(surface, height)
    assert fit(image, box, keypoint, height) is not None
    assert fit(image, box, keypoint, height + 0.2) is None


def test_a_pole_cut_by_the_top_border_is_measured_from_the_rest() -> None:
    surface, height = 0.9, 0.3
    image = draw_pole(surface, height)
    box, keypoint = detection_of(surface, height)
    assert box[1] < 0 < keypoint[1] and box[3] < CAMERA.height  # only the top is out
    with_bottom = fit(image, box, keypoint, height)
    assert with_bottom is not None and with_bottom.edges == ("junction", "base", "bottom")
    assert with_bottom.distance_m == pytest.approx(surface + POLE.radius_m, rel=0.01)
    bands = PoleEdgeConfig(searched_edges=("top", "junction", "base"))
    assert pole_edge_distance(image, box, keypoint, 0.0, CAMERA, LEVEL, height, POLE, bands) is None


def test_relative_variance_follows_least_squares() -> None:
    surface = 3.0
    result = EdgeFit(
        distance_m=surface + POLE.radius_m,
        edges=("top", "junction", "base"),
        rows=np.zeros(3),
        rms_px=0.0,
        spread_m=float(np.std([0.8, 0.6, 0.4])),
        surface_m=surface,
    )
    # slope fx / d; var(slope) = s^2 / sum((z - mean z)^2) = s^2 / 0.08 m^2
    slope = CAMERA.fx / surface
    expected = 0.3**2 / 0.08 / slope**2
    assert result.relative_variance(0.3, CAMERA.fx) == pytest.approx(expected)
    assert result.relative_variance(0.3, CAMERA.fx, 0.01) == pytest.approx(expected + 1e-4)


@pytest.mark.parametrize(
    ("field", "value", "error"),
    [
        ("window_fraction", 0.0, ValueError),
        ("row_std_px", math.nan, ValueError),
        ("min_contrast", 5, ValueError),
        ("searched_edges", ("top", "middle"), ValueError),
        ("searched_edges", ["top", "junction"], ValueError),
        ("bottom_min_band_px", -1.0, ValueError),
        ("width_min_px", math.inf, ValueError),
        ("min_edges", 1, ValueError),
        ("min_edges", 5, ValueError),  # more than the four edges
        ("min_edges", True, ValueError),
    ],
)
def test_config_refuses_bad_values(field: str, value: object, error: type) -> None:
    with pytest.raises(error, match=field):
        PoleEdgeConfig(**{field: value})  # type: ignore[arg-type]


def test_detector_measures_from_edges_when_it_has_the_image() -> None:
    codes = [PoleCode(landmark_id=2, top="pink", bottom="blue")]
    surface, height = 3.0, 0.52
    image = draw_pole(surface, height)
    box, keypoint = detection_of(surface, height, error_px=1.0)
    detection = Detection(
        class_name="pole_pink_blue", class_id=2, box=box, score=0.9, keypoint=keypoint
    )
    state = CameraState(position=np.array([0.0, 0.0, height]), head_yaw=0.0, head_pitch=0.0)
    detector = CnnPoleDetector(CnnDetectorConfig(), CAMERA, codes, POLE)
    with_edges = detector.observe_pole(2, detection, state, image)
    expected = fit(image, box, keypoint, height)
    assert with_edges is not None and expected is not None
    assert with_edges.range_m == pytest.approx(expected.distance_m, rel=1e-9)
    # the camera sits at the robot origin: the range is the drawn pole's axis distance
    band_px = CAMERA.fy * POLE.band_height_m / surface
    assert with_edges.range_m == pytest.approx(surface + POLE.radius_m, rel=0.3 / band_px)
    assert with_edges.bearing_rad == pytest.approx(0.0, abs=1e-9)
    relative = expected.relative_variance(CONFIG.row_std_px, CAMERA.fx, CONFIG.rel_std_floor)
    variance = relative * with_edges.range_m**2
    assert with_edges.cov[0, 0] == pytest.approx(variance, rel=1e-9)
    extents_only = detector.observe_pole(2, detection, state)
    no_edges = CnnPoleDetector(CnnDetectorConfig(edges=None), CAMERA, codes, POLE)
    assert extents_only is not None and extents_only.range_m != with_edges.range_m
    unused = no_edges.observe_pole(2, detection, state, image)
    assert unused is not None and unused.range_m == pytest.approx(extents_only.range_m)


@pytest.mark.parametrize("distance_m", [0.7, 1.1, 1.8])
def test_width_distance_of_a_drawn_band(distance_m: float) -> None:
    half = CAMERA.fx * math.tan(math.asin(POLE.radius_m / distance_m))
    junction = 60.0
    image = draw_band_across(distance_m, (int(junction), CAMERA.height))
    box = np.array([CAMERA.cx - half - 1.0, 0.0, CAMERA.cx + half + 1.2, CAMERA.height - 0.5])
    keypoint = np.array([CAMERA.cx, junction])
    result = pole_width_distance(image, box, keypoint, 0.0, CAMERA, LEVEL, POLE, CONFIG)
    assert result is not None
    assert result.width_px == pytest.approx(2 * half, abs=0.3)
    # two edges within 0.15 px each over the width bound the relative error
    assert result.distance_m == pytest.approx(distance_m, rel=0.3 / (2 * half))


def test_width_distance_refuses_narrow_cut_and_featureless_poles() -> None:
    image = draw_band_across(1.0, (60, CAMERA.height))
    half = CAMERA.fx * math.tan(math.asin(POLE.radius_m / 1.0))
    box = np.array([CAMERA.cx - half, 0.0, CAMERA.cx + half, CAMERA.height - 0.5])
    keypoint = np.array([CAMERA.cx, 60.0])
    assert pole_width_distance(image, box, keypoint, 0.0, CAMERA, LEVEL, POLE, CONFIG) is not None
    narrow = PoleEdgeConfig(width_min_px=2 * half + 1)
    assert pole_width_distance(image, box, keypoint, 0.0, CAMERA, LEVEL, POLE, narrow) is None
    plain = np.full_like(image, 128)  # no edges to find
    assert pole_width_distance(plain, box, keypoint, 0.0, CAMERA, LEVEL, POLE, CONFIG) is None
    at_border = box - np.array([CAMERA.cx - half - 2, 0, CAMERA.cx - half - 2, 0])
    shifted = keypoint - np.array([CAMERA.cx - half - 2, 0])
    assert pole_width_distance(image, at_border, shifted, 0.0, CAMERA, LEVEL, POLE, CONFIG) is None
