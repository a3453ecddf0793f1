"""Colour-filter pole detector on synthetic images: poles painted with OpenCV from their geometry.

Each pole part (white base, two colour bands) is a solid cylinder section, so its image is the
convex hull of the projections of its top and bottom circles; parts are painted so that the one
nearer the camera's height wins where they overlap, as in a real view. Range and bearing are
then checked against the pole's placed position, which the painter never derives from pixels.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any

import cv2
import numpy as np
import pytest
from numpy.typing import NDArray

from perception.geometry import FloatArray, project_points
from perception.types import CameraModel, CameraState, PoleCode, PoleGeometry
from perception.vision import ColourFilterConfig, ColourPoleDetector

CAMERA = CameraModel()
POLE = PoleGeometry()
PARTNERS = ("yellow", "green", "blue")
CODES = tuple(  # as the scene's layout: pink over a colour, then the colours over pink
    [PoleCode(landmark_id=i, top="pink", bottom=c) for i, c in enumerate(PARTNERS)]
    + [PoleCode(landmark_id=3 + i, top=c, bottom="pink") for i, c in enumerate(PARTNERS)]
)
PAINT = {  # RGB paint, about the scene's pole colours
    "pink": (255, 82, 173),
    "yellow": (250, 219, 20),
    "blue": (20, 77, 242),
    "green": (0, 209, 133),
    "white": (235, 235, 235),
}
CARPET = (41, 122, 46)
GREY = (60, 60, 60)  # neither a band colour nor white (too dark)
Rgb = tuple[int, int, int]


def camera_state(yaw: float = 0.0, pitch: float = 0.0) -> CameraState:
    """A standing Nao's top camera, about 0.52 m high, with head ``yaw``/``pitch`` (rad)."""
    return CameraState(
        position=np.array([0.06, 0.0, 0.52]), head_yaw=yaw, head_pitch=pitch, tilt=math.radians(1.2)
    )


def blank(colour: Rgb = CARPET) -> NDArray[np.uint8]:
    """An (H, W, 3) uint8 image of one colour."""
    return np.full((CAMERA.height, CAMERA.width, 3), colour, dtype=np.uint8)


def pole_parts(
    code: PoleCode, *, base: Rgb | None = None, bottom: Rgb | None = None
) -> list[tuple[float, float, Rgb]]:
    """(z0, z1, rgb) of a pole's base and bands; ``base``/``bottom`` repaint those parts."""
    g = POLE
    return [
        (0.0, g.base_top_m, base or PAINT["white"]),
        (g.base_top_m, g.base_top_m + g.band_height_m, bottom or PAINT[code.bottom]),
        (g.base_top_m + g.band_height_m, g.top_m, PAINT[code.top]),
    ]


def part_outline(state: CameraState, xy: FloatArray, z0: float, z1: float) -> FloatArray:
    """Pixels (128, 2) of the top and bottom circles of the cylinder section z0..z1 at ``xy``."""
    theta = np.linspace(0.0, 2 * math.pi, 64, endpoint=False)
    ring = np.asarray(xy) + POLE.radius_m * np.column_stack([np.cos(theta), np.sin(theta)])
    points = np.vstack([np.column_stack([ring, np.full(64, z)]) for z in (z0, z1)])
    camera_frame = (points - state.position) @ state.rotation()
    uv, front = project_points(camera_frame, CAMERA.fx, CAMERA.fy, CAMERA.cx, CAMERA.cy)
    assert front.all(), "test setup: the pole must be in front of the camera"
    return uv


def paint_pole(
    image: NDArray[np.uint8],
    state: CameraState,
    xy: tuple[float, float],
    parts: list[tuple[float, float, Rgb]],
) -> None:
    """Paint the pole parts standing at robot-frame ``xy`` (m) into ``image`` in place."""
    height = state.position[2]
    for z0, z1, rgb in sorted(parts, key=lambda p: -abs(0.5 * (p[0] + p[1]) - height)):
        uv = part_outline(state, np.asarray(xy), z0, z1)
        # OpenCV puts pixel centres on integers, ours on half-integers; 4 fractional bits
        hull = cv2.convexHull(
            np.round(uv * 16).astype(np.int32)
        )  # OpenCV centres pixels on integers
        cv2.fillConvexPoly(image, hull, rgb, shift=4)


def in_view(state: CameraState, xy: tuple[float, float]) -> bool:
    """Whether the bands and the base's top 5 cm of a pole at ``xy`` lie inside the image."""
    uv = part_outline(state, np.asarray(xy), POLE.base_top_m - 0.05, POLE.top_m)
    return bool(np.all((uv >= 1) & (uv <= (CAMERA.width - 1, CAMERA.height - 1))))


def range_tolerance(distance_m: float) -> float:
    """Relative range tolerance: 1 % plus a 1 px error in the band centres' spacing.

    Band edges snap to pixel rows, so each centre may be off by up to half a pixel.
    """
    spacing_px = CAMERA.fy * POLE.band_height_m / distance_m
    return 0.01 + 1.0 / spacing_px


def noisy(image: NDArray[np.uint8], seed: int = 0) -> NDArray[np.uint8]:
    """``image`` with Gaussian sensor noise (std 2 levels)."""
    noise = np.random.default_rng(seed).normal(0.0, 2.0, image.shape)
    return np.clip(image + noise, 0, 255).astype(np.uint8)


@pytest.fixture(scope="module")
def detector() -> ColourPoleDetector:
    return ColourPoleDetector(ColourFilterConfig(), CAMERA, CODES, POLE)


def view(
    code: PoleCode,
    xy: tuple[float, float],
    state: CameraState,
    **repaint: Rgb,
) -> NDArray[np.uint8]:
    """A noisy image of one pole on carpet; ``repaint`` as in :func:`pole_parts`."""
    assert in_view(state, xy), "test setup: the pole must be fully in view"
    image = blank()
    paint_pole(image, state, xy, pole_parts(code, **repaint))
    return noisy(image)


@pytest.mark.parametrize(
    ("xy", "yaw", "pitch"),
    [
        ((2.0, 0.0), 0.0, 0.0),
        ((1.2, 0.3), 0.2, 0.05),
        ((3.5, -1.0), -0.25, -0.05),
        ((4.8, 0.8), 0.1, 0.0),
        ((2.93, 0.65), -0.2, 0.22),  # looking down: the pole leans in the image
        ((2.0, -1.9), -0.55, 0.25),
    ],
)
def test_recovers_id_range_and_bearing(
    detector: ColourPoleDetector,
    xy: tuple[float, float],
    yaw: float,
    pitch: float,
) -> None:
    state = camera_state(yaw, pitch)
    code = CODES[1]
    observations = detector.detect(view(code, xy, state), state)
    assert [o.landmark_id for o in observations] == [code.landmark_id]
    obs = observations[0]
    true_range, true_bearing = math.hypot(*xy), math.atan2(xy[1], xy[0])
    assert obs.range_m == pytest.approx(true_range, rel=range_tolerance(true_range))
    assert abs(obs.bearing_rad - true_bearing) < math.radians(1.0)
    u0, v0, u1, v1 = obs.box
    assert u0 <= obs.pixel[0] <= u1 and v0 <= obs.pixel[1] <= v1


@pytest.mark.parametrize("code", CODES, ids=lambda c: f"{c.top}-over-{c.bottom}")
def test_each_code_maps_to_its_id(detector: ColourPoleDetector, code: PoleCode) -> None:
    state = camera_state()
    observations = detector.detect(view(code, (2.5, 0.2), state), state)
    assert [o.landmark_id for o in observations] == [code.landmark_id]


def test_pink_without_partner_gives_nothing(detector: ColourPoleDetector) -> None:
    state = camera_state()
    image = view(CODES[0], (2.0, 0.0), state, bottom=PAINT["white"])  # pink on a white pole
    assert detector.detect(image, state) == []


@pytest.mark.parametrize("code", [CODES[0], CODES[3]], ids=["pink-top", "pink-bottom"])
def test_bands_without_white_base_give_nothing(
    detector: ColourPoleDetector,
    code: PoleCode,
) -> None:
    state = camera_state()
    assert detector.detect(view(code, (2.0, 0.0), state, base=GREY), state) == []


@pytest.mark.parametrize(("lift_m", "found"), [(0.3, []), (0.0, [0])])
def test_pole_at_the_wrong_height_gives_nothing(
    detector: ColourPoleDetector,
    lift_m: float,
    found: list[int],
) -> None:
    """A pole raised 0.3 m (as if printed on a board) shows its bands too high for its size."""
    state = camera_state()
    image = blank()
    parts = [(z0 + lift_m, z1 + lift_m, rgb) for z0, z1, rgb in pole_parts(CODES[0])]
    paint_pole(image, state, (2.5, 0.0), parts)
    assert [o.landmark_id for o in detector.detect(noisy(image), state)] == found


def test_poster_blocks_of_pole_colours_give_nothing(detector: ColourPoleDetector) -> None:
    """Pink over yellow over white, but as wide blocks: no band's proportions."""
    image = blank()
    cv2.rectangle(image, (100, 60), (199, 89), PAINT["pink"], thickness=-1)
    cv2.rectangle(image, (100, 90), (199, 119), PAINT["yellow"], thickness=-1)
    cv2.rectangle(image, (100, 120), (199, 179), PAINT["white"], thickness=-1)
    assert detector.detect(noisy(image), camera_state()) == []


def test_band_merged_with_clutter_behind_is_still_measured(detector: ColourPoleDetector) -> None:
    """A yellow stripe behind the pole joins its yellow band into one wide segment."""
    state, xy, code = camera_state(), (2.5, 0.0), CODES[0]
    image = blank()
    rows = part_outline(state, np.asarray(xy), POLE.base_top_m, POLE.base_top_m + 0.1)[:, 1]
    cv2.rectangle(image, (20, int(rows.min())), (300, int(rows.max())), PAINT["yellow"], -1)
    paint_pole(image, state, xy, pole_parts(code))
    observations = detector.detect(noisy(image), state)
    assert [o.landmark_id for o in observations] == [code.landmark_id]
    assert observations[0].range_m == pytest.approx(2.5, rel=range_tolerance(2.5))


def test_pink_band_merged_with_pink_clutter_is_still_measured(
    detector: ColourPoleDetector,
) -> None:
    """A pink stripe behind the pole's pink band: the search starts from the other band."""
    state, xy, code = camera_state(), (2.5, 0.0), CODES[0]
    image = blank()
    top_band = POLE.base_top_m + POLE.band_height_m
    rows = part_outline(state, np.asarray(xy), top_band + 0.05, top_band + 0.15)[:, 1]
    cv2.rectangle(image, (20, int(rows.min())), (300, int(rows.max())), PAINT["pink"], -1)
    paint_pole(image, state, xy, pole_parts(code))
    observations = detector.detect(noisy(image), state)
    assert [o.landmark_id for o in observations] == [code.landmark_id]
    assert observations[0].range_m == pytest.approx(2.5, rel=range_tolerance(2.5))


def test_one_observation_per_id_the_nearer(detector: ColourPoleDetector) -> None:
    state, code = camera_state(), CODES[2]
    image = blank()
    for xy in ((3.5, -0.6), (1.5, 0.4)):
        paint_pole(image, state, xy, pole_parts(code))
    observations = detector.detect(noisy(image), state)
    assert [o.landmark_id for o in observations] == [code.landmark_id]
    near = math.hypot(1.5, 0.4)
    assert observations[0].range_m == pytest.approx(near, rel=range_tolerance(near))


def test_two_poles_two_observations(detector: ColourPoleDetector) -> None:
    state = camera_state()
    image = blank()
    placed = {0: (2.0, 0.5), 5: (3.0, -0.6)}
    for landmark_id, xy in placed.items():
        paint_pole(image, state, xy, pole_parts(CODES[landmark_id]))
    observations = detector.detect(noisy(image), state)
    assert [o.landmark_id for o in observations] == [0, 5]
    for obs in observations:
        true_range = math.hypot(*placed[obs.landmark_id])
        assert obs.range_m == pytest.approx(true_range, rel=range_tolerance(true_range))


def test_covariance_is_diagonal_positive_and_grows_with_range(
    detector: ColourPoleDetector,
) -> None:
    state, config = camera_state(), detector.config
    covs = []
    for distance in (1.5, 4.0):
        (obs,) = detector.detect(view(CODES[0], (distance, 0.0), state), state)
        assert obs.cov.shape == (2, 2) and obs.cov[0, 1] == obs.cov[1, 0] == 0.0
        assert obs.cov[1, 1] >= config.bearing_std_floor_rad**2
        covs.append(obs.cov)
    near, far = covs
    assert 0.0 < near[0, 0] < far[0, 0]
    # the range std follows from the band spacing: a far pole is measured relatively worse too
    assert math.sqrt(far[0, 0]) / 4.0 > math.sqrt(near[0, 0]) / 1.5


def test_empty_image_gives_nothing(detector: ColourPoleDetector) -> None:
    assert detector.detect(noisy(blank()), camera_state()) == []


@pytest.mark.parametrize(
    "image",
    [
        np.zeros((240, 320), dtype=np.uint8),
        np.zeros((240, 320, 4), dtype=np.uint8),
        np.zeros((120, 160, 3), dtype=np.uint8),
        np.zeros((240, 320, 3), dtype=np.float32),
        [[0, 0, 0]],
    ],
    ids=["grey", "rgba", "small", "float", "list"],
)
def test_rejects_images_not_of_the_camera(detector: ColourPoleDetector, image: object) -> None:
    with pytest.raises(ValueError, match="image"):
        detector.detect(image, camera_state())  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("pink_hsv", ((170, 80, 90), (160, 255, 255))),
        ("white_hsv", ((0, 0, 80), (180, 45, 255))),
        ("yellow_hsv", ((23, 130), (30, 255))),
        ("min_segment_area_px", 0),
        ("search_distance_factor", 1.0),
        ("alpha_step_deg", 0.0),
        ("alpha_max_deg", 90.0),
        ("band_height_ratio", (1.3, 0.75)),
        ("band_width_ratio", (0.0, 0.75)),
        ("max_height_mismatch", 0.9),
        ("max_box_width_ratio", math.inf),
        ("corridor_width_ratio", 0.0),
        ("min_corridor_fill", 1.5),
        ("max_range_m", 0.0),
        ("elevation_tolerance_rad", -0.1),
        ("pixel_std_px", math.nan),
        ("bearing_std_floor_rad", -1.0),
    ],
)
def test_config_rejects_bad_values(field: str, value: Any) -> None:
    with pytest.raises(ValueError, match=f"ColourFilterConfig.{field}"):
        replace(ColourFilterConfig(), **{field: value})


def test_rejects_ambiguous_codes() -> None:
    codes = [*CODES, PoleCode(landmark_id=9, top="pink", bottom="yellow")]
    with pytest.raises(ValueError, match="codes"):
        ColourPoleDetector(ColourFilterConfig(), CAMERA, codes, POLE)
