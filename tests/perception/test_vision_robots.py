"""Robot detection from field-edge indents (seed 004 §6.2) on synthetic images.

The images are drawn with numpy and OpenCV: green carpet up to a far edge on the ground, a
plain board behind it, white field lines, and Nao-shaped robots (grey legs, arms and head, a
team-coloured jersey and a darker waistband) built from 3-D boxes whose corners are projected
through :func:`perception.geometry.project_points` from a known camera state. So each robot's
range and bearing (robot frame, to its centre) are known exactly.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import cv2
import numpy as np
import pytest

from perception.geometry import FloatArray, pixel_rays, project_points, ray_ground_intersection
from perception.types import CameraModel, CameraState
from perception.validation import InvalidTypeError
from perception.vision.robots import RobotDetector, RobotDetectorConfig

CAMERA = CameraModel()
STATE = CameraState(
    position=np.array([0.06, 0.0, 0.50]), head_yaw=0.0, head_pitch=0.22, tilt=math.radians(1.2)
)
CARPET_EDGE_M = 6.0  # the carpet ends this far ahead (robot frame x)
RGB = {
    "carpet": (41, 122, 46),
    "board": (150, 140, 128),
    "white": (240, 240, 240),
    "grey": (150, 150, 155),
    "pink": (255, 82, 173),
    "pole_blue": (20, 77, 242),
    "jersey0": (31, 56, 204),
    "waistband0": (13, 26, 140),
    "jersey1": (217, 31, 26),
    "waistband1": (166, 13, 13),
}
# A standing Nao as the env builds it (spl_env.robots.nao): (half sizes, centre, colour) per part
NAO_PARTS: tuple[tuple[tuple[float, float, float], tuple[float, float, float], str], ...] = (
    ((0.045, 0.035, 0.13), (0.0, -0.05, 0.13), "grey"),
    ((0.045, 0.035, 0.13), (0.0, 0.05, 0.13), "grey"),
    ((0.055, 0.085, 0.02), (0.0, 0.0, 0.28), "waistband"),
    ((0.05, 0.08, 0.07), (0.0, 0.0, 0.37), "jersey"),
    ((0.03, 0.025, 0.1), (0.0, -0.11, 0.34), "grey"),
    ((0.03, 0.025, 0.1), (0.0, 0.11, 0.34), "grey"),
    ((0.05, 0.065, 0.03), (0.0, 0.0, 0.502), "grey"),
)


@dataclass(frozen=True)
class Robot:
    """A robot to draw: centre ``(x, y)`` (m, robot frame of the camera state), heading (rad)."""

    x: float
    y: float
    team: int
    heading: float = math.pi  # facing the camera

    @property
    def range_bearing(self) -> tuple[float, float]:
        return math.hypot(self.x, self.y), math.atan2(self.y, self.x)


def _box_corners(
    half: tuple[float, float, float],
    centre: tuple[float, float, float],
    x: float,
    y: float,
    yaw: float,
) -> FloatArray:
    """(8, 3) corners of a box with ``half`` sizes at ``centre`` in a body at (x, y, yaw)."""
    c, s = math.cos(yaw), math.sin(yaw)
    local = np.array(
        [
            (centre[0] + sx * half[0], centre[1] + sy * half[1], centre[2] + sz * half[2])
            for sx in (-1, 1)
            for sy in (-1, 1)
            for sz in (-1, 1)
        ]
    )
    return np.column_stack(
        [x + c * local[:, 0] - s * local[:, 1], y + s * local[:, 0] + c * local[:, 1], local[:, 2]]
    )


def _fill(image: np.ndarray, corners: FloatArray, state: CameraState, colour: str) -> None:
    """Paint the projection of the convex solid with (N, 3) robot-frame ``corners``."""
    cam = (corners - state.position) @ state.rotation()
    if (cam[:, 0] <= 0.02).any():  # too close: not drawn
        return
    uv, _ = project_points(cam, CAMERA.fx, CAMERA.fy, CAMERA.cx, CAMERA.cy)
    hull = cv2.convexHull(np.round(uv * 16).astype(np.int32))
    cv2.fillConvexPoly(image, hull, RGB[colour], lineType=cv2.LINE_8, shift=4)


def draw(
    robots: list[Robot] = (),  # type: ignore[assignment]
    *,
    state: CameraState = STATE,
    lines: list[tuple[float, float, float, float]] = (),  # type: ignore[assignment]
    solids: list[tuple[FloatArray, str]] = (),  # type: ignore[assignment]
    noise: float = 2.0,
    seed: int = 0,
) -> np.ndarray:
    """A (H, W, 3) uint8 RGB frame: board, carpet up to ``CARPET_EDGE_M``, white ``lines``
    (x0, y0, x1, y1) on the ground 0.05 m wide, ``solids`` ((N, 3) corners, colour) and the
    ``robots``, painted far to near, plus Gaussian noise."""
    h, w = CAMERA.height, CAMERA.width
    image = np.empty((h, w, 3), np.uint8)
    image[:] = RGB["board"]
    v, u = np.mgrid[0:h, 0:w]
    rays = pixel_rays(
        np.column_stack([u.ravel(), v.ravel()]), CAMERA.fx, CAMERA.fy, CAMERA.cx, CAMERA.cy
    )
    xy, hits = ray_ground_intersection(state.position, rays @ state.rotation().T)
    carpet = hits & (xy[:, 0] < CARPET_EDGE_M) & (np.abs(xy[:, 1]) < 4.0)
    image[carpet.reshape(h, w)] = RGB["carpet"]
    for x0, y0, x1, y1 in lines:
        yaw = math.atan2(y1 - y0, x1 - x0)
        half = (math.hypot(x1 - x0, y1 - y0) / 2, 0.025, 0.0005)
        corners = _box_corners(half, (0.0, 0.0, 0.0005), (x0 + x1) / 2, (y0 + y1) / 2, yaw)
        _fill(image, corners, state, "white")
    items = [(c, colour) for c, colour in solids]
    for robot in robots:
        for half, centre, part in NAO_PARTS:
            colour = f"{part}{robot.team}" if part in ("jersey", "waistband") else part
            items.append((_box_corners(half, centre, robot.x, robot.y, robot.heading), colour))
    distance = [float(np.linalg.norm(c.mean(axis=0) - state.position)) for c, _ in items]
    for k in np.argsort(distance)[::-1]:
        _fill(image, items[k][0], state, items[k][1])
    if noise > 0:
        rng = np.random.default_rng(seed)
        image = np.clip(image + rng.normal(0.0, noise, image.shape), 0, 255).astype(np.uint8)
    return image


def _cylinder(radius: float, z0: float, z1: float, x: float, y: float) -> FloatArray:
    """(32, 3) corners of a 16-sided prism standing for a cylinder at (x, y) from z0 to z1."""
    angles = np.linspace(0.0, 2 * math.pi, 16, endpoint=False)
    ring = np.column_stack([x + radius * np.cos(angles), y + radius * np.sin(angles)])
    return np.vstack([np.column_stack([ring, np.full(16, z)]) for z in (z0, z1)])


def post(x: float, y: float, bands: tuple[str, ...] = ()) -> list[tuple[FloatArray, str]]:
    """A white post 0.1 m thick and 0.8 m tall at (x, y): with colour ``bands`` 0.2 m tall
    from 0.4 m up a landmark pole, else a goal post."""
    solids = [(_cylinder(0.05, 0.0, 0.4 if bands else 0.8, x, y), "white")]
    for k, colour in enumerate(bands):
        solids.append((_cylinder(0.05, 0.4 + 0.2 * k, 0.6 + 0.2 * k, x, y), colour))
    return solids


@pytest.fixture(scope="module")
def detector() -> RobotDetector:
    return RobotDetector(RobotDetectorConfig(), CAMERA)


def _bearing_error(a: float, b: float) -> float:
    return abs((a - b + math.pi) % (2 * math.pi) - math.pi)


@pytest.mark.parametrize(
    ("x", "y", "team", "heading"),
    [
        (0.9, 0.15, 0, math.pi),
        (1.5, -0.3, 1, math.pi),
        (2.0, 0.5, 0, 2.0),
        (2.6, -0.6, 1, -1.2),
        (3.0, 0.2, 0, math.pi / 2),  # side-on
        (4.0, -0.4, 1, math.pi),
    ],
)
def test_finds_a_robot_with_its_team_range_and_bearing(
    detector: RobotDetector, x: float, y: float, team: int, heading: float
) -> None:
    robot = Robot(x, y, team, heading)
    sightings = detector.detect(draw([robot]), STATE)
    assert len(sightings) == 1
    s = sightings[0]
    true_range, true_bearing = robot.range_bearing
    assert s.team == team
    assert abs(s.range_m - true_range) < 0.04 * true_range
    assert _bearing_error(s.bearing_rad, true_bearing) < math.radians(1.0)
    assert s.cov.shape == (2, 2)
    assert np.all(np.linalg.eigvalsh(s.cov) > 0)
    u0, v0, u1, v1 = s.box
    assert u0 < u1 and v0 < v1


def test_several_robots_left_to_right(detector: RobotDetector) -> None:
    robots = [Robot(1.2, 0.4, 1), Robot(2.5, 0.0, 0), Robot(1.8, -0.7, 0, 2.5)]
    sightings = detector.detect(draw(robots), STATE)
    assert len(sightings) == 3
    bearings = [s.bearing_rad for s in sightings]
    assert bearings == sorted(bearings, reverse=True)  # image columns grow to the right
    for s, robot in zip(sightings, sorted(robots, key=lambda r: -r.range_bearing[1]), strict=True):
        assert s.team == robot.team
        assert abs(s.range_m - robot.range_bearing[0]) < 0.05 * robot.range_bearing[0]


def test_robots_overlapping_at_different_ranges_are_split(detector: RobotDetector) -> None:
    near, far = Robot(1.3, 0.0, 1), Robot(2.4, 0.45, 0)
    sightings = detector.detect(draw([near, far]), STATE)
    found = sorted((round(s.range_m, 1), s.team) for s in sightings)
    assert len(sightings) == 2, found
    for s in sightings:
        robot = near if s.team == 1 else far
        assert abs(s.range_m - robot.range_bearing[0]) < 0.05 * robot.range_bearing[0]


def test_no_robot_on_plain_carpet_with_white_lines(detector: RobotDetector) -> None:
    edge = CARPET_EDGE_M - 0.7  # the outer lines lie 0.7 m inside the carpet's edge
    lines = [
        (1.5, -3.0, 1.5, 3.0),  # across the view, near
        (4.0, -3.0, 4.0, 3.0),  # across the view, far
        (0.0, 0.4, edge, 0.4),  # along the view
        (0.5, -2.0, edge, 0.8),  # slanted
        (edge, -3.0, edge, 3.0),  # the outer line
    ]
    assert detector.detect(draw(lines=lines), STATE) == []
    assert detector.detect(draw(), STATE) == []


def test_robot_standing_on_a_line_is_still_found(detector: RobotDetector) -> None:
    robot = Robot(2.0, 0.1, 1)
    image = draw([robot], lines=[(robot.x, -3.0, robot.x, 3.0), (0.0, 0.1, 5.3, 0.1)])
    sightings = detector.detect(image, STATE)
    assert len(sightings) == 1
    assert sightings[0].team == 1
    assert abs(sightings[0].range_m - robot.range_bearing[0]) < 0.06 * robot.range_bearing[0]


def test_goal_post_and_landmark_pole_are_no_robots(detector: RobotDetector) -> None:
    image = draw(solids=post(3.0, 0.6) + post(2.5, -0.7, ("pink", "pole_blue")))
    candidates = detector.candidates(image, STATE)
    assert len(candidates) == 2  # both cut indents into the carpet's edge
    assert all(c.sighting is None for c in candidates)
    assert {c.rejected for c in candidates} <= {"too_narrow", "narrow_m", "pole", "post"}


def test_robot_cut_at_the_image_bottom_is_ranged_by_its_waistband(detector: RobotDetector) -> None:
    state = replace(STATE, head_pitch=0.05)  # looking ahead: the near robot's feet are cut off
    robot = Robot(0.7, -0.05, 0)
    candidates = detector.candidates(draw([robot], state=state), state)
    kept = [c for c in candidates if c.sighting is not None]
    assert len(kept) == 1
    c = kept[0]
    assert c.cut
    assert c.team == 0
    assert c.base[1] < CAMERA.height - 10  # ranged at the waistband, above the image bottom
    true_range, true_bearing = robot.range_bearing
    assert c.sighting is not None
    assert abs(c.sighting.range_m - true_range) < 0.06 * true_range
    assert _bearing_error(c.sighting.bearing_rad, true_bearing) < math.radians(2.0)


def test_robot_cut_at_the_bottom_without_waistband_keeps_its_base(detector: RobotDetector) -> None:
    state = replace(STATE, head_pitch=0.05)
    robot = Robot(0.7, -0.05, 0)
    image = draw([robot], state=state)
    grey = np.array(RGB["grey"], np.uint8)
    jersey = cv2.inRange(image, np.array([0, 0, 100], np.uint8), np.array([90, 110, 255], np.uint8))
    image[jersey > 0] = grey  # no team colour left
    kept = [c for c in detector.candidates(image, state) if c.sighting is not None]
    assert len(kept) == 1
    assert kept[0].cut and kept[0].team is None
    assert kept[0].base[1] > CAMERA.height - 2  # the image bottom: a lower bound on range
    assert kept[0].sighting is not None
    assert kept[0].sighting.range_m > robot.range_bearing[0]


def test_robot_in_a_window_glare_is_found(detector: RobotDetector) -> None:
    glare = np.linspace(0.0, 0.5, CAMERA.width)[None, :, None]  # washed out to the right

    def washed(image: np.ndarray) -> np.ndarray:
        return np.clip(image * (1 - glare) + 255 * glare, 0, 255).astype(np.uint8)

    robot = Robot(2.0, -0.5, 1)
    image = washed(draw([robot]))
    hsv = cv2.cvtColor(image, cv2.COLOR_RGB2HSV)
    assert hsv[-1, -1, 1] < RobotDetectorConfig().green_hsv[0][1]  # the carpet: below the floor
    assert detector.detect(washed(draw()), STATE) == []
    sightings = detector.detect(image, STATE)
    assert len(sightings) == 1
    assert sightings[0].team == 1
    assert abs(sightings[0].range_m - robot.range_bearing[0]) < 0.05 * robot.range_bearing[0]


def test_covariance_grows_with_range(detector: RobotDetector) -> None:
    near = detector.detect(draw([Robot(1.0, 0.0, 0)]), STATE)[0]
    far = detector.detect(draw([Robot(3.5, 0.0, 0)]), STATE)[0]
    assert far.cov[0, 0] > 4 * near.cov[0, 0]
    np.testing.assert_allclose(near.cov, near.cov.T)


def test_field_boundary_follows_the_carpet_edge_and_bridges_a_robot(
    detector: RobotDetector,
) -> None:
    plain = detector.field_boundary(draw(), STATE)
    with_robot = detector.field_boundary(draw([Robot(2.0, 0.0, 1)]), STATE)
    np.testing.assert_allclose(with_robot.smooth, plain.smooth, atol=1.5)
    assert (with_robot.raw > plain.raw + 10).any()  # the raw edge dips to the robot's feet
    assert plain.columns[0] == detector.config.column_step_px // 2


def test_looking_at_the_boards_finds_nothing(detector: RobotDetector) -> None:
    state = replace(STATE, head_pitch=-0.6)  # above the horizon: no carpet in view
    image = draw([Robot(2.0, 0.0, 0)], state=state)
    assert detector.detect(image, state) == []


def test_image_of_the_wrong_size_is_refused(detector: RobotDetector) -> None:
    with pytest.raises(ValueError, match="image must be"):
        detector.detect(np.zeros((10, 10, 3), np.uint8), STATE)
    with pytest.raises(ValueError, match="image must be"):
        detector.detect(np.zeros((CAMERA.height, CAMERA.width, 3), np.float32), STATE)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("green_hsv", ((52, 80, 30), (180, 255, 255))),
        ("green_hsv", ((60, 80, 30), (50, 255, 255))),
        ("green_hsv", ((52.0, 80, 30), (72, 255, 255))),
        ("team_hsv", ((((113, 80, 30), (122, 255, 255)),),)),
        ("team_hsv", ((), (((0, 80, 30), (8, 255, 255)),))),
        ("column_step_px", 0),
        ("column_step_px", 1.5),
        ("median_columns", 4),
        ("min_indent_px", 0),
        ("width_ratio", (2.0, 0.4)),
        ("width_ratio", (0.0, 2.0)),
        ("shrink_green_fraction", 0.0),
        ("shrink_green_fraction", 1.5),
        ("robot_width_m", -0.2),
        ("pixel_std_px", 0.0),
        ("min_width_m", math.nan),
        ("team_search_heights_m", (0.5, 0.1)),
        ("waistband_bottom_m", 0.6),
        ("bottom_margin_px", -1),
    ],
)
def test_config_validation(field: str, value: object) -> None:
    with pytest.raises(ValueError, match=field):
        RobotDetectorConfig(**{field: value})


def test_config_rejects_wrong_types() -> None:
    with pytest.raises(InvalidTypeError):
        RobotDetectorConfig(column_step_px=True)  # type: ignore[arg-type]
    with pytest.raises(InvalidTypeError):
        RobotDetectorConfig(pixel_std_px="1")  # type: ignore[arg-type]


def test_a_near_pole_seen_steeply_from_above_is_still_a_pole(detector: RobotDetector) -> None:
    # Pitched 0.6 rad down, the camera sees the carpet up to the image top; a landmark pole
    # 0.5 m ahead cuts an indent whose band search height (1.2 m) lies behind the camera, so
    # the search starts at the image top (the env once raised OverflowError on such a frame).
    steep = CameraState(
        position=np.array([0.06, 0.0, 0.50]), head_yaw=0.0, head_pitch=0.6, tilt=math.radians(1.2)
    )
    image = draw(solids=post(0.5, 0.0, ("pink", "pole_blue")), state=steep)
    (candidate,) = detector.candidates(image, steep)
    assert candidate.box[1] < 0 and candidate.rejected == "pole"


def test_box_shrinking_helpers_match_np_percentile_and_the_shrinking_loops() -> None:
    """The upper quartile equals ``np.percentile(..., 75)``; the shrink helpers stop where
    the one-row-at-a-time loops of Algorithm 2's line 3 stop."""
    from perception.vision.robots import _first_below, _last_below, _upper_quartile

    rng = np.random.default_rng(3)
    for _ in range(500):
        widths = rng.integers(0, 200, size=int(rng.integers(1, 60)))
        assert _upper_quartile(widths) == float(np.percentile(widths, 75))
        shares = rng.choice([0.2, 0.5, 0.9, 1.0], size=int(rng.integers(2, 30)))
        low, high = 0, len(shares) - 1
        bottom = high
        while bottom > low and shares[bottom] >= 0.7:
            bottom -= 1
        assert _last_below(shares, 0.7, low, high) == bottom
        left = low
        while left < high and shares[left] >= 0.7:
            left += 1
        assert _first_below(shares, 0.7, low, high) == left
