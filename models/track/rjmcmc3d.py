"""``dbntrack track rjmcmc3d VIEW_DIR...``: 3-D positions and identities of people seen by
calibrated cameras (seed 003; formats in :mod:`models.io.rjmcmc3d`).

Config keys: ``floor`` ``[x_min, x_max, y_min, y_max]`` (metres; default: the bounding box
of the camera centres on the ground), ``scale`` (image rescaling of the calibration, 1),
``min_blob`` (pixels, 40), ``sigma_px`` (detector foot noise, 4), and the fields of
:class:`~models.rjmcmc3d.model.TrackerParams` (e.g. ``num_moves``, ``burn_in``, ``tau``).
"""

from __future__ import annotations

import re

import numpy as np

from dbn.errors import ConfigError, InputError
from models.io.rjmcmc3d import detections, read_png, read_tracks3d, read_view, warp, write_tracks3d
from models.track.context import RunContext
from models.track.options import array, build, check_keys, integer, number

INPUTS = ("VIEW_DIR ...: one folder per camera: a Tsai calibration .xml and one foreground "
          "mask .png per frame",)  # fmt: skip


def _frame_numbers(masks: list) -> list[int] | None:
    """The last number in each mask's name (``mask_0005.png``: 5); None if a name has none."""
    found = [re.findall(r"\d+", m.stem) for m in masks]
    return [int(f[-1]) for f in found] if all(found) else None


def _check_frame_numbers(views: list) -> None:
    """Refuse views whose masks, matched by position, carry different frame numbers (one
    exported from frame 1, another from frame 0: every frame would pair images of two
    instants). Views whose names carry no numbers are matched by position alone."""
    numbers = [_frame_numbers(v.masks) for v in views]
    if any(n is None for n in numbers):
        return
    for v, n in zip(views[1:], numbers[1:]):
        if n != numbers[0]:
            k = next(i for i, (a, b) in enumerate(zip(numbers[0], n)) if a != b)
            raise InputError(f"{views[0].masks[k]} and {v.masks[k]} are mask {k + 1} of their "
                             f"views, of frames {numbers[0][k]} and {n[k]}: the views' masks "
                             "are matched by position and must be of the same frames")  # fmt: skip


def _spans_area(floor: np.ndarray) -> bool:
    """Whether ``floor`` is ``[x_min, x_max, y_min, y_max]`` of a rectangle of some area."""
    return floor.shape == (4,) and bool(floor[1] > floor[0] and floor[3] > floor[2])


def _floor(floor: np.ndarray) -> np.ndarray:
    if not _spans_area(floor):
        raise ConfigError(f"config floor = {floor.tolist()}: need [x_min, x_max, y_min, y_max]")
    return floor


def _scene(ctx, views, floor: np.ndarray | None, sigma_px: float):
    """The scene of the views; ``floor`` (from the config) else the span of the camera
    centres."""
    from models.rjmcmc3d.scene import scene_from_cameras

    cams = [v.camera for v in views]
    centres = np.array([-c.R.T @ c.t for c in cams])
    if floor is None:  # the span of the camera centres
        floor = np.array([*np.sort(centres[:, 0])[[0, -1]], *np.sort(centres[:, 1])[[0, -1]]])
        if not _spans_area(floor):
            files = ", ".join(str(v.calibration) for v in views)
            raise InputError(f"{files}: the camera centres span no floor area "
                             f"({floor.tolist()}): give floor [x_min, x_max, y_min, y_max] "
                             "in --config")  # fmt: skip
    V = len(cams)
    sigma = np.full(V, sigma_px)
    return scene_from_cameras(ctx.seed, cams, floor, np.ones((V, 3)), sigma)


def _ground(scene, dv: np.ndarray, dpx: np.ndarray):
    """``(det_view, det_px, det_ground)`` of the detections whose feet map to a ground point
    in front of their camera (:func:`~models.rjmcmc3d.geometry.in_front`) and within
    :data:`~models.rjmcmc3d.frames.MAX_METRES`. A blob above a view's horizon (a moving
    tree, a reflection in the sky) maps behind the camera, possibly into the floor; one on
    the horizon maps to infinity. Neither is a place the camera sees, so neither is a
    detection. Shapes: ``dv`` (n,) int, ``dpx`` (n, 2) rectified pixels."""
    from models.rjmcmc3d.frames import MAX_METRES
    from models.rjmcmc3d.geometry import apply_homography, ground_homography, in_front

    ground = np.zeros((len(dv), 2))
    keep = np.zeros(len(dv), dtype=bool)
    for v in np.unique(dv):
        sel = dv == v
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            g = apply_homography(np.linalg.inv(ground_homography(scene.P[v])), dpx[sel])
        near = np.all(np.abs(g) <= MAX_METRES, axis=1)  # False for NaN and inf
        keep[sel] = near & in_front(scene.cameras[v], np.where(near[:, None], g, 0.0))
        ground[sel] = g
    return dv[keep], dpx[keep], ground[keep]


def _frames(views, scene, min_blob: int):
    from models.rjmcmc3d.scene import Frame

    shape = (scene.height, scene.width)
    for t in range(len(views[0].masks)):
        D, img, dv, dpx = [], [], [], []
        for v, view in enumerate(views):
            H = scene.rects[v].H
            m = warp(read_png(view.masks[t], shape), H, shape)
            c = read_png(view.colour[t], shape, 3) if view.colour else np.repeat(m[..., None], 3, 2)
            D.append(m)
            img.append(warp(c, H, shape, fill=0.5))
            feet = detections(m, min_blob)
            dv += [v] * len(feet)
            dpx.append(feet)
        dpx = np.concatenate(dpx) if dpx else np.zeros((0, 2))
        dv, dpx, ground = _ground(scene, np.array(dv, dtype=np.int64), dpx)
        yield Frame(np.stack(D).astype(np.float32), np.stack(img).astype(np.float32), dv, dpx,
                    ground, t)  # fmt: skip


def track(ctx: RunContext, inputs: list[str], config: dict) -> dict:
    """Track people in 3-D; write ``tracks3d.txt`` and ``tracks3d.png``."""
    import models
    from models.protocol import split_run_keys
    from models.rjmcmc3d.model import TrackerParams

    check_keys(config, set(TrackerParams._fields) | {"floor", "scale", "min_blob", "sigma_px"})
    params = build(TrackerParams, {k: config[k] for k in TrackerParams._fields if k in config})
    scale, min_blob = number(config, "scale", 1.0), integer(config, "min_blob", 40)
    sigma_px = number(config, "sigma_px", 4.0)
    floor = _floor(array(config, "floor")) if "floor" in config else None
    with ctx.timed("read"):
        views = [read_view(p, scale) for p in inputs]
        counts = [len(v.masks) for v in views]
        if len(set(counts)) != 1:  # name the folders: frames are matched by position
            each = ", ".join(f"{p}: {c}" for p, c in zip(inputs, counts))
            raise InputError(f"the views have different numbers of masks ({each}); "
                             "every folder needs one mask per frame")
        _check_frame_numbers(views)
        scene = _scene(ctx, views, floor, sigma_px)
    tracker = models.get("rjmcmc3d").make(scene=scene, params=params)
    T = len(views[0].masks)
    k_init, keys = split_run_keys(ctx.key(), T)
    frames, ids, X, pres = [], [], [], []
    with ctx.timed("track"):
        state = tracker.init(k_init)
        frame_iter = _frames(views, scene, min_blob)
        for t, frame in ctx.progress(enumerate(frame_iter), T, "frames"):
            state, res = tracker.step(keys[t], state, frame)
            frames.append(t + 1)
            ids.append(res.ids)
            X.append(res.X)
            pres.append(res.presence)
    write_tracks3d(ctx.outdir / "tracks3d.txt", frames, ids, X, pres)
    _plot(ctx, scene, ids, X)
    out = {"num_views": len(views), "num_frames": T, "floor": scene.floor.tolist(),
           **params._asdict()}  # fmt: skip
    return {"parameters": out, "outputs": ["tracks3d.txt", "tracks3d.png"]}


def _plot(ctx: RunContext, scene, ids, X) -> None:
    import matplotlib

    cmap = matplotlib.colormaps["tab10"]
    with ctx.figure("tracks3d.png", figsize=(6, 6)) as (_, ax):
        fl = scene.floor
        ax.plot(
            [fl[0], fl[1], fl[1], fl[0], fl[0]], [fl[2], fl[2], fl[3], fl[3], fl[2]], "k--", lw=1
        )
        ax.plot(scene.centers[:, 0], scene.centers[:, 1], "k^", label="cameras")
        tracks: dict[int, list] = {}
        for i, x in zip(ids, X):
            for k in range(len(i)):
                tracks.setdefault(int(i[k]), []).append(x[k, :2])
        for i, pts in tracks.items():
            p = np.array(pts)
            ax.plot(p[:, 0], p[:, 1], ".-", color=cmap(i % 10), label=f"id {i}")
        ax.set_aspect("equal")
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        ax.legend(fontsize=7)
        ax.set_title("ground-plane tracks")


def evaluate(result: str, truth: str, threshold: float = 0.5) -> dict:
    """MOTA, IDF1, ID switches, ... on ground-plane positions (match within 0.5 m), by
    :func:`models.rjmcmc3d.metrics.evaluate` (the benchmark's metric), over the truth's
    span of frames (a frame missing from the result has no hypothesis; a result's frame
    inside the span that the truth lacks has no person; frames outside are not scored)."""
    from models.rjmcmc3d.metrics import evaluate as mot_eval
    from models.rjmcmc3d.scene import FrameTruth
    from models.rjmcmc3d.tracker import FrameResult

    pred, ref = read_tracks3d(result), read_tracks3d(truth)
    if not ref:
        raise InputError(f"{truth}: no rows")
    lo, hi = min(ref), max(ref)  # frames in neither file add nothing: not a range(lo, hi)
    frames = sorted(set(ref) | {f for f in pred if lo <= f <= hi})
    empty = (np.zeros(0, np.int64), np.zeros((0, 2)))
    gts, hyps = [], []
    for f in frames:
        i, u = ref.get(f, empty)
        gts.append(FrameTruth(i, u, np.zeros(len(i)), np.zeros(len(i))))
        j, x = pred.get(f, empty)
        X = np.zeros((len(j), 6))
        X[:, :2] = x
        hyps.append(FrameResult(j, X, np.ones(len(j)), np.full(6, np.nan), 0.0))
    return mot_eval(gts, hyps, threshold)


__all__ = ["INPUTS", "track", "evaluate"]
