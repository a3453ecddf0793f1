"""Overrides of a nested dataclass config by dotted path, top-level name or explicit alias.

Generic over any tree of dataclasses (fields whose annotation is a dataclass, or a dataclass
``| None``, are nested configs)::

    apply_overrides(
        config,
        {"sensors.camera.noise_std": 0.0, "control_dt_s": 0.2, "frontend": "colour"},
        aliases={"frontend": "perception.pole_sightings"},
    )

A key is a dotted path from the root, a top-level field name (a one-element path) or an alias
from a short explicit table. A bare name is never looked up anywhere else in the tree, so adding
a field to a nested config cannot change what an existing key means; an unknown bare name raises
a ``TypeError`` that lists the dotted paths where a field of that name occurs.
"""

from __future__ import annotations

import dataclasses
import difflib
import numbers
import types
import typing
from collections.abc import Mapping
from typing import Any, TypeVar

T = TypeVar("T")

_NO_ALIASES: Mapping[str, str] = types.MappingProxyType({})


def _config_class(tp: Any) -> type | None:
    """The config dataclass in the annotation ``tp`` (``X`` or ``X | None``), if any."""
    is_union = typing.get_origin(tp) in (typing.Union, types.UnionType)
    options = typing.get_args(tp) if is_union else (tp,)
    return next((t for t in options if isinstance(t, type) and dataclasses.is_dataclass(t)), None)


def _schema(cls: type, prefix: str = "") -> dict[str, Any]:
    """Map the dotted path of every field that can be overridden to its annotation, in tree order.

    Walks the annotations, not values, so optional parts that are None count too and what a
    path means never depends on the current config. Fields with ``init=False`` are left out:
    ``dataclasses.replace`` cannot set them.
    """
    schema: dict[str, Any] = {}
    hints = typing.get_type_hints(cls)
    for f in dataclasses.fields(cls):
        if not f.init:
            continue
        path = f"{prefix}{f.name}"
        schema[path] = hints[f.name]
        sub_class = _config_class(hints[f.name])
        if sub_class is not None:
            schema.update(_schema(sub_class, f"{path}."))
    return schema


def _by_name(schema: Mapping[str, Any]) -> dict[str, list[str]]:
    """Map each field name in ``schema`` (dotted path -> annotation) to its dotted paths."""
    paths: dict[str, list[str]] = {}
    for path in schema:
        paths.setdefault(path.rpartition(".")[2], []).append(path)
    return paths


def _type_name(tp: Any) -> str:
    """The annotation ``tp`` as written in code, without module prefixes."""
    if tp is type(None):
        return "None"
    if tp is Ellipsis:
        return "..."
    origin = typing.get_origin(tp)
    args = typing.get_args(tp)
    if origin in (typing.Union, types.UnionType):
        return " | ".join(_type_name(arg) for arg in args)
    if origin is typing.Literal:
        return f"Literal[{', '.join(repr(arg) for arg in args)}]"
    if origin is not None:
        return f"{_type_name(origin)}[{', '.join(_type_name(arg) for arg in args)}]"
    return tp.__name__ if isinstance(tp, type) else str(tp)


class _MismatchError(Exception):
    """A value does not fit a type annotation."""


def _convert(tp: Any, value: Any) -> Any:
    """``value`` as the annotation ``tp`` asks (lists to tuples, numbers to int or float)."""
    origin = typing.get_origin(tp)
    if origin in (typing.Union, types.UnionType):
        for option in typing.get_args(tp):
            try:
                return _convert(option, value)
            except _MismatchError:
                pass
        raise _MismatchError
    if origin is typing.Literal:  # same type too: True == 1, but True is not Literal[1]
        if any(type(value) is type(arg) and value == arg for arg in typing.get_args(tp)):
            return value
        raise _MismatchError
    if tp is tuple or origin is tuple:
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
        raise TypeError(
            f"config field {path!r} expects {_type_name(tp)}, got {type(value).__name__} {value!r}"
        ) from None


def _suggestions(name: str, schema: Mapping[str, Any], aliases: Mapping[str, str]) -> str:
    """A did-you-mean hint for the unknown field ``name``: the dotted paths of fields of that
    name, else of near-miss names (typos), and the aliases of those paths; empty if none."""
    paths = _by_name(schema)
    names = [name] if name in paths else difflib.get_close_matches(name, list(paths), n=3)
    found = [path for near in names for path in paths[near]]
    if not found:
        return ""
    hint = f"; did you mean one of {found}? Pass a dotted path"
    short = [f"{alias!r} for {path!r}" for alias, path in aliases.items() if path in found]
    return hint + (f" or an alias ({', '.join(short)})" if short else "")


def _check_aliases(cls: type, schema: Mapping[str, Any], aliases: Mapping[str, str]) -> None:
    """A ValueError unless every alias is a bare name that is no top-level field of ``cls``
    and maps to the dotted path of a field."""
    for alias, path in aliases.items():
        if not alias or "." in alias:
            raise ValueError(f"config alias {alias!r} must be a bare name, without dots")
        if alias in schema:
            raise ValueError(
                f"config alias {alias!r} would shadow the top-level field {alias!r} of "
                f"{cls.__name__}"
            )
        if path not in schema:
            raise ValueError(
                f"config alias {alias!r} maps to {path!r}, which is no field of {cls.__name__}"
                + _suggestions(path.rpartition(".")[2], schema, {})
            )


class _Tree:
    """Overrides gathered by dotted path, each remembering the key that set it, with the
    conflicts (a field set twice, or set whole and by sub-field) refused as they come in."""

    def __init__(self, schema: Mapping[str, Any], aliases: Mapping[str, str]) -> None:
        self.schema = schema
        self.aliases = aliases
        self.values: dict[str, Any] = {}  # leaf path -> value
        self.set_by: dict[str, str] = {}  # leaf path -> key
        self.opened_by: dict[str, str] = {}  # path of a config set by sub-field -> key

    def add(self, key: str, path: str, value: Any) -> None:
        """Set ``path`` to ``value`` for ``key``; a mapping value sets sub-fields instead."""
        if path not in self.schema:
            where = "key" if path == key else "field"
            origin = "" if path == key else f" (in the value of key {key!r})"
            hint = _suggestions(path.rpartition(".")[2], self.schema, self.aliases)
            raise TypeError(
                f"unknown config {where} {path!r}{origin}"
                + (hint or "; a key is a dotted path from the root, a top-level field or an alias")
            )
        parents = path.split(".")[:-1]
        for i in range(len(parents)):
            self._open(key, ".".join(parents[: i + 1]))
        if isinstance(value, Mapping):
            if _config_class(self.schema[path]) is None:
                raise TypeError(f"config field {path!r} has no sub-fields to set")
            self._open(key, path)
            for name, sub in value.items():
                self.add(key, f"{path}.{name}", sub)
        elif path in self.opened_by:
            self._conflict(path, "both whole and by sub-field", self.opened_by[path], key)
        elif path in self.set_by:
            self._conflict(path, "twice", self.set_by[path], key)
        else:
            self.values[path] = value
            self.set_by[path] = key

    def _open(self, key: str, path: str) -> None:
        """Note that ``key`` sets sub-fields of the config at ``path``."""
        if path in self.set_by:
            self._conflict(path, "both whole and by sub-field", self.set_by[path], key)
        self.opened_by.setdefault(path, key)

    @staticmethod
    def _conflict(path: str, how: str, first: str, second: str) -> None:
        """Raise the TypeError for ``path`` set ``how`` by the keys ``first`` and ``second``."""
        keys = f"key {first!r}" if first == second else f"keys {first!r} and {second!r}"
        raise TypeError(f"config field {path!r} is set {how} (by {keys})")

    def nested(self) -> dict[str, Any]:
        """The overrides as nested dicts, one per config whose sub-fields are set."""
        tree: dict[str, Any] = {}
        for path in self.opened_by:
            _node(tree, path.split("."))
        for path, value in self.values.items():
            *parents, leaf = path.split(".")
            _node(tree, parents)[leaf] = value
        return tree


def _node(tree: dict[str, Any], names: list[str]) -> dict[str, Any]:
    """The dict at the path ``names`` of ``tree``, made where missing."""
    for name in names:
        tree = tree.setdefault(name, {})
    return tree


def _apply(config: Any, tree: dict[str, Any], prefix: str, schema: Mapping[str, Any]) -> Any:
    """Replace the fields named in ``tree`` (nested dicts for nested configs) in one go per
    dataclass, innermost first, so that validation sees every change together. Sub-fields of
    an optional config that is None are set on its defaults."""
    changes = {}
    for name, value in tree.items():
        path = f"{prefix}{name}"
        if isinstance(value, dict):  # a node of the tree: mapping values were spread
            sub_class = typing.cast(type, _config_class(schema[path]))
            current = getattr(config, name)
            start = sub_class() if current is None else current
            changes[name] = _apply(start, value, f"{path}.", schema)
        else:
            changes[name] = _coerce(path, schema[path], value)
    return dataclasses.replace(config, **changes)


def apply_overrides(
    config: T, overrides: Mapping[str, Any], aliases: Mapping[str, str] = _NO_ALIASES
) -> T:
    """A copy of the dataclass ``config`` with the fields named in ``overrides`` replaced.

    Each key is a dotted path from the root (``"sensors.camera.noise_std"``), a top-level field
    name, or an alias in ``aliases`` (alias -> dotted path; an alias must be a bare name, must
    map to a field, and must not be a top-level field name, else ``ValueError``). A bare name
    that is neither raises ``TypeError`` listing the dotted paths where that name occurs.

    All overrides are applied together, one ``dataclasses.replace`` per config, innermost
    first, so related fields can change in any order and ``__post_init__`` validation sees
    every change at once. Values must fit the field's annotation: an int is accepted for a
    float, numpy scalars for numbers, lists for tuples, None only where the field is optional,
    and a bool is no number. A mapping value sets sub-fields of a nested config (on its
    defaults if it is None). A wrong type, or a field set twice (twice as a leaf, e.g. by alias
    and by path, or whole and by sub-field), raises ``TypeError`` naming the field. Neither
    ``overrides`` nor the mappings in it are changed.
    """
    if not dataclasses.is_dataclass(config) or isinstance(config, type):
        raise TypeError(f"config must be a dataclass instance, got {type(config).__name__}")
    cls = type(config)
    schema = _schema(cls)
    _check_aliases(cls, schema, aliases)
    tree = _Tree(schema, aliases)
    for key, value in overrides.items():
        tree.add(key, aliases.get(key, key), value)
    return typing.cast(T, _apply(config, tree.nested(), "", schema))
