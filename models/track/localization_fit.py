r"""``dbntrack fit localization TRAIN... --validate HELD...``: your robot's noise measured on
runs with ground truth, and the widening of it the filter needs, written as a config for
``dbntrack track localization --config``.

A run (each TRAIN and HELD) is a robot's odometry file in an MRCLAM folder
(``RobotN_Odometry.dat[.gz]``: that folder, robot N), an MRCLAM folder (the config's
``robot``), or a folder of the generic CSVs (``odometry.csv``, ``measurements.csv``,
``landmarks.csv``, ``groundtruth.csv``; :mod:`models.io.localization`); each needs its
ground truth, and starts at its first true pose. The config's ``duration``, ``start``,
``dt``, ``num_particles`` and ``algorithm`` apply to every run; without a ``duration`` a
run ends where its odometry or its truth does (the truth must cover every step).

The fit, a documented search rather than a likelihood:

1. the measured noise (:mod:`models.localization.fit`): the robust spreads of the training
   runs' range, bearing and odometry errors against their truth, pooled, and the median
   range error as the range bias;
2. the filter run on every training run with the measured motion noise (``a_xy``,
   ``a_theta``) times each of ``search_scales`` and the measured sensor noise
   (``sigma_range``, ``sigma_bearing``) times each of them (default :data:`SEARCH_SCALES`:
   16 pairs), and the pair of the least mean position RMSE kept (ties: the smaller
   scales). The bare spreads make an overconfident filter: a step's quantisation of the
   measurement times and the truth's own error are noise to it, and on MRCLAM the filter
   did best with the range spread 2.7 and the bearing spread 5 times wider
   (:data:`~models.localization.mrclam.MRCLAM_NOISE`);
3. at the kept scales, the filter run on every training run once more without the range
   bias (``range_bias`` 0), and the measured bias kept unless the mean position RMSE is
   less without it. On MRCLAM the median range error against the motion-capture truth is
   +0.05 m in each of the first two 5-minute windows of both robots, and at MRCLAM's noise
   a filter given it did worse in each of the four (one seed; robot 1's first 5 minutes
   0.155 -> 0.183 m): why is not known here (the truth's reference point need not be the
   sensor's), so the training runs decide.

``b_xy``, ``b_theta``, ``outlier_prob``, ``initial_std`` and ``max_range`` are kept (the
config's, else MRCLAM's). A run's error is the position RMSE (m) of the filter's mean pose
against its truth at the filter's steps, the mean over ``--seeds`` runs of seeds ``--seed``,
``--seed + 1``, ... (as ``dbntrack track --seed``), with the config's noise and with the
fitted. There is no prior strength and no cross-validation: the training runs choose the
scales, the held-out runs say how well the choice holds. The error on the runs fitted on
is not a result: hold runs out (a held-out run of which half the odometry rows or more
are a training run's is named as not held out).
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from typing import NamedTuple

import jax
import numpy as np

from dbn.errors import ConfigError, DBNError, InputError, in_file
from models.io.localization import mrclam_file, read_generic, read_mrclam_folder
from models.localization.fit import noise_residuals, noise_settings, pool_residuals, robust_noise
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
from models.track.localization import (
    NOISE_KEYS,
    run_options,
    run_sequence,
    scan_means,
)

__all__ = ["fit", "fit_report", "keeps_bias", "SEARCH_SCALES"]

SEARCH_SCALES = (1.0, 2.0, 4.0, 8.0)
"""The factors of the measured motion and sensor noise the search tries (config key
``search_scales``): doublings from the bare spreads to eight times them."""

_CSV = ("odometry", "measurements", "landmarks", "groundtruth")
_ODOMETRY = re.compile(r"Robot(\d+)_Odometry\.dat(\.gz)?")


class Run(NamedTuple):
    """A run's filter steps (:class:`~models.localization.mrclam.MRCLAMSequence`) and its
    odometry rows as text (to tell a copy of a training run)."""

    seq: object
    rows: frozenset


def fit(ctx: RunContext, train: list[str], validate: list[str], config: dict, seeds: int = 1,
        prior_strength=(0.0,), folds: int = 0, fold_by: str | None = None) -> dict:
    """Measure and search on ``train``, score ``train`` and ``validate`` (module
    docstring); write ``config.json`` and ``fit.png``. Returns ``parameters``, ``metrics``,
    ``files`` (one row per run) and ``outputs`` for ``summary.json``."""
    refuse_strengths("localization", "measures its noise and searches its scales",
                     "its scales", prior_strength, folds, fold_by)  # fmt: skip
    scales = search_values(config, "search_scales", SEARCH_SCALES)
    base = {k: v for k, v in config.items() if k != "search_scales"}
    if "initial_pose" in base:
        raise ConfigError("config initial_pose: the fit starts each run at its ground truth's "
                          "first pose; leave it out")  # fmt: skip
    opts = run_options(base)
    check_disjoint(train, validate)
    with ctx.timed("read"):
        runs = {p: _read_run(p, opts) for p in [*train, *validate]}
    try:
        measured = robust_noise(pool_residuals([noise_residuals(runs[p].seq) for p in train]))
    except InputError as exc:
        raise InputError(f"training runs {train}: {exc}") from None
    keys = [jax.random.key(ctx.seed + i) for i in range(seeds)]
    with ctx.timed("search"):
        search = search_grid(ctx, (scales, scales), train, lambda m, s, p: _rmse(
            runs[p].seq, noise_settings(opts["noise"], measured, m, s), opts, keys))
        mean = {ms: float(np.mean(list(e.values()))) for ms, e in search.items()}
        chosen = min(mean, key=lambda ms: (mean[ms], ms))
        noise = noise_settings(opts["noise"], measured, *chosen)
        unbiased = {p: _rmse(runs[p].seq, {**noise, "range_bias": 0.0}, opts, keys)
                    for p in ctx.progress(train, len(train), "range bias")}  # fmt: skip
    keep_bias = keeps_bias(search[chosen], unbiased)
    noise = noise if keep_bias else {**noise, "range_bias": 0.0}
    searched = search[chosen] if keep_bias else unbiased
    fitted = {**base, **{k: _listed(noise[k]) for k in NOISE_KEYS}}
    run_options(fitted)  # as dbntrack track will read it
    with ctx.timed("score"):
        files = [_row(p, runs[p], opts, noise, keys, searched if p in train else None)
                 for p in ctx.progress(runs, len(runs), "runs")]  # fmt: skip
    (ctx.outdir / "config.json").write_text(json.dumps(fitted, indent=1) + "\n",
                                            encoding="utf-8")  # fmt: skip
    plot_fit(ctx, files, "noise", "position RMSE (m)")
    params = {"seeds": seeds, "search_scales": list(scales), "measured": measured,
              "motion_scale": chosen[0], "sensor_scale": chosen[1],
              "range_bias_kept": keep_bias,
              "range_bias_errors": {"measured": mean[chosen],
                                    "zero": float(np.mean(list(unbiased.values())))},
              "search": [{"motion_scale": m, "sensor_scale": s, "error": mean[(m, s)]}
                         for m, s in search],
              "validation_same_recording": copies_of_training(
                  {p: run.rows for p, run in runs.items()}, train, validate),
              "fitted": {k: fitted[k] for k in NOISE_KEYS}}  # fmt: skip
    return {"parameters": params, "metrics": mean_errors(files), "files": files,
            "outputs": ["config.json", "fit.png"]}


def _read_run(path: str, opts: dict) -> Run:
    """A run (the forms of the module docstring), which must have its ground truth."""
    p = Path(path)
    m = _ODOMETRY.fullmatch(p.name)
    if m and p.is_file():
        data, odometry = read_mrclam_folder(p.parent, int(m[1])), p
    elif p.is_dir() and (p / "odometry.csv").is_file():
        files = [p / f"{n}.csv" for n in _CSV]
        if not files[-1].is_file():
            raise InputError(f"{path}: no groundtruth.csv: dbntrack fit needs each run's truth")
        data, odometry = read_generic(*files), files[0]
    elif p.is_dir():
        robot = opts["robot"]
        data, odometry = read_mrclam_folder(p, robot), mrclam_file(p, f"Robot{robot}_Odometry")
    else:
        raise InputError(f"{path}: expected a robot's MRCLAM odometry file "
                         "(RobotN_Odometry.dat[.gz]), an MRCLAM folder or a folder of "
                         f"{', '.join(f'{n}.csv' for n in _CSV)}")  # fmt: skip
    if data.groundtruth is None:
        raise InputError(f"{path}: no ground truth (RobotN_Groundtruth.dat): dbntrack fit "
                         "needs each run's truth")  # fmt: skip
    try:
        end = min(data.odometry[-1, 0], data.groundtruth[-1, 0])  # without a duration
        seq = run_sequence(data, odometry, opts, end)[0]
    except DBNError as exc:  # named by its run, unless it names the odometry file
        raise (exc if str(odometry) in str(exc) else in_file(exc, path)) from None
    gt = data.groundtruth[:, 0]
    if seq.times[0] < gt[0] or seq.times[-1] > gt[-1]:
        raise InputError(f"{path}: the ground truth covers t = [{gt[0]:.6g}, {gt[-1]:.6g}], "
                         f"the run t = [{seq.times[0]:.6g}, {seq.times[-1]:.6g}]: the fit needs "
                         "the truth of every step (config start, duration)")  # fmt: skip
    return Run(seq, frozenset(tuple(f"{x:.9g}" for x in row) for row in data.odometry))


def _rmse(seq, noise: dict, opts: dict, keys: list) -> float:
    """The mean over ``keys`` of the position RMSE of the filter's mean pose, ``noise``'s
    model, against the run's truth at the filter's steps (:func:`scan_means`: the poses
    ``dbntrack track`` gives)."""
    out = []
    for key in keys:
        means = scan_means(seq, {**opts, "noise": noise}, key)
        err = np.hypot(*(means[:, :2] - seq.truth[1:, :2]).T)
        out.append(float(np.sqrt(np.mean(err**2))))
    return float(np.mean(out))


def keeps_bias(biased: dict, unbiased: dict) -> bool:
    """Whether the measured range bias stays: the mean training error ``{run: RMSE}`` with
    it (``biased``) at most the mean without it (``unbiased``, the same runs)."""
    if set(biased) != set(unbiased) or not biased:
        raise ValueError("keeps_bias: the same training runs, with and without the bias")
    return bool(np.mean(list(biased.values())) <= np.mean(list(unbiased.values())))


def _row(path: str, run: Run, opts: dict, noise: dict, keys: list,
         searched: dict | None) -> dict:
    """One run's row: its steps and measurements, its error with the config's noise and
    with the fitted (a training run's from the search)."""
    fitted = searched[path] if searched is not None else _rmse(run.seq, noise, opts, keys)
    return {"file": str(Path(path).resolve()),
            "split": "train" if searched is not None else "validation",
            "steps": int(len(run.seq.odometry)),
            "measurements": int(np.asarray(run.seq.observations.mask).sum()),
            "error_config": _rmse(run.seq, opts["noise"], opts, keys),
            "error_fitted": fitted}  # fmt: skip


def _listed(v):
    """A setting as JSON has it (tuples as lists)."""
    return [float(x) for x in v] if isinstance(v, tuple | list) else float(v)


def fit_report(summary: dict) -> list[str]:
    """The lines ``dbntrack fit localization`` prints for ``summary``
    (:func:`models.track.fitting.report`): each run's error, then the measured noise and the
    scales the search chose."""

    def row_text(row: dict, other: str) -> str:
        return (f"{row['steps']} steps, {row['measurements']} measurements, position RMSE "
                f"{row['error_config']:.3f} m (config) -> {row['error_fitted']:.3f} m "
                f"(fitted){other}")  # fmt: skip

    p = summary["parameters"]
    m = p["measured"]
    best, bias = min(r["error"] for r in p["search"]), p["range_bias_errors"]
    return [*report(summary, row_text, "noise", "of which half the odometry rows or more "
                    "are a training run's"),
            f"localization: measured on {m['num_measurements']} measurements and "
            f"{m['num_steps']} steps: range sd {m['sigma_range']:.4g} m (bias "
            f"{m['range_bias']:+.3g} m), bearing sd {m['sigma_bearing']:.3g} rad, odometry "
            f"a_xy {m['a_xy']:.3g}, a_theta {m['a_theta']:.3g}; the search chose motion x "
            f"{p['motion_scale']:g}, sensor x {p['sensor_scale']:g} (mean training RMSE "
            f"{best:.3f} m) and {'kept' if p['range_bias_kept'] else 'dropped'} the range "
            f"bias ({bias['zero']:.3f} m without it)"]  # fmt: skip
