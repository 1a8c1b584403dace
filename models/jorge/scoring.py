r"""Scoring a labelling against the true sets of people (seed 004, Table 3), the true
stroke graph (the benchmark's oracle links and its diagnoses) and the colour-only baseline.

An object id ``o`` is the object first seen in stroke ``o``. Objects are matched one to
one with people, by default with the matching that maximises co-occurrences (as IDF1
matches identities); with ``mapping="first_seen"`` an object stands for the person of
the stroke where it was first seen, if that stroke held one person not already
claimed. A stroke is a labelling error (LE) when the people its label stands for
differ from its true set. Identity switches: over each person's
one-person strokes in time order, the number of consecutive pairs given different
labels.

The true predecessors of a stroke (:func:`true_predecessors`) are, for each of its
people, the latest earlier stroke holding that person that ended before it starts;
:func:`true_links` turns them into links the label network can hold, :func:`first_errors`
and :func:`after_crowd` split the errors for the benchmark's diagnosis keys, and
:func:`link_accuracy` measures the on-line link rule against them.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment

from dbn.checks import check_count
from dbn.errors import InputError
from models.jorge.evidence import colour_log_likelihood
from models.jorge.labels import Label, birth_stroke
from models.jorge.strokes import Stroke

__all__ = [
    "Score",
    "score",
    "object_people",
    "optimal_people",
    "stands_for",
    "first_errors",
    "group_errors",
    "after_crowd",
    "true_predecessors",
    "true_links",
    "link_accuracy",
    "colour_only_labels",
]


@dataclass(frozen=True)
class Score:
    """Labelling errors (seed 004, Table 3) and identity switches.

    Attributes
    ----------
    label_errors : int
        LE, strokes whose label stands for a set of people other than the true set.
    num_strokes : int
        NT.
    error_rate : float
        LE / NT.
    id_switches : int
    errors : tuple of int
        Indices of the mislabelled strokes.
    """

    label_errors: int
    num_strokes: int
    error_rate: float
    id_switches: int
    errors: tuple


def object_people(strokes: Sequence[Stroke]) -> dict[int, int | None]:
    """Who each object id stands for (module docstring): ``o -> person`` or ``None``."""
    out: dict[int, int | None] = {}
    claimed: set[int] = set()
    for s in strokes:
        if len(s.truth) == 1:
            (p,) = tuple(s.truth)
            if p not in claimed:
                out[s.index] = p
                claimed.add(p)
                continue
        out[s.index] = None
    return out


def optimal_people(strokes: Sequence[Stroke], labels: Sequence[Label]) -> dict[int, int | None]:
    """Who each object id stands for under the best one-to-one matching of objects and
    people (as IDF1 does for identities): the matching maximises the number of strokes in
    which object and person occur together (Hungarian algorithm); unmatched objects stand
    for nobody."""
    objects = sorted({o for lab in labels for o in lab})
    persons = sorted({p for s in strokes for p in s.truth})
    out: dict[int, int | None] = {o: None for o in objects}
    if not objects or not persons:
        return out
    oi = {o: i for i, o in enumerate(objects)}
    pi = {p: j for j, p in enumerate(persons)}
    weight = np.zeros((len(objects), len(persons)))
    for s, lab in zip(strokes, labels):
        rows = [oi[o] for o in lab]
        cols = [pi[p] for p in s.truth]
        weight[np.ix_(rows, cols)] += 1.0
    r, c = linear_sum_assignment(weight, maximize=True)
    for i, j in zip(r, c):
        if weight[i, j] > 0:
            out[objects[i]] = persons[j]
    return out


def stands_for(label: Label, people: dict[int, int | None]) -> set:
    """The people ``label`` stands for under the matching ``people`` (:func:`optimal_people`
    or :func:`object_people`): an object matched to nobody stands for ``("nobody", o)``, so
    a label holding one never equals a true set."""
    return {people[o] if people.get(o) is not None else ("nobody", o) for o in label}


def score(strokes: Sequence[Stroke], labels: Sequence[Label], mapping: str = "optimal") -> Score:
    """LE, LE / NT and identity switches of a labelling.

    Parameters
    ----------
    strokes : sequence of Stroke, length num_strokes
        With their true sets.
    labels : sequence of Label, length num_strokes
        Label of each stroke (sets of object ids, object ``o`` = first seen in stroke ``o``).
    mapping : {"optimal", "first_seen"}
        How object ids are matched to people: the best one-to-one matching
        (:func:`optimal_people`, default) or the person of the stroke where the object was
        first seen, if not already claimed (:func:`object_people`, stricter: one early
        mistake makes every later stroke of that person an error).

    Returns
    -------
    Score
    """
    strokes = list(strokes)
    labels = list(labels)
    if len(labels) != len(strokes):
        raise InputError(f"score: {len(labels)} labels for {len(strokes)} strokes")
    known = {s.index for s in strokes}
    for s, lab in zip(strokes, labels):
        unknown = [o for o in lab if birth_stroke(o) not in known]
        if unknown or not lab:
            raise InputError(f"score: stroke {s.index} has label {set(lab)} with unknown object ids {unknown}")
    if mapping == "optimal":
        people = optimal_people(strokes, labels)
    elif mapping == "first_seen":
        people = object_people(strokes)
    else:
        raise InputError(f"score: mapping must be 'optimal' or 'first_seen', got {mapping!r}")
    errors = [s.index for s, lab in zip(strokes, labels) if stands_for(lab, people) != set(s.truth)]
    switches = 0
    last: dict[int, Label] = {}
    for s, lab in zip(strokes, labels):
        if len(s.truth) == 1:
            (p,) = tuple(s.truth)
            if p in last and last[p] != lab:
                switches += 1
            last[p] = lab
    n = len(strokes)
    return Score(len(errors), n, len(errors) / n if n else 0.0, switches, tuple(errors))


def group_errors(strokes: Sequence[Stroke], errors: Iterable[int],
                 min_people: int = 3) -> tuple[int, int]:
    """``(wrong, total)``: of the strokes whose true group has ``min_people`` or more people,
    the number among ``errors`` (stroke indices, :attr:`Score.errors`) and the number in
    all; issue 16's ``error_rate_group_3plus`` is ``wrong / total`` with the default."""
    big = {s.index for s in strokes if len(s.truth) >= min_people}
    return len(big & {int(e) for e in errors}), len(big)


def first_errors(strokes: Sequence[Stroke], errors: Iterable[int]) -> tuple:
    """The labelling errors that are first mistakes: strokes in error none of whose true
    predecessors (for each of its people, the latest earlier stroke holding that person,
    ended before it starts) is in error. The other errors are carried: a wrong label
    inherited along the links.

    Parameters
    ----------
    strokes : sequence of Stroke, length num_strokes
        In start order, with their true sets.
    errors : iterable of int
        Indices of the mislabelled strokes (:attr:`Score.errors`).

    Returns
    -------
    tuple of int
        The first mistakes, in index order.
    """
    strokes = list(strokes)
    bad = set(int(e) for e in errors)
    unknown = sorted(e for e in bad if not 0 <= e < len(strokes))
    if unknown:
        raise InputError(f"first_errors: error indices {unknown} outside 0..{len(strokes) - 1}")
    preds = true_predecessors(strokes)
    return tuple(k for k in sorted(bad) if not preds[k] & bad)


def after_crowd(strokes: Sequence[Stroke], max_group_size: int) -> np.ndarray:
    """Strokes one of whose people was earlier in a crowd: a stroke of more than
    ``max_group_size`` people that ended before this one starts.

    A label holds at most ``max_group_size`` objects, so a crowd's label leaves some of its
    people out, and a later stroke of one of them inherits a label that does not hold
    them (a diagnosis of the benchmark; nothing is chosen on it).

    Parameters
    ----------
    strokes : sequence of Stroke, length num_strokes
        With their true sets.
    max_group_size : int
        The label network's ``labels.max_group_size``.

    Returns
    -------
    ndarray of bool, shape (num_strokes,)
    """
    check_count("after_crowd: max_group_size", max_group_size)
    strokes = list(strokes)
    first_crowd_end: dict[int, int] = {}  # person -> the earliest end of a crowd stroke holding them
    for s in strokes:
        if len(s.truth) > max_group_size:
            for p in s.truth:
                first_crowd_end[p] = min(first_crowd_end.get(p, s.end), s.end)
    return np.array([any(first_crowd_end.get(p, s.start) < s.start for p in s.truth) for s in strokes], dtype=bool)


def true_predecessors(strokes: Sequence[Stroke]) -> list[frozenset]:
    """For each stroke, its true predecessors: for each of its people, the latest earlier
    stroke holding that person that ended before it starts (the links a perfect stroke
    graph would have; :func:`first_errors` uses the same rule).

    Returns
    -------
    list of frozenset of int, length num_strokes
    """
    strokes = list(strokes)
    latest: dict[int, list[int]] = {}
    out = []
    for k, s in enumerate(strokes):
        preds = set()
        for p in s.truth:
            earlier = [i for i in latest.get(p, []) if strokes[i].end < s.start]
            if earlier:
                preds.add(max(earlier, key=lambda i: strokes[i].end))
        out.append(frozenset(preds))
        for p in s.truth:
            latest.setdefault(p, []).append(k)
    return out


def true_links(strokes: Sequence[Stroke], max_parents: int = 2, max_children: int = 2) -> list[tuple]:
    """The true predecessors (:func:`true_predecessors`) as links the label network can
    hold: at most ``max_parents`` per stroke (the latest-ending first) and
    ``max_children`` per parent (first come), for :func:`label_online` ``links=`` (the
    oracle that measures what the on-line link rule costs; issue 16 diagnosis).

    Returns
    -------
    list of tuple of int, length num_strokes
    """
    strokes = list(strokes)
    children: dict[int, int] = {}
    out = []
    for preds in true_predecessors(strokes):
        kept = [p for p in sorted(preds, key=lambda i: (-strokes[i].end, i))
                if children.get(p, 0) < max_children][:max_parents]
        for p in kept:
            children[p] = children.get(p, 0) + 1
        out.append(tuple(sorted(kept)))
    return out


def link_accuracy(strokes: Sequence[Stroke], parents: Sequence[Iterable[int]]) -> float:
    """Share of strokes whose parents in the label network are exactly their true
    predecessors (:func:`true_predecessors`): how well the on-line link rule recovers
    the stroke graph (issue 16 diagnosis; about 0.5 in the PETS2009 S1 crowds, 0.7-0.95
    on CAVIAR).

    Raises
    ------
    InputError
        ``parents`` not one entry per stroke.
    """
    strokes = list(strokes)
    if len(parents) != len(strokes):
        raise InputError(f"link_accuracy: {len(parents)} parent sets for {len(strokes)} strokes")
    if not strokes:
        return float("nan")
    truth = true_predecessors(strokes)
    return float(np.mean([frozenset(int(p) for p in par) == t for par, t in zip(parents, truth)]))


def colour_only_labels(strokes: Iterable[Stroke], max_group_size: int = 3, match_prob: float = 0.8,
                       pool_size: int = 12, mode: str = "ratio") -> list[Label]:
    """Baseline without the network: each stroke takes the label whose palette matches
    its colours best (eq. 6 alone), among the objects seen so far, their groups of up to
    ``max_group_size``, and a new object (log-likelihood ratio 0 in the default mode).

    Parameters
    ----------
    strokes : iterable of Stroke
        In start order.
    max_group_size : int
    match_prob : float
    pool_size : int
    mode : {"ratio", "eq6"}

    Returns
    -------
    list of Label
        One per stroke; a stroke labelled new founds object ``stroke.index``.
    """
    objects: list[int] = []
    palettes: dict[int, np.ndarray] = {}
    out: list[Label] = []
    for s in strokes:
        new = frozenset({s.index})
        own = np.zeros(pool_size, dtype=bool)
        own[s.palette] = True
        cands: list[Label] = [new]
        blocks = [own[None]]
        obj_pal = np.array([palettes[o] for o in objects]).reshape(len(objects), pool_size)
        for r in range(1, min(max_group_size, len(objects)) + 1):
            idx = np.array(list(itertools.combinations(range(len(objects)), r)), dtype=np.int64)
            cands += [frozenset(objects[i] for i in row) for row in idx]
            blocks.append(obj_pal[idx].any(axis=1))
        pal = np.concatenate(blocks, axis=0)
        is_new = np.zeros(len(cands), dtype=bool)
        is_new[0] = True
        ll = colour_log_likelihood(s.colours, pal, is_new, match_prob, pool_size, mode)
        best = cands[int(np.argmax(ll))]
        if best == new:
            objects.append(s.index)
            palettes[s.index] = own
        out.append(best)
    return out
