"""Which field features a camera sees from a known pose (the oracle's and the benchmark's ideal
detections): the image border, the range limit, exact points without noise, and noise whose
scatter matches the reported covariance."""

from __future__ import annotations

import math

import numpy as np
import pytest

from perception.field.field_map import FieldMap
from perception.field.visibility import OCCLUSION_EVERY, FeatureViewConfig, visible_features
from perception.geometry import project_points
from perception.types import CameraModel, CameraState

FIELD = FieldMap()
CAMERA = CameraModel()
STATE = CameraState(
    position=np.array([0.05, 0.0, 0.5]), head_yaw=0.0, head_pitch=0.0, tilt=math.radians(20)
)
CONFIG = FeatureViewConfig()
BEFORE_CENTRE = np.array([-1.5, 0.0, 0.0])  # 1.5 m before the halfway line, facing it


def pixels(robot_points: np.ndarray) -> np.ndarray:
    ground = np.column_stack([robot_points, np.zeros(len(robot_points))])
    in_camera = (ground - STATE.position) @ STATE.rotation()
    uv, _ = project_points(in_camera, CAMERA.fx, CAMERA.fy, CAMERA.cx, CAMERA.cy)
    return uv


def test_the_halfway_line_is_seen_from_border_to_border_of_the_image() -> None:
    features = visible_features(FIELD, BEFORE_CENTRE, CAMERA, STATE, CONFIG)
    lines = [f for f in features if f.kind == "line"]
    assert len(lines) == 1
    ends = lines[0].points
    np.testing.assert_allclose(ends[:, 0], 1.5, atol=1e-9)  # x = 0 in the field: 1.5 m ahead
    u = pixels(ends)[:, 0]
    # the stretch ends where the line leaves the image (within one sampling step)
    step_px = CONFIG.sample_m * CAMERA.fx / 1.5
    assert min(u) == pytest.approx(CONFIG.margin_px, abs=step_px + 1e-6)
    assert max(u) == pytest.approx(CAMERA.width - 1 - CONFIG.margin_px, abs=step_px + 1e-6)


def test_the_centre_circle_and_its_crossings_are_seen_with_the_halfway_line() -> None:
    features = visible_features(FIELD, BEFORE_CENTRE, CAMERA, STATE, CONFIG)
    kinds = sorted(f.kind for f in features)
    assert kinds == ["centre_circle", "line", "x_junction", "x_junction"]
    circle = next(f for f in features if f.kind == "centre_circle")
    np.testing.assert_allclose(circle.points[0], [1.5, 0.0], atol=1e-12)
    assert circle.direction == pytest.approx(math.pi / 2)  # along the halfway line


def test_nothing_beyond_the_range_limit_is_seen() -> None:
    near = FeatureViewConfig(max_range_m=1.0)
    assert visible_features(FIELD, BEFORE_CENTRE, CAMERA, STATE, near) == ()
    behind = np.array([-1.5, 0.0, math.pi])  # facing the own goal, 3 m of empty half ahead
    assert all(
        f.distance_m <= CONFIG.max_range_m
        for f in visible_features(FIELD, behind, CAMERA, STATE, CONFIG)
    )


def test_noise_scatters_as_the_reported_covariance_says() -> None:
    rng = np.random.default_rng(5)
    exact = visible_features(FIELD, BEFORE_CENTRE, CAMERA, STATE, CONFIG)
    circle = next(f for f in exact if f.kind == "centre_circle")
    draws = []
    for _ in range(400):
        noisy = visible_features(FIELD, BEFORE_CENTRE, CAMERA, STATE, CONFIG, rng)
        draws.append(next(f for f in noisy if f.kind == "centre_circle").points[0])
    errors = np.array(draws) - circle.points[0]
    nees = np.einsum("ni,ij,nj->n", errors, np.linalg.inv(circle.cov[0]), errors)
    assert 2.0 - 0.3 < nees.mean() < 2.0 + 0.3  # 2 dof, standard error sqrt(4 / 400) = 0.1
    std = CONFIG.point_std_m + CONFIG.point_std_per_m * 1.5
    np.testing.assert_allclose(circle.cov[0], std**2 * np.eye(2))


def test_bad_settings_are_refused() -> None:
    with pytest.raises(ValueError, match="max_range_m"):
        FeatureViewConfig(max_range_m=0.0)
    with pytest.raises(ValueError, match="min_circle_fraction"):
        FeatureViewConfig(min_circle_fraction=1.5)
    with pytest.raises(ValueError, match="pose"):
        visible_features(FIELD, np.array([0.0, np.inf, 0.0]), CAMERA, STATE, CONFIG)


def test_hidden_ground_is_not_seen_and_a_line_keeps_its_longest_clear_stretch() -> None:
    """A stand-in occluder hides the halfway line's ground points with y in [-0.5, 0.3]: the
    line is seen from the hidden stretch's edge to the image border on its longer side, to
    within the OCCLUSION_EVERY samples the verdict is asked at."""
    asked: list[np.ndarray] = []

    def occluded(points: np.ndarray) -> np.ndarray:
        asked.append(points.copy())
        return (points[:, 1] >= -0.5) & (points[:, 1] <= 0.3) & (np.abs(points[:, 0]) < 0.01)

    clear = visible_features(FIELD, BEFORE_CENTRE, CAMERA, STATE, CONFIG)
    features = visible_features(FIELD, BEFORE_CENTRE, CAMERA, STATE, CONFIG, occluded=occluded)
    (whole,) = [f for f in clear if f.kind == "line"]
    (line,) = [f for f in features if f.kind == "line"]
    lo, hi = sorted(whole.points[:, 1])  # robot frame y = field y: the robot faces +x at y = 0
    kept = sorted(line.points[:, 1])
    slack = OCCLUSION_EVERY * CONFIG.sample_m + 1e-9
    if hi - 0.3 >= -0.5 - lo:  # the clear stretch on the left is the longer
        assert kept == [pytest.approx(0.3, abs=slack), pytest.approx(hi)]
    else:
        assert kept == [pytest.approx(lo), pytest.approx(-0.5, abs=slack)]
    assert sorted(f.kind for f in features) == sorted(f.kind for f in clear)
    # along the line it was asked every OCCLUSION_EVERY samples, not at each
    (points,) = asked
    on_line = np.sort(points[np.abs(points[:, 0]) < 1e-9, 1])
    assert np.median(np.diff(on_line)) == pytest.approx(slack, rel=0.01)


def test_a_goal_post_is_seen_only_with_enough_of_it_in_the_image() -> None:
    """With ``post_seen_height_m``, a post whose point that high above its foot falls outside
    the image (looking down) is not seen, though its foot is."""
    facing_goal = np.array([2.5, 0.0, 0.0])  # 2.1 m before the +x goal line, facing it
    posts = FeatureViewConfig(post_seen_height_m=0.45)
    level = CameraState(position=STATE.position, head_yaw=0.0, head_pitch=0.0, tilt=0.1)
    down = CameraState(position=STATE.position, head_yaw=0.0, head_pitch=0.5, tilt=0.02)
    for state, seen in ((level, True), (down, False)):
        feet = visible_features(FIELD, facing_goal, CAMERA, state, CONFIG)
        with_height = visible_features(FIELD, facing_goal, CAMERA, state, posts)
        foot_posts = [f for f in feet if f.kind == "goal_post"]
        assert len(foot_posts) == 2  # both feet in view either way
        high = np.array([[p.points[0, 0], p.points[0, 1], 0.45] for p in foot_posts])
        uv, _ = project_points(
            (high - state.position) @ state.rotation(), CAMERA.fx, CAMERA.fy, CAMERA.cx, CAMERA.cy
        )
        inside = bool(np.all((uv[:, 1] >= CONFIG.margin_px) & (uv[:, 1] <= CAMERA.height - 3)))
        assert inside == seen
        assert sum(f.kind == "goal_post" for f in with_height) == (2 if seen else 0)
