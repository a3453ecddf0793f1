"""Ball sightings from CNN ball boxes.

Detections are synthetic: a ball of radius 0.05 m placed at a known range and bearing, its
centre (0.05 m above the ground) projected through the camera model
(:func:`perception.geometry.project_points`) and boxed with the apparent diameter
``2 r fx / distance``, so that range and bearing are known exactly.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from numpy.typing import NDArray

from perception.geometry import FloatArray, project_points, wrap_angle
from perception.types import CameraModel, CameraState
from perception.validation import InvalidTypeError
from perception.vision.cnn_ball import (
    BALL_CLASS,
    CnnBallConfig,
    ball_in_view,
    ball_sightings,
    middle_shading,
)
from perception.vision.cnn_detector import OBJECT_CLASSES, Detection
from perception.vision.ground_point import height_point

CAMERA = CameraModel()
RADIUS = 0.05
# row_offset_px 0: the camera obeys the model; no images (the flat-box check has tests of its own)
CONFIG = CnnBallConfig(min_shading_std=None)
STATES = [
    CameraState(position=np.array([0.05, 0.0, 0.5]), head_yaw=0.0, head_pitch=0.3),
    CameraState(position=np.array([0.03, 0.04, 0.48]), head_yaw=0.6, head_pitch=0.25, tilt=0.05),
    CameraState(position=np.array([0.04, -0.03, 0.52]), head_yaw=-0.9, head_pitch=0.35),
]


def project(point: FloatArray, state: CameraState) -> FloatArray:
    """(2,) pixel of the robot-frame ``point`` (3,) seen from ``state``."""
    cam = (np.atleast_2d(point) - state.position) @ state.rotation()
    pixels, front = project_points(cam, CAMERA.fx, CAMERA.fy, CAMERA.cx, CAMERA.cy)
    assert front.all()
    return pixels[0]


def ball_centre(range_m: float, bearing: float) -> FloatArray:
    return np.array([range_m * math.cos(bearing), range_m * math.sin(bearing), RADIUS])


def ball_box(
    range_m: float, bearing: float, state: CameraState, rows_up: float = 0.0
) -> FloatArray:
    """(4,) box of a ball on the ground at ``range_m``, ``bearing`` from the robot origin: centred
    on its centre's pixel (drawn ``rows_up`` rows higher), as wide and tall as its apparent
    diameter."""
    centre = ball_centre(range_m, bearing)
    u, v = project(centre, state)
    half = RADIUS * CAMERA.fx / float(np.linalg.norm(centre - state.position))
    return np.array([u - half, v - rows_up - half, u + half, v - rows_up + half])


def detection(box: FloatArray, score: float = 0.8, name: str = BALL_CLASS) -> Detection:
    """A CNN detection of class ``name`` with ``box`` (4,)."""
    centre = np.array([(box[0] + box[2]) / 2, (box[1] + box[3]) / 2])
    return Detection(
        class_name=name, class_id=OBJECT_CLASSES.index(name), box=box, score=score, keypoint=centre
    )


def in_image(box: FloatArray, margin: float = 2.0) -> bool:
    return bool(
        box[0] > margin
        and box[1] > margin
        and box[2] < CAMERA.width - 1 - margin
        and box[3] < CAMERA.height - 1 - margin
    )


# --- range and bearing ----------------------------------------------------------------------------


@pytest.mark.parametrize("state", STATES)
@pytest.mark.parametrize("range_m", [0.8, 1.5, 3.0, 5.0])
@pytest.mark.parametrize("off_axis", [-0.3, 0.0, 0.25])
def test_the_box_centre_gives_the_range_and_bearing_of_the_ball(
    state: CameraState, range_m: float, off_axis: float
) -> None:
    bearing = state.head_yaw + off_axis
    box = ball_box(range_m, bearing, state)
    if not in_image(box):
        pytest.skip("out of the image for this camera")
    (found,) = ball_sightings([detection(box, score=0.7)], CAMERA, state, CONFIG, image=None)
    assert abs(found.range_m - range_m) < 1e-6
    assert abs(wrap_angle(found.bearing_rad - bearing)) < 1e-6
    assert found.score == 0.7
    np.testing.assert_array_equal(found.box, box)


def test_enough_cases_are_in_the_image() -> None:
    """The parametrised geometry above is not skipped wholesale."""
    cases = [
        in_image(ball_box(r, s.head_yaw + o, s))
        for s in STATES
        for r in (0.8, 1.5, 3.0, 5.0)
        for o in (-0.3, 0.0, 0.25)
    ]
    assert sum(cases) >= 25


@pytest.mark.parametrize("state", STATES)
def test_a_box_drawn_one_row_higher_reads_the_same_with_the_row_offset(state: CameraState) -> None:
    shifted = dataclasses.replace(CONFIG, row_offset_px=1.0)
    for range_m in (1.0, 2.5, 4.0):
        bearing = state.head_yaw + 0.1
        box = ball_box(range_m, bearing, state, rows_up=1.0)
        (found,) = ball_sightings([detection(box)], CAMERA, state, shifted, image=None)
        assert abs(found.range_m - range_m) < 1e-6
        assert abs(wrap_angle(found.bearing_rad - bearing)) < 1e-6
        # without the offset the same box, one row nearer the horizon, reads farther
        (unshifted,) = ball_sightings([detection(box)], CAMERA, state, CONFIG, image=None)
        assert unshifted.range_m > range_m + 1e-3


def test_a_box_above_the_horizon_or_degenerate_gives_nothing() -> None:
    level = CameraState(position=np.array([0.05, 0.0, 0.5]), head_yaw=0.0, head_pitch=0.0)
    above = np.array([150.0, 100.0, 160.0, 110.0])  # centre row 105 < 120: above the horizon
    flat = np.array([150.0, 150.0, 150.0, 160.0])
    upside_down = np.array([160.0, 150.0, 150.0, 160.0])
    for box in (above, flat, upside_down):
        assert ball_sightings([detection(box)], CAMERA, level, CONFIG, image=None) == ()


# --- what is dropped --------------------------------------------------------------------------


def test_boxes_touching_the_image_border_are_dropped() -> None:
    """Pixel centres run 0 .. width - 1, the image's edges lie half a pixel out: a box within
    border_margin_px (1 px) of an edge, i.e. with u0 < 0.5 or u1 > width - 1.5 (and so for v),
    is cut off. The size check is opened wide to test the border alone."""
    # pitched down 0.6 rad (more than half the 44 deg vertical FOV): the whole image is ground
    steep = CameraState(position=np.array([0.05, 0.0, 0.5]), head_yaw=0.0, head_pitch=0.6)
    config = dataclasses.replace(CONFIG, size_tolerance=100.0)
    w, h = CAMERA.width, CAMERA.height
    size = 12.0
    inside_and_cut = [
        # (box kept, box cut): left, top, right, bottom
        ((0.6, 150.0), (0.4, 150.0)),
        ((150.0, 0.6), (150.0, 0.4)),
        ((w - 1.6 - size, 150.0), (w - 1.4 - size, 150.0)),
        ((150.0, h - 1.6 - size), (150.0, h - 1.4 - size)),
    ]
    for (u_kept, v_kept), (u_cut, v_cut) in inside_and_cut:
        kept = np.array([u_kept, v_kept, u_kept + size, v_kept + size])
        cut = np.array([u_cut, v_cut, u_cut + size, v_cut + size])
        assert len(ball_sightings([detection(kept)], CAMERA, steep, config, image=None)) == 1, kept
        assert ball_sightings([detection(cut)], CAMERA, steep, config, image=None) == (), cut
    state = STATES[0]
    wide = dataclasses.replace(config, border_margin_px=30.0)
    box = ball_box(1.5, 0.0, state)
    assert box[0] > 30 and box[1] > 30 and box[2] < w - 31 and box[3] < h - 31
    assert len(ball_sightings([detection(box)], CAMERA, state, wide, image=None)) == 1
    box = ball_box(1.5, 0.42, state)  # towards the left edge, within 30 px of it
    assert 0.6 < box[0] < 29.5
    assert ball_sightings([detection(box)], CAMERA, state, wide, image=None) == ()


@pytest.mark.parametrize(
    ("scale", "kept"),
    [(1.0, True), (1.5, True), (0.5, True), (2.0, False), (0.3, False), (1.7, False)],
)
def test_a_box_of_the_wrong_width_for_its_range_is_dropped(scale: float, kept: bool) -> None:
    """The apparent width off the expected 2 r fx / d by more than size_tolerance (0.6) of it."""
    state = STATES[0]
    box = ball_box(2.0, 0.05, state)
    centre = (box[:2] + box[2:]) / 2
    half = scale * (box[2:] - box[:2]) / 2
    scaled = np.concatenate([centre - half, centre + half])
    found = ball_sightings([detection(scaled)], CAMERA, state, CONFIG, image=None)
    assert len(found) == int(kept)
    if kept:
        assert abs(found[0].range_m - 2.0) < 1e-6  # the width does not move the range


def test_only_ball_detections_at_or_above_the_threshold_are_sighted_best_first() -> None:
    state = STATES[0]
    threshold = CONFIG.score_threshold
    places = [(1.2, -0.2), (2.0, 0.0), (3.0, 0.15), (4.0, -0.1), (2.5, 0.2)]
    boxes = [ball_box(r, b, state) for r, b in places]
    detections = [
        detection(boxes[0], score=0.5),
        detection(boxes[1], score=0.9),
        detection(boxes[2], score=threshold),
        detection(boxes[3], score=threshold - 1e-3),  # below the threshold
        detection(boxes[4], score=0.95, name="robot"),  # another class
        detection(boxes[4], score=0.99, name="goal_post"),
    ]
    found = ball_sightings(detections, CAMERA, state, CONFIG, image=None)
    assert [s.score for s in found] == [0.9, 0.5, threshold]
    for s, (r, b) in zip(found, [places[1], places[0], places[2]], strict=True):
        assert abs(s.range_m - r) < 1e-6 and abs(s.bearing_rad - b) < 1e-6
    assert ball_sightings([], CAMERA, state, CONFIG, image=None) == ()
    stricter = dataclasses.replace(CONFIG, score_threshold=0.8)
    assert [s.score for s in ball_sightings(detections, CAMERA, state, stricter, image=None)] == [
        0.9
    ]


def test_non_finite_boxes_raise_unless_not_read() -> None:
    state = STATES[0]
    for box in (np.array([1.0, 2.0, np.nan, 4.0]), np.array([np.inf, 2.0, 3.0, 4.0])):
        with pytest.raises(ValueError, match=r"detections\[1\].box"):
            ball_sightings(
                [detection(ball_box(2.0, 0.0, state)), detection(box)],
                CAMERA,
                state,
                CONFIG,
                image=None,
            )
    with pytest.raises(ValueError, match=r"detections\[0\].box"):
        short = Detection(
            class_name=BALL_CLASS, class_id=1, box=np.ones(3), score=0.8, keypoint=np.zeros(2)
        )
        ball_sightings([short], CAMERA, state, CONFIG, image=None)
    bad = np.full(4, np.nan)
    assert ball_sightings([detection(bad, name="robot")], CAMERA, state, CONFIG, image=None) == ()
    assert ball_sightings([detection(bad, score=0.1)], CAMERA, state, CONFIG, image=None) == ()


# --- covariance ---------------------------------------------------------------------------------


def test_covariance_is_symmetric_positive_definite_and_grows_with_range() -> None:
    state = STATES[0]
    covs = []
    for range_m in (0.8, 1.2, 2.0, 3.0, 4.5):
        (found,) = ball_sightings(
            [detection(ball_box(range_m, 0.1, state))], CAMERA, state, CONFIG, image=None
        )
        np.testing.assert_array_equal(found.cov, found.cov.T)
        assert np.linalg.eigvalsh(found.cov).min() > 0
        covs.append(found.cov)
    assert np.all(np.diff([c[0, 0] for c in covs]) > 0)


@pytest.mark.parametrize("range_m", [0.8, 1.5, 3.0, 5.0])
@pytest.mark.parametrize("tilt_std", [0.0, 0.0075, 0.02])
def test_range_and_bearing_variance_match_the_closed_form_on_the_centre_column(
    range_m: float, tilt_std: float
) -> None:
    """Camera at the origin, height h, pitched down by p, looking along x; the ball's centre on
    the centre column at horizontal distance d lies (h - r) below the camera, at the angle
    theta = atan((h - r) / d) below the horizon and row v = cy + fy tan(theta - p). Then
    dd/dv = -(h - r) / sin(theta)^2 * fy / (fy^2 + (v - cy)^2), the bearing moves by
    cos(theta - p) / (fx cos(theta)) per column and neither depends on the other pixel axis;
    the pixel std is hypot(1.15, 0.0475 * box width) on u, and on v also fy times the
    camera's unsensed tilt std, which thus widens the range alone."""
    h, p = 0.5, 0.3
    state = CameraState(position=np.array([0.0, 0.0, h]), head_yaw=0.0, head_pitch=p)
    box = ball_box(range_m, 0.0, state)
    config = dataclasses.replace(CONFIG, camera_tilt_std_rad=tilt_std)
    (found,) = ball_sightings([detection(box)], CAMERA, state, config, image=None)
    theta = math.atan((h - RADIUS) / range_m)
    v = CAMERA.cy + CAMERA.fy * math.tan(theta - p)
    assert (box[1] + box[3]) / 2 == pytest.approx(v)
    slope = (h - RADIUS) / math.sin(theta) ** 2 * CAMERA.fy / (CAMERA.fy**2 + (v - CAMERA.cy) ** 2)
    std = math.hypot(1.15, 0.0475 * (box[2] - box[0]))
    row_std = math.hypot(std, CAMERA.fy * tilt_std)
    assert found.cov[0, 0] == pytest.approx((slope * row_std) ** 2, rel=2e-3)
    bearing_slope = math.cos(theta - p) / (CAMERA.fx * math.cos(theta))
    assert found.cov[1, 1] == pytest.approx((bearing_slope * std) ** 2, rel=2e-3)
    assert abs(found.cov[0, 1]) < 1e-9 * math.sqrt(found.cov[0, 0] * found.cov[1, 1])


# --- configuration ------------------------------------------------------------------------------


def test_a_ball_box_on_our_own_shoulder_is_dropped() -> None:
    """The head turned to its right limit and pitched down shows the top camera its own right
    arm across the image's lower part: a ball-sized box there (the size a ball would have where
    its centre's ray meets the ball's plane) is our body, not a ball, unless the body check is
    off (``body=None``)."""
    yaw = -1.55
    state = CameraState(
        position=np.array([0.059 * math.cos(yaw), 0.059 * math.sin(yaw), 0.49]),
        head_yaw=yaw,
        head_pitch=0.46,
    )
    point = height_point(np.array([CAMERA.cx, CAMERA.height - 28.0]), RADIUS, CAMERA, state)
    assert point is not None
    box = ball_box(*point, state)
    assert ball_sightings([detection(box)], CAMERA, state, CONFIG, image=None) == ()
    unchecked = dataclasses.replace(CONFIG, body=None)
    (kept,) = ball_sightings([detection(box)], CAMERA, state, unchecked, image=None)
    assert kept.range_m == pytest.approx(point[0], abs=1e-9)


# --- flat boxes (step 5) -------------------------------------------------------------------------

GREEN = (40, 120, 40)


def carpet() -> NDArray[np.uint8]:
    """A carpet-green frame of the camera's size."""
    return np.tile(np.array(GREEN, dtype=np.uint8), (CAMERA.height, CAMERA.width, 1))


def paint_sphere(image: NDArray[np.uint8], box: FloatArray, light: FloatArray) -> None:
    """A Lambertian sphere of albedo 0.9 inscribed in ``box`` (4,), lit along the unit
    ``light`` (3,) (camera axes: x right, y down, z towards the viewer) with ambient 0.15."""
    u0, v0, u1, v1 = box
    cu, cv, r = (u0 + u1) / 2, (v0 + v1) / 2, (u1 - u0) / 2
    v, u = np.mgrid[0 : image.shape[0], 0 : image.shape[1]] + 0.5
    x, y = (u - cu) / r, (v - cv) / r
    inside = x**2 + y**2 < 1.0
    z = np.sqrt(np.clip(1.0 - x**2 - y**2, 0.0, 1.0))
    grey = 255 * 0.9 * (0.15 + 0.85 * np.clip(x * light[0] + y * light[1] + z * light[2], 0, 1))
    image[inside] = np.round(grey[inside])[:, None].astype(np.uint8)


def test_middle_shading_is_the_std_of_the_middle_half_luminance() -> None:
    """By hand: a box (99.5, 59.5)-(139.5, 99.5) has its middle half over the pixel centres
    110-129 and 70-89 (pixel i centred at i); columns 110-119 black, 120-129 white give
    luminances 0 and 255 in equal numbers: std 127.5 (a pixel more either way would add green).
    A box under ``min_judged_px`` across is not judged; a middle beyond the image is clipped to
    it, one wholly outside (any side) is not judged; an over-exposed one (median luminance at
    ``clipped_luminance`` or more) is not judged."""
    config = CnnBallConfig()
    image = carpet()
    image[70:90, 110:120] = 0
    image[70:90, 120:130] = 255
    box = np.array([99.5, 59.5, 139.5, 99.5])
    assert middle_shading(image, box, config) == pytest.approx(127.5)
    assert middle_shading(image, box + np.array([-1.0, 0.0, 1.0, 0.0]), config) != 127.5
    assert middle_shading(image, np.array([100.0, 60.0, 107.0, 100.0]), config) is None
    w, h = CAMERA.width, CAMERA.height
    corner = np.array([w - 20.0, -20.0, w + 20.0, 20.0])
    assert middle_shading(image, corner, config) == pytest.approx(0.0)  # the green corner
    for outside in ([w + 10, 100, w + 50, 140], [-50, 100, -10, 140], [100, -50, 140, -10]):
        assert middle_shading(image, np.array(outside, dtype=float), config) is None, outside
    assert middle_shading(image, np.array([100, h + 10, 140, h + 50.0]), config) is None
    image[70:90, 110:130] = 250
    assert middle_shading(image, box, config) is None
    assert middle_shading(image, box, dataclasses.replace(config, clipped_luminance=251.0)) == 0.0


@pytest.mark.parametrize(
    "light", [(0.0, 0.0, 1.0), (0.6, -0.6, 0.53), (-0.8, 0.0, 0.6), (0.0, -0.95, 0.31)]
)
def test_a_lit_sphere_is_kept_and_a_flat_disc_in_its_place_dropped(
    light: tuple[float, float, float],
) -> None:
    """A ball box 1 m ahead: painted as a lit sphere (any light from the camera's side shades
    its middle half by tens of grey levels) it is sighted; painted as a flat white disc with
    the camera's noise (a penalty mark) it is dropped, unless the check is off."""
    state = STATES[0]
    box = ball_box(1.0, 0.05, state)
    assert box[2] - box[0] > 16  # judged
    config = CnnBallConfig()
    rng = np.random.default_rng(3)
    sphere = carpet()
    paint_sphere(sphere, box, np.array(light) / np.linalg.norm(light))
    shading = middle_shading(sphere, box, config)
    assert shading is not None and shading >= 9.0  # judged: shaded (three times the check)
    (found,) = ball_sightings([detection(box)], CAMERA, state, config, image=sphere)
    assert found.range_m == pytest.approx(1.0, abs=1e-6)
    disc = carpet()
    v, u = np.mgrid[0 : CAMERA.height, 0 : CAMERA.width] + 0.5
    centre = ((box[0] + box[2]) / 2, (box[1] + box[3]) / 2)
    disc[np.hypot(u - centre[0], v - centre[1]) < (box[2] - box[0]) / 2] = 245
    noisy = np.clip(disc + rng.normal(0.0, 2.0, disc.shape), 0, 255).astype(np.uint8)
    assert ball_sightings([detection(box)], CAMERA, state, config, image=noisy) == ()
    unchecked = dataclasses.replace(config, min_shading_std=None)
    assert len(ball_sightings([detection(box)], CAMERA, state, unchecked, image=noisy)) == 1


def test_a_flat_box_too_small_to_judge_is_kept() -> None:
    """A ball 4 m ahead boxes under ``min_judged_px``: flat or not, it is not judged."""
    state = STATES[0]
    box = ball_box(4.0, 0.0, state)
    assert box[2] - box[0] < CnnBallConfig().min_judged_px
    flat = carpet()
    flat[int(box[1]) : int(box[3]) + 1, int(box[0]) : int(box[2]) + 1] = 245
    assert len(ball_sightings([detection(box)], CAMERA, state, CnnBallConfig(), image=flat)) == 1


def test_the_flat_box_check_needs_the_frame() -> None:
    state = STATES[0]
    box = ball_box(1.0, 0.0, state)
    with pytest.raises(ValueError, match="image must be a"):
        ball_sightings([detection(box)], CAMERA, state, CnnBallConfig(), image=None)
    with pytest.raises(ValueError, match=r"got \(10, 10, 3\) uint8"):
        small = np.zeros((10, 10, 3), dtype=np.uint8)
        ball_sightings([detection(box)], CAMERA, state, CnnBallConfig(), image=small)
    with pytest.raises(ValueError, match="got list"):
        ball_sightings([detection(box)], CAMERA, state, CnnBallConfig(), image=[[0]])  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("field", "value", "error"),
    [
        ("score_threshold", 0.0, ValueError),
        ("score_threshold", 1.0, ValueError),
        ("score_threshold", 1, InvalidTypeError),
        ("score_threshold", math.nan, ValueError),
        ("radius_m", 0.0, ValueError),
        ("radius_m", -0.05, ValueError),
        ("radius_m", "0.05", TypeError),
        ("border_margin_px", -1.0, ValueError),
        ("pixel_std_px", 0.0, ValueError),
        ("pixel_std_per_size", -0.1, ValueError),
        ("pixel_std_per_size", math.inf, ValueError),
        ("camera_tilt_std_rad", -0.01, ValueError),
        ("camera_tilt_std_rad", math.nan, ValueError),
        ("size_tolerance", 0.0, ValueError),
        ("row_offset_px", 5.0, ValueError),
        ("row_offset_px", -6.0, ValueError),
        ("row_offset_px", math.nan, ValueError),
        ("bottom_downscale", 0, ValueError),
        ("bottom_downscale", 2.0, InvalidTypeError),
        ("body", "arms", InvalidTypeError),
        ("min_shading_std", 0.0, ValueError),
        ("min_shading_std", math.nan, ValueError),
        ("min_judged_px", -1.0, ValueError),
        ("clipped_luminance", 256.0, ValueError),
        ("clipped_luminance", 0.0, ValueError),
        ("min_judged_px", math.nan, ValueError),
    ],
)
def test_config_rejects_bad_values(field: str, value: object, error: type[Exception]) -> None:
    with pytest.raises(error, match=f"CnnBallConfig.{field}"):
        CnnBallConfig(**{field: value})  # type: ignore[arg-type]


def test_config_defaults() -> None:
    config = CnnBallConfig()
    assert config.radius_m == 0.05  # the SPL ball, 0.1 m across
    assert config.row_offset_px == 0.0
    assert CnnBallConfig(border_margin_px=0.0, pixel_std_per_size=0.0).border_margin_px == 0.0
    assert config.pixel_std(np.array([0.0, 0.0, 20.0, 20.0])) == pytest.approx(
        math.hypot(1.15, 0.0475 * 20.0)
    )
    with pytest.raises(dataclasses.FrozenInstanceError):
        config.radius_m = 0.1  # type: ignore[misc]


# --- ball_in_view -------------------------------------------------------------------------------


@pytest.mark.parametrize("margin", [0.0, 0.1, 0.3])
def test_a_ball_is_in_view_within_the_field_of_view_less_the_margin(margin: float) -> None:
    """A level camera (pitch 0) at the height of the ball's centre: a ball at horizontal angle a
    is in view iff tan|a| <= tan(hfov / 2) (1 - 2 margin) (by hand: the image's half-width in
    the focal plane), vertically alike with the vertical FOV; never behind the camera."""
    radius = 0.05
    state = CameraState(position=np.array([0.0, 0.0, radius]), head_yaw=0.0, head_pitch=0.0)
    half_h = math.atan(math.tan(math.radians(CAMERA.hfov_deg) / 2) * (1 - 2 * margin))
    for angle, inside in ((half_h - 1e-3, True), (half_h + 1e-3, False)):
        for sign in (1.0, -1.0):
            point = 2.0 * np.array([1.0, sign * math.tan(angle)])
            assert ball_in_view(point, CAMERA, state, radius, margin) == inside, (angle, sign)
    # a camera lower (or higher) than the ball's centre by 2 tan(a): the ball sits at vertical
    # angle a above (or below) the optical axis
    half_v = math.atan(math.tan(math.radians(CAMERA.vfov_deg) / 2) * (1 - 2 * margin))
    for angle, inside in ((half_v - 1e-3, True), (half_v + 1e-3, False)):
        for sign in (1.0, -1.0):
            low = CameraState(
                position=np.array([0.0, 0.0, radius - sign * 2.0 * math.tan(angle)]),
                head_yaw=0.0,
                head_pitch=0.0,
            )
            assert ball_in_view(np.array([2.0, 0.0]), CAMERA, low, radius, margin) == inside
    assert not ball_in_view(np.array([-2.0, 0.0]), CAMERA, state, radius, margin)


def test_a_ball_is_in_view_where_the_head_turns() -> None:
    """A ball 60 degrees to the left is out of view of a head looking ahead, in view of one
    turned 60 degrees left (projected at the image's centre column)."""
    radius = 0.05
    point = 2.0 * np.array([math.cos(math.radians(60)), math.sin(math.radians(60))])
    ahead = CameraState(position=np.array([0.0, 0.0, 0.5]), head_yaw=0.0, head_pitch=0.2)
    turned = dataclasses.replace(ahead, head_yaw=math.radians(60))
    assert not ball_in_view(point, CAMERA, ahead, radius, 0.1)
    assert ball_in_view(point, CAMERA, turned, radius, 0.1)
