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
shrinks every CPD row towards the config's network (the default: the fit on the shared
data's training split) with :math:`\lambda` pseudo-observations
(:mod:`models.jorge.fit_prior`): 0, the default, is the plain fit.

``OUTDIR/config.json`` is the config with the fitted fields written over its ``network``
and ``labels``, its other keys kept, so the same stroke settings build the strokes you
label with it.

Hold files out (``--validate``): the summary gives each file's labelling error with the
config's network and with the fitted one, and their means over the training and the
held-out files (each file weighs the same). The error on the files fitted on is not a
result. Fitting the shared data's declared training split
(:data:`models.jorge.fit.TRAIN_SEQUENCES`) with ``--seed 100 --seeds 10`` writes the
default network's parameters again.
"""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path
from typing import NamedTuple

import numpy as np

from dbn.errors import ConfigError, InputError
from models.io.jorge_regions import is_regions
from models.track.context import RunContext
from models.track.jorge import (
    builder_keys,
    label_steps,
    linked_steps,
    read_box_truth,
    read_checked_regions,
    read_options,
    require_truth,
)

__all__ = ["fit", "fitted_config", "FitSet", "FITTED_LABEL_FIELDS"]

FITTED_LABEL_FIELDS = ("p_new", "p_merge", "p_merge_one_split", "p_merge_both_split", "p_split",
                       "p_part", "p_join", "new_group_probs", "split_cover")
"""The :class:`~models.jorge.labels.LabelParams` fields the fit sets (``labels`` in
``config.json``); the network's are :data:`models.jorge.fit.FITTED_FIELDS` but ``labels``."""


class FitSet(NamedTuple):
    """One stroke set of a file: its strokes, their links (the file's, or None: the link
    rule) and frame rate."""

    path: str
    strokes: list
    links: list | None
    fps: float


def fit(ctx: RunContext, train: list[str], validate: list[str], config: dict,
        seeds: int = 1, prior_strength: float = 0.0) -> dict:
    """Fit on ``train``, score on ``train`` and ``validate``; write ``config.json`` and
    ``fit.png``. ``prior_strength`` > 0 shrinks each CPD row towards the config's network
    with that many pseudo-observations (:func:`models.jorge.fit_prior.shrink`). Returns
    ``parameters``, ``metrics``, ``files`` (one row per file) and ``outputs`` for
    ``summary.json``."""
    from models.jorge.fit import EventCounts, count_events, fit_counts, fitted_like
    from models.jorge.fit_prior import shrink

    if not (np.isfinite(prior_strength) and prior_strength >= 0):
        raise InputError(f"prior strength {prior_strength!r}: expected a finite number >= 0")
    opt = read_options(config)
    base, own, split_cover = opt.online, opt.own, opt.split_cover
    _check_disjoint(train, validate)
    builder = builder_keys(config, own)
    if builder and all(map(is_regions, [*train, *validate])):
        raise ConfigError(f"config {builder}: stroke-builder settings apply to box files, and "
                          "every file is a regions file")  # fmt: skip
    with ctx.timed("read"):
        read = {p: _sets(ctx, p, config, own, opt.fps, base, seeds) for p in [*train, *validate]}
    counts = EventCounts()
    with ctx.timed("fit"):
        for fs in (fs for p in train for fs in read[p]):
            count_events(fs.strokes, base.network, counts, links=fs.links, fps=fs.fps)
        if counts.children == 0:
            raise InputError(f"no stroke of the training files {train} has a parent (a link "
                             "to an earlier stroke): nothing to fit the network's transitions on")
        ml = fit_counts(counts, base.network)
        shrunk = shrink(ml, base.network, counts, prior_strength)
        fitted = replace(base, network=fitted_like(base.network, shrunk))
    with ctx.timed("score"):  # every file labelled with both networks
        files = [_score_file(ctx, p, read[p], base, fitted, "train" if p in train else
                             "validation") for p in ctx.progress(read, len(read), "files")]
    out = fitted_config(config, fitted.network)
    (ctx.outdir / "config.json").write_text(json.dumps(out, indent=1) + "\n", encoding="utf-8")
    _plot(ctx, files)
    training = [fs for p in train for fs in read[p]]
    params = {"seeds": seeds, "split_cover": split_cover, "prior_strength": prior_strength,
              **_counted(training, counts.children, base.network.labels.max_group_size),
              "fitted": {k: v for k, v in out["labels"].items() if isinstance(v, float)}
              | {k: out["network"][k] for k in ("size_mu_single", "size_slope", "size_sigma")}}
    return {"parameters": params, "metrics": _means(files), "files": files,
            "outputs": ["config.json", "fit.png"]}


def _counted(training: list[FitSet], children: int, gmax: int) -> dict:
    """What the fit counted: the training strokes, those with a parent, and those of more
    people than the largest group (off the model, not counted)."""
    strokes = [s for fs in training for s in fs.strokes]
    return {"training_strokes": len(strokes), "counted_children": children,
            "strokes_beyond_max_group_size": sum(len(s.truth) > gmax for s in strokes)}


def _check_disjoint(train: list[str], validate: list[str]) -> None:
    """Refuse a file both fitted on and held out (by resolved path), or given twice."""
    seen: dict[Path, str] = {}
    for p in [*train, *validate]:
        q = Path(p).resolve()
        if q in seen:
            raise InputError(f"{p}: given twice (as {seen[q]!r}); a held-out file must not be "
                             "a training file")  # fmt: skip
        seen[q] = p


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
        return [FitSet(path, regions.strokes, regions.parents, rate)]
    truth, scfg, _, _ = read_box_truth(ctx, path, config, own, fps)
    rate = truth.fps if fps is None else fps
    return [FitSet(path, list(build_strokes(ctx.seed + i, truth, scfg)), None, rate)
            for i in range(seeds)]  # fmt: skip


def _score_file(ctx: RunContext, path: str, sets: list[FitSet], base, fitted, split: str) -> dict:
    """One file's row: its strokes and the labelling error (mean over its stroke sets) with
    the config's network and the fitted one."""
    from models.jorge.scoring import score

    errors = {}
    for name, online in (("config", base), ("fitted", fitted)):
        rates = []
        for fs in sets:
            steps = linked_steps(fs.strokes, fs.links)
            labels, _ = label_steps(ctx, online, steps, fs.fps, phase=None)
            rates.append(score(fs.strokes, labels).error_rate)
        errors[name] = float(np.mean(rates))
    return {"file": str(Path(path).resolve()), "split": split,
            "strokes": int(np.mean([len(fs.strokes) for fs in sets])),
            "error_config": errors["config"], "error_fitted": errors["fitted"]}  # fmt: skip


def _means(files: list[dict]) -> dict:
    """Mean errors over the training and the held-out files (NaN where there are none)."""
    out = {}
    for split in ("train", "validation"):
        rows = [f for f in files if f["split"] == split]
        for name in ("config", "fitted"):
            out[f"error_{split}_{name}"] = float(np.mean([f[f"error_{name}"] for f in rows])
                                               if rows else np.nan)  # fmt: skip
    return out


def fitted_config(config: dict, network) -> dict:
    """``config`` with ``network``'s fitted fields over its ``network`` and ``labels``
    objects (tables as nested tuples, which JSON writes as lists): a config for ``dbntrack
    track jorge``, whose :func:`~models.track.jorge.labeller_config` is ``network``."""
    from models.jorge.fit import FITTED_FIELDS

    net = {f: getattr(network, f) for f in sorted(FITTED_FIELDS - {"labels"})}
    labels = {f: getattr(network.labels, f) for f in FITTED_LABEL_FIELDS}
    return {**config, "network": {**config.get("network", {}), **net},
            "labels": {**config.get("labels", {}), **labels}}


def _plot(ctx: RunContext, files: list[dict]) -> None:
    """``fit.png``: each file's error with the config's and the fitted network."""
    size = (min(14.0, max(4.0, 0.45 * len(files) + 2)), 4.0)
    with ctx.figure("fit.png", figsize=size) as (_, ax):
        x = np.arange(len(files))
        for dx, name in ((-0.2, "config"), (0.2, "fitted")):
            ax.bar(x + dx, [f[f"error_{name}"] for f in files], 0.4, label=f"{name} network")
        ax.set_xticks(x, [("" if f["split"] == "train" else "held out\n") + Path(f["file"]).name
                          for f in files], rotation=30, ha="right", fontsize=7)  # fmt: skip
        held = [i for i, f in enumerate(files) if f["split"] != "train"]
        if held and held[0] > 0:  # the training files first, then the held-out ones
            ax.axvline(held[0] - 0.5, color="0.5", lw=0.8, ls="--")
        ax.set_ylabel("labelling error")
        ax.set_title("dbntrack fit: each file's error, config's and fitted network", fontsize=9)
        ax.legend(fontsize=7)
