"""``dbntrack``: the command line of the library.

``dbntrack demo`` runs a short example of every model, on bundled or simulated data
(real data from ``../shared/data`` where it is there; when it is not, the demo says so
and falls back to simulated data).
"""

from __future__ import annotations

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
    """Run the demo of every model present (or of those whose module name contains a part).

    Raises
    ------
    InputError
        A part that matches no demo (the message lists the valid names).
    """
    from dbn.errors import InputError

    modules = [m for _, m in DEMO_PARTS]
    for p in parts or ():
        if not any(p in m for m in modules):
            valid = sorted({m.split(".")[1] for m in modules})
            raise InputError(f"--only {p!r} matches no demo; valid: {', '.join(valid)}")
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
    """Entry point of ``dbntrack``; returns the exit status (2 on bad input, with a
    one-line message on stderr)."""
    from models.commands import build_parser, dispatch

    parser = build_parser(demo)
    args = parser.parse_args(argv)
    return dispatch(parser, args)

if __name__ == "__main__":
    sys.exit(main())
