"""Saving and loading a filter's belief (a NamedTuple of arrays) without pickle.

The file is an ``.npz`` holding every field of the state plus a JSON header (a
``format`` tag and whatever the caller adds, e.g. its static configuration), so that
a run resumed from a loaded state continues bit-identically.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np

from dbn.errors import InputError

__all__ = ["save_state", "load_state"]


def save_state(path, state, fmt: str, header: dict | None = None) -> None:
    """Write ``state`` (a NamedTuple of arrays) and a JSON header to ``path`` (.npz).

    Parameters
    ----------
    path : file name or file object
    state : NamedTuple whose fields are arrays
    fmt : format tag stored in the header and checked by :func:`load_state`
    header : extra JSON-serialisable entries
    """
    arrays = {f: np.asarray(getattr(state, f)) for f in state._fields}
    head = json.dumps({"format": fmt, **(header or {})})
    np.savez(path, __header__=np.frombuffer(head.encode(), np.uint8), **arrays)


def load_state(
    path, state_type: type, fmt: str, check: Callable[[dict], None] | None = None
) -> Any:
    """Read a state written by :func:`save_state`.

    Parameters
    ----------
    path : file written by :func:`save_state`
    state_type : the NamedTuple class of the state
    fmt : expected format tag (an :class:`~dbn.errors.InputError` otherwise)
    check : called with the header before the arrays are read (raise to refuse)

    Returns
    -------
    ``state_type`` with jax arrays of the stored dtypes (float64 kept as float64).
    """
    with np.load(path, allow_pickle=False) as f:
        if "__header__" not in f.files:
            raise InputError(f"{path}: not a saved filter state (no header)")
        header = json.loads(bytes(f["__header__"]).decode())
        if header.get("format") != fmt:
            raise InputError(f"{path}: format {header.get('format')!r}, expected {fmt!r}")
        missing = [n for n in state_type._fields if n not in f.files]
        if missing:
            raise InputError(f"{path}: missing state fields {missing}")
        if check is not None:
            check(header)
        with jax.enable_x64(True):  # keep the stored precision
            return state_type(*(jnp.asarray(f[name]) for name in state_type._fields))
