"""Saving and loading a filter's belief (a NamedTuple of arrays) without pickle.

A thin layer over :mod:`inference.checkpoint`: an ``.npz`` holding every field of the
state plus a versioned, checksummed JSON header (a ``format`` tag, the configuration the
state was saved under, and whatever the caller adds), so that a run resumed from a
loaded state continues bit-identically, and a damaged, foreign or mismatched file is a
:class:`~dbn.errors.CheckpointError`.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import jax
import jax.numpy as jnp

from dbn.errors import CheckpointError, DBNError
from inference.checkpoint import load_arrays, save_arrays

__all__ = ["save_state", "load_state"]


def save_state(
    path, state, fmt: str, header: dict | None = None, config: Any = None, neg_inf=()
) -> None:
    """Write ``state`` (a NamedTuple of arrays) and a JSON header to ``path`` (.npz).

    Parameters
    ----------
    path : file name or file object
    state : NamedTuple whose fields are arrays
    fmt : format tag stored in the header and checked by :func:`load_state`
    header : extra JSON-serialisable entries
    config : the configuration the state belongs to (checked by :func:`load_state`)
    neg_inf : fields where -inf is a legal value (see :func:`~inference.checkpoint.save_arrays`)
    """
    arrays = {f: getattr(state, f) for f in state._fields}
    save_arrays(path, arrays, fmt, config=config, extra=header, neg_inf=neg_inf)


def load_state(
    path,
    state_type: type,
    fmt: str,
    check: Callable[[dict], None] | None = None,
    config: Any = None,
    neg_inf=(),
) -> Any:
    """Read a state written by :func:`save_state`.

    Parameters
    ----------
    path : file written by :func:`save_state`
    state_type : the NamedTuple class of the state
    fmt : expected format tag
    check : called with the header after the file is verified (raise to refuse; any
        non-library exception it raises becomes a :class:`~dbn.errors.CheckpointError`)
    config : this loader's configuration; must equal the one saved
    neg_inf : fields where -inf is a legal value

    Returns
    -------
    ``state_type`` with jax arrays of the stored dtypes (float64 kept as float64).

    Raises
    ------
    CheckpointError
        Naming the file (see :func:`inference.checkpoint.load_arrays`).
    """
    arrays, header = load_arrays(path, fmt, state_type._fields, config=config, neg_inf=neg_inf)
    if check is not None:
        try:
            check(header)
        except DBNError:
            raise
        except (KeyError, TypeError, ValueError) as exc:
            raise CheckpointError(path, f"header does not fit this loader ({exc!r})") from None
    with jax.enable_x64(True):  # keep the stored precision
        return state_type(*(jnp.asarray(arrays[name]) for name in state_type._fields))
