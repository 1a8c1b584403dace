"""K-fold cross-validation over files: the error of a fit on data it was not fitted on,
measured on the training files alone, and the candidate setting of the fit that
minimises it.

The items (training files) are cut, in the order given, into ``k`` contiguous folds as
equal as can be (the first ``n mod k`` folds one item longer, as
:func:`numpy.array_split`); each fold's items are scored by the fit on the other
``k - 1`` folds. A scene in two folds leaks into its own score, so a fold must hold whole
recordings: keep the files of one recording next to each other, or give each item its
group (``groups``, e.g. :func:`group_keys` of the file names): the groups, in the order
they first appear, are then cut as the items would be, and a fold holds every item of its
groups (as group K-fold).

For every candidate ``c`` the cross-validation error is the mean over items (each weighs
the same) of ``error(fit(other folds, c), item)``; :func:`cross_validate` chooses the
candidate with the lowest (the first given on a tie), and
:meth:`CrossValidation.versus_chosen` says how far each other candidate is from it (the
paired difference over the items, and its standard error). Held-out files that took no
part in the choice still give the error to quote.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Hashable, Iterable, Sequence
from typing import Any, NamedTuple

import numpy as np

from dbn.errors import InputError

__all__ = ["CrossValidation", "cross_validate", "fold_blocks", "group_keys"]


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

    def versus_chosen(self, candidate: Hashable) -> tuple[float, float]:
        """``(mean, standard error)`` over the items of ``candidate``'s error minus the
        chosen one's, paired item by item (both are scored on the same items, so their
        difference varies less than either mean): how far a candidate is from the choice,
        against the noise of the items. ``(0, 0)`` for the chosen one; an
        :class:`InputError` for a candidate that was not scored."""
        if candidate not in self.errors:
            raise InputError(f"versus_chosen: {candidate!r} is not one of the candidates "
                             f"{list(self.errors)}")  # fmt: skip
        items = list(self.errors[self.chosen])
        diff = np.array([self.errors[candidate][x] - self.errors[self.chosen][x] for x in items])
        return float(np.mean(diff)), float(np.std(diff, ddof=1) / np.sqrt(diff.size))


def fold_blocks(items: Sequence[Hashable], k: int,
                groups: Sequence[Hashable] | None = None) -> list[list]:
    """``items`` cut in order into ``k`` contiguous folds, the first ``len(items) mod k``
    one item longer; with ``groups`` (one per item), the distinct groups in the order they
    first appear are so cut, and each fold holds its groups' items in the order given.

    Raises
    ------
    InputError
        ``k`` not an integer from 2 to the number of items (of groups), an item given
        twice, or ``groups`` not one per item.
    """
    items = _as_list("items", items)
    _check_unique(items)
    units = items if groups is None else list(dict.fromkeys(_per_item(items, groups)))
    what = "training files" if groups is None else "groups of training files"
    if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or not 2 <= k <= len(units):
        raise InputError(f"folds {k!r}: expected an integer from 2 to the number of {what} "
                         f"({len(units)}), each fold scored by a fit on the others")  # fmt: skip
    cuts = np.cumsum([0] + [len(b) for b in np.array_split(np.arange(len(units)), int(k))])
    if groups is None:
        return [items[a:b] for a, b in zip(cuts[:-1], cuts[1:])]
    fold_of = {u: i for i, (a, b) in enumerate(zip(cuts[:-1], cuts[1:])) for u in units[a:b]}
    folds: list[list] = [[] for _ in range(int(k))]
    for item, group in zip(items, groups):
        folds[fold_of[group]].append(item)
    return folds


def _as_list(what: str, value: Any) -> list:
    """``value`` as a list; a string (split into its letters before) or what is not a
    collection is an :class:`InputError` naming ``what``."""
    if isinstance(value, str | bytes) or not isinstance(value, Iterable):
        raise InputError(f"cross-validation: {what} must be a list, got {value!r:.60}")
    return list(value)


def _check_unique(items: list) -> None:
    """An :class:`InputError` for the first item given twice (scored by a fit on itself),
    or one that is not hashable."""
    seen: set = set()
    for item in items:
        _check_hashable(item, f"item {item!r}", "a file path names an item")
        if item in seen:
            raise InputError(f"cross-validation: {item!r} given twice (it would be scored by "
                             "a fit on itself)")  # fmt: skip
        seen.add(item)


def _per_item(items: list, groups: Sequence[Hashable]) -> list:
    """``groups`` as a list, checked to hold one hashable group per item."""
    groups = _as_list("groups", groups)
    if len(groups) != len(items):
        raise InputError(f"cross-validation: {len(groups)} groups for {len(items)} items "
                         "(expected one group per item)")  # fmt: skip
    for item, group in zip(items, groups):
        _check_hashable(group, f"the group {group!r} of {item!r}",
                        "a string or a number names a group")  # fmt: skip
    return groups


def _check_hashable(value: Any, what: str, hint: str) -> None:
    """An :class:`InputError` saying that ``what`` is not hashable, with ``hint``, where
    ``value`` is not (a fold's items and groups key dicts and sets)."""
    try:
        hash(value)
    except TypeError:
        raise InputError(f"cross-validation: {what} is not hashable ({hint})") from None


def group_keys(items: Sequence[str], pattern: str) -> list[str]:
    r"""The group of each item (a file path, as given) for :func:`fold_blocks`: the part
    the regular expression ``pattern`` first matches (:func:`re.search`), its first group
    where it has one. E.g. ``r"(.*)_seed\d+"`` puts ``walk_seed0.jsonl`` and
    ``walk_seed1.jsonl`` in the group ``walk``; ``r"^.*/"`` groups files by folder.

    Raises
    ------
    InputError
        ``pattern`` not a regular expression, or an item it does not match (or whose first
        group takes no part in the match).
    """
    try:
        rx = re.compile(pattern)
    except (re.error, TypeError) as exc:
        raise InputError(f"fold groups {pattern!r}: not a regular expression ({exc})") from None
    keys = []
    for item in _as_list("items", items):
        m = rx.search(str(item))
        if m is None:
            raise InputError(f"fold groups {pattern!r}: no match in {str(item)!r} (every "
                             "training file needs a group)")  # fmt: skip
        if rx.groups and m.group(1) is None:
            raise InputError(f"fold groups {pattern!r}: its first group takes no part in the "
                             f"match in {str(item)!r}")  # fmt: skip
        keys.append(m.group(1) if rx.groups else m.group(0))
    return keys


def cross_validate(items: Sequence[Hashable], k: int, candidates: Sequence[Hashable],
                   fit: Callable[[list, Hashable], Any], error: Callable[[Any, Hashable], float],
                   progress: Callable[[Iterable, int], Iterable] | None = None,
                   groups: Sequence[Hashable] | None = None) -> CrossValidation:
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
    groups : sequence of hashable, optional
        Each item's group (e.g. its recording): no group is split between folds
        (:func:`fold_blocks`).

    Returns
    -------
    CrossValidation

    Raises
    ------
    InputError
        A bad ``k``, a repeated item or bad ``groups`` (:func:`fold_blocks`), no candidate
        or one twice.
    """
    folds = fold_blocks(items, k, groups)
    candidates = _as_list("candidates", candidates)
    try:
        distinct = len(set(candidates))
    except TypeError:
        distinct = -1  # an unhashable candidate cannot key the errors
    if not candidates or distinct != len(candidates):
        raise InputError(f"cross-validation: candidates {candidates!r}: expected at least one, "
                         "none twice, each hashable")  # fmt: skip
    jobs = [(c, i) for c in candidates for i in range(len(folds))]
    errors: dict[Any, dict[Any, float]] = {c: {} for c in candidates}
    for c, i in jobs if progress is None else progress(jobs, len(jobs)):
        model = fit([x for j, fold in enumerate(folds) if j != i for x in fold], c)
        for x in folds[i]:
            errors[c][x] = float(error(model, x))
    mean = {c: float(np.mean([errors[c][x] for x in items])) for c in candidates}
    chosen = min(candidates, key=lambda c: mean[c])  # min keeps the first of equals
    return CrossValidation(folds, errors, mean, chosen)
