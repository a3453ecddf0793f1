"""Field-end recognition (:mod:`perception.landmarks.field_end`, seed 004 Algorithm 1): the
walk-on database, votes and the beta belief over the observation window."""

from __future__ import annotations

import numpy as np
import pytest

from perception.landmarks.field_end import (
    AWAY,
    HOME,
    FieldEndConfig,
    FieldEndRecogniser,
)
from perception.landmarks.vocabulary import Vocabulary

COLUMNS = 10.0 + 25.0 * np.arange(12)  # 12 features spread over a 320 px image
VOCABULARY = Vocabulary(words=np.arange(100, dtype=float)[:, None], stopped=np.zeros(100, bool))


def view(n: int) -> np.ndarray:
    """The words of view n: 12 words of its own (n = 0 .. 7)."""
    return np.arange(12 * n, 12 * n + 12)


def recogniser(**kwargs: object) -> FieldEndRecogniser:
    return FieldEndRecogniser(
        VOCABULARY,
        FieldEndConfig(**kwargs),  # type: ignore[arg-type]
        np.random.default_rng(0),
    )


def with_two_goals(**kwargs: object) -> FieldEndRecogniser:
    """Database: view 0 facing the away goal, view 1 facing the home goal (a frame facing no
    goal in between, so that view 1 is stored without view 0's words)."""
    r = recogniser(**kwargs)
    assert r.build(view(0), COLUMNS, AWAY, facing_goal=True, post_visible=True)
    assert not r.build(view(0), COLUMNS, AWAY, facing_goal=False, post_visible=True)
    assert r.build(view(1), COLUMNS, HOME, facing_goal=True, post_visible=True)
    assert len(r.database) == 2
    return r


def test_p_away_is_the_beta_mean_over_the_window() -> None:
    """After k away and j home observations in the window P(away) = (1 + k) / (2 + k + j);
    frames facing no goal add no observation but age the window (5 frames here)."""
    r = with_two_goals(min_consensus=1, window=5)
    assert r.observe(view(1), COLUMNS, facing_goal=False).p_away == 0.5
    beliefs = [r.observe(view(0), COLUMNS + 5.0, facing_goal=True) for _ in range(3)]
    assert [b.p_away for b in beliefs] == [2 / 3, 3 / 4, 4 / 5]
    assert [b.votes for b in beliefs] == [1, 1, 1]
    beliefs = [r.observe(view(1), COLUMNS - 5.0, facing_goal=True) for _ in range(2)]
    assert [b.hits[0].label for b in beliefs] == [HOME, HOME]
    last = beliefs[-1]
    assert (last.away_observations, last.home_observations) == (3, 2)
    assert last.p_away == 4 / 7
    # the oldest observations leave the window: (2 away, 2 home), then (1, 2), (0, 2), (0, 1)
    p = [r.observe(view(1), COLUMNS, facing_goal=False).p_away for _ in range(4)]
    assert p == [3 / 6, 2 / 5, 1 / 4, 1 / 3]


def test_the_first_view_after_turning_is_voted_on_this_frames_features() -> None:
    """The query sums the previous frame (away view) with this one (home view): both images
    share words with it, but only the home view's features verify."""
    r = with_two_goals(min_consensus=1)
    r.observe(view(0), COLUMNS, facing_goal=True)
    belief = r.observe(view(1), COLUMNS, facing_goal=True)
    assert [hit.image for hit in belief.hits] == [1]
    assert belief.hits[0].cosine == pytest.approx(1 / np.sqrt(2))


def test_votes_need_the_consensus() -> None:
    r = with_two_goals(min_consensus=2)
    belief = r.observe(view(0), COLUMNS, facing_goal=True)
    assert belief.votes == 1
    assert (belief.away_observations, belief.home_observations, belief.p_away) == (0, 0, 0.5)


def test_a_certain_observation_passes_the_confidence() -> None:
    r = with_two_goals(min_consensus=1, confidence=0.75)
    certain = [r.observe(view(0), COLUMNS, facing_goal=True).certain for _ in range(3)]
    assert certain == [0, 0, AWAY]  # P(away) = 2/3, 3/4 (not above 0.75), 4/5
    r.reset()
    assert len(r.database) == 0
    assert r.observe(view(0), COLUMNS, facing_goal=True).p_away == 0.5  # window cleared
    r = with_two_goals(min_consensus=1, confidence=0.75)
    certain = [r.observe(view(1), COLUMNS, facing_goal=True).certain for _ in range(3)]
    assert certain == [0, 0, HOME]


def test_building_stops_at_max_size() -> None:
    """Views of their own words draw no hit (a view shares only the previous frame's words
    with the last stored image, and those fail the geometric check), until the database is
    full."""
    r = recogniser(max_size=3, min_response=1)
    stored = [
        r.build(view(n), COLUMNS, AWAY, facing_goal=True, post_visible=True) for n in range(5)
    ]
    assert stored == [True, True, True, False, False]
    assert len(r.database) == 3


def test_building_stores_at_most_max_per_goal_views_of_each_goal() -> None:
    """With room for two views per goal, the third away view is refused and a home view is
    still stored (the seed: up to 40 images of each goal area)."""
    r = recogniser(max_per_goal=2, min_response=1)
    labels = (AWAY, AWAY, AWAY, HOME)
    stored = [
        r.build(view(n), COLUMNS, label, facing_goal=True, post_visible=True)
        for n, label in enumerate(labels)
    ]
    assert stored == [True, True, False, True]
    assert (r.database.count(AWAY), r.database.count(HOME)) == (2, 1)


def with_three_away_and_one_home(**kwargs: object) -> FieldEndRecogniser:
    """Database: views 0, 2 and 4 facing the away goal, view 1 facing home (each after a
    frame facing no goal: no query expansion)."""
    r = recogniser(**kwargs)
    for n, label in ((0, AWAY), (2, AWAY), (4, AWAY), (1, HOME)):
        r.build(view(n), COLUMNS, label, facing_goal=False, post_visible=True)
        assert r.build(view(n), COLUMNS, label, facing_goal=True, post_visible=True)
    return r


@pytest.mark.parametrize(("balance_votes", "votes"), [(True, 2 / 3 - 2), (False, 0.0)])
def test_votes_are_scaled_by_each_goals_share_of_the_database(
    balance_votes: bool, votes: float
) -> None:
    """A view holding views 0 (away) and 1 (home) side by side hits both. Balanced, with 3
    away and 1 home images (N = 4) an away hit counts (4 / 2) / 3 = 2/3 and a home hit
    (4 / 2) / 1 = 2: net -4/3, a home observation at min_consensus 1; unbalanced, 1 - 1 = 0,
    none."""
    r = with_three_away_and_one_home(min_consensus=1.0, balance_votes=balance_votes)
    words = np.concatenate([view(0), view(1)])
    x = np.concatenate([COLUMNS, COLUMNS + 1.0])
    belief = r.observe(words, x, facing_goal=True)
    assert sorted(hit.image for hit in belief.hits) == [0, 3]
    assert belief.votes == pytest.approx(votes)
    assert belief.observation == (HOME if balance_votes else 0)


def test_building_adds_only_frames_with_fewer_than_min_response_hits() -> None:
    for min_response, expected in ((1, False), (2, True)):
        r = with_two_goals(min_response=min_response)
        r.build(view(0), COLUMNS, AWAY, facing_goal=False, post_visible=False)  # no expansion
        stored = r.build(view(0), COLUMNS + 3.0, AWAY, facing_goal=True, post_visible=True)
        assert stored is expected  # one hit: image 0
        assert len(r.database) == 2 + expected


def test_building_needs_a_goal_area_and_a_visible_post() -> None:
    r = recogniser()
    for facing_goal, post_visible in ((False, True), (True, False), (False, False)):
        added = r.build(view(0), COLUMNS, HOME, facing_goal=facing_goal, post_visible=post_visible)
        assert not added
    assert len(r.database) == 0


def stored_counts(r: FieldEndRecogniser) -> np.ndarray:
    """The word counts (K,) of the last image the recogniser's database stored."""
    return r.database._images[-1].counts


def test_a_labelled_play_frame_with_few_hits_is_remembered_only_when_asked() -> None:
    r = with_two_goals(min_response=2)
    assert not r.remember()  # nothing observed yet: no candidate
    r.observe(view(2), COLUMNS, facing_goal=False)  # no expansion with the walk-on's last
    r.observe(view(2), COLUMNS, facing_goal=True, label=AWAY)  # new words: no hit
    assert len(r.database) == 2  # observing alone stores nothing
    assert r.remember() and len(r.database) == 3 and r.database.count(AWAY) == 2
    np.testing.assert_array_equal(stored_counts(r), np.isin(np.arange(100), view(2)))
    assert not r.remember()  # stored once
    # a frame without a label, or one not facing a goal, leaves no candidate
    r.observe(view(3), COLUMNS, facing_goal=True)
    assert not r.remember()
    r.observe(view(4), COLUMNS, facing_goal=False, label=HOME)
    assert not r.remember()


def test_the_next_observed_frame_replaces_the_candidate() -> None:
    r = with_two_goals(min_response=2)
    r.observe(view(5), COLUMNS, facing_goal=False)
    r.observe(view(5), COLUMNS, facing_goal=True, label=HOME)
    r.observe(view(6), COLUMNS, facing_goal=True, label=AWAY)
    assert r.remember() and r.database.count(HOME) == 1 and r.database.count(AWAY) == 2
    # ... stored with its own words only: the frame before faced the other goal
    np.testing.assert_array_equal(stored_counts(r), np.isin(np.arange(100), view(6)))
    r.observe(view(7), COLUMNS, facing_goal=True, label=AWAY)
    r.observe(view(7), COLUMNS, facing_goal=False)
    assert not r.remember() and len(r.database) == 3


def test_a_candidate_is_expanded_with_the_frame_before_of_its_label() -> None:
    r = with_two_goals(min_response=3)
    r.observe(view(5), COLUMNS, facing_goal=False)
    r.observe(view(5), COLUMNS, facing_goal=True, label=AWAY)
    r.observe(view(6), COLUMNS, facing_goal=True, label=AWAY)
    assert r.remember()
    expected = np.isin(np.arange(100), view(5)).astype(int) + np.isin(np.arange(100), view(6))
    np.testing.assert_array_equal(stored_counts(r), expected)


def test_a_play_frame_that_draws_min_response_hits_is_no_candidate() -> None:
    r = with_two_goals(min_response=1)
    r.observe(view(0), COLUMNS + 3.0, facing_goal=True, label=AWAY)  # one hit: image 0
    assert not r.remember() and len(r.database) == 2


@pytest.mark.parametrize(
    ("limits", "label", "stored"),
    [
        ({"max_per_goal": 1}, HOME, False),  # HOME holds its one view
        ({"max_per_goal": 2}, HOME, True),
        ({"max_size": 2}, AWAY, False),
        ({"max_size": 3}, AWAY, True),
    ],
)
def test_remembering_keeps_to_the_database_limits(
    limits: dict[str, int], label: int, stored: bool
) -> None:
    r = with_two_goals(**limits)
    r.observe(view(2), COLUMNS, facing_goal=False)
    r.observe(view(2), COLUMNS, facing_goal=True, label=label)
    assert r.remember() is stored
    assert r.database.count(label) == 1 + stored


def test_building_forgets_a_play_candidate() -> None:
    r = with_two_goals(min_response=2)
    r.observe(view(2), COLUMNS, facing_goal=True, label=AWAY)
    r.build(view(3), COLUMNS, HOME, facing_goal=False, post_visible=True)
    assert not r.remember()


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"max_size": 0}, "FieldEndConfig.max_size"),
        ({"max_per_goal": 0}, "FieldEndConfig.max_per_goal"),
        ({"min_response": 0}, "FieldEndConfig.min_response"),
        ({"min_consensus": 0}, "FieldEndConfig.min_consensus"),
        ({"window": 0}, "FieldEndConfig.window"),
        ({"confidence": 0.5}, "FieldEndConfig.confidence"),
        ({"confidence": 1.0}, "FieldEndConfig.confidence"),
    ],
)
def test_bad_configs_are_named(kwargs: dict[str, object], field: str) -> None:
    with pytest.raises(ValueError, match=field):
        FieldEndConfig(**kwargs)  # type: ignore[arg-type]


def test_bad_arguments_are_refused() -> None:
    r = recogniser()
    with pytest.raises(ValueError, match="label"):
        r.build(view(0), COLUMNS, 0, facing_goal=True, post_visible=True)
    with pytest.raises(TypeError, match="facing_goal"):
        r.observe(view(0), COLUMNS, facing_goal=1)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"observe\.label"):
        r.observe(view(0), COLUMNS, facing_goal=True, label=2)
    with pytest.raises(TypeError, match=r"observe\.label"):
        r.observe(view(0), COLUMNS, facing_goal=True, label=None)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="balance_votes"):
        FieldEndConfig(balance_votes=1)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="retrieval"):
        FieldEndConfig(retrieval=None)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="rng"):
        FieldEndRecogniser(VOCABULARY, FieldEndConfig(), rng=0)  # type: ignore[arg-type]
