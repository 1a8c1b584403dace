"""Reading a runner's ``--config`` options: every problem is a
:class:`~dbn.errors.ConfigError` naming the key (``dbntrack track`` adds the file), never
a raw ``ValueError`` / ``TypeError`` of a conversion."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Collection, Mapping
from typing import Any, TypeVar

import numpy as np

from dbn.errors import ConfigError

__all__ = ["array", "build", "check_keys", "flag", "integer", "number", "override", "text"]

T = TypeVar("T")
_MISSING = object()


def check_keys(config: Mapping[str, Any], known: Collection[str]) -> None:
    """Refuse keys outside ``known`` (a misspelt option would silently do nothing)."""
    unknown = set(config) - set(known)
    if unknown:
        raise ConfigError(f"unknown config key(s) {sorted(unknown)}; valid: {sorted(known)}")


def _value(config: Mapping[str, Any], key: str, default: Any) -> Any:
    if key not in config and default is _MISSING:
        raise ConfigError(f"config {key}: missing")
    return config.get(key, default)


def number(config: Mapping[str, Any], key: str, default: Any = _MISSING) -> float:
    """``config[key]`` as a finite float (a JSON number, not a string or a boolean), else
    ``default`` (taken as it is: the caller's own value)."""
    v = _value(config, key, default)
    if key not in config:
        return float(v)
    try:
        out = float(v) if isinstance(v, int | float) and not isinstance(v, bool) else np.nan
    except OverflowError:  # a JSON integer beyond float range
        out = np.nan
    if not np.isfinite(out):
        raise ConfigError(f"config {key} = {v!r}: expected a finite number")
    return out


def integer(config: Mapping[str, Any], key: str, default: Any = _MISSING) -> int:
    """``config[key]`` as an int (a JSON integer: ``3.0`` is refused), else ``default``."""
    v = _value(config, key, default)
    if key in config and (isinstance(v, bool) or not isinstance(v, int)):
        raise ConfigError(f"config {key} = {v!r}: expected an integer")
    return int(v)


def flag(config: Mapping[str, Any], key: str, default: bool) -> bool:
    """``config[key]`` (else ``default``): ``true`` or ``false``."""
    v = config.get(key, default)
    if not isinstance(v, bool):
        raise ConfigError(f"config {key} = {v!r}: expected true or false")
    return v


def text(config: Mapping[str, Any], key: str, default: str) -> str:
    """``config[key]`` (else ``default``): a string."""
    v = config.get(key, default)
    if not isinstance(v, str):
        raise ConfigError(f"config {key} = {v!r}: expected a string")
    return v


def array(config: Mapping[str, Any], key: str, default: Any = _MISSING,
          ndim: int | None = None) -> np.ndarray:
    """``config[key]`` as a finite float array (nested JSON lists of numbers), of ``ndim``
    axes where given; else ``default`` as a float array (the caller's own value)."""
    v = _value(config, key, default)
    if key not in config:
        return np.asarray(v, dtype=np.float64)
    if _holds_bool(v):  # numpy would read true as 1.0
        raise ConfigError(f"config {key} = {v!r}: expected numbers, not true / false")
    try:
        out = np.asarray(v, dtype=np.float64)
    except (TypeError, ValueError):
        raise ConfigError(f"config {key} = {v!r}: expected numbers (a list, or lists)") from None
    if ndim is not None and out.ndim != ndim:
        raise ConfigError(f"config {key}: expected {ndim} axes, got shape {out.shape}")
    if not np.isfinite(out).all():
        raise ConfigError(f"config {key}: expected finite numbers")
    return out


def _holds_bool(v: Any) -> bool:
    """Whether ``v`` is a boolean or a (nested) list holding one."""
    return isinstance(v, bool) or (isinstance(v, list | tuple) and any(map(_holds_bool, v)))


def _defaults(cls: Any) -> dict[str, Any]:
    if hasattr(cls, "_field_defaults"):  # a NamedTuple
        return dict(cls._field_defaults)
    if dataclasses.is_dataclass(cls):
        return {f.name: f.default for f in dataclasses.fields(cls)
                if f.default is not dataclasses.MISSING}  # fmt: skip
    return {}


def build(cls: Callable[..., T], fields: Mapping[str, Any]) -> T:
    """``cls(**fields)`` for options taken from the config. A value must have the type of
    the field's default (a boolean, a string, a number; an integer where the default is
    one); a wrong type, or a value the class's own check refuses (its constructor, and
    its ``validate()`` where it has one), is a :class:`ConfigError`."""
    for key, default in _defaults(cls).items():
        if key in fields:
            _as_type_of(default, fields, key)  # checked; the value is passed as given
    try:
        obj = cls(**fields)
        if callable(getattr(obj, "validate", None)):
            obj.validate()
        return obj
    except ConfigError:
        raise
    except (TypeError, ValueError) as exc:  # library errors (DBNError) are ValueErrors
        raise ConfigError(f"config {sorted(fields)}: {exc}") from None


def override(obj: T, fields: Any, key: str) -> T:
    """``obj`` (a dataclass instance, e.g. a fitted default) with the config object
    ``fields`` (``config[key]``, e.g. ``{"max_gap_frames": 45}``) laid over it. Its scalar
    fields (those holding a boolean, an integer, a number or a string) take a value of
    that type (an integer where it holds one); a field holding a tuple (a fitted table)
    takes nested lists of numbers (e.g. a table ``dbntrack fit`` wrote), or ``[]`` to
    switch it off; the others keep ``obj``'s. An unknown field, a wrong type, or a value
    the class's own check refuses (its constructor: a table of the wrong shape) is a
    :class:`ConfigError` naming ``key.field``."""
    name = type(obj).__name__
    if not isinstance(fields, Mapping):
        raise ConfigError(f"config {key} = {fields!r}: expected an object of {name} fields")
    current = {f.name: getattr(obj, f.name)
               for f in dataclasses.fields(obj)}  # type: ignore[arg-type]  # fmt: skip
    settable = {f for f, v in current.items() if isinstance(v, bool | int | float | str | tuple)}
    unknown = sorted(set(fields) - settable)
    if unknown:
        raise ConfigError(f"config {key}: unknown or non-scalar {name} field(s) {unknown}; "
                          f"valid: {sorted(settable)}")  # fmt: skip
    typed = {field: _typed(key, field, value, current[field]) for field, value in fields.items()}
    try:
        return dataclasses.replace(obj, **typed)  # type: ignore[type-var]
    except (TypeError, ValueError) as exc:  # library errors (DBNError) are ValueErrors
        raise ConfigError(f"config {key}: {exc}") from None


def _typed(key: str, field: str, value: Any, current: Any) -> Any:
    """``value`` for ``key.field`` as the type of its ``current`` value (:func:`override`);
    a table (a tuple) as :func:`_table` reads it."""
    name = f"{key}.{field}"
    if isinstance(current, tuple):
        return _table(name, value, current)
    return _as_type_of(current, {name: value}, name)


def _table(name: str, value: Any, current: tuple) -> tuple:
    """A table field's value: ``[]`` switches it off (the empty tuple); a list, or nested
    lists, of numbers sets one (nested tuples; integers where ``current``'s entries are
    integers). Its shape is the class's own check (:func:`override`)."""
    if not isinstance(value, list) or _holds_bool(value):
        raise ConfigError(f"config {name} = {_shown(value)}: expected a table (a list, or "
                          "lists, of numbers), or [] to switch it off")  # fmt: skip
    leaf = _first_leaf(current)
    whole = isinstance(leaf, int) and not isinstance(leaf, bool)

    def entry(v: Any) -> Any:
        if isinstance(v, list):
            return tuple(entry(x) for x in v)
        return integer({name: v}, name) if whole else number({name: v}, name)

    try:
        return entry(value)
    except ConfigError:
        raise ConfigError(f"config {name}: expected {'integers' if whole else 'finite numbers'} "
                          f"in the table, got {_shown(value)}") from None  # fmt: skip


def _first_leaf(table: Any) -> Any:
    """The first entry of a (nested) tuple that is not a tuple; None if it has none."""
    while isinstance(table, tuple):
        if not table:
            return None
        table = table[0]
    return table


def _shown(value: Any, width: int = 60) -> str:
    """``repr(value)``, cut to ``width`` characters (a table can be long)."""
    text = repr(value)
    return text if len(text) <= width else text[: width - 3] + "..."


def _as_type_of(default: Any, config: Mapping[str, Any], key: str) -> Any:
    """``config[key]`` checked, and converted, as a value of ``default``'s type: a boolean,
    an integer (a JSON integer only), a number or a string; any other kind as it is."""
    if isinstance(default, bool):
        return flag(config, key, default)
    if isinstance(default, int):
        return integer(config, key)
    if isinstance(default, float):
        return number(config, key)
    if isinstance(default, str):
        return text(config, key, default)
    return config[key]
