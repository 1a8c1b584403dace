"""``dbntrack track pathrecovery EDGES.csv OBSERVATIONS.csv [CAMERAS.csv]``: the path of
one target through a camera network (seed 001; formats in :mod:`models.io.pathrecovery`).

The first phase runs through the registry's protocol adapter (one step per time step),
the second (dynamic programming over the k-best lists) is
:func:`models.pathrecovery.recover_path`. The target starts at its observation at
``t = 0``: the only one there, or config ``target_obs`` (an obs id), or config ``c0`` and
``f0``. ``sigma`` (the typical feature covariance of eq. 2) defaults to the covariance
of all features. Other config keys: the fields of
:class:`~models.pathrecovery.filter.FilterConfig` and ``k_dp`` (7, the second phase's k).
``dbntrack fit pathrecovery`` searches the weighting's ``sharpness`` and
``hidden_likelihood`` on runs whose true path is known, and on request counts the network
from their objects' moves (:mod:`models.track.pathrecovery_fit`).
"""

from __future__ import annotations

import numpy as np

from dbn.errors import ConfigError, InputError
from models.io.pathrecovery import read_network, read_observations, read_path, write_path
from models.track.context import RunContext
from models.track.options import array, build, check_keys, integer

OTHER_KEYS = ("c0", "f0", "target_obs", "sigma", "k_dp")
"""The config keys of ``dbntrack track pathrecovery`` besides the fields of
:class:`~models.pathrecovery.filter.FilterConfig`: the start, ``sigma`` and ``k_dp``."""

INPUTS = ("EDGES.csv: from,to,prob[,gap_mean] camera network (with self loops)",
          "OBSERVATIONS.csv: t,camera,f0,f1,... (the target's start at t = 0)",
          "[CAMERAS.csv: camera,x,y positions, for the figure]")  # fmt: skip


def target_start(odb, config: dict, path: str) -> tuple[int, np.ndarray]:
    """The target's camera and feature at ``t = 0``: config ``c0`` and ``f0`` (both), or
    config ``target_obs``, or the only observation at ``t = 0`` of ``path``'s."""
    given = [k for k in ("c0", "f0", "target_obs") if k in config]
    if given and given not in (["c0", "f0"], ["target_obs"]):
        raise ConfigError(f"config {given}: give c0 and f0 together, or target_obs alone")
    if "c0" in config:
        f0, dim = array(config, "f0"), odb.feat.shape[1]
        if f0.shape != (dim,):
            raise ConfigError(f"config f0: expected {dim} numbers (the observations' features), "
                              f"got shape {f0.shape}")  # fmt: skip
        return integer(config, "c0"), f0
    lo, hi = int(odb.time_ptr[0]), int(odb.time_ptr[1])
    if "target_obs" in config:
        hit = np.flatnonzero(odb.ids[lo:hi] == integer(config, "target_obs"))
        if hit.size != 1:
            raise ConfigError(f"config target_obs = {config['target_obs']}: no such obs at t = 0")
        i = lo + int(hit[0])
    elif hi - lo == 1:
        i = lo
    else:
        raise InputError(f"{path}: t = 0 has {hi - lo} observations: give target_obs "
                         "(or c0 and f0) in --config")  # fmt: skip
    return int(odb.cam[i]), odb.feat[i]


def feature_cov(feat: np.ndarray, path: str) -> np.ndarray:
    """The features' covariance (n, d) -> (d, d), the default ``sigma``; an
    :class:`InputError` naming ``path`` where it is not positive definite (too few
    observations, or a constant feature), instead of the model's "sigma is not SPD"."""
    sigma = np.atleast_2d(np.cov(feat.T)) if len(feat) > 1 else None
    if sigma is None or not np.all(np.isfinite(sigma)) or not _positive_definite(sigma):
        n = f"{len(feat)} observation" + ("" if len(feat) == 1 else "s")
        raise InputError(f"{path}: the covariance of the features of its {n} is not positive "
                         "definite (too few observations, or a constant feature): give sigma "
                         "in --config")
    return sigma


def _positive_definite(sigma: np.ndarray) -> bool:
    """Whether a finite symmetric matrix has a Cholesky factor (the test ``make_model``
    applies to ``sigma``)."""
    try:
        np.linalg.cholesky(sigma)
    except np.linalg.LinAlgError:
        return False
    return True


def track(ctx: RunContext, inputs: list[str], config: dict) -> dict:
    """Recover the target's path; write ``path.csv`` and ``path.png``."""
    from models.pathrecovery.recover import recover_path

    if len(inputs) not in (2, 3):
        raise InputError(f"pathrecovery needs EDGES.csv OBSERVATIONS.csv [CAMERAS.csv], "
                         f"got {len(inputs)} input(s)")  # fmt: skip
    fcfg, k_dp = run_options(config)
    with ctx.timed("read"):
        net = read_network(inputs[0], inputs[2] if len(inputs) == 3 else None)
        odb = read_observations(inputs[1])
    check_cameras(net, odb, inputs[0], inputs[1])
    c0, f0 = target_start(odb, config, inputs[1])
    sigma = array(config, "sigma") if "sigma" in config else feature_cov(odb.feat, inputs[1])
    with ctx.timed("filter"):
        model, lists = filter_lists(net, odb, (c0, f0, sigma), fcfg, ctx.key(), ctx.bar("steps"))
    with ctx.timed("recover"):
        path = recover_path(model, lists, odb.feat, k=min(k_dp, fcfg.k))
    T = odb.time_ptr.size - 1
    write_path(ctx.outdir / "path.csv", np.arange(1, T), path.kind, path.cam, path.ta,
               path_ids(path, odb))  # fmt: skip
    _plot(ctx, net, path, c0)
    params = {"num_steps": T, "num_cameras": net.num_cameras, "c0": c0, "k_dp": k_dp,
              **fcfg._asdict(), "jumps": int(path.jumped.sum())}  # fmt: skip
    return {"parameters": params, "outputs": ["path.csv", "path.png"]}


def run_options(config: dict) -> tuple:
    """The config's :class:`~models.pathrecovery.filter.FilterConfig` and ``k_dp``, its keys
    checked before any file is read (those fields and :data:`OTHER_KEYS`)."""
    from models.pathrecovery.filter import FilterConfig

    check_keys(config, {*FilterConfig._fields, *OTHER_KEYS})
    fcfg = build(FilterConfig, {k: config[k] for k in FilterConfig._fields if k in config})
    return fcfg, integer(config, "k_dp", 7)


def check_cameras(net, odb, edges: str, observations: str) -> None:
    """Refuse observations in a camera the network does not have."""
    if odb.cam.max() >= net.num_cameras:
        raise InputError(f"{observations}: camera {int(odb.cam.max())} is not in the network "
                         f"{edges} (cameras 0..{net.num_cameras - 1})")  # fmt: skip


def recover(net, odb, start: tuple, fcfg, k_dp: int, key):
    """Both phases on one run: :func:`filter_lists`, then
    :func:`models.pathrecovery.recover_path` over its k-best lists with
    ``min(k_dp, fcfg.k)``. Returns the :class:`~models.pathrecovery.recover.RecoveredPath`
    of steps ``1 .. T-1``."""
    from models.pathrecovery.recover import recover_path

    model, lists = filter_lists(net, odb, start, fcfg, key)
    return recover_path(model, lists, odb.feat, k=min(k_dp, fcfg.k))


def filter_lists(net, odb, start: tuple, fcfg, key, progress=None) -> tuple:
    """The first phase on one run: the registry's tracker stepped through the protocol
    over ``t = 1 .. T-1`` (``progress`` as :meth:`models.protocol.StepTracker.fold` takes
    it). ``start`` is ``(c0, f0, sigma)``. Returns the model and its
    :class:`~models.pathrecovery.filter.KBestLists`."""
    import models
    from models.pathrecovery.api import PathObservation
    from models.pathrecovery.filter import KBestLists, make_model

    model = make_model(net, *start, fcfg)
    tracker = models.get("pathrecovery").make(model=model)
    T = odb.time_ptr.size - 1
    bounds = [(t, int(odb.time_ptr[t]), int(odb.time_ptr[t + 1])) for t in range(1, T)]
    steps = [PathObservation(odb.cam[lo:hi], odb.feat[lo:hi], lo, t) for t, lo, hi in bounds]
    _, infos = tracker.fold(key, steps, progress)
    lists = KBestLists(*(np.stack([getattr(i, f) for i in infos])
                         for f in ("kind", "cam", "ta", "obs", "mass", "num_tracked_cameras")),
                       step_seconds=np.zeros(T - 1))  # fmt: skip
    return model, lists


def path_ids(path, odb) -> np.ndarray:
    """The observation id (``obs`` of the observations CSV) of each recovered step, -1
    where it has none."""
    return np.where(path.obs >= 0, odb.ids[np.maximum(path.obs, 0)], -1)


def _plot(ctx: RunContext, net, path, c0: int) -> None:
    with ctx.figure("path.png", ncols=2, figsize=(12, 4.5)) as (_, (ax0, ax1)):
        xy = net.coords
        for a, b in zip(net.rows, net.indices):
            if a != b:
                ax0.plot(*xy[[a, b]].T, color="0.85", lw=1, zorder=0)
        ax0.scatter(*xy.T, s=12, color="0.5")
        cams = np.concatenate([[c0], path.cam[path.kind == 0]])
        ax0.plot(*xy[cams].T, "b.-", lw=1.5, label="recovered (visible states)")
        ax0.plot(*xy[c0], "go", label="start")
        ax0.legend(fontsize=8)
        ax0.set_title("camera network and recovered path")
        t = np.arange(1, path.kind.size + 1)
        vis = path.kind == 0
        ax1.plot(t[vis], path.cam[vis], "b.", label="visible: camera")
        ax1.plot(t[~vis], path.cam[~vis], "r.", ms=3, label="hidden: destination")
        ax1.set_xlabel("step")
        ax1.set_ylabel("camera")
        ax1.legend(fontsize=8)


def evaluate(result: str, truth: str) -> dict:
    """Seed 001's path score (sec. 7.2): fraction of steps whose state is correct, overall,
    on visible and on hidden steps (:func:`models.pathrecovery.metrics.path_score`), and
    the camera accuracy on visible steps, over the steps ``t >= 1`` of the truth."""
    return score_path(read_path(result), read_path(truth), result, truth)


def score_path(pred: dict, true: dict, result: str, truth: str) -> dict:
    """:func:`evaluate` of two paths as :func:`models.io.pathrecovery.read_path` gives
    them (``t -> (kind, camera, ta, obs)``), ``result`` and ``truth`` naming them in
    errors."""
    from models.pathrecovery.metrics import path_score

    steps = sorted(t for t in true if t >= 1)
    if not steps:
        raise InputError(f"{truth}: no step t >= 1 to score (the path score counts the "
                         f"steps after the target's start at t = 0)")
    missing = [t for t in steps if t not in pred]
    if missing:
        raise InputError(f"{result}: no state for step(s) {missing[:5]} of {truth}")
    kind = np.array([pred[t][0] for t in steps])
    obs = np.array([pred[t][3] for t in steps])
    true_obs = np.array([true[t][3] if true[t][0] == 0 else -1 for t in steps])
    ps = path_score(kind, obs, true_obs)
    vis = true_obs >= 0
    cam_ok = np.array([pred[t][1] == true[t][1] for t in steps])
    return {"path_score": ps.overall, "path_score_visible": ps.visible,
            "path_score_hidden": ps.hidden,
            "camera_accuracy_visible": float(cam_ok[vis].mean()) if vis.any() else float("nan"),
            "num_steps": len(steps)}  # fmt: skip


def fit(ctx: RunContext, train: list[str], validate: list[str], config: dict, seeds: int = 1,
        prior_strength=(0.0,), folds: int = 0, fold_by: str | None = None) -> dict:
    """``dbntrack fit``: the default weighting's ``sharpness`` and ``hidden_likelihood``
    searched on runs whose true path is known, and on request the network counted from
    their objects' moves (:mod:`models.track.pathrecovery_fit`)."""
    from models.track.pathrecovery_fit import fit as fit_runs

    return fit_runs(ctx, train, validate, config, seeds, prior_strength, folds, fold_by)


def fit_report(summary: dict) -> list[str]:
    """The lines ``dbntrack fit pathrecovery`` prints
    (:func:`models.track.pathrecovery_fit.fit_report`)."""
    from models.track.pathrecovery_fit import fit_report as report

    return report(summary)


__all__ = ["INPUTS", "OTHER_KEYS", "track", "evaluate", "fit", "fit_report", "score_path",
           "run_options", "check_cameras", "target_start", "feature_cov", "recover", "filter_lists",
           "path_ids"]
