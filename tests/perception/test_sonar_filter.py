"""The sonar filter and Algorithm 2's sonar check (seed 004 §6.2) against independent truths:
hand-worked clusterings, a brute-force agglomeration, the gap rule of single linkage, and the
plain geometry of a sonar mounted ahead of the robot origin."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from perception.sensor_models import SonarModel
from perception.tracking.sonar_filter import (
    LINKAGES,
    SonarFilter,
    SonarFilterConfig,
    SonarObservation,
    audible,
    cluster_ranges,
    confirm_with_sonar,
    origin_range,
    sonar_cones,
    sonar_polar,
)
from perception.types import RobotSighting
from perception.validation import InvalidTypeError

NAN = math.nan
LEFT, MIDDLE, RIGHT = 0, 1, 2
MODEL = SonarModel()  # cones: left 25±30°, middle 0±20°, right -25±30°; 5 cm ahead; 1 cm noise


def _reading(left=(), middle=(), right=(), width=4):
    """A (3, width) NaN-padded reading of the given echoes (m)."""
    out = np.full((3, width), NAN)
    for row, echoes in enumerate((left, middle, right)):
        out[row, : len(echoes)] = echoes
    return out


def _summary(observations):
    """(sector, range rounded to 0.1 mm, count) of each observation."""
    return [(o.sector, round(o.range_m, 4), o.count) for o in observations]


def _sighting(range_m, bearing_deg, team=None, **kwargs):
    cov = np.diag([0.2**2, math.radians(3.0) ** 2])
    return RobotSighting(
        range_m=range_m, bearing_rad=math.radians(bearing_deg), cov=cov, team=team, **kwargs
    )


# ----- clustering -----------------------------------------------------------------------------
def test_three_close_echoes_form_one_cluster_and_a_lone_outlier_is_removed():
    f = SonarFilter(SonarFilterConfig(window_frames=5, min_cluster_size=3))
    frames = [(1.00, 1.30), (1.02, 1.30, 1.70), (1.04, 1.30)]
    for k, echoes in enumerate(frames):
        observations = f.update(0.1 * k, _reading(left=echoes))
    assert _summary(observations) == [(LEFT, 1.02, 3), (LEFT, 1.30, 3)]
    assert f.observations == observations


def test_a_cluster_below_the_minimum_size_is_not_reported():
    f = SonarFilter(SonarFilterConfig(window_frames=5, min_cluster_size=3))
    f.update(0.0, _reading(middle=(1.00, 1.30)))
    f.update(0.1, _reading(middle=(1.02, 1.30)))
    assert _summary(f.update(0.2, _reading(middle=(1.04,)))) == [(MIDDLE, 1.02, 3)]


@pytest.mark.parametrize(("gap_m", "expected"), [(0.04, [1.02]), (0.06, [1.00, 1.06])])
def test_two_objects_merge_within_the_cut_off_and_stay_apart_beyond_it(gap_m, expected):
    # The centroid rule: two clusters merge while their mean ranges are within 5 cm.
    f = SonarFilter(SonarFilterConfig(window_frames=6, min_cluster_size=3))
    for k in range(6):
        f.update(0.1 * k, _reading(right=(1.00 if k < 3 else 1.00 + gap_m,)))
    observations = f.observations
    assert [o.sector for o in observations] == [RIGHT] * len(expected)
    assert [o.range_m for o in observations] == pytest.approx(expected)
    assert sum(o.count for o in observations) == 6


def test_the_linkages_differ_as_documented():
    chain = [1.00, 1.04, 1.08, 1.12]  # neighbours 4 cm apart, ends 12 cm apart
    means, counts = cluster_ranges(chain, method="single")
    assert means == pytest.approx([1.06]) and counts.tolist() == [4]
    for method in ("centroid", "complete", "average"):
        means, counts = cluster_ranges(chain, method=method)
        assert means == pytest.approx([1.02, 1.10]) and counts.tolist() == [2, 2], method
    spread = [1.00, 1.03, 1.06]  # 6 cm wide; the third is 4.5 cm from the mean of the others
    for method, expected in (
        ("centroid", [1.03]),
        ("average", [1.03]),
        ("single", [1.03]),
        ("complete", None),  # 6 cm > 5 cm: never all three
    ):
        means, counts = cluster_ranges(spread, method=method)
        if expected is None:
            assert len(means) == 2 and sorted(counts.tolist()) == [1, 2]
        else:
            assert means == pytest.approx(expected) and counts.tolist() == [3], method


def test_the_cut_off_is_inclusive_despite_rounding():
    means, counts = cluster_ranges([1.00, 1.05], method="complete")
    assert means == pytest.approx([1.025]) and counts.tolist() == [2]
    means, _ = cluster_ranges([1.00, 1.0501], method="complete")
    assert means == pytest.approx([1.00, 1.0501])


def test_cluster_ranges_of_none_and_one():
    means, counts = cluster_ranges([])
    assert means.shape == (0,) and counts.shape == (0,)
    means, counts = cluster_ranges([0.7])
    assert means.tolist() == [0.7] and counts.tolist() == [1]


@pytest.mark.parametrize(
    ("args", "match"),
    [
        ({"ranges": [1.0, math.nan]}, r"ranges must be a finite \(N,\) array"),
        ({"ranges": [[1.0, 1.1]]}, r"ranges must be a finite \(N,\) array"),
        ({"ranges": [1.0, 1.1], "cutoff_m": -1.0}, "cutoff_m"),
        ({"ranges": [1.0, 1.1], "cutoff_m": math.nan}, "cutoff_m"),
        ({"ranges": [1.0, 1.1], "method": "ward"}, "method"),
    ],
)
def test_cluster_ranges_refuses_bad_arguments_naming_them(args: dict[str, Any], match: str) -> None:
    with pytest.raises(ValueError, match=match):
        cluster_ranges(**args)


def _gap_split(x, cutoff):
    """Single linkage in 1-D: sorted values split wherever a gap exceeds the cut-off."""
    x = np.sort(x)
    groups = np.split(x, np.flatnonzero(np.diff(x) > cutoff) + 1)
    return [g.mean() for g in groups], [len(g) for g in groups]


def _brute_centroid(x, cutoff):
    """Centroid agglomeration written out: merge the two clusters with the nearest means while
    they are within the cut-off."""
    clusters = [[v] for v in x]
    while len(clusters) > 1:
        pairs = [
            (abs(np.mean(a) - np.mean(b)), i, j)
            for i, a in enumerate(clusters)
            for j, b in enumerate(clusters)
            if i < j
        ]
        d, i, j = min(pairs)
        if d > cutoff:
            break
        clusters[i] = clusters[i] + clusters.pop(j)
    clusters.sort(key=np.mean)
    return [float(np.mean(c)) for c in clusters], [len(c) for c in clusters]


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(2, 25))
def test_linkages_match_their_definitions(seed, n):
    rng = np.random.default_rng(seed)
    x = rng.uniform(0.3, 1.0, n)  # dense enough to form clusters, no ties
    cutoff = 0.05
    for method, reference in (("single", _gap_split), ("centroid", _brute_centroid)):
        means, counts = cluster_ranges(x, cutoff_m=cutoff, method=method)
        expected_means, expected_counts = reference(x, cutoff)
        assert means == pytest.approx(expected_means, abs=1e-12), method
        assert counts.tolist() == expected_counts, method
    # Complete linkage: no cluster wider than the cut-off.
    # (In 1-D its clusters are runs of the sorted values, ordered like their means.)
    xs = np.sort(x)
    means, counts = cluster_ranges(x, cutoff_m=cutoff, method="complete")
    assert counts.sum() == n
    starts = np.cumsum(np.r_[0, counts[:-1]])
    for start, count, mean in zip(starts, counts, means, strict=True):
        members = xs[start : start + count]
        assert members.max() - members.min() <= cutoff + 1e-12
        assert members.mean() == pytest.approx(mean)


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), objects=st.integers(1, 5), per_object=st.integers(1, 8))
def test_clusters_equal_one_scipy_linkage_over_all_echoes(seed, objects, per_object):
    """Echoes of a few objects (some runs wider than the cut-off, some gaps narrower): the
    clustering, which takes each run between wide gaps alone, equals SciPy's over them all."""
    from scipy.cluster.hierarchy import fcluster, linkage

    rng = np.random.default_rng(seed)
    x = np.repeat(rng.uniform(0.3, 1.5, objects), per_object)
    x = x + rng.normal(0.0, 0.025, len(x))
    cutoff = 0.05
    for method in LINKAGES:
        means, counts = cluster_ranges(x, cutoff_m=cutoff, method=method)
        xs = np.sort(x)
        if len(xs) < 2:
            labels = np.zeros(len(xs), dtype=np.intp)
        else:
            Z = linkage(xs[:, None], method=method)
            labels = fcluster(Z, t=cutoff + 1e-9, criterion="distance") - 1
        expected = np.bincount(labels, weights=xs) / np.bincount(labels)
        order = np.argsort(expected)
        assert means == pytest.approx(expected[order], abs=1e-12), method
        assert counts.tolist() == np.bincount(labels)[order].tolist(), method


def test_noisy_echoes_of_one_static_object_give_one_accurate_observation():
    rng = np.random.default_rng(4)
    f = SonarFilter()
    for k in range(20):
        echoes = 0.9 + 0.01 * rng.standard_normal(1)
        observations = f.update(0.1 * k, _reading(middle=echoes))
        if k >= 2:
            assert len(observations) == 1
            assert observations[0].sector == MIDDLE
            assert abs(observations[0].range_m - 0.9) < 0.02


# ----- the window ----------------------------------------------------------------------------
def test_the_window_forgets_old_frames():
    f = SonarFilter(SonarFilterConfig(window_frames=3, min_cluster_size=1))
    f.update(0.0, _reading(left=(1.0,)))
    assert _summary(f.update(0.1, _reading(left=(2.0,)))) == [(LEFT, 1.0, 1), (LEFT, 2.0, 1)]
    f.update(0.2, _reading(left=(2.0,)))
    assert _summary(f.update(0.3, _reading(left=(2.0,)))) == [(LEFT, 2.0, 3)]


def test_the_window_in_seconds_forgets_old_frames():
    f = SonarFilter(SonarFilterConfig(window_frames=10, window_s=0.25, min_cluster_size=1))
    for k, echo in enumerate((1.0, 1.5, 2.0)):
        f.update(0.1 * k, _reading(middle=(echo,)))
    assert [o.range_m for o in f.observations] == [1.0, 1.5, 2.0]
    f.update(0.32, _reading(middle=(2.0,)))  # ages 0.32, 0.22, 0.12, 0: the first goes
    assert _summary(f.observations) == [(MIDDLE, 1.5, 1), (MIDDLE, 2.0, 2)]
    f.update(5.0, _reading())  # a long gap empties the window but the newest frame
    assert f.observations == ()


def test_the_window_in_seconds_holds_as_many_frames_whatever_the_rounding_of_summed_times():
    """Frame times summed 0.1 s at a time come out a hair off k * 0.1: a 0.5 s window holds
    the newest five frames every time (the same echo each frame: one cluster of five)."""
    f = SonarFilter(SonarFilterConfig(window_frames=10, window_s=0.5, min_cluster_size=1))
    t, sizes = 0.0, []
    for _ in range(20):
        sizes.append(_summary(f.update(t, _reading(middle=(1.0,))))[0][2])
        t += 0.1
    assert sizes[4:] == [5] * 16


def test_nan_padding_and_empty_readings_are_ignored():
    f = SonarFilter(SonarFilterConfig(window_frames=3, min_cluster_size=2))
    f.update(0.0, np.full((3, 10), NAN))
    f.update(0.1, np.empty((3, 0)))
    assert f.observations == ()
    f.update(0.2, _reading(left=(0.6,), right=(1.2, 2.4), width=10))
    observations = f.update(0.3, _reading(left=(0.62,), right=(2.4,), width=2))
    assert _summary(observations) == [(LEFT, 0.61, 2), (RIGHT, 2.4, 2)]


def test_reset_forgets_everything_and_allows_time_to_restart():
    f = SonarFilter(SonarFilterConfig(window_frames=5, min_cluster_size=1))
    f.update(1.0, _reading(left=(1.0,)))
    f.update(1.1, _reading(left=(1.0,)))
    f.reset()
    assert f.observations == ()
    assert _summary(f.update(0.0, _reading(right=(0.5,)))) == [(RIGHT, 0.5, 1)]


def test_the_same_time_twice_is_allowed():
    f = SonarFilter(SonarFilterConfig(window_frames=2, min_cluster_size=2))
    f.update(0.5, _reading(middle=(1.0,)))
    assert _summary(f.update(0.5, _reading(middle=(1.0,)))) == [(MIDDLE, 1.0, 2)]


# ----- bad input -----------------------------------------------------------------------------
@pytest.mark.parametrize("time_s", [NAN, math.inf, -math.inf])
def test_non_finite_time_is_rejected(time_s):
    with pytest.raises(ValueError, match="time_s"):
        SonarFilter().update(time_s, _reading())


@pytest.mark.parametrize("time_s", ["0.1", None, True])
def test_time_of_the_wrong_type_is_rejected(time_s):
    with pytest.raises(InvalidTypeError, match="time_s"):
        SonarFilter().update(time_s, _reading())


def test_time_going_back_is_rejected_and_leaves_the_window_alone():
    f = SonarFilter(SonarFilterConfig(window_frames=3, min_cluster_size=1))
    f.update(1.0, _reading(left=(1.0,)))
    with pytest.raises(ValueError, match="go back"):
        f.update(0.9, _reading(left=(2.0,)))
    assert _summary(f.update(1.1, _reading())) == [(LEFT, 1.0, 1)]


@pytest.mark.parametrize(
    "echoes", [np.full((2, 4), 1.0), np.full(3, 1.0), np.full((3, 2, 1), 1.0), np.full((4, 3), 1.0)]
)
def test_wrong_shapes_are_rejected(echoes):
    with pytest.raises(ValueError, match=r"shape \(3, E\)"):
        SonarFilter().update(0.0, echoes)


@pytest.mark.parametrize("bad", [math.inf, -math.inf, -1.0, 0.0])
def test_non_finite_or_non_positive_echoes_are_rejected(bad):
    f = SonarFilter(SonarFilterConfig(window_frames=2, min_cluster_size=1))
    with pytest.raises(ValueError, match="echoes"):
        f.update(0.0, _reading(middle=(1.0, bad)))
    assert f.update(0.0, _reading()) == ()  # the bad reading never entered the window


def test_echoes_that_are_not_numbers_are_rejected():
    with pytest.raises(InvalidTypeError, match="echoes"):
        SonarFilter().update(0.0, [["a", "b"], ["c", "d"], ["e", "f"]])


FLOAT_FIELDS = (
    "cluster_cutoff_m",
    "match_abs_m",
    "match_rel",
    "target_depth_m",
    "min_range_std_m",
    "window_s",
)


@pytest.mark.parametrize("name", FLOAT_FIELDS)
@pytest.mark.parametrize("value", [NAN, math.inf, -math.inf, -0.1])
def test_config_rejects_non_finite_and_negative_values(name, value):
    with pytest.raises(ValueError, match=f"SonarFilterConfig.{name}"):
        SonarFilterConfig(**{name: value})


@pytest.mark.parametrize("name", ["cluster_cutoff_m", "min_range_std_m", "window_s"])
def test_config_rejects_zero_where_it_must_be_positive(name):
    with pytest.raises(ValueError, match=f"SonarFilterConfig.{name}"):
        SonarFilterConfig(**{name: 0.0})


@pytest.mark.parametrize(
    ("kwargs", "error"),
    [
        ({"window_frames": 0}, ValueError),
        ({"window_frames": 2.0}, InvalidTypeError),
        ({"window_frames": True}, InvalidTypeError),
        ({"min_cluster_size": 0}, ValueError),
        ({"min_cluster_size": 6}, ValueError),  # more than window_frames (5)
        ({"linkage": "ward"}, ValueError),
        ({"linkage": None}, InvalidTypeError),
        ({"match_rel": "0.2"}, InvalidTypeError),
    ],
)
def test_config_rejects_bad_fields(kwargs, error):
    with pytest.raises(error, match=f"SonarFilterConfig.{next(iter(kwargs))}"):
        SonarFilterConfig(**kwargs)


def test_config_defaults():
    config = SonarFilterConfig()
    assert config.cluster_cutoff_m == 0.05 and config.linkage in LINKAGES
    assert config.match_tolerance_m(1.0) == pytest.approx(0.20)
    assert config.match_tolerance_m(2.0) == pytest.approx(0.30)
    assert SonarFilterConfig(match_abs_m=0.0, match_rel=0.0).match_tolerance_m(1.0) == 0.0


@pytest.mark.parametrize(
    "kwargs",
    [
        {"sector": 3, "range_m": 1.0, "count": 1},
        {"sector": -1, "range_m": 1.0, "count": 1},
        {"sector": 0, "range_m": NAN, "count": 1},
        {"sector": 0, "range_m": 0.0, "count": 1},
        {"sector": 0, "range_m": 1.0, "count": 0},
        {"sector": 1.0, "range_m": 1.0, "count": 1},
    ],
)
def test_sonar_observation_rejects_bad_fields(kwargs):
    with pytest.raises(ValueError):
        SonarObservation(**kwargs)


# ----- the mount geometry --------------------------------------------------------------------
def test_audible_needs_a_cone_and_the_range_seen_from_the_transducers():
    # straight ahead, 0.30 m from the origin is 0.25 m from the transducers: the nearest heard
    assert audible(MODEL, 0.301, 0.0) and not audible(MODEL, 0.299, 0.0)
    assert audible(MODEL, 2.599, 0.0) and not audible(MODEL, 2.601, 0.0)  # 2.55 m + the mount
    # 57.9° from the transducers (53° from the origin at 0.5 m): beyond the left cone's 55°
    assert not audible(MODEL, 0.5, math.radians(53.0)) and audible(MODEL, 0.5, math.radians(50.0))
    distance, in_cone = sonar_cones(MODEL, 1.0, math.radians(10.0))
    assert distance == pytest.approx(sonar_polar(1.0, math.radians(10.0), MODEL.mount_x_m)[0])
    assert in_cone.tolist() == [True, True, False]  # left (-5°..55°) and middle (-20°..20°)


def test_sonar_polar_sees_points_from_the_transducers():
    assert sonar_polar(1.0, 0.0, 0.05) == pytest.approx((0.95, 0.0))
    distance, bearing = sonar_polar(1.0, math.radians(90.0), 0.05)
    assert distance == pytest.approx(math.sqrt(1.0 + 0.05**2))
    assert bearing == pytest.approx(math.pi / 2 + math.atan2(0.05, 1.0))
    assert sonar_polar(0.3, math.pi, 0.05) == pytest.approx((0.35, math.pi))


@settings(max_examples=50, deadline=None)
@given(
    s=st.floats(0.3, 2.6),
    bearing=st.floats(-math.pi, math.pi),
    mount=st.floats(-0.1, 0.1),
)
def test_origin_range_lands_at_the_sonar_range(s, bearing, mount):
    crossing = origin_range(s, bearing, mount, near_m=1.0)
    assert crossing is not None
    r, slope = crossing
    point = np.array([r * math.cos(bearing) - mount, r * math.sin(bearing)])
    assert np.hypot(*point) == pytest.approx(s)
    # the slope against a finite difference
    r2, _ = origin_range(s + 1e-6, bearing, mount, near_m=1.0)
    assert slope == pytest.approx((r2 - r) / 1e-6, rel=1e-4)


def test_origin_range_outside_the_circle():
    # origin 1 m behind the sonar, circle of 0.3 m: along the axis, crossings at 0.7 and 1.3
    assert origin_range(0.3, 0.0, 1.0, near_m=0.6)[0] == pytest.approx(0.7)
    assert origin_range(0.3, 0.0, 1.0, near_m=1.4)[0] == pytest.approx(1.3)
    assert origin_range(0.3, math.radians(90.0), 1.0, near_m=1.0) is None  # misses it
    assert origin_range(0.3, math.pi, 1.0, near_m=1.0) is None  # only behind the origin


# ----- Algorithm 2 ---------------------------------------------------------------------------
# The worked cases below use a 5 cm body depth and a 0.10 m + 20 % match window (round numbers,
# not the defaults).
WORKED = SonarFilterConfig(target_depth_m=0.05, match_abs_m=0.10, match_rel=0.20)


def test_in_cone_and_close_range_takes_the_sonar_range_and_is_confirmed():
    # Straight ahead at 1.00 m: 0.95 m from the transducers, its near surface 0.90 m.
    sighting = _sighting(1.00, 0.0, team=None, box=np.array([1.0, 2.0, 3.0, 4.0]), score=0.7)
    observations = (SonarObservation(sector=MIDDLE, range_m=0.92, count=4),)
    (out,) = confirm_with_sonar([sighting], observations, MODEL, WORKED)
    assert out.sonar_confirmed
    assert out.range_m == pytest.approx(0.92 + 0.05 + 0.05)  # echo + body depth + mount
    assert out.bearing_rad == sighting.bearing_rad
    assert out.cov == pytest.approx(np.diag([0.01**2, math.radians(3.0) ** 2]))
    assert out.team is None and out.score == 0.7 and out.box.tolist() == [1.0, 2.0, 3.0, 4.0]
    assert not sighting.sonar_confirmed and sighting.range_m == 1.0  # the input is untouched


def test_a_confirmed_range_off_axis_accounts_for_the_mount():
    sighting = _sighting(1.0, 40.0, team=1)
    observations = (SonarObservation(sector=LEFT, range_m=0.95, count=3),)
    (out,) = confirm_with_sonar([sighting], observations, MODEL, WORKED)
    assert out.sonar_confirmed and out.team == 1
    # The new point on the sighting's bearing lies echo + depth from the transducers.
    x = out.range_m * math.cos(out.bearing_rad) - MODEL.mount_x_m
    y = out.range_m * math.sin(out.bearing_rad)
    assert math.hypot(x, y) == pytest.approx(0.95 + 0.05)
    assert out.range_m == pytest.approx(1.0378, abs=1e-4)  # worked by hand
    assert out.cov[0, 0] == pytest.approx(0.01**2, rel=0.01)
    assert out.cov[0, 1] == out.cov[1, 0] == 0.0


def test_the_match_uses_the_distance_from_the_transducers():
    # At 1 m and 40° the transducers are 0.9622 m away (0.9122 m to the near surface); from the
    # robot origin it would look like 0.95 m.
    tight = SonarFilterConfig(match_abs_m=0.005, match_rel=0.0, target_depth_m=0.05)
    sighting = _sighting(1.0, 40.0)
    at = (SonarObservation(sector=LEFT, range_m=0.9122, count=3),)
    naive = (SonarObservation(sector=LEFT, range_m=0.95, count=3),)
    assert confirm_with_sonar([sighting], at, MODEL, tight)[0].sonar_confirmed
    assert confirm_with_sonar([sighting], naive, MODEL, tight) == ()


def test_the_cone_is_seen_from_the_transducers():
    # 53° from the origin at 0.5 m is 57.9° from the transducers: beyond the left cone's 55°.
    echo = sonar_polar(0.5, math.radians(53.0), MODEL.mount_x_m)[0] - 0.05
    observations = (SonarObservation(sector=LEFT, range_m=echo, count=3),)
    assert confirm_with_sonar([_sighting(0.5, 53.0)], observations, MODEL, WORKED) == ()
    echo = sonar_polar(0.5, math.radians(50.0), MODEL.mount_x_m)[0] - 0.05  # 54.7°: inside
    observations = (SonarObservation(sector=LEFT, range_m=echo, count=3),)
    assert confirm_with_sonar([_sighting(0.5, 50.0)], observations, MODEL, WORKED)[
        0
    ].sonar_confirmed


@pytest.mark.parametrize(
    ("bearing_deg", "observation"),
    [
        (70.0, SonarObservation(sector=LEFT, range_m=0.9, count=3)),  # outside every cone
        (40.0, SonarObservation(sector=MIDDLE, range_m=0.9, count=3)),  # in left, not middle
        (-40.0, SonarObservation(sector=LEFT, range_m=0.9, count=3)),  # in right, not left
        (0.0, SonarObservation(sector=MIDDLE, range_m=0.55, count=3)),  # 0.35 m too near
        (0.0, SonarObservation(sector=MIDDLE, range_m=1.25, count=3)),  # 0.35 m too far
    ],
)
def test_out_of_cone_or_far_range_is_unchanged_and_unconfirmed(bearing_deg, observation):
    with_team = _sighting(1.0, bearing_deg, team=0)
    without = _sighting(1.0, bearing_deg, team=None)
    assert confirm_with_sonar([with_team, without], [observation], MODEL, WORKED) == (with_team,)


def test_no_team_and_unconfirmed_is_dropped_team_and_unconfirmed_is_kept():
    sightings = [
        _sighting(1.0, 0.0, team=None),  # confirmed by the middle echo: kept
        _sighting(2.0, 60.0, team=None),  # out of cone: dropped
        _sighting(2.0, 60.0, team=0),  # out of cone, has a team: kept unchanged
        _sighting(1.5, -30.0, team=None),  # no echo near: dropped
        _sighting(1.5, -30.0, team=1),  # kept unchanged
        _sighting(2.0, 60.0, team=None, sonar_confirmed=True),  # confirmed before: kept
    ]
    observations = (SonarObservation(sector=MIDDLE, range_m=0.9, count=5),)
    out = confirm_with_sonar(sightings, observations, MODEL, WORKED)
    assert len(out) == 4
    assert out[0].sonar_confirmed and out[0].range_m == pytest.approx(1.0)
    assert out[1:] == (sightings[2], sightings[4], sightings[5])
    assert confirm_with_sonar([], observations, MODEL, WORKED) == ()
    assert confirm_with_sonar(sightings, (), MODEL, WORKED) == (
        sightings[2],
        sightings[4],
        sightings[5],
    )


def test_the_nearest_matching_range_wins_across_overlapping_cones():
    # 10° is in both the left (-5°..55°) and the middle (-20°..20°) cone.
    sighting = _sighting(1.0, 10.0)
    predicted = sonar_polar(1.0, math.radians(10.0), MODEL.mount_x_m)[0] - 0.05
    observations = (
        SonarObservation(sector=MIDDLE, range_m=predicted - 0.05, count=3),
        SonarObservation(sector=LEFT, range_m=predicted + 0.02, count=3),
        SonarObservation(sector=RIGHT, range_m=predicted, count=3),  # right cone ends at 5°
    )
    (out,) = confirm_with_sonar([sighting], observations, MODEL, WORKED)
    x = out.range_m * math.cos(out.bearing_rad) - MODEL.mount_x_m
    y = out.range_m * math.sin(out.bearing_rad)
    assert math.hypot(x, y) == pytest.approx(predicted + 0.02 + 0.05)


def test_one_echo_confirms_one_sighting_the_nearest_in_range():
    # Two teamless sightings straight ahead at 1.0 and 1.2 m (predicted echoes 0.90 and 1.10 m)
    # and one echo at 0.95 m, within the window of both: only the first takes it.
    sightings = [_sighting(1.2, 0.0, team=None), _sighting(1.0, 0.0, team=None)]
    one = (SonarObservation(sector=MIDDLE, range_m=0.95, count=3),)
    (out,) = confirm_with_sonar(sightings, one, MODEL, WORKED)
    assert out.sonar_confirmed and out.range_m == pytest.approx(0.95 + 0.05 + 0.05)
    # a second echo nearer the other sighting confirms it too, each with its own range
    two = (*one, SonarObservation(sector=MIDDLE, range_m=1.12, count=3))
    far, near = confirm_with_sonar(sightings, two, MODEL, WORKED)
    assert far.range_m == pytest.approx(1.12 + 0.1) and near.range_m == pytest.approx(1.05)
    # a sighting with a team that loses the echo is kept unconfirmed
    teams = [_sighting(1.2, 0.0, team=0), _sighting(1.0, 0.0, team=1)]
    kept = confirm_with_sonar(teams, one, MODEL, WORKED)
    assert [s.sonar_confirmed for s in kept] == [False, True]
    assert kept[0] == teams[0]


def test_the_tolerance_grows_with_range():
    config = SonarFilterConfig(match_abs_m=0.1, match_rel=0.2, target_depth_m=0.0)
    # 2.05 m ahead: 2.0 m from the transducers, tolerance 0.5 m
    sighting = _sighting(2.05, 0.0)
    inside = (SonarObservation(sector=MIDDLE, range_m=1.55, count=3),)
    outside = (SonarObservation(sector=MIDDLE, range_m=1.45, count=3),)
    assert confirm_with_sonar([sighting], inside, MODEL, config)[0].range_m == pytest.approx(1.6)
    assert confirm_with_sonar([sighting], outside, MODEL, config) == ()


def test_a_noise_free_sonar_keeps_a_positive_definite_covariance():
    model = SonarModel(range_noise_std_m=0.0)
    observations = (SonarObservation(sector=MIDDLE, range_m=0.9, count=3),)
    (out,) = confirm_with_sonar([_sighting(1.0, 0.0)], observations, model, WORKED)
    assert out.cov[0, 0] == pytest.approx(1e-3**2)
    assert np.linalg.eigvalsh(out.cov).min() > 0


def test_filter_and_confirmation_together():
    rng = np.random.default_rng(7)
    f = SonarFilter()
    for k in range(5):  # a robot 1.2 m ahead: its chest 1.10 m from the transducers
        f.update(0.1 * k, _reading(middle=1.10 + 0.01 * rng.standard_normal(1)))
    vision = [_sighting(1.0, 2.0, team=None), _sighting(1.3, 45.0, team=None)]
    (out,) = confirm_with_sonar(vision, f.observations, MODEL, WORKED)
    assert out.sonar_confirmed and out.range_m == pytest.approx(1.2, abs=0.02)


def test_confirm_rejects_bad_inputs():
    observation = SonarObservation(sector=MIDDLE, range_m=0.9, count=3)
    with pytest.raises(InvalidTypeError, match=r"sightings\[0\]"):
        confirm_with_sonar([(1.0, 0.0)], [observation], MODEL)
    with pytest.raises(InvalidTypeError, match=r"observations\[0\]"):
        confirm_with_sonar([_sighting(1.0, 0.0)], [(MIDDLE, 0.9, 3)], MODEL)
    with pytest.raises(InvalidTypeError, match="SonarModel"):
        confirm_with_sonar([_sighting(1.0, 0.0)], [observation], None)
    with pytest.raises(ValueError, match=r"sightings\[0\].range_m"):
        confirm_with_sonar([_sighting(NAN, 0.0)], [observation], MODEL)
    with pytest.raises(ValueError, match=r"sightings\[0\].bearing_rad"):
        confirm_with_sonar([_sighting(1.0, math.inf)], [observation], MODEL)
    singular = RobotSighting(range_m=1.0, bearing_rad=0.0, cov=np.diag([0.01, 0.0]))
    with pytest.raises(ValueError, match=r"sightings\[0\].cov"):  # the tracker refuses it
        confirm_with_sonar([singular], [observation], MODEL)
    with pytest.raises(ValueError, match=r"sightings\[0\].team"):
        confirm_with_sonar([_sighting(1.0, 0.0, team="red")], [observation], MODEL)


def test_confirm_with_sonar_names_arguments_of_the_wrong_kind() -> None:
    sighting = RobotSighting(range_m=1.0, bearing_rad=0.1, cov=np.eye(2) * 1e-3)
    model = SonarModel()
    with pytest.raises(
        InvalidTypeError, match=r"^sightings must be a sequence of RobotSighting, got NoneType"
    ):
        confirm_with_sonar(None, [], model)  # type: ignore[arg-type]
    with pytest.raises(
        InvalidTypeError, match=r"^sightings must be a sequence of RobotSighting, got RobotSighting"
    ):
        confirm_with_sonar(sighting, [], model)  # type: ignore[arg-type]
    with pytest.raises(InvalidTypeError, match=r"^observations must be a sequence, got NoneType"):
        confirm_with_sonar([], None, model)  # type: ignore[arg-type]
    with pytest.raises(InvalidTypeError, match=r"^config must be a SonarFilterConfig, got str"):
        confirm_with_sonar([], [], model, "x")  # type: ignore[arg-type]


@pytest.mark.parametrize("echoes", [np.ones((3, 2)) * (1 + 1j), [["1"], ["1"], ["1"]]])
def test_echoes_that_are_not_real_numbers_are_refused(echoes: Any) -> None:
    with pytest.raises(InvalidTypeError, match=r"echoes must be a \(3, E\) array of distances"):
        SonarFilter().update(0.0, echoes)
