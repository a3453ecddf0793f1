"""The unified field-feature sensor model (seed 004 §2.2) on synthetic features at known poses:
exact recovery without noise, what a line constrains, the matching order and the seed's
pre-processing, refusal, and an information matrix that matches the estimator's scatter."""

from __future__ import annotations

import math

import numpy as np
import pytest

from perception.field import sensor_model
from perception.field.dimensions import FieldDimensions
from perception.field.features import FieldFeature
from perception.field.field_map import FieldMap, MapFeature
from perception.field.sensor_model import SensorModelConfig, match_items, observe_pose
from perception.geometry import wrap_angle

FIELD = FieldMap()
CONFIG = SensorModelConfig()
POINT_STD_M = 0.02
DIRECTION_STD_RAD = 0.03


def named(name: str) -> MapFeature:
    return next(f for f in FIELD.features if f.name == name)


def to_robot(pose: np.ndarray, points: np.ndarray) -> np.ndarray:
    c, s = math.cos(pose[2]), math.sin(pose[2])
    return (np.asarray(points, dtype=float) - pose[:2]) @ np.array([[c, -s], [s, c]])


def seen(
    pose: np.ndarray,
    name: str,
    part: np.ndarray | None = None,
    rng: np.random.Generator | None = None,
    std: float = POINT_STD_M,
) -> FieldFeature:
    """The map feature ``name`` as the robot at ``pose`` sees it (``part``: a line's seen
    stretch, field frame), with noise drawn from its covariance when ``rng`` is given."""
    feature = named(name)
    points = to_robot(pose, feature.points if part is None else part)
    direction = None if feature.direction is None else feature.direction - pose[2]
    if rng is not None:
        points = points + rng.normal(0.0, std, points.shape)
        if direction is not None:
            direction += rng.normal(0.0, DIRECTION_STD_RAD)
    cov = np.array([np.eye(2) * std**2] * len(points))
    return FieldFeature(
        feature.kind, points, cov, direction, math.nan if direction is None else DIRECTION_STD_RAD
    )


TRUTH = np.array([-2.0, 1.0, 0.3])


def rich_view(
    pose: np.ndarray = TRUTH, rng: np.random.Generator | None = None
) -> list[FieldFeature]:
    return [
        seen(pose, "corner_penalty_area_-x_+y", rng=rng),
        seen(pose, "goal_post_-x_+y", rng=rng),
        seen(pose, "centre_circle", rng=rng),
        seen(pose, "halfway_line", np.array([[0.0, -1.0], [0.0, 2.0]]), rng=rng),
        seen(pose, "penalty_area_-x_side_+y", np.array([[-4.2, 2.0], [-3.2, 2.0]]), rng=rng),
    ]


def pose_error(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    d = a - b
    d[2] = wrap_angle(d[2])
    return d


def test_noiseless_features_give_the_true_pose_from_nearby_priors() -> None:
    rng = np.random.default_rng(0)
    features = rich_view()
    for _ in range(20):
        prior = TRUTH + rng.uniform([-0.3, -0.3, -0.3], [0.3, 0.3, 0.3])
        result = observe_pose(features, prior, FIELD, CONFIG)
        assert result.observation is not None
        np.testing.assert_allclose(pose_error(result.pose, TRUTH), 0.0, atol=1e-6)
        assert result.rms_error_m < 1e-6


@pytest.mark.parametrize(
    ("name", "part", "free_axis"),
    [
        ("halfway_line", [[0.0, -1.0], [0.0, 2.0]], 1),  # along y: x and the heading
        ("touch_line_+y", [[-3.0, 3.0], [-1.0, 3.0]], 0),  # along x: y and the heading
    ],
)
def test_a_single_line_constrains_only_the_two_components_across_it(
    name: str, part: list, free_axis: int
) -> None:
    features = [seen(TRUTH, name, np.array(part))]
    fixed = [axis for axis in (0, 1, 2) if axis != free_axis]
    prior = TRUTH + np.array([0.3, 0.4, 0.1])
    result = observe_pose(features, prior, FIELD, CONFIG)
    assert result.observation is not None
    np.testing.assert_allclose(pose_error(result.pose, TRUTH)[fixed], 0.0, atol=1e-6)
    # with the heading right, no turn about the line moves the robot along it: the line
    # leaves that component as the prior had it
    level = TRUTH + np.array([0.3, 0.4, 0.0])
    moved = observe_pose(features, level, FIELD, CONFIG)
    np.testing.assert_allclose(pose_error(moved.pose, TRUTH)[fixed], 0.0, atol=1e-6)
    assert moved.pose[free_axis] == pytest.approx(level[free_axis], abs=1e-9)
    information = result.observation.information
    null = np.zeros(3)
    null[free_axis] = 1.0
    np.testing.assert_allclose(information @ null, 0.0, atol=1e-6)
    assert np.linalg.matrix_rank(information, tol=1e-6 * np.abs(information).max()) == 2


def test_items_are_matched_in_the_seeds_order_nearest_first_within_a_kind() -> None:
    pose = np.array([3.0, 0.3, 0.1])  # before the +x goal, facing it
    features = [
        seen(pose, "halfway_line", np.array([[0.0, -1.0], [0.0, 1.0]])),
        seen(pose, "centre_circle"),
        seen(pose, "penalty_mark_+x"),
        seen(pose, "t_junction_halfway_+y"),
        seen(pose, "corner_goal_area_+x_+y"),
        seen(pose, "corner_penalty_area_+x_+y"),
        seen(pose, "goal_post_+x_-y"),
        seen(pose, "goal_post_+x_+y"),
        seen(pose, "goal_area_+x_front", np.array([[3.9, -1.0], [3.9, 1.0]])),
        seen(pose, "penalty_area_+x_front", np.array([[2.85, -1.0], [2.85, 1.0]])),
    ]
    items = match_items(features, FIELD, CONFIG)
    assert [item.kind for item in items] == [
        "two_posts",
        "parallel_lines",
        "corner",
        "corner",
        "t_junction",
        "penalty_mark",
        "centre_circle",
        "line",
    ]
    corners = [item.features[0].distance_m for item in items if item.kind == "corner"]
    assert corners == sorted(corners)


def test_two_posts_match_only_goal_orders_that_keep_the_robot_on_the_carpet() -> None:
    pose = np.array([3.0, 0.3, 0.1])
    features = [seen(pose, "goal_post_+x_-y"), seen(pose, "goal_post_+x_+y")]
    (item,) = match_items(features, FIELD, CONFIG)
    pairs = {tuple(m.name for m in c) for c in item.candidates}
    # the seen order on either goal; the swapped orders would put the robot behind a goal
    assert pairs == {("goal_post_+x_-y", "goal_post_+x_+y"), ("goal_post_-x_+y", "goal_post_-x_-y")}


def test_two_posts_that_put_the_robot_off_the_carpet_in_every_order_make_no_item() -> None:
    """Seen from just past the side edge (as noise can place a robot near it), no goal order
    keeps the robot on the carpet: no two-posts item (each post is still an item of its own),
    and the sensor model answers rather than crashing (it had indexed the empty candidates)."""
    pose = np.array([4.55, 3.72, -math.pi / 2])
    posts = [seen(pose, "goal_post_+x_+y"), seen(pose, "goal_post_+x_-y")]
    assert [item.kind for item in match_items(posts, FIELD, CONFIG)] == ["goal_post"] * 2
    prior = np.array([4.5, 3.6, -math.pi / 2])
    line = seen(pose, "goal_line_+x", np.array([[4.5, 2.0], [4.5, 0.5]]))
    for features in (posts, [*posts, line]):
        for starts in ("prior", "hypotheses"):
            result = observe_pose(features, prior, FIELD, SensorModelConfig(starts=starts))
            assert result.observation is None or np.isfinite(result.observation.pose).all()


def test_a_t_junction_beside_a_post_matches_only_junctions_with_a_post_there() -> None:
    pose = np.array([3.0, 0.3, 0.1])
    features = [seen(pose, "t_junction_goal_area_+x_+y"), seen(pose, "goal_post_+x_+y")]
    t_item = next(
        item for item in match_items(features, FIELD, CONFIG) if item.kind == "t_junction"
    )
    names = {c[0].name for c in t_item.candidates}
    assert names == {"t_junction_goal_area_+x_+y", "t_junction_goal_area_-x_-y"}


def test_an_edge_beside_a_corner_or_a_line_keeps_only_outer_ones() -> None:
    pose = np.array([3.5, 2.0, 0.6])
    edge = seen(pose, "field_edge_+y", np.array([[2.5, 3.7], [5.0, 3.7]]))
    corner = seen(pose, "corner_field_+x_+y")
    line = seen(pose, "touch_line_+y", np.array([[2.0, 3.0], [4.0, 3.0]]))
    items = match_items([edge, corner, line], FIELD, CONFIG)
    by_kind = {item.kind: {c[0].name for c in item.candidates} for item in items}
    assert by_kind["corner"] == {f.name for f in FIELD.of_kind("corner") if "field" in f.name}
    assert by_kind["line"] == {"touch_line_-y", "touch_line_+y", "goal_line_-x", "goal_line_+x"}
    assert "field_edge" not in by_kind  # the edges only sort the others


def test_each_map_restricts_candidates_by_its_own_relations() -> None:
    # the map's side of the relations is worked out once per map: a map with a wider border
    # has no corner 0.7 m from an edge (all kept), and the first map's answer is unchanged
    pose = np.array([3.5, 2.0, 0.6])
    edge = seen(pose, "field_edge_+y", np.array([[2.5, 3.7], [5.0, 3.7]]))
    features = [edge, seen(pose, "corner_field_+x_+y")]
    wide = FieldMap(FieldDimensions(border_strip_m=1.5))

    def corners(field_map: FieldMap) -> set[str]:
        (item,) = match_items(features, field_map, CONFIG)
        return {c[0].name for c in item.candidates}

    field_corners = {f.name for f in FIELD.of_kind("corner") if "field" in f.name}
    assert corners(FIELD) == field_corners
    assert corners(wide) == {f.name for f in wide.of_kind("corner")}
    assert corners(FIELD) == field_corners


def test_features_that_do_not_fit_together_are_refused() -> None:
    features = rich_view()
    post = features[1]
    features[1] = FieldFeature("goal_post", post.points + np.array([[1.0, 0.0]]), post.cov)
    result = observe_pose(features, TRUTH, FIELD, CONFIG)
    assert result.observation is None
    assert result.rms_error_m > CONFIG.accept_rms_m


def test_the_information_matches_the_estimators_scatter() -> None:
    rng = np.random.default_rng(3)
    errors, information = [], None
    for _ in range(300):
        result = observe_pose(rich_view(rng=rng), TRUTH, FIELD, CONFIG)
        assert result.observation is not None
        errors.append(pose_error(result.pose, TRUTH))
        information = result.observation.information
    errors = np.array(errors)
    nees = np.einsum("ni,ij,nj->n", errors, information, errors)
    # mean NEES of 300 runs, 3 dof: 3 with a standard error of sqrt(6 / 300) = 0.14
    assert 2.55 < nees.mean() < 3.45


def test_bad_arguments_are_refused() -> None:
    with pytest.raises(TypeError, match="features"):
        observe_pose(rich_view()[0], TRUTH, FIELD, CONFIG)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="prior_pose"):
        observe_pose(rich_view(), np.array([0.0, np.nan, 0.0]), FIELD, CONFIG)
    with pytest.raises(ValueError, match="accept_rms_m"):
        SensorModelConfig(accept_rms_m=0.0)
    with pytest.raises(ValueError, match="max_iterations"):
        SensorModelConfig(max_iterations=0)


def test_no_features_give_no_observation() -> None:
    result = observe_pose([], TRUTH, FIELD, CONFIG)
    assert result.observation is None and result.iterations == 0


def twin(pose: np.ndarray) -> np.ndarray:
    """The pose's half-turn twin: the field looks the same from there."""
    return np.array([-pose[0], -pose[1], float(wrap_angle(pose[2] + math.pi))])


def test_a_start_per_candidate_finds_the_pose_or_its_twin_from_anywhere() -> None:
    config = SensorModelConfig(starts="hypotheses")
    features = rich_view()
    rng = np.random.default_rng(1)
    for _ in range(10):
        prior = np.array([*rng.uniform([-4.5, -3.0], [4.5, 3.0]), rng.uniform(-math.pi, math.pi)])
        result = observe_pose(features, prior, FIELD, config)
        assert result.observation is not None
        truth, mirror = pose_error(result.pose, TRUTH), pose_error(result.pose, twin(TRUTH))
        found = truth if np.abs(truth).max() < np.abs(mirror).max() else mirror
        np.testing.assert_allclose(found, 0.0, atol=1e-6)
        # of the two equally good fits, the one nearer the prior
        nearer = min(
            (TRUTH, twin(TRUTH)),
            key=lambda p: (
                np.linalg.norm(p[:2] - prior[:2])
                + CONFIG.direction_scale_m_per_rad * abs(float(wrap_angle(p[2] - prior[2])))
            ),
        )
        np.testing.assert_allclose(pose_error(result.pose, nearer), 0.0, atol=1e-6)
    # the seed's single start from the prior fails from far enough
    far = twin(TRUTH) + np.array([0.0, 0.0, 1.5])
    single = observe_pose(features, far, FIELD, CONFIG)
    assert single.observation is None  # refused: the error says the match is inconsistent
    for fit in (TRUTH, twin(TRUTH)):  # where it stopped is neither of the two fits
        assert np.abs(pose_error(single.pose, fit)).max() > 0.1


def test_a_missing_field_map_is_a_type_error_naming_it() -> None:
    with pytest.raises(TypeError, match="field_map must be a FieldMap, got NoneType"):
        observe_pose([], np.zeros(3), None, CONFIG)  # type: ignore[arg-type]


def _lstsq_step(weights: np.ndarray, levers: np.ndarray, residuals: np.ndarray) -> np.ndarray:
    """The step by SVD least squares over the counted rows (the oracle)."""
    rows, targets = [], []
    for i in range(len(levers)):
        for axis in (0, 1):
            if weights[i, axis] > 0.0:
                row = np.zeros(3)
                row[axis], row[2] = 1.0, levers[i, axis]
                rows.append(math.sqrt(weights[i, axis]) * row)
                targets.append(math.sqrt(weights[i, axis]) * residuals[i, axis])
    return np.linalg.lstsq(np.array(rows), np.array(targets), rcond=None)[0]


@pytest.mark.parametrize("counted", ["both", "y_only", "x_only", "mixed"])
def test_the_step_is_the_minimum_norm_least_squares_solution(counted: str) -> None:
    """The closed-form step equals SVD least squares; an axis with no counted component (lines
    along it only) gets no translation, as the minimum-norm solution gives it."""
    rng = np.random.default_rng(5)
    n = 6
    weights = rng.uniform(0.2, 2.0, (n, 2))
    if counted == "y_only":
        weights[:, 0] = 0.0
    elif counted == "x_only":
        weights[:, 1] = 0.0
    elif counted == "mixed":
        weights[: n // 2, 0] = 0.0
        weights[n // 2 :, 1] = 0.0
    levers = rng.normal(0.0, 1.0, (n, 2))
    residuals = rng.normal(0.0, 0.1, (n, 2))
    got = np.array(sensor_model._step_solution(weights, levers, residuals))
    np.testing.assert_allclose(got, _lstsq_step(weights, levers, residuals), atol=1e-12)
    if counted in ("y_only", "x_only"):
        assert got[0 if counted == "y_only" else 1] == 0.0


@pytest.mark.parametrize("lever_m", [0.0, 1e-9])
def test_one_point_pins_the_translation_and_leaves_the_turn_alone(lever_m: float) -> None:
    """A single point pair (its lever zero about the centroid, or rounding's nanometre) says
    nothing of the turn: the step moves the point onto its target and turns by nothing."""
    weights = np.array([[1.5, 1.5], [0.5, 0.5]])
    residuals = np.array([[0.3, -0.2], [0.3, -0.2]])
    levers = np.array([[lever_m, -lever_m], [0.0, 0.0]])
    got = sensor_model._step_solution(weights, levers, residuals)
    np.testing.assert_allclose(got, [0.3, -0.2, 0.0], atol=1e-12)


def test_a_step_without_counted_components_is_refused() -> None:
    with pytest.raises(ValueError, match="weights"):
        sensor_model._step_solution(np.zeros((2, 2)), np.ones((2, 2)), np.ones((2, 2)))


def test_stopping_before_every_item_is_matched_observes_from_the_matched_ones() -> None:
    """With fewer iterations than items the ICP stops before the last items join: the
    observation comes from the items matched by then (here the first two: the corner and the
    goal post, one feature each)."""
    config = SensorModelConfig(max_iterations=2)
    features = rich_view()
    assert len(match_items(features, FIELD, config)) > 2
    result = observe_pose(features, TRUTH + np.array([0.05, -0.03, 0.02]), FIELD, config)
    assert result.observation is not None
    assert result.observation.features == 2
    assert len(result.matches) == 2


def test_the_pseudo_inverse_is_numpys_on_a_rank_deficient_matrix() -> None:
    """Lines along one axis say nothing along it: the normal matrix has a zero direction,
    which the pseudo-inverse leaves at zero as numpy's does."""
    rng = np.random.default_rng(2)
    a = rng.normal(size=(6, 3))
    a[:, 0] = 0.0  # no row constrains x
    normal = a.T @ a
    np.testing.assert_allclose(
        sensor_model._pseudo_inverse(normal),
        np.linalg.pinv(normal, rcond=1e-10, hermitian=True),
        atol=1e-12,
    )


def test_each_item_takes_its_nearest_candidate_the_first_of_equals() -> None:
    """The matcher's one-pass costs pick, per item, the candidate a per-item search picks:
    the nearest (line ends' distances to the map segment; a point's distance plus its
    direction's difference), the first of equals, over items of 1 to many candidates."""
    rng = np.random.default_rng(4)
    items = match_items(rich_view(rng=rng), FIELD, CONFIG)
    assert {len(item.candidates) for item in items} >= {1} and max(
        len(item.candidates) for item in items
    ) > 1
    matcher = sensor_model._Matcher(items, CONFIG)
    for _ in range(20):
        pose = TRUTH + rng.normal(0.0, [0.5, 0.5, 0.3])
        expected = tuple(
            int(np.argmin([brute_cost(item, c, pose) for c in item.candidates])) for item in items
        )
        assert matcher.nearest(pose, len(items)) == expected


def brute_cost(
    item: sensor_model.MatchItem, candidate: tuple[MapFeature, ...], pose: np.ndarray
) -> float:
    """The matching cost of ``item`` placed from ``pose`` against ``candidate``, by hand."""
    c, s = math.cos(pose[2]), math.sin(pose[2])
    total = 0.0
    for feature, target in zip(item.features, candidate, strict=True):
        placed = feature.points @ np.array([[c, s], [-s, c]]) + pose[:2]
        if feature.kind == "line":
            a, b = target.points
            for p in placed:
                t = min(max(float((p - a) @ (b - a)) / float((b - a) @ (b - a)), 0.0), 1.0)
                total += float(np.hypot(*(p - a - t * (b - a))))
            continue
        total += float(np.hypot(*(placed[0] - target.points[0])))
        if feature.direction is not None and target.direction is not None:
            turn = feature.direction + pose[2] - target.direction
            if feature.kind in ("x_junction", "centre_circle"):
                gap = abs(float(wrap_angle(2.0 * turn))) / 2
            else:
                gap = abs(float(wrap_angle(turn)))
            total += CONFIG.direction_scale_m_per_rad * gap
    return total
