r"""``dbntrack fit zajdel_adf | zajdel_learnsearch TRAIN.csv... --validate HELD.csv...``: the
path model and the appearance scales fitted on passes whose people you know, written as a
config for ``dbntrack track NAME --config`` (the fit is :mod:`models.zajdel.fit`).

The files are the observations CSVs ``dbntrack track`` reads (:mod:`models.io.zajdel`),
each with a ``person`` column on every pass. With the people known, a person's passes in
time order are an entry and a chain of moves, so the maximum-likelihood parameters are the
moves' frequencies and moments (no EM, no search): the transition table ``trans``, the entry
table ``entry``, the travel times ``travel_mean`` / ``travel_std`` per camera pair,
``p_new``, and for ``zajdel_adf`` the appearance scales ``within_std`` / ``between_std``
(learn-search learns the appearance by EM on the file it labels, and takes the fitted path
model as its start). ``--prior-strength`` :math:`\lambda` adds that many
pseudo-observations per row (a uniform transition row, the moments of every move for each
camera pair's travel times; :mod:`models.zajdel.fit`); its default here is 1
(:data:`models.track.zajdel.DEFAULT_PRIOR_STRENGTH`), since a plain fit (0) forbids every
move its training files never show. ``--folds K`` with several strengths chooses among them
by K-fold cross-validation over the training files (:mod:`models.crossval`; ``--fold-by``
keeps a recording's files in one fold), as for ``jorge``.

Each file is then labelled by the tracker with the config's parameters (the runner's
defaults from the file where the config has none: uniform layout tables, broad travel
times, :mod:`models.track.zajdel`) and with the fitted ones. A file's error is
:math:`1 - F_1`, the pairwise F1 of its passes' labels against its people
(:func:`models.zajdel.metrics.pairwise_prf`): it counts both a person cut into several
tracks and two people merged, where the partition accuracy :math:`q` (also reported) gives
one track per pass a perfect score. The cameras and borders are numbered over every file
given (or the config's ``num_cameras`` / ``num_borders``), and written into the config so
that a file showing fewer of them is labelled with the same tables. ``OUTDIR/config.json``
is the config with the fitted keys written over it (``window`` is not fitted: each run
takes its file's span). The error on the files fitted on is not a result: hold files out.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from dbn.errors import DBNError, InputError, in_file
from models.io.zajdel import read_observations
from models.track.context import RunContext, shown_strength
from models.track.fitting import (
    check_disjoint,
    check_strengths,
    copies_of_training,
    cross_validate_files,
    cv_record,
    fold_groups,
    held_of_training,
    mean_errors,
    plot_fit,
    report,
)
from models.track.options import integer
from models.track.zajdel import (
    DEFAULT_PRIOR_STRENGTH,
    check_config,
    check_path_size,
    label_passes,
)
from models.zajdel.fit import fit_counts, pass_counts, sum_counts

__all__ = ["fit", "fit_report", "fitted_config", "FITTED_KEYS"]

FITTED_KEYS = {"zajdel_adf": ("trans", "entry", "travel_mean", "travel_std", "p_new",
                              "within_std", "between_std"),
               "zajdel_learnsearch": ("trans", "entry", "travel_mean", "travel_std", "p_new")}
"""The config keys the fit writes, per tracker (besides ``num_cameras``, ``num_borders``)."""


def fit(ctx: RunContext, train: list[str], validate: list[str], config: dict, seeds: int = 1,
        prior_strength=DEFAULT_PRIOR_STRENGTH, folds: int = 0,
        fold_by: str | None = None) -> dict:
    """Fit on ``train``, score on ``train`` and ``validate`` (module docstring); write
    ``config.json`` and ``fit.png``. Returns ``parameters``, ``metrics``, ``files`` (one
    row per file) and ``outputs`` for ``summary.json``."""
    if seeds != 1:
        raise InputError(f"--seeds {seeds}: {ctx.name} labels its files as they are (no "
                         "simulated part): give one seed")  # fmt: skip
    groups = fold_groups(train, folds, fold_by)
    strengths = check_strengths(prior_strength, folds, train, groups)
    if any(np.isinf(strengths)):
        raise InputError(f"prior strengths {strengths}: {ctx.name}'s prior is a uniform "
                         "table, not the config's parameters; give finite strengths")  # fmt: skip
    check_disjoint(train, validate)
    base = check_config(ctx.name, config)
    with ctx.timed("read"):
        tables = {p: _read(p) for p in [*train, *validate]}
    layout = _layout(config, tables)
    counts = {p: _counts(p, tables[p], layout) for p in train}
    cv, held = None, {}
    if folds:
        with ctx.timed("cross-validate"):
            cv, held = _cross_validate(ctx, tables, counts, layout, config, strengths, folds,
                                       groups)  # fmt: skip
    strength = strengths[0] if cv is None else cv.chosen
    fitted = _fitted(ctx.name, config, layout, counts, train, strength)
    check_config(ctx.name, fitted)
    with ctx.timed("score"):
        files = [_score_file(ctx, p, tables[p], config, base, fitted, train, held.get(p))
                 for p in ctx.progress(tables, len(tables), "files")]
    (ctx.outdir / "config.json").write_text(json.dumps(fitted, indent=1) + "\n",
                                            encoding="utf-8")  # fmt: skip
    plot_fit(ctx, files, "parameters", "error (1 - pairwise F1)")
    total = sum_counts([counts[p] for p in train])
    params = {"prior_strength": shown_strength(strength), "folds": folds, "fold_by": fold_by,
              **({} if groups is None else {"validation_of_training_recordings":
                                            held_of_training(validate, fold_by, groups)}),
              **({} if cv is None else {"cross_validation": cv_record(cv)}),
              "validation_same_recording": _same_recordings(tables, train, validate),
              "num_cameras": layout[0], "num_borders": layout[1],
              "training_passes": total.passes, "training_people": total.people,
              "training_moves": int(total.travel[0].sum()),
              "fitted": {k: fitted[k] for k in ("p_new", "within_std", "between_std")
                         if k in fitted}}  # fmt: skip
    return {"parameters": params, "metrics": mean_errors(files), "files": files,
            "outputs": ["config.json", "fit.png"]}


def _read(path: str):
    """The passes of ``path``, which must name every pass's person."""
    table = read_observations(path)
    if table.person is None:
        raise InputError(f"{path}: no person on every pass: dbntrack fit needs the people "
                         "(a person column)")  # fmt: skip
    return table


def _layout(config: dict, tables: dict) -> tuple[int, int]:
    """(cameras, borders): the config's, else one more than the largest ids of the files;
    a dense path table too large to count in is refused, naming the file with the largest
    ids (:func:`models.track.zajdel.check_path_size`), before anything is counted."""
    ids = {p: (int(t.obs.camera.max()) + 1,
               int(max(t.obs.border_enter.max(), t.obs.border_quit.max())) + 1)
           for p, t in tables.items()}  # fmt: skip
    C = integer(config, "num_cameras", max(c for c, _ in ids.values()))
    B = integer(config, "num_borders", max(b for _, b in ids.values()))
    check_path_size(max(ids, key=lambda p: ids[p][0] * ids[p][1]), config, C, B)
    return C, B


def _same_recordings(tables: dict, train: list[str], validate: list[str]) -> dict[str, str]:
    """Each held-out file (resolved) of which at least half the passes are a training
    file's, with that file: the same passes (a copy, a cut, other ids or times), whose error
    is not held out. A pass is matched by its camera and its appearance to 6 significant
    digits (features of real data do not repeat)."""

    def keys(table) -> set:
        o = table.obs
        return {(int(c), *(f"{x:.6g}" for x in a)) for c, a in zip(o.camera, o.appearance)}

    return copies_of_training({p: keys(tables[p]) for p in [*train, *validate]}, train,
                              validate)  # fmt: skip


def _counts(path: str, table, layout: tuple[int, int]):
    try:
        return pass_counts(table.obs, table.person, *layout, ids=table.ids)
    except DBNError as exc:
        raise in_file(exc, path) from None


def _fitted(name: str, config: dict, layout, counts: dict, files: list[str],
            strength: float) -> dict:
    """The config with the parameters fitted on ``files`` written over it."""
    try:
        total = sum_counts([counts[p] for p in files])
        return fitted_config(name, config, layout, fit_counts(total, strength))
    except InputError as exc:
        raise InputError(f"training files {files}: {exc}") from None


def fitted_config(name: str, config: dict, layout: tuple[int, int], fitted) -> dict:
    """``config`` with the :class:`~models.zajdel.fit.PassFit` ``fitted``'s keys of tracker
    ``name`` (:data:`FITTED_KEYS`) and the layout written over it (arrays as lists)."""
    values = {k: np.asarray(getattr(fitted, k)).tolist() for k in FITTED_KEYS[name]}
    return {**config, "num_cameras": layout[0], "num_borders": layout[1], **values}


def _error(ctx: RunContext, path: str, table, config: dict, checked=None) -> tuple[float, float]:
    """``(1 - pairwise F1, q)`` of the tracker's labels of ``table`` against its people."""
    from models.zajdel.metrics import pairwise_prf, partition_accuracy

    labels = label_passes(ctx, table, config, path, checked)[0]
    return 1.0 - pairwise_prf(labels, table.person)[2], partition_accuracy(labels, table.person)


def _score_file(ctx: RunContext, path: str, table, config: dict, base, fitted: dict,
                train: list[str], held: float | None) -> dict:
    """One file's row: its passes and people, the error and ``q`` with the config's and the
    fitted parameters, and under cross-validation ``error_cv`` (the other folds' fit)."""
    mine, new = _error(ctx, path, table, config, base), _error(ctx, path, table, fitted)
    row = {"file": str(Path(path).resolve()), "split": "train" if path in train else "validation",
           "passes": int(table.obs.num_obs), "people": int(np.unique(table.person).size),
           "error_config": mine[0], "error_fitted": new[0], "q_config": mine[1],
           "q_fitted": new[1]}  # fmt: skip
    if held is not None:
        row["error_cv"] = held
    return row


def _cross_validate(ctx: RunContext, tables: dict, counts: dict, layout, config: dict,
                    strengths: list, folds: int, groups):
    """Each training file labelled with the parameters fitted on the other folds, for every
    strength (:func:`models.track.fitting.cross_validate_files`); and each file's error
    under the chosen strength's fit on the other folds."""

    def score(fitted: dict, path: str) -> tuple[float, float]:
        error = _error(ctx, path, tables[path], fitted)[0]
        return error, error

    return cross_validate_files(
        ctx, list(counts), strengths, folds, groups,
        lambda files, strength: _fitted(ctx.name, config, layout, counts, files, strength),
        score)


def fit_report(summary: dict) -> list[str]:
    """The lines ``dbntrack fit zajdel_*`` prints for ``summary``
    (:func:`models.track.fitting.report`): each file's passes, people, error and ``q``."""

    def row_text(row: dict, other: str) -> str:
        return (f"{row['passes']} passes of {row['people']} people, error "
                f"{row['error_config']:.3f} (config) -> {row['error_fitted']:.3f} (fitted)"
                f"{other}; q {row['q_config']:.3f} -> {row['q_fitted']:.3f}")

    return report(summary, row_text, "parameters",
                  "of which half the passes or more are a training file's")
