"""Multi-camera observation files of the Zajdel trackers (ADF, learn-search).

Observations CSV, one of two layouts (``docs/formats.md``):

* one row per pass: ``t_enter,t_quit,camera,border_enter,border_quit,a0,a1,...``
  (optional ``pass`` id, default the row's 0-based index; optional ``person``: the truth);
* events: ``pass,time,camera,event,border,a0,a1,...`` with ``event`` = ``enter`` or
  ``leave``, one of each per pass, appearance on either row (the mean when on both).

Cameras and borders are 0-based ints; appearance columns are ``a0 .. a{r-1}``. Passes
are ordered by quit time (the trackers' order). Labels CSV (output):
``pass,camera,t_enter,t_quit,label``; partition CSV: ``label,size,passes`` (pass ids
separated by spaces).
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import NamedTuple

import numpy as np

from dbn.errors import InputError
from models.io.table import fail, read_rows, write_rows
from models.zajdel.data import MAX_APPEARANCE, MAX_TIME, Observations

__all__ = ["PassTable", "read_observations", "write_labels", "read_labels", "write_partition"]

_APP = re.compile(r"^a(\d+)$")


class PassTable(NamedTuple):
    """Passes in quit-time order: ``obs`` for the trackers, ``ids`` (n,) pass ids,
    ``person`` (n,) true person labels or None."""

    obs: Observations
    ids: np.ndarray
    person: np.ndarray | None


def _app_columns(path, header: list[str]) -> list[str]:
    cols = sorted((c for c in header if _APP.match(c)), key=lambda c: int(c[1:]))
    if not cols or [int(c[1:]) for c in cols] != list(range(len(cols))):
        raise fail(path, 1, f"need appearance columns a0, a1, ... (found {cols or 'none'})")
    return cols


def _time(r, col: str) -> float:
    """Column ``col`` of row ``r``: a time, ``|t| <=`` :data:`MAX_TIME`."""
    t = r.float(col)
    if abs(t) > MAX_TIME:
        raise r.fail(f"{col} = {t:g}: |time| must be <= {MAX_TIME:g} s (a unit mistake?)")
    return t


def _appearance(r, cols: list[str]) -> list[float]:
    """The appearance columns of row ``r``, each ``|a| <=`` :data:`MAX_APPEARANCE`
    (:func:`models.zajdel.data.validate_observations` checks the same, by index; the
    trackers' data-driven prior is computed before it runs and went NaN)."""
    out = [r.float(c) for c in cols]
    for c, v in zip(cols, out):
        if abs(v) > MAX_APPEARANCE:
            raise r.fail(f"{c} = {v:g}: |appearance| must be <= {MAX_APPEARANCE:g} "
                         "(features are expected of order 1-1000; rescale them)")  # fmt: skip
    return out


def _from_passes(path, header, rows):
    app_cols = _app_columns(path, header)
    out = []
    for i, r in enumerate(rows):
        te, tq = _time(r, "t_enter"), _time(r, "t_quit")
        if tq < te:
            raise r.fail(f"t_quit = {tq} comes before t_enter = {te}")
        pid = r.int("pass") if "pass" in header else i
        person = r.int("person") if "person" in header and r["person"] != "" else None
        out.append((pid, te, tq, r.int("camera"), r.int("border_enter"), r.int("border_quit"),
                    _appearance(r, app_cols), person, r))  # fmt: skip
    return out


def _from_events(path, header, rows):
    app_cols = _app_columns(path, header)
    passes: dict[int, dict] = {}
    for r in rows:
        ev = r["event"].lower()
        if ev not in ("enter", "leave"):
            raise r.fail(f"event = {r['event']!r}, expected enter or leave")
        p = passes.setdefault(r.int("pass"), {"apps": [], "row": r})
        if ev in p:
            raise r.fail(f"pass {r['pass']} has a second {ev} event")
        if "camera" in p and p["camera"] != r.int("camera"):
            raise r.fail(f"pass {r['pass']} changes camera ({p['camera']} -> {r['camera']})")
        p[ev], p["camera"] = (_time(r, "time"), r.int("border")), r.int("camera")
        given = [c for c in app_cols if r[c] != ""]
        if given and len(given) < len(app_cols):  # the row's appearance was dropped
            empty = [c for c in app_cols if r[c] == ""]
            raise r.fail(f"appearance columns {empty} are empty where {given} are not: "
                         "give a row all of them or none")  # fmt: skip
        if given:
            p["apps"].append(_appearance(r, app_cols))
        if "person" in header and r["person"] != "":
            p["person"] = r.int("person")
    out = []
    for pid, p in passes.items():
        r = p["row"]
        if "enter" not in p or "leave" not in p or not p["apps"]:
            raise r.fail(f"pass {pid} needs an enter and a leave event and an appearance")
        (te, be), (tq, bq) = p["enter"], p["leave"]
        if tq < te:
            raise r.fail(f"pass {pid} leaves at {tq} before it enters at {te}")
        out.append((pid, te, tq, p["camera"], be, bq, np.mean(p["apps"], axis=0).tolist(),
                    p.get("person"), r))  # fmt: skip
    return out


def read_observations(path: str | Path) -> PassTable:
    """Read an observations CSV (either layout) into passes ordered by quit time."""
    header, rows = read_rows(path, what="observations CSV")
    if not rows:
        raise fail(path, 0, "no observations")
    if "event" in header:
        need = ("pass", "time", "camera", "event", "border")
        parse = _from_events
    else:
        need = ("t_enter", "t_quit", "camera", "border_enter", "border_quit")
        parse = _from_passes
    missing = [c for c in need if c not in header]
    if missing:
        raise fail(path, 1, f"missing column(s) {missing}; header is {header}")
    passes = parse(path, header, rows)
    for p in passes:
        if min(p[3], p[4], p[5]) < 0:
            raise p[8].fail("camera and borders must be >= 0")
    if len({p[0] for p in passes}) != len(passes):
        raise fail(path, 0, "pass ids are not unique")
    passes.sort(key=lambda p: p[2])
    ids = [p[0] for p in passes]  # in the passes' (quit-time) order, as obs and person
    obs = Observations(
        np.array([p[6] for p in passes], float), np.array([p[3] for p in passes], np.int64),
        np.array([p[1] for p in passes], float), np.array([p[2] for p in passes], float),
        np.array([p[4] for p in passes], np.int64), np.array([p[5] for p in passes], np.int64),
    )  # fmt: skip
    persons = [p[7] for p in passes]
    person = None if any(x is None for x in persons) else np.array(persons, np.int64)
    return PassTable(obs, np.array(ids, np.int64), person)


def write_labels(path, table: PassTable, labels: np.ndarray) -> Path:
    """``pass,camera,t_enter,t_quit,label`` (quit-time order)."""
    o = table.obs
    rows = [(int(i), int(c), float(te), float(tq), int(lab))
            for i, c, te, tq, lab in zip(table.ids, o.camera, o.t_enter, o.t_quit, labels)]  # fmt: skip
    return write_rows(path, ("pass", "camera", "t_enter", "t_quit", "label"), rows)


def write_partition(path, table: PassTable, labels: np.ndarray) -> Path:
    """``label,size,passes``: one row per track, its pass ids separated by spaces."""
    rows = []
    for lab in np.unique(labels):
        members = table.ids[labels == lab]
        rows.append((int(lab), members.size, " ".join(map(str, members))))
    return write_rows(path, ("label", "size", "passes"), rows)


def read_labels(path: str | Path, column: str = "label") -> dict[int, int]:
    """``pass -> label`` of a labels CSV (``column`` 'person' reads a truth file: an
    observations CSV with a ``person`` column, or any ``pass,person`` CSV)."""
    header, rows = read_rows(path, what="labels CSV")
    if column not in header:
        raise fail(path, 1, f"no {column!r} column; header is {header}")
    if "pass" not in header:
        if "event" in header:
            raise fail(path, 1, "an events file needs a pass column")
        return {i: r.int(column) for i, r in enumerate(rows) if r[column] != ""}
    out: dict[int, int] = {}
    for r in rows:
        if r[column] == "":
            continue
        pid = r.int("pass")
        if pid in out and out[pid] != r.int(column):
            raise r.fail(f"pass {pid} has two {column}s")
        out[pid] = r.int(column)
    if not out:
        raise InputError(f"{path}: no {column} labels")
    return out
