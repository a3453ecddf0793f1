"""Environment configuration: composes each part's frozen config, plus ``gym.make`` overrides.

Each algorithm's parameters live next to it (``SimConfig`` in :mod:`spl_env.simulation`,
``PipelineConfig`` in :mod:`perception.pipeline`, ...). :class:`EnvConfig` joins them. Keyword
arguments to ``gym.make`` name any field, top level or nested, as long as the name is unique::

    gym.make("SPL/ActiveVision-v0", episode_s=30.0, n_other_robots=2, randomise_lighting=True)

A dotted path (``**{"sim.camera.noise_std": 0.0}``) reaches fields whose name is not unique.
"""

from __future__ import annotations

import dataclasses
import math
import numbers
import types
import typing
from dataclasses import dataclass, field
from typing import Any

from perception.pipeline import PipelineConfig
from spl_env.behaviours import WalkerConfig
from spl_env.simulation import SimConfig

BODY_BEHAVIOURS = ("patrol", "square")


@dataclass(frozen=True, kw_only=True)
class EnvConfig:
    """Everything an SPL env is made of."""

    sim: SimConfig = field(default_factory=SimConfig)
    perception: PipelineConfig = field(default_factory=PipelineConfig)
    episode_s: float = 60.0  # episode length (s); truncation after episode_s / control_dt_s steps
    body_behaviour: str = "patrol"  # our walk: "patrol" (random waypoints) or "square"
    walker: WalkerConfig = field(default_factory=WalkerConfig)  # our robot's walking
    square_side_m: float = 1.8  # side of the "square" walk (seed 000's one-minute square)
    error_weight: float = 1.0  # reward per metre of true position error, per step
    uncertainty_weight: float = 0.5  # reward per metre of position std, per step

    def __post_init__(self) -> None:
        steps = self.episode_s / self.sim.control_dt_s
        if not (math.isfinite(steps) and steps >= 1 and abs(steps - round(steps)) < 1e-6):
            raise ValueError(
                "EnvConfig.episode_s must be a whole number (>= 1) of control steps of "
                f"{self.sim.control_dt_s} s, got {self.episode_s}"
            )
        if not self.sim.scene.poles_enabled:
            raise ValueError(
                "EnvConfig.sim.scene.poles_enabled must be True: the SPL envs map the poles"
            )
        if self.perception.frontend == "cnn" and self.sim.camera_mode != "rendered":
            raise ValueError(
                "EnvConfig.perception.frontend='cnn' (the default) needs "
                f"sim.camera_mode='rendered' (the CNN reads pixels), got camera_mode="
                f"{self.sim.camera_mode!r}; the geometric mode emulates the colour front end: "
                "pass frontend='colour' with it"
            )
        if self.body_behaviour not in BODY_BEHAVIOURS:
            raise ValueError(
                f"EnvConfig.body_behaviour must be one of {BODY_BEHAVIOURS}, "
                f"got {self.body_behaviour!r}"
            )
        if not (math.isfinite(self.square_side_m) and 0 < self.square_side_m <= 5.0):
            raise ValueError(
                f"EnvConfig.square_side_m must be in (0, 5] m, got {self.square_side_m}"
            )
        for name in ("error_weight", "uncertainty_weight"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0):
                raise ValueError(f"EnvConfig.{name} must be finite and >= 0, got {value}")

    @property
    def max_steps(self) -> int:
        """Control steps per episode."""
        return round(self.episode_s / self.sim.control_dt_s)


def _config_class(tp: Any) -> type | None:
    """The config dataclass in the annotation ``tp`` (``X`` or ``X | None``), if any."""
    is_union = typing.get_origin(tp) in (typing.Union, types.UnionType)
    options = typing.get_args(tp) if is_union else (tp,)
    return next((t for t in options if isinstance(t, type) and dataclasses.is_dataclass(t)), None)


def _field_paths(cls: type, prefix: str = "") -> dict[str, list[str]]:
    """Map each field name to the dotted paths where it occurs in the config class ``cls``.

    Walks the annotated types, so optional parts that are None by default (``sim.laser``)
    count too and whether a name is unique does not depend on the current values.
    """
    paths: dict[str, list[str]] = {}
    hints = typing.get_type_hints(cls)
    for f in dataclasses.fields(cls):
        path = f"{prefix}{f.name}"
        paths.setdefault(f.name, []).append(path)
        sub_class = _config_class(hints[f.name])
        if sub_class is not None:
            for name, sub in _field_paths(sub_class, f"{path}.").items():
                paths.setdefault(name, []).extend(sub)
    return paths


class _MismatchError(Exception):
    """A value does not fit a type annotation."""


def _convert(tp: Any, value: Any) -> Any:
    """``value`` as the annotation ``tp`` asks (lists to tuples, numbers to int or float)."""
    if typing.get_origin(tp) in (typing.Union, types.UnionType):
        for option in typing.get_args(tp):
            try:
                return _convert(option, value)
            except _MismatchError:
                pass
        raise _MismatchError
    if tp is tuple or typing.get_origin(tp) is tuple:
        if not isinstance(value, (tuple, list)):
            raise _MismatchError
        args = typing.get_args(tp)
        if not args or args[-1] is Ellipsis:  # tuple or tuple[X, ...]: any length
            args = (args[0] if args else Any,) * len(value)
        if len(args) != len(value):
            raise _MismatchError
        return tuple(_convert(arg, item) for arg, item in zip(args, value, strict=True))
    if tp is Any:
        return value
    if isinstance(value, bool) and tp is not bool:  # a bool is an int to Python, not here
        raise _MismatchError
    if tp is float and isinstance(value, numbers.Real):  # numpy scalars and ints included
        return float(value)
    if tp is int and isinstance(value, numbers.Integral):
        return int(value)
    if isinstance(tp, type) and isinstance(value, tp):  # str, bool, a config, None
        return value
    raise _MismatchError


def _coerce(path: str, tp: Any, value: Any) -> Any:
    """``value`` converted to the field's annotation ``tp``, or a TypeError naming ``path``."""
    try:
        return _convert(tp, value)
    except _MismatchError:
        name = tp.__name__ if isinstance(tp, type) else str(tp)
        raise TypeError(
            f"config field {path!r} expects {name}, got {type(value).__name__} {value!r}"
        ) from None


def _apply(config: Any, tree: dict[str, Any], prefix: str) -> Any:
    """Replace the fields named in ``tree`` (nested dicts for nested configs) in one go per
    dataclass, innermost first, so that validation sees every change together. Sub-fields of
    an optional config that is None are set on its defaults."""
    hints = typing.get_type_hints(type(config))
    changes = {}
    for name, value in tree.items():
        path = f"{prefix}{name}"
        if name not in {f.name for f in dataclasses.fields(config)}:
            raise TypeError(
                f"unknown config field {path!r}: {type(config).__name__} has no {name!r}"
            )
        if isinstance(value, dict):
            sub_class = _config_class(hints[name])
            if sub_class is None:
                raise TypeError(f"config field {path!r} has no sub-fields to set")
            current = getattr(config, name)
            changes[name] = _apply(sub_class() if current is None else current, value, f"{path}.")
        else:
            changes[name] = _coerce(path, hints[name], value)
    return dataclasses.replace(config, **changes)


def _insert(tree: dict[str, Any], path: str, value: Any) -> None:
    """Put ``value`` at the dotted ``path`` of ``tree``, a dict value spread into its sub-fields
    (never stored, so the caller's dicts are not changed); a TypeError if a field is set twice.
    """
    *parents, leaf = path.split(".")
    node = tree
    for i, parent in enumerate(parents):
        node = node.setdefault(parent, {})
        if not isinstance(node, dict):
            whole = ".".join(parents[: i + 1])
            raise TypeError(f"config field {whole!r} is set both whole and by sub-field")
    if isinstance(value, dict):
        if not isinstance(node.setdefault(leaf, {}), dict):
            raise TypeError(f"config field {path!r} is set both whole and by sub-field")
        for name, sub in value.items():
            _insert(tree, f"{path}.{name}", sub)
    elif isinstance(node.get(leaf), dict):
        raise TypeError(f"config field {path!r} is set both whole and by sub-field")
    elif leaf in node:
        raise TypeError(f"config field {path!r} is set twice")
    else:
        node[leaf] = value


def with_overrides(config: EnvConfig, **overrides: Any) -> EnvConfig:
    """A copy of ``config`` with fields replaced by name (unique) or dotted path.

    All overrides are applied together, so related fields (``physics_dt_s`` and
    ``control_dt_s``) can change in any order. Values must fit the field's annotation: an int
    is accepted for a float, numpy scalars for numbers, lists for tuples, None only where the
    field is optional; a dict sets sub-fields of a nested config (on its defaults if it is
    None). A wrong type, an unknown or ambiguous name, or a field set twice (twice as a leaf,
    or whole and by sub-field) raises ``TypeError`` naming the field.
    """
    paths = _field_paths(type(config))
    tree: dict[str, Any] = {}
    for key, value in overrides.items():
        if "." in key:
            path = key
        else:
            found = paths.get(key, [])
            if not found:
                raise TypeError(f"unknown config field {key!r} for EnvConfig")
            if len(found) > 1:
                raise TypeError(
                    f"config field {key!r} is ambiguous; use one of {found} as a dotted path"
                )
            path = found[0]
        _insert(tree, path, value)
    return _apply(config, tree, "")
