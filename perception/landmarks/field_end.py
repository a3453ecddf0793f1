"""Which end of the field the robot faces, from natural landmarks (seed 004 §4.2, Algorithm 1).

:class:`FieldEndRecogniser` keeps an :class:`perception.landmarks.bag_of_words.ImageDatabase`
of horizon views labelled :data:`AWAY` (+1) or :data:`HOME` (-1):

- :meth:`~FieldEndRecogniser.reset` at the start of each half clears the database and the
  observation window (Algorithm 1 lines 1-2);
- :meth:`~FieldEndRecogniser.build` while walking on (lines 3-7): a frame taken facing a goal
  area with a goal post visible queries the database and is stored with its label when it
  draws fewer than ``min_response`` hits and the database holds fewer than ``max_size``
  images, and fewer than ``max_per_goal`` of its label (the seed: up to 40 of each goal area;
  only correctly labelled views may enter: the caller vouches for the label);
- :meth:`~FieldEndRecogniser.observe` during play (lines 8-24): a frame facing a goal area
  queries the database; each hit votes +1 if stored facing the away goal, else -1, scaled
  (``balance_votes``) by ``(N / 2) / N_label`` for a database of ``N`` images, ``N_label`` of
  the hit's label, so that the goal with more stored views does not win by their number;
  votes >= ``min_consensus`` make an away observation, <= -``min_consensus`` a home one. Over the
  last ``window`` frames (the seed's ``i = t - N .. t``), with ``k`` away and ``j`` home
  observations, the belief is the mean of Beta(1 + k, 1 + j)::

      P(away) = (1 + k) / (2 + k + j)

  ``certain`` is +1 (away) when ``P(away) > confidence``, -1 (home) when ``P(away) <
  1 - confidence``, else 0: a certain observation re-initialises the localisation filter.

Query expansion: each processed frame's word counts are summed with the previous frame's
before querying (and, while building, storing), Algorithm 1 lines 5, 7, 10. A frame that is
not processed (not facing a goal area; while building, also no goal post visible) resets the
expansion: the next processed frame is queried alone, as it is after :meth:`reset`. While
building, a frame of the other label is not summed either.

Words are feature word ids from :meth:`perception.landmarks.vocabulary.Vocabulary.quantise`
and ``x`` their image columns (px), e.g. of :class:`perception.landmarks.horizon_features
.HorizonFeatures` less the features on robots (the seed discards those in both phases).
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from perception.landmarks.bag_of_words import (
    Hit,
    ImageDatabase,
    IntArray,
    RetrievalConfig,
    word_counts,
)
from perception.landmarks.vocabulary import Vocabulary
from perception.validation import (
    InvalidTypeError,
    check_bool,
    check_generator,
    check_in_interval,
    check_int,
    check_nested_configs,
    check_positive,
)

AWAY = 1  # label of views facing the away goal (the opponents')
HOME = -1  # label of views facing the home goal


@dataclass(frozen=True, kw_only=True)
class FieldEndConfig:
    """Database building, voting and the observation window of Algorithm 1.

    (a) The seed gives no values (``minRESPONSE``, ``minCONSENSUS``); these were chosen with
    :class:`perception.landmarks.bag_of_words.RetrievalConfig`'s defaults on rendered scenes
    1030-1035 (training scenes, not reporting ones): a database built from 240 walk-on frames
    in our half, queried by 4-frame views of either goal area from anywhere on the field with
    four other robots about and half of them under random lighting. About half the frames
    gave an observation of the right end and 6 % one of the wrong end.

    (b) Chosen on the kidnap benchmark's tuning seeds 0-4 (``benchmarks/kidnaps.py``, its
    recogniser inputs recorded and replayed). ``balance_votes``: the walk-on stored up to 3.5
    times as many views of one goal as of the other, and most wrong observations named the
    goal with more views. The sizes: the 45 s walk-on faces a goal area in about 150 frames;
    a view stored from one place rarely matches one taken from a few metres nearer or
    farther, so more stored views mean more observations (the seed's 80 was the Nao's time
    budget; a query verifies at most ``retrieval.max_results`` hits whatever the size).
    """

    max_size: int = 200  # images stored in all (seed 004 §4.2: 80 in SPL games) (b)
    max_per_goal: int = 100  # images of each goal area (seed 004 §4.2: up to 40) (b)
    min_response: int = 4  # while building, frames drawing fewer hits are stored (a)
    min_consensus: float = 2.0  # net votes of an observation (minCONSENSUS) (a)
    balance_votes: bool = True  # scale each label's votes by its share of the database (b)
    window: int = 30  # frames N of the sliding observation window (the seed gives no N)
    confidence: float = 0.9  # P(away) above it (below 1 - it) is certain (seed: "very high")
    retrieval: RetrievalConfig = field(default_factory=RetrievalConfig)

    def __post_init__(self) -> None:
        check_nested_configs(self)
        check_int("FieldEndConfig", "max_size", self.max_size, 1)
        check_int("FieldEndConfig", "max_per_goal", self.max_per_goal, 1)
        check_int("FieldEndConfig", "min_response", self.min_response, 1)
        check_positive("FieldEndConfig", "min_consensus", self.min_consensus)
        check_bool("FieldEndConfig", "balance_votes", self.balance_votes)
        check_int("FieldEndConfig", "window", self.window, 1)
        check_in_interval("FieldEndConfig", "confidence", self.confidence, 0.5, 1.0)


@dataclass(frozen=True)
class FieldEndBelief:
    """One frame's belief: ``p_away`` = P(facing the away goal), ``certain`` (+1 away, -1
    home, 0 neither), the window's ``away_observations`` / ``home_observations``, this frame's
    net ``votes``, its ``observation`` (+1 an away one, -1 a home one, 0 none: Algorithm 1's
    awayGoalObs / homeGoalObs) and its ``hits`` (empty for a frame not facing a goal area).
    ``side_observation``: not the seed's, the side board a second recogniser of side-board
    views saw in this frame (+1 the +y one, -1 the -y one, 0 none;
    :class:`perception.providers.field_end.NaturalLandmarkFieldEnd`); under the field's
    half-turn symmetry the sides swap as the ends do."""

    p_away: float
    certain: int
    away_observations: int
    home_observations: int
    votes: float
    hits: tuple[Hit, ...]
    observation: int = 0
    side_observation: int = 0


class FieldEndRecogniser:
    """Algorithm 1 of seed 004 (module docstring). RANSAC draws come from ``rng``."""

    def __init__(
        self, vocabulary: Vocabulary, config: FieldEndConfig, rng: np.random.Generator
    ) -> None:
        if not isinstance(config, FieldEndConfig):
            raise InvalidTypeError(f"config must be a FieldEndConfig, got {type(config).__name__}")
        check_generator("rng", rng)
        self.config = config
        self.rng = rng
        self.database = ImageDatabase(vocabulary, config.retrieval)
        self._window: deque[int] = deque(maxlen=config.window)  # observations, 0 for none
        self._previous: IntArray | None = None  # last processed frame's counts
        self._previous_label: int | None = None  # ... and its label (building, or a candidate)
        # the last observed frame, if it may be remembered: (words, x, label, counts)
        self._candidate: tuple[IntArray, NDArray[np.float64], int, IntArray] | None = None

    def reset(self) -> None:
        """Start of a half: clear the database, the window and the query expansion."""
        self.database.clear()
        self._window.clear()
        self._previous = self._previous_label = None
        self._candidate = None

    def build(
        self, words: ArrayLike, x: ArrayLike, label: int, *, facing_goal: bool, post_visible: bool
    ) -> bool:
        """Walk-on frame with features' words (N,) and columns ``x`` (N,) (px), facing the
        ``label`` goal (:data:`AWAY` or :data:`HOME`; not read when not ``facing_goal``).
        Returns whether it was stored."""
        check_bool("FieldEndRecogniser.build", "facing_goal", facing_goal)
        check_bool("FieldEndRecogniser.build", "post_visible", post_visible)
        self._candidate = None
        if not (facing_goal and post_visible):
            self._previous = self._previous_label = None
            return False
        _check_label("FieldEndRecogniser.build", label)
        counts = self._expanded(words, same_label=label)
        self._previous_label = label
        if not self._has_room(label):
            return False
        hits = self.database.query(words, x, self.rng, counts)
        if len(hits) >= self.config.min_response:
            return False
        self.database.add(words, x, label, counts)
        return True

    def observe(
        self, words: ArrayLike, x: ArrayLike, *, facing_goal: bool, label: int = 0
    ) -> FieldEndBelief:
        """Play frame with features' words (N,) and columns ``x`` (N,) (px): the belief after
        it. A frame not facing a goal area adds no observation but still ages the window.

        ``label`` (:data:`AWAY` or :data:`HOME`; 0, the default: unknown) is the goal area the
        caller believes the camera faces; a frame so labelled that draws fewer than
        ``min_response`` hits, as a walk-on frame must to be stored, becomes the candidate
        that :meth:`remember` stores once the caller has confirmed the label (the next
        observed frame replaces it). The query is expanded with the previous frame whatever
        it faced; the candidate only with a previous frame of the same label, as in building."""
        check_bool("FieldEndRecogniser.observe", "facing_goal", facing_goal)
        check_int("FieldEndRecogniser.observe", "label", label)
        if label:
            _check_label("FieldEndRecogniser.observe", label)
        hits: tuple[Hit, ...] = ()
        self._candidate = None
        if facing_goal:
            previous_label = self._previous_label
            counts = self._expanded(words, same_label=None)
            own = self._previous  # this frame's counts alone (_expanded keeps them)
            self._previous_label = label or None
            hits = self.database.query(words, x, self.rng, counts)
            if label and own is not None and len(hits) < self.config.min_response:
                self._candidate = (
                    np.asarray(words, dtype=np.int64),
                    np.asarray(x, dtype=np.float64),
                    label,
                    counts if previous_label == label else own,
                )
        else:
            self._previous = self._previous_label = None
        votes = self._votes(hits)
        consensus = self.config.min_consensus
        observation = AWAY if votes >= consensus else HOME if votes <= -consensus else 0
        self._window.append(observation)
        k, j = self._window.count(AWAY), self._window.count(HOME)
        p_away = (1 + k) / (2 + k + j)
        certain = 0
        if p_away > self.config.confidence:
            certain = AWAY
        elif p_away < 1.0 - self.config.confidence:
            certain = HOME
        return FieldEndBelief(
            p_away=p_away,
            certain=certain,
            away_observations=k,
            home_observations=j,
            votes=votes,
            hits=hits,
            observation=observation,
        )

    def remember(self) -> bool:
        """Store the last observed frame's candidate view (:meth:`observe`) with its label,
        if the database has room for it (``max_size``, ``max_per_goal``); it is then no longer
        a candidate. Returns whether it was stored."""
        candidate, self._candidate = self._candidate, None
        if candidate is None or not self._has_room(candidate[2]):
            return False
        words, x, label, counts = candidate
        self.database.add(words, x, label, counts)
        return True

    def _has_room(self, label: int) -> bool:
        """Whether the database may store another view of the ``label`` goal."""
        return (
            len(self.database) < self.config.max_size
            and self.database.count(label) < self.config.max_per_goal
        )

    def _votes(self, hits: tuple[Hit, ...]) -> float:
        """Net votes for the away goal: +1 per away hit, -1 per home hit, each scaled by
        ``(N / 2) / N_label`` (``N`` images stored, ``N_label`` of the hit's label) when
        ``balance_votes``, so that a database holding more of one goal's views does not
        outvote the other by its size (1 each for a balanced database)."""
        total = len(self.database)
        weights = {AWAY: 1.0, HOME: 1.0}
        if self.config.balance_votes:
            weights = {
                label: 0.5 * total / max(self.database.count(label), 1) for label in (AWAY, HOME)
            }
        return sum(weights[AWAY] if hit.label == AWAY else -weights[HOME] for hit in hits)

    def _expanded(self, words: ArrayLike, same_label: int | None) -> IntArray:
        """This frame's counts plus the previous processed frame's (not if ``same_label`` is
        given and differs from the previous frame's label); remembers this frame's."""
        counts = word_counts(words, self.database.vocabulary)
        previous, self._previous = self._previous, counts
        if previous is None or (same_label is not None and same_label != self._previous_label):
            return counts
        return counts + previous


def _check_label(owner: str, label: int) -> None:
    """Refuse a ``label`` that is neither :data:`AWAY` nor :data:`HOME`."""
    check_int(owner, "label", label)
    if label not in (AWAY, HOME):
        raise ValueError(f"{owner}.label must be AWAY ({AWAY}) or HOME ({HOME}), got {label!r}")
