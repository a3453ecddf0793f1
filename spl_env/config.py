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


def _field_paths(config: Any, prefix: str = "") -> dict[str, list[str]]:
    """Map each field name to the dotted paths where it occurs in a nested config."""
    paths: dict[str, list[str]] = {}
    for f in dataclasses.fields(config):
        path = f"{prefix}{f.name}"
        paths.setdefault(f.name, []).append(path)
        value = getattr(config, f.name)
        if dataclasses.is_dataclass(value) and not isinstance(value, type):
            for name, sub in _field_paths(value, f"{path}.").items():
                paths.setdefault(name, []).extend(sub)
    return paths


def _coerce(path: str, current: Any, value: Any) -> Any:
    """``value`` as the type of the field's ``current`` value, or a TypeError naming ``path``."""
    if current is None or value is None:  # optional parts, e.g. laser=LaserConfig() or sonar=None
        return value
    expected = type(current)
    if isinstance(current, bool) or not isinstance(current, (int, float, tuple)):
        ok = isinstance(value, expected)
    elif isinstance(current, tuple):
        ok = isinstance(value, (tuple, list))
        value = tuple(value) if ok else value
    else:  # int or float; an int is fine where a float is expected, a bool is not a number here
        ok = isinstance(value, (int, float) if expected is float else int)
        ok = ok and not isinstance(value, bool)
        value = float(value) if ok and expected is float else value
    if not ok:
        raise TypeError(
            f"config field {path!r} expects {expected.__name__}, got {type(value).__name__} "
            f"{value!r}"
        )
    return value


def _apply(config: Any, tree: dict[str, Any], prefix: str) -> Any:
    """Replace the fields named in ``tree`` (nested dicts for nested configs) in one go per
    dataclass, innermost first, so that validation sees every change together."""
    changes = {}
    for name, value in tree.items():
        path = f"{prefix}{name}"
        if name not in {f.name for f in dataclasses.fields(config)}:
            raise TypeError(f"{type(config).__name__} has no field {name!r} (in {path!r})")
        current = getattr(config, name)
        if isinstance(value, dict):
            if not dataclasses.is_dataclass(current):
                raise TypeError(f"config field {path!r} has no sub-fields to set")
            changes[name] = _apply(current, value, f"{path}.")
        else:
            changes[name] = _coerce(path, current, value)
    return dataclasses.replace(config, **changes)


def with_overrides(config: EnvConfig, **overrides: Any) -> EnvConfig:
    """A copy of ``config`` with fields replaced by name (unique) or dotted path.

    All overrides are applied together, so related fields (``physics_dt_s`` and
    ``control_dt_s``) can change in any order. Values must have the field's type (an int is
    accepted for a float); a wrong type raises ``TypeError`` naming the field.
    """
    paths = _field_paths(config)
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
        *parents, leaf = path.split(".")
        node = tree
        for parent in parents:
            node = node.setdefault(parent, {})
            if not isinstance(node, dict):
                raise TypeError(f"config field {parent!r} is set both whole and by sub-field")
        if isinstance(node.get(leaf), dict):
            raise TypeError(f"config field {path!r} is set both whole and by sub-field")
        node[leaf] = value
    return _apply(config, tree, "")
