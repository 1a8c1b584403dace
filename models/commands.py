"""The sub-commands of ``dbntrack``: ``list``, ``track``, ``fit``, ``eval``, ``demo``,
``sweep``.

``track``, ``fit`` and ``eval`` go through :mod:`models.track` (one runner per tracker, each
built on the registry :func:`models.get` and the protocol of :mod:`models.protocol`). Bad input
(any :mod:`dbn.errors` class, a missing file) ends the command with exit status 2 and one
line on stderr naming the file and the line.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from collections.abc import Callable
from pathlib import Path

__all__ = ["build_parser", "dispatch", "list_trackers", "track", "fit", "evaluate",
           "prior_strengths"]

_EPILOG = "Input formats: docs/formats.md. Example files: tests/data/."


def build_parser(demo: Callable, demo_names: list[str]) -> argparse.ArgumentParser:
    """The ``dbntrack`` argument parser (``demo`` runs the parts ``demo_names`` of
    :mod:`models.cli`)."""
    parser = argparse.ArgumentParser(
        prog="dbntrack",
        description="Tracking with dynamic Bayesian networks: run the seed trackers on your "
        "files, evaluate results, or watch the demos.",
        epilog=_EPILOG,
    )
    parser.add_argument("--data", metavar="DIR", help="real-data folder (default: "
                        "$DBNTRACK_DATA, else ../shared/data beside the checkout)")  # fmt: skip
    sub = parser.add_subparsers(dest="command", required=True)
    p = sub.add_parser("list", help="list the trackers, what they track and their inputs",
                       description="List the trackers: name, seed paper, what it tracks, "
                       "the inputs of `dbntrack track NAME`.")  # fmt: skip
    p.add_argument("--json", action="store_true", help="one JSON object per tracker")
    p = sub.add_parser(
        "track", help="run a tracker on your files", epilog=_EPILOG,
        description="Run tracker NAME on INPUT files; write results, summary.json and PNG "
        "figures into OUTDIR. `dbntrack list` shows the inputs of each tracker.",
    )  # fmt: skip
    p.add_argument("name", metavar="NAME", help="tracker (see `dbntrack list`)")
    p.add_argument("inputs", metavar="INPUT", nargs="+", help="input files or folders")
    p.add_argument("-o", "--outdir", required=True, help="output folder (created)")
    p.add_argument("--seed", type=_seed, default=0, help="seed of the run, 0 to 2**32 - 1 "
                   "(default 0)")  # fmt: skip
    p.add_argument("--config", metavar="FILE", help="JSON file of tracker options")
    p.add_argument("--truth", metavar="FILE", help="truth file: metrics go into summary.json")
    p.add_argument("--method", help="dbn only: exact (default), auto, bk, particle, rbpf")
    p.add_argument("--quiet", action="store_true", help="no progress bars")
    p = sub.add_parser(
        "fit",
        help="fit a tracker's parameters on your files "
        "(jorge, zajdel_*, localization, pathrecovery)",
        epilog=_EPILOG,
        description="Fit tracker NAME's parameters on TRAIN files whose truth you know; write "
        "OUTDIR/config.json (for `dbntrack track NAME --config`), summary.json and fit.png, with "
        "the error of the config's and the fitted parameters on the training and the held-out "
        "(--validate) files.",
    )  # fmt: skip
    p.add_argument("name", metavar="NAME", help="tracker with a fit (jorge, zajdel_adf, "
                   "zajdel_learnsearch, localization, pathrecovery)")  # fmt: skip
    p.add_argument("train", metavar="TRAIN", nargs="+", help="training files")
    p.add_argument("--validate", metavar="FILE", nargs="+", default=[],
                   help="held-out files: scored, never fitted on")  # fmt: skip
    p.add_argument("-o", "--outdir", required=True, help="output folder (created)")
    p.add_argument("--seed", type=_seed, default=0, help="first seed of the simulated parts "
                   "and the filter runs (default 0)")  # fmt: skip
    p.add_argument("--seeds", type=_positive, default=1, help="seeds SEED, SEED + 1, ... per "
                   "file: jorge's stroke sets simulated per box file, localization's and "
                   "pathrecovery's filter runs averaged (default 1)")  # fmt: skip
    p.add_argument("--config", metavar="FILE", help="JSON file of tracker options: the "
                   "settings the fit keeps")  # fmt: skip
    p.add_argument("--prior-strength", type=prior_strengths, default=None,
                   metavar="LAMBDA[,LAMBDA...]", help="pseudo-observations per parameter row "
                   "as a prior, for fits on little data (jorge: of the config's network, "
                   "default 0, the plain fit; zajdel_*: of uniform tables, default 1); several "
                   "are chosen among by --folds")  # fmt: skip
    p.add_argument("--folds", type=_int_in(2, None), default=0, metavar="K",
                   help="K-fold cross-validation over the training files, cut in the order "
                   "given (keep a recording's files together): the error of fits on the "
                   "other folds, and the prior strength with the lowest")  # fmt: skip
    p.add_argument("--fold-by", metavar="PATTERN", help="keep in one fold the training files "
                   "whose paths share the first match of this regular expression (its first "
                   "group where it has one), e.g. " r"'(\w+)_seed\d+'" " or '^.*/' (by "
                   "folder)")  # fmt: skip
    p.add_argument("--quiet", action="store_true", help="no progress bars")
    p = sub.add_parser("eval", help="score a result file against a truth file", epilog=_EPILOG,
                       description="Metrics of tracker NAME's RESULT file against TRUTH: "
                       "MOTA/IDF1 (jorge, rjmcmc3d), partition q and pairwise F1 (zajdel), "
                       "label error rate (jorge, dbn), RMSE (localization), path score "
                       "(pathrecovery).")  # fmt: skip
    p.add_argument("name", metavar="NAME")
    p.add_argument("result", metavar="RESULT")
    p.add_argument("truth", metavar="TRUTH")
    p.add_argument("--json", action="store_true", help="print the metrics as one JSON line")
    p = sub.add_parser("demo", help="run a short example of every model",
                       description="Run a short example of every model (or of some).")  # fmt: skip
    p.add_argument("--only", nargs="*", metavar="NAME",
                   help=f"run only the named parts: {', '.join(demo_names)}")  # fmt: skip
    p.set_defaults(demo=demo, demo_names=demo_names, demo_parser=p)
    p = sub.add_parser(
        "sweep", help="run a sweep (trackers x data x seeds x parameters) on Dask distributed",
        description="Each grid point of CONFIG (TOML; format in models.experiments.load_sweep, "
        "example tests/data/sweep_example.toml) is one Dask task; results are appended to OUT "
        "as they finish.",
    )  # fmt: skip
    p.add_argument("config", help="sweep configuration (TOML)")
    p.add_argument("-o", "--out", default="sweep.jsonl", help="results file (JSON lines)")
    p.add_argument("--scheduler", help="address of a running Dask scheduler (default: a "
                   "local cluster)")  # fmt: skip
    p.add_argument("--workers", type=_positive, help="local cluster size (default: one per core)")
    p.add_argument("--resume", action="store_true", help="skip points already done in OUT")
    return parser


def list_trackers(as_json: bool = False) -> None:
    """Print the registry (and the generic ``dbn`` runner): what each tracks, the files
    ``dbntrack track`` reads, what one protocol step takes and whether ``dbntrack fit``
    fits it."""
    import models
    from models.track import available, runner

    runners = set(available())
    for name in ["dbn", *models.available()]:
        if name == "dbn":
            info = {"name": "dbn", "seed_paper": "-", "tracks": "per-slice marginals of any "
                    "discrete two-slice DBN (generic engines)", "step_input": []}  # fmt: skip
        else:
            e = models.get(name)
            info = {"name": name, "seed_paper": e.seed_paper, "tracks": e.tracks,
                    "step_input": list(e.input_formats)}  # fmt: skip
        mod = runner(name) if name in runners else None
        info["track_inputs"] = list(mod.INPUTS) if mod is not None else []
        info["fit"] = hasattr(mod, "fit")  # dbntrack fit NAME
        if as_json:
            print(json.dumps(info))
            continue
        print(f"{name}\n  seed paper: {info['seed_paper']}\n  tracks: {info['tracks']}")
        files = info["track_inputs"] or ["(no file reader yet: use the Python API)"]
        print("  dbntrack track inputs: " + "\n                         ".join(files))
        for fmt in info["step_input"]:
            print(f"  protocol step input: {fmt}")
        if info["fit"]:
            print("  dbntrack fit: yes (its parameters fitted on your files)")


def track(args: argparse.Namespace) -> dict:
    """Run ``dbntrack track``; returns the summary written to ``OUTDIR/summary.json``."""
    from dbn.errors import InputError
    from models.track import runner
    from models.track.context import clean

    mod = runner(args.name)
    config = _read_config(args.config)
    if args.method:
        if args.name != "dbn":
            raise InputError(f"--method applies to dbn only, not {args.name!r}")
        config["method"] = args.method
    summary = {"tracker": args.name, "inputs": [str(Path(p).resolve()) for p in args.inputs],
               "seed": args.seed, "config": dict(config)}  # fmt: skip

    def score_truth(ctx, summary: dict) -> None:
        if args.truth:
            with ctx.timed("eval"):
                summary["truth"] = str(Path(args.truth).resolve())
                result = str(ctx.outdir / summary["outputs"][0])
                summary["metrics"] = mod.evaluate(result, args.truth)

    ctx = _run(args, summary, lambda ctx: mod.track(ctx, list(args.inputs), config), score_truth)
    print(f"{args.name}: wrote {', '.join(summary['outputs'])}, summary.json to {ctx.outdir}")
    if "metrics" in summary:
        print(json.dumps(clean(summary["metrics"])))
    return summary


def fit(args: argparse.Namespace) -> dict:
    """Run ``dbntrack fit``; returns the summary written to ``OUTDIR/summary.json``."""
    from dbn.errors import InputError
    from models.track import available, runner
    from models.track.context import clean, shown_strength

    mod = runner(args.name)
    if not hasattr(mod, "fit"):
        with_fit = [n for n in available() if hasattr(runner(n), "fit")]
        raise InputError(f"tracker {args.name!r} has no fit; trackers with one: "
                         f"{', '.join(with_fit)}")  # fmt: skip
    config = _read_config(args.config)
    strengths = list(args.prior_strength or getattr(mod, "DEFAULT_PRIOR_STRENGTH", (0.0,)))
    summary = {"tracker": args.name, "train": [str(Path(p).resolve()) for p in args.train],
               "validate": [str(Path(p).resolve()) for p in args.validate],
               "seed": args.seed, "seeds": args.seeds, "folds": args.folds,
               "fold_by": args.fold_by,
               "prior_strength": shown_strength(strengths[0]) if len(strengths) == 1
               else [shown_strength(v) for v in strengths],
               "config": dict(config)}  # fmt: skip
    ctx = _run(args, summary, lambda ctx: mod.fit(ctx, list(args.train), list(args.validate),
                                                  config, args.seeds, strengths, args.folds,
                                                  args.fold_by))
    for line in mod.fit_report(summary):
        print(line)
    if not args.validate:
        print(f"{args.name}: no --validate file: an error on the files fitted on is not a result")
    print(f"{args.name}: wrote {', '.join(summary['outputs'])}, summary.json to {ctx.outdir}")
    print(json.dumps(clean(summary["metrics"])))
    return summary


def _read_config(path: str | None) -> dict:
    """The ``--config`` JSON file's options (none without one)."""
    if not path:
        return {}
    from models.io.table import read_json_config

    return read_json_config(path)


def _run(args: argparse.Namespace, summary: dict, run: Callable, then: Callable | None = None):
    """``run(ctx)`` in a :class:`~models.track.context.RunContext` of ``args`` (outdir,
    seed, quiet), its result laid into ``summary`` (a :class:`~dbn.errors.ConfigError`
    names the ``--config`` file), then ``then(ctx, summary)``; the total time, timings and
    versions added and ``OUTDIR/summary.json`` written. Returns the context."""
    from dbn.errors import ConfigError, in_file
    from models.track.context import RunContext, versions, write_summary

    ctx = RunContext(args.name, Path(args.outdir), args.seed)
    if args.quiet:
        ctx.quiet = True
    t0 = time.perf_counter()
    try:
        summary.update(run(ctx))
    except ConfigError as exc:  # the option's key is named; name the file it came from
        raise (in_file(exc, args.config) if args.config else exc) from None
    if then is not None:
        then(ctx, summary)
    ctx.timings["total"] = round(time.perf_counter() - t0, 4)
    summary["timings_s"] = ctx.timings
    summary["versions"] = versions()
    write_summary(ctx.outdir / "summary.json", summary)
    return ctx


def evaluate(args: argparse.Namespace) -> dict:
    """Run ``dbntrack eval``; prints the metrics."""
    from models.track import runner
    from models.track.context import clean

    metrics = clean(runner(args.name).evaluate(args.result, args.truth))
    if args.json:
        print(json.dumps(metrics))
    else:
        for k, v in metrics.items():
            print(f"{k}: {v:.6g}" if isinstance(v, float) else f"{k}: {v}")
    return metrics


def _int_in(lo: int, hi: int | None):
    """An argparse type: an int in ``[lo, hi)`` (``hi`` None: no upper bound)."""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not an integer: {text!r}") from None
        if value < lo or (hi is not None and value >= hi):
            span = f">= {lo}" if hi is None else f"in {lo} .. {hi - 1}"
            raise argparse.ArgumentTypeError(f"{value} is not {span}")
        return value

    return parse


def prior_strengths(text: str) -> tuple[float, ...]:
    """An argparse type: comma-separated numbers >= 0, ``inf`` among them (the prior
    itself: the config's parameters as they are) (``--prior-strength``)."""
    values = []
    for part in text.split(","):
        try:
            value = float(part)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not a number: {part.strip()!r}") from None
        if not value >= 0:  # NaN too
            raise argparse.ArgumentTypeError(f"{part.strip()} is not a number >= 0 (or inf)")
        values.append(value)
    return tuple(values)


# --seed: numpy's generators refuse a negative seed, and some of the trackers' seed
# arithmetic overflowed C longs beyond 2**32 - 1
_seed = _int_in(0, 2**32)
# --workers: 0 ran one worker per core, -1 hung the local cluster
_positive = _int_in(1, None)


def dispatch(parser: argparse.ArgumentParser, args: argparse.Namespace) -> int:
    """Run the parsed command; bad input -> one line on stderr, exit status 2."""
    from dbn.errors import DBNError, as_memory_limit

    if args.data and not Path(args.data).expanduser().is_dir():
        parser.error(f"--data {args.data}: no such folder")
    if args.data:
        os.environ["DBNTRACK_DATA"] = str(Path(args.data).expanduser().resolve())
    try:
        if args.command == "list":
            list_trackers(args.json)
        elif args.command == "track":
            track(args)
        elif args.command == "eval":
            evaluate(args)
        elif args.command == "fit":
            fit(args)
        elif args.command == "demo":
            unknown = [p for p in args.only or [] if p not in args.demo_names]
            if unknown:  # argparse's error: usage, one line, exit status 2
                args.demo_parser.error(
                    f"unknown part(s) {', '.join(unknown)}; valid: {', '.join(args.demo_names)}"
                )
            args.demo(args.only)
        elif args.command == "sweep":
            from models.experiments import sweep_main

            return sweep_main(args.config, args.out, args.scheduler, args.resume, args.workers)
    except (DBNError, FileNotFoundError, MemoryError, RuntimeError) as exc:
        if isinstance(exc, MemoryError | RuntimeError):  # jax's out of memory: a RuntimeError
            oom = as_memory_limit(exc, "the run", "lower the sizes in --config "
                                  "(num_particles, ...) or give less data")  # fmt: skip
            if oom is None:
                raise
            exc = oom
        msg = " ".join(str(exc).split())
        print(f"dbntrack {args.command}: error: {msg}", file=sys.stderr)
        return 2
    return 0
