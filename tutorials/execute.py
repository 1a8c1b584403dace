"""Re-execute every tutorial and store its notebook WITH outputs (figures inline).

Each ``tutorials/NN_name.py`` (jupytext percent format, the source of truth) is read,
run top to bottom in a fresh ``python3`` kernel with the tutorials folder as working
directory, and written to ``NN_name.ipynb`` with its outputs and the jupytext pairing
metadata (so ``jupytext --sync`` and ``tests/test_tutorials.py`` keep working).

Usage (from the repository root; needs the ``notebooks`` extra)::

    python tutorials/execute.py            # every tutorial, full sizes
    python tutorials/execute.py --quick 03 # DBNTRACK_QUICK=1, only names containing 03

Exit status 1 if a tutorial fails (its error is printed; the other notebooks are kept).
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent


def execute(path: Path, timeout: int, quick: bool) -> float:
    """Run ``path`` (a .py tutorial) and write its executed ``.ipynb``; returns seconds."""
    import jupytext
    import nbclient

    nb = jupytext.read(path)
    nb.metadata.setdefault("jupytext", {})["formats"] = "ipynb,py:percent"
    nb.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3",
                                 "language": "python"}  # fmt: skip
    env = dict(os.environ, MPLBACKEND="module://matplotlib_inline.backend_inline")
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(HERE.parent), env.get("PYTHONPATH")]))
    if quick:
        env["DBNTRACK_QUICK"] = "1"
    t0 = time.perf_counter()
    client = nbclient.NotebookClient(nb, timeout=timeout, kernel_name="python3",
                                     resources={"metadata": {"path": str(HERE)}})  # fmt: skip
    client.execute(env=env)
    jupytext.write(nb, path.with_suffix(".ipynb"))
    return time.perf_counter() - t0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("only", nargs="*", help="run only tutorials whose name contains one")
    parser.add_argument("--quick", action="store_true", help="set DBNTRACK_QUICK=1 (small sizes)")
    parser.add_argument("--timeout", type=int, default=1800, help="seconds per cell (1800)")
    args = parser.parse_args(argv)
    paths = sorted(HERE.glob("[0-9]*.py"))
    if args.only:
        paths = [p for p in paths if any(o in p.stem for o in args.only)]
        if not paths:
            parser.error(f"no tutorial matches {args.only}")
    failed = []
    for p in paths:
        print(f"{p.name} ...", end=" ", flush=True)
        try:
            print(f"{execute(p, args.timeout, args.quick):.1f} s -> {p.with_suffix('.ipynb').name}")
        except Exception as exc:  # report and go on with the others
            print(f"FAILED: {type(exc).__name__}: {str(exc)[-2000:]}")
            failed.append(p.name)
    if failed:
        print(f"failed: {', '.join(failed)}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
