"""Robot sightings from CNN robot boxes, and the ground-plane geometry under them.

Detections are synthetic: known 3-D robot boxes projected through the camera model
(:func:`perception.geometry.project_points`), so that range and bearing are known exactly.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from perception.geometry import project_points, wrap_angle
from perception.types import CameraModel, CameraState
from perception.validation import InvalidTypeError
from perception.vision.cnn_detector import Detection
from perception.vision.cnn_robots import (
    CnnRobotConfig,
    box_bottom_cut,
    robot_sightings,
    waistband_sighting,
)
from perception.vision.ground_point import (
    JACOBIAN_STEP_PX,
    ground_point,
    height_point,
    pixel_ray,
    range_bearing_cov,
)

CAMERA = CameraModel()
# A robot as a box around its centre: half depth and half width (m), height (m).
HALF_DEPTH, HALF_WIDTH, TOP = 0.05, 0.135, 0.57
CONFIG = CnnRobotConfig(centre_beyond_m=HALF_DEPTH)
STATES = [
    CameraState(position=np.array([0.05, 0.0, 0.52]), head_yaw=0.0, head_pitch=0.2, tilt=0.02),
    CameraState(position=np.array([0.03, 0.04, 0.50]), head_yaw=0.7, head_pitch=0.35),
    CameraState(position=np.array([0.04, -0.03, 0.53]), head_yaw=-1.1, head_pitch=0.05, tilt=0.02),
]


def project(points: np.ndarray, state: CameraState, camera: CameraModel = CAMERA) -> np.ndarray:
    """(N, 2) pixels of (N, 3) robot-frame points seen from ``state``."""
    cam = (np.atleast_2d(points) - state.position) @ state.rotation()
    pixels, front = project_points(cam, camera.fx, camera.fy, camera.cx, camera.cy)
    assert front.all()
    return pixels


def robot_box(centre: np.ndarray, yaw: float, state: CameraState) -> np.ndarray:
    """(4,) pixel box ``(u0, v0, u1, v1)`` of a robot-shaped box standing at ``centre`` (2,)
    (robot frame) turned by ``yaw``."""
    c, s = math.cos(yaw), math.sin(yaw)
    corners = np.array(
        [
            [centre[0] + c * x - s * y, centre[1] + s * x + c * y, z]
            for x in (-HALF_DEPTH, HALF_DEPTH)
            for y in (-HALF_WIDTH, HALF_WIDTH)
            for z in (0.0, TOP)
        ]
    )
    pixels = project(corners, state)
    return np.concatenate([pixels.min(axis=0), pixels.max(axis=0)])


def facing_robot(distance: float, state: CameraState) -> tuple[np.ndarray, float, float]:
    """The box (4,) of a robot ``distance`` m ahead of the camera along its heading, facing it,
    and the robot's true range (m) and bearing (rad) from our origin. Seen square on, the
    box's bottom centre is the middle of the robot's front bottom edge, ``HALF_DEPTH`` in
    front of its centre."""
    heading = state.head_yaw
    centre = state.position[:2] + distance * np.array([math.cos(heading), math.sin(heading)])
    box = robot_box(centre, heading, state)
    return box, float(np.hypot(*centre)), math.atan2(centre[1], centre[0])


def detection(box: np.ndarray, score: float = 0.8, name: str = "robot") -> Detection:
    """A CNN detection of class ``name`` with ``box`` (4,) (the keypoint is not read)."""
    return Detection(class_name=name, class_id=0, box=box, score=score, keypoint=np.zeros(2))


# --- ground_point.py ------------------------------------------------------------------------


@pytest.mark.parametrize("state", STATES)
def test_ground_point_recovers_projected_ground_points(state: CameraState) -> None:
    rng = np.random.default_rng(0)
    checked = 0
    for _ in range(200):
        distance = rng.uniform(0.3, 8.0)
        heading = state.head_yaw + rng.uniform(-0.45, 0.45)
        point = np.array([distance * math.cos(heading), distance * math.sin(heading), 0.0])
        pixel = project(point + np.array([*state.position[:2], 0.0]), state)[0]
        if not (0 <= pixel[0] <= CAMERA.width - 1 and 0 <= pixel[1] <= CAMERA.height - 1):
            continue
        truth = point[:2] + state.position[:2]
        found = ground_point(pixel, CAMERA, state)
        assert found is not None
        xy = found[0] * np.array([math.cos(found[1]), math.sin(found[1])])
        assert np.linalg.norm(xy - truth) < 1e-6  # far below the 1 mm asked
        checked += 1
    assert checked > 50


def test_height_point_recovers_points_on_planes_above_and_below_the_camera() -> None:
    state = STATES[1]
    for height in (0.0, 0.28, 0.45, 0.8):
        point = state.position + np.array([1.2, 0.9, 0.0])
        point[2] = height
        found = height_point(project(point, state)[0], height, CAMERA, state)
        assert found is not None
        assert found[0] == pytest.approx(np.hypot(*point[:2]), abs=1e-6)
        assert found[1] == pytest.approx(math.atan2(point[1], point[0]), abs=1e-9)


def test_beyond_moves_the_point_along_the_horizontal_heading_from_the_camera() -> None:
    state = STATES[1]
    point = state.position[:2] + np.array([1.5, 0.5])
    pixel = project(np.array([*point, 0.0]), state)[0]
    found = ground_point(pixel, CAMERA, state, beyond_m=0.1)
    assert found is not None
    heading = (point - state.position[:2]) / np.linalg.norm(point - state.position[:2])
    truth = point + 0.1 * heading
    assert found[0] == pytest.approx(np.hypot(*truth), abs=1e-9)
    assert found[1] == pytest.approx(math.atan2(truth[1], truth[0]), abs=1e-9)


def test_pixels_above_the_horizon_have_no_ground_point() -> None:
    level = CameraState(position=np.array([0.05, 0.0, 0.52]), head_yaw=0.3, head_pitch=0.0)
    assert ground_point(np.array([160.0, 100.0]), CAMERA, level) is None  # above the centre
    assert ground_point(np.array([160.0, 120.0]), CAMERA, level) is None  # on the horizon
    assert ground_point(np.array([160.0, 121.0]), CAMERA, level) is not None
    # a plane above the camera is seen above the horizon only
    assert height_point(np.array([160.0, 130.0]), 0.6, CAMERA, level) is None
    assert height_point(np.array([160.0, 100.0]), 0.6, CAMERA, level) is not None
    # no covariance where a displaced pixel crosses the horizon
    assert range_bearing_cov(np.array([160.0, 120.1]), CAMERA, level, 1.0) is None


def test_pixel_ray_is_a_unit_robot_frame_ray() -> None:
    state = STATES[0]
    ray = pixel_ray(np.array([CAMERA.cx, CAMERA.cy]), CAMERA, state)
    assert ray == pytest.approx(state.rotation()[:, 0])
    assert np.linalg.norm(ray) == pytest.approx(1.0)


@pytest.mark.parametrize("pitch", [0.0, 0.2, 0.4])
def test_range_variance_matches_the_closed_form_derivative_and_grows_with_range(
    pitch: float,
) -> None:
    """Camera at the origin, height h, looking along x pitched down by p: a ground point on
    the centre column at row v lies at d = h / tan(p + atan((v - cy) / fy)), so
    dd/dv = -h / sin(theta)^2 * fy / (fy^2 + (v - cy)^2)."""
    h, std = 0.52, 1.5
    state = CameraState(position=np.array([0.0, 0.0, h]), head_yaw=0.0, head_pitch=pitch)
    fy, cy = CAMERA.fy, CAMERA.cy
    variances = []
    for distance in (0.6, 1.0, 2.0, 3.0, 5.0, 8.0):
        theta = math.atan(h / distance)
        v = cy + fy * math.tan(theta - pitch)
        if not 0 <= v <= CAMERA.height - 1:
            continue
        slope = h / math.sin(theta) ** 2 * fy / (fy**2 + (v - cy) ** 2)
        cov = range_bearing_cov(np.array([CAMERA.cx, v]), CAMERA, state, std)
        assert cov is not None
        assert cov[0, 0] == pytest.approx((slope * std) ** 2, rel=1e-3)  # O(step^2) differences
        assert abs(cov[0, 1]) < 1e-12 * math.sqrt(cov[0, 0] * cov[1, 1])  # u moves no range
        # on the centre column a pixel across turns the ray's azimuth by cos(a) / (fx cos(theta))
        # with a = theta - p the ray's angle below the optical axis
        bearing_slope = math.cos(theta - pitch) / (CAMERA.fx * math.cos(theta))
        assert cov[1, 1] == pytest.approx((std * bearing_slope) ** 2, rel=1e-3)
        variances.append(cov[0, 0])
    assert len(variances) >= 3
    assert np.all(np.diff(variances) > 0)


def test_covariance_takes_one_std_per_image_axis() -> None:
    state = STATES[0]
    pixel = np.array([180.0, 190.0])
    both = range_bearing_cov(pixel, CAMERA, state, 2.0)
    u_only = range_bearing_cov(pixel, CAMERA, state, [2.0, 0.0])
    v_only = range_bearing_cov(pixel, CAMERA, state, np.array([0.0, 2.0]))
    assert both is not None and u_only is not None and v_only is not None
    assert both == pytest.approx(u_only + v_only, rel=1e-12)
    assert np.linalg.eigvalsh(both).min() > 0
    np.testing.assert_array_equal(both, both.T)
    assert JACOBIAN_STEP_PX > 0


# --- cnn_robots.py: sightings -----------------------------------------------------------------


@pytest.mark.parametrize(
    ("state", "distance"),
    [(state, d) for state in STATES for d in (1.7, 3.0, 5.0)]
    + [(STATES[0], 1.2), (STATES[1], 0.9), (STATES[1], 1.2)],
)
def test_box_bottom_recovers_range_and_bearing_of_a_facing_robot(
    state: CameraState, distance: float
) -> None:
    box, true_range, true_bearing = facing_robot(distance, state)
    assert not box_bottom_cut(box, CAMERA, CONFIG)  # feet in view
    (sighting,) = robot_sightings([detection(box)], CAMERA, state, CONFIG)
    assert sighting.range_m == pytest.approx(true_range, abs=1e-3)
    assert abs(wrap_angle(sighting.bearing_rad - true_bearing)) < 1e-6
    assert abs(sighting.range_m - true_range) < 1e-6  # exact, not merely within 1 mm
    assert sighting.team is None and not sighting.sonar_confirmed
    assert sighting.score == 0.8
    np.testing.assert_array_equal(sighting.box, box)
    std = math.hypot(CONFIG.pixel_std_px, CONFIG.pixel_std_per_height * (box[3] - box[1]))
    pixel = np.array([(box[0] + box[2]) / 2, box[3]])
    expected = range_bearing_cov(pixel, CAMERA, state, std, 0.0, CONFIG.centre_beyond_m)
    assert expected is not None
    np.testing.assert_allclose(sighting.cov, expected, rtol=1e-12)
    assert np.linalg.eigvalsh(sighting.cov).min() > 0


def test_sighting_covariance_grows_with_range() -> None:
    state = STATES[0]
    covs = []
    for distance in (1.3, 2.0, 3.0, 4.5, 6.0):
        box, _, _ = facing_robot(distance, state)
        (sighting,) = robot_sightings([detection(box)], CAMERA, state, CONFIG)
        covs.append(sighting.cov)
    assert np.all(np.diff([c[0, 0] for c in covs]) > 0)
    # relative range std: a few per cent at a few metres with the default pixel noise
    assert 0.005 < math.sqrt(covs[2][0, 0]) / 3.0 < 0.1


def test_boxes_cut_by_the_image_bottom_are_dropped() -> None:
    state = STATES[0]  # pitched 0.22 rad down: feet out of view nearer than about 0.75 m
    box, _, _ = facing_robot(0.6, state)
    assert box[3] > CAMERA.height - 1
    clipped = box.copy()
    clipped[3] = CAMERA.height - 1.0  # the box the CNN gives: cut at the last row
    assert box_bottom_cut(clipped, CAMERA, CONFIG)
    assert robot_sightings([detection(clipped)], CAMERA, state, CONFIG) == ()
    # within the margin: dropped; just above it: kept
    margin = CONFIG.border_margin_px
    for bottom, kept in ((CAMERA.height - 0.5 - margin + 0.1, 0), (CAMERA.height - margin - 1, 1)):
        moved = np.array([140.0, 20.0, 180.0, bottom])
        assert len(robot_sightings([detection(moved)], CAMERA, state, CONFIG)) == kept
    wide_margin = dataclasses.replace(CONFIG, border_margin_px=80.0)
    box, _, _ = facing_robot(1.3, state)
    assert robot_sightings([detection(box)], CAMERA, state, CONFIG)
    assert robot_sightings([detection(box)], CAMERA, state, wide_margin) == ()


@pytest.mark.parametrize("distance", [0.5, 0.6, 1.0, 2.5])
def test_waistband_row_gives_the_range_of_a_robot_with_its_feet_cut(distance: float) -> None:
    """Seed 004 §6.2's cut-bottom model: the waistband's front centre, at the known height of
    a standing robot's waistband, seen at its image row."""
    state = STATES[0]
    box, true_range, true_bearing = facing_robot(distance, state)
    heading = np.array([math.cos(state.head_yaw), math.sin(state.head_yaw)])
    front = state.position[:2] + (distance - HALF_DEPTH) * heading
    row = project(np.array([*front, CONFIG.waistband_height_m]), state)[0, 1]
    assert 0 <= row <= CAMERA.height - 1
    clipped = np.minimum(box, [CAMERA.width - 1, CAMERA.height - 1] * 2)
    sighting = waistband_sighting(clipped, row, CAMERA, state, CONFIG, score=0.6)
    assert sighting is not None
    assert abs(sighting.range_m - true_range) < 1e-6
    assert abs(wrap_angle(sighting.bearing_rad - true_bearing)) < 1e-6
    assert sighting.team is None and sighting.score == 0.6
    assert np.linalg.eigvalsh(sighting.cov).min() > 0
    # a camera below the waistband sees it above the horizon only
    low = CameraState(position=np.array([0.05, 0.0, 0.2]), head_yaw=0.0, head_pitch=0.0)
    assert waistband_sighting(clipped, 140.0, CAMERA, low, CONFIG) is None
    assert waistband_sighting(clipped, 100.0, CAMERA, low, CONFIG) is not None


def test_boxes_too_wide_for_one_robot_are_dropped() -> None:
    state = STATES[0]
    box, _, _ = facing_robot(2.0, state)
    centre_u, half = (box[0] + box[2]) / 2, (box[2] - box[0]) / 2
    wide = np.array([centre_u - 2 * half, box[1], centre_u + 2 * half, box[3]])  # 0.54 m
    assert len(robot_sightings([detection(box)], CAMERA, state, CONFIG)) == 1
    assert robot_sightings([detection(wide)], CAMERA, state, CONFIG) == ()
    roomy = dataclasses.replace(CONFIG, max_width_m=0.6)
    assert len(robot_sightings([detection(wide)], CAMERA, state, roomy)) == 1


def test_only_robot_detections_at_or_above_the_threshold_are_sighted() -> None:
    state = STATES[0]
    boxes = [facing_robot(d, state)[0] for d in (1.5, 2.5, 3.5)]
    threshold = CONFIG.score_threshold
    detections = [
        detection(boxes[0], score=threshold - 1e-3),
        detection(boxes[1], score=threshold),
        detection(boxes[2], score=0.9, name="ball"),
        detection(boxes[2], score=0.95),
    ]
    found = robot_sightings(detections, CAMERA, state, CONFIG)
    assert [s.score for s in found] == [threshold, 0.95]  # in the detections' order
    assert robot_sightings([], CAMERA, state, CONFIG) == ()
    stricter = dataclasses.replace(CONFIG, score_threshold=0.9)
    assert [s.score for s in robot_sightings(detections, CAMERA, state, stricter)] == [0.95]


def test_boxes_with_the_bottom_above_the_horizon_or_degenerate_give_nothing() -> None:
    level = CameraState(position=np.array([0.05, 0.0, 0.52]), head_yaw=0.0, head_pitch=0.0)
    floating = np.array([150.0, 40.0, 170.0, 110.0])  # bottom above the horizon (row 120)
    flat = np.array([150.0, 150.0, 150.0, 180.0])  # no width
    upside_down = np.array([150.0, 180.0, 170.0, 150.0])
    for box in (floating, flat, upside_down):
        assert robot_sightings([detection(box)], CAMERA, level, CONFIG) == ()


# --- bad input --------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("field", "value", "error"),
    [
        ("score_threshold", 0.0, ValueError),
        ("score_threshold", 1.0, ValueError),
        ("score_threshold", 1, InvalidTypeError),
        ("score_threshold", math.nan, ValueError),
        ("pixel_std_px", 0.0, ValueError),
        ("pixel_std_px", -1.0, ValueError),
        ("pixel_std_per_height", -0.1, ValueError),
        ("pixel_std_per_height", math.inf, ValueError),
        ("border_margin_px", -1.0, ValueError),
        ("centre_beyond_m", -0.01, ValueError),
        ("centre_beyond_m", True, InvalidTypeError),
        ("max_width_m", 0.0, ValueError),
        ("waistband_height_m", 0.0, ValueError),
        ("waistband_height_m", "0.28", InvalidTypeError),
    ],
)
def test_config_rejects_bad_values(field: str, value: object, error: type[Exception]) -> None:
    with pytest.raises(error, match=f"CnnRobotConfig.{field}"):
        CnnRobotConfig(**{field: value})  # type: ignore[arg-type]


def test_config_defaults_cite_the_nao_body() -> None:
    config = CnnRobotConfig()
    assert config.waistband_height_m == 0.28  # spl_env/robots/nao.py _body_parts
    assert 0.045 <= config.centre_beyond_m <= 0.085  # the nearest foot's edge, by the turn
    with pytest.raises(dataclasses.FrozenInstanceError):
        config.score_threshold = 0.5  # type: ignore[misc]


def test_bad_boxes_and_pixels_raise() -> None:
    state = STATES[0]
    for box in (np.array([1.0, 2.0, 3.0]), np.array([1.0, 2.0, np.nan, 4.0])):
        with pytest.raises(ValueError, match=r"detections\[0\].box"):
            robot_sightings([detection(box)], CAMERA, state, CONFIG)
    # a bad box of another class or below the threshold is not read
    bad = np.array([np.nan] * 4)
    assert robot_sightings([detection(bad, name="ball")], CAMERA, state, CONFIG) == ()
    assert robot_sightings([detection(bad, score=0.1)], CAMERA, state, CONFIG) == ()
    with pytest.raises(ValueError, match="pixel"):
        ground_point(np.array([1.0, 2.0, 3.0]), CAMERA, state)
    with pytest.raises(ValueError, match="pixel"):
        ground_point(np.array([np.inf, 2.0]), CAMERA, state)
    with pytest.raises(ValueError, match="height_m"):
        height_point(np.array([1.0, 2.0]), math.nan, CAMERA, state)
    with pytest.raises(ValueError, match="pixel_std_px"):
        range_bearing_cov(np.array([160.0, 200.0]), CAMERA, state, -1.0)
    with pytest.raises(ValueError, match="pixel_std_px"):
        range_bearing_cov(np.array([160.0, 200.0]), CAMERA, state, [1.0, -1.0])
    with pytest.raises(ValueError, match="pixel_std_px"):
        range_bearing_cov(np.array([160.0, 200.0]), CAMERA, state, [1.0, 2.0, 3.0])
    with pytest.raises(ValueError, match="box"):
        waistband_sighting(np.array([1.0, 2.0]), 100.0, CAMERA, state, CONFIG)
