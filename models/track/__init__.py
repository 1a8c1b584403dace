"""``dbntrack track`` / ``dbntrack eval``: one runner module per tracker.

A runner module (``models.track.<name>``) offers

* ``INPUTS``: what the positional inputs of ``dbntrack track NAME`` are (one line each);
* ``track(ctx, inputs, config) -> dict``: read the inputs (:mod:`models.io`), build the
  tracker from the registry (``models.get(name).make``) and run it through the protocol
  (:mod:`models.protocol`), write the results and figures into ``ctx.outdir``; returns the
  ``parameters`` and ``outputs`` for ``summary.json`` (and ``metrics`` when ``config``
  holds a ``truth`` file);
* ``evaluate(result, truth) -> dict``: the tracker's metrics of a result file against a
  truth file;
* optionally ``fit(ctx, train, validate, config, seeds, prior_strength, folds, fold_by)
  -> dict`` (``dbntrack fit``): the tracker's parameters fitted on training files whose
  truth is known, written into ``ctx.outdir`` as a config for ``track``, with the errors on
  the training and the held-out files, and with ``folds`` >= 2 the cross-validation over
  the training files that chooses among several prior strengths, its folds keeping
  together the files of one recording (``fold_by``, a regular expression) where given
  (``jorge``: :mod:`models.track.jorge_fit`; ``zajdel_adf`` and ``zajdel_learnsearch``:
  :mod:`models.track.zajdel_fit`; their shared parts: :mod:`models.track.fitting`;
  ``localization``: :mod:`models.track.localization_fit` and ``pathrecovery``:
  :mod:`models.track.pathrecovery_fit`, measurements and searches without prior
  strengths or folds), with
  ``fit_report(summary) -> list[str]``, the lines ``dbntrack fit`` prints of it, and
  optionally ``DEFAULT_PRIOR_STRENGTH``, the strengths where ``--prior-strength`` is not
  given (else ``(0.0,)``).

``dbn`` (any two-slice DBN from a BIF file) is not a tracker of the registry: it runs the
library's generic engines.
"""

from __future__ import annotations

import importlib
import importlib.util

__all__ = ["RUNNERS", "available", "runner"]

# name -> runner module; the registry's trackers plus the generic DBN filter
RUNNERS: dict[str, str] = {
    "dbn": "models.track.dbn",
    "localization": "models.track.localization",
    "zajdel_adf": "models.track.zajdel",
    "zajdel_learnsearch": "models.track.zajdel",
    "pathrecovery": "models.track.pathrecovery",
    "jorge": "models.track.jorge",
    "rjmcmc3d": "models.track.rjmcmc3d",
}


def available() -> list[str]:
    """The names whose runner module is present."""
    return [n for n, m in RUNNERS.items() if importlib.util.find_spec(m) is not None]


def runner(name: str):
    """The runner module of ``name`` (:class:`dbn.errors.InputError` listing the valid
    names when unknown or not written yet)."""
    from dbn.errors import InputError

    valid = available()
    if name not in valid:
        raise InputError(f"unknown tracker {name!r}; valid: {', '.join(valid)}")
    return importlib.import_module(RUNNERS[name])
