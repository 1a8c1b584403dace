"""``dbntrack``: the command line of the library.

``dbntrack demo`` runs a short example of every model, on bundled or simulated data
(real data from ``../shared/data`` where it is there; when it is not, the demo says so
and falls back to simulated data). ``dbntrack demo --only NAME ...`` runs the named parts
(``primer`` or a tracker of the registry, ``models.available()``); ``dbntrack list``
prints the registry; ``dbntrack track`` / ``eval`` run a tracker on files
(:mod:`models.commands`).
"""

from __future__ import annotations

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


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``dbntrack`` (sub-commands in :mod:`models.commands`); returns the
    exit status: 2 on bad input, with a one-line message on stderr."""
    from models.commands import build_parser, dispatch

    parser = build_parser(demo, [name for name, _, _ in demo_parts()])
    return dispatch(parser, parser.parse_args(argv))


if __name__ == "__main__":
    sys.exit(main())
