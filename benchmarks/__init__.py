"""Measured claims: ``python -m benchmarks NAME [--quick] [--seed S]``.

Each benchmark is a module ``benchmarks/NAME.py`` exposing
``run(quick: bool, seed: int) -> dict``. The runner adds ``name``, ``quick``, ``seed``
and, unless the benchmark set it, ``ok``; it prints the JSON object as the last line
of standard output and exits non-zero when ``ok`` is false (see
``../shared/spec/benchmarks.md``).
"""

from __future__ import annotations

import pkgutil
from pathlib import Path

__all__ = ["available"]


def available() -> list[str]:
    """Names of the benchmarks in this package (modules not starting with ``_``)."""
    here = Path(__file__).parent
    return sorted(m.name for m in pkgutil.iter_modules([str(here)]) if not m.name.startswith("_"))
