"""Field-feature detection (seed 004 §2.2) piece by piece, and whole on ray-cast images.

No rendering: the geometry steps (:mod:`perception.vision.field_geometry`) get hand-made
points and segments whose answer is known, the projection steps are checked against
:mod:`perception.vision.ground_point`, and :func:`detect_field_features` runs on images
ray-cast from the ground: each pixel's ray (3 x 3 samples per pixel) meets the ground and is
white on a painted marking (lines 0.05 m wide, a 0.1 m mark), carpet green elsewhere, grey
above the horizon. So every feature's true place in the robot frame is known exactly.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from perception.geometry import FloatArray, pixel_rays, ray_ground_intersection, wrap_angle
from perception.types import CameraModel, CameraState
from perception.vision.field_features import FieldFeatureConfig, detect_field_features
from perception.vision.field_geometry import (
    Segment,
    curvature,
    find_circle,
    find_junctions,
    image_lines,
    merge_segments,
)
from perception.vision.field_pixels import (
    GroundProjection,
    best_splits,
    ground_covariances,
    ground_points,
    masked_median,
    pixels_of,
    row_runs,
    rows_from,
    run_pixels,
    transposed,
)
from perception.vision.ground_point import range_bearing_cov

CAMERA = CameraModel()
STATE = CameraState(
    position=np.array([0.06, 0.0, 0.55]), head_yaw=0.0, head_pitch=0.45, tilt=math.radians(1.2)
)
HALF_WIDTH_M = 0.025  # half a painted line
GREEN, WHITE, SKY = (40, 124, 45), (246, 246, 246), (90, 90, 95)
ANGLE_TOL = math.radians(15)


def _segment(a: tuple[float, float], b: tuple[float, float], std: float = 0.01) -> Segment:
    return Segment(np.array([a, b], dtype=np.float64), np.tile(std**2 * np.eye(2), (2, 1, 1)))


def _distance_to_segments(points: FloatArray, segments: FloatArray) -> FloatArray:
    """(N,) distance of ground points (N, 2) to the nearest of ``segments`` (S, 2, 2)."""
    best = np.full(len(points), np.inf)
    for a, b in segments:
        d = b - a
        t = np.clip((points - a) @ d / (d @ d), 0.0, 1.0)
        best = np.minimum(best, np.hypot(*(points - a - t[:, None] * d).T))
    return best


def _post_distances(
    origin: FloatArray, rays: FloatArray, posts: FloatArray, radius: float, height: float
) -> FloatArray:
    """Distance along each of ``rays`` (N, 3) from ``origin`` (3,) to the nearest of the upright
    cylinders of ``radius`` and ``height`` (m) standing at ``posts`` (P, 2); inf for a miss."""
    best = np.full(len(rays), np.inf)
    a = (rays[:, :2] ** 2).sum(axis=1)
    for post in posts:
        offset = origin[:2] - post
        b = 2.0 * rays[:, :2] @ offset
        c = offset @ offset - radius**2
        disc = b**2 - 4.0 * a * c
        t = (-b - np.sqrt(np.maximum(disc, 0.0))) / (2.0 * a)
        z = origin[2] + t * rays[:, 2]
        hit = (disc >= 0.0) & (t > 0.0) & (z >= 0.0) & (z <= height)
        best = np.where(hit, np.minimum(best, t), best)
    return best


def raycast(
    segments: FloatArray,
    circle: tuple[FloatArray, float] | None = None,
    marks: FloatArray | None = None,
    state: CameraState = STATE,
    posts: FloatArray | None = None,
) -> np.ndarray:
    """An (H, W, 3) uint8 RGB image of painted ``segments`` (S, 2, 2) (centre lines, m, robot
    frame), an optional ``circle`` (centre, radius), 0.1 m square ``marks`` (M, 2) and white
    goal posts (0.1 m across, 0.8 m tall) standing at ``posts`` (P, 2)."""
    k = 3
    offsets = (np.arange(k) + 0.5) / k - 0.5
    u, v = np.meshgrid(np.arange(CAMERA.width), np.arange(CAMERA.height))
    du, dv = np.meshgrid(offsets, offsets)
    pixels = np.column_stack(
        [(u[..., None] + du.ravel()).ravel(), (v[..., None] + dv.ravel()).ravel()]
    )
    rays = pixel_rays(pixels, CAMERA.fx, CAMERA.fy, CAMERA.cx, CAMERA.cy) @ state.rotation().T
    xy, hit = ray_ground_intersection(state.position, rays)
    paint = np.zeros(len(xy), dtype=bool)
    if len(segments):
        paint[hit] = _distance_to_segments(xy[hit], segments) <= HALF_WIDTH_M
    if circle is not None:
        centre, radius = circle
        paint[hit] |= np.abs(np.hypot(*(xy[hit] - centre).T) - radius) <= HALF_WIDTH_M
    if marks is not None:
        for m in marks:
            paint[hit] |= (np.abs(xy[hit] - m) <= 0.05).all(axis=1)
    colour = np.where(paint[:, None], WHITE, GREEN).astype(np.float64)
    colour[~hit] = SKY
    if posts is not None:
        ground_t = np.where(hit, -state.position[2] / np.minimum(rays[:, 2], -1e-12), np.inf)
        on_post = _post_distances(state.position, rays, posts, 0.05, 0.8) < ground_t
        colour[on_post] = WHITE
    image = colour.reshape(CAMERA.height, CAMERA.width, k * k, 3).mean(axis=2)
    return np.rint(image).astype(np.uint8)


def of_kind(features: tuple, kind: str) -> list:
    return [f for f in features if f.kind == kind]


# ----- configuration -----------------------------------------------------------------------


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("line_width_m", 0.0),
        ("min_line_points", 0),
        ("junction_angle_deg", 60.0),
        ("mark_size_m", (0.2, 0.1)),
        ("green_hsv", ((0, 0, 0), (200, 255, 255))),
        ("pixel_std_px", -1.0),
        ("mark_green_fraction", 1.5),
    ],
)
def test_config_rejects_bad_values_naming_the_field(field: str, value: object) -> None:
    with pytest.raises(ValueError, match=f"FieldFeatureConfig.{field}"):
        FieldFeatureConfig(**{field: value})


@pytest.mark.parametrize(
    ("fields", "match"),
    [
        ({"position": np.array([math.nan, 0.0, 0.55])}, "CameraState.position must be finite"),
        ({"position": np.zeros(2)}, r"CameraState.position must have shape \(3,\)"),
        ({"head_pitch": math.nan}, "CameraState.head_pitch"),
        ({"head_yaw": math.inf}, "CameraState.head_yaw"),
    ],
)
def test_a_camera_state_of_nan_or_wrong_shape_is_refused(fields: dict, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        replace(STATE, **fields)


def test_detect_rejects_an_image_of_the_wrong_size() -> None:
    with pytest.raises(ValueError, match="image must be"):
        detect_field_features(np.zeros((10, 10, 3), np.uint8), CAMERA, STATE)


# ----- projection and covariance -----------------------------------------------------------


def test_pixels_and_ground_points_round_trip() -> None:
    points = np.array([[1.0, 0.0], [2.0, 0.5], [3.5, -1.0]])
    pixels = pixels_of(points, CAMERA, STATE)
    back, hit = ground_points(pixels, CAMERA, STATE)
    assert hit.all()
    np.testing.assert_allclose(back, points, atol=1e-9)


def test_ground_covariance_agrees_with_range_bearing_and_grows_with_range() -> None:
    """Down the image's centre column to the horizon: the covariance (x, y) equals
    ground_point's (range, bearing) covariance moved to x, y, and its size grows with range."""
    rows = np.linspace(230.0, 30.0, 9)
    pixels = np.column_stack([np.full(len(rows), 150.0), rows])
    covs = ground_covariances(pixels, CAMERA, STATE, 1.0)
    points, hit = ground_points(pixels, CAMERA, STATE)
    assert hit.all()
    for p, c, px in zip(points, covs, pixels, strict=True):
        rb = range_bearing_cov(px, CAMERA, STATE, 1.0)
        assert rb is not None
        r, b = math.hypot(*p), math.atan2(p[1], p[0])
        jac = np.array([[math.cos(b), -r * math.sin(b)], [math.sin(b), r * math.cos(b)]])
        np.testing.assert_allclose(c, jac @ rb @ jac.T, atol=1e-4 * float(np.abs(c).max()))
    sizes = np.sqrt(np.linalg.eigvalsh(covs)[:, 1])
    ranges = np.hypot(*points.T)
    assert (np.diff(ranges) > 0).all() and (np.diff(sizes) > 0).all()
    # about (d² + h²) / (h f) per pixel along the view (ground_point's docstring)
    h, d = STATE.position[2], ranges[-1] - STATE.position[0]
    assert sizes[-1] == pytest.approx((d**2 + h**2) / (h * CAMERA.fy), rel=0.15)


def test_ground_points_agree_with_unit_rays_on_the_ground() -> None:
    """Every pixel: below the horizon, the ground point of the pixel's unit ray; above it,
    NaN and not hit."""
    u, v = np.meshgrid(np.arange(0.0, CAMERA.width, 7.0), np.arange(0.0, CAMERA.height, 5.0))
    pixels = np.column_stack([u.ravel(), v.ravel()])
    state = CameraState(position=np.array([0.0, 0.0, 0.5]), head_yaw=0.3, head_pitch=0.05)
    rays = pixel_rays(pixels, CAMERA.fx, CAMERA.fy, CAMERA.cx, CAMERA.cy) @ state.rotation().T
    expected, expected_hit = ray_ground_intersection(state.position, rays)
    points, hit = ground_points(pixels, CAMERA, state)
    assert expected_hit.any() and not expected_hit.all()
    np.testing.assert_array_equal(hit, expected_hit)
    np.testing.assert_allclose(points[hit], expected[hit], rtol=1e-12, atol=1e-12)
    assert np.isnan(points[~hit]).all()


# ----- image helpers -------------------------------------------------------------------------


def test_row_runs_and_their_pixels_rebuild_the_mask() -> None:
    mask = np.random.default_rng(1).random((20, 30)) < 0.4
    mask[:, 0] = mask[:, -1] = True  # runs at both sides
    mask[5] = False  # an empty row
    rows, starts, ends = row_runs(mask)
    assert (ends > starts).all() and (np.diff(rows) >= 0).all()
    assert not mask[rows, starts - 1][starts > 0].any()  # each run is whole
    assert not mask[rows, ends % mask.shape[1]][ends < mask.shape[1]].any()
    rebuilt = np.zeros(mask.size, dtype=bool)
    rebuilt[run_pixels(rows * mask.shape[1] + starts, 1, ends - starts)] = True
    np.testing.assert_array_equal(rebuilt.reshape(mask.shape), mask)
    cols, tops, bottoms = row_runs(mask.T)  # down the columns
    rebuilt[:] = False
    rebuilt[run_pixels(tops * mask.shape[1] + cols, mask.shape[1], bottoms - tops)] = True
    np.testing.assert_array_equal(rebuilt.reshape(mask.shape), mask)


def test_transposed_is_the_contiguous_transpose_of_any_mask() -> None:
    rng = np.random.default_rng(0)
    for shape in [(0, 5), (1, 7), (7, 1), (240, 320), (33, 17)]:
        mask = rng.random(shape) > 0.5
        for view in (mask, mask[:, ::2], mask[::3]):  # strided views too
            flipped = transposed(view)
            assert flipped.dtype == np.bool_ and flipped.flags.c_contiguous
            np.testing.assert_array_equal(flipped, view.T)


def test_slopes_are_the_jacobians_columns_to_the_last_bit() -> None:
    rng = np.random.default_rng(2)
    pixels = rng.uniform([0.0, 100.0], [320.0, 240.0], (200, 2))
    axes = rng.integers(0, 2, 200)
    projection = GroundProjection(CAMERA, STATE)
    jacobians = projection.jacobians(pixels)
    slopes = projection.slopes(pixels, axes)
    assert slopes.tobytes() == jacobians[np.arange(200), :, axes].tobytes()


def test_best_splits_of_random_masks_match_a_direct_count() -> None:
    rng = np.random.default_rng(1)
    for _ in range(20):
        carpet = rng.random((int(rng.integers(1, 30)), int(rng.integers(1, 30)))) > rng.random()
        height = carpet.shape[0]
        below = np.cumsum(carpet[::-1], axis=0)[::-1]  # carpet from each row down
        value = 2 * below - np.arange(height, 0, -1)[:, None]  # ... less all pixels from it down
        best, score = best_splits(carpet)
        np.testing.assert_array_equal(best, np.argmax(value, axis=0))
        np.testing.assert_array_equal(score, value.max(axis=0))


def test_rows_from_and_masked_median() -> None:
    first = np.array([-np.inf, -2.5, 0.0, 3.2, 4.0, 9.0, np.inf])
    np.testing.assert_array_equal(rows_from(first, 6), np.arange(6)[:, None] >= first[None, :])
    image = np.random.default_rng(3).integers(0, 256, (30, 40, 3), dtype=np.uint8)
    for size in (1, 2, 7, 10):  # odd and even counts: the middle two are averaged
        mask = np.zeros((30, 40), dtype=bool)
        mask.flat[np.random.default_rng(size).choice(mask.size, size, replace=False)] = True
        assert masked_median(image, 1, mask) == float(np.median(image[..., 1][mask]))


# ----- image lines, segments, merging ------------------------------------------------------


def test_image_lines_of_too_few_points_is_empty() -> None:
    line = np.column_stack([np.arange(12.0), np.zeros(12)])
    assert image_lines(line[:11], tol_px=1.0, min_points=12, split_gap_px=5.0) == []
    (found,) = image_lines(line, tol_px=1.0, min_points=12, split_gap_px=5.0)
    assert sorted(found.indices.tolist()) == list(range(12))


def test_a_peak_of_min_points_votes_is_a_line_and_one_fewer_is_not() -> None:
    """With 14 points left after the first line (enough to look again), a second line of 11
    collinear points has a peak of 11 votes: under ``min_points`` = 12, no line; of 12, one."""
    first = np.column_stack([np.arange(0.0, 24.0, 2.0), np.zeros(12)])  # 12 points, y = 0
    strays = np.array([[5.0, 40.0], [37.0, 71.0], [61.0, 23.0]])  # on no line with the rest
    for n, expected in ((11, 1), (12, 2)):
        second = np.column_stack([np.full(n, 100.0), np.arange(20.0, 20.0 + 3 * n, 3.0)])
        points = np.vstack([first, second, strays])
        lines = image_lines(points, tol_px=1.0, min_points=12, split_gap_px=5.0)
        found = sorted(sorted(line.indices.tolist()) for line in lines)
        assert found == [list(range(12)), list(range(12, 12 + n))][:expected]


def test_image_lines_groups_collinear_points_and_splits_at_gaps() -> None:
    rng = np.random.default_rng(0)
    t = np.arange(0.0, 200.0, 1.0)
    a = np.column_stack([20 + t, 50 + 0.3 * t]) + rng.normal(0, 0.3, (len(t), 2))
    b = np.column_stack([10 + 0 * t[:80], 60 + t[:80]])  # a vertical line
    b = np.vstack([b[:30], b[55:]])  # with a 25 px gap
    lines = image_lines(np.vstack([a, b]), tol_px=1.5, min_points=12, split_gap_px=10.0)
    assert len(lines) == 3
    long = max(lines, key=lambda line: len(line.indices))
    assert len(long.indices) >= 195
    ends = long.ends[np.argsort(long.ends[:, 0])]  # in either order
    np.testing.assert_allclose(ends, [[20, 50], [219, 50 + 0.3 * 199]], atol=1.0)
    pieces = sorted((line for line in lines if line is not long), key=lambda x: x.ends.min())
    np.testing.assert_allclose(pieces[0].ends[:, 0], 10.0, atol=1e-6)
    assert {len(p.indices) for p in pieces} == {30, 25}


def test_merge_segments_joins_collinear_overlapping_pieces_only() -> None:
    pieces = [
        _segment((1.0, 0.0), (2.0, 0.01)),
        _segment((1.8, 0.0), (3.0, 0.0)),  # overlaps the first: merged
        _segment((3.2, 0.02), (4.0, 0.02)),  # 0.2 m gap: merged
        _segment((1.0, 0.5), (3.0, 0.5)),  # parallel, 0.5 m aside: kept
        _segment((5.5, 0.0), (6.0, 0.0)),  # 1.5 m gap: kept
    ]
    merged = merge_segments(pieces, angle_tol_rad=0.1, offset_tol_m=0.1, gap_tol_m=0.3)
    assert len(merged) == 3
    whole = merged[0]
    assert {round(float(x), 2) for x in whole.ends[:, 0]} == {1.0, 4.0}
    assert np.abs(whole.ends[:, 1]).max() < 0.03


def test_merge_keeps_the_open_flag_of_the_end_it_keeps() -> None:
    a = Segment(np.array([[1.0, 0.0], [2.0, 0.0]]), np.tile(1e-4 * np.eye(2), (2, 1, 1)))
    b = Segment(np.array([[1.9, 0.0], [3.0, 0.0]]), np.tile(1e-4 * np.eye(2), (2, 1, 1)))
    merged = merge_segments(
        [a, replace(b, open=(False, True))], angle_tol_rad=0.1, offset_tol_m=0.1, gap_tol_m=0.3
    )
    (whole,) = merged
    far = int(np.argmax(whole.ends[:, 0]))
    assert whole.open[far] and not whole.open[1 - far]


# ----- junctions ---------------------------------------------------------------------------


def test_corner_t_and_x_are_told_apart_with_the_documented_directions() -> None:
    corner = find_junctions(
        [_segment((2.0, 0.0), (2.0, 1.0)), _segment((2.0, 0.0), (3.0, 0.0))],
        angle_tol_rad=ANGLE_TOL,
        end_tol_m=0.2,
    )
    assert [j.kind for j in corner] == ["corner"]
    np.testing.assert_allclose(corner[0].point, [2.0, 0.0], atol=1e-9)
    assert corner[0].direction == pytest.approx(math.pi / 4)  # bisector, into the opening

    # the stem ends 0.1 m short of the bar (the bar's white hides its last pixels)
    tee = find_junctions(
        [_segment((2.0, -1.0), (2.0, 1.0)), _segment((1.9, 0.3), (0.5, 0.3))],
        angle_tol_rad=ANGLE_TOL,
        end_tol_m=0.2,
    )
    assert [j.kind for j in tee] == ["t_junction"]
    np.testing.assert_allclose(tee[0].point, [2.0, 0.3], atol=1e-9)
    assert abs(wrap_angle(tee[0].direction - math.pi)) < 1e-9  # along the stem, off the bar

    cross = find_junctions(
        [_segment((2.0, -1.0), (2.0, 1.0)), _segment((1.0, 0.2), (2.5, 0.2))],
        angle_tol_rad=ANGLE_TOL,
        end_tol_m=0.2,
    )
    assert [j.kind for j in cross] == ["x_junction"]
    assert cross[0].direction == pytest.approx(math.pi / 2)  # along the longer, in [0, pi)


def test_no_junction_for_oblique_apart_or_cut_off_segments() -> None:
    oblique = [_segment((2.0, 0.0), (2.0, 1.0)), _segment((2.0, 0.0), (3.0, 0.6))]
    apart = [_segment((2.0, 0.0), (2.0, 1.0)), _segment((2.6, 0.0), (3.6, 0.0))]
    bar = Segment(
        np.array([[2.0, -1.0], [2.0, 0.05]]), np.tile(1e-4 * np.eye(2), (2, 1, 1)), (False, True)
    )
    cut = [bar, _segment((1.95, 0.0), (1.0, 0.0))]  # the bar leaves the image at the vertex
    for segments in (oblique, apart, cut):
        assert find_junctions(segments, angle_tol_rad=ANGLE_TOL, end_tol_m=0.2) == []


# ----- circle and curvature ----------------------------------------------------------------


def _arc(
    centre: tuple[float, float], radius: float, start: float, stop: float, n: int
) -> FloatArray:
    a = np.linspace(start, stop, n)
    return np.asarray(centre) + radius * np.column_stack([np.cos(a), np.sin(a)])


def test_find_circle_recovers_a_quarter_arc_among_outliers() -> None:
    rng = np.random.default_rng(1)
    arc = _arc((2.0, 0.5), 0.75, 2.5, 4.1, 120) + rng.normal(0, 0.01, (120, 2))
    clutter = rng.uniform([0.5, -2.0], [4.0, 2.0], (40, 2))
    found = find_circle(
        np.vstack([arc, clutter]),
        0.75,
        tol_m=0.06,
        radius_tol_m=0.15,
        min_points=25,
        min_arc_rad=math.radians(45),
    )
    assert found is not None
    np.testing.assert_allclose(found.centre, [2.0, 0.5], atol=0.02)
    assert found.inliers[:120].mean() > 0.95
    assert found.arc == pytest.approx(1.6, abs=0.1)


def test_find_circle_rejects_lines_a_wrong_radius_and_scattered_pieces() -> None:
    gates = {"tol_m": 0.06, "radius_tol_m": 0.15, "min_points": 25, "min_arc_rad": math.radians(45)}
    line = np.column_stack([np.linspace(1, 3, 200), np.full(200, 0.3)])
    corner = np.vstack([line, np.column_stack([np.full(200, 3.0), np.linspace(0.3, 2.3, 200)])])
    big = _arc((2.0, 0.0), 1.3, 2.5, 4.0, 150)
    # (the corner: a circle dipping into both lines meets each over 60°, but straight)
    # a mark and a junction's corner 0.75 m from one point: no arc between them
    clusters = np.vstack(
        [_arc((2.0, 0.0), 0.75, 0.0, 0.2, 40), _arc((2.0, 0.0), 0.75, 2.0, 2.2, 40)]
    )
    for points in (line, corner, big, clusters):
        assert find_circle(points, 0.75, **gates) is None


def test_curvature_tells_a_polygon_piece_of_the_circle_from_a_line() -> None:
    rng = np.random.default_rng(2)
    line = np.column_stack([np.linspace(1, 1.5, 60), np.full(60, 0.3)])
    arc = _arc((0.0, 0.0), 0.75, 0.2, 0.85, 60)  # 0.5 m of the circle
    k_line, s_line = curvature(line + rng.normal(0, 0.005, line.shape))
    k_arc, s_arc = curvature(arc + rng.normal(0, 0.005, arc.shape))
    assert abs(k_line) < 3 * s_line
    assert abs(k_arc) == pytest.approx(1 / 0.75, rel=0.2) and abs(k_arc) > 10 * s_arc


# ----- the whole detector on ray-cast images -----------------------------------------------


def test_empty_carpet_gives_nothing() -> None:
    assert detect_field_features(raycast(np.zeros((0, 2, 2))), CAMERA, STATE) == ()


def test_l_corner_lines_and_vertex_on_the_ground() -> None:
    # an L with its vertex 1.6 m ahead, arms to the left and away
    segments = np.array([[[1.6, -0.3], [1.6, 1.2]], [[1.6, -0.3], [3.5, -0.3]]])
    features = detect_field_features(raycast(segments), CAMERA, STATE)
    lines = of_kind(features, "line")
    assert len(lines) == 2
    for line in lines:  # the paint reaches half a width beyond the vertex
        assert _distance_to_segments(line.points, segments).max() < HALF_WIDTH_M + 0.005
    (corner,) = of_kind(features, "corner")
    assert np.hypot(*(corner.points[0] - [1.6, -0.3])) < 0.03
    assert abs(wrap_angle(corner.direction - math.pi / 4)) < math.radians(3)
    assert of_kind(features, "t_junction") == of_kind(features, "x_junction") == []


def test_t_junction_and_penalty_mark() -> None:
    bar = [[2.2, -1.5], [2.2, 1.5]]
    stem = [[2.2, 0.4], [1.2, 0.4]]
    features = detect_field_features(
        raycast(np.array([bar, stem]), marks=np.array([[1.5, -0.6]])), CAMERA, STATE
    )
    (tee,) = of_kind(features, "t_junction")
    assert np.hypot(*(tee.points[0] - [2.2, 0.4])) < 0.03
    assert abs(wrap_angle(tee.direction - math.pi)) < math.radians(3)
    (mark,) = of_kind(features, "penalty_mark")
    assert np.hypot(*(mark.points[0] - [1.5, -0.6])) < 0.02
    assert of_kind(features, "corner") == []


def test_centre_circle_with_the_halfway_line_through_it() -> None:
    state = replace(STATE, head_pitch=0.35)
    centre = np.array([2.0, 0.2])
    halfway = np.array([[[2.0, -3.0], [2.0, 3.0]]])
    features = detect_field_features(
        raycast(halfway, circle=(centre, 0.75), state=state), CAMERA, state
    )
    (circle,) = of_kind(features, "centre_circle")
    assert np.hypot(*(circle.points[0] - centre)) < 0.03
    assert circle.direction is not None
    assert abs(wrap_angle(2 * (circle.direction - math.pi / 2))) / 2 < math.radians(2)
    crossings = sorted(f.points[0, 1] for f in of_kind(features, "x_junction"))
    np.testing.assert_allclose(crossings, [0.2 - 0.75, 0.2 + 0.75], atol=0.04)
    (line,) = of_kind(features, "line")  # pieces of the circle are not lines
    assert _distance_to_segments(line.points, halfway).max() < 0.02


def test_a_post_leaning_in_the_image_is_found_at_its_foot() -> None:
    """A post off the image centre of a pitched camera leans (verticals meet below it): here
    by about half its width over its height, so fewer of its columns are white all the way up
    than it is wide. Its extent is the white run along each row through them."""
    state = replace(STATE, head_pitch=0.2)
    post = np.array([2.4, 0.9])
    image = raycast(np.zeros((0, 2, 2)), state=state, posts=post[None])
    (found,) = of_kind(detect_field_features(image, CAMERA, state), "goal_post")
    assert np.hypot(*(found.points[0] - post)) < 0.06


def test_covariances_are_positive_definite_and_grow_with_range() -> None:
    segments = np.array([[[1.0, -0.5], [1.0, 0.5]], [[3.0, -1.0], [3.0, 1.0]]])
    features = detect_field_features(raycast(segments), CAMERA, STATE)
    near, far = sorted(of_kind(features, "line"), key=lambda f: f.points[0, 0])
    assert near.points[0, 0] == pytest.approx(1.0, abs=0.02)
    assert far.points[0, 0] == pytest.approx(3.0, abs=0.05)
    assert np.linalg.eigvalsh(far.cov).min() > np.linalg.eigvalsh(near.cov).max()
