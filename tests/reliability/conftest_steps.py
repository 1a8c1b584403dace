"""Helpers of the public-step fuzz (``test_steps.py``): one bad field at a time.

An observation is walked as a tree (named tuples, tuples, lists, dataclasses, arrays,
numbers); :func:`mutants` yields ``(label, bad_obs)`` pairs that each change ONE leaf in
one of the ways of issue 14 (NaN, inf, huge, negative, wrong dtype, text, wrong shape,
out-of-range id). :func:`snapshot` / :func:`same` compare a state before and after a
rejected step deeply (arrays by value, NaN equal to NaN, objects by their attributes).
"""

from __future__ import annotations

import copy
import dataclasses
from collections.abc import Iterator
from typing import Any

import jax
import numpy as np

KINDS = ("nan", "inf", "huge", "negative", "dtype", "text", "shape", "id")


def _is_array(x: Any) -> bool:
    return isinstance(x, (np.ndarray, jax.Array))


def _is_leaf(x: Any) -> bool:
    return _is_array(x) or (isinstance(x, (int, float, np.number)) and not isinstance(x, bool))


def _children(x: Any) -> list[tuple[str, Any]] | None:
    if isinstance(x, tuple) and hasattr(x, "_fields"):
        return list(zip(x._fields, x))
    if isinstance(x, (tuple, list)):
        return [(str(i), v) for i, v in enumerate(x)]
    if dataclasses.is_dataclass(x) and not isinstance(x, type):
        return [(f.name, getattr(x, f.name)) for f in dataclasses.fields(x)]
    return None


def _rebuild(x: Any, name: str, value: Any) -> Any:
    if isinstance(x, tuple) and hasattr(x, "_fields"):
        return x._replace(**{name: value})
    if isinstance(x, (tuple, list)):
        out = list(x)
        out[int(name)] = value
        return type(x)(out) if isinstance(x, list) else tuple(out)
    return dataclasses.replace(x, **{name: value})


def _bad_leaves(v: Any) -> Iterator[tuple[str, Any]]:
    """The bad versions of one leaf (array or number)."""
    a = np.asarray(v)
    isint = np.issubdtype(a.dtype, np.integer)
    isfloat = np.issubdtype(a.dtype, np.floating)
    if a.dtype == bool:
        yield "shape", np.zeros(a.shape + (2,), bool) if a.ndim else np.zeros(3, bool)
        return
    if not (isint or isfloat):
        return
    scalar = a.ndim == 0 and not _is_array(v)
    wrap = (lambda b: b.item()) if scalar else (lambda b: b)
    if isfloat and a.size:
        huge = min(1e50, float(np.finfo(a.dtype).max) / 10)  # huge, still finite in dtype
        for kind, val in (("nan", np.nan), ("inf", np.inf), ("huge", huge)):
            b = a.copy()
            b.flat[0] = val
            yield kind, wrap(b)
        b = a.copy()
        b.flat[0] = -abs(b.flat[0]) - 1.0
        yield "negative", wrap(b)
    if isint and a.size:
        for kind, val in (("id", 10**6), ("negative", -1)):
            b = a.copy()
            b.flat[0] = val
            yield kind, wrap(b)
        b = a.astype(np.float64)
        b.flat[0] += 0.5
        yield "dtype", wrap(b)
    if a.size:
        yield "dtype", wrap(a.astype(np.complex128)) if not scalar else "1"
    if a.size and not scalar:  # an array of text of the right shape (numpy's float() failed)
        yield "text", np.full(a.shape, "x")
    if not scalar:
        yield "shape", a[..., None] if a.ndim else a.reshape(1, 1)
        if a.ndim and a.shape[-1] > 1:
            yield "shape", a[..., :-1]


def mutants(obs: Any, prefix: str = "obs", depth: int = 0) -> Iterator[tuple[str, Any]]:
    """``(label, bad_obs)``: ``obs`` with ONE leaf made bad (label names field and kind)."""
    if _is_leaf(obs):
        for kind, bad in _bad_leaves(obs):
            yield f"{prefix}:{kind}", bad
        return
    kids = _children(obs) if depth < 4 else None
    if not kids:
        return
    for name, v in kids:
        for label, bad in mutants(v, f"{prefix}.{name}", depth + 1):
            yield label, _rebuild(obs, name, bad)


def snapshot(state: Any) -> Any:
    """A deep copy of ``state`` to compare with :func:`same` after a rejected step."""
    return copy.deepcopy(state)


def _plain(x: Any, seen: set[int], depth: int = 0) -> Any:
    if depth > 30:
        return "<deep>"
    if _is_array(x):
        return ("array", np.asarray(x).dtype.str, np.asarray(x).shape, np.asarray(x).tobytes())
    if isinstance(x, (str, bytes, int, float, bool, complex, type(None), np.number)):
        return ("f", repr(x)) if isinstance(x, float) else x
    if id(x) in seen:
        return "<cycle>"
    seen = seen | {id(x)}
    if isinstance(x, dict):
        return ("dict", [(_plain(k, seen, depth + 1), _plain(v, seen, depth + 1))
                         for k, v in x.items()])  # fmt: skip
    if isinstance(x, (list, tuple, set, frozenset)):
        items = sorted(x, key=repr) if isinstance(x, (set, frozenset)) else x
        return (type(x).__name__, [_plain(v, seen, depth + 1) for v in items])
    if hasattr(x, "__dict__") or hasattr(x, "__slots__"):
        attrs = dict(vars(x)) if hasattr(x, "__dict__") else {}
        for s in getattr(type(x), "__slots__", ()):
            if hasattr(x, s):
                attrs[s] = getattr(x, s)
        attrs = {k: v for k, v in attrs.items() if not callable(v) or _is_array(v)}
        return (type(x).__name__, _plain(attrs, seen, depth + 1))
    return repr(x)


def same(a: Any, b: Any) -> bool:
    """Whether two states are equal deeply (arrays bitwise, objects by attributes)."""
    return _plain(a, set()) == _plain(b, set())


def nan_leaves(state: Any, prefix: str = "state") -> list[str]:
    """The paths of the floating leaves of ``state`` holding NaN."""
    out: list[str] = []

    def walk(x: Any, path: str, seen: set[int], depth: int) -> None:
        if depth > 30:
            return
        if _is_array(x) or isinstance(x, (float, np.floating)):
            a = np.asarray(x)
            if np.issubdtype(a.dtype, np.inexact) and np.isnan(a).any():
                out.append(path)
            return
        if id(x) in seen or isinstance(x, (str, bytes, int, bool, type(None))):
            return
        seen = seen | {id(x)}
        if isinstance(x, dict):
            for k, v in x.items():
                walk(v, f"{path}[{k!r}]", seen, depth + 1)
        elif isinstance(x, (list, tuple)):
            for i, v in enumerate(x):
                walk(v, f"{path}[{i}]", seen, depth + 1)
        elif hasattr(x, "__dict__"):
            for k, v in vars(x).items():
                walk(v, f"{path}.{k}", seen, depth + 1)

    walk(state, prefix, set(), 0)
    return out
