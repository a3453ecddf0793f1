"""``apply_overrides``: dotted paths, top-level names and explicit aliases onto toy config trees."""

from __future__ import annotations

import dataclasses
import functools
import math
import types
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from spl_env.overrides import apply_overrides


@dataclass(frozen=True, kw_only=True)
class Timing:
    """Two rates that must agree: validation needs both at once."""

    physics_dt_s: float = 0.01
    control_dt_s: float = 0.1

    def __post_init__(self) -> None:
        ratio = self.control_dt_s / self.physics_dt_s
        if not (ratio >= 1 and math.isclose(ratio, round(ratio))):
            raise ValueError(
                f"control_dt_s must be a whole multiple of physics_dt_s, got {self.control_dt_s} "
                f"and {self.physics_dt_s}"
            )


@dataclass(frozen=True, kw_only=True)
class Camera:
    noise_std: float = 0.01
    gain: int = 1
    lighting: bool = False
    mode: Literal["rendered", "geometric"] = "rendered"


@dataclass(frozen=True, kw_only=True)
class Sonar:
    range_noise_std_m: float = 0.02
    mount_height_m: float = 0.3


@dataclass(frozen=True, kw_only=True)
class Laser:
    n_beams: int = 60
    mount_height_m: float = 0.2

    def __post_init__(self) -> None:
        if self.n_beams < 1:
            raise ValueError(f"n_beams must be >= 1, got {self.n_beams}")


@dataclass(frozen=True, kw_only=True)
class Sim:
    timing: Timing = field(default_factory=Timing)
    camera: Camera = field(default_factory=Camera)
    sonar: Sonar | None = field(default_factory=Sonar)
    laser: Laser | None = None
    n_robots: int = 1
    seed: int | None = None
    speed: tuple[float, float, float] = (0.2, 0.1, 1.0)
    recall: tuple[tuple[float, float], ...] = ((2.0, 1.0),)


@dataclass(frozen=True, kw_only=True)
class Perception:
    frontend: str = "cnn"
    threshold: float = 0.6


@dataclass(frozen=True, kw_only=True)
class Root:
    sim: Sim = field(default_factory=Sim)
    perception: Perception = field(default_factory=Perception)
    episode_s: float = 60.0
    steps: int = field(default=0, init=False)  # derived, never set from outside

    def __post_init__(self) -> None:
        steps = self.episode_s / self.sim.timing.control_dt_s
        if not math.isclose(steps, round(steps)):
            raise ValueError(f"episode_s must be whole control steps, got {self.episode_s}")
        object.__setattr__(self, "steps", round(steps))


@dataclass(frozen=True, kw_only=True)
class GrownSim(Sim):
    """``Sim`` a release later: a field named like an alias target's leaf and like a
    top-level field."""

    frontend: str = "pixels"
    episode_s: float = 1.0


@dataclass(frozen=True, kw_only=True)
class GrownRoot(Root):
    sim: GrownSim = field(default_factory=GrownSim)


ALIASES = {"frontend": "perception.frontend", "n_robots": "sim.n_robots", "laser": "sim.laser"}


def get(config: Any, path: str) -> Any:
    """The value at the dotted ``path`` of ``config``."""
    return functools.reduce(getattr, path.split("."), config)


def test_dotted_path_top_level_name_and_alias_reach_their_fields() -> None:
    config = apply_overrides(
        Root(),
        {"sim.camera.noise_std": 0.02, "episode_s": 30, "frontend": "colour", "n_robots": 3},
        ALIASES,
    )
    assert config.sim.camera.noise_std == 0.02
    assert config.episode_s == 30.0 and type(config.episode_s) is float
    assert config.perception.frontend == "colour" and config.sim.n_robots == 3
    assert config.steps == 300  # recomputed by __post_init__, not copied
    assert apply_overrides(Root(), {}) == Root()


def test_a_key_names_no_field_elsewhere_in_the_tree() -> None:
    # n_beams and threshold are unique in the tree, but bare names are top-level fields only
    for key in ("n_beams", "threshold", "frontend"):
        with pytest.raises(TypeError, match=f"unknown config key '{key}'"):
            apply_overrides(Root(), {key: 1})


def test_an_unknown_bare_name_lists_the_dotted_paths_of_that_name() -> None:
    # mount_height_m is in sim.sonar and sim.laser, even while laser is None
    hint = (
        r"unknown config key 'mount_height_m'; did you mean one of "
        r"\['sim\.sonar\.mount_height_m', 'sim\.laser\.mount_height_m'\]\? Pass a dotted path$"
    )
    with pytest.raises(TypeError, match=hint):
        apply_overrides(Root(), {"mount_height_m": 0.4}, ALIASES)
    with pytest.raises(TypeError, match=r"\['sim\.camera\.noise_std'\]\? Pass a dotted path$"):
        apply_overrides(Root(), {"noise_std": 0.0}, ALIASES)


def test_the_hint_names_aliases_of_the_paths_it_lists() -> None:
    aliases = {"noise": "sim.camera.noise_std"}
    with pytest.raises(TypeError, match=r"or an alias \('noise' for 'sim\.camera\.noise_std'\)"):
        apply_overrides(Root(), {"noise_std": 0.0}, aliases)


@pytest.mark.parametrize(
    "overrides, match",
    [
        ({"n_beam": 90}, r"'n_beam'; did you mean one of \['sim\.laser\.n_beams'\]"),
        ({"sim.camera.noise": 0.0}, r"'sim\.camera\.noise'; .*\['sim\.camera\.noise_std'\]"),
        ({"sim.sonar.n_beams": 9}, r"key 'sim\.sonar\.n_beams'; .*\['sim\.laser\.n_beams'\]"),
        ({"xyz": 1}, r"^unknown config key 'xyz'; a key is a dotted path from the root"),
        ({"episode_s.x": 1}, r"^unknown config key 'episode_s\.x'; a key is a dotted path"),
        (
            {"sim": {"camera": {"nosie_std": 0.0}}},
            r"unknown config field 'sim\.camera\.nosie_std' \(in the value of key 'sim'\)",
        ),
        ({"laser": {"fov": 9}}, r"field 'sim\.laser\.fov' \(in the value of key 'laser'\)"),
        ({"steps": 3}, r"unknown config key 'steps'"),  # init=False: not overridable
    ],
)
def test_unknown_keys_and_fields_raise_type_errors(overrides: dict[str, Any], match: str) -> None:
    with pytest.raises(TypeError, match=match):
        apply_overrides(Root(), overrides, ALIASES)


@pytest.mark.parametrize(
    "aliases, match",
    [
        ({"episode_s": "sim.timing.control_dt_s"}, r"'episode_s' would shadow the top-level"),
        ({"sim": "sim.camera"}, r"'sim' would shadow the top-level field 'sim' of Root"),
        ({"beams": "sim.laser.nbeams"}, r"'sim\.laser\.nbeams', which is no field of Root"),
        ({"beams": "sim.laser.nbeams"}, r"did you mean one of \['sim\.laser\.n_beams'\]"),
        ({"beams": "n_beams"}, r"'n_beams', which is no field"),  # paths start at the root
        ({"steps": "steps"}, r"'steps', which is no field"),  # init=False
        ({"sim.n": "sim.n_robots"}, r"alias 'sim\.n' must be a bare name"),
        ({"": "sim.n_robots"}, r"alias '' must be a bare name"),
    ],
)
def test_the_alias_table_is_validated_even_with_no_overrides(
    aliases: dict[str, str], match: str
) -> None:
    with pytest.raises(ValueError, match=match):
        apply_overrides(Root(), {}, aliases)


def test_aliases_may_name_a_whole_config_a_leaf_or_a_top_level_field() -> None:
    aliases = {"clock": "sim.timing", "length": "episode_s", "noise": "sim.camera.noise_std"}
    config = apply_overrides(
        Root(), {"clock": {"control_dt_s": 0.2}, "noise": 0, "length": 2}, aliases
    )
    assert config.sim.timing == Timing(control_dt_s=0.2)
    assert (config.sim.camera.noise_std, config.episode_s, config.steps) == (0.0, 2.0, 10)
    with pytest.raises(TypeError, match="unknown config key 'clock'"):  # only with the table
        apply_overrides(Root(), {"clock": {"control_dt_s": 0.2}})


def test_adding_a_nested_field_does_not_change_what_keys_mean() -> None:
    # GrownRoot adds sim.frontend (the leaf of the alias target perception.frontend) and
    # sim.episode_s (a top-level name): the alias, the top-level name and the paths stay put
    overrides = {"frontend": "colour", "episode_s": 30, "sim.camera.noise_std": 0, "n_robots": 2}
    old = apply_overrides(Root(), overrides, ALIASES)
    new = apply_overrides(GrownRoot(), overrides, ALIASES)
    for path in ("perception.frontend", "episode_s", "sim.camera.noise_std", "sim.n_robots"):
        assert get(new, path) == get(old, path)
    assert (new.perception.frontend, new.episode_s) == ("colour", 30.0)
    assert (new.sim.frontend, new.sim.episode_s) == ("pixels", 1.0)  # the new fields untouched
    assert apply_overrides(GrownRoot(), {"sim.frontend": "rays"}).sim.frontend == "rays"


@pytest.mark.parametrize(
    "key, value, expected",
    [
        ("episode_s", 30, 30.0),
        ("episode_s", np.float32(0.5), 0.5),
        ("episode_s", np.int64(2), 2.0),
        ("sim.n_robots", np.int64(3), 3),
        ("sim.camera.lighting", True, True),
        ("sim.camera.mode", "geometric", "geometric"),
        ("sim.seed", None, None),
        ("sim.seed", np.int32(7), 7),
        ("sim.speed", [0.3, 0, np.float64(1)], (0.3, 0.0, 1.0)),
        ("sim.recall", [[2, 1], (8, np.float32(0.5))], ((2.0, 1.0), (8.0, 0.5))),
        ("sim.recall", [], ()),
        ("sim.sonar", None, None),
        ("sim.laser", Laser(n_beams=9), Laser(n_beams=9)),
    ],
)
def test_values_are_converted_to_the_annotation(key: str, value: Any, expected: Any) -> None:
    config = apply_overrides(Root(), {key: value})
    got = get(config, key)
    assert got == expected and type_tree(got) == type_tree(expected)
    hash(config)


def type_tree(value: Any) -> Any:
    """The type of ``value``; for a tuple, the tuple of its items' type trees."""
    return tuple(type_tree(item) for item in value) if isinstance(value, tuple) else type(value)


@pytest.mark.parametrize(
    "overrides, match",
    [
        ({"episode_s": "30"}, r"'episode_s' expects float, got str '30'"),
        ({"episode_s": True}, r"'episode_s' expects float, got bool True"),
        ({"episode_s": None}, r"'episode_s' expects float, got NoneType None"),
        ({"sim.n_robots": 2.0}, r"'sim\.n_robots' expects int, got float"),
        ({"sim.n_robots": np.float64(2)}, r"'sim\.n_robots' expects int, got float64"),
        ({"n_robots": False}, r"'sim\.n_robots' expects int, got bool"),
        ({"sim.seed": True}, r"'sim\.seed' expects int \| None, got bool"),
        ({"sim.camera.lighting": 1}, r"'sim\.camera\.lighting' expects bool, got int"),
        ({"sim.camera.mode": "raw"}, r"'sim\.camera\.mode' expects Literal\['rendered', 'geo"),
        ({"sim.camera": None}, r"'sim\.camera' expects Camera, got NoneType"),
        ({"laser": 5}, r"'sim\.laser' expects Laser \| None, got int 5"),
        ({"laser": Sonar()}, r"'sim\.laser' expects Laser \| None, got Sonar"),
        ({"sim.speed": [0.2, 0.1]}, r"'sim\.speed' expects tuple\[float, float, float\]"),
        ({"sim.speed": 0.2}, r"'sim\.speed' expects tuple.*got float"),
        ({"sim.speed": [0.2, 0.1, "1"]}, r"'sim\.speed' expects"),
        (
            {"sim.recall": [[2, 1], [8]]},
            r"'sim\.recall' expects tuple\[tuple\[float, float\], \.\.\.\]",
        ),
        ({"sim.recall": [[2, True]]}, r"'sim\.recall' expects"),
        ({"episode_s": {"x": 1}}, r"config field 'episode_s' has no sub-fields to set"),
        ({"sim.camera.gain": {}}, r"config field 'sim\.camera\.gain' has no sub-fields"),
    ],
)
def test_wrong_types_raise_type_errors_naming_path_and_type(
    overrides: dict[str, Any], match: str
) -> None:
    with pytest.raises(TypeError, match=match):
        apply_overrides(Root(), overrides, ALIASES)


def test_mappings_set_sub_fields_of_nested_configs() -> None:
    config = apply_overrides(Root(), {"sim": {"camera": {"gain": 2}, "n_robots": 4}})
    assert config.sim.camera == Camera(gain=2) and config.sim.n_robots == 4
    config = apply_overrides(config, {"sim": {"camera": {"noise_std": 0}}})
    assert config.sim.camera == Camera(gain=2, noise_std=0.0)  # on the current value
    assert apply_overrides(Root(), {"sim": {}}) == Root()
    proxy = types.MappingProxyType({"timing": types.MappingProxyType({"control_dt_s": 0.2})})
    assert apply_overrides(Root(), {"sim": proxy}).sim.timing == Timing(control_dt_s=0.2)


def test_sub_fields_of_an_optional_config_that_is_none_start_from_its_defaults() -> None:
    assert Root().sim.laser is None
    for overrides in (
        {"sim.laser.n_beams": 90},
        {"laser": {"n_beams": 90}},
        {"sim": {"laser": {"n_beams": 90}}},
    ):
        assert apply_overrides(Root(), overrides, ALIASES).sim.laser == Laser(n_beams=90)
    assert apply_overrides(Root(), {"laser": {}}, ALIASES).sim.laser == Laser()
    with_laser = apply_overrides(Root(), {"laser": Laser(n_beams=90)}, ALIASES)
    config = apply_overrides(with_laser, {"sim.laser.mount_height_m": 1})
    assert config.sim.laser == Laser(n_beams=90, mount_height_m=1.0)
    no_sonar = apply_overrides(Root(), {"sim.sonar": None})
    assert apply_overrides(no_sonar, {"sim.sonar.mount_height_m": 1}).sim.sonar == Sonar(
        mount_height_m=1.0
    )


@pytest.mark.parametrize(
    "overrides, match",
    [
        (
            {"n_robots": 2, "sim.n_robots": 3},
            r"'sim\.n_robots' is set twice \(by keys 'n_robots' and 'sim\.n_robots'\)",
        ),
        ({"sim": {"n_robots": 2}, "n_robots": 3}, r"'sim\.n_robots' is set twice \(by keys 'sim'"),
        (
            {"laser": {"n_beams": 2}, "sim.laser.n_beams": 3},
            r"'sim\.laser\.n_beams' is set twice \(by keys 'laser' and 'sim\.laser\.n_beams'\)",
        ),
        (
            {"sim": {"laser.n_beams": 2, "laser": {"n_beams": 3}}},
            r"'sim\.laser\.n_beams' is set twice \(by key 'sim'\)",
        ),
        (
            {"sim": Sim(), "n_robots": 2},
            r"'sim' is set both whole and by sub-field \(by keys 'sim'",
        ),
        ({"n_robots": 2, "sim": Sim()}, r"'sim' is set both whole and by sub-field \(by keys 'n_"),
        ({"sim.camera": None, "sim.camera.gain": 2}, r"'sim\.camera' is set both whole and by"),
        ({"laser": Laser(), "sim.laser.n_beams": 9}, r"'sim\.laser' is set both whole and by"),
        ({"laser": None, "sim.laser": {}}, r"'sim\.laser' is set both whole and by"),
        ({"sim.laser": {}, "laser": None}, r"'sim\.laser' is set both whole and by"),
        ({"sim": {"camera": {}}, "sim.camera": Camera()}, r"'sim\.camera' is set both whole"),
    ],
)
def test_a_field_set_twice_raises(overrides: dict[str, Any], match: str) -> None:
    with pytest.raises(TypeError, match=match):
        apply_overrides(Root(), overrides, ALIASES)


def test_different_sub_fields_of_one_config_can_come_from_different_keys() -> None:
    config = apply_overrides(
        Root(),
        {"laser": {"n_beams": 9}, "sim.laser.mount_height_m": 1, "sim": {"n_robots": 2}},
        ALIASES,
    )
    assert config.sim.laser == Laser(n_beams=9, mount_height_m=1.0) and config.sim.n_robots == 2


def test_validation_sees_all_changes_together_in_any_order() -> None:
    changes = {"sim.timing.physics_dt_s": 0.03, "sim.timing.control_dt_s": 0.09, "episode_s": 0.9}
    with pytest.raises(ValueError, match="whole multiple"):  # 0.1 s is no multiple of 0.03 s
        apply_overrides(Root(), {"sim.timing.physics_dt_s": 0.03})
    with pytest.raises(ValueError, match="whole control steps"):  # 60 s is no multiple of 0.09 s
        apply_overrides(Root(), {"sim.timing.control_dt_s": 0.09})
    a = apply_overrides(Root(), changes)
    b = apply_overrides(Root(), dict(reversed(changes.items())))
    c = apply_overrides(
        Root(), {"sim": {"timing": {"control_dt_s": 0.09, "physics_dt_s": 0.03}}, "episode_s": 0.9}
    )
    assert a == b == c and a.steps == 10
    assert a.sim.timing == Timing(physics_dt_s=0.03, control_dt_s=0.09)


@pytest.mark.parametrize(
    "overrides, match",
    [
        ({"sim.timing.physics_dt_s": 0.3}, "whole multiple"),
        ({"sim.timing.control_dt_s": 0.7}, "whole control steps"),  # the root sees the new dt
        ({"laser": {"n_beams": 0}}, "n_beams must be >= 1"),
    ],
)
def test_bad_values_raise_the_configs_value_errors(overrides: dict[str, Any], match: str) -> None:
    with pytest.raises(ValueError, match=match):
        apply_overrides(Root(), overrides, ALIASES)


def test_caller_mappings_are_not_changed() -> None:
    camera: dict[str, Any] = {"noise_std": 0.0}
    sim: dict[str, Any] = {"camera": camera, "laser": {}}
    overrides = {"sim": sim, "sim.camera.gain": 2, "laser": {"n_beams": 9}}
    aliases = dict(ALIASES)
    config = apply_overrides(Root(), overrides, aliases)
    assert config.sim.camera == Camera(noise_std=0.0, gain=2)
    assert config.sim.laser == Laser(n_beams=9)
    assert overrides == {"sim": sim, "sim.camera.gain": 2, "laser": {"n_beams": 9}}
    assert sim == {"camera": {"noise_std": 0.0}, "laser": {}} and sim["camera"] is camera
    assert camera == {"noise_std": 0.0} and aliases == ALIASES


def test_the_config_must_be_a_dataclass_instance() -> None:
    with pytest.raises(TypeError, match="config must be a dataclass instance, got type"):
        apply_overrides(Root, {})
    with pytest.raises(TypeError, match="config must be a dataclass instance, got dict"):
        apply_overrides({"episode_s": 1.0}, {})


# a value for some leaves; each can be spelt as its dotted path, as a mapping under any of its
# configs, or through an alias of it or of one of its configs
VALUES = {
    "perception.frontend": "colour",
    "sim.n_robots": 3,
    "sim.laser.n_beams": 8,
    "sim.camera.noise_std": 0,
    "sim.timing.physics_dt_s": 0.05,
    "sim.timing.control_dt_s": 0.2,
    "episode_s": 0.6,
}


def spellings(path: str) -> list[tuple[str, Any]]:
    """Every (key, value) that sets ``path`` to ``VALUES[path]``."""
    names = path.split(".")
    found = []
    for i in range(1, len(names) + 1):
        value = VALUES[path]
        for name in reversed(names[i:]):
            value = {name: value}
        target = ".".join(names[:i])
        found += [(key, value) for key in [target, *ALIASES] if ALIASES.get(key, key) == target]
    return found


def merge(a: dict[str, Any], b: dict[str, Any]) -> dict[str, Any]:
    """``a`` and ``b`` merged, nested mappings too."""
    both = {**a, **b}
    for key in a.keys() & b.keys():
        both[key] = merge(a[key], b[key])  # spellings of different leaves: mappings here
    return both


@st.composite
def spelt_overrides(draw: st.DrawFn) -> tuple[list[str], list[tuple[str, Any]]]:
    """Some leaves of ``VALUES``, and overrides that set them, each leaf spelt its own way
    (mappings for the same key merged), in a random order."""
    paths = [path for path in VALUES if draw(st.booleans())]
    merged: dict[str, Any] = {}
    for path in paths:
        key, value = draw(st.sampled_from(spellings(path)))
        merged = merge(merged, {key: value})
    return paths, draw(st.permutations(list(merged.items())))


# every field of Root that can be set, by hand, in tree order (Root.steps has init=False)
ROOT_PATHS = (
    "sim",
    "sim.timing",
    "sim.timing.physics_dt_s",
    "sim.timing.control_dt_s",
    "sim.camera",
    "sim.camera.noise_std",
    "sim.camera.gain",
    "sim.camera.lighting",
    "sim.camera.mode",
    "sim.sonar",
    "sim.sonar.range_noise_std_m",
    "sim.sonar.mount_height_m",
    "sim.laser",
    "sim.laser.n_beams",
    "sim.laser.mount_height_m",
    "sim.n_robots",
    "sim.seed",
    "sim.speed",
    "sim.recall",
    "perception",
    "perception.frontend",
    "perception.threshold",
    "episode_s",
)


def leaves(config: Any) -> dict[str, Any]:
    """The value at every path of ``Root`` that holds no config (None below a None config)."""
    found = {}
    for path in ROOT_PATHS:
        value = functools.reduce(
            lambda obj, name: getattr(obj, name, None), path.split("."), config
        )
        if not dataclasses.is_dataclass(value):
            found[path] = value
    return found


def test_spellings_cover_paths_aliases_and_mappings() -> None:
    assert spellings("sim.laser.n_beams") == [
        ("sim", {"laser": {"n_beams": 8}}),
        ("sim.laser", {"n_beams": 8}),
        ("laser", {"n_beams": 8}),
        ("sim.laser.n_beams", 8),
    ]


@given(spelt_overrides())
def test_the_result_depends_on_the_fields_set_not_on_spelling_order_or_new_fields(
    drawn: tuple[list[str], list[tuple[str, Any]]],
) -> None:
    paths, items = drawn
    config = apply_overrides(Root(), dict(items), ALIASES)
    assert config == apply_overrides(Root(), {path: VALUES[path] for path in paths})
    grown = apply_overrides(GrownRoot(), dict(items), ALIASES)
    assert leaves(grown) == leaves(config)
    assert (grown.sim.frontend, grown.sim.episode_s) == ("pixels", 1.0)
