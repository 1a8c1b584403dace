"""K-fold cross-validation over files: the error of a fit on data it was not fitted on,
measured on the training files alone, and the candidate setting of the fit that
minimises it.

The items (training files) are cut, in the order given, into ``k`` contiguous folds as
equal as can be (the first ``n mod k`` folds one item longer, as
:func:`numpy.array_split`); each fold's items are scored by the fit on the other
``k - 1`` folds. Keep the files of one recording next to each other, so that a fold
holds whole recordings: a scene in two folds leaks into its own score.

For every candidate ``c`` the cross-validation error is the mean over items (each weighs
the same) of ``error(fit(other folds, c), item)``; :func:`cross_validate` chooses the
candidate with the lowest, the first given on a tie. Held-out files that took no part
in the choice still give the error to quote.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable, Iterable, Sequence
from typing import Any, NamedTuple

import numpy as np

from dbn.errors import InputError

__all__ = ["CrossValidation", "cross_validate", "fold_blocks"]


class CrossValidation(NamedTuple):
    """What :func:`cross_validate` measured.

    Attributes
    ----------
    folds : list of list
        The items of each fold, in the order given.
    errors : dict
        Candidate -> {item: its error under the fit on the other folds}.
    mean : dict
        Candidate -> the mean of its item errors (each item weighs the same).
    chosen : Hashable
        The candidate with the lowest mean error (the first given on a tie).
    """

    folds: list[list]
    errors: dict[Any, dict[Any, float]]
    mean: dict[Any, float]
    chosen: Hashable


def fold_blocks(items: Sequence[Hashable], k: int) -> list[list]:
    """``items`` cut in order into ``k`` contiguous folds, the first ``len(items) mod k``
    one item longer.

    Raises
    ------
    InputError
        ``k`` not an integer from 2 to ``len(items)``, or an item given twice.
    """
    items = list(items)
    if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or not 2 <= k <= len(items):
        raise InputError(f"folds {k!r}: expected an integer from 2 to the number of training "
                         f"files ({len(items)}), each fold scored by a fit on the others")  # fmt: skip
    seen: set = set()
    for item in items:
        if item in seen:
            raise InputError(f"cross-validation: {item!r} given twice (it would be scored by "
                             "a fit on itself)")  # fmt: skip
        seen.add(item)
    cuts = np.cumsum([0] + [len(b) for b in np.array_split(np.arange(len(items)), int(k))])
    return [items[a:b] for a, b in zip(cuts[:-1], cuts[1:])]


def cross_validate(items: Sequence[Hashable], k: int, candidates: Sequence[Hashable],
                   fit: Callable[[list, Hashable], Any], error: Callable[[Any, Hashable], float],
                   progress: Callable[[Iterable, int], Iterable] | None = None) -> CrossValidation:
    """``k``-fold cross-validation of ``fit`` over ``items`` for each of ``candidates``
    (module docstring).

    Parameters
    ----------
    items : sequence of hashable
        The training items (file paths), in fold order.
    k : int
        Number of folds, 2 to ``len(items)``.
    candidates : sequence of hashable
        The settings to choose among (e.g. prior strengths); at least one, none twice.
    fit : callable
        ``fit(training_items, candidate) -> model``.
    error : callable
        ``error(model, item) -> float``: the item's error under ``model``.
    progress : callable, optional
        ``progress(iterable, total)`` wrapping the ``len(candidates) * k`` fits.

    Returns
    -------
    CrossValidation

    Raises
    ------
    InputError
        A bad ``k`` or a repeated item (:func:`fold_blocks`), no candidate or one twice.
    """
    folds = fold_blocks(items, k)
    candidates = list(candidates)
    if not candidates or len(set(candidates)) != len(candidates):
        raise InputError(f"cross-validation: candidates {candidates!r}: expected at least one, "
                         "none twice")  # fmt: skip
    jobs = [(c, i) for c in candidates for i in range(len(folds))]
    errors: dict[Any, dict[Any, float]] = {c: {} for c in candidates}
    for c, i in jobs if progress is None else progress(jobs, len(jobs)):
        model = fit([x for j, fold in enumerate(folds) if j != i for x in fold], c)
        for x in folds[i]:
            errors[c][x] = float(error(model, x))
    mean = {c: float(np.mean([errors[c][x] for x in items])) for c in candidates}
    chosen = min(candidates, key=lambda c: mean[c])  # min keeps the first of equals
    return CrossValidation(folds, errors, mean, chosen)
