"""Command line of the benchmarks: ``python -m benchmarks NAME [--quick] [--seed S]``."""

from __future__ import annotations

import argparse
import contextlib
import importlib
import inspect
import json
import sys
import time

from benchmarks import available
from benchmarks._common import dask_mapper, to_jsonable


def main(argv: list[str] | None = None) -> int:
    with contextlib.ExitStack() as stack:
        return _main(argv, stack)


def _main(argv: list[str] | None, stack: contextlib.ExitStack) -> int:
    names = available()
    parser = argparse.ArgumentParser(prog="python -m benchmarks", description=__doc__)
    parser.add_argument("name", choices=names, help="which benchmark to run")
    parser.add_argument("--quick", action="store_true", help="small sizes, under 60 s on 2 cores")
    parser.add_argument("--seed", type=int, default=0, help="base random seed (default 0)")
    parser.add_argument(
        "--dask",
        nargs="?",
        const="local",
        metavar="ADDRESS",
        help="run the benchmark's multi-seed loop on Dask distributed: a local cluster, or "
        "the scheduler at ADDRESS (benchmarks whose run() takes a mapper)",
    )
    args = parser.parse_args(argv)

    module = importlib.import_module(f"benchmarks.{args.name}")
    kwargs = {}
    if args.dask:
        if "mapper" not in inspect.signature(module.run).parameters:
            parser.error(f"benchmark {args.name!r} has no multi-seed loop to distribute")
        kwargs["mapper"] = stack.enter_context(dask_mapper(args.dask))
    start = time.perf_counter()
    result = dict(module.run(quick=args.quick, seed=args.seed, **kwargs))
    result.setdefault("ok", True)
    result.setdefault("wall_s", round(time.perf_counter() - start, 3))
    out = {"name": args.name, "quick": args.quick, "seed": args.seed, **result}
    sys.stdout.flush()
    print(json.dumps(to_jsonable(out)))
    return 0 if out["ok"] else 1


if __name__ == "__main__":
    sys.exit(main())
