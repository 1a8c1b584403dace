"""What every runner shares: the output folder, the seed, progress bars, figures,
``summary.json``."""

from __future__ import annotations

import json
import math
import platform
import sys
import time
from collections.abc import Callable, Iterable
from contextlib import contextmanager
from dataclasses import dataclass, field
from importlib import metadata
from pathlib import Path
from typing import Any

from dbn.errors import InputError

__all__ = ["RunContext", "clean", "short_names", "shown_strength", "versions", "write_summary"]


@dataclass
class RunContext:
    """One ``dbntrack track`` run.

    Attributes
    ----------
    name : tracker name
    outdir : output folder (created)
    seed : the run's seed (trackers get ``jax.random.key(seed)``)
    quiet : no progress bars (default: quiet unless stderr is a terminal)
    timings : seconds per named phase (filled by :meth:`timed`)
    """

    name: str
    outdir: Path
    seed: int
    quiet: bool = field(default_factory=lambda: not sys.stderr.isatty())
    timings: dict[str, float] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.outdir = Path(self.outdir)
        try:
            self.outdir.mkdir(parents=True, exist_ok=True)
        except OSError as exc:  # a file of that name, a read-only place, ...
            raise InputError(f"output folder {self.outdir}: cannot create it "
                             f"({exc.strerror or exc})") from None  # fmt: skip

    def progress(self, iterable: Iterable, total: int | None = None, desc: str = ""):
        """``iterable`` wrapped in a tqdm bar (silent when :attr:`quiet`)."""
        from inference.progress import progress_bar

        return progress_bar(iterable, total=total, desc=desc or self.name, disable=self.quiet,
                    leave=False, mininterval=1.0)  # fmt: skip

    def bar(self, desc: str) -> Callable[[Iterable, int], Iterable]:
        """A ``progress`` for :meth:`models.protocol.StepTracker.fold`: its steps in a
        :meth:`progress` bar counting ``desc``."""
        return lambda steps, total: self.progress(steps, total, desc)

    def note(self, message: str) -> None:
        """Tell the user about an assumption the run made (on stderr, even when quiet)."""
        print(f"{self.name}: {message}", file=sys.stderr)

    @contextmanager
    def timed(self, phase: str):
        """Record the wall time of a phase in :attr:`timings`."""
        t0 = time.perf_counter()
        try:
            yield
        finally:
            self.timings[phase] = round(time.perf_counter() - t0, 4)

    def key(self):
        """``jax.random.key(seed)``."""
        import jax

        return jax.random.key(self.seed)

    @contextmanager
    def figure(self, filename: str, figsize=None, layout=None, **subplots: Any):
        """``(fig, axes)`` of ``Figure.subplots(**subplots)``, saved as ``outdir/filename``.

        Uses :class:`matplotlib.figure.Figure` (Agg canvas) without pyplot, so no window
        opens and the caller's matplotlib backend is left alone.
        """
        from matplotlib.figure import Figure

        fig = Figure(figsize=figsize, layout=layout)
        axes = fig.subplots(**subplots)
        yield fig, axes
        if layout is None:
            fig.tight_layout()
        fig.savefig(self.outdir / filename, dpi=100)


def versions() -> dict[str, str]:
    """Versions of Python, this library and its main dependencies."""
    out = {"python": platform.python_version()}
    for pkg in ("dbn-tracking", "numpy", "scipy", "jax", "pgmpy", "motmetrics", "matplotlib"):
        try:
            out[pkg] = metadata.version(pkg)
        except metadata.PackageNotFoundError:
            out[pkg] = "not installed"
    return out


def clean(x: Any) -> Any:
    """``x`` with NaN / inf floats replaced by ``None`` (strict JSON), recursively."""
    if isinstance(x, dict):
        return {k: clean(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [clean(v) for v in x]
    if isinstance(x, float) and not math.isfinite(x):
        return None
    return x


def short_names(paths: list[str]) -> dict[str, str]:
    """Each path's shortest tail of path parts that tells it from the others (two
    ``gt.txt`` in ``MOT17-02/gt/`` and ``MOT17-04/gt/`` show as ``MOT17-02/gt/gt.txt`` and
    ``MOT17-04/gt/gt.txt``; a path every tail of which ends another shows whole): the names
    a terminal or a figure shows files by."""
    parts = {str(p): Path(p).parts for p in paths}
    out = {}
    for p, q in parts.items():
        others = [o for r, o in parts.items() if r != p]
        n = 1
        while n < len(q) and any(o[-n:] == q[-n:] for o in others):
            n += 1
        out[p] = "/".join(q[-n:]) if n < len(q) else p
    return out


def shown_strength(value: float) -> float | str:
    """A prior strength (``dbntrack fit --prior-strength``) for JSON: ``"inf"`` for the
    prior itself, as JSON has no infinity (:func:`clean` would make it ``null``)."""
    return value if math.isfinite(value) else "inf"


def write_summary(path: Path, summary: dict) -> Path:
    """Write ``summary`` as indented JSON (numpy scalars as numbers, NaN as null)."""

    def default(x):
        try:
            return x.item()
        except AttributeError:
            return str(x)

    path.write_text(json.dumps(clean(summary), indent=2, default=default) + "\n", encoding="utf-8")
    return path
