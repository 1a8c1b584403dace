"""``dbntrack``: the command line of the library.

``dbntrack demo`` runs a short example of every model, on bundled or simulated data
(real data from ``../shared/data`` where it is there; when it is not, the demo says so
and falls back to simulated data).
"""

from __future__ import annotations

import argparse
import importlib
import importlib.util
import sys
import time

# Each part is a module exposing ``run_demo(quick: bool = True) -> None``.
DEMO_PARTS: tuple[tuple[str, str], ...] = (
    ("DBN primer", "models.primer"),
    ("Zajdel ADF tracker (seed 002)", "models.zajdel.demo"),
    ("Zajdel learn-search tracker (seed 000)", "models.zajdel.demo_learnsearch"),
    ("Jorge group labels (seed 004)", "models.jorge.demo"),
    ("Robot localisation, auxiliary particle filter (seed 002)", "models.localization.demo"),
    ("Path recovery (seed 001)", "models.pathrecovery.demo"),
    ("Multi-camera RJ-MCMC 3-D tracker (seed 003)", "models.rjmcmc3d.demo"),
)


def _module_exists(name: str) -> bool:
    try:
        return importlib.util.find_spec(name) is not None
    except ModuleNotFoundError:
        return False


def demo(parts: list[str] | None = None) -> None:
    """Run the demo of every model present (or of those whose module name contains a part)."""
    for title, module_name in DEMO_PARTS:
        if parts and not any(p in module_name for p in parts):
            continue
        if not _module_exists(module_name):
            continue
        print(f"\n=== {title} ===", flush=True)
        t0 = time.perf_counter()
        importlib.import_module(module_name).run_demo(quick=True)
        print(f"[{title}: {time.perf_counter() - t0:.1f} s]", flush=True)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="dbntrack",
        description="Tracking with dynamic Bayesian networks: demos of the seed trackers.",
    )
    sub = parser.add_subparsers(dest="command", required=True)
    p_demo = sub.add_parser("demo", help="run a short example of every model")
    p_demo.add_argument(
        "--only",
        nargs="*",
        metavar="PART",
        help="run only the parts whose module contains PART (e.g. primer zajdel jorge)",
    )
    p_sweep = sub.add_parser(
        "sweep",
        help="run a sweep (trackers x data x seeds x parameters) on Dask distributed",
        description="Each grid point of CONFIG (TOML, format in models.experiments.load_sweep) "
        "is one Dask task; results are appended to OUT as they finish.",
    )
    p_sweep.add_argument("config", help="sweep configuration (TOML)")
    p_sweep.add_argument("-o", "--out", default="sweep.jsonl", help="results file (JSON lines)")
    p_sweep.add_argument("--scheduler", help="address of a running Dask scheduler")
    p_sweep.add_argument("--workers", type=int, help="local cluster size (default: cores)")
    p_sweep.add_argument("--resume", action="store_true", help="skip points already done")
    args = parser.parse_args(argv)
    if args.command == "demo":
        demo(args.only)
    elif args.command == "sweep":
        from dbn.errors import DBNError
        from models.experiments import sweep_main

        try:
            return sweep_main(args.config, args.out, args.scheduler, args.resume, args.workers)
        except DBNError as exc:
            print(f"dbntrack sweep: {exc}", file=sys.stderr)
            return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
