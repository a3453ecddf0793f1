"""1-D SURF features and the horizon band (seed 004 chapter 3): invariants and closed forms."""

from __future__ import annotations

import math

import numpy as np
import pytest

from perception.geometry import camera_rotation
from perception.landmarks.horizon import HorizonConfig, horizon_band, horizon_rows
from perception.landmarks.surf1d import Surf1dConfig, Surf1dFeatures, extract_features
from perception.types import CameraModel, CameraState

CONFIG = Surf1dConfig()
CAMERA = CameraModel()  # 320 x 240


def bumps(x: np.ndarray, seed: int, count: int = 25, span: tuple[float, float] = (60, 340)):
    """A smooth random signal on positions ``x``: Gaussian bumps (bright and dark) of 1.5 to 8
    samples on a level of 2000, inside ``span``."""
    rng = np.random.default_rng(seed)
    centres = rng.uniform(*span, count)
    widths = rng.uniform(1.5, 8.0, count)
    heights = rng.uniform(-400.0, 400.0, count)
    profile = np.exp(-0.5 * ((x[:, None] - centres) / widths) ** 2)
    return 2000.0 + profile @ heights


def keyed(features: Surf1dFeatures, shift: int, length: int) -> dict:
    """Features whose descriptor window (under 8.5 s + 2 samples either side) lies within
    samples ``shift .. shift + length - 1``, keyed by (index - shift, filter size)."""
    margin = 8.5 * features.scale + 2.0
    position = features.index - shift
    keep = (position >= margin) & (position + margin < length)
    return {
        (int(i) - shift, int(size)): (int(sign), float(r), d)
        for i, size, sign, r, d in zip(
            features.index[keep],
            features.filter_size[keep],
            features.laplacian[keep],
            features.response[keep],
            features.descriptors[keep],
            strict=True,
        )
    }


def bump_scale(width: float) -> tuple[float, int]:
    """Scale and Laplacian sign of the strongest feature at the centre of one bright Gaussian
    bump of std ``width`` samples, centred on sample 200 of 400."""
    x = np.arange(400.0)
    features = extract_features(1000.0 + 300.0 * np.exp(-0.5 * ((x - 200) / width) ** 2), CONFIG)
    centre = features.index == 200
    strongest = np.argmax(np.where(centre, np.abs(features.response), -1.0))
    assert centre[strongest]
    return float(features.scale[strongest]), int(features.laplacian[strongest])


# --- configuration -----------------------------------------------------------------------


def test_filter_sizes_follow_surf_scheme() -> None:
    assert CONFIG.filter_sizes() == (
        (9, 1),
        (15, 1),
        (21, 1),
        (27, 1),
        (39, 2),
        (51, 2),
        (75, 4),
        (99, 4),
        (147, 8),
        (195, 8),
    )
    assert Surf1dConfig(octaves=1, intervals=2).filter_sizes() == ((9, 1), (15, 1), (21, 1))


@pytest.mark.parametrize(
    ("field", "value", "error"),
    [
        ("octaves", 0, ValueError),
        ("octaves", 2.0, TypeError),
        ("intervals", 0, ValueError),
        ("response_threshold", -1.0, ValueError),
        ("response_threshold", math.nan, ValueError),
        ("samples_per_subregion", 0, ValueError),
    ],
)
def test_surf_config_rejects_bad_fields(field: str, value: object, error: type) -> None:
    with pytest.raises(error, match=f"Surf1dConfig.{field}"):
        Surf1dConfig(**{field: value})  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("field", "value", "error"),
    [("band_rows", 0, ValueError), ("column_step", -2, ValueError), ("band_rows", 1.5, TypeError)],
)
def test_horizon_config_rejects_bad_fields(field: str, value: object, error: type) -> None:
    with pytest.raises(error, match=f"HorizonConfig.{field}"):
        HorizonConfig(**{field: value})  # type: ignore[arg-type]


def test_horizon_config_scales_seed_band_with_resolution() -> None:
    seed = HorizonConfig.for_resolution(640, 480)
    assert (seed.band_rows, seed.column_step) == (30, 4)
    assert (
        HorizonConfig.for_resolution(320, 240)
        == HorizonConfig()
        == HorizonConfig(band_rows=15, column_step=2)
    )
    small = HorizonConfig.for_resolution(160, 120)
    assert (small.band_rows, small.column_step) == (8, 1)  # 7.5 rounds up; step at least 1
    assert HorizonConfig.for_resolution(16, 16).column_step == 1


# --- extraction --------------------------------------------------------------------------


def test_features_shift_with_the_signal() -> None:
    x = np.arange(400.0)
    shift = 16  # a multiple of the coarsest sample step (8): every layer's grid moves along
    base = extract_features(bumps(x, seed=1), CONFIG)
    moved = extract_features(bumps(x - shift, seed=1), CONFIG)
    a, b = keyed(base, 0, 400 - shift), keyed(moved, shift, 400 - shift)  # the common part
    assert len(a) >= 30
    assert a.keys() == b.keys()
    for key, (sign, response, descriptor) in a.items():
        assert b[key][0] == sign
        assert b[key][1] == pytest.approx(response, rel=1e-9, abs=1e-9)
        np.testing.assert_allclose(b[key][2], descriptor, atol=1e-9)


def test_features_ignore_offset_and_gain() -> None:
    signal = bumps(np.arange(300.0), seed=2, span=(40, 260))
    base = extract_features(signal, CONFIG)
    scaled = extract_features(3.0 * signal - 500.0, Surf1dConfig(response_threshold=90.0))
    np.testing.assert_array_equal(scaled.index, base.index)
    np.testing.assert_array_equal(scaled.filter_size, base.filter_size)
    np.testing.assert_allclose(scaled.response, 3.0 * base.response, rtol=1e-9)
    np.testing.assert_allclose(scaled.descriptors, base.descriptors, atol=1e-9)


@pytest.mark.parametrize("width", [2.0, 3.0, 4.0, 6.0])
def test_detected_scale_doubles_with_the_blob(width: float) -> None:
    small, small_sign = bump_scale(width)
    large, large_sign = bump_scale(2.0 * width)
    assert small_sign == large_sign == -1  # bright blobs: negative second derivative
    assert 1.6 <= large / small <= 2.5  # 2 on the discrete grid (neighbouring ratios 1.8-2.4)
    assert 0.75 <= small / width <= 1.25  # s = 1.2 L / 9 tracks the blob's std


def test_dark_blob_has_positive_laplacian() -> None:
    x = np.arange(200.0)
    features = extract_features(1000.0 - 300.0 * np.exp(-0.5 * ((x - 96) / 3.0) ** 2), CONFIG)
    at_centre = features.index == 96
    assert at_centre.any()
    assert (features.laplacian[at_centre] == 1).all()
    assert (features.response[at_centre] > 0).all()


@pytest.mark.parametrize(
    "signal",
    [np.full(160, 1234.0), 7.0 * np.arange(160.0) + 300.0, np.zeros(80), np.zeros(0)],
    ids=["constant", "linear", "zeros", "empty"],
)
def test_flat_signals_have_no_features(signal: np.ndarray) -> None:
    features = extract_features(signal, CONFIG)
    assert len(features) == 0
    assert features.descriptors.shape == (0, 6)


def test_feature_arrays_are_consistent() -> None:
    signal = bumps(np.arange(160.0), seed=3, count=12, span=(0, 160))
    columns = 2 * np.arange(160)
    features = extract_features(signal, CONFIG, columns=columns)
    n = len(features)
    assert n > 10
    assert features.descriptors.shape == (n, 6)
    np.testing.assert_allclose(np.linalg.norm(features.descriptors, axis=1), 1.0)
    np.testing.assert_array_equal(features.x, columns[features.index])
    np.testing.assert_array_equal(features.laplacian, np.sign(features.response))
    assert (np.abs(features.response) > CONFIG.response_threshold).all()
    np.testing.assert_allclose(features.scale, 1.2 * features.filter_size / 9.0)
    # the descriptor window (about 7.5 s either side) lies inside the signal
    assert (features.index >= 7.0 * features.scale).all()
    assert (features.index <= 159 - 7.0 * features.scale).all()
    with pytest.raises(ValueError):
        features.x[0] = 1.0  # read-only


def test_window_leaving_the_signal_drops_the_feature() -> None:
    x = np.arange(100.0)
    blob = 1000.0 + 300.0 * np.exp(-0.5 * ((x - 50) / 2.0) ** 2)
    assert (extract_features(blob, CONFIG).index == 50).any()
    near_border = 1000.0 + 300.0 * np.exp(-0.5 * ((x - 12) / 2.0) ** 2)
    features = extract_features(near_border, CONFIG)
    assert not (features.filter_size[features.index == 12] >= 15).any()  # 7 s + h > 12 for s >= 2


@pytest.mark.parametrize(
    ("signal", "columns", "message"),
    [
        (np.zeros((2, 80)), None, "signal must be 1-D"),
        (np.array([1.0, np.nan, 2.0]), None, "signal must be finite"),
        ("abc", None, "signal must be"),
        (np.zeros(80), np.arange(79), "columns"),
    ],
)
def test_extract_rejects_bad_input(signal: object, columns: object, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        extract_features(signal, CONFIG, columns=columns)  # type: ignore[arg-type]


# --- horizon -----------------------------------------------------------------------------


def state(pitch: float = 0.0, yaw: float = 0.0, tilt: float = 0.0) -> CameraState:
    return CameraState(
        position=np.array([0.0, 0.0, 0.5]), head_yaw=yaw, head_pitch=pitch, tilt=tilt
    )


def test_level_camera_horizon_is_principal_row() -> None:
    u = np.arange(0.0, 320.0, 10.0)
    rows = horizon_rows(u, CAMERA, camera_rotation(0.0, 0.0))
    np.testing.assert_allclose(rows, CAMERA.cy)
    np.testing.assert_allclose(horizon_rows(u, CAMERA, camera_rotation(1.0, 0.0)), CAMERA.cy)


@pytest.mark.parametrize("pitch", [0.1, 0.3, -0.2])
def test_pitch_moves_horizon_by_f_tan_pitch(pitch: float) -> None:
    u = np.arange(0.0, 320.0, 10.0)
    expected = CAMERA.cy - CAMERA.fy * math.tan(pitch)  # pitched down: the horizon rises
    np.testing.assert_allclose(horizon_rows(u, CAMERA, camera_rotation(0.0, pitch)), expected)
    band = horizon_band(
        np.zeros((240, 320)), CAMERA, state(pitch=pitch - 0.05, tilt=0.05), HorizonConfig()
    )
    np.testing.assert_allclose(band.rows, expected)


@pytest.mark.parametrize("roll", [0.1, -0.25])
def test_roll_tilts_horizon_by_roll_angle(roll: float) -> None:
    u = np.array([0.0, 160.0, 319.0])
    rows = horizon_rows(u, CAMERA, camera_rotation(0.0, 0.0, body_roll=roll))
    assert rows[1] == pytest.approx(CAMERA.cy)
    assert math.atan2(rows[0] - rows[2], u[2] - u[0]) == pytest.approx(roll)
    band = horizon_band(np.zeros((240, 320)), CAMERA, state(), HorizonConfig(), body_roll=roll)
    np.testing.assert_allclose(band.rows, CAMERA.cy - math.tan(roll) * (band.columns - CAMERA.cx))


def test_camera_looking_down_has_no_horizon() -> None:
    band = horizon_band(np.zeros((240, 320)), CAMERA, state(pitch=math.pi / 2), HorizonConfig())
    assert np.isnan(band.rows).all()
    assert not band.valid.any()


def test_band_of_constant_image_is_rows_times_value() -> None:
    config = HorizonConfig()
    band = horizon_band(np.full((240, 320), 77, dtype=np.uint8), CAMERA, state(), config)
    np.testing.assert_array_equal(band.columns, np.arange(0, 320, 2))
    np.testing.assert_allclose(band.signal, config.band_rows * 77.0)  # no uint8 overflow
    assert band.valid.all()


def test_band_is_centred_on_horizon_and_shifted_inside() -> None:
    image = np.repeat(np.arange(240.0)[:, None], 320, axis=1)  # grey value = row index
    config = HorizonConfig()  # 15 rows
    level = horizon_band(image, CAMERA, state(), config)
    np.testing.assert_allclose(level.signal, 15 * 120.0)  # rows 113 .. 127
    low = CAMERA.cy - 236.0  # horizon on row 236: 3 rows from the bottom border
    near_bottom = horizon_band(image, CAMERA, state(pitch=math.atan(low / CAMERA.fy)), config)
    np.testing.assert_allclose(near_bottom.rows, 236.0)
    np.testing.assert_allclose(near_bottom.signal, np.arange(225, 240).sum())  # last 15 rows
    assert near_bottom.valid.all()
    below = CAMERA.cy - 260.0
    outside = horizon_band(image, CAMERA, state(pitch=math.atan(below / CAMERA.fy)), config)
    assert not outside.valid.any()


def test_horizon_band_rejects_bad_input() -> None:
    with pytest.raises(ValueError, match="gray_image must have shape"):
        horizon_band(np.zeros((240, 320, 3)), CAMERA, state(), HorizonConfig())
    with pytest.raises(ValueError, match="band_rows"):
        horizon_band(np.zeros((240, 320)), CAMERA, state(), HorizonConfig(band_rows=241))
    with pytest.raises(TypeError, match="gray_image"):
        horizon_band(np.zeros((240, 320), dtype=bool), CAMERA, state(), HorizonConfig())
    with pytest.raises(ValueError, match="body_roll"):
        horizon_band(np.zeros((240, 320)), CAMERA, state(), HorizonConfig(), body_roll=math.inf)
