"""Confirming a change of the label network on fresh training-side seeds (issue 16).

A change the grid search (:func:`models.jorge.fit.search_settings`) cannot express (new
evidence, a new link rule) lands only after a comparison whose rule is written down before
it runs (:data:`models.jorge.fit.CONFIRM_SEEDS` records every one, and the next fresh
seeds). This module is that comparison, so that anyone can run it again:

* :func:`refit`: the default network with some :class:`NetworkConfig` fields changed, its
  parameters fitted again on the declared training split as the search fits them (a change
  of the link rule changes the events the fit counts); no change gives the default back;
* :func:`confirmation_sets`: the 12 scoring sets of one seed: the training sequences and
  SIMULATED meetings of 3-5 people of :func:`models.jorge.fit.scoring_groups`, plus the
  same meetings at PETS2009's 7 fps (:func:`models.jorge.fit.meeting_strokes`; since issue
  16's thirty-first round);
* :func:`compare`: both networks label every set of every seed; per seed the mean error
  over its sets, and the paired difference's mean and standard error over the seeds.

``python -m models.jorge.confirm --set max_gap_frames=60 --seeds 960 1000 --workers 2``
prints the comparison as one JSON line. Only training-side data is labelled (never the
held-out validation sequences).
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Callable, Mapping, Sequence
from typing import NamedTuple

import numpy as np

from dbn.errors import InputError
from models.jorge.estimate import mean_and_standard_error
from models.jorge.network import NetworkConfig
from models.jorge.strokes import PETS2009_FPS, StrokeSet

__all__ = ["Comparison", "refit", "confirmation_sets", "compare", "main"]


class Comparison(NamedTuple):
    """A paired comparison of two networks over seeds.

    Attributes
    ----------
    seeds : tuple of int
    incumbent, candidate : ndarray, shape (num_seeds,)
        Mean error rate over each seed's sets.
    per_set : dict name -> (float, float)
        Each set's mean error over the seeds, incumbent then candidate (sets of the same
        name, e.g. the meetings at 25 and 7 fps, are told apart by their frame rate).
    """

    seeds: tuple
    incumbent: np.ndarray
    candidate: np.ndarray
    per_set: dict

    @property
    def difference(self) -> float:
        """Mean paired difference, candidate minus incumbent (negative: the candidate is better)."""
        return float(np.mean(self.candidate - self.incumbent))

    @property
    def standard_error(self) -> float:
        """Standard error of :attr:`difference` (NaN with one seed)."""
        return mean_and_standard_error(self.candidate - self.incumbent)[1]

    @property
    def lower_on(self) -> int:
        """Seeds where the candidate's mean error is lower."""
        return int(np.sum(self.candidate < self.incumbent))

    def summary(self) -> dict:
        """The figures a closing note quotes (JSON-ready; the standard error None with one seed)."""
        return {"seeds": list(self.seeds), "num_seeds": len(self.seeds),
                "incumbent": float(np.mean(self.incumbent)), "candidate": float(np.mean(self.candidate)),
                "difference": self.difference,
                "standard_error": None if np.isnan(self.standard_error) else self.standard_error,
                "lower_on": self.lower_on, "per_set": self.per_set}


def refit(changes: Mapping[str, object] | None = None) -> NetworkConfig:
    """The default network with ``changes`` (``NetworkConfig`` field -> value), its
    parameters fitted again on the training split at the search's default point
    (:data:`models.jorge.fit.DEFAULT_POINT`); ``refit()`` is :class:`NetworkConfig` itself.

    Raises
    ------
    InputError
        A name that is not a ``NetworkConfig`` field, or one the fit sets.
    FileNotFoundError
        No training sequence in the data folder.
    """
    from models.jorge.fit import (
        DEFAULT_POINT,
        FITTED_FIELDS,
        TRAIN_SEEDS,
        fit_parameters,
        point_config,
        training_strokes,
    )

    changes = dict(changes or {})
    names = {f.name for f in dataclasses.fields(NetworkConfig)}
    bad = sorted(set(changes) - (names - FITTED_FIELDS))
    if bad:
        raise InputError(f"refit: {bad} are not NetworkConfig fields a change may set "
                         f"(the fit sets {sorted(FITTED_FIELDS)})")
    sets = training_strokes(seeds=TRAIN_SEEDS)
    if not sets:
        raise FileNotFoundError("refit: no training sequence found (set DBNTRACK_DATA to the shared data folder)")
    point = {**DEFAULT_POINT, **{k: v for k, v in changes.items() if k in DEFAULT_POINT}}
    gated = dataclasses.replace(NetworkConfig(), **{**changes, "gate": point["gate"], "merge_area": point["merge_area"]})
    return point_config(gated, fit_parameters(sets, gated), point)


def confirmation_sets(seed: int) -> list[StrokeSet]:
    """The scoring sets of one seed (module docstring): 9 with the shared data, plus the 3
    SIMULATED meetings at 7 fps."""
    from models.jorge.fit import meeting_strokes, scoring_groups

    return scoring_groups((seed,))[0] + meeting_strokes((seed,), fps=PETS2009_FPS)


def _set_name(strokes: StrokeSet) -> str:
    return f"{strokes.name} at {strokes.fps:g} fps"


def _label_one(job: tuple) -> tuple[str, float, float]:
    """(set name, incumbent's error rate, candidate's) of one set."""
    from models.jorge.fit import _error_and_speed

    incumbent, candidate, strokes = job
    return _set_name(strokes), _error_and_speed((incumbent, strokes))[0], _error_and_speed((candidate, strokes))[0]


def compare(candidate: NetworkConfig, seeds: Sequence[int], incumbent: NetworkConfig | None = None,
            sets: Callable[[int], Sequence[StrokeSet]] = confirmation_sets, workers: int = 1) -> Comparison:
    """Label every set of every seed with both networks (module docstring).

    Parameters
    ----------
    candidate, incumbent : NetworkConfig
        ``incumbent`` defaults to :class:`NetworkConfig` (the default network).
    seeds : sequence of int
        Fresh seeds, written down with the rule before the run.
    sets : callable seed -> sequence of StrokeSet
        The sets of one seed (default :func:`confirmation_sets`).
    workers : int
        Processes labelling in parallel (1: in this process).

    Raises
    ------
    InputError
        No seeds, a repeated seed, or a seed with no set.
    """
    seeds = tuple(int(s) for s in seeds)
    if not seeds or len(set(seeds)) != len(seeds):
        raise InputError(f"compare: give distinct seeds, got {list(seeds)}")
    from models.jorge.fit import _map

    incumbent = NetworkConfig() if incumbent is None else incumbent
    jobs, owner = [], []
    for s in seeds:
        group = list(sets(s))
        if not group:
            raise InputError(f"compare: seed {s} has no set to label")
        jobs += [(incumbent, candidate, st) for st in group]
        owner += [s] * len(group)
    rows = _map(_label_one, jobs, workers)
    a, b = (np.array([np.mean([r[i] for r, o in zip(rows, owner) if o == s]) for s in seeds]) for i in (1, 2))
    per_set = {name: (float(np.mean([r[1] for r in rows if r[0] == name])),
                      float(np.mean([r[2] for r in rows if r[0] == name]))) for name in dict.fromkeys(r[0] for r in rows)}
    return Comparison(seeds, a, b, per_set)


def _parse_change(text: str) -> tuple[str, object]:
    name, sep, value = text.partition("=")
    if not sep or not name:
        raise InputError(f"--set {text!r}: expected FIELD=VALUE (VALUE in JSON, e.g. max_gap_frames=60)")
    try:
        return name, json.loads(value)
    except json.JSONDecodeError:
        raise InputError(f"--set {text!r}: the value {value!r} is not JSON") from None


def main(argv: Sequence[str] | None = None) -> None:
    """``python -m models.jorge.confirm --set FIELD=VALUE [...] --seeds FIRST STOP [--workers 2]``:
    the default network against the same with the changes, refitted (:func:`refit`), on
    seeds ``FIRST`` .. ``STOP - 1``; one JSON line (:meth:`Comparison.summary`)."""
    import argparse

    ap = argparse.ArgumentParser(prog="python -m models.jorge.confirm", description=main.__doc__)
    ap.add_argument("--set", action="append", default=[], metavar="FIELD=VALUE", dest="changes",
                    help="a NetworkConfig field of the candidate, VALUE in JSON (repeat for several)")
    ap.add_argument("--seeds", nargs=2, type=int, required=True, metavar=("FIRST", "STOP"),
                    help="fresh seeds FIRST .. STOP - 1 (models.jorge.fit.CONFIRM_SEEDS says which are fresh)")
    ap.add_argument("--workers", type=int, default=1, help="processes labelling in parallel")
    args = ap.parse_args(argv)
    changes = dict(_parse_change(c) for c in args.changes)
    if args.seeds[1] <= args.seeds[0]:
        raise InputError(f"--seeds {args.seeds[0]} {args.seeds[1]}: STOP must be above FIRST")
    result = compare(refit(changes), range(*args.seeds), refit(), workers=args.workers)
    print(json.dumps({"changes": changes, **result.summary()}))


if __name__ == "__main__":
    main()
