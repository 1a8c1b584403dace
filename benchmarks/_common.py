"""Helpers shared by the benchmarks: timing, JSON conversion, progress on stderr."""

from __future__ import annotations

import contextlib
import math
import sys
import time
from collections.abc import Callable
from typing import Any

import numpy as np

__all__ = ["best_time", "median_time", "log", "to_jsonable", "dask_mapper"]


def log(*args: object) -> None:
    """Progress message on standard error (the last stdout line is the JSON)."""
    print(*args, file=sys.stderr, flush=True)


def best_time(fn: Callable[[], Any], repeat: int = 5, number: int = 1) -> float:
    """Smallest wall time in seconds of ``number`` calls of ``fn`` over ``repeat`` tries."""
    best = math.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        for _ in range(number):
            fn()
        best = min(best, (time.perf_counter() - t0) / number)
    return best


def median_time(fn: Callable[[], Any], repeat: int = 5, number: int = 1) -> float:
    """Median wall time in seconds of ``number`` calls of ``fn`` over ``repeat`` tries."""
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        for _ in range(number):
            fn()
        times.append((time.perf_counter() - t0) / number)
    return float(np.median(times))


def to_jsonable(obj: Any) -> Any:
    """Turn numpy scalars/arrays and non-finite floats into plain JSON values.

    NaN and infinities become ``None`` (JSON has no such numbers).
    """
    if isinstance(obj, dict):
        return {str(k): to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [to_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return to_jsonable(obj.tolist())
    if isinstance(obj, np.bool_ | bool):
        return bool(obj)
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, np.floating | float):
        value = float(obj)
        return value if math.isfinite(value) else None
    if hasattr(obj, "item") and callable(obj.item):  # jax scalars
        return to_jsonable(obj.item())
    return obj


@contextlib.contextmanager
def dask_mapper(address: str = "local"):
    """``mapper(fn, items) -> list`` running one Dask task per item, results in order.

    ``address="local"`` starts a local cluster (one worker per core) for the duration of
    the context; otherwise it connects to the scheduler at ``address``. Benchmarks whose
    ``run`` takes ``mapper`` (default the builtin serial ``map``) use it for their
    multi-seed loops: ``python -m benchmarks NAME --dask [ADDRESS]``.
    """
    from dask.distributed import Client

    from models.experiments import local_cluster

    with contextlib.ExitStack() as stack:
        if address == "local":
            client = stack.enter_context(Client(stack.enter_context(local_cluster())))
        else:
            client = stack.enter_context(Client(address))

        def mapper(fn, items):
            return client.gather(client.map(fn, list(items), pure=False))

        yield mapper
