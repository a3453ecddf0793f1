"""``with_overrides``: ``gym.make`` keyword arguments onto the nested frozen ``EnvConfig``."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from spl_env.config import EnvConfig, with_overrides
from spl_env.sensors.laser import LaserConfig


def test_unique_names_and_dotted_paths_reach_nested_fields() -> None:
    config = with_overrides(EnvConfig(), episode_s=30, **{"sim.camera.noise_std": 0.01})
    assert config.episode_s == 30.0 and type(config.episode_s) is float
    assert config.sim.camera.noise_std == 0.01
    assert with_overrides(EnvConfig(), n_other_robots=2).sim.n_other_robots == 2


def test_overrides_apply_together_so_validation_sees_related_fields() -> None:
    a = with_overrides(EnvConfig(), physics_dt_s=0.05, control_dt_s=0.2, episode_s=2.0)
    b = with_overrides(EnvConfig(), episode_s=2.0, control_dt_s=0.2, physics_dt_s=0.05)
    assert a == b and a.max_steps == 10


def test_sub_fields_of_an_optional_config_that_is_none_start_from_its_defaults() -> None:
    assert EnvConfig().sim.laser is None
    for overrides in ({"n_beams": 90}, {"sim.laser.n_beams": 90}, {"laser": {"n_beams": 90}}):
        assert with_overrides(EnvConfig(), **overrides).sim.laser == LaserConfig(n_beams=90)
    with_laser = with_overrides(EnvConfig(), laser=LaserConfig(n_beams=90))
    config = with_overrides(with_laser, **{"sim.laser.fov_deg": 90})
    assert config.sim.laser == LaserConfig(n_beams=90, fov_deg=90.0)
    assert with_overrides(EnvConfig(), laser={}).sim.laser == LaserConfig()
    assert with_overrides(EnvConfig(), sonar=None).sim.sonar is None


def test_names_are_ambiguous_whether_or_not_optional_parts_are_none() -> None:
    # mount_height_m is in sim.sonar and sim.laser, even while laser is None
    with pytest.raises(TypeError, match=r"mount_height_m.*ambiguous.*sim\.laser\.mount_height_m"):
        with_overrides(EnvConfig(), mount_height_m=0.4)
    config = with_overrides(EnvConfig(), **{"sim.laser.mount_height_m": 0.4})
    assert config.sim.laser == LaserConfig(mount_height_m=0.4)


def test_nested_lists_become_tuples_and_the_config_stays_hashable() -> None:
    config = with_overrides(
        EnvConfig(), recall_by_smear=[[2, 1], [8, np.float64(0.5)]], max_speed=[0.2, 0.1, 1]
    )
    assert config.sim.geometric_camera.recall_by_smear == ((2.0, 1.0), (8.0, 0.5))
    assert all(
        type(v) is float for pair in config.sim.geometric_camera.recall_by_smear for v in pair
    )
    assert config.sim.robot.max_speed == (0.2, 0.1, 1.0)
    hash(config)


def test_numbers_accept_numpy_scalars_as_plain_python_numbers() -> None:
    config = with_overrides(EnvConfig(), noise_std=np.float32(0.5), n_other_robots=np.int64(2))
    assert config.sim.camera.noise_std == 0.5 and type(config.sim.camera.noise_std) is float
    assert config.sim.n_other_robots == 2 and type(config.sim.n_other_robots) is int


def test_caller_dicts_are_not_changed() -> None:
    camera = {"noise_std": 0.0}
    sim: dict[str, Any] = {"camera": camera}
    config = with_overrides(EnvConfig(), sim=sim, camera_mode="geometric", frontend="colour")
    assert config.sim.camera.noise_std == 0.0 and config.sim.camera_mode == "geometric"
    assert sim == {"camera": {"noise_std": 0.0}} and sim["camera"] is camera


@pytest.mark.parametrize(
    "overrides, match",
    [
        ({"episode_s": "30"}, r"'episode_s' expects float, got str"),
        ({"n_other_robots": 2.5}, r"'sim\.n_other_robots' expects int, got float"),
        ({"n_other_robots": True}, r"'sim\.n_other_robots' expects int, got bool"),
        ({"noise_std": False}, r"'sim\.camera\.noise_std' expects float, got bool"),
        ({"randomise_lighting": 1}, r"'sim\.camera\.randomise_lighting' expects bool"),
        ({"camera": None}, r"'sim\.camera' expects CameraConfig, got NoneType"),
        ({"walker": None}, r"'walker' expects WalkerConfig, got NoneType"),
        ({"episode_s": None}, r"'episode_s' expects float, got NoneType"),
        ({"laser": 5}, r"'sim\.laser' expects .*LaserConfig \| None, got int"),
        ({"n_beams": 90.0}, r"'sim\.laser\.n_beams' expects int, got float"),
        (
            {"max_speed": [0.2, 0.1]},
            r"'sim\.robot\.max_speed' expects tuple\[float, float, float\]",
        ),
        ({"max_speed": 0.2}, r"'sim\.robot\.max_speed' expects tuple.*got float"),
        ({"recall_by_smear": [[2, 1], [8]]}, r"'sim\.geometric_camera\.recall_by_smear' expects"),
        ({"recall_by_smear": [[2, "1"]]}, r"'sim\.geometric_camera\.recall_by_smear' expects"),
        ({"recall_by_smear": [[2, True]]}, r"'sim\.geometric_camera\.recall_by_smear' expects"),
        ({"pink_hsv": [[0, 0, 0], [1.5, 0, 0]]}, r"'perception\.colour_filter\.pink_hsv'"),
        ({"no_such_field": 1}, r"unknown config field 'no_such_field'"),
        ({"sim.camera.no_such_field": 1}, r"unknown config field 'sim\.camera\.no_such_field'"),
        ({"camera": {"no_such_field": 1}}, r"unknown config field 'sim\.camera\.no_such_field'"),
        ({"episode_s": {"x": 1}}, r"'episode_s' has no sub-fields"),
        ({"max_range_m": 5.0}, r"'max_range_m' is ambiguous.*'sim\.sonar\.max_range_m'"),
    ],
)
def test_bad_overrides_raise_type_errors_naming_the_field(
    overrides: dict[str, Any], match: str
) -> None:
    with pytest.raises(TypeError, match=match):
        with_overrides(EnvConfig(), **overrides)


@pytest.mark.parametrize(
    "overrides, match",
    [
        (
            {"noise_std": 0.0, "sim.camera.noise_std": 0.02},
            r"'sim\.camera\.noise_std' is set twice",
        ),
        (
            {"camera": {"noise_std": 0.0}, "noise_std": 0.02},
            r"'sim\.camera\.noise_std' is set twice",
        ),
        ({"sim": {"camera_mode": "geometric"}, "camera_mode": "rendered"}, r"'sim\.camera_mode'"),
        ({"sim": EnvConfig().sim, "camera_mode": "geometric"}, r"'sim' is set both whole and by"),
        ({"camera_mode": "geometric", "sim": EnvConfig().sim}, r"'sim' is set both whole and by"),
        ({"noise_std": 0.0, "sim.camera": None}, r"'sim\.camera' is set both whole and by"),
        ({"laser": LaserConfig(), "n_beams": 90}, r"'sim\.laser' is set both whole and by"),
        ({"laser": None, "sim.laser.n_beams": 90}, r"'sim\.laser' is set both whole and by"),
    ],
)
def test_a_field_set_twice_raises(overrides: dict[str, Any], match: str) -> None:
    with pytest.raises(TypeError, match=match):
        with_overrides(EnvConfig(), **overrides)


@pytest.mark.parametrize(
    "overrides, match",
    [
        ({"episode_s": 0.15}, "whole number"),
        ({"physics_dt_s": 0.2, "control_dt_s": 0.4}, "physics_dt_s"),
        ({"n_beams": 0}, "n_beams"),
    ],
)
def test_bad_values_raise_value_errors(overrides: dict[str, Any], match: str) -> None:
    with pytest.raises(ValueError, match=match):
        with_overrides(EnvConfig(), **overrides)


def test_front_and_back_end_are_selected_by_name() -> None:
    config = with_overrides(
        EnvConfig(), frontend="cnn", backend="fej", min_views=5, gate="mahalanobis"
    )
    assert config.perception.frontend == "cnn"
    slam = config.perception.slam
    assert (slam.backend, slam.resolved_min_views, slam.resolved_gate) == ("fej", 5, "mahalanobis")
    gated = with_overrides(EnvConfig(), backend="gated").perception.slam
    assert (gated.resolved_gate, gated.resolved_min_views) == ("thresholds", 1)


def test_default_perception_and_cnn_settings_by_name() -> None:
    default = EnvConfig().perception
    assert (default.frontend, default.slam.backend, default.cnn.score_threshold) == (
        "cnn",
        "gated",
        0.6,
    )
    assert default.cnn.require_both_colours
    cnn = with_overrides(EnvConfig(), score_threshold=0.5, edges=None, check_colours=False)
    assert cnn.perception.cnn.score_threshold == 0.5
    assert cnn.perception.cnn.edges is None and cnn.perception.cnn.check_colours is False
    near = with_overrides(EnvConfig(), width_min_px=20).perception.cnn.edges
    assert near is not None and near.width_min_px == 20.0


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        ({"frontend": "yolo"}, "frontend must be one of"),
        ({"backend": "ukf"}, "backend must be one of"),
        ({"min_views": 0}, "min_views must be >= 1"),
        ({"frontend": "cnn", "camera_mode": "geometric"}, "needs sim.camera_mode='rendered'"),
    ],
)
def test_bad_front_or_back_end_is_refused(overrides: dict[str, Any], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        with_overrides(EnvConfig(), **overrides)
