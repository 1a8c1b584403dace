"""Path-recovery files (seed 001): a camera network, observations, a recovered path.

Network ``edges.csv``: ``from,to,prob[,gap_mean]`` (0-based cameras): ``prob`` is
``W^p(from, to)``, the rows of each ``from`` sum to 1, every camera has its self loop
``c,c``; ``gap_mean`` is the mean travel time in steps of an edge crossing a blind gap
(0 or empty: one step). Optional ``cameras.csv``: ``camera,x,y`` (plots only).

Observations ``observations.csv``: ``t,camera,f0,f1,...`` (steps ``t = 0 .. T-1``),
optional ``obs`` id (default: the data row's 0-based index) and ``object`` (truth).

Path (output, and truth for eval): ``t,state,camera,ta,obs``: ``state`` visible or hidden,
``camera`` the camera (visible) or destination (hidden), ``ta`` steps to arrival, ``obs``
the id of the associated observation (-1 while hidden).
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import NamedTuple

import numpy as np

from dbn.errors import DBNError, InputError, TimeOrderError
from models.io.table import fail, read_rows, write_rows

__all__ = ["Observations", "read_network", "read_observations", "write_path", "read_path",
           "write_network", "write_scene"]

_FEAT = re.compile(r"^f(\d+)$")
_KIND = {"visible": 0, "hidden": 1, "none": -1}


def read_network(edges: str | Path, cameras: str | Path | None = None):
    """A :class:`models.pathrecovery.model.CameraNetwork` from ``edges.csv`` (and
    ``cameras.csv``); coordinates default to a circle."""
    from models.pathrecovery.model import CameraNetwork

    header, rows = read_rows(edges, ("from", "to", "prob"), "edges CSV")
    if not rows:
        raise fail(edges, 0, "no edges")
    e = np.array([(r.int("from"), r.int("to"), r.float("prob"),
                   r.float("gap_mean", allow_empty=True) if "gap_mean" in header else 0.0)
                  for r in rows])  # fmt: skip
    src, dst = e[:, 0].astype(np.int64), e[:, 1].astype(np.int64)
    if (src < 0).any() or (dst < 0).any():
        raise fail(edges, rows[int(np.argmax((src < 0) | (dst < 0)))].line, "negative camera")
    gap = np.nan_to_num(e[:, 3])
    top = int(np.argmax(np.maximum(src, dst)))
    n = int(max(src[top], dst[top])) + 1
    if n > len(rows):  # before any array of n cameras is made (an id of 4e18 did)
        raise fail(edges, rows[top].line, f"camera {n - 1} needs cameras 0..{n - 1}, each with an outgoing "
                   f"edge, but only {len(rows)} edges are listed (number the cameras from 0)")
    order = np.lexsort((dst, src))
    dup = np.flatnonzero((np.diff(src[order]) == 0) & (np.diff(dst[order]) == 0))
    if dup.size:
        i = int(max(order[dup[0]], order[dup[0] + 1]))  # the second listing
        raise fail(edges, rows[i].line, f"edge {src[i]} -> {dst[i]} is listed twice")
    coords = np.column_stack([np.cos(2 * np.pi * np.arange(n) / n),
                              np.sin(2 * np.pi * np.arange(n) / n)])  # fmt: skip
    if cameras is not None:
        _, crow = read_rows(cameras, ("camera", "x", "y"), "cameras CSV")
        placed: set[int] = set()
        for r in crow:
            c = r.int("camera")
            if not 0 <= c < n:
                raise r.fail(f"camera {c} is not in the network (0..{n - 1})")
            if c in placed:  # the last row silently won
                raise r.fail(f"camera {c} is listed twice")
            placed.add(c)
            coords[c] = r.float("x"), r.float("y")
        unplaced = sorted(set(range(n)) - placed)
        if unplaced:  # they were drawn on a circle among the real positions
            raise fail(cameras, 0, f"no position for camera(s) {unplaced[:10]}"
                       f"{' ...' if len(unplaced) > 10 else ''}: list every camera of the "
                       "network, or give no cameras CSV (a circle)")
    indptr = np.concatenate([[0], np.cumsum(np.bincount(src, minlength=n))])
    try:
        return CameraNetwork(indptr, dst[order], e[order, 2], gap[order], coords, name=str(edges))
    except DBNError as exc:
        raise InputError(f"{edges}: {exc}") from None


class Observations(NamedTuple):
    """Observations sorted by step then camera (the filter's ODB layout): ``time_ptr``
    (T + 1,), ``cam`` (n,), ``feat`` (n, d), ``ids`` (n,) file ids, ``obj`` (n,) or None."""

    time_ptr: np.ndarray
    cam: np.ndarray
    feat: np.ndarray
    ids: np.ndarray
    obj: np.ndarray | None


def read_observations(path: str | Path) -> Observations:
    """Read ``observations.csv`` (module docstring) into the ODB layout."""
    from models.pathrecovery.filter import MAX_FEATURE  # not at import: the filter needs jax

    header, rows = read_rows(path, ("t", "camera"), "observations CSV")
    fcols = sorted((c for c in header if _FEAT.match(c)), key=lambda c: int(c[1:]))
    if not fcols or [int(c[1:]) for c in fcols] != list(range(len(fcols))):
        raise fail(path, 1, f"need feature columns f0, f1, ... (found {fcols or 'none'})")
    if not rows:
        raise fail(path, 0, "no observations")
    t = np.array([r.int("t") for r in rows])
    cam = np.array([r.int("camera") for r in rows])
    bad = np.flatnonzero((t < 0) | (cam < 0))
    if bad.size:
        raise rows[int(bad[0])].fail("t and camera must be >= 0")
    feat = np.array([[r.float(c) for c in fcols] for r in rows])
    big = np.flatnonzero(np.abs(feat).max(axis=1) > MAX_FEATURE)
    if big.size:  # the filter refuses them; say where
        raise rows[int(big[0])].fail(f"a feature of |value| > {MAX_FEATURE:g} (features are "
                                     "expected of order 1-1000; rescale them)")  # fmt: skip
    ids = np.array([r.int("obs") for r in rows]) if "obs" in header else np.arange(len(rows))
    if ids.size and ids.min() < 0:  # -1 marks a hidden step in a path
        raise rows[int(np.argmin(ids))].fail(f"obs = {int(ids.min())}: obs ids count from 0")
    if np.unique(ids).size != ids.size:
        raise fail(path, 0, "obs ids are not unique")
    obj = np.array([r.int("object") for r in rows]) if "object" in header else None
    order = np.lexsort((cam, t))
    T = int(t.max()) + 1
    time_ptr = np.concatenate([[0], np.cumsum(np.bincount(t, minlength=T))])
    pick = lambda a: None if a is None else a[order]  # noqa: E731
    return Observations(time_ptr, cam[order], feat[order], ids[order], pick(obj))


def write_path(path, t: np.ndarray, kind, cam, ta, obs_ids) -> Path:
    """Write ``t,state,camera,ta,obs`` rows."""
    names = {v: k for k, v in _KIND.items()}
    rows = [(int(a), names[int(k)], int(c), int(b), int(o))
            for a, k, c, b, o in zip(t, kind, cam, ta, obs_ids)]  # fmt: skip
    return write_rows(path, ("t", "state", "camera", "ta", "obs"), rows)


def _path_step(r, kind: int, cam: int, ta: int, obs: int) -> tuple[int, int, int, int]:
    """One checked step of :func:`read_path`: a visible step names its observation (obs
    >= 0), a hidden one has none (obs -1); camera >= -1 (-1: unknown), ta >= 0."""
    if kind == 0 and obs < 0:
        raise r.fail(f"obs = {obs}: a visible step names its observation (an id >= 0)")
    if kind == 1 and obs != -1:
        raise r.fail(f"obs = {obs}: a hidden step has no observation (obs = -1)")
    if cam < -1 or ta < 0:
        raise r.fail(f"camera = {cam}, ta = {ta}: expected camera >= -1 (-1 or empty: "
                     "unknown) and ta >= 0")  # fmt: skip
    return kind, cam, ta, obs


def read_path(path: str | Path) -> dict[int, tuple[int, int, int, int]]:
    """``t -> (kind, camera, ta, obs)`` of a path CSV (kind 0 visible, 1 hidden); rows in
    increasing ``t >= 0`` (a repeated, earlier or negative step is a TimeOrderError
    naming file and line: it would silently replace a step); each step checked by
    :func:`_path_step`."""
    _, rows = read_rows(path, ("t", "state", "obs"), "path CSV")
    out, last = {}, -1
    for r in rows:
        t = r.int("t")
        if t <= last:
            raise TimeOrderError(f"{r.path}:{r.line}: t = {t} (steps must increase from 0)")
        if r["state"] not in _KIND:
            raise r.fail(f"state = {r['state']!r}, expected visible or hidden")
        cam = r.int("camera") if r.get("camera", "") != "" else -1
        ta = r.int("ta") if r.get("ta", "") != "" else 0
        out[t], last = _path_step(r, _KIND[r["state"]], cam, ta, r.int("obs")), t
    if not out:
        raise fail(path, 0, "no steps")
    return out


def write_network(path: str | Path, net) -> Path:
    """Write a :class:`models.pathrecovery.model.CameraNetwork`'s edges as ``edges.csv``
    (``from,to,prob,gap_mean``; :func:`read_network` reads it back)."""
    return write_rows(path, ("from", "to", "prob", "gap_mean"),
                      [(int(a), int(b), float(p), float(g))
                       for a, b, p, g in zip(net.rows, net.indices, net.probs, net.gap_mean)])


def write_scene(folder: str | Path, scene) -> Path:
    """Write a :class:`models.pathrecovery.simulate.Scene` (SIMULATED) as a run's files in
    ``folder`` (made if absent): ``edges.csv``, ``cameras.csv``, ``observations.csv`` (every
    observation, its row index as ``obs``, its ``object``) and ``truth_path.csv`` (the
    target's path from ``t = 0``: what ``dbntrack track pathrecovery`` reads, ``dbntrack
    eval`` scores against and ``dbntrack fit pathrecovery`` fits on). Returns ``folder``."""
    out = Path(folder)
    out.mkdir(parents=True, exist_ok=True)
    net, odb = scene.network, scene.odb
    write_network(out / "edges.csv", net)
    write_rows(out / "cameras.csv", ("camera", "x", "y"),
               [(i, float(x), float(y)) for i, (x, y) in enumerate(net.coords)])  # fmt: skip
    t_of = np.repeat(np.arange(odb.num_timesteps), np.diff(odb.time_ptr))
    d = odb.feat.shape[1]
    write_rows(out / "observations.csv", ("obs", "t", "camera", *(f"f{i}" for i in range(d)),
                                          "object"),
               [(i, int(t_of[i]), int(odb.cam[i]), *map(float, odb.feat[i]),
                 int(odb.obj[i])) for i in range(odb.cam.size)])  # fmt: skip
    T = odb.num_timesteps
    write_path(out / "truth_path.csv", np.arange(T), np.where(scene.true_ta == 0, 0, 1),
               scene.true_cam, scene.true_ta, scene.true_obs)  # fmt: skip
    return out
