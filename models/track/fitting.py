"""What every ``dbntrack fit`` runner shares (:mod:`models.track.jorge_fit`,
:mod:`models.track.zajdel_fit`, :mod:`models.track.localization_fit`,
:mod:`models.track.pathrecovery_fit`): the checks of the files and options before any
file is read, the cross-validation's folds and record, the grid search of the
localization and pathrecovery fits, the mean errors and ``fit.png``.

A runner's ``fit`` returns one row per file (``file``, resolved; ``split``, ``"train"`` or
``"validation"``; ``error_config`` and ``error_fitted``, the file's error with the config's
and the fitted parameters; ``error_cv`` for a training file under cross-validation, with
the fit on the other folds), which these helpers read.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np

from dbn.checks import is_real_number
from dbn.errors import ConfigError, InputError
from models.crossval import CrossValidation, cross_validate, fold_blocks, group_keys
from models.track.context import RunContext, short_names, shown_strength
from models.track.options import array

__all__ = ["check_disjoint", "refuse_strengths", "search_values", "fold_groups", "held_of_training",
           "copies_of_training", "check_strengths", "cross_validate_files", "cv_record",
           "search_grid", "mean_errors", "plot_fit", "report"]  # fmt: skip


def check_disjoint(train: list[str], validate: list[str]) -> None:
    """Refuse a file both fitted on and held out (by resolved path), or given twice."""
    seen: dict[Path, str] = {}
    for p in [*train, *validate]:
        q = Path(p).resolve()
        if q in seen:
            raise InputError(f"{p}: given twice (as {seen[q]!r}); a held-out file must not be "
                             "a training file")  # fmt: skip
        seen[q] = p


def refuse_strengths(name: str, does: str, chooses: str, prior_strength, folds: int,
                     fold_by: str | None) -> None:
    """Refuse ``--prior-strength`` (other than the default 0), ``--folds`` and ``--fold-by``
    for a fit that searches on its training files instead (``does``, e.g. ``"searches its
    weighting"``; ``chooses``, what the search chooses, e.g. ``"its weighting"``)."""
    if list(np.atleast_1d(prior_strength)) != [0.0]:
        raise InputError(f"prior strength {prior_strength!r}: {name}'s fit {does}; it has no "
                         "prior strength")  # fmt: skip
    if folds or fold_by is not None:
        raise InputError(f"--folds / --fold-by: {name}'s fit chooses {chooses} on the training "
                         "runs (no strengths to cross-validate); hold runs out with --validate")


def search_values(config: dict, key: str, default: tuple, most: float = np.inf) -> tuple:
    """The values a search tries: the config's list ``key`` (numbers > 0, or in [0,
    ``most``] where ``most`` is finite; at least one, none twice), sorted, else
    ``default``. A :class:`~dbn.errors.ConfigError` naming the key otherwise."""
    if key not in config:
        return default
    v = array(config, key, ndim=1)
    ok = (v > 0) if np.isinf(most) else (v >= 0) & (v <= most)
    if v.size == 0 or not np.all(ok) or np.unique(v).size != v.size:
        what = "numbers > 0" if np.isinf(most) else f"numbers in [0, {most:g}]"
        raise ConfigError(f"config {key} = {config[key]!r}: expected {what}, at least one, "
                          "none twice")  # fmt: skip
    return tuple(sorted(float(x) for x in v))


def fold_groups(train: list[str], folds: int, fold_by: str | None) -> list[str] | None:
    """Each training file's group (:func:`models.crossval.group_keys`) where ``fold_by`` is
    given, which needs ``folds``; None without it. Checked before any file is read."""
    if fold_by is None:
        return None
    if not folds:
        raise InputError(f"fold groups {fold_by!r}: they group the folds of a cross-validation "
                         "(give folds >= 2)")  # fmt: skip
    return group_keys(train, fold_by)


def held_of_training(validate: list[str], fold_by: str, groups: list[str]) -> list[str]:
    """The held-out files (resolved) whose recording, the match of ``fold_by``, a training
    file's is too (``groups``): their error is not held out from that recording. Held-out
    files the pattern does not match are not compared."""
    train = set(groups)
    out = []
    for p in validate:
        try:
            (key,) = group_keys([p], fold_by)
        except InputError:
            continue
        if key in train:
            out.append(str(Path(p).resolve()))
    return out


def copies_of_training(keys: dict, train: list[str], validate: list[str],
                       share: float = 0.5) -> dict[str, str]:
    """Each held-out file (resolved) of which at least ``share`` of its items (``keys[p]``,
    a set: passes, odometry rows) are a training file's, with the first such training file
    (resolved): a copy or a cut of it, whose error is not held out."""
    out = {}
    for p in validate:
        held = keys[p]
        for q in train:
            if len(held & keys[q]) >= share * len(held):
                out[str(Path(p).resolve())] = str(Path(q).resolve())
                break
    return out


def check_strengths(prior_strength: float | Sequence[float], folds: int, train: list[str],
                    groups: list[str] | None = None) -> list:
    """The prior strengths as a list, each a number >= 0 or inf, none twice; several only
    with ``folds`` to choose among them, and ``folds`` 0 or 2 .. the number of training
    files (of their ``groups``). Checked before any file is read."""
    one = np.ndim(prior_strength) == 0
    strengths = [prior_strength] if one else list(prior_strength)  # type: ignore[arg-type]
    for lam in strengths:
        if not is_real_number(lam) or not lam >= 0:
            raise InputError(f"prior strength {lam!r}: expected a number >= 0 (or inf)")
    if not strengths or len(set(strengths)) != len(strengths):
        raise InputError(f"prior strengths {strengths!r}: expected at least one, none twice")
    if folds:
        fold_blocks(train, folds, groups)  # refuses a bad number of folds
    elif len(strengths) > 1:
        raise InputError(f"prior strengths {strengths!r}: choosing among several needs "
                         "cross-validation (folds >= 2)")  # fmt: skip
    return [float(lam) for lam in strengths]


def cross_validate_files(ctx: RunContext, train: list[str], strengths: list, folds: int,
                         groups: list[str] | None, fit: Callable, score: Callable,
                         advice: str = "") -> tuple[CrossValidation, dict]:
    """Each training file scored with the parameters fitted on the other folds (no group of
    ``groups`` split between folds), for every strength
    (:func:`models.crossval.cross_validate`): ``fit(files, strength) -> model``,
    ``score(model, path) -> (error, record)``. Returns the cross-validation and each
    training file's record under the chosen strength's fit on the other folds. A fit that
    fails (:class:`InputError`) is named by the fold it was for, then ``advice``."""
    seen: dict = {}

    def fit_on(files: list[str], strength: float):
        try:
            return strength, fit(files, strength)
        except InputError as exc:
            held = [p for p in train if p not in files]
            raise InputError(f"cross-validation, the fit for the fold of {held}: {exc}"
                             f"{advice}") from None  # fmt: skip

    def error(model: tuple, path: str) -> float:
        strength, fitted = model
        err, seen[strength, path] = score(fitted, path)
        return err

    cv = cross_validate(train, folds, strengths, fit_on, error, ctx.bar("fits"), groups)
    return cv, {p: seen[cv.chosen, p] for p in train}


def cv_record(cv: CrossValidation) -> dict:
    """The cross-validation for ``summary.json``: each fold's files (resolved, as in
    ``files``), and each strength's mean error of the fits on the other folds, with its
    paired difference from the chosen one's and that difference's standard error over
    the files (:meth:`models.crossval.CrossValidation.versus_chosen`)."""
    rows = []
    for lam, e in cv.mean.items():
        d, se = cv.versus_chosen(lam)
        rows.append({"prior_strength": shown_strength(lam), "error": e,
                     "versus_chosen": d, "versus_chosen_se": se})
    return {"folds": [[str(Path(p).resolve()) for p in fold] for fold in cv.folds],
            "errors": rows, "chosen": shown_strength(cv.chosen)}


def search_grid(ctx: RunContext, axes: Sequence[Sequence[float]], train: list[str],
                error: Callable[[float, float, str], float]) -> dict:
    """``{(a, b): {run: error(a, b, run)}}`` for every pair of ``axes[0]`` x ``axes[1]``
    and every training run, pair by pair, with a progress bar: the search of the
    localization and pathrecovery fits."""
    grid = [(a, b) for a in axes[0] for b in axes[1]]
    jobs = [(pair, p) for pair in grid for p in train]
    out: dict = {pair: {} for pair in grid}
    for pair, p in ctx.progress(jobs, len(jobs), "search"):
        out[pair][p] = error(*pair, p)
    return out


def mean_errors(files: list[dict]) -> dict:
    """``error_{train,validation}_{config,fitted}``: the mean errors over the training and
    the held-out files (each file weighs the same; NaN where there are none), and under
    cross-validation ``error_cv_fitted``, the mean of the training files' ``error_cv``."""
    out = {}
    for split in ("train", "validation"):
        rows = [f for f in files if f["split"] == split]
        for name in ("config", "fitted"):
            out[f"error_{split}_{name}"] = float(np.mean([f[f"error_{name}"] for f in rows])
                                               if rows else np.nan)  # fmt: skip
    rows = [f for f in files if "error_cv" in f]
    if rows:
        out["error_cv_fitted"] = float(np.mean([f["error_cv"] for f in rows]))
    return out


def plot_fit(ctx: RunContext, files: list[dict], fitted: str, error: str) -> None:
    """``fit.png``: each file's ``error`` (the axis label) with the config's and the
    ``fitted`` parameters (e.g. ``"network"``), and, for the training files under
    cross-validation, with the fit on the other folds."""
    size = (min(14.0, max(5.0, 0.45 * len(files) + 2)), 4.0)
    bars = [("config", f"config's {fitted}"), ("fitted", f"fitted {fitted}")]
    if any("error_cv" in f for f in files):
        bars.append(("cv", "fitted on the other folds"))
    with ctx.figure("fit.png", figsize=size) as (_, ax):
        x, width = np.arange(len(files)), 0.8 / len(bars)
        for i, (name, label) in enumerate(bars):
            ax.bar(x + (i - (len(bars) - 1) / 2) * width,
                   [f.get(f"error_{name}", np.nan) for f in files], width, label=label)
        names = short_names([f["file"] for f in files])
        ax.set_xticks(x, [("" if f["split"] == "train" else "held out\n") + names[f["file"]]
                          for f in files], rotation=30, ha="right", fontsize=7)  # fmt: skip
        held = [i for i, f in enumerate(files) if f["split"] != "train"]
        if held and held[0] > 0:  # the training files first, then the held-out ones
            ax.axvline(held[0] - 0.5, color="0.5", lw=0.8, ls="--")
        ax.set_ylabel(error)
        ax.set_title(f"dbntrack fit: each file's error, config's and fitted {fitted}", fontsize=9)
        ax.legend(fontsize=7)


def report(summary: dict, row_text: Callable[[dict, str], str], fitted: str,
           same: str) -> list[str]:
    """The lines ``dbntrack fit`` prints before its closing ones: a line per file
    (``row_text(row, other)``, ``other`` the other folds' fit's error where there is one,
    else empty), the held-out files of training recordings (``--fold-by``) and those that
    hold a training file's data (``parameters.validation_same_recording``, described by
    ``same``, e.g. ``"whose boxes are mostly a training file's"``), and the
    cross-validation's errors by prior strength beside the config's ``fitted`` (e.g.
    ``"network"``) on the training files."""
    name, params = summary["tracker"], summary["parameters"]
    names = short_names([row["file"] for row in summary["files"]])
    lines = []
    for row in summary["files"]:
        other = f" (other folds' fit {row['error_cv']:.3f})" if "error_cv" in row else ""
        lines.append(f"{row['split']:>10}  {names[row['file']]}: {row_text(row, other)}")
    shared = params.get("validation_of_training_recordings")
    if shared:
        lines.append(f"{name}: held-out files of recordings the training files hold too "
                     f"(--fold-by): {', '.join(names[p] for p in shared)}: their errors are not "
                     "held out from those recordings")  # fmt: skip
    copies = params["validation_same_recording"]
    if copies:
        lines.append(f"{name}: held-out files {same}: "
                     f"{', '.join(f'{names[p]} ({names[t]})' for p, t in copies.items())}: "
                     "their errors are not held out")  # fmt: skip
    if "cross_validation" in params:
        cv = params["cross_validation"]
        errors = ", ".join(f"{_number(r['prior_strength'])}: {r['error']:.3f}"
                           + (f" ({r['versus_chosen']:+.3f} +- {r['versus_chosen_se']:.3f})"
                              if r["prior_strength"] != cv["chosen"] else "")
                           for r in cv["errors"])  # fmt: skip
        lines.append(f"{name}: {summary['folds']}-fold cross-validation error by prior strength: "
                     f"{errors}; chosen {_number(cv['chosen'])} (the config's {fitted} on the "
                     f"training files: {summary['metrics']['error_train_config']:.3f})")
    return lines


def _number(value: float | str) -> str:
    """A summary's number for the terminal (``"inf"``, JSON's stand-in, as it is)."""
    return value if isinstance(value, str) else f"{value:g}"
