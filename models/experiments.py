"""Sweeps over trackers x data x seeds x parameters, one Dask task per grid point.

A sweep is a *task* (a picklable function ``task(point) -> dict`` of JSON-able results)
and a *grid* (a list of :class:`GridPoint`). :func:`run_grid` runs every point as one
Dask task on a ``dask.distributed`` cluster, appends each result to a JSON-lines file as
soon as it finishes, and returns the results in grid order.

- Without a client it starts a :class:`dask.distributed.LocalCluster` sized to the
  machine (one single-threaded worker process per core); with a ``Client`` (or a
  scheduler address) it runs on that cluster: the address is the only change between a
  laptop and a cluster.
- Nothing is lost on interruption: each finished point is on disk; ``resume=True`` skips
  the points already recorded as ``ok``.
- A task that raises is recorded with its error (``status: "error"``); the others go on.
- Reproducible: a point's random seed is derived from the point itself
  (:attr:`GridPoint.rng_seed`), so results do not depend on the number of workers, the
  order of completion, or whether the sweep ran serially (``serial=True``).
- A worker that dies is restarted by its nanny and its tasks are rescheduled by Dask.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import os
import sys
import time
import traceback
import uuid
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from dbn.checks import check_count, check_size, check_type
from dbn.errors import FileFormatError, InputError

__all__ = [
    "GridPoint",
    "make_grid",
    "run_grid",
    "read_results",
    "local_cluster",
    "load_sweep",
    "check_params",
    "example_task",
]

Task = Callable[["GridPoint"], Mapping[str, Any]]


@dataclass(frozen=True)
class GridPoint:
    """One point of a sweep: which tracker, on which data, with which seed and parameters.

    Attributes
    ----------
    tracker : str
        A registry name (or any label the task understands).
    data : str
        A data source the task understands (a file, a dataset name, ``"simulated"``).
    seed : int
        The user-facing replicate number.
    params : tuple of (str, value) pairs
        Parameters, sorted by name (JSON-able values).
    """

    tracker: str
    data: str = "simulated"
    seed: int = 0
    params: tuple[tuple[str, Any], ...] = field(default=())

    def as_dict(self) -> dict[str, Any]:
        """Plain-JSON form: ``{"tracker", "data", "seed", "params": {...}}``."""
        return {
            "tracker": self.tracker,
            "data": self.data,
            "seed": self.seed,
            "params": dict(self.params),
        }

    @property
    def id(self) -> str:
        """Stable identifier (16 hex digits of the SHA-256 of the canonical JSON)."""
        text = json.dumps(self.as_dict(), sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(text.encode()).hexdigest()[:16]

    @property
    def rng_seed(self) -> int:
        """A 63-bit seed derived from the whole point: same point, same seed, anywhere."""
        return int(self.id, 16) & (2**63 - 1)

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> GridPoint:
        return cls(
            str(d["tracker"]),
            str(d.get("data", "simulated")),
            int(d.get("seed", 0)),
            tuple(sorted(dict(d.get("params", {})).items())),
        )


def make_grid(
    trackers: Sequence[str],
    data: Sequence[str] = ("simulated",),
    seeds: Iterable[int] = (0,),
    params: Mapping[str, Sequence[Any]] | None = None,
) -> list[GridPoint]:
    """The cartesian product trackers x data x seeds x every parameter's values.

    ``params={"num_particles": [100, 1000]}`` gives two points per (tracker, data, seed).

    Raises
    ------
    InputError
        ``trackers`` or ``data`` not a non-empty list of names (a string was split into
        its letters), ``seeds`` not integers >= 0 (text raised Python's ValueError, 1.5
        was truncated, True read as 1, -1 failed only inside a worker), or a parameter
        that is not a non-empty list of values.
    """
    for field_name, names in (("trackers", trackers), ("data", data)):
        if (isinstance(names, str) or not isinstance(names, Sequence) or not names
                or not all(isinstance(n, str) for n in names)):  # fmt: skip
            raise InputError(f"{field_name} must be a non-empty list of names, got {names!r}")
    seeds = list(seeds) if isinstance(seeds, Iterable) and not isinstance(seeds, str) else None
    if not seeds:
        raise InputError("seeds must be a non-empty list of integers >= 0")
    seeds = [check_size("seeds: each seed", s) for s in seeds]
    params = dict(params or {})
    for name, values in params.items():
        if isinstance(values, Mapping):  # TOML reads an unquoted dotted name as a table
            raise InputError(f"grid parameter {name!r} is a table, not a list of values; a "
                             f"name with dots is quoted: \"{name}.FIELD\" = [...]")  # fmt: skip
        if isinstance(values, str | bytes) or not isinstance(values, Sequence) or not values:
            raise InputError(f"grid parameter {name!r} must be a non-empty list of values")
    names = sorted(params)
    combos = list(itertools.product(*(params[n] for n in names))) or [()]
    return [
        GridPoint(t, d, s, tuple(zip(names, combo)))
        for t, d, s, combo in itertools.product(trackers, data, seeds, combos)
    ]


def _execute(task: Task, point: GridPoint) -> dict[str, Any]:
    """Run one point, catching its error: the record written to the results file."""
    t0 = time.perf_counter()
    try:
        result = dict(task(point))
        json.dumps(result)  # must be JSON-able: fail here, inside the record
        status, error = "ok", None
    except Exception as exc:  # noqa: BLE001 - a failing point is recorded, not fatal
        result, status = None, "error"
        error = f"{type(exc).__name__}: {exc}\n" + "".join(traceback.format_tb(exc.__traceback__))
    return {
        "id": point.id,
        "point": point.as_dict(),
        "status": status,
        "result": result,
        "error": error,
        "wall_s": round(time.perf_counter() - t0, 6),
    }


def read_results(path: str | os.PathLike) -> list[dict[str, Any]]:
    """Every record of a results file (a truncated last line, from a crash, is skipped).

    Raises
    ------
    FileFormatError
        Naming the file and the line: unreadable or not UTF-8, a line (other than the
        last) that is not JSON, a record that is not an object with a string ``id`` and a
        ``status`` of ``ok`` or ``error`` (and, if any, a ``point`` object).
    """
    p = Path(path)
    if not p.exists():
        return []
    try:
        lines = p.read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError) as exc:
        raise FileFormatError(p, f"unreadable results file ({exc})") from None
    records = []
    for i, line in enumerate(lines, 1):
        if not line.strip():
            continue
        try:
            record = json.loads(line)
        except (json.JSONDecodeError, RecursionError):
            if i == len(lines):  # interrupted while writing the last line
                continue
            raise FileFormatError(p, f"line {i} is not a JSON record", i) from None
        if not (
            isinstance(record, dict)
            and isinstance(record.get("id"), str)
            and record.get("status") in ("ok", "error")
            and isinstance(record.get("point", {}), dict)
        ):
            raise FileFormatError(p, f"line {i} is not a result record (id, status)", i)
        records.append(record)
    return records


def local_cluster(n_workers: int | None = None):
    """A ``LocalCluster`` of single-threaded worker processes (one per core by default).

    BLAS, OpenMP and XLA are limited to one thread per worker, so ``n`` workers use ``n``
    cores and a CPU-bound sweep scales with them.

    Raises
    ------
    InputError
        ``n_workers`` given but not an int >= 1 (0 ran one per core, -1 hung).
    """
    from dask.distributed import LocalCluster

    n = (os.cpu_count() or 1) if n_workers is None else check_count("n_workers", n_workers)
    env = {k: "1" for k in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")}
    env["XLA_FLAGS"] = "--xla_cpu_multi_thread_eigen=false intra_op_parallelism_threads=1"
    return LocalCluster(
        n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None, env=env
    )


def _progress(total: int, enabled: bool):
    from inference.progress import progress_bar

    return progress_bar(total=total, desc="sweep", unit="task", disable=not enabled or None)


def run_grid(
    task: Task,
    grid: Sequence[GridPoint],
    *,
    client: Any = None,
    out: str | os.PathLike | None = None,
    resume: bool = False,
    serial: bool = False,
    n_workers: int | None = None,
    progress: bool = True,
) -> list[dict[str, Any]]:
    """Run ``task`` on every point of ``grid``; one Dask task per point.

    Parameters
    ----------
    task : callable ``GridPoint -> dict``
        A picklable (module-level) function; its dict must be JSON-able.
    grid : sequence of GridPoint
        Duplicate points are rejected, and so are parameters the task says it does not
        read (:func:`check_params`).
    client : dask.distributed.Client or str, optional
        A client, or a scheduler address (``"tcp://host:8786"``); default a new
        :func:`local_cluster` closed at the end.
    out : path, optional
        JSON-lines results file, appended to as tasks finish.
    resume : bool
        Skip points recorded as ``ok`` in ``out``; their records are returned as read.
    serial : bool
        Run in this process, one point after the other (no Dask): the reference a
        distributed run must equal.
    n_workers : int, optional
        Workers of the local cluster (default: one per core).
    progress : bool
        A tqdm progress bar (quiet when standard error is not a terminal).

    Returns
    -------
    list of dict
        One record per grid point, in grid order: ``id``, ``point``, ``status`` (``"ok"``
        or ``"error"``), ``result``, ``error``, ``wall_s``.
    """
    if not callable(task):  # each point would have failed and been recorded as an error
        raise InputError(f"task must be a function GridPoint -> dict, got {task!r:.60}")
    if isinstance(grid, GridPoint) or not isinstance(grid, Iterable):
        raise InputError(f"grid must be a list of GridPoint (make_grid), got {grid!r:.60}")
    grid = list(grid)
    for i, p in enumerate(grid):
        check_type(f"grid[{i}]", p, GridPoint, InputError)
    ids = [p.id for p in grid]
    if len(set(ids)) != len(ids):
        raise InputError("grid has duplicate points (same tracker, data, seed and params)")
    if resume and out is None:
        raise InputError("resume=True needs the results file (out=...)")
    check_params(task, grid)
    if n_workers is not None:  # before the results file is opened
        check_count("n_workers", n_workers)
    # the points already done (resume) are returned as recorded; the rest are run
    records = {}
    if resume:
        records = {r["id"]: r for r in read_results(out) if r.get("status") == "ok"}
    todo = [p for p in grid if p.id not in records]
    try:
        sink = open(out, "a") if out is not None else None  # noqa: SIM115 - closed below
    except OSError as exc:  # a folder, a read-only place, ...
        raise InputError(f"results file {out}: cannot write it ({exc.strerror or exc})") from None
    bar = _progress(len(todo), progress and sys.stderr.isatty())
    try:
        for rec in _records(task, todo, client, serial, n_workers):
            records[rec["id"]] = rec
            if sink is not None:
                sink.write(json.dumps(rec, sort_keys=True) + "\n")
                sink.flush()
            bar.update(1)
    finally:
        bar.close()
        if sink is not None:
            sink.close()
    return [records[i] for i in ids]


def check_params(task: Task, grid: Sequence[GridPoint]) -> None:
    """Refuse grid parameters that ``task`` does not read, where it says which it reads.

    A task declares them as a ``params`` attribute (a collection of names; empty: none);
    a task without one is taken at its word for any. Without this a misspelt name (``N``
    for ``n``) ran every point with the default, silently.

    Raises
    ------
    InputError
        Naming the unknown parameters and the ones the task reads.
    """
    accepted = getattr(task, "params", None)
    if accepted is None:
        return
    unknown = sorted({name for p in grid for name, _ in p.params} - set(accepted))
    if unknown:
        reads = ", ".join(sorted(accepted)) or "none"
        name = getattr(task, "__qualname__", repr(task))
        raise InputError(f"parameter(s) {unknown} are not read by {name} (it reads: {reads})")


def _records(task: Task, todo: list[GridPoint], client: Any, serial: bool, n_workers):
    """Yield each point's record as it finishes (serially, or from Dask as completed)."""
    if serial or not todo:
        for p in todo:
            yield _execute(task, p)
        return
    from dask.distributed import Client, as_completed

    own_cluster = own_client = None
    if client is None:
        own_cluster = local_cluster(n_workers)
        client = own_client = Client(own_cluster)
    elif isinstance(client, str):
        try:
            client = own_client = Client(client)
        except (ValueError, OSError, TimeoutError) as exc:  # a bad address, no scheduler
            raise InputError(f"client {client!r}: cannot connect to a Dask scheduler there "
                             f"({exc}); give an address like 'tcp://host:8786'") from None
    run = uuid.uuid4().hex[:8]  # fresh task keys: a re-run is run again, not fetched
    try:
        futures = [
            client.submit(_execute, task, p, key=f"point-{p.id}-{run}", pure=False) for p in todo
        ]
        for fut in as_completed(futures):
            yield fut.result()
    finally:
        if own_client is not None:
            own_client.close()
        if own_cluster is not None:
            own_cluster.close()


def example_task(point: GridPoint) -> dict[str, Any]:
    """A sweep task over the tracker registry: run ``point.tracker`` on its tiny SIMULATED
    example (``models.get(name).example``) through the protocol's ``run``.

    The jax key is ``jax.random.key(point.rng_seed % 2**32)``. It reads no ``point.params``
    (the example fixes its own settings: ``example_task.params`` is empty, so a grid that
    gives some is refused). Returns the number of steps and the sum of the tracker's
    one-step scores (its ``score_field``; ``None`` where it has none).
    """
    import jax
    import numpy as np

    import models

    key = jax.random.key(point.rng_seed % 2**32)
    k_example, k_run = jax.random.split(key)
    ex = models.get(point.tracker).example(k_example)
    _, infos = ex.tracker.run(k_run, ex.observations)
    field_name = ex.tracker.score_field
    score = None
    if field_name is not None:
        score = float(sum(np.sum(np.asarray(getattr(info, field_name))) for info in infos))
    return {"steps": len(infos), "score_field": field_name, "total_score": score}


example_task.params = ()  # type: ignore[attr-defined]


SWEEP_FIELDS = frozenset({"task", "trackers", "data", "seeds", "params"})
"""The fields of a sweep configuration (:func:`load_sweep`)."""


def _seeds(seeds: Any) -> list[int]:
    """The ``seeds`` field: a list of ints or ``{start = a, stop = b}``."""
    if isinstance(seeds, dict):
        if set(seeds) - {"start", "stop"}:  # {begin = 0, stop = 4} would start at 0 silently
            raise InputError(f"field 'seeds': keys {sorted(set(seeds) - {'start', 'stop'})} "
                             "are not start or stop")
        start, stop = seeds.get("start", 0), seeds.get("stop")
        if not all(isinstance(v, int) and not isinstance(v, bool) for v in (start, stop)):
            raise InputError(f"field 'seeds': start/stop must be integers, got {seeds!r}")
        seeds = list(range(start, stop))
    elif not isinstance(seeds, list) or not all(
        isinstance(v, int) and not isinstance(v, bool) for v in seeds
    ):
        raise InputError("field 'seeds' must be a list of integers or {start, stop}")
    if not seeds:
        raise InputError("field 'seeds' gives no seed (an empty list, or stop <= start)")
    return seeds


def load_sweep(path: str | os.PathLike) -> tuple[Task, list[GridPoint]]:
    """Read a sweep configuration (TOML): the task and its grid.

    Format::

        task = "benchmarks.scale_out:chain_task"   # module:function, GridPoint -> dict
        trackers = ["chains"]                       # registry names (or task labels)
        data = ["simulated"]                        # optional, default ["simulated"]
        seeds = [0, 1, 2, 3]                        # or {start = 0, stop = 8}
        [params]                                    # optional: each a list of values
        n = [9, 10]                                 # (names the task reads: check_params)

    Raises
    ------
    InputError
        Naming the file and the field, for a missing or malformed entry.
    """
    import importlib
    import tomllib

    p = Path(path)
    try:
        cfg = tomllib.loads(p.read_text(encoding="utf-8-sig"))  # a leading BOM dropped
    except FileNotFoundError:
        raise FileFormatError(p, "no such sweep configuration") from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError, OSError) as exc:
        raise FileFormatError(p, f"not a TOML file: {exc}") from None
    unknown = sorted(set(cfg) - SWEEP_FIELDS)
    if unknown:  # a misspelt field (``seed``, ``[param]``) would run the defaults silently
        raise FileFormatError(
            p, f"unknown field(s) {unknown}; the fields are {sorted(SWEEP_FIELDS)}"
        )
    spec = cfg.get("task")
    if not isinstance(spec, str) or spec.count(":") != 1:
        raise FileFormatError(p, f"field 'task' must be 'module:function', got {spec!r}")
    module, name = spec.split(":")
    try:
        task = getattr(importlib.import_module(module), name)
    except Exception as exc:  # noqa: BLE001 - any import failure is a bad field
        raise FileFormatError(p, f"field 'task': cannot load {spec!r} ({exc})") from None
    if not callable(task):
        raise FileFormatError(p, f"field 'task': {spec!r} is not a function")
    for field_name in ("trackers", "data"):
        value = cfg.get(field_name, ["simulated"] if field_name == "data" else None)
        if not isinstance(value, list) or not value:
            raise FileFormatError(p, f"field {field_name!r} must be a non-empty list")
        if not all(isinstance(v, str) for v in value):
            raise FileFormatError(p, f"field {field_name!r} must be a list of names")
    if not isinstance(cfg.get("params", {}), dict):
        raise FileFormatError(p, "field 'params' must be a table ([params], one list per name)")
    try:
        seeds = _seeds(cfg.get("seeds", [0]))
        grid = make_grid(cfg["trackers"], cfg.get("data", ["simulated"]), seeds, cfg.get("params"))
        check_params(task, grid)
    except (InputError, TypeError, ValueError, KeyError, AttributeError) as exc:
        raise FileFormatError(p, str(exc)) from None
    return task, grid


def sweep_main(config: str, out: str, scheduler: str | None, resume: bool, workers: int | None):
    """``dbntrack sweep``: run a configuration, print a one-line summary, return 0/1."""
    task, grid = load_sweep(config)
    records = run_grid(task, grid, client=scheduler, out=out, resume=resume, n_workers=workers)
    failed = [r for r in records if r["status"] != "ok"]
    print(f"{len(records) - len(failed)} of {len(records)} points ok; results in {out}")
    for r in failed:
        print(f"  failed: {r['point']}: {r['error'].splitlines()[0]}", file=sys.stderr)
    return 1 if failed else 0
