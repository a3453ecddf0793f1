"""Visual heading odometry (seed 004 ch. 5): the modes of bearing changes, the best of three
previous frames (eqs. 10-12), the fallback to the walk, and the collision average."""

from __future__ import annotations

import math

import numpy as np
import pytest

from perception.landmarks.horizon_features import HorizonFeatures
from perception.landmarks.matching import MatchingConfig
from perception.landmarks.surf1d import Surf1dFeatures
from perception.landmarks.visual_odometry import (
    CollisionDetector,
    VisualHeadingOdometry,
    VisualOdometryConfig,
    nearest_neighbours,
    shift_modes,
)

CONFIG = VisualOdometryConfig()


LANDMARK_DESCRIPTORS = np.random.default_rng(99).normal(size=(2000, 6))


def frame(bearings: np.ndarray, ids: np.ndarray, head_yaw: float = 0.0) -> HorizonFeatures:
    """Features at ``bearings`` of landmarks ``ids`` (kept as the features' ``index``), each
    with the landmark's own random descriptor."""
    n = len(bearings)
    features = Surf1dFeatures(
        index=np.asarray(ids, dtype=np.int64),
        x=np.zeros(n),
        scale=np.ones(n),
        filter_size=np.full(n, 9),
        laplacian=np.ones(n, dtype=np.int8),
        response=np.ones(n),
        descriptors=LANDMARK_DESCRIPTORS[np.asarray(ids, dtype=np.int64)],
    )
    return HorizonFeatures(features=features, bearings=np.asarray(bearings), head_yaw=head_yaw)


def same_id(earlier: HorizonFeatures, later: HorizonFeatures) -> np.ndarray:
    """Pairs features with equal ids: an exact matcher."""
    _, ia, ib = np.intersect1d(earlier.features.index, later.features.index, return_indices=True)
    return np.stack([ia, ib], axis=1)


def scene(rng: np.random.Generator, n: int = 300) -> np.ndarray:
    """Background landmarks at azimuths (rad) all round the robot."""
    return np.sort(rng.uniform(-math.pi, math.pi, n))


def view(
    azimuths: np.ndarray, heading: float, head_yaw: float = 0.0, half_fov: float = 0.53
) -> HorizonFeatures:
    """What a camera on a body at ``heading`` with the head at ``head_yaw`` sees."""
    bearings = (azimuths - heading - head_yaw + math.pi) % (2 * math.pi) - math.pi
    seen = np.abs(bearings) < half_fov
    return frame(bearings[seen], np.flatnonzero(seen).astype(np.float64), head_yaw)


def test_the_first_mode_is_the_turn_and_the_confidence_its_margin() -> None:
    rng = np.random.default_rng(0)
    background = 0.05 + rng.normal(0.0, 0.001, 20)
    walker = -0.1 + rng.normal(0.0, 0.001, 8)
    modes = shift_modes(np.concatenate([background, walker]), CONFIG)
    assert modes.turn == pytest.approx(float(np.mean(background)), abs=1e-12)
    assert (modes.first, modes.second, modes.confidence) == (20, 8, 12)
    empty = shift_modes(np.zeros(0), CONFIG)
    assert math.isnan(empty.turn) and empty.confidence == 0


@pytest.mark.parametrize("matcher", ["exact", "nearest_neighbours"])
def test_heading_follows_body_turns_less_the_head_yaw(matcher: str) -> None:
    rng = np.random.default_rng(1)
    azimuths = scene(rng)
    match = same_id if matcher == "exact" else nearest_neighbours(MatchingConfig())
    odometry = VisualHeadingOdometry(CONFIG, match)
    heading, head, total = 0.3, 0.0, 0.0
    odometry.update(view(azimuths, heading, head), 0.0)
    for k in range(40):
        turn, head_move = 0.04 * math.sin(k / 5), 0.03 * math.cos(k / 3)
        heading, head = heading + turn, head + head_move
        step = odometry.update(view(azimuths, heading, head), walk_delta_rad=0.0)
        assert step.visual
        assert step.delta_rad == pytest.approx(turn, abs=2e-12)
        total += step.delta_rad
    assert total == pytest.approx(heading - 0.3, abs=1e-10)


def test_the_best_of_three_frames_skips_a_corrupt_one() -> None:
    rng = np.random.default_rng(2)
    azimuths = scene(rng)
    odometry = VisualHeadingOdometry(CONFIG, same_id)
    odometry.update(view(azimuths, 0.0), 0.0)  # frame 0: reliability inf (eq. 12)
    first = odometry.update(view(azimuths, 0.02), 0.0)
    assert first.reference == 1 and first.reliability == first.confidence  # eq. 11
    # frame 2 shows other ids (a blurred, corrupt frame): no match to anything
    seen = view(azimuths, 0.04)
    corrupt = odometry.update(frame(seen.bearings, np.arange(len(seen)) + 1000), 0.015)
    assert not corrupt.visual and corrupt.delta_rad == 0.015  # the walk's heading change
    # frame 3: eq. 10 weighs frames 0 (reliability inf), 1 and the corrupt 2 (no votes):
    # the reference is one of the good ones, and the reliability follows eq. 11
    step = odometry.update(view(azimuths, 0.06), 0.0)
    assert step.visual and step.reference in (2, 3)
    assert step.reliability == (
        step.confidence if step.reference == 3 else min(first.reliability, step.confidence)
    )
    # the heading is the good frame's plus the measured turn: the corrupt frame's walk step
    # (0.015 instead of 0.02) is undone
    assert corrupt.delta_rad + step.delta_rad == pytest.approx(0.04, abs=1e-12)


def test_ties_go_to_the_oldest_frame() -> None:
    rng = np.random.default_rng(3)
    azimuths = scene(rng)
    odometry = VisualHeadingOdometry(CONFIG, same_id)
    for _ in range(4):
        step = odometry.update(view(azimuths, 0.0), 0.0)  # a still robot
    assert step.reference == 3 and step.delta_rad == pytest.approx(0.0, abs=1e-15)


def test_two_equal_modes_fall_back_to_the_walk() -> None:
    config = VisualOdometryConfig(min_confidence=2)
    odometry = VisualHeadingOdometry(config, same_id)
    ids = np.arange(20.0)
    before = np.linspace(-0.4, 0.4, 20)
    after = before - np.where(ids < 10, 0.05, -0.08)  # two movers, ten votes each
    odometry.update(frame(before, ids), 0.0)
    step = odometry.update(frame(after, ids), walk_delta_rad=0.01)
    assert not step.visual and step.confidence == 0 and step.delta_rad == 0.01


def test_collision_average_crosses_its_bound_only_on_a_sustained_difference() -> None:
    detector = CollisionDetector(CONFIG)
    bound, a = CONFIG.collision_bound_rad, CONFIG.collision_smoothing
    assert detector.update(3 * bound, 0.0) == 0  # one spike: a * 3 bound < bound
    assert detector.average == pytest.approx(a * 3 * bound)
    detector.reset()
    flags = [detector.update(0.0, 2 * bound) for _ in range(10)]  # walk turns, body does not
    # the average after n frames: -2 bound (1 - (1 - a)^n), below -bound from n = 4 on
    first = next(n for n in range(1, 11) if 2 * (1 - (1 - a) ** n) > 1)
    assert flags == [0] * (first - 1) + [-1] * (10 - first + 1)


def test_bad_configs_are_refused() -> None:
    with pytest.raises(ValueError, match="bin_rad"):
        VisualOdometryConfig(bin_rad=0.0)
    with pytest.raises(ValueError, match="collision_smoothing"):
        VisualOdometryConfig(collision_smoothing=1.5)
    with pytest.raises((ValueError, TypeError), match="history"):
        VisualOdometryConfig(history=0)


def test_a_turn_the_walk_cannot_have_made_falls_back_to_the_walk() -> None:
    rng = np.random.default_rng(5)
    azimuths = scene(rng)
    odometry = VisualHeadingOdometry(CONFIG, same_id)
    odometry.update(view(azimuths, 0.0), 0.0)
    jump = CONFIG.max_disagreement_rad + 0.05  # a confident, wrong mode
    step = odometry.update(view(azimuths, jump), walk_delta_rad=0.0)
    assert not step.visual and step.delta_rad == 0.0
    small = odometry.update(view(azimuths, jump + 0.02), walk_delta_rad=0.0)
    assert small.visual and small.delta_rad == pytest.approx(0.02, abs=1e-12)


def test_a_nan_heading_change_is_refused_before_the_collision_average_changes() -> None:
    detector = CollisionDetector(CONFIG)
    detector.update(0.01, 0.0)
    before = detector.average
    for visual, walk in ((math.nan, 0.0), (0.0, math.inf)):
        with pytest.raises(ValueError, match="delta_rad must be finite"):
            detector.update(visual, walk)
    assert detector.average == before


@pytest.mark.parametrize("shifts", [[0.1, math.nan], [[0.1, 0.2]]])
def test_shift_modes_refuses_shifts_that_are_not_a_finite_vector(shifts: list[object]) -> None:
    with pytest.raises(ValueError, match=r"shifts must be a finite \(M,\) array"):
        shift_modes(np.array(shifts), CONFIG)
