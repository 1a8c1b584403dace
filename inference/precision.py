"""Floating-point precision of the engines, chosen per call and never globally.

No module of the library changes jax's global configuration (``jax_enable_x64``) at
import. jax computes in float32 unless 64-bit mode is on, so an engine that promises
float64 (the filters, by default: seed 002's weights underflow in float32 over long runs)
enters :func:`precision_scope` around its own work: a thread-local
``jax.enable_x64(True)`` context that ends when the engine returns. A caller that asks for
``float32`` gets plain float32 computation and no context at all.

Usage::

    with precision_scope(dtype):
        x = jnp.zeros(3, dtype)  # float64 inside when dtype is float64

    step = scoped(jnp.float64)(step)  # the same, around every call of ``step``
"""

from __future__ import annotations

import contextlib
import functools
from collections.abc import Callable
from typing import Any, TypeVar

import jax
import numpy as np

__all__ = ["honours_dtype", "is_64bit", "precision_scope", "scoped"]

F = TypeVar("F", bound=Callable[..., Any])


def is_64bit(dtype: Any) -> bool:
    """Whether ``dtype`` (numpy or jax dtype, type or name) is a 64-bit float or int."""
    if dtype is None:
        return False
    return np.dtype(dtype).itemsize == 8 and np.dtype(dtype).kind in "fiuc"


def precision_scope(dtype: Any) -> contextlib.AbstractContextManager:
    """A context in which jax honours ``dtype``: 64-bit mode for 64-bit dtypes, else none.

    Parameters
    ----------
    dtype : dtype-like or None
        ``jnp.float64`` (or any 64-bit dtype) enters ``jax.enable_x64(True)``; ``float32``
        or ``None`` enters nothing (jax's current mode is kept).

    Returns
    -------
    context manager
    """
    return jax.enable_x64(True) if is_64bit(dtype) else contextlib.nullcontext()


def scoped(dtype: Any) -> Callable[[F], F]:
    """Decorator: run the function inside :func:`precision_scope` of ``dtype``."""

    def wrap(fn: F) -> F:
        if not is_64bit(dtype):
            return fn

        @functools.wraps(fn)
        def inner(*args, **kwargs):
            with precision_scope(dtype):
                return fn(*args, **kwargs)

        return inner  # type: ignore[return-value]

    return wrap


def honours_dtype(fn: F) -> F:
    """Decorator: run ``fn`` inside :func:`precision_scope` of its own ``dtype`` argument.

    For entry points with a ``dtype`` parameter (default included): a call with
    ``dtype=jnp.float64`` computes in float64 whatever jax's global mode.
    """
    import inspect

    sig = inspect.signature(fn)
    if "dtype" not in sig.parameters:
        raise TypeError(f"{fn.__qualname__} has no dtype parameter")

    @functools.wraps(fn)
    def inner(*args, **kwargs):
        bound = sig.bind(*args, **kwargs)
        bound.apply_defaults()
        with precision_scope(bound.arguments["dtype"]):
            return fn(*args, **kwargs)

    return inner  # type: ignore[return-value]
