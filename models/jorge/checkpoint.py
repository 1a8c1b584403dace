"""Saving the on-line group labeller of seed 004 and resuming it.

The labeller is deterministic: its labels, beliefs, domains and inference log after ``K``
strokes are a function of its configuration, its frame rate and the ``K`` strokes with
their links. A checkpoint holds exactly those, as named arrays with a versioned,
checksummed header (:mod:`inference.checkpoint`: no pickle); :func:`load_labeller` adds
the strokes again, each with its saved links, and checks that they get their saved labels
and inference count back, so the labeller comes back exactly as it was or not at all (a
file saved by a labeller that labels otherwise, another version of this library, is a
:class:`~dbn.errors.CheckpointError`; a labeller on which inferences were run from outside
:meth:`~models.jorge.online.OnlineLabeller.add_stroke` is refused at saving). Loading costs
the labelling of the saved strokes again (not the link search): about as long as the run up
to the checkpoint took.
"""

from __future__ import annotations

import numpy as np

from dbn.errors import CheckpointError, DBNError
from inference.checkpoint import load_arrays, save_arrays
from models.jorge.online import OnlineConfig, OnlineLabeller
from models.jorge.strokes import Stroke

__all__ = ["FORMAT", "save_labeller", "load_labeller"]

FORMAT = "jorge-online-labeller"
"""Format tag of the checkpoint file."""

_RAGGED = ("frames", "positions", "colours", "truth", "palette", "extent", "parents", "labels")
_NAMES = ("index", "start", "end", "has_extent",
          *_RAGGED, *(f"num_{name}" for name in _RAGGED))


def _ragged(rows: list, dtype, width: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Rows of different lengths as one array and the lengths ``(num_rows,)``; ``width``:
    the rows are ``(n, width)``."""
    tail = () if width is None else (width,)
    rows = [np.asarray(r, dtype).reshape((-1, *tail)) for r in rows]
    flat = np.concatenate(rows) if rows else np.zeros((0, *tail), dtype)
    return flat.astype(dtype), np.array([len(r) for r in rows], np.int64)


def _split(flat: np.ndarray, counts: np.ndarray) -> list[np.ndarray]:
    return np.split(flat, np.cumsum(counts)[:-1]) if counts.size else []


def save_labeller(path, labeller: OnlineLabeller) -> None:
    """Write ``labeller``'s strokes and links, under its configuration and frame rate, to
    ``path`` (``.npz``).

    Raises
    ------
    CheckpointError
        A stroke holds a non-finite number, or inferences were run from outside
        :meth:`~models.jorge.online.OnlineLabeller.add_stroke` (``infer``, ``finish``):
        adding the strokes again would not give this labeller back. Nothing is written.
    """
    _check_periodic(path, labeller)
    nodes = labeller.graph.nodes
    strokes = [node.stroke for node in nodes]
    extent = [s.extent if s.extent is not None else np.zeros((0, 2)) for s in strokes]
    arrays = {
        "index": np.array([s.index for s in strokes], np.int64),
        "start": np.array([s.start for s in strokes], np.int64),
        "end": np.array([s.end for s in strokes], np.int64),
        "has_extent": np.array([s.extent is not None for s in strokes], bool),
    }
    columns = {
        "frames": _ragged([s.frames for s in strokes], np.int64),
        "positions": _ragged([s.positions for s in strokes], np.float64, 2),
        "colours": _ragged([s.colours for s in strokes], np.int64),
        "truth": _ragged([sorted(s.truth) for s in strokes], np.int64),
        "palette": _ragged([s.palette for s in strokes], np.int64),
        "extent": _ragged(extent, np.float64, 2),
        "parents": _ragged([node.parents for node in nodes], np.int64),
        "labels": _ragged([sorted(labeller.labels[k]) for k in range(len(nodes))], np.int64),
    }
    for name, (flat, counts) in columns.items():
        arrays[name], arrays[f"num_{name}"] = flat, counts
    save_arrays(path, arrays, FORMAT, _config(labeller.config, labeller.fps),
                extra={"keep_windows": bool(labeller.keep_windows),
                       "num_inferences": len(labeller.records)})


def _check_periodic(path, lab: OnlineLabeller) -> None:
    """Refuse a labeller with inferences that ``add_stroke`` did not run
    (:attr:`~models.jorge.online.OnlineLabeller.periodic_inferences`)."""
    if len(lab.records) != lab.periodic_inferences:
        raise CheckpointError(path, "inferences run from outside add_stroke (infer, finish): "
                              f"{len(lab.records)} inferences where adding the strokes again "
                              f"runs {lab.periodic_inferences}; such a labeller cannot be "
                              "resumed")


def _config(config: OnlineConfig, fps: float) -> dict:
    return {"online": config, "fps": float(fps)}


def load_labeller(path, config: OnlineConfig | None = None,
                  fps: float | None = None) -> OnlineLabeller:
    """The labeller saved by :func:`save_labeller`, which must have been saved under
    ``config`` (default :class:`OnlineConfig`) and ``fps``: every stroke added again with
    its saved links.

    Raises
    ------
    CheckpointError
        Naming the file: unreadable, another format or version, a changed byte, saved
        under another configuration or frame rate, or strokes that do not make a labeller.
    """
    config = OnlineConfig() if config is None else config
    lab = OnlineLabeller(config, fps)
    arrays, header = load_arrays(path, FORMAT, _NAMES, _config(config, lab.fps))
    lab.keep_windows = bool(header.get("keep_windows", False))
    saved = _strokes(path, arrays)
    for stroke, parents, _ in saved:
        try:
            lab.add_stroke(stroke, parents)
        except DBNError as exc:
            raise CheckpointError(path, f"stroke {stroke.index}: {exc}") from None
    for stroke, _, label in saved:
        again = sorted(lab.labels[stroke.index])
        if again != label:
            raise CheckpointError(path, f"stroke {stroke.index} labelled {again}, saved "
                                  f"{label}: saved by a labeller that labels otherwise")
    if len(lab.records) != header.get("num_inferences"):
        raise CheckpointError(path, f"{len(lab.records)} inferences, saved "
                              f"{header.get('num_inferences')}: inferences run from outside "
                              "add_stroke (infer, finish) are not in the file")
    return lab


def _strokes(path, a: dict) -> list[tuple[Stroke, tuple[int, ...], list[int]]]:
    """The saved strokes, their links and labels; inconsistent arrays are a
    CheckpointError."""
    n = a["index"].size
    cols = {}
    for name in _RAGGED:
        counts = a[f"num_{name}"]
        if counts.shape != (n,) or np.any(counts < 0) or counts.sum() != len(a[name]):
            raise CheckpointError(path, f"array {name!r} does not hold {n} strokes' rows")
        cols[name] = _split(a[name], counts)
    if not all(a[k].shape == (n,) for k in ("start", "end", "has_extent")):
        raise CheckpointError(path, f"start, end and has_extent must hold {n} strokes")
    out = []
    for i in range(n):
        stroke = Stroke(int(a["index"][i]), int(a["start"][i]), int(a["end"][i]),
                        cols["frames"][i], cols["positions"][i], cols["colours"][i],
                        frozenset(int(t) for t in cols["truth"][i]), cols["palette"][i],
                        cols["extent"][i] if a["has_extent"][i] else None)
        out.append((stroke, tuple(int(p) for p in cols["parents"][i]),
                    [int(m) for m in cols["labels"][i]]))
    return out
