"""Strokes from your own low-level tracker for the group labeller (seed 004): a regions file.

Seed 004 labels the *strokes* of a low-level tracker: regions (one person or a group)
followed without a break, each with its dominant colours. ``dbntrack track jorge`` makes
them from ground-truth boxes with SIMULATED occlusion gaps and colours
(:func:`models.jorge.strokes.build_strokes`); a regions file gives your tracker's own, which
are labelled as they are (nothing simulated). JSON lines, one stroke per line, in start
order (a stroke's index is its position, from 0), after optional header lines::

    # fps=25
    {"frames": [10, 11, 12], "boxes": [[320.5, 200, 40, 90], ...], "colours": [0, 3, 7]}
    {"frames": [13, 14], "boxes": [...], "colours": [1, 3], "palette": [1, 3, 5],
     "truth": [4, 5], "parents": [0]}

Fields:

* ``frames``: the stroke's frame numbers, integers >= 0, increasing;
* ``boxes``: the region's box at each frame, ``[x_centre, y_centre, width, height]``
  in pixels (its size is the evidence on the number of people);
* ``colours``: the dominant colours seen in the region, distinct indices into a pool of
  ``NetworkConfig.pool_size`` colours (12 by default; the config's ``network.pool_size``);
* ``palette`` (optional): the colours a label created at this stroke gets (seed 004,
  sec. 4.1), not empty, default ``colours``;
* ``truth`` (optional): the people in the region, ids >= 0, for scoring (``dbntrack eval``
  needs it on every stroke);
* ``parents`` (optional; on every line or on none): the earlier strokes your tracker saw
  this one split from or merge out of (at most two, each ending before it starts); without
  them the on-line link rule links the strokes.

Header lines: ``# fps=F`` (the frame rate; the config's ``fps`` overrides it, else 25 fps is
assumed and the run says so); other lines starting with ``#`` are comments, blank lines
are skipped. A key not listed, a value of the wrong kind or a broken line is a
:class:`~dbn.errors.FileFormatError` naming the file, line and field; what the label
network itself refuses (colours beyond the pool, a link it cannot hold) is checked, with
the same naming, before anything is labelled (:func:`check_regions`).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from dbn.errors import InputError
from models.io.table import fail, read_lines

__all__ = ["Regions", "is_regions", "read_regions", "check_regions", "write_regions"]

FIELDS = ("frames", "boxes", "colours", "palette", "truth", "parents")
"""The keys of a stroke's line (module docstring)."""


class Regions(NamedTuple):
    """A regions file read (:func:`read_regions`).

    Attributes
    ----------
    path : Path
    strokes : list of Stroke
        In file order (``index`` = position); ``truth`` empty where the line has none;
        ``extent`` the boxes' widths and heights.
    parents : list of tuple of int, or None
        Each stroke's links, where the file gives them.
    lines : list of int
        The line number of each stroke.
    fps : float or None
        The header's ``# fps=``, where it has one.
    """

    path: Path
    strokes: list
    parents: list | None
    lines: list
    fps: float | None

    @property
    def has_truth(self) -> bool:
        """Every line has a non-empty ``truth``."""
        return all(s.truth for s in self.strokes)


def is_regions(path: str | Path) -> bool:
    """Whether ``path`` names a regions file (``.jsonl``, may be gzipped)."""
    return Path(path).name.lower().removesuffix(".gz").endswith(".jsonl")


def read_regions(path: str | Path) -> Regions:
    """Read a regions file (module docstring).

    Raises
    ------
    FileFormatError
        Naming the file, line and field: a line that is not a JSON object, an unknown or
        missing key, a value of the wrong kind, frames not increasing, a box per frame
        missing or not positive, strokes not in start order, ``parents`` on some lines
        only or naming a stroke that is not earlier, a bad ``# fps=``; an empty file.
    """
    path = Path(path)
    strokes, parents, lines, fps = [], [], [], None
    for line_no, raw in enumerate(read_lines(path, "regions file"), start=1):
        text = raw.strip()
        if not text:
            continue
        if text.startswith("#"):
            fps = _header(path, line_no, text, fps, bool(strokes))
            continue
        stroke, links = _stroke(path, line_no, text, len(strokes))
        if strokes and stroke.start < strokes[-1].start:
            raise fail(path, line_no, f"stroke {stroke.index} starts at frame {stroke.start}, "
                       f"before stroke {stroke.index - 1} (frame {strokes[-1].start}): "
                       "strokes come in start order")  # fmt: skip
        if parents and (links is None) != (parents[0] is None):
            first = "has" if parents[0] is not None else "has no"
            raise fail(path, line_no, "parents: on every line or on none (the first stroke's "
                       f"line {first} parents)")  # fmt: skip
        strokes.append(stroke)
        parents.append(links)
        lines.append(line_no)
    if not strokes:
        raise fail(path, 0, "no stroke (one JSON object per line expected)")
    return Regions(path, strokes, None if parents[0] is None else parents, lines, fps)


def _header(path: Path, line_no: int, text: str, fps: float | None, late: bool) -> float | None:
    """The frame rate after a ``#`` line (``# fps=F``; other ``#`` lines are comments)."""
    key, eq, value = text[1:].strip().partition("=")
    if not eq or key.strip() != "fps":
        return fps
    if late or fps is not None:
        raise fail(path, line_no, "'# fps=' comes once, before the first stroke")
    try:
        rate = float(value)
    except ValueError:
        rate = math.nan
    if not (math.isfinite(rate) and rate > 0):
        raise fail(path, line_no, f"fps = {value.strip()!r}: expected a finite number > 0")
    return rate


def _stroke(path: Path, line_no: int, text: str, index: int):
    """The stroke (and its links, None where the line has none) of one line."""
    from models.jorge.strokes import Stroke

    try:
        obj = json.loads(text)
    except ValueError as exc:
        raise fail(path, line_no, f"not a JSON object ({exc})") from None
    if not isinstance(obj, dict):
        raise fail(path, line_no, f"not a JSON object (got {type(obj).__name__})")
    unknown = sorted(set(obj) - set(FIELDS))
    if unknown:
        raise fail(path, line_no, f"unknown key(s) {unknown}; the keys are {list(FIELDS)}")
    for key in ("frames", "boxes", "colours"):
        if key not in obj:
            raise fail(path, line_no, f"{key}: missing")
    frames = _ints(path, line_no, "frames", obj["frames"], non_empty=True)
    if np.any(np.diff(frames) <= 0):
        raise fail(path, line_no, f"frames {frames.tolist()}: expected increasing frame numbers")
    boxes = _boxes(path, line_no, obj["boxes"], frames.size)
    colours = _ints(path, line_no, "colours", obj["colours"], non_empty=True, distinct=True)
    palette = _ints(path, line_no, "palette", obj.get("palette", colours.tolist()),
                    non_empty=True, distinct=True)  # fmt: skip
    truth = _ints(path, line_no, "truth", obj.get("truth", []), distinct=True)
    links = None
    if "parents" in obj:
        links = tuple(sorted(int(p) for p in _ints(path, line_no, "parents", obj["parents"],
                                                   distinct=True)))  # fmt: skip
        if any(p >= index for p in links):
            raise fail(path, line_no, f"parents {list(links)}: stroke {index} links to "
                       "earlier strokes only (a stroke's index is its position in the file, "
                       "from 0)")  # fmt: skip
    stroke = Stroke(index, int(frames[0]), int(frames[-1]), frames, boxes[:, :2].copy(),
                    np.sort(colours), frozenset(int(p) for p in truth), np.sort(palette),
                    boxes[:, 2:].copy())  # fmt: skip
    return stroke, links


def _ints(path: Path, line_no: int, key: str, value: Any, non_empty: bool = False,
          distinct: bool = False) -> np.ndarray:
    """A list of integers >= 0 (int64), checked as the key's rules say."""
    ok = isinstance(value, list) and all(type(v) is int for v in value)  # not bool, not float
    if not ok:
        raise fail(path, line_no, f"{key} = {_short(value)}: expected a list of integers")
    if non_empty and not value:
        raise fail(path, line_no, f"{key}: empty")
    if any(not 0 <= v < 2**62 for v in value):
        raise fail(path, line_no, f"{key} = {_short(value)}: expected integers >= 0")
    if distinct and len(set(value)) != len(value):
        raise fail(path, line_no, f"{key} = {_short(value)}: repeated")
    return np.asarray(value, dtype=np.int64)


def _boxes(path: Path, line_no: int, value: Any, num_frames: int) -> np.ndarray:
    """``[[x, y, w, h], ...]``, one per frame, finite, with w, h > 0; shape (num_frames, 4)."""
    rows = value if isinstance(value, list) else None
    ok = rows is not None and all(
        isinstance(r, list) and len(r) == 4
        and all(isinstance(v, int | float) and not isinstance(v, bool) for v in r) for r in rows
    )
    if not ok:
        raise fail(path, line_no, f"boxes = {_short(value)}: expected a list of "
                   "[x_centre, y_centre, width, height]")  # fmt: skip
    if len(rows) != num_frames:
        raise fail(path, line_no, f"boxes: {len(rows)} for {num_frames} frames (one per frame)")
    boxes = np.asarray(rows, dtype=np.float64)
    if not np.all(np.isfinite(boxes)) or np.any(boxes[:, 2:] <= 0):
        raise fail(path, line_no, "boxes: expected finite numbers, width and height > 0")
    return boxes


def _short(value: Any) -> str:
    finite = not isinstance(value, float) or math.isfinite(value)
    text = json.dumps(value) if finite else repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def check_regions(regions: Regions, network, fps: float) -> None:
    """What the label network refuses, checked on every stroke before any is labelled: a
    dry run of a links-only :class:`~models.jorge.network.LabelGraph` of ``network`` at
    ``fps`` over the strokes (colours and palettes within the pool, sizes within range)
    and their links (``parents``: each ends before the stroke, at most two, a parent with
    a free child slot). Raises :class:`~dbn.errors.FileFormatError` naming the line."""
    from models.jorge.network import LabelGraph

    graph = LabelGraph(network, with_domains=False, fps=fps)
    # without the file's links, roots: the rule's links cannot be refused, so the dry run
    # does not compute them (the labeller will)
    links = regions.parents or [()] * len(regions.strokes)
    for stroke, par, line_no in zip(regions.strokes, links, regions.lines):
        try:
            graph.add_stroke(stroke, par)  # checks the stroke, and its links
        except InputError as exc:
            raise fail(regions.path, line_no, str(exc)) from None


def write_regions(path: str | Path, strokes, parents=None, fps: float | None = None) -> Path:
    """Write ``strokes`` (:class:`~models.jorge.strokes.Stroke`, with an ``extent``) as a
    regions file (module docstring), with ``parents`` (one int sequence per stroke) and
    ``# fps=F`` where given: e.g. SIMULATED strokes, to see the format or to label them
    with links of your own."""
    out = [] if fps is None else [f"# fps={float(fps)!r}"]
    for k, s in enumerate(strokes):
        if s.extent is None:
            raise InputError(f"stroke {k}: no extent (box sizes): a regions file needs boxes")
        obj = {"frames": [int(f) for f in s.frames],
               "boxes": [[float(x), float(y), float(w), float(h)]
                         for (x, y), (w, h) in zip(s.positions, s.extent)],
               "colours": [int(c) for c in s.colours], "palette": [int(c) for c in s.palette],
               "truth": sorted(int(p) for p in s.truth)}  # fmt: skip
        if parents is not None:
            obj["parents"] = sorted(int(p) for p in parents[k])
        out.append(json.dumps(obj))
    path = Path(path)
    path.write_text("\n".join(out) + "\n", encoding="utf-8")
    return path
