"""The geometric camera mode's field features: the detector model's misses and noise
(:func:`perception.field.visibility.detected_features`, statistically), its validation, the
camera sway the emulator reproduces and the covariances it reports
(:mod:`spl_env.sensors.emulation.field`)."""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from scipy import stats

from perception.field.features import FEATURE_KINDS, FieldFeature
from perception.field.field_map import FieldMap
from perception.field.visibility import (
    DIRECTION_KINDS,
    DetectorModel,
    FeatureViewConfig,
    detected_features,
    visible_features,
)
from perception.geometry import camera_rotation
from perception.pipeline import PipelineConfig
from perception.types import CameraModel, CameraState
from perception.vision.field_features import FieldFeatureConfig
from spl_env.sensors.emulation.field import (
    GeometricFieldFeatures,
    detector_covariances,
    joints_camera,
    reproject,
)

FIELD = FieldMap()
CAMERA = CameraModel()
STATE = CameraState(
    position=np.array([0.05, 0.0, 0.5]), head_yaw=0.0, head_pitch=0.0, tilt=math.radians(20)
)
BEFORE_CENTRE = np.array([-1.5, 0.0, 0.0])  # 1.5 m before the halfway line, facing it
LEVEL = 0.999  # two-sided acceptance of the statistical checks
RESULTS = Path(__file__).resolve().parents[2] / "benchmarks" / "results"


def model(**changes: Any) -> DetectorModel:
    """A model with recall 1 and 1 cm + 2 %/m noise everywhere, but ``changes``."""
    bands = changes.pop("bands_m", (1.0, 2.0, 4.0, 6.0))
    values: dict[str, Any] = {
        "bands_m": bands,
        "recall": {k: (1.0,) * len(bands) for k in FEATURE_KINDS},
        "point_std_m": {k: (0.01, 0.02) for k in FEATURE_KINDS},
        "direction_std_rad": {k: 0.02 for k in DIRECTION_KINDS},
        "reported_direction_std_rad": {k: 0.05 for k in DIRECTION_KINDS},
    }
    return DetectorModel(**(values | changes))


def corner_at(distance_m: float, bearing_rad: float = 0.3) -> FieldFeature:
    point = distance_m * np.array([[math.cos(bearing_rad), math.sin(bearing_rad)]])
    return FieldFeature("corner", point, 1e-6 * np.eye(2)[None], 0.4, 0.01)


def chi2_accepts(sum_of_squares: float, dof: int) -> bool:
    low, high = stats.chi2.ppf([(1 - LEVEL) / 2, (1 + LEVEL) / 2], dof)
    return bool(low <= sum_of_squares <= high)


# ----- recall --------------------------------------------------------------------------------


def test_the_share_kept_per_band_is_the_configured_recall() -> None:
    recall = (0.9, 0.6, 0.3, 0.05)
    m = model(recall={k: recall for k in FEATURE_KINDS})
    rng = np.random.default_rng(0)
    draws = 4000
    for distance, p in zip((0.5, 1.5, 3.0, 5.0), recall, strict=True):
        kept = len(detected_features([corner_at(distance)] * draws, m, rng))
        low, high = stats.binom.interval(LEVEL, draws, p)
        assert low <= kept <= high, (distance, kept / draws, p)


def test_recall_goes_by_the_features_nearest_point_and_is_zero_beyond_the_bands() -> None:
    m = model(recall={k: (1.0, 1.0, 0.0, 1.0) for k in FEATURE_KINDS})
    rng = np.random.default_rng(1)
    # a line from 5 m to 1.5 m ahead: its nearest point (1.5 m) is in a band of recall 1
    line = FieldFeature(
        "line", np.array([[5.0, 0.5], [1.5, 0.5]]), 1e-6 * np.stack([np.eye(2)] * 2)
    )
    assert len(detected_features([line] * 200, m, rng)) == 200
    assert detected_features([corner_at(3.0)] * 200, m, rng) == ()  # 2-4 m: recall 0
    assert detected_features([corner_at(6.5)] * 200, m, rng) == ()  # beyond the last band


# ----- noise and its covariance -------------------------------------------------------------


@pytest.mark.parametrize("distance", [0.5, 2.5, 5.5])
def test_the_position_noise_has_the_configured_std_a_plus_b_range(distance: float) -> None:
    a, b = 0.01, 0.03
    m = model(point_std_m={k: (a, b) for k in FEATURE_KINDS})
    truth = corner_at(distance)
    found = detected_features([truth] * 3000, m, np.random.default_rng(2))
    errors = np.array([f.points[0] - truth.points[0] for f in found])
    std = a + b * distance
    assert chi2_accepts(float(np.sum((errors / std) ** 2)), errors.size)
    # ... and a sample far off that std is refused by the same test
    assert not chi2_accepts(float(np.sum((errors / (1.1 * std)) ** 2)), errors.size)
    # the reported covariance is that of the noise, the mean error none
    for f in found[:10]:
        np.testing.assert_allclose(f.cov[0], std**2 * np.eye(2))
    assert np.all(np.abs(errors.mean(axis=0)) < 4 * std / math.sqrt(len(errors)))


def test_a_segments_ends_take_the_noise_of_their_own_range() -> None:
    a, b = 0.005, 0.02
    m = model(point_std_m={k: (a, b) for k in FEATURE_KINDS})
    ends = np.array([[1.0, 0.0], [4.0, 3.0]])  # 1 m and 5 m away
    line = FieldFeature("line", ends, 1e-6 * np.stack([np.eye(2)] * 2))
    found = detected_features([line] * 3000, m, np.random.default_rng(3))
    errors = np.array([f.points - ends for f in found])  # (N, 2 ends, 2 axes)
    for k, distance in enumerate((1.0, 5.0)):
        std = a + b * distance
        assert chi2_accepts(float(np.sum((errors[:, k] / std) ** 2)), errors[:, k].size)
        np.testing.assert_allclose(found[0].cov[k], std**2 * np.eye(2))


def test_the_direction_noise_has_the_configured_std() -> None:
    m = model(direction_std_rad={k: 0.04 for k in DIRECTION_KINDS})
    truth = corner_at(2.0)
    found = detected_features([truth] * 3000, m, np.random.default_rng(4))
    assert truth.direction is not None
    errors = np.array([f.direction for f in found]) - truth.direction
    assert chi2_accepts(float(np.sum((errors / 0.04) ** 2)), len(errors))
    assert {f.direction_std for f in found} == {0.04}


def test_features_without_a_direction_keep_none() -> None:
    mark = FieldFeature("penalty_mark", np.array([[2.0, 0.0]]), 1e-6 * np.eye(2)[None])
    (found,) = detected_features([mark], model(), np.random.default_rng(5))
    assert found.direction is None and math.isnan(found.direction_std)


# ----- exact without a generator -------------------------------------------------------------


def test_without_a_generator_the_view_stays_exact_whatever_the_detector_model() -> None:
    blind = model(recall={k: (0.0,) * 4 for k in FEATURE_KINDS})
    exact = visible_features(FIELD, BEFORE_CENTRE, CAMERA, STATE, FeatureViewConfig())
    again = visible_features(FIELD, BEFORE_CENTRE, CAMERA, STATE, FeatureViewConfig(detector=blind))
    assert len(exact) == len(again) == 4
    for f, g in zip(exact, again, strict=True):
        np.testing.assert_array_equal(f.points, g.points)
        np.testing.assert_array_equal(f.cov, g.cov)
        assert f.direction == g.direction


# ----- validation -----------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("changes", "field"),
    [
        ({"bands_m": ()}, "DetectorModel.bands_m"),
        ({"bands_m": (2.0, 1.0, 3.0, 4.0)}, "DetectorModel.bands_m"),
        ({"bands_m": (0.0, 1.0, 3.0, 4.0)}, r"DetectorModel.bands_m\[0\]"),
        ({"bands_m": (1.0, 2.0, math.inf, 5.0)}, r"DetectorModel.bands_m\[2\]"),
        ({"recall": {"line": (1.0,) * 4}}, "DetectorModel.recall"),
        ({"recall": {k: (1.0, 1.0, 1.5, 1.0) for k in FEATURE_KINDS}}, r"recall\['line'\]\[2\]"),
        ({"recall": {k: (1.0, 1.0) for k in FEATURE_KINDS}}, r"DetectorModel.recall\['line'\]"),
        ({"recall": {k: (1.0, 1.0, math.nan, 1.0) for k in FEATURE_KINDS}}, r"\['line'\]\[2\]"),
        ({"point_std_m": {k: (0.0, 0.01) for k in FEATURE_KINDS}}, r"point_std_m\['line'\]\[0\]"),
        ({"point_std_m": {k: (0.01, -0.1) for k in FEATURE_KINDS}}, r"point_std_m\['line'\]\[1\]"),
        ({"point_std_m": {k: (0.01,) for k in FEATURE_KINDS}}, r"DetectorModel.point_std_m"),
        ({"direction_std_rad": {k: 0.0 for k in DIRECTION_KINDS}}, r"direction_std_rad\['corner'"),
        ({"direction_std_rad": {"corner": 0.01}}, "DetectorModel.direction_std_rad"),
        (
            {"reported_direction_std_rad": {k: -1.0 for k in DIRECTION_KINDS}},
            r"DetectorModel.reported_direction_std_rad\['corner'\]",
        ),
    ],
)
def test_bad_detector_models_are_refused_naming_the_field(
    changes: dict[str, Any], field: str
) -> None:
    with pytest.raises(ValueError, match=field):
        model(**changes)


def test_a_wrong_type_is_refused_naming_the_field() -> None:
    with pytest.raises(ValueError, match=r"DetectorModel\.recall"):
        model(recall=[1.0, 1.0])
    with pytest.raises(ValueError, match=r"DetectorModel.bands_m\[1\]"):
        model(bands_m=(1.0, "2", 4.0, 6.0))
    with pytest.raises(ValueError, match=r"FeatureViewConfig\.detector"):
        FeatureViewConfig(detector="fitted")  # type: ignore[arg-type]


def test_the_model_is_kept_as_validated_copies() -> None:
    recall = {k: [1.0, 0.5, 0.5, 0.0] for k in FEATURE_KINDS}
    m = model(recall=recall)
    recall["line"][0] = 0.0
    assert m.recall["line"] == (1.0, 0.5, 0.5, 0.0)


def test_the_default_model_is_the_fitted_one() -> None:
    """``DetectorModel``'s defaults are the model that
    ``benchmarks/fit_geometric_field_features.py`` wrote."""
    fitted = json.loads((RESULTS / "geometric_field_features.json").read_text())["model"]
    default = dataclasses.asdict(DetectorModel())
    assert tuple(fitted["bands_m"]) == default["bands_m"]
    for name in ("recall", "point_std_m"):
        assert {k: tuple(v) for k, v in fitted[name].items()} == default[name]
    for name in ("direction_std_rad", "reported_direction_std_rad"):
        assert fitted[name] == default[name]


# ----- the emulator: sway and reported covariances --------------------------------------------


def test_reprojecting_with_the_same_camera_changes_nothing() -> None:
    points = np.array([[1.0, 0.2], [3.0, -1.0], [6.0, 2.0]])
    camera = joints_camera(STATE)
    np.testing.assert_allclose(reproject(points, camera, camera, CAMERA), points, atol=1e-9)


def test_a_camera_pitched_lower_than_reported_places_points_farther() -> None:
    """A point straight ahead seen by a camera pitched ``delta`` lower than the joints say is
    placed where the reported camera's ray at its depression angle less ``delta`` lands."""
    delta = 0.02
    seen_by = (STATE.position, camera_rotation(0.0, STATE.head_pitch + STATE.tilt + delta))
    x0, h = float(STATE.position[0]), float(STATE.position[2])
    distances = np.array([1.0, 2.0, 4.0])
    points = np.column_stack([x0 + distances, np.zeros(3)])
    placed = reproject(points, seen_by, joints_camera(STATE), CAMERA)
    expected = x0 + h / np.tan(np.arctan(h / distances) - delta)
    np.testing.assert_allclose(placed[:, 0], expected, rtol=1e-9)
    np.testing.assert_allclose(placed[:, 1], 0.0, atol=1e-9)


def test_without_sway_the_emulator_reports_the_view_with_the_detectors_covariances() -> None:
    quiet = model(
        bands_m=(8.0,),
        point_std_m={k: (1e-6, 0.0) for k in FEATURE_KINDS},
        direction_std_rad={k: 1e-6 for k in DIRECTION_KINDS},
    )
    config = FeatureViewConfig(detector=quiet)
    emulator = GeometricFieldFeatures(FIELD, CAMERA, config)
    found = emulator.emulate(BEFORE_CENTRE, STATE, joints_camera(STATE), np.random.default_rng(6))
    exact = visible_features(
        FIELD, BEFORE_CENTRE, CAMERA, STATE, dataclasses.replace(config, max_range_m=8.0)
    )
    assert [f.kind for f in found] == [f.kind for f in exact]
    for f, e in zip(found, exact, strict=True):
        np.testing.assert_allclose(f.points, e.points, atol=1e-5)
        covariances = detector_covariances(f.points, CAMERA, STATE, FieldFeatureConfig())
        np.testing.assert_allclose(f.cov, covariances)
        if f.direction is not None:
            assert f.direction_std == quiet.reported_direction_std_rad[f.kind]


def test_the_reported_covariance_grows_with_range_as_the_detectors() -> None:
    """Ahead of the camera the detector's model: a pixel's footprint, mostly along the view,
    plus 1 cm + 1 % of the range on each axis."""
    points = np.array([[1.0, 0.0], [2.0, 0.0], [4.0, 0.0]])
    cov = detector_covariances(points, CAMERA, STATE, FieldFeatureConfig())
    along, across = np.sqrt(cov[:, 0, 0]), np.sqrt(cov[:, 1, 1])
    assert np.all(np.diff(along) > 0) and np.all(along > across)
    np.testing.assert_array_less(0.01 + 0.01 * points[:, 0], across + 1e-12)


def test_the_model_and_the_configs_holding_it_hash_by_value() -> None:
    assert hash(DetectorModel()) == hash(DetectorModel())
    assert DetectorModel() == DetectorModel()
    hash(PipelineConfig())  # every env config is hashable
