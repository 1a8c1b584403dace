r"""``dbntrack fit jorge TRAIN... --validate HELD...``: the label network's parameters fitted on
your files, written as a config for ``dbntrack track jorge --config`` (seed 004; the fit is
:mod:`models.jorge.fit`).

The files are those ``dbntrack track jorge`` reads: regions files with ``truth`` on every
line (your low-level tracker's strokes, linked by the file's ``parents`` where it has them,
else by the link rule), or box files, whose strokes the SIMULATED low-level tracker builds,
once per seed (``--seeds N`` seeds from ``--seed``). The people of every stroke stand for
its label, so the network's hidden nodes are observed and the maximum-likelihood
parameters are event frequencies (:func:`models.jorge.fit.fit_parameters`; no EM): the
label CPDs (:math:`P_{new}`, :math:`P_{merge}`, :math:`P_{split}`, :math:`P_{part}`,
:math:`P_{join}`, :math:`q_m`, the split cover), the region-size likelihood and the palette
tables (:data:`models.jorge.fit.FITTED_FIELDS`).

The network fitted is the config's (:func:`models.track.jorge.labeller_config`: the link
rule, ``labels.max_group_size``, a table switched off, which stays off,
:func:`models.jorge.fit.fitted_like`). On a few files, ``--prior-strength`` :math:`\lambda`
shrinks every CPD row and the region-size regression towards the config's network (the
default: the fit on the shared data's training split) with :math:`\lambda`
pseudo-observations (:mod:`models.jorge.fit_prior`): 0, the default, is the plain fit;
``inf`` is the prior itself, the config's network as it is.

How strong a prior your files need depends on how many there are and how like the shared
data they are. ``--folds K`` with several strengths (``--prior-strength
0,30,100,300,1000,inf``) chooses among them by K-fold cross-validation over the training
files alone (:mod:`models.crossval`: the files cut in the order given into K contiguous
folds, each labelled with the network fitted on the others; keep one recording's files
together, or name each file's recording with ``--fold-by PATTERN``, a regular expression
whose first match in the file's path, its first group where it has one, keeps the files that
share it in one fold, and the summary names the held-out files of a training recording): the
strength whose fits have the lowest mean error on the folds they were not fitted on is the
one fitted on all the training files. With one strength, ``--folds`` reports that error
(``error_cv_fitted``) beside the config's network's on the same files
(``error_train_config``: a held-out error too, unless the config's network was fitted on
these files, as the default network was on the shared data's training split).

``OUTDIR/config.json`` is the config with the fitted fields written over its ``network``
and ``labels``, its other keys kept, so the same stroke settings build the strokes you
label with it.

Hold files out (``--validate``): the summary gives each file's labelling error with the
config's network and with the fitted one, and their means over the training and the held-out
files (each file weighs the same); and the same over the strokes of three and more people
(issue 16's crowd figure, pooled over those strokes). The error on the files fitted on is
not a result. Fitting the shared data's declared training split
(:data:`models.jorge.fit.TRAIN_SEQUENCES`) with ``--seed 100 --seeds 10`` writes the default
network's parameters again.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path
from typing import NamedTuple

import numpy as np

from dbn.errors import ConfigError, InputError
from models.crossval import CrossValidation
from models.io.jorge_regions import is_regions
from models.track.context import RunContext, shown_strength
from models.track.fitting import (
    check_disjoint,
    check_strengths,
    cross_validate_files,
    cv_record,
    fold_groups,
    held_of_training,
    mean_errors,
    plot_fit,
    report,
)
from models.track.jorge import (
    builder_keys,
    label_steps,
    linked_steps,
    read_box_truth,
    read_checked_regions,
    read_options,
    require_truth,
)

__all__ = ["fit", "fit_report", "fitted_config", "FitSet", "FITTED_LABEL_FIELDS"]

FITTED_LABEL_FIELDS = ("p_new", "p_merge", "p_merge_one_split", "p_merge_both_split", "p_split",
                       "p_part", "p_join", "new_group_probs", "split_cover")
"""The :class:`~models.jorge.labels.LabelParams` fields the fit sets (``labels`` in
``config.json``); the network's are :data:`models.jorge.fit.FITTED_FIELDS` but ``labels``."""


class FitSet(NamedTuple):
    """One stroke set of a file: its strokes, their links (the file's, or None: the link
    rule), frame rate and, for a box file, its ground truth (None for a regions file)."""

    strokes: list
    links: list | None
    fps: float
    truth: object = None


def fit(ctx: RunContext, train: list[str], validate: list[str], config: dict,
        seeds: int = 1, prior_strength: float | Sequence[float] = 0.0, folds: int = 0,
        fold_by: str | None = None) -> dict:
    """Fit on ``train``, score on ``train`` and ``validate``; write ``config.json`` and
    ``fit.png``. ``prior_strength`` > 0 shrinks each CPD row and the size regression towards
    the config's network with that many pseudo-observations
    (:func:`models.jorge.fit_prior.shrink`; inf: the config's network itself); several
    strengths are chosen among by ``folds``-fold cross-validation over the training files
    (:func:`models.crossval.cross_validate`, module docstring), whose folds keep together
    the files that share the match of the regular expression ``fold_by``
    (:func:`models.crossval.group_keys`) where it is given. Returns ``parameters``,
    ``metrics``, ``files`` (one row per file) and ``outputs`` for ``summary.json``."""
    groups = fold_groups(train, folds, fold_by)
    strengths = check_strengths(prior_strength, folds, train, groups)
    opt = read_options(config)
    base, own = opt.online, opt.own
    check_disjoint(train, validate)
    builder = builder_keys(config, own)
    if builder and all(map(is_regions, [*train, *validate])):
        raise ConfigError(f"config {builder}: stroke-builder settings apply to box files, and "
                          "every file is a regions file")  # fmt: skip
    with ctx.timed("read"):
        read = {p: _sets(ctx, p, config, own, opt.fps, base, seeds) for p in [*train, *validate]}
    cv, held = None, {}
    if folds:
        with ctx.timed("cross-validate"):
            cv, held = _cross_validate(ctx, read, train, base, strengths, folds, groups)
    strength = strengths[0] if cv is None else cv.chosen
    with ctx.timed("fit"):
        fitted, counts = _fitted(read, train, base, strength)
    with ctx.timed("score"):  # every file labelled with both networks
        split = {p: "train" if p in train else "validation" for p in read}
        files = [_score_file(ctx, p, read[p], base, fitted, split[p], held.get(p))
                 for p in ctx.progress(read, len(read), "files")]
    out = fitted_config(config, fitted.network)
    (ctx.outdir / "config.json").write_text(json.dumps(out, indent=1) + "\n", encoding="utf-8")
    plot_fit(ctx, files, "network", "labelling error")
    training = [fs for p in train for fs in read[p]]
    params = {"seeds": seeds, "split_cover": opt.split_cover,
              "prior_strength": shown_strength(strength),
              "folds": folds, "fold_by": fold_by,
              **({} if groups is None else {"validation_of_training_recordings":
                                            held_of_training(validate, fold_by, groups)}),
              "validation_same_recording": _same_recordings(read, train, validate),
              **({} if cv is None else {"cross_validation": cv_record(cv)}),
              **_counted(training, counts.children, base.network.labels.max_group_size),
              "fitted": {k: v for k, v in out["labels"].items() if isinstance(v, float)}
              | {k: out["network"][k] for k in ("size_mu_single", "size_slope", "size_sigma")}}
    return {"parameters": params, "metrics": _means(files), "files": files,
            "outputs": ["config.json", "fit.png"]}


def fit_report(summary: dict) -> list[str]:
    """The lines ``dbntrack fit jorge`` prints for ``summary``
    (:func:`models.track.fitting.report`): each file's strokes and errors, those of its
    strokes of three and more people, and the held-out files of a training recording."""

    def row_text(row: dict, other: str) -> str:
        big = (f"; {row['strokes_group_3plus']} strokes of 3+ people: "
               f"{row['error_group_3plus_config']:.3f} -> {row['error_group_3plus_fitted']:.3f}"
               if row["strokes_group_3plus"] else "")  # fmt: skip
        return (f"{row['strokes']} strokes, error {row['error_config']:.3f} (config) -> "
                f"{row['error_fitted']:.3f} (fitted){other}{big}")

    return report(summary, row_text, "network", "whose boxes are mostly a training file's "
                  "(the same recording, or a cut of it)")


def _same_recordings(read: dict, train: list[str], validate: list[str]) -> dict[str, str]:
    """Each held-out box file (resolved) whose boxes are mostly a training box file's
    (:func:`models.jorge.recordings.same_recording`), with that file: the same recording or
    a cut of it, whose error is not held out. Regions files hold no boxes per person and
    are not compared."""
    from models.jorge.recordings import same_recording

    mine = {str(Path(p).resolve()): read[p][0].truth for p in train if read[p][0].truth is not None}
    out = {}
    for p in validate:
        truth = read[p][0].truth
        same = None if truth is None else same_recording(truth, mine)
        if same is not None:
            out[str(Path(p).resolve())] = same
    return out


def _fitted(read: dict, files: list[str], base, strength: float):
    """``(online, counts)``: the config's labeller ``base`` with its network fitted on the
    stroke sets of ``files`` (``read[path]``) and shrunk with ``strength``, and the events
    counted; ``strength`` inf gives ``base`` itself (the limit of the shrinkage)."""
    from models.jorge.fit import EventCounts, count_events, fit_counts, fitted_like
    from models.jorge.fit_prior import shrink

    counts = EventCounts()
    for fs in (fs for p in files for fs in read[p]):
        count_events(fs.strokes, base.network, counts, links=fs.links, fps=fs.fps)
    if counts.children == 0:
        raise InputError(f"no stroke of the training files {files} has a parent (a link to "
                         "an earlier stroke): nothing to fit the network's transitions on")
    if np.isinf(strength):
        return base, counts
    shrunk = shrink(fit_counts(counts, base.network), base.network, counts, strength)
    return replace(base, network=fitted_like(base.network, shrunk)), counts


def _cross_validate(ctx: RunContext, read: dict, train: list[str], base, strengths: list,
                    folds: int, groups: list[str] | None) -> tuple[CrossValidation, dict]:
    """Each training file labelled with the network fitted on the other folds, for every
    strength (:func:`models.track.fitting.cross_validate_files`); and each training file's
    :class:`_Errors` under the chosen strength's fit on the other folds."""

    def score(online, path: str) -> tuple[float, _Errors]:
        errors = _errors(ctx, online, read[path])
        return errors.rate, errors

    return cross_validate_files(
        ctx, train, strengths, folds, groups,
        lambda files, strength: _fitted(read, files, base, strength)[0], score,
        "; give fewer folds or order the files so that every fold's complement has links")


def _counted(training: list[FitSet], children: int, gmax: int) -> dict:
    """What the fit counted: the training strokes, those with a parent, and those of more
    people than the largest group (off the model, not counted)."""
    strokes = [s for fs in training for s in fs.strokes]
    return {"training_strokes": len(strokes), "counted_children": children,
            "strokes_beyond_max_group_size": sum(len(s.truth) > gmax for s in strokes)}


def _sets(ctx: RunContext, path: str, config: dict, own: set, fps: float | None, base,
          seeds: int) -> list[FitSet]:
    """The stroke sets of one file: a regions file's own (its people on every line; the
    config's stroke-builder settings do not apply), or one SIMULATED per seed ``ctx.seed ..
    ctx.seed + seeds - 1`` of a box file."""
    from models.jorge.strokes import build_strokes

    if is_regions(path):  # the stroke builder's settings are for the box files
        mine = {k: v for k, v in config.items() if k in own and k != "view"}
        regions, rate, _ = read_checked_regions(ctx, path, mine, own, fps, base)
        require_truth(regions, "fitting")
        return [FitSet(regions.strokes, regions.parents, rate)]
    truth, scfg, _, _ = read_box_truth(ctx, path, config, own, fps)
    rate = truth.fps if fps is None else fps
    return [FitSet(list(build_strokes(ctx.seed + i, truth, scfg)), None, rate, truth)
            for i in range(seeds)]  # fmt: skip


def _score_file(ctx: RunContext, path: str, sets: list[FitSet], base, fitted, split: str,
                held: _Errors | None = None) -> dict:
    """One file's row: its strokes (per stroke set) and the labelling error (mean over its
    stroke sets) with the config's network and the fitted one; its strokes of three and
    more people (over all its stroke sets) and their error with each (NaN: none); for a
    training file under cross-validation, ``held``, the errors of the fit on the other
    folds (``error_cv``, ``error_cv_group_3plus``)."""
    mine, new = _errors(ctx, base, sets), _errors(ctx, fitted, sets)
    n = mine.strokes_3plus
    row = {"file": str(Path(path).resolve()), "split": split,
           "strokes": int(np.mean([len(fs.strokes) for fs in sets])),
           "error_config": mine.rate, "error_fitted": new.rate, "strokes_group_3plus": n,
           "error_group_3plus_config": mine.wrong_3plus / n if n else np.nan,
           "error_group_3plus_fitted": new.wrong_3plus / n if n else np.nan}  # fmt: skip
    if held is not None:
        row["error_cv"] = held.rate
        row["error_cv_group_3plus"] = held.wrong_3plus / n if n else np.nan
    return row


class _Errors(NamedTuple):
    """A labeller's errors on a file's stroke sets: the mean error rate, and the strokes of
    three and more people, wrong and in all, summed over the sets."""

    rate: float
    wrong_3plus: int
    strokes_3plus: int


def _errors(ctx: RunContext, online, sets: list[FitSet]) -> _Errors:
    """The labelling errors of ``online`` on a file's stroke sets."""
    from models.jorge.scoring import group_errors, score

    rates, wrong, big = [], 0, 0
    for fs in sets:
        labels, _ = label_steps(ctx, online, linked_steps(fs.strokes, fs.links), fs.fps,
                                phase=None)  # fmt: skip
        sc = score(fs.strokes, labels)
        rates.append(sc.error_rate)
        w, n = group_errors(fs.strokes, sc.errors)
        wrong, big = wrong + w, big + n
    return _Errors(float(np.mean(rates)), wrong, big)


def _means(files: list[dict]) -> dict:
    """:func:`models.track.fitting.mean_errors`, and the errors over the files' strokes of
    three and more people, pooled (NaN where there are none; ``error_cv_group_3plus_fitted``
    under cross-validation)."""
    crowd = {f"error_{split}_group_3plus_{name}":
             _pooled([f for f in files if f["split"] == split], f"error_group_3plus_{name}")
             for split in ("train", "validation") for name in ("config", "fitted")}
    rows = [f for f in files if "error_cv" in f]
    if rows:
        crowd["error_cv_group_3plus_fitted"] = _pooled(rows, "error_cv_group_3plus")
    return mean_errors(files) | crowd


def _pooled(rows: list[dict], key: str) -> float:
    """The error ``key`` of the rows' strokes of three and more people, pooled over them
    (NaN where there are none)."""
    big = sum(f["strokes_group_3plus"] for f in rows)
    wrong = sum(f[key] * f["strokes_group_3plus"] for f in rows if f["strokes_group_3plus"])
    return wrong / big if big else np.nan


def fitted_config(config: dict, network) -> dict:
    """``config`` with ``network``'s fitted fields over its ``network`` and ``labels``
    objects (tables as nested tuples, which JSON writes as lists): a config for ``dbntrack
    track jorge``, whose :func:`~models.track.jorge.labeller_config` is ``network``."""
    from models.jorge.fit import FITTED_FIELDS

    net = {f: getattr(network, f) for f in sorted(FITTED_FIELDS - {"labels"})}
    labels = {f: getattr(network.labels, f) for f in FITTED_LABEL_FIELDS}
    return {**config, "network": {**config.get("network", {}), **net},
            "labels": {**config.get("labels", {}), **labels}}

