"""The natural-landmark field end as a provider: views stored while walking on, labelled by
the end the camera faces, recognised afterwards; and the pipeline feeding it the previous
frame's pose."""

from __future__ import annotations

import math

import numpy as np
import pytest

from perception.field.features import FieldFeature
from perception.landmarks.field_end import AWAY, HOME
from perception.landmarks.horizon_features import HorizonFeatures
from perception.landmarks.surf1d import Surf1dFeatures
from perception.landmarks.vocabulary import default_vocabulary
from perception.pipeline import PerceptionPipeline, PipelineConfig
from perception.providers.base import PREVIOUS, PerceptionContext
from perception.providers.field_end import (
    ENDS,
    SIDES,
    UNKNOWN,
    FieldEndProviderConfig,
    NaturalLandmarkFieldEnd,
)
from perception.representations import (
    FIELD_END,
    FIELD_FEATURES,
    HORIZON_FEATURES,
    ROBOT_SIGHTINGS,
    SELF_POSE,
    Prior,
)
from perception.types import CameraModel, PoleGeometry, SlamEstimate, TrackedPoseEstimate

WORDS = default_vocabulary().words
CONTEXT = PerceptionContext(CameraModel(), (), PoleGeometry())
POST = FieldFeature("goal_post", np.array([[2.0, 0.1]]), 1e-4 * np.eye(2)[None])


def view(end: int, shift_px: float = 0.0, *, novel: bool = False) -> HorizonFeatures:
    """A goal area's horizon: 40 features on distinct words (one end's words, the other's
    another set; ``novel``: a third set, a view from elsewhere) at spread columns, shifted by
    ``shift_px``."""
    usable = np.flatnonzero(~default_vocabulary().stopped)
    words = usable[80:120] if novel else usable[:40] if end == AWAY else usable[40:80]
    n = len(words)
    x = np.linspace(10.0, 300.0, n) + shift_px
    features = Surf1dFeatures(
        index=np.arange(n),
        x=x,
        scale=np.ones(n),
        filter_size=np.full(n, 9),
        laplacian=np.ones(n, dtype=np.int8),
        response=np.ones(n),
        descriptors=WORDS[words],
    )
    camera = CameraModel()
    bearings = np.arctan((camera.cx - x) / camera.fx)
    return HorizonFeatures(features=features, bearings=bearings, head_yaw=0.0)


def estimate(heading: float) -> SlamEstimate:
    return SlamEstimate(
        pose=np.array([0.0, 0.0, heading]),
        pose_cov=np.eye(3) * 0.01,
        landmark_ids=np.zeros(0, dtype=np.int64),
        landmarks=np.zeros((0, 2)),
        landmark_covs=np.zeros((0, 2, 2)),
    )


def tracked(
    heading: float, *, accepted: bool, x: float = 0.0, restarted: bool = False
) -> TrackedPoseEstimate:
    """The field-feature pose filter's estimate at (x, 0, heading); ``accepted``: it took the
    frame's features; ``restarted``: it relocalised or turned through the centre spot."""
    return TrackedPoseEstimate(
        pose=np.array([x, 0.0, heading]),
        pose_cov=np.eye(3) * 0.01,
        landmark_ids=np.zeros(0, dtype=np.int64),
        landmarks=np.zeros((0, 2)),
        landmark_covs=np.zeros((0, 2, 2)),
        accepted=accepted,
        restarted=restarted,
    )


def walked_on(config: FieldEndProviderConfig) -> NaturalLandmarkFieldEnd:
    """A provider after a walk-on (``config.walk_on_s`` <= 1 s) of five views of each end,
    ending facing away at the centre spot."""
    provider = NaturalLandmarkFieldEnd(config, CONTEXT)
    provider.reset(Prior(pose=np.zeros(3), rng=np.random.default_rng(0)))
    for end, heading in ((HOME, math.pi), (AWAY, 0.0)):
        for k in range(5):
            inputs = {
                HORIZON_FEATURES: view(end, shift_px=2.0 * k),
                FIELD_FEATURES: (),
                PREVIOUS + SELF_POSE: tracked(heading, accepted=True),
            }
            provider.update(inputs, 0.1 * k)
    return provider


def walked_on_sides(config: FieldEndProviderConfig) -> NaturalLandmarkFieldEnd:
    """A provider after a walk-on (``config.walk_on_s`` <= 1 s) of five views of each side
    board at the centre spot: the +y board shows the words of :func:`view` ``(AWAY)``, the -y
    board those of ``view(HOME)``; every walk-on frame returns the unknown belief."""
    provider = NaturalLandmarkFieldEnd(config, CONTEXT)
    provider.reset(Prior(pose=np.zeros(3), rng=np.random.default_rng(0)))
    for side, heading in ((1, math.pi / 2), (-1, -math.pi / 2)):
        for k in range(5):
            inputs = {
                HORIZON_FEATURES: view(AWAY if side > 0 else HOME, shift_px=2.0 * k),
                FIELD_FEATURES: (),
                PREVIOUS + SELF_POSE: tracked(heading, accepted=True),
            }
            assert provider.update(inputs, 0.1 * k) == UNKNOWN
    return provider


def play(
    provider: NaturalLandmarkFieldEnd, time_s: float, seen: HorizonFeatures, pose: SlamEstimate
) -> int:
    """One play frame seeing ``seen`` after the estimate ``pose``: the database's size after."""
    provider.update(
        {HORIZON_FEATURES: seen, FIELD_FEATURES: (), PREVIOUS + SELF_POSE: pose}, time_s
    )
    return len(provider._recogniser.database)  # type: ignore[union-attr]


@pytest.mark.parametrize(
    ("learn_in_play", "accepted", "stored"), [(True, True, 1), (True, False, 0), (False, True, 0)]
)
def test_a_new_play_view_is_stored_once_the_pose_filter_took_its_frame(
    learn_in_play: bool, accepted: bool, stored: int
) -> None:
    """After the walk-on the pose is trusted: a view unlike any stored, facing the away goal,
    is stored on the next frame, labelled away, if the pose filter took the frame's features
    (a kidnapped robot's would be refused) and learning in play is on."""
    provider = walked_on(FieldEndProviderConfig(walk_on_s=1.0, learn_in_play=learn_in_play))
    database = provider._recogniser.database  # type: ignore[union-attr]
    size, away = len(database), database.count(AWAY)
    assert play(provider, 1.0, view(AWAY, novel=True), tracked(0.0, accepted=True)) == size
    after = play(provider, 1.1, view(AWAY), tracked(0.0, accepted=accepted))
    assert after == size + stored and database.count(AWAY) == away + stored
    assert provider.learned == stored


def test_after_the_pose_filter_restarts_views_are_stored_only_once_observations_agree() -> None:
    """learn_after_agreeing = 2: after the filter relocalised, a new view is stored only once
    two away observations agreed with the pose (facing away)."""
    provider = walked_on(FieldEndProviderConfig(walk_on_s=1.0, learn_in_play=True))
    database = provider._recogniser.database  # type: ignore[union-attr]
    size = len(database)
    here = tracked(0.0, accepted=True)
    relocalised = tracked(0.0, accepted=True, x=1.0, restarted=True)
    there = tracked(0.0, accepted=True, x=1.0)
    play(provider, 1.0, view(AWAY, novel=True), here)
    # the filter relocalised 1 m away: the candidate is not stored, and the new view seen there
    # is none (no observation has agreed with the pose since)
    assert play(provider, 1.1, view(AWAY, novel=True), relocalised) == size
    t = 1.2
    for stored in (0, 1):
        for _ in range(100):  # views of the stored away goal until one is recognised
            t += 0.1
            seen = {HORIZON_FEATURES: view(AWAY), FIELD_FEATURES: (), PREVIOUS + SELF_POSE: there}
            if provider.update(seen, t).observation == AWAY:
                break
        else:
            pytest.fail("the stored away views never gave an away observation")
        play(provider, t + 0.1, view(AWAY, novel=True), there)
        assert play(provider, t + 0.2, view(AWAY), there) == size + stored
        t += 0.2


def test_a_half_turn_of_the_pose_filter_ends_the_trust_too() -> None:
    """A half turn through the centre spot is a restart: the view seen before it is not
    stored, though the filter took the frame's features."""
    provider = walked_on(FieldEndProviderConfig(walk_on_s=1.0, learn_in_play=True))
    size = len(provider._recogniser.database)  # type: ignore[union-attr]
    play(provider, 1.0, view(AWAY, novel=True), tracked(0.0, accepted=True))
    turned = tracked(math.pi, accepted=True, restarted=True)
    assert play(provider, 1.1, view(HOME), turned) == size


def test_a_restart_during_the_walk_on_ends_the_walk_ons_trust() -> None:
    """The filter restarts on the walk-on's last frame: play's new views are not stored until
    observations agree with the pose again."""
    provider = walked_on(FieldEndProviderConfig(walk_on_s=1.0, learn_in_play=True))
    provider.update(
        {
            HORIZON_FEATURES: view(AWAY),
            FIELD_FEATURES: (),
            PREVIOUS + SELF_POSE: tracked(0.0, accepted=True, restarted=True),
        },
        0.9,
    )
    size = len(provider._recogniser.database)  # type: ignore[union-attr]
    play(provider, 1.0, view(AWAY, novel=True), tracked(0.0, accepted=True))
    assert play(provider, 1.1, view(AWAY), tracked(0.0, accepted=True)) == size


def test_a_pose_that_moves_without_a_restart_keeps_the_trust() -> None:
    """Trust ends with the filter's restarts, not with how far its pose moves: a pose 1 m
    from the last (a fast walk, a large correction) still stores the new view."""
    provider = walked_on(FieldEndProviderConfig(walk_on_s=1.0, learn_in_play=True))
    size = len(provider._recogniser.database)  # type: ignore[union-attr]
    play(provider, 1.0, view(AWAY, novel=True), tracked(0.0, accepted=True))
    assert play(provider, 1.1, view(AWAY), tracked(0.0, accepted=True, x=1.0)) == size + 1


def test_a_new_episode_trusts_its_walk_on_again() -> None:
    config = FieldEndProviderConfig(walk_on_s=1.0, learn_in_play=True)
    provider = walked_on(config)
    play(provider, 1.0, view(AWAY, novel=True), tracked(0.0, accepted=True))
    relocalised = tracked(0.0, accepted=True, x=1.0, restarted=True)
    play(provider, 1.1, view(AWAY), relocalised)  # a restart: no trust
    assert provider.learned == 0
    provider.reset(Prior(pose=np.zeros(3), rng=np.random.default_rng(1)))
    assert len(provider._recogniser.database) == 0  # type: ignore[union-attr]
    for k in range(5):  # the walk-on, facing away, ending at x = 1 m
        seen = {
            HORIZON_FEATURES: view(AWAY, shift_px=2.0 * k),
            FIELD_FEATURES: (),
            PREVIOUS + SELF_POSE: tracked(0.0, accepted=True, x=1.0),
        }
        provider.update(seen, 0.1 * k)
    size = len(provider._recogniser.database)  # type: ignore[union-attr]
    here = tracked(0.0, accepted=True, x=1.0)
    play(provider, 1.0, view(AWAY, novel=True), here)
    assert play(provider, 1.1, view(AWAY), here) == size + 1 and provider.learned == 1


def test_views_stored_on_the_walk_on_tell_the_ends_apart_later() -> None:
    config = FieldEndProviderConfig(walk_on_s=2.0)
    provider = NaturalLandmarkFieldEnd(config, CONTEXT)
    provider.reset(Prior(pose=np.zeros(3), rng=np.random.default_rng(0)))
    t = 0.0
    for end, heading in ((AWAY, 0.0), (HOME, math.pi)):  # the walk on: both ends in view
        for k in range(5):
            inputs = {
                HORIZON_FEATURES: view(end, shift_px=2.0 * k),
                FIELD_FEATURES: (POST,),
                PREVIOUS + SELF_POSE: estimate(heading),
            }
            stored = len(provider._recogniser.database)  # type: ignore[union-attr]
            provider.update(inputs, t)
            grown = len(provider._recogniser.database) - stored  # type: ignore[union-attr]
            assert grown in (0, 1)  # a walk-on frame stores at most its own view
            t += 0.1
    database = provider._recogniser.database  # type: ignore[union-attr]
    assert database.count(AWAY) >= 1 and database.count(HOME) >= 1  # both ends stored
    t = 2.5
    for end in (AWAY, HOME):
        for k in range(config.recogniser.window):  # playing: a window of views of one end
            # the pose believes the robot faces +x whatever it sees: recognition must not care
            inputs = {
                HORIZON_FEATURES: view(end, shift_px=5.0 + k % 3),
                FIELD_FEATURES: (),
                PREVIOUS + SELF_POSE: estimate(0.0),
            }
            belief = provider.update(inputs, t)
            t += 0.1
        assert belief.certain == end
        assert (belief.p_away > 0.9) if end == AWAY else (belief.p_away < 0.1)


def test_a_camera_facing_the_side_line_is_not_recognised() -> None:
    provider = NaturalLandmarkFieldEnd(FieldEndProviderConfig(walk_on_s=0.5), CONTEXT)
    provider.reset(Prior(pose=np.zeros(3), rng=np.random.default_rng(0)))
    inputs = {
        HORIZON_FEATURES: view(AWAY),
        FIELD_FEATURES: (POST,),
        PREVIOUS + SELF_POSE: estimate(math.pi / 2),  # facing the side
    }
    provider.update(inputs, 0.0)
    assert len(provider._recogniser.database) == 0  # type: ignore[union-attr]
    belief = provider.update(inputs, 1.0)
    assert belief.hits == () and belief.certain == 0


@pytest.mark.parametrize(("needs_post", "stored"), [(False, 1), (True, 0)])
def test_a_walk_on_view_needs_a_goal_post_only_when_configured(
    needs_post: bool, stored: int
) -> None:
    """Facing the away goal area with no post detected: stored by default, not with the
    seed's check."""
    config = FieldEndProviderConfig(walk_on_s=1.0, walk_on_needs_post=needs_post)
    provider = NaturalLandmarkFieldEnd(config, CONTEXT)
    provider.reset(Prior(pose=np.zeros(3), rng=np.random.default_rng(0)))
    inputs = {
        HORIZON_FEATURES: view(AWAY),
        FIELD_FEATURES: (),
        PREVIOUS + SELF_POSE: estimate(0.0),
    }
    provider.update(inputs, 0.0)
    assert len(provider._recogniser.database) == stored  # type: ignore[union-attr]


def test_the_pipeline_runs_the_field_end_before_the_pose_it_reads_late() -> None:
    config = PipelineConfig(
        self_pose="field_features", field_features="oracle", field_end="bag_of_words"
    )
    pipeline = PerceptionPipeline(config, CONTEXT, outputs=[SELF_POSE])
    order = pipeline.representations
    assert order.index(FIELD_END) < order.index(SELF_POSE)  # no cycle: the pose comes late
    assert isinstance(pipeline.provider(FIELD_END), NaturalLandmarkFieldEnd)
    # the features on robots go before anyone reads the horizon
    assert order.index(ROBOT_SIGHTINGS) < order.index(HORIZON_FEATURES) < order.index(FIELD_END)


def test_bad_provider_settings_are_refused() -> None:
    with pytest.raises(ValueError, match="walk_on_s"):
        FieldEndProviderConfig(walk_on_s=0.0)
    with pytest.raises(ValueError, match="facing_tolerance_rad"):
        FieldEndProviderConfig(facing_tolerance_rad=2.0)
    with pytest.raises(TypeError, match="walk_on_needs_post"):
        FieldEndProviderConfig(walk_on_needs_post=1)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="learn_in_play"):
        FieldEndProviderConfig(learn_in_play=1)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="side_boards"):
        FieldEndProviderConfig(side_boards=1)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="learn_after_agreeing"):
        FieldEndProviderConfig(learn_after_agreeing=0)


def test_facing_a_goal_area_means_the_optical_axis_meets_the_end_between_the_side_lines() -> None:
    provider = NaturalLandmarkFieldEnd(FieldEndProviderConfig(), CONTEXT)
    field = CONTEXT.field
    edge = field.half_length_m + field.border_strip_m
    assert provider._facing(np.array([0.0, 0.0, 0.0]), 0.0, ENDS) == AWAY
    assert provider._facing(np.array([0.0, 0.0, 0.0]), math.pi, ENDS) == HOME
    assert provider._facing(np.array([0.0, 0.0, 0.0]), math.pi / 2, ENDS) == 0  # the side line
    # from near the side line, a heading aiming just inside / outside the end's corner
    y0 = field.half_width_m - 0.2
    inside = math.atan2(0.1, edge - 1.0)  # meets the edge 0.1 m past y0: inside
    outside = math.atan2(0.3, edge - 1.0)  # 0.3 m past: beyond the side line's extension
    assert provider._facing(np.array([1.0, y0, 0.0]), inside, ENDS) == AWAY
    assert provider._facing(np.array([1.0, y0, 0.0]), outside, ENDS) == 0


def test_facing_a_side_board_means_the_optical_axis_meets_it_between_the_end_lines() -> None:
    provider = NaturalLandmarkFieldEnd(FieldEndProviderConfig(), CONTEXT)
    field = CONTEXT.field
    edge = field.half_width_m + field.border_strip_m
    centre = np.array([0.0, 0.0, 0.0])
    assert provider._facing(centre, math.pi / 2, SIDES) == 1
    assert provider._facing(centre, -math.pi / 2, SIDES) == -1
    assert provider._facing(centre, 0.0, SIDES) == 0  # an end
    assert provider._facing(centre, math.radians(45.0), SIDES) == 0  # beyond the tolerance
    # from near the end line, a heading aiming just inside / outside the side's corner
    x0 = field.half_length_m - 0.2
    inside = math.atan2(edge - 1.0, 0.1)  # meets the edge 0.1 m past x0: inside
    outside = math.atan2(edge - 1.0, 0.3)  # 0.3 m past: beyond the end line's extension
    assert provider._facing(np.array([x0, 1.0, 0.0]), inside, SIDES) == 1
    assert provider._facing(np.array([x0, 1.0, 0.0]), outside, SIDES) == 0


@pytest.mark.parametrize("side_boards", [True, False])
def test_side_board_views_stored_on_the_walk_on_tell_the_sides_apart(side_boards: bool) -> None:
    """Walking on at the centre spot facing +y (one board's words) and -y (another's); in
    play the pose faces +y: a view of the +y board is a side observation of +1, of the -y
    board -1 (the pose is mirrored), and no end observation; without ``side_boards`` none."""
    provider = walked_on_sides(FieldEndProviderConfig(walk_on_s=1.0, side_boards=side_boards))
    assert len(provider._recogniser.database) == 0  # type: ignore[union-attr]
    t = 1.0
    for words, expected in ((AWAY, 1), (HOME, -1)):
        observed = set()
        for k in range(10):
            seen = {
                HORIZON_FEATURES: view(words, shift_px=5.0 + k % 3),
                FIELD_FEATURES: (),
                PREVIOUS + SELF_POSE: tracked(math.pi / 2, accepted=False),
            }
            belief = provider.update(seen, t)
            assert belief.observation == 0
            observed.add(belief.side_observation)
            t += 0.1
        if side_boards:
            assert expected in observed and -expected not in observed
        else:
            assert observed == {0}


@pytest.mark.parametrize("disagreed", [False, True])
def test_side_views_are_learned_in_play_while_the_pose_is_trusted(disagreed: bool) -> None:
    """After a walk-on facing both sides, a novel view of the +y board (the pose facing +y)
    is stored on the next accepted frame; not once a view of the -y board disagreed."""
    provider = walked_on_sides(FieldEndProviderConfig(walk_on_s=1.0))
    sides = provider._sides
    assert sides is not None
    size, t = len(sides.database), 1.0
    facing_plus_y = tracked(math.pi / 2, accepted=True)
    if disagreed:  # the -y board seen while the pose faces +y, until an observation says so
        for _ in range(20):
            seen = {
                HORIZON_FEATURES: view(HOME),
                FIELD_FEATURES: (),
                PREVIOUS + SELF_POSE: facing_plus_y,
            }
            t += 0.1
            if provider.update(seen, t).side_observation == -1:
                break
        else:
            pytest.fail("the -y board's stored views never gave a -y observation")
    play(provider, t + 0.1, view(AWAY, novel=True), facing_plus_y)
    play(provider, t + 0.2, view(AWAY), facing_plus_y)
    assert len(sides.database) == size + (0 if disagreed else 1)


def test_features_on_the_faced_goal_are_left_out() -> None:
    provider = NaturalLandmarkFieldEnd(FieldEndProviderConfig(goal_margin_rad=0.0), CONTEXT)
    seen = view(AWAY)
    pose = np.array([0.0, 0.0, 0.0])
    on_goal = provider._on_goal(seen, pose, AWAY)
    post = CONTEXT.field.goal_posts()[3]  # the away goal's left post
    half = math.atan2(post[1], post[0])  # the posts' bearings from the centre spot: +-half
    np.testing.assert_array_equal(on_goal, np.abs(seen.bearings) <= half)
    assert on_goal.any() and not on_goal.all()


@pytest.mark.parametrize("axis", [ENDS, SIDES])
def test_only_features_on_the_faced_boards_are_kept(axis: int) -> None:
    """5 m from the +1 board of ``axis`` (the away end's, the +y side's), facing it, 3 m to
    the left of the field's middle line across it: the board spans ``extent`` either side of
    that line, so a bearing b (+ left) meets it where ``3 + 5 tan(b)`` (to the left of that
    line) lies within ``extent`` of it."""
    provider = NaturalLandmarkFieldEnd(FieldEndProviderConfig(), CONTEXT)
    field = CONTEXT.field
    half = (field.half_length_m, field.half_width_m)
    edge = half[axis] + field.border_strip_m
    extent = half[1 - axis] + field.border_strip_m
    seen = view(AWAY)
    # facing +x, 3 m to the left is y = 3; facing +y, it is x = -3
    pose = (
        np.array([edge - 5.0, 3.0, 0.0])
        if axis == ENDS
        else np.array([-3.0, edge - 5.0, math.pi / 2])
    )
    on_board = provider._on_boards(seen, pose, 1, axis)
    left, right = math.atan2(extent - 3.0, 5.0), math.atan2(-extent - 3.0, 5.0)
    np.testing.assert_array_equal(on_board, (seen.bearings <= left) & (seen.bearings >= right))
    assert on_board.any() and not on_board.all()
    assert not provider._on_boards(seen, pose, -1, axis).any()  # nothing on the other board
