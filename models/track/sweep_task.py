"""Sweep tasks that run ``dbntrack track`` (:func:`track_task`) or ``dbntrack fit``
(:func:`fit_task`) on your own files, one run per grid point.

In a sweep configuration (:func:`models.experiments.load_sweep`)::

    task = "models.track.sweep_task:track_task"
    trackers = ["jorge"]                             # the runner (dbntrack list)
    data = ["caviar/ms3ggt.xml.gz --truth caviar/ms3ggt.xml.gz",
            "'my video.xml' --truth 'my video.xml'"]
    seeds = [0, 1, 2]
    [params]
    "network.max_gap_frames" = [30, 45]              # a dotted name: a field of an object
    "labels.max_group_size" = [5, 6]

each point is the command ``dbntrack track TRACKER DATA --seed SEED --config PARAMS``:
``data`` is the rest of that command line (the inputs and, optionally, ``--truth FILE``
and ``--keep DIR``; shell quoting), the seed is the point's own (0 to 2**32 - 1, as
``--seed``: the grid's seed 3 is ``--seed 3``), and the parameters are the config, where
a dotted name sets a field of a config object (``"network.max_gap_frames" = 45`` is
``{"network": {"max_gap_frames": 45}}``). A relative path is relative to the worker's
folder (a local cluster's is the sweep's). The runner checks the config as ``dbntrack
track`` does: a key it does not read fails that point, with the error in its record. The
task keeps the run's summary (``parameters``, ``metrics`` where ``--truth`` is given,
``timings_s``, ``outputs``); the output files go to a temporary folder, removed after the
run, or with ``--keep DIR`` to ``DIR/POINT_ID`` (the record's ``id``; the record's
``outdir`` names it).
"""

from __future__ import annotations

import argparse
import contextlib
import copy
import io
import json
import shlex
import tempfile
from collections.abc import Iterable
from pathlib import Path
from typing import Any, NamedTuple

from dbn.errors import ConfigError, InputError

__all__ = ["track_task", "fit_task", "nest_params", "data_arguments", "fit_arguments", "FitData"]

_KEPT = ("parameters", "metrics", "timings_s", "outputs")
_KEPT_FIT = (*_KEPT, "files")


def track_task(point) -> dict[str, Any]:
    """Run ``dbntrack track`` for one :class:`~models.experiments.GridPoint` (module
    docstring); returns the parts :data:`_KEPT` of its summary that it has, as
    ``summary.json`` holds them (NaN as null).

    Raises
    ------
    InputError
        ``data`` that is not a command line of inputs (an option other than ``--truth``,
        no input), a seed outside 0 .. 2**32 - 1, or parameters that clash; and any error
        of the run itself (bad files, a :class:`~dbn.errors.ConfigError` naming the key).
    """
    from models.commands import track

    inputs, truth, keep = data_arguments(point.data)
    return _run(track, point, keep, _KEPT, inputs=inputs, truth=truth, method=None)


def _run(command, point, keep: str | None, kept: tuple, **fields) -> dict[str, Any]:
    """Run the CLI's ``command`` (:func:`models.commands.track` or ``fit``) for ``point``
    with ``fields`` of its command line: the config from the point's parameters, in a
    temporary file; the outputs in a temporary folder, or ``keep/POINT_ID``. Returns the
    summary's ``kept`` parts (NaN as null), and ``outdir`` where kept."""
    from models.track.context import clean

    if not 0 <= point.seed < 2**32:
        raise InputError(f"seed {point.seed}: dbntrack {command.__name__} takes 0 to 2**32 - 1")
    config = nest_params(point.params)
    with tempfile.TemporaryDirectory(prefix="dbntrack-sweep-") as tmp:
        cfg = Path(tmp) / "config.json"
        cfg.write_text(json.dumps(config))
        out = Path(tmp) / "out" if keep is None else Path(keep) / point.id
        args = argparse.Namespace(name=point.tracker, outdir=str(out), seed=point.seed,
                                  config=str(cfg), quiet=True, **fields)  # fmt: skip
        with contextlib.redirect_stdout(io.StringIO()):  # the CLI's report
            summary = command(args)
    extra = {} if keep is None else {"outdir": str(out.resolve())}
    return clean({**{k: summary[k] for k in kept if k in summary}, **extra})  # NaN -> None


def data_arguments(data: str) -> tuple[list[str], str | None, str | None]:
    """``(inputs, truth, keep)`` of a point's ``data``: a ``dbntrack track`` command line
    after the tracker's name, without ``-o``, ``--seed`` and ``--config`` (the sweep's
    own), with ``--keep DIR`` where the outputs are to be kept (``None`` where not given).

    Raises
    ------
    InputError
        Quoting that does not close, an option other than ``--truth FILE`` and ``--keep
        DIR``, either twice or without its value, or no input.
    """
    try:
        words = shlex.split(data)
    except ValueError as exc:
        raise InputError(f"data {data!r}: {exc}") from None
    inputs, options = [], {"--truth": None, "--keep": None}
    it = iter(words)
    for w in it:
        if w in options:
            if options[w] is not None:
                raise InputError(f"data {data!r}: {w} given twice")
            options[w] = next(it, None)
            if options[w] is None:
                what = "a file" if w == "--truth" else "a folder"
                raise InputError(f"data {data!r}: {w} needs {what}")
        elif w.startswith("-") and w != "-":
            raise InputError(f"data {data!r}: option {w!r}: data holds the inputs, --truth "
                             "FILE and --keep DIR only (the sweep sets -o, --seed and "
                             "--config)")  # fmt: skip
        else:
            inputs.append(w)
    if not inputs:
        raise InputError(f"data {data!r}: no input file")
    return inputs, options["--truth"], options["--keep"]


def fit_task(point) -> dict[str, Any]:
    """Run ``dbntrack fit`` for one :class:`~models.experiments.GridPoint`: ``data`` is the
    rest of a fit command line, ``TRAIN... [--validate HELD...] [--seeds N]
    [--prior-strength LAMBDA[,LAMBDA...]] [--folds K [--fold-by PATTERN]]`` (and ``--keep
    DIR`` to keep each point's ``config.json`` in ``DIR/POINT_ID``), the seed is ``--seed``
    (the first of a box file's SIMULATED stroke sets), and the parameters are the config:
    the settings the fit keeps (dotted names as for :func:`track_task`). The record keeps
    the summary's ``parameters``, ``metrics`` (the training and held-out errors of the
    config's and the fitted network, over all strokes and those of three and more people),
    ``files``, ``timings_s`` and ``outputs``.

    Settings chosen by the held-out error have seen the held-out files: score the chosen
    ones on files that took no part before quoting an error, or choose by the
    cross-validation error over the training files (``--folds K`` in ``data``: the
    metric ``error_cv_fitted``), which leaves the held-out files out of the choice.

    Raises
    ------
    InputError
        ``data`` that is not a fit command line (:func:`fit_arguments`), a seed outside
        0 .. 2**32 - 1; and any error of the fit itself.
    """
    from models.commands import fit

    d = fit_arguments(point.data)
    return _run(fit, point, d.keep, _KEPT_FIT, train=d.train, validate=d.validate,
                seeds=d.seeds, prior_strength=d.prior_strength, folds=d.folds,
                fold_by=d.fold_by)


class _DataParser(argparse.ArgumentParser):
    """An argument parser whose errors are :class:`InputError` (argparse's own exit the
    process; a sweep point fails in its record instead)."""

    def error(self, message: str):  # type: ignore[override]
        raise InputError(message)


class FitData(NamedTuple):
    """A :func:`fit_task` point's ``data`` read (:func:`fit_arguments`); ``keep`` None
    where the outputs are not kept."""

    train: list[str]
    validate: list[str]
    seeds: int
    prior_strength: tuple[float, ...]
    folds: int
    fold_by: str | None
    keep: str | None


def fit_arguments(data: str) -> FitData:
    """A :func:`fit_task` point's ``data``: a ``dbntrack fit`` command line after the
    tracker's name, without ``-o``, ``--seed`` and ``--config`` (the sweep's own), with
    ``--keep DIR`` where the outputs are kept.

    Raises
    ------
    InputError
        Quoting that does not close, an option other than ``--validate``, ``--seeds``,
        ``--prior-strength``, ``--folds``, ``--fold-by`` and ``--keep``, a value missing or
        not valid, no training file.
    """
    from models.commands import prior_strengths

    parser = _DataParser(prog="data", add_help=False, allow_abbrev=False)
    parser.add_argument("train", nargs="+")
    parser.add_argument("--validate", nargs="+", default=[])
    parser.add_argument("--seeds", type=int, default=1)
    parser.add_argument("--prior-strength", type=prior_strengths, default=(0.0,))
    parser.add_argument("--folds", type=int, default=0)
    parser.add_argument("--fold-by")
    parser.add_argument("--keep")
    try:
        words = shlex.split(data)
    except ValueError as exc:
        raise InputError(f"data {data!r}: {exc}") from None
    own = [w for w in words if w.split("=")[0] in ("-o", "--outdir", "--seed", "--config")]
    if own:
        raise InputError(f"data {data!r}: option {own[0]!r}: the sweep sets -o, --seed and "
                         "--config")  # fmt: skip
    try:
        args = parser.parse_args(words)
    except InputError as exc:
        raise InputError(f"data {data!r}: {exc} (a fit command line: TRAIN... [--validate "
                         "HELD...] [--seeds N] [--prior-strength L[,L...]] [--folds K] "
                         "[--fold-by PATTERN] [--keep DIR])") from None
    if args.seeds < 1:
        raise InputError(f"data {data!r}: --seeds {args.seeds}: at least 1")
    if args.folds == 1 or args.folds < 0:
        raise InputError(f"data {data!r}: --folds {args.folds}: at least 2 (0: none)")
    return FitData(args.train, args.validate, args.seeds, args.prior_strength, args.folds,
                   args.fold_by, args.keep)


def nest_params(params: Iterable[tuple[str, Any]]) -> dict[str, Any]:
    """A config from ``(name, value)`` pairs, a dotted name setting a field of a nested
    object: ``[("network.max_gap_frames", 45), ("fps", 7)]`` gives ``{"network":
    {"max_gap_frames": 45}, "fps": 7}``. Values are copied (a grid's values are shared by
    its points).

    Raises
    ------
    ConfigError
        An empty part of a name, or a name that is also a prefix of another
        (``"network"`` beside ``"network.max_gap_frames"``: a value and an object).
    """
    pairs = [(str(name), value) for name, value in params]
    names = {name for name, _ in pairs}
    out: dict[str, Any] = {}
    for name, value in pairs:
        parts = name.split(".")
        if not all(parts):
            raise ConfigError(f"parameter {name!r}: an empty part")
        clash = [".".join(parts[:i]) for i in range(1, len(parts)) if ".".join(parts[:i]) in names]
        if clash:
            raise ConfigError(f"parameter {name!r}: {clash[0]!r} is also given a value")
        node = out
        for part in parts[:-1]:
            node = node.setdefault(part, {})
        node[parts[-1]] = copy.deepcopy(value)
    return out
