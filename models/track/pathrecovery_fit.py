r"""``dbntrack fit pathrecovery TRAIN... --validate HELD...``: the filter's weighting chosen
by the path score on runs of yours whose target's path you know, written as a config for
``dbntrack track pathrecovery --config``, and on request the camera network's transition
probabilities and gap means counted from every object's moves.

A run (each TRAIN and HELD) is a folder holding ``edges.csv``, ``observations.csv`` and
``truth_path.csv`` (:mod:`models.io.pathrecovery`: the files ``dbntrack track
pathrecovery`` reads and the truth ``dbntrack eval pathrecovery`` scores against;
:func:`models.io.pathrecovery.write_scene` writes a SIMULATED scene so). The runs share one
network (the same ``edges.csv``). The target starts at its true observation at ``t = 0``
(the truth's first row, which must be visible), and the truth must hold every step ``t =
0 .. T-1`` of the observations. The config's other keys (``num_particles``, ``k``,
``alpha``, ..., ``sigma``, ``k_dp``) apply to every run.

The fit:

1. the network (only with config ``fit_network: true``, default false, and an ``object``
   column in every training run's observations): ``W^p`` and the gap means counted from
   the training runs' objects' moves (:mod:`models.pathrecovery.fit`; the edges, and which
   of them have a gap, are kept), else the runs' own;
2. a documented search rather than a likelihood: the default weighting's two settings
   (:class:`~models.pathrecovery.filter.FilterConfig`: ``sharpness`` ``kappa``, the power
   the weights are raised to, and ``hidden_likelihood`` ``q``, the weight of a hidden
   particle) were chosen on SIMULATED scenes with the simulator's ``sigma``
   (:mod:`models.pathrecovery.filter`), where ``dbntrack track`` takes, without a config
   ``sigma``, the covariance of all of a run's features. Both phases run on every
   training run with that network for each pair of ``search_sharpness`` x
   ``search_hidden_likelihood`` (config keys; default :data:`SEARCH_SHARPNESS` x
   :data:`SEARCH_HIDDEN_LIKELIHOOD`, the grid of that choice: 36 pairs), and the pair of
   the least mean path error is kept (ties: the config's pair where it is among them,
   else the smaller ``kappa``, then the smaller ``q``); a choice at an edge of the grid is
   reported (``on_edge``).

A run's path error is one minus seed 001's path score (sec. 7.2,
:func:`models.track.pathrecovery.evaluate`): the fraction of steps ``t >= 1`` whose
recovered state is wrong, the mean over ``--seeds`` runs of seeds ``--seed``, ``--seed +
1``, ... (as ``dbntrack track --seed``), with its own network and the config's settings,
and with the fitted (``OUTDIR/edges.csv`` and ``OUTDIR/config.json``, the config with
``sharpness`` and ``hidden_likelihood`` written over it). There is no prior strength and
no cross-validation: the training runs choose, the held-out runs say how well the choice
holds (a held-out run of which half the observations or more are a training run's is named
as not held out).

What the SIMULATED scenes said (3 x 3 intersections, 78 cameras, 300 walkers, 40 steps,
confusion 0.3, and 7 x 7, 490 cameras, 2000 walkers, 60 steps, confusion 0.17; four
training and four held-out scenes each, three seeds):

* the default grid chose ``kappa = 8``, ``q = 0.6``, its corner, lowering the held-out path
  error from 0.308 to 0.199 (78 cameras) and from 0.333 to 0.106 (490); a grid widened to
  ``kappa`` 24 and ``q`` 0.9 chose ``kappa = 16``: a lower training error, a higher
  held-out one (0.229, 0.218);
* the counted network, close to the simulator's, did not lower the path error where the
  given network was right or a fair guess (78 cameras: held out 0.209 with it, 0.199 with
  the simulator's own network; from uniform transitions with every gap the mean gap, 0.207
  with it, 0.179 keeping the guess), hence off by default (decided before the next case
  ran); from uniform transitions with every gap twice the mean gap it did (0.226 with it,
  0.321 keeping the guess): turn it on where your gap means are guesses;
* ``sigma`` measured as the covariance of the target's own features about its mean (pooled
  over the training runs' true paths) did worse (held out 0.55 and 0.36, against 0.20 and
  0.11 with each run's covariance of all features): eq. 5-6's mixture support needs a
  similarity wider than one object's spread. ``sigma`` is not fitted.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import NamedTuple

import jax
import numpy as np

from dbn.errors import ConfigError, DBNError, InputError, in_file
from models.io.pathrecovery import read_network, read_observations, read_path, write_network
from models.pathrecovery.fit import PRIOR_MOVES, count_moves, fitted_network, pool_moves
from models.track.context import RunContext
from models.track.fitting import (
    check_disjoint,
    copies_of_training,
    mean_errors,
    plot_fit,
    refuse_strengths,
    report,
    search_grid,
    search_values,
)
from models.track.options import array, flag
from models.track.pathrecovery import (
    check_cameras,
    feature_cov,
    path_ids,
    recover,
    run_options,
    score_path,
    target_start,
)

__all__ = ["fit", "fit_report", "SEARCH_SHARPNESS", "SEARCH_HIDDEN_LIKELIHOOD"]

SEARCH_SHARPNESS = (1.0, 3.0, 4.0, 5.0, 6.0, 8.0)
"""The ``kappa`` the search tries (config key ``search_sharpness``)."""

SEARCH_HIDDEN_LIKELIHOOD = (0.1, 0.2, 0.3, 0.4, 0.5, 0.6)
"""The ``q`` the search tries (config key ``search_hidden_likelihood``)."""

_SEARCH_KEYS = ("search_sharpness", "search_hidden_likelihood")
_FILES = ("edges.csv", "observations.csv", "truth_path.csv")


class Run(NamedTuple):
    """A run's network, observations, start ``(c0, f0, sigma)`` (``sigma`` as ``dbntrack
    track`` takes it from the config) and true path, with its observations' rows (to tell
    a copy of a training run)."""

    net: object
    odb: object
    start: tuple
    truth: dict
    truth_file: str
    rows: frozenset


def fit(ctx: RunContext, train: list[str], validate: list[str], config: dict, seeds: int = 1,
        prior_strength=(0.0,), folds: int = 0, fold_by: str | None = None) -> dict:
    """Fit on ``train``, score ``train`` and ``validate`` (module docstring); write
    ``config.json``, ``edges.csv`` and ``fit.png``. Returns ``parameters``, ``metrics``,
    ``files`` (one row per run) and ``outputs`` for ``summary.json``."""
    _refuse(config, prior_strength, folds, fold_by)
    axes = _axes(config)
    base = {k: v for k, v in config.items() if k not in (*_SEARCH_KEYS, "fit_network")}
    fcfg, k_dp = run_options(base)
    fit_net = flag(config, "fit_network", False)
    check_disjoint(train, validate)
    with ctx.timed("read"):
        runs = {p: _read_run(p, base) for p in [*train, *validate]}
    _check_one_network(runs, train[0])
    net, network = _network(runs, train, fit_net)
    keys = [jax.random.key(ctx.seed + i) for i in range(seeds)]
    with ctx.timed("search"):
        search = search_grid(ctx, axes, train, lambda s, q, p: _error(
            p, runs[p], net, fcfg._replace(sharpness=s, hidden_likelihood=q), k_dp, keys))
    mean = {pair: float(np.mean(list(e.values()))) for pair, e in search.items()}
    own = (float(fcfg.sharpness), float(fcfg.hidden_likelihood))
    chosen = min(mean, key=lambda pair: (mean[pair], pair != own, pair))
    fitted = {**base, "sharpness": chosen[0], "hidden_likelihood": chosen[1]}
    run_options(fitted)  # as dbntrack track will read it
    scored = (net, fcfg._replace(sharpness=chosen[0], hidden_likelihood=chosen[1]))
    with ctx.timed("score"):
        files = [_row(p, runs[p], fcfg, scored, k_dp, keys, search[chosen] if p in train else None)
                 for p in ctx.progress(runs, len(runs), "runs")]  # fmt: skip
    (ctx.outdir / "config.json").write_text(json.dumps(fitted, indent=1) + "\n",
                                            encoding="utf-8")  # fmt: skip
    write_network(ctx.outdir / "edges.csv", net)
    plot_fit(ctx, files, "network and weighting", "path error (1 - path score)")
    params = {"seeds": seeds, "k_dp": k_dp, "network": network,
              "sharpness": chosen[0], "hidden_likelihood": chosen[1],
              "on_edge": _on_edge(chosen, axes),
              "search": [{"sharpness": s, "hidden_likelihood": q, "error": mean[(s, q)]}
                         for s, q in search],
              "validation_same_recording": copies_of_training(
                  {p: run.rows for p, run in runs.items()}, train, validate)}  # fmt: skip
    return {"parameters": params, "metrics": mean_errors(files), "files": files,
            "outputs": ["config.json", "edges.csv", "fit.png"]}


def _check_one_network(runs: dict, first: str) -> None:
    """Refuse runs whose ``edges.csv`` differ: one network is fitted and scored."""
    ref = runs[first].net
    for p, run in runs.items():
        same = all(np.array_equal(getattr(run.net, f), getattr(ref, f))
                   for f in ("indptr", "indices", "probs", "gap_mean"))  # fmt: skip
        if not same:
            raise InputError(f"{Path(p) / 'edges.csv'}: not the network of "
                             f"{Path(first) / 'edges.csv'}: the runs of one fit share one "
                             "camera network")  # fmt: skip


def _network(runs: dict, train: list[str], fit_net: bool) -> tuple:
    """The network the search and the fitted settings use, and its record: counted from
    the training runs' objects' moves (:mod:`models.pathrecovery.fit`) where each has an
    ``object`` column and ``fit_network`` is true, else the runs' own."""
    net = runs[train[0]].net
    lacking = [p for p in train if runs[p].odb.obj is None]
    if not fit_net or lacking:
        files = ", ".join(str(Path(p) / "observations.csv") for p in lacking)
        why = "config fit_network = false" if not fit_net else f"no object column in {files}"
        return net, {"fitted": False, "why_not": why}
    counts = []
    for p in train:
        odb = runs[p].odb
        steps = np.repeat(np.arange(odb.time_ptr.size - 1), np.diff(odb.time_ptr))
        try:
            counts.append(count_moves(net, steps, odb.cam, odb.obj))
        except InputError as exc:
            raise InputError(f"{Path(p) / 'observations.csv'}: {exc}") from None
    pooled = pool_moves(counts)
    return fitted_network(net, pooled), {
        "fitted": True, "moves": int(pooled.edge_moves.sum()),
        "unexplained_moves": pooled.unexplained, "prior_moves": PRIOR_MOVES}


def _refuse(config: dict, prior_strength, folds: int, fold_by: str | None) -> None:
    """The options of the other fits that have no meaning here, and the config keys that
    cannot apply to every run or leave nothing to search."""
    refuse_strengths("pathrecovery", "searches its weighting", "its weighting", prior_strength,
                     folds, fold_by)  # fmt: skip
    start = [k for k in ("c0", "f0", "target_obs") if k in config]
    if start:
        raise ConfigError(f"config {start}: the fit starts each run at its true path's "
                          "observation at t = 0; leave them out")  # fmt: skip
    if config.get("faithful") is True:
        raise ConfigError("config faithful = true: the paper's weighting has neither sharpness "
                          "nor hidden_likelihood to fit")  # fmt: skip


def _axes(config: dict) -> list[tuple[float, ...]]:
    """The searched ``kappa`` (config ``search_sharpness``, numbers > 0) and ``q``
    (``search_hidden_likelihood``, in [0, 1]), sorted
    (:func:`models.track.fitting.search_values`)."""
    return [search_values(config, "search_sharpness", SEARCH_SHARPNESS),
            search_values(config, "search_hidden_likelihood", SEARCH_HIDDEN_LIKELIHOOD, 1.0)]


def _on_edge(chosen: tuple, axes: list) -> list[str]:
    """The search keys whose chosen value is the least or the largest of several tried: a
    wider search may do better."""
    return [key for key, v, axis in zip(_SEARCH_KEYS, chosen, axes)
            if len(axis) > 1 and v in (axis[0], axis[-1])]  # fmt: skip


def _read_run(path: str, config: dict) -> Run:
    """A run folder (module docstring), its start taken from its true path."""
    p = Path(path)
    if not p.is_dir():
        raise InputError(f"{path}: expected a run folder holding {', '.join(_FILES)}")
    missing = [n for n in _FILES if not (p / n).is_file()]
    if missing:
        raise InputError(f"{path}: no {', '.join(missing)} (a run folder holds "
                         f"{', '.join(_FILES)}; dbntrack fit needs each run's true path)")
    edges, obs, truth_file = (str(p / n) for n in _FILES)
    net, odb, truth = read_network(edges), read_observations(obs), read_path(truth_file)
    check_cameras(net, odb, edges, obs)
    T = odb.time_ptr.size - 1
    if sorted(truth) != list(range(T)):
        raise InputError(f"{truth_file}: the true path has steps {_span(truth)}, the "
                         f"observations t = 0 .. {T - 1}: the fit needs the truth of every "
                         "step")  # fmt: skip
    kind, _, _, obs_id = truth[0]
    if kind != 0 or obs_id < 0:
        raise InputError(f"{truth_file}: the target is not seen at t = 0 (the fit starts "
                         "each run at its true observation there)")  # fmt: skip
    try:
        c0, f0 = target_start(odb, {"target_obs": obs_id}, obs)
    except ConfigError as exc:  # not about the config: the truth names a missing obs
        raise InputError(f"{truth_file}: t = 0: {exc}") from None
    sigma = array(config, "sigma") if "sigma" in config else feature_cov(odb.feat, obs)
    rows = frozenset(zip(odb.cam.tolist(), map(tuple, np.round(odb.feat, 9).tolist())))
    return Run(net, odb, (c0, f0, sigma), truth, truth_file, rows)


def _span(truth: dict) -> str:
    t = sorted(truth)
    return f"t = {t[0]} .. {t[-1]} ({len(t)} steps)"


def _error(path: str, run: Run, net, fcfg, k_dp: int, keys: list) -> float:
    """The mean over ``keys`` of the run's path error (1 - path score) with the network
    ``net`` and ``fcfg``."""
    out = []
    for key in keys:
        try:
            rec = recover(net, run.odb, run.start, fcfg, k_dp, key)
        except DBNError as exc:
            raise in_file(exc, path) from None
        t = np.arange(1, rec.kind.size + 1)
        pred = dict(zip(t.tolist(), zip(rec.kind.tolist(), rec.cam.tolist(), rec.ta.tolist(),
                                        path_ids(rec, run.odb).tolist())))  # fmt: skip
        score = score_path(pred, run.truth, f"{path} (recovered)", run.truth_file)
        out.append(1.0 - score["path_score"])
    return float(np.mean(out))


def _row(path: str, run: Run, fcfg, fitted: tuple, k_dp: int, keys: list,
         searched: dict | None) -> dict:
    """One run's row: its steps and observations, its path error with its own network and
    the config's settings, and with the ``fitted`` ``(network, FilterConfig)`` (a training
    run's from the search)."""
    error = (searched[path] if searched is not None
             else _error(path, run, *fitted, k_dp, keys))  # fmt: skip
    return {"file": str(Path(path).resolve()),
            "split": "train" if searched is not None else "validation",
            "steps": int(run.odb.time_ptr.size - 1),
            "observations": int(run.odb.cam.size),
            "hidden_steps": int(sum(v[0] != 0 for v in run.truth.values())),
            "error_config": _error(path, run, run.net, fcfg, k_dp, keys),
            "error_fitted": error}  # fmt: skip


def fit_report(summary: dict) -> list[str]:
    """The lines ``dbntrack fit pathrecovery`` prints for ``summary``
    (:func:`models.track.fitting.report`): each run's error, then the chosen pair."""

    def row_text(row: dict, other: str) -> str:
        return (f"{row['steps']} steps ({row['hidden_steps']} hidden), {row['observations']} "
                f"observations, path error {row['error_config']:.3f} (config) -> "
                f"{row['error_fitted']:.3f} (fitted){other}")  # fmt: skip

    p = summary["parameters"]
    best = min(r["error"] for r in p["search"])
    net = p["network"]
    network = (f"pathrecovery: W^p and the gap means from {net['moves']} moves of the training "
               f"runs' objects ({net['unexplained_moves']} no edge explains, left out), "
               "written to edges.csv" if net["fitted"] else
               f"pathrecovery: the network is the runs' own ({net['why_not']})")  # fmt: skip
    return [*report(summary, row_text, "network and weighting", "of which half the "
                    "observations or more are a training run's"), network,
            f"pathrecovery: the search over {len(p['search'])} pairs chose sharpness "
            f"{p['sharpness']:g}, hidden_likelihood {p['hidden_likelihood']:g} (mean training "
            f"path error {best:.3f})",
            *(f"pathrecovery: the chosen value is the edge of config {key}: a wider search may "
              "fit the training runs better (read the held-out errors: on SIMULATED scenes "
              "it fitted them worse)" for key in p["on_edge"])]  # fmt: skip
