"""``dbntrack``: the command line of the library.

``dbntrack demo`` runs a short example of every model, on bundled or simulated data
(real data from ``../shared/data`` where it is there; when it is not, the demo says so
and falls back to simulated data). ``dbntrack demo --only NAME ...`` runs the named parts
(``primer`` or a tracker of the registry, ``models.available()``); ``dbntrack list``
prints the registry.
"""

from __future__ import annotations

import argparse
import importlib
import importlib.util
import sys
import time

import models

# Titles of the demo parts; the module of every tracker's demo comes from the registry.
_TITLES = {
    "primer": "DBN primer",
    "zajdel_adf": "Zajdel ADF tracker (seed 002)",
    "zajdel_learnsearch": "Zajdel learn-search tracker (seed 000)",
    "jorge": "Jorge group labels (seed 004)",
    "localization": "Robot localisation, auxiliary particle filter (seed 002)",
    "pathrecovery": "Path recovery (seed 001)",
    "rjmcmc3d": "Multi-camera RJ-MCMC 3-D tracker (seed 003)",
}


def demo_parts() -> tuple[tuple[str, str, str], ...]:
    """``(name, title, module)`` of every demo part: the primer, then each registered tracker."""
    parts = [("primer", _TITLES["primer"], "models.primer")]
    for name in models.available():
        entry = models.get(name)
        if entry.demo_module is not None:
            parts.append((name, _TITLES.get(name, name), entry.demo_module))
    return tuple(parts)


# Each part is a module exposing ``run_demo(quick: bool = True) -> None``.
DEMO_PARTS: tuple[tuple[str, str], ...] = tuple(
    (title, module) for _, title, module in demo_parts()
)


def _module_exists(name: str) -> bool:
    try:
        return importlib.util.find_spec(name) is not None
    except ModuleNotFoundError:
        return False


def demo(parts: list[str] | None = None) -> None:
    """Run the demo of every model present, or of the parts named in ``parts``."""
    for name, title, module_name in demo_parts():
        if parts and name not in parts:
            continue
        if not _module_exists(module_name):
            continue
        print(f"\n=== {title} ===", flush=True)
        t0 = time.perf_counter()
        importlib.import_module(module_name).run_demo(quick=True)
        print(f"[{title}: {time.perf_counter() - t0:.1f} s]", flush=True)


def list_trackers() -> None:
    """Print the registry: name, seed paper, what it tracks, input formats."""
    for name in models.available():
        e = models.get(name)
        print(f"{name}\n  seed paper: {e.seed_paper}\n  tracks: {e.tracks}")
        for fmt in e.input_formats:
            print(f"  input: {fmt}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="dbntrack",
        description="Tracking with dynamic Bayesian networks: demos of the seed trackers.",
    )
    sub = parser.add_subparsers(dest="command", required=True)
    names = [name for name, _, _ in demo_parts()]
    p_demo = sub.add_parser("demo", help="run a short example of every model")
    p_demo.add_argument(
        "--only",
        nargs="*",
        metavar="NAME",
        help=f"run only the named parts: {', '.join(names)}",
    )
    sub.add_parser("list", help="list the registered trackers")
    args = parser.parse_args(argv)
    if args.command == "demo":
        unknown = [p for p in args.only or [] if p not in names]
        if unknown:
            p_demo.error(f"unknown part(s) {', '.join(unknown)}; valid: {', '.join(names)}")
        demo(args.only)
    elif args.command == "list":
        list_trackers()
    return 0


if __name__ == "__main__":
    sys.exit(main())
