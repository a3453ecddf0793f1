"""The SPL envs' configs and their keyword overrides: dotted paths, top-level names and aliases.

The generic mechanism (:func:`spl_env.overrides.apply_overrides` on toy config trees) is tested
in ``test_overrides.py``; here: the env configs' own validation, their alias tables, and what
the envs' keyword arguments reach.
"""

from __future__ import annotations

import dataclasses
import functools
import re
from typing import Any

import gymnasium as gym
import numpy as np
import pytest

import spl_env  # noqa: F401  (registers the env ids)
from perception.pipeline import PipelineConfig
from perception.types import CameraModel
from perception.vision.robots import RobotDetectorConfig
from spl_env.config import SPL_ALIASES, EnvConfig
from spl_env.envs.active_vision import ACTIVE_VISION_ALIASES, ActiveVisionConfig
from spl_env.envs.look_around import LookAroundConfig
from spl_env.field import PoleLayout
from spl_env.overrides import apply_overrides
from spl_env.robots.nao import RobotConfig
from spl_env.scenes.spl_field import SceneConfig
from spl_env.sensors.camera import LightingRandomisation
from spl_env.sensors.laser import LaserConfig
from spl_env.sensors.odometry import OdometryConfig
from spl_env.sensors.rig import RigConfig
from spl_env.tasks.active_vision import ActiveVisionTaskConfig
from spl_env.tasks.base import TaskConfig
from spl_env.tasks.head_control import HeadControlTaskConfig

# Every alias, by hand: the dotted path it must reach and a valid value that is not the default
# of that field (so that setting it shows).
SPL_ALIAS_CASES: dict[str, tuple[str, Any]] = {
    "episode_s": ("task.episode_s", 30.0),
    "n_other_robots": ("task.n_other_robots", 2),
    "camera_mode": ("sensors.camera_mode", "geometric"),
    "randomise_lighting": ("sensors.camera.randomise_lighting", True),
    "sonar": ("sensors.sonar", None),
    "laser": ("sensors.laser", LaserConfig(n_beams=90)),
    "frontend": ("perception.pole_sightings", "colour"),
    "self_pose": ("perception.self_pose", "oracle"),
    "field_features": ("perception.field_features", "oracle"),
    "backend": ("perception.slam.backend", "fej"),
    "min_views": ("perception.slam.min_views", 3),
    "gate": ("perception.slam.gate", "mahalanobis"),
    # at least perception.cnn.score_threshold (0.4), which the detections keep
    "score_threshold": ("perception.cnn_pole_score_threshold", 0.5),
}
ACTIVE_VISION_ALIAS_CASES: dict[str, tuple[str, Any]] = {
    **SPL_ALIAS_CASES,
    "body_behaviour": ("task.body_behaviour", "square"),
    "square_side_m": ("task.square_side_m", 2.5),
}

# every env config class with the alias table its env uses, and that table's cases by hand
ENV_CONFIGS: list[tuple[type[EnvConfig], dict[str, str], dict[str, tuple[str, Any]]]] = [
    (EnvConfig, SPL_ALIASES, SPL_ALIAS_CASES),
    (ActiveVisionConfig, ACTIVE_VISION_ALIASES, ACTIVE_VISION_ALIAS_CASES),
    (LookAroundConfig, SPL_ALIASES, SPL_ALIAS_CASES),
]


def av(**overrides: Any) -> ActiveVisionConfig:
    """``ActiveVisionConfig()`` with ``overrides`` as ``SPL/ActiveVision-v0`` applies them."""
    return apply_overrides(ActiveVisionConfig(), overrides, ACTIVE_VISION_ALIASES)


def get(config: Any, path: str) -> Any:
    """The value at the dotted ``path`` of ``config``."""
    return functools.reduce(getattr, path.split("."), config)


# --- the alias tables --------------------------------------------------------------------------


@pytest.mark.parametrize(("config_class", "aliases", "cases"), ENV_CONFIGS)
def test_every_alias_names_its_path_and_shadows_no_top_level_field(
    config_class: type[EnvConfig], aliases: dict[str, str], cases: dict[str, tuple[str, Any]]
) -> None:
    assert aliases == {alias: path for alias, (path, _) in cases.items()}
    top_level = {f.name for f in dataclasses.fields(config_class)}
    for alias in aliases:
        assert "." not in alias and alias not in top_level, alias
    apply_overrides(config_class(), {}, aliases)  # the table itself is accepted


@pytest.mark.parametrize(("config_class", "aliases", "cases"), ENV_CONFIGS)
def test_each_alias_sets_the_field_of_its_path(
    config_class: type[EnvConfig], aliases: dict[str, str], cases: dict[str, tuple[str, Any]]
) -> None:
    default = config_class()
    assert set(cases) == set(aliases)  # a case by hand for every alias
    for alias, (path, value) in cases.items():
        assert get(default, path) != value, f"pick a value for {alias!r} that is no default"
        config = apply_overrides(default, {alias: value}, aliases)
        assert get(config, path) == value, alias
        # it sets that field and nothing else: the same config as its dotted path
        assert config == apply_overrides(default, {path: value}), alias
        # the alias and its path are one field: setting both is setting it twice
        with pytest.raises(TypeError, match=f"'{re.escape(path)}' is set twice"):
            apply_overrides(default, {alias: value, path: value}, aliases)


def test_the_shared_table_is_inside_the_active_vision_table() -> None:
    assert SPL_ALIASES.items() <= ACTIVE_VISION_ALIASES.items()
    assert set(ACTIVE_VISION_ALIASES) - set(SPL_ALIASES) == {"body_behaviour", "square_side_m"}


def test_an_alias_may_not_shadow_a_top_level_field() -> None:
    with pytest.raises(ValueError, match="would shadow the top-level field 'control_dt_s'"):
        apply_overrides(EnvConfig(), {}, {**SPL_ALIASES, "control_dt_s": "task.episode_s"})
    # a top-level name keeps meaning its own field
    assert apply_overrides(EnvConfig(), {"control_dt_s": 0.2}, SPL_ALIASES).control_dt_s == 0.2


def test_the_active_vision_aliases_fit_no_other_task() -> None:
    with pytest.raises(ValueError, match=r"'body_behaviour' maps to 'task\.body_behaviour'"):
        apply_overrides(EnvConfig(), {}, ACTIVE_VISION_ALIASES)
    with pytest.raises(TypeError, match="unknown config key 'body_behaviour'"):
        apply_overrides(LookAroundConfig(), {"body_behaviour": "square"}, SPL_ALIASES)


# --- what keys reach ---------------------------------------------------------------------------


def test_dotted_paths_top_level_names_and_aliases_reach_their_fields() -> None:
    config = av(episode_s=30, control_dt_s=0.2, **{"sensors.camera.noise_std": 0.01})
    assert config.task.episode_s == 30.0 and type(config.task.episode_s) is float
    assert config.control_dt_s == 0.2 and config.sensors.camera.noise_std == 0.01
    assert av(n_other_robots=2).task.n_other_robots == 2
    assert av(body_behaviour="square", square_side_m=2).task == ActiveVisionTaskConfig(
        body_behaviour="square", square_side_m=2.0
    )
    assert av(camera_mode="geometric", frontend="colour").sensors.camera_mode == "geometric"
    assert av(randomise_lighting=True).sensors.camera.randomise_lighting is True
    assert av(self_pose="oracle").perception.self_pose == "oracle"
    assert av(**{"task.episode_s": 6}).task.episode_s == 6.0


@pytest.mark.parametrize(
    ("key", "paths"),
    [
        ("noise_std", ["sensors.camera.noise_std"]),
        ("mount_height_m", ["sensors.sonar.mount_height_m", "sensors.laser.mount_height_m"]),
        ("n_beams", ["sensors.laser.n_beams"]),
        ("walker", ["task.walker"]),
        ("offset_outside_m", ["scene.poles.offset_outside_m"]),
    ],
)
def test_bare_nested_names_are_refused_with_their_dotted_paths(key: str, paths: list[str]) -> None:
    with pytest.raises(TypeError, match=f"unknown config key '{key}'") as raised:
        av(**{key: 1.0})
    message = str(raised.value)
    assert "did you mean" in message
    for path in paths:
        assert repr(path) in message


def test_the_hint_names_the_alias_of_a_refused_bare_name() -> None:
    with pytest.raises(TypeError, match=r"'perception\.pole_sightings'.*'frontend'"):
        av(pole_sightings="colour")
    with pytest.raises(TypeError, match=r"'sensors\.camera\.randomise_lighting'.*alias"):
        av(**{"randomise_lightning": True})  # a typo gets the near names


def test_overrides_apply_together_so_validation_sees_related_fields() -> None:
    a = av(physics_dt_s=0.05, control_dt_s=0.2, episode_s=2.0)
    b = av(episode_s=2.0, control_dt_s=0.2, physics_dt_s=0.05)
    assert a == b and a.max_steps == 10 and a.substeps == 4


def test_sub_fields_of_an_optional_config_that_is_none_start_from_its_defaults() -> None:
    assert ActiveVisionConfig().sensors.laser is None
    for overrides in ({"sensors.laser.n_beams": 90}, {"laser": {"n_beams": 90}}):
        assert av(**overrides).sensors.laser == LaserConfig(n_beams=90)
    with_laser = av(laser=LaserConfig(n_beams=90))
    config = apply_overrides(with_laser, {"sensors.laser.fov_deg": 90}, ACTIVE_VISION_ALIASES)
    assert config.sensors.laser == LaserConfig(n_beams=90, fov_deg=90.0)
    assert av(laser={}).sensors.laser == LaserConfig()
    assert av(sonar=None).sensors.sonar is None


def test_nested_lists_become_tuples_and_the_config_stays_hashable() -> None:
    config = av(
        **{
            "sensors.geometric_camera.recall_by_smear": [[2, 1], [8, np.float64(0.5)]],
            "robot.max_speed": [0.2, 0.1, 1],
        }
    )
    smear = config.sensors.geometric_camera.recall_by_smear
    assert smear == ((2.0, 1.0), (8.0, 0.5))
    assert all(type(v) is float for pair in smear for v in pair)
    assert config.robot.max_speed == (0.2, 0.1, 1.0)
    hash(config)


def test_numbers_accept_numpy_scalars_as_plain_python_numbers() -> None:
    config = av(n_other_robots=np.int64(2), **{"sensors.camera.noise_std": np.float32(0.5)})
    assert config.sensors.camera.noise_std == 0.5 and type(config.sensors.camera.noise_std) is float
    assert config.task.n_other_robots == 2 and type(config.task.n_other_robots) is int


def test_caller_dicts_are_not_changed() -> None:
    camera = {"noise_std": 0.0}
    sensors: dict[str, Any] = {"camera": camera}
    config = av(sensors=sensors, camera_mode="geometric", frontend="colour")
    assert config.sensors.camera.noise_std == 0.0 and config.sensors.camera_mode == "geometric"
    assert sensors == {"camera": {"noise_std": 0.0}} and sensors["camera"] is camera


@pytest.mark.parametrize(
    ("overrides", "match"),
    [
        ({"episode_s": "30"}, r"'task\.episode_s' expects float, got str"),
        ({"episode_s": None}, r"'task\.episode_s' expects float, got NoneType"),
        ({"episode_s": {"x": 1}}, r"'task\.episode_s' has no sub-fields"),
        ({"n_other_robots": 2.5}, r"'task\.n_other_robots' expects int, got float"),
        ({"n_other_robots": True}, r"'task\.n_other_robots' expects int, got bool"),
        ({"sensors.camera.noise_std": False}, r"'sensors\.camera\.noise_std' expects float"),
        ({"randomise_lighting": 1}, r"'sensors\.camera\.randomise_lighting' expects bool"),
        ({"sensors.camera": None}, r"'sensors\.camera' expects CameraConfig, got NoneType"),
        ({"task.walker": None}, r"'task\.walker' expects WalkerConfig, got NoneType"),
        ({"laser": 5}, r"'sensors\.laser' expects .*LaserConfig \| None, got int"),
        ({"sensors.laser.n_beams": 90.0}, r"'sensors\.laser\.n_beams' expects int, got float"),
        ({"robot.max_speed": [0.2, 0.1]}, r"'robot\.max_speed' expects tuple\[float, float, float"),
        ({"robot.max_speed": 0.2}, r"'robot\.max_speed' expects tuple.*got float"),
        (
            {"sensors.geometric_camera.recall_by_smear": [[2, 1], [8]]},
            r"'sensors\.geometric_camera\.recall_by_smear' expects",
        ),
        (
            {"sensors.geometric_camera.recall_by_smear": [[2, True]]},
            r"'sensors\.geometric_camera\.recall_by_smear' expects",
        ),
        (
            {"perception.colour_filter.pink_hsv": [[0, 0, 0], [1.5, 0, 0]]},
            r"'perception\.colour_filter\.pink_hsv'",
        ),
        ({"no_such_field": 1}, r"unknown config key 'no_such_field'"),
        ({"sensors.camera.no_such_field": 1}, r"unknown config key 'sensors\.camera\.no_such"),
        (
            {"sensors": {"camera": {"no_such_field": 1}}},
            r"unknown config field 'sensors\.camera\.no_such_field' \(in the value of key",
        ),
        # the old paths are gone
        ({"sim.camera.noise_std": 0.0}, r"unknown config key 'sim\.camera\.noise_std'"),
        ({"perception.frontend": "colour"}, r"unknown config key 'perception\.frontend'"),
    ],
)
def test_bad_overrides_raise_type_errors_naming_the_field(
    overrides: dict[str, Any], match: str
) -> None:
    with pytest.raises(TypeError, match=match):
        av(**overrides)


@pytest.mark.parametrize(
    ("overrides", "match"),
    [
        (
            {"randomise_lighting": True, "sensors.camera.randomise_lighting": False},
            r"'sensors\.camera\.randomise_lighting' is set twice",
        ),
        (
            {"sensors": {"camera_mode": "geometric"}, "camera_mode": "rendered"},
            r"'sensors\.camera_mode'",
        ),
        (
            {"sensors": RigConfig(), "camera_mode": "geometric"},
            r"'sensors' is set both whole and by",
        ),
        (
            {"sensors.camera.noise_std": 0.0, "sensors.camera": None},
            r"'sensors\.camera' is set both whole and by",
        ),
        (
            {"laser": LaserConfig(), "sensors.laser.n_beams": 90},
            r"'sensors\.laser' is set both whole and by",
        ),
        ({"episode_s": 3.0, "task.episode_s": 6.0}, r"'task\.episode_s' is set twice"),
    ],
)
def test_a_field_set_twice_raises(overrides: dict[str, Any], match: str) -> None:
    with pytest.raises(TypeError, match=match):
        av(**overrides)


# --- validation --------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("overrides", "match"),
    [
        ({"episode_s": 0.15}, "whole number"),
        ({"episode_s": 0.05}, "whole number"),  # less than one step
        ({"episode_s": -1.0}, "episode_s"),
        ({"physics_dt_s": 0.2, "control_dt_s": 0.4}, "physics_dt_s"),
        ({"control_dt_s": 2.0}, "control_dt_s <= 1 s"),
        ({"physics_dt_s": 0.03}, "whole multiple of physics_dt_s"),
        ({"scene.poles_enabled": False}, "poles_enabled"),
        ({"scene.poles.offset_outside_m": 0.69}, "border strip"),
        ({"info_level": "heavy"}, "info_level must be one of"),
        ({"sensors.laser.n_beams": 0}, "n_beams"),
        ({"n_other_robots": 10}, "n_other_robots"),
        ({"body_behaviour": "dance"}, "body_behaviour must be one of"),
        ({"square_side_m": 6.0}, "square_side_m"),
        ({"camera_mode": "magic"}, "camera_mode must be one of"),
    ],
)
def test_bad_values_raise_value_errors(overrides: dict[str, Any], match: str) -> None:
    with pytest.raises(ValueError, match=match):
        av(**overrides)


def test_env_config_validates_when_built_directly() -> None:
    with pytest.raises(ValueError, match="whole number"):
        EnvConfig(task=TaskConfig(episode_s=0.15))
    with pytest.raises(ValueError, match="whole multiple"):
        EnvConfig(control_dt_s=0.1, physics_dt_s=0.03)
    with pytest.raises(ValueError, match="poles_enabled=False needs a self pose"):
        EnvConfig(scene=SceneConfig(poles_enabled=False))
    with pytest.raises(ValueError, match="got 'ekf_slam_field_features'"):
        EnvConfig(
            scene=SceneConfig(poles_enabled=False),
            perception=PipelineConfig(self_pose="ekf_slam_field_features"),
        )
    with pytest.raises(ValueError, match="info_level"):
        EnvConfig(info_level="none")
    with pytest.raises(ValueError, match="whole number"):
        ActiveVisionConfig(task=ActiveVisionTaskConfig(episode_s=0.25))
    geometric = EnvConfig(
        sensors=RigConfig(camera_mode="geometric"),
        perception=PipelineConfig(pole_sightings="colour"),
        task=TaskConfig(episode_s=3.0),
        info_level="light",
        info_timing=True,
    )
    assert geometric.max_steps == 30 and geometric.substeps == 10


@pytest.mark.parametrize(
    ("build", "match"),
    [
        (lambda: EnvConfig(robot=None), r"EnvConfig\.robot must be a RobotConfig, got NoneType"),
        (lambda: EnvConfig(task=None), r"EnvConfig\.task must be a TaskConfig, got NoneType"),
        (
            lambda: EnvConfig(perception=PipelineConfig(slam=None)),
            r"PipelineConfig\.slam must be a EkfSlamConfig, got NoneType",
        ),
        (
            lambda: RigConfig(geometric_camera="bogus"),
            r"RigConfig\.geometric_camera must be a GeometricCameraConfig, got str",
        ),
        (lambda: RigConfig(laser="fine"), r"RigConfig\.laser must be a LaserConfig or None"),
        (lambda: SceneConfig(poles_enabled="False"), r"SceneConfig\.poles_enabled must be a bool"),
        (lambda: SceneConfig(boards_enabled=1), r"SceneConfig\.boards_enabled must be a bool"),
        (lambda: EnvConfig(info_timing="yes"), r"EnvConfig\.info_timing must be a bool"),
        (lambda: EnvConfig(control_dt_s="0.1"), r"EnvConfig\.control_dt_s must be a real number"),
        (lambda: CameraModel(hfov_deg="60"), r"CameraModel\.hfov_deg must be a real number"),
        (
            lambda: LightingRandomisation(ambient=None),
            r"LightingRandomisation\.ambient must be a tuple of 2 real numbers",
        ),
        (
            lambda: PoleLayout(x_positions_m=None),
            r"PoleLayout\.x_positions_m must be a tuple of 3 real numbers",
        ),
        (
            lambda: RobotDetectorConfig(width_ratio=None),
            r"RobotDetectorConfig\.width_ratio must be a tuple of 2 real numbers",
        ),
        (
            lambda: EnvConfig(robot=RobotConfig(max_speed=(0.25,))),
            r"RobotConfig\.max_speed must be a tuple of 3 real numbers, got tuple",
        ),
        (
            lambda: EnvConfig(
                sensors=RigConfig(odometry=OdometryConfig(heading_drift_rad_per_m=None))
            ),
            r"odometry\.heading_drift_rad_per_m must be a real number, got NoneType",
        ),
    ],
)
def test_nested_configs_and_flags_of_the_wrong_type_are_refused_by_name(
    build: Any, match: str
) -> None:
    with pytest.raises(TypeError, match=match):
        build()


def test_defaults_and_task_configs_per_env() -> None:
    assert type(ActiveVisionConfig().task) is ActiveVisionTaskConfig
    assert type(LookAroundConfig().task) is HeadControlTaskConfig
    default = EnvConfig()
    assert (default.control_dt_s, default.physics_dt_s) == (0.1, 0.01)
    assert (default.info_level, default.info_timing) == ("full", False)
    assert default.max_steps == 600 and default.sensors.camera_mode == "rendered"


def test_front_and_back_end_are_selected_by_name() -> None:
    config = av(frontend="cnn", backend="fej", min_views=5, gate="mahalanobis")
    assert config.perception.pole_sightings == "cnn"
    slam = config.perception.slam
    assert (slam.backend, slam.resolved_min_views, slam.resolved_gate) == ("fej", 5, "mahalanobis")
    gated = av(backend="gated").perception.slam
    assert (gated.resolved_gate, gated.resolved_min_views) == ("thresholds", 1)
    assert av(frontend="colour").perception.pole_sightings == "colour"
    assert av(frontend="oracle", self_pose="oracle").perception.self_pose == "oracle"


def test_default_perception_and_cnn_settings_by_path() -> None:
    default = ActiveVisionConfig().perception
    assert (default.pole_sightings, default.self_pose) == ("cnn", "ekf_slam")
    assert (default.slam.backend, default.cnn.score_threshold) == ("gated", 0.4)
    assert default.cnn_pole_score_threshold == 0.6 and default.cnn.require_both_colours
    cnn = av(
        score_threshold=0.5,
        **{"perception.cnn.edges": None, "perception.cnn.check_colours": False},
    )
    assert cnn.perception.cnn_pole_score_threshold == 0.5
    assert cnn.perception.cnn.score_threshold == 0.4  # the image detections keep theirs
    with pytest.raises(ValueError, match="cnn_pole_score_threshold"):
        av(score_threshold=0.3)  # below the detections' own threshold: it could not act
    assert cnn.perception.cnn.edges is None and cnn.perception.cnn.check_colours is False
    near = av(**{"perception.cnn.edges.width_min_px": 20}).perception.cnn.edges
    assert near is not None and near.width_min_px == 20.0


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        ({"frontend": "yolo"}, "pole_sightings must be one of"),
        ({"self_pose": "gps"}, "self_pose must be one of"),
        ({"backend": "ukf"}, "backend must be one of"),
        ({"min_views": 0}, r"min_views must be .*>= 1"),
    ],
)
def test_bad_front_or_back_end_is_refused(overrides: dict[str, Any], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        av(**overrides)


@pytest.mark.parametrize(
    "overrides",
    [{"frontend": "cnn", "camera_mode": "geometric"}, {"camera_mode": "geometric"}],
)
def test_the_geometric_mode_refuses_an_image_reader_without_emulator(
    overrides: dict[str, Any],
) -> None:
    # the default front end is the CNN, which reads images and has no emulator
    with pytest.raises(
        ValueError,
        match=r"renders no image.*'image_detections', 'pole_sightings'.*frontend='colour'",
    ):
        gym.make("SPL/ActiveVision-v0", **overrides)


@pytest.mark.parametrize(
    "overrides",
    [{"perception.odometry": "visual"}, {"robot_frontend": "vision_only"}],
)
def test_the_geometric_refusal_offers_what_would_help(overrides: dict[str, Any]) -> None:
    """The colour front end is already there: the message names the emulated providers and
    does not suggest it again."""
    with pytest.raises(ValueError, match="renders no image") as refused:
        gym.make("SPL/ActiveVision-v1", camera_mode="geometric", frontend="colour", **overrides)
    assert "frontend='colour'" not in str(refused.value)
    assert "robot_sightings='vision'" in str(refused.value)


def test_the_geometric_mode_builds_no_emulator_the_env_does_not_read() -> None:
    """ActiveVision-v0 tracks no robots: without a sonar it runs in the geometric mode, as in
    the rendered one (the robot sightings' emulator, which needs the sonar, is not built)."""
    env = gym.make("SPL/ActiveVision-v0", camera_mode="geometric", frontend="colour", sonar=None)
    assert sorted(env.unwrapped.rig.emulators) == ["pole_sightings"]
    env.reset(seed=0)
    env.step(np.zeros(2, dtype=np.float32))
    env.close()


@pytest.mark.parametrize(
    ("overrides", "sensor", "readers"),
    [
        ({"self_pose": "circle_slam", "camera_mode": "geometric"}, "laser", "'self_pose'"),
        # rendered: the geometric mode's robot emulator refuses a missing sonar itself
        ({"sonar": None}, "sonar", "'sonar_observations', 'robot_sightings'"),
    ],
)
def test_a_provider_reading_a_switched_off_sensor_is_refused_at_construction(
    overrides: dict[str, Any], sensor: str, readers: str
) -> None:
    with pytest.raises(ValueError, match=rf"\[{readers}\] read the {sensor}, but {sensor}=None"):
        gym.make("SPL/ActiveVision-v1", frontend="colour", **overrides)


def test_more_track_rows_than_the_tracker_keeps_are_refused() -> None:
    with pytest.raises(ValueError, match=r"task.max_tracked_robots must be <= .*max_tracks \(16"):
        gym.make(
            "SPL/ActiveVision-v1",
            camera_mode="geometric",
            frontend="colour",
            **{"task.max_tracked_robots": 17},
        )


# --- the envs' keyword arguments ---------------------------------------------------------------


def test_a_bare_nested_name_to_gym_make_is_refused_with_a_hint() -> None:
    with pytest.raises(TypeError, match=r"'noise_std'.*did you mean.*'sensors\.camera\.noise_std'"):
        gym.make("SPL/ActiveVision-v0", noise_std=0)
    with pytest.raises(TypeError, match="unknown config key 'body_behaviour'"):
        gym.make("SPL/LookAround-v0", body_behaviour="square")


def test_gym_make_takes_dotted_paths_top_level_names_and_aliases() -> None:
    env = gym.make(
        "SPL/ActiveVision-v0",
        frontend="colour",
        episode_s=3.0,
        body_behaviour="square",
        info_level="light",
        **{"sensors.camera.noise_std": 0.0},
    )
    config = env.unwrapped.config
    assert isinstance(config, ActiveVisionConfig)
    assert config.perception.pole_sightings == "colour"
    assert config.sensors.camera.noise_std == 0.0
    assert config.task.episode_s == 3.0 and config.task.body_behaviour == "square"
    assert config.info_level == "light"
    env.close()


def test_gym_make_takes_a_whole_config_and_refuses_another_envs() -> None:
    config = LookAroundConfig(
        perception=PipelineConfig(pole_sightings="colour"),
        task=HeadControlTaskConfig(episode_s=3.0),
    )
    env = gym.make("SPL/LookAround-v0", config=config, n_other_robots=1)
    assert env.unwrapped.config == dataclasses.replace(
        config, task=HeadControlTaskConfig(episode_s=3.0, n_other_robots=1)
    )
    env.close()
    with pytest.raises(TypeError, match="config must be a LookAroundConfig"):
        gym.make("SPL/LookAround-v0", config=ActiveVisionConfig())
