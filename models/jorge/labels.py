r"""Group labels of seed 004: admissible label sets (eqs. 2, 7-9), the CPDs of the basic
structures (fig. 3; eqs. 3-5 and 10) and label pruning. The colour model (eq. 6) and the
other soft evidence of a label are in :mod:`models.jorge.evidence` (their names are also
importable from here, as before).

A *label* is a frozenset of object ids: ``{3}`` is object 3 alone, ``{1, 2}`` the group
of objects 1 and 2. Objects are born at strokes: the new label ``l_new`` of stroke ``k``
is ``{k}`` ("the object first seen in stroke k"), as in Table 2 of seed 004.

Groups of any size (issue 16, our additions). In the seed a stroke seen for the first
time is one new object, so a group that enters together (or is first seen as a group)
can never be labelled as a group, nor can any of its later strokes; and a stroke that is
its parent's group plus a person arriving unseen is not admissible. Hence, optionally:
new groups, ``new_objects(k, m)`` (``m`` objects born at stroke ``k``, prior
:math:`q_m`, ``LabelParams.new_group_probs``), and joins, an inherited label plus
``{k}`` (``LabelParams.p_join``). The cap ``max_group_size`` (3 before issue 16, so a
group of 4 or 5 was never admissible) is 5 by default.

The seven basic structures
--------------------------
Seed 004 limits a node to two parents and two hidden children, and states that seven
basic structures follow (fig. 3, not reproduced in the text we have), giving only
eqs. 3, 4, 5 and 10 and leaving the rest to its reference [10]. We define them by what a
child's CPD depends on, its number of parents and whether each parent is *shared* (has a
second child, i.e. splits):

====  ===================  ========  =========================================
 id   name                 parents   CPD
====  ===================  ========  =========================================
 a    ROOT                 0         :func:`root_table`
 b    OCCLUSION            1         :func:`child_table`, parent not shared
 c    SPLIT                1         :func:`child_table`, parent shared
 d    MERGE                2         :func:`child_table`, none shared
 e    MERGE_ONE_SPLITTING  2         :func:`child_table`, one shared
 f    MERGE_BOTH_SPLITTING 2         :func:`child_table`, both shared
 g    RESTRICTION          2 labels  :func:`restriction_table` (eq. 5)
====  ===================  ========  =========================================

A restriction node sits on two children of one parent. When one child is also the
other's parent (a nested link, ``NetworkConfig.nested_links``: a member seen alone for a
moment, then the group again) it restricts the pieces the shared parent hands them, and
allows the first child inside the second (:func:`restriction_allows`; our addition).

All hidden-node CPDs come from one generative rule. A parent :math:`p` hands its child a
*piece* :math:`s` of its label, with the piece law

.. math::
    \pi_p(s \mid x_p) = \begin{cases}
        \delta(s = x_p) & |x_p| = 1 \\
        (1 - P_{split})\,\delta(s = x_p)
          + \frac{P_{split}}{2^{|x_p|} - 2}\,[\emptyset \ne s \subsetneq x_p]
          & p \text{ shared (eq. 9)} \\
        (1 - P_{part})\,\delta(s = x_p)
          + \frac{P_{part}}{2^{|x_p|} - 2}\,[\emptyset \ne s \subsetneq x_p]
          & p \text{ not shared}
    \end{cases}

:math:`P_{part}` (our addition, default 0.3; 0 gives the seed's eq. 10 exactly) is the
probability that the only visible child of a group is a part of it: the group split
while its other part was hidden (by the background or a gap of the low-level tracker),
which the seed's occlusion structure cannot express.

and the child is

.. math::
    p(x_k \mid x_{pa}) \propto P_{new}\,\delta(x_k = l_{new})
      + \frac{1 - P_{new} - m P_{merge}}{n}\sum_{p} \pi_p(x_k \mid x_p)
      + m P_{merge} \sum_{a \cup b = x_k} \pi_1(a \mid x_1)\,\pi_2(b \mid x_2)

with :math:`n` the number of parents and :math:`m = [n = 2]`. :math:`P_{merge}` depends on
how many of the two parents split (our addition): ``p_merge`` for structure d (neither),
``p_merge_one_split`` for e and ``p_merge_both_split`` for f. A stroke linked to two
parents that both split is almost never their union: it is one of two people passing each
other. Counted over the two-parent strokes of the CAVIAR ground truth with held-out
simulation seeds 20-39 (the benchmark uses 0-4) and of :mod:`models.jorge.simulate`
sequences, the union is the truth in 205 of 255 d nodes, 16 of 109 e nodes and 2 of 206
f nodes: the defaults 0.8, 0.15 and 0.02. With one unshared parent
and :math:`P_{part} = 0` this is eq. 10 exactly (eq. 3 for the new label); with two parents and
:math:`P_{merge} = 0` it is eq. 4. Mass on labels outside the child's domain (a union
larger than the maximum group size, a union of overlapping pieces, which eq. 8 excludes,
or a label pruned away) is dropped and the row renormalised; the new label is always in
the domain, so no row is empty.
"""

from __future__ import annotations

import functools
import itertools
from collections.abc import Collection, Iterable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from dbn.checks import check_number_fields
from dbn.errors import InputError, ModelError
from models.jorge.evidence import (  # re-exported: they lived here before they had a module
    colour_log_likelihood,
    gain_bins_rise,
    palette_count_log_likelihood,
    palette_gain_bin,
    palette_gain_log_likelihood,
    palette_missing_log_likelihood,
    size_log_likelihood,
)

__all__ = [
    "Label",
    "LabelParams",
    "STRUCTURES",
    "structure_of",
    "format_label",
    "proper_subsets",
    "pieces",
    "admissible_labels",
    "root_table",
    "child_table",
    "restriction_table",
    "restriction_allows",
    "split_loss_weights",
    "split_pair_scale",
    "colour_log_likelihood",
    "size_log_likelihood",
    "palette_count_log_likelihood",
    "gain_bins_rise",
    "palette_gain_bin",
    "palette_gain_log_likelihood",
    "palette_missing_log_likelihood",
    "prune_labels",
    "NEW_STRIDE",
    "new_objects",
    "birth_stroke",
    "cohort_size",
    "known_objects",
    "LabelObjects",
    "label_objects",
    "union_rows",
    "is_new_object",
]

Label = frozenset

STRUCTURES = (
    "ROOT",
    "OCCLUSION",
    "SPLIT",
    "MERGE",
    "MERGE_ONE_SPLITTING",
    "MERGE_BOTH_SPLITTING",
    "RESTRICTION",
)


@dataclass(frozen=True)
class LabelParams:
    """Parameters of the label CPDs and domains (seed 004, section 4.2).

    Attributes
    ----------
    p_new : float
        :math:`P_{new}`, probability that a stroke is a new object (eqs. 3, 10).
    p_merge : float
        :math:`P_{merge}`, probability that a two-parent stroke is the union of its
        parents' pieces (a group forms), structure d (neither parent splits).
    p_merge_one_split, p_merge_both_split : float
        The same for structures e (one parent splits) and f (both split). Our addition:
        the three defaults are the frequencies of unions among two-parent strokes of each
        structure, counted on the CAVIAR ground truth with held-out simulation seeds
        20-39 and on :mod:`models.jorge.simulate` sequences (module docstring).
    p_split : float
        :math:`P_{split}`, probability that a child of a splitting group takes a proper
        part of it rather than all of it.
    p_part : float
        :math:`P_{part}`, the same for the only child of a group (its other part hidden);
        0 gives eq. 10 of the seed exactly. Our addition.
    max_group_size : int
        Largest admissible group (labels with more objects are not admitted).
    new_group_probs : tuple of float
        :math:`q_m`, probability that a stroke seen for the first time holds ``m = 1, 2,
        ...`` new objects (people entering together); ``(1.0,)`` (the default) is the
        seed's single ``l_new``. Our addition: a group first seen as a group can only be
        labelled as one if its new label can hold several objects.
    p_join : float
        Probability that a stroke with parents holds, besides what it inherits, one
        object seen for the first time (a person joining while unseen or unlinked). 0
        (the default) is the seed's model. Our addition.
    child_new_groups : bool
        Whether a stroke *with* parents may also be a new group (``new_group_probs``);
        False: only a root (a stroke with no parent, e.g. people walking in together) may,
        a child's :math:`P_{new}` mass all goes to :math:`l_{new}`. Our addition (issue 16:
        new groups at children made the training crowds worse, at roots they do not).
    split_cover : tuple of float
        :math:`p_n`, probability that the two children of a group of ``n = 1, 2, ...``
        people (the last entry for larger groups) that take disjoint parts of it hold all
        of its people (:func:`split_loss_weights`, :func:`restriction_table` with the
        parent; the instant labels weigh it given the parent's current label). ``()``, this
        class's default, is seed 004's eq. 5; the default network's
        (:data:`models.jorge.config.FITTED_LABELS`) is
        :data:`models.jorge.config.FITTED_SPLIT_COVER`. Our addition (issue 16, sixteenth
        round; the default network's since the twenty-second).
    split_normalise : bool
        Whether the restriction node of a group's two children, given the group
        (``split_cover``; without it there is no group in the node's scope and this does
        nothing), divides by the chance :math:`Z_n` that two pieces of a group of ``n``
        drawn independently (eq. 9) are compatible (:func:`split_pair_scale`), so that the
        two children's labels are a draw from the restricted law. Seed 004 observes the
        restriction :math:`r = 1` on independent pieces, and that observation weighs the
        group's own label by :math:`Z_n`, which falls with ``n``: every split of a group of
        four made it about 3.4 times less likely than a group of three plus an unseen
        joiner. False, this class's default, is seed 004's; the default network's is True.
        Our addition (issue 16, twenty-third round).
    """

    p_new: float = 0.02
    p_merge: float = 0.8
    p_split: float = 0.8
    max_group_size: int = 3
    p_part: float = 0.3
    p_merge_one_split: float = 0.15
    p_merge_both_split: float = 0.02
    new_group_probs: tuple = (1.0,)
    p_join: float = 0.0
    child_new_groups: bool = True
    split_cover: tuple = ()
    split_normalise: bool = False

    def __post_init__(self) -> None:
        check_number_fields(self, ModelError)
        q = np.asarray(self.new_group_probs, dtype=np.float64)
        if q.ndim != 1 or q.size < 1 or np.any(q < 0) or not np.all(np.isfinite(q)) or q[0] <= 0:
            raise ModelError(
                f"LabelParams.new_group_probs must be a non-empty list of probabilities with "
                f"q_1 > 0, got {self.new_group_probs}"
            )
        if abs(q.sum() - 1.0) > 1e-9:
            raise ModelError(f"LabelParams.new_group_probs must sum to 1, got {q.sum()}")
        if not 0.0 <= self.p_join < 1.0:
            raise ModelError(f"LabelParams.p_join must be in [0, 1), got {self.p_join}")
        for name in ("p_new", "p_merge", "p_split", "p_part", "p_merge_one_split", "p_merge_both_split"):
            v = getattr(self, name)
            if not 0.0 <= v <= 1.0 or not np.isfinite(v):
                raise ModelError(f"LabelParams.{name} must be in [0, 1], got {v}")
        if not 0.0 < self.p_new < 1.0:
            raise ModelError(f"LabelParams.p_new must be in (0, 1), got {self.p_new}")
        for name in ("p_merge", "p_merge_one_split", "p_merge_both_split"):
            if self.p_new + getattr(self, name) >= 1.0:
                raise ModelError(
                    f"LabelParams: p_new + {name} must be < 1, got {self.p_new} + {getattr(self, name)}"
                )
        if isinstance(self.max_group_size, bool) or int(self.max_group_size) < 1:
            raise ModelError(f"LabelParams.max_group_size must be >= 1, got {self.max_group_size}")
        c = np.asarray(self.split_cover, dtype=np.float64)
        if c.ndim != 1 or not np.all((c > 0) & (c <= 1)):
            raise ModelError(f"LabelParams.split_cover must be probabilities in (0, 1], got {self.split_cover}")


def structure_of(num_parents: int, shared: Sequence[bool]) -> str:
    """Name of the basic structure (fig. 3) of a hidden node.

    Parameters
    ----------
    num_parents : int
        0, 1 or 2.
    shared : sequence of bool, length num_parents
        Whether each parent has a second child.
    """
    if num_parents == 0:
        return "ROOT"
    if num_parents == 1:
        return "SPLIT" if shared[0] else "OCCLUSION"
    if num_parents == 2:
        return ("MERGE", "MERGE_ONE_SPLITTING", "MERGE_BOTH_SPLITTING")[int(sum(map(bool, shared)))]
    raise ModelError(f"a node has at most 2 parents (seed 004, sec. 4), got {num_parents}")


NEW_STRIDE = 1_000_000
"""Object ids: the objects born at stroke ``k`` are ``k + j * NEW_STRIDE``. A lone newcomer
is ``k`` itself (``j = 0``, the seed's ``l_new``); the ``m`` objects of a new group of ``m``
(people entering together) are ``j = T(m) .. T(m) + m - 1`` with ``T(m) = m (m - 1) / 2``,
so that the size of the group an object was born in (its *cohort*, :func:`cohort_size`)
can be read from its id: a stroke seen for the first time can be labelled with a new group
of ``m`` objects, and a later label holding only some of them is known to be a part."""


def _cohort_offset(m: int) -> int:
    return m * (m - 1) // 2


def new_objects(k: int, m: int = 1) -> Label:
    """The new label of stroke ``k`` holding ``m`` new objects (a new group for ``m >= 2``):
    ``{k + j S : T(m) <= j < T(m) + m}``, ``S = NEW_STRIDE``, ``T(m) = m (m - 1) / 2``
    (``m = 1``: the seed's ``l_new = {k}``)."""
    if m < 1:
        raise InputError(f"new_objects: m must be >= 1, got {m}")
    first = _cohort_offset(m)
    return frozenset(int(k) + j * NEW_STRIDE for j in range(first, first + m))


def birth_stroke(o: int) -> int:
    """The stroke where object ``o`` was born (whose palette it takes, sec. 4.1)."""
    return int(o) % NEW_STRIDE


@functools.lru_cache(maxsize=1 << 16)
def cohort_size(o: int) -> int:
    """The number of objects born together with object ``o`` (itself included): 1 for a
    lone newcomer, ``m`` for a member of a new group of ``m`` (:func:`new_objects`)."""
    j = int(o) // NEW_STRIDE
    m = 1
    while _cohort_offset(m + 1) <= j:
        m += 1
    return m


@functools.lru_cache(maxsize=1 << 16)
def _cohort(o: int) -> Label:
    """All the objects born together with ``o`` (itself included)."""
    return new_objects(birth_stroke(o), cohort_size(o))


def known_objects(label: Label, k: int, own: Collection[int] = (),
                  joined: Mapping[int, Label] | None = None) -> list[int]:
    """The objects of ``label`` whose palette is on record at stroke ``k``: not born at
    ``k``, and born alone, or with their whole cohort in ``label``, or in ``own`` (members
    of a new group or joiners with a palette of their own, seen alone since:
    :meth:`models.jorge.network.LabelGraph.freeze`). The palette recorded at a new group's
    birth is the group's, not any one member's, so a label holding only part of a cohort
    knows none of their own palettes (issue 16: otherwise one member is credited with the
    whole pair's colours and a pair continued as one person explains them as well as the
    pair does). Likewise a joiner (in ``joined``: a newcomer who joined an inherited label,
    ``joined[o]`` its birth label) is known only where ``label`` holds that whole birth
    label (issue 16, tenth round). The plain definition :func:`label_objects` follows."""
    joined = {} if joined is None else joined
    born: dict[tuple[int, int], list[int]] = {}
    out = []
    for o in label:
        if birth_stroke(o) == k:
            continue
        if o in joined:
            if o in own or joined[o] <= label:
                out.append(int(o))
        else:
            born.setdefault((birth_stroke(o), cohort_size(o)), []).append(int(o))
    return out + [o for (_, m), objs in born.items() for o in objs if len(objs) == m or o in own]


@dataclass(frozen=True)
class LabelObjects:
    """What the evidence needs of each label of a domain at stroke ``k``, flattened over
    the labels in order (one pass over their objects, :func:`label_objects`).

    Attributes
    ----------
    palette_strokes : ndarray of int64, shape (sum of the label sizes,)
        For each object of each label in turn, the stroke whose palette it has.
    sizes : ndarray of int64, shape (num_labels,)
    known_strokes : ndarray of int64, shape (sum of known_counts,)
        The same for the known objects only (:func:`known_objects` at ``k``).
    known_counts : ndarray of int64, shape (num_labels,)
    is_new : ndarray of bool, shape (num_labels,)
        Whether the label holds an object born at ``k``.
    """

    palette_strokes: np.ndarray
    sizes: np.ndarray
    known_strokes: np.ndarray
    known_counts: np.ndarray
    is_new: np.ndarray


def label_objects(domain: Sequence[Label], k: int, own: Mapping[int, int] | None = None,
                  joined: Mapping[int, Label] | None = None) -> LabelObjects:
    """:class:`LabelObjects` of ``domain`` at stroke ``k``; ``own`` maps a member of a new
    group (or a joiner) to the stroke with its own palette (else its birth stroke's);
    ``joined`` maps a joiner to its birth label. The known objects are those of
    :func:`known_objects` (``label``, ``k``, ``own``, ``joined``): a joiner's birth palette
    holds the colours of everyone in its birth label (issue 16, tenth round)."""
    own = {} if own is None else own
    joined = {} if joined is None else joined
    records: dict[int, tuple[int, int, Label | None]] = {}  # per object, once per domain
    pal: list[int] = []
    known: list[int] = []
    known_counts, is_new = [], []
    for lab in domain:
        new, n_known = False, 0
        for o in lab:
            rec = records.get(o)
            if rec is None:
                rec = records[o] = _object_record(o, k, own, joined)
            stroke, kind, needs = rec
            pal.append(stroke)
            if kind == _BORN_HERE:
                new = True
            elif kind == _KNOWN or needs <= lab:
                known.append(stroke)
                n_known += 1
        known_counts.append(n_known)
        is_new.append(new)
    return LabelObjects(np.array(pal, dtype=np.int64), np.array([len(lab) for lab in domain], dtype=np.int64),
                        np.array(known, dtype=np.int64), np.array(known_counts, dtype=np.int64),
                        np.array(is_new, dtype=bool))


_BORN_HERE, _KNOWN, _KNOWN_WITH = 0, 1, 2  # kinds of object of :func:`_object_record`


def _object_record(o: int, k: int, own: Mapping[int, int], joined: Mapping[int, Label]
                   ) -> tuple[int, int, Label | None]:
    """What :func:`label_objects` needs of object ``o`` at stroke ``k`` whatever its label:
    ``(palette stroke, kind, needs)``. Kind ``_BORN_HERE``: born at ``k``; ``_KNOWN``:
    its palette is on record (its own, or born alone); ``_KNOWN_WITH``: on record only in
    a label holding all of ``needs`` (its birth label as a joiner, else its cohort)."""
    b = o % NEW_STRIDE
    stroke = own.get(o, b)
    if b == k:
        return stroke, _BORN_HERE, None
    if o in own:
        return stroke, _KNOWN, None
    if o in joined:
        return stroke, _KNOWN_WITH, joined[o]
    if o < NEW_STRIDE:
        return stroke, _KNOWN, None
    return stroke, _KNOWN_WITH, _cohort(o)


def union_rows(palettes: np.ndarray, strokes: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """Row ``i``: the union of the palettes (rows of ``palettes``, bool, shape
    (num_strokes, pool_size)) of the next ``counts[i]`` entries of ``strokes``; an empty
    group gives an empty palette.

    Returns
    -------
    ndarray of bool, shape (len(counts), pool_size)
    """
    counts = np.asarray(counts, dtype=np.int64)
    out = np.zeros((counts.size, palettes.shape[1]), dtype=bool)
    full = counts > 0
    if full.any():
        starts = (np.cumsum(counts) - counts)[full]
        out[full] = np.logical_or.reduceat(palettes[np.asarray(strokes, dtype=np.int64)], starts, axis=0)
    return out


def is_new_object(o: int, k: int) -> bool:
    """Whether object ``o`` was born at stroke ``k``."""
    return birth_stroke(o) == int(k)


def _format_object(o: int) -> str:
    j, k = divmod(int(o), NEW_STRIDE)
    return str(k) if j == 0 else f"{k}.{j}"


@functools.lru_cache(maxsize=1 << 16)
def format_label(label: Label) -> str:
    """``{1}`` -> ``'1'``, ``{1, 2}`` -> ``'(1,2)'`` (the notation of seed 004, Table 2); the
    second object born at stroke 7 prints as ``7.1``. Remembered (a window names every
    label of every active node, again at each inference)."""
    items = sorted(label, key=lambda o: (birth_stroke(o), o))
    names = [_format_object(o) for o in items]
    return names[0] if len(items) == 1 else "(" + ",".join(names) + ")"


def _sort_key(label: Label) -> tuple:
    return (len(label), tuple(sorted(label)))


def proper_subsets(label: Label) -> list[Label]:
    """Non-empty proper subsets of a label, smallest first."""
    items = sorted(label)
    return [
        frozenset(c) for r in range(1, len(items)) for c in itertools.combinations(items, r)
    ]


def pieces(domain: Sequence[Label], shared: bool, partial: bool = False) -> list[Label]:
    """What a parent with admissible labels ``domain`` can hand one child.

    Not shared: its labels (eq. 7), and with ``partial`` (:math:`P_{part} > 0`) also their
    non-empty subsets. Shared (its region splits): every non-empty subset of each label
    (eq. 9, :math:`\\mathcal{P}(L_i)` without the empty set).
    """
    if not shared and not partial:
        return list(dict.fromkeys(domain))
    out: dict[Label, None] = {}
    for lab in domain:
        out[lab] = None
        for s in proper_subsets(lab):
            out[s] = None
    return list(out)


def admissible_labels(
    parent_domains: Sequence[Sequence[Label]],
    parent_shared: Sequence[bool],
    new_label: Label,
    max_group_size: int,
    partial: bool = False,
    max_new: int = 1,
    join: bool = False,
) -> list[Label]:
    r"""Admissible labels :math:`L_k` of a node (seed 004, eqs. 2 and 7-9).

    .. math::
        L_k = \{l_{new}\} \cup S_1 \cup S_2 \cup
              \{a \cup b : a \in S_1, b \in S_2, a \cap b = \emptyset\}

    with :math:`S_p` the pieces of parent :math:`p` (:func:`pieces`); labels with more
    than ``max_group_size`` objects are left out.

    Parameters
    ----------
    parent_domains : sequence (length 0-2) of sequences of Label
    parent_shared : sequence of bool, same length
    new_label : Label
        ``{k}`` for node ``k``.
    max_group_size : int
    partial : bool
        Whether an unshared parent may hand a part of a group (:math:`P_{part} > 0`).
    max_new : int
        Largest new group (``new_objects(k, m)`` for ``m <= max_new``; our addition, 1 is
        the seed's single ``l_new``).
    join : bool
        Also admit every inherited label plus one new object, :math:`a \cup l_{new}`
        (:math:`P_{join} > 0`; our addition).

    Returns
    -------
    list of Label
        ``l_new`` first, then the others by size and ids (deterministic order).
    """
    if len(parent_domains) != len(parent_shared):
        raise ModelError(
            f"admissible_labels: {len(parent_domains)} parent domains but "
            f"{len(parent_shared)} shared flags"
        )
    if len(parent_domains) > 2:
        raise ModelError(f"a node has at most 2 parents, got {len(parent_domains)}")
    parts = [pieces(d, s, partial) for d, s in zip(parent_domains, parent_shared)]
    found: set[Label] = set()
    for p in parts:
        found.update(p)
    if len(parts) == 2:
        found.update(_disjoint_unions(parts[0], parts[1], max_group_size))
    if join and len(new_label) == 1:
        found.update([lab | new_label for lab in found if len(lab) < max_group_size])
    if len(new_label) == 1:
        (k,) = tuple(new_label)
        found.update(new_objects(k, m) for m in range(2, min(max_new, max_group_size) + 1))
    found.discard(new_label)
    others = sorted((lab for lab in found if len(lab) <= max_group_size), key=_sort_key)
    return [new_label, *others]


def _disjoint_unions(first: Sequence[Label], second: Sequence[Label], max_size: int) -> set[Label]:
    r"""Eq. 8's merged labels :math:`\{a \cup b\}` over ``a`` of ``first`` and ``b`` of
    ``second`` that share no object and hold at most ``max_size`` together. Vectorised
    over the pairs with object bit masks (a merge of two groups pairs hundreds of pieces);
    a loop past 62 objects."""
    if not first or not second:
        return set()
    bit = _object_bits((*first, *second))
    if bit is None:
        return {a | b for a in first for b in second
                if a.isdisjoint(b) and len(a) + len(b) <= max_size}
    m0, m1 = (np.array([_mask(bit, lab) for lab in side], dtype=np.int64)
              for side in (first, second))
    s0, s1 = (np.array([len(lab) for lab in side]) for side in (first, second))
    ia, ib = _disjoint_pairs(m0, s0, m1, s1, max_size)
    _, one = np.unique(m0[ia] | m1[ib], return_index=True)  # one pair per distinct union
    return {first[i] | second[j] for i, j in zip(ia[one].tolist(), ib[one].tolist())}


def _object_bits(labels: Iterable[Label]) -> dict[int, int] | None:
    """One bit per object of ``labels`` (in object order), for int64 masks; None past 62
    objects."""
    objects = sorted({o for lab in labels for o in lab})
    return None if len(objects) > 62 else {o: 1 << t for t, o in enumerate(objects)}


def _mask(bit: Mapping[int, int], label: Label) -> int:
    """The bit mask of ``label`` (:func:`_object_bits`)."""
    return sum(map(bit.__getitem__, label))


def _disjoint_pairs(m0: np.ndarray, s0: np.ndarray, m1: np.ndarray, s1: np.ndarray,
                    max_size: int) -> tuple[np.ndarray, np.ndarray]:
    """Indices ``(i, j)``, in row-major order, of the masks ``m0[i]``, ``m1[j]`` that share
    no object and whose sizes ``s0[i] + s1[j]`` are at most ``max_size``."""
    return np.nonzero(((m0[:, None] & m1[None, :]) == 0) & (s0[:, None] + s1[None, :] <= max_size))


def root_table(domain: Sequence[Label], new_label: Label, params: LabelParams | None = None) -> np.ndarray:
    """CPD of structure (a) ROOT: a stroke with no parent is new: ``m`` new objects with
    probability :math:`q_m` (``params.new_group_probs``; without ``params`` the seed's
    single :math:`l_{new}`), renormalised over the sizes in the domain.

    ==============================  ==============
    :math:`x_k`                     p
    ==============================  ==============
    :math:`l_{new} = \\{k\\}`         :math:`q_1` (1 in the seed)
    ``new_objects(k, m)``, m >= 2   :math:`q_m`
    any other label                 0
    ==============================  ==============

    Returns
    -------
    ndarray, shape (num_labels,)
    """
    if new_label not in domain:
        raise ModelError(f"root_table: new label {set(new_label)} not in the domain")
    t = _new_column(domain, new_label, params)
    return t / t.sum()


def _new_column(domain: Sequence[Label], new_label: Label, params: LabelParams | None) -> np.ndarray:
    """:math:`q_m` at each new-group label of the domain (``new_label`` is ``m = 1``)."""
    q = (1.0,) if params is None else params.new_group_probs
    weight = {new_label: q[0]}
    if len(new_label) == 1:
        (k,) = tuple(new_label)
        weight.update({new_objects(k, m): q[m - 1] for m in range(2, len(q) + 1)})
    return np.array([weight.get(lab, 0.0) for lab in domain], dtype=np.float64)


def _piece_law(label: Label, shared: bool, params: LabelParams) -> list[tuple[Label, float]]:
    p = params.p_split if shared else params.p_part
    if len(label) == 1 or p == 0.0:
        return [(label, 1.0)]
    subs = proper_subsets(label)
    return [(label, 1.0 - p)] + [(s, p / len(subs)) for s in subs]


def child_table(
    parent_domains: Sequence[Sequence[Label]],
    parent_shared: Sequence[bool],
    domain: Sequence[Label],
    new_label: Label,
    params: LabelParams,
    truncate: bool = False,
) -> np.ndarray:
    r"""CPD of a hidden node with 1 or 2 parents: structures (b)-(f) of fig. 3.

    The rule is in the module docstring. Per structure, for parent labels
    :math:`x_1, x_2` (piece laws :math:`\pi` as there):

    ===  =======================  ============================================================
     b   OCCLUSION (eq. 10)       :math:`x_k = x_1`: :math:`1-P_{new}`; :math:`l_{new}`: :math:`P_{new}`
                                  (for a group :math:`x_1`, :math:`P_{part}` of the inherited mass
                                  goes to its proper parts, as in c)
     c   SPLIT (eq. 9)            :math:`x_k = x_1`: :math:`(1-P_{new})(1-P_{split})` if
                                  :math:`|x_1|>1` (else :math:`1-P_{new}`); each non-empty proper
                                  subset: :math:`(1-P_{new})P_{split}/(2^{|x_1|}-2)`;
                                  :math:`l_{new}`: :math:`P_{new}`
     d   MERGE (eqs. 4, 8)        :math:`x_1` and :math:`x_2`: :math:`(1-P_{new}-P_{merge})/2` each;
                                  :math:`x_1\cup x_2`: :math:`P_{merge}`; :math:`l_{new}`: :math:`P_{new}`
     e   MERGE_ONE_SPLITTING      as d, the shared parent handing a piece drawn from its piece law
     f   MERGE_BOTH_SPLITTING     as d, both parents handing pieces
    ===  =======================  ============================================================

    Our additions: the :math:`P_{new}` mass is shared among new groups of ``m`` objects by
    :math:`q_m` (``new_group_probs``; the seed: all on :math:`l_{new}`), and a fraction
    :math:`P_{join}` of the inherited mass on each label :math:`a` moves to
    :math:`a \cup l_{new}` (a person joining unseen). Then restricted to ``domain`` and
    each row renormalised (module docstring), or, with ``truncate``, each row divided by
    the mass it has over *all* admissible labels (:func:`admissible_labels` of these
    parent domains), so a row of a pruned ``domain`` sums to the share of its mass that
    the pruning kept (issue 16, fourth round: renormalising a row whose likely labels were
    pruned moved their mass onto what was left, often :math:`l_{new}`, and made a wrong
    parent label look as good as the right one).

    Parameters
    ----------
    parent_domains : sequence (length 1 or 2) of sequences of Label
        Admissible labels of the parents (the CPD's parent states, in order).
    parent_shared : sequence of bool
        Whether each parent has a second child.
    domain : sequence of Label
        The child's admissible labels (its states); must contain ``new_label``.
    new_label : Label
    params : LabelParams

    truncate : bool
        Rows divided by their unpruned mass instead of renormalised (see above).

    Returns
    -------
    ndarray, shape (len(L_1), [len(L_2),] len(domain))
        Last axis the child; every row sums to 1 (``truncate``: at most 1).
    """
    n = len(parent_domains)
    if n not in (1, 2) or len(parent_shared) != n:
        raise ModelError(f"child_table: need 1 or 2 parents with flags, got {n} / {len(parent_shared)}")
    if new_label not in domain:
        raise ModelError(f"child_table: new label {set(new_label)} not in the child's domain")
    kept = len(domain)
    if params.p_join > 0:  # a kept join label's source is needed even where it was pruned
        have = set(domain)
        sources = {lab - new_label for lab in domain if new_label < lab} - have
        domain = [*domain, *sorted(sources, key=sorted)]
    index = {lab: i for i, lab in enumerate(domain)}
    p_new = params.p_new
    p_merge = 0.0
    if n == 2:
        p_merge = (params.p_merge, params.p_merge_one_split,
                   params.p_merge_both_split)[int(sum(map(bool, parent_shared)))]
    w_single = (1.0 - p_new - p_merge) / n
    laws = [
        [_piece_law(lab, sh, params) for lab in dom]
        for dom, sh in zip(parent_domains, parent_shared)
    ]
    gmax = params.max_group_size
    table, total = _inherit(laws, index, len(domain), w_single, gmax)
    if n == 2 and p_merge > 0:
        _merge_mass(table, total, laws, index, p_merge, gmax)
    if params.p_join > 0:  # one new object joins what is inherited (our addition)
        _join(table, index, new_label, params)
    new_params = params if params.child_new_groups else None
    table += p_new * _new_column(domain, new_label, new_params)
    table = table[..., :kept]
    if truncate:
        total += p_new * _new_mass(new_label, new_params)
        return table / total[..., None]
    return table / table.sum(axis=-1, keepdims=True)


def _inherit(
    laws: list, index: dict, num_labels: int, w_single: float, gmax: int
) -> tuple[np.ndarray, np.ndarray]:
    """Single-parent inheritance of :func:`child_table`: each parent ``p`` hands each
    piece ``s`` of its label's piece law (weight ``w``) to the child with mass
    ``w_single * w``; one slab per parent, broadcast over the other parent.

    Returns the (len(L_1), [len(L_2),] num_labels) table over ``index``'s labels and the
    per-row mass over all admissible labels (pieces of at most ``gmax`` objects; for
    ``truncate``)."""
    n = len(laws)
    shape = tuple(len(law) for law in laws) + (num_labels,)
    table = np.zeros(shape)
    total = np.zeros(shape[:-1])  # mass per row over all admissible labels (``truncate``)
    for p in range(n):
        # a law's pieces are distinct, so each (i, j) of the slab is set once
        rows, cols, vals, masses = [], [], [], []
        for i, law in enumerate(laws[p]):
            m = 0.0
            for s, w in law:
                m += w_single * w * (len(s) <= gmax)
                j = index.get(s)
                if j is not None:
                    rows.append(i)
                    cols.append(j)
                    vals.append(w_single * w)
            masses.append(m)
        slab = np.zeros((len(laws[p]), num_labels))
        slab[rows, cols] = vals
        mass = np.array(masses)
        total += mass.reshape([-1 if q == p else 1 for q in range(n)])
        if n == 1:
            table += slab
        elif p == 0:
            table += slab[:, None, :]
        else:
            table += slab[None, :, :]
    return table, total


def _merge_mass(table: np.ndarray, total: np.ndarray, laws: list, index: dict, p_merge: float,
                gmax: int) -> None:
    """Eq. 8 in place: each pair of pieces ``a`` (of parent label ``i``, weight ``wa``) and
    ``b`` (of ``j``, ``wb``), disjoint and together at most ``gmax`` objects, adds
    :math:`P_{merge} w_a w_b` to ``total[i, j]`` and, if ``a | b`` is in ``index``, to
    ``table[i, j, index[a | b]]``. Vectorised over the pairs with object bit masks, in the
    loop's order (so the sums are the same to the last bit); a loop past 62 objects."""
    bit = _object_bits(piece for law in laws[0] + laws[1] for piece, _ in law)
    if bit is None:
        _merge_mass_loop(table, total, laws, index, p_merge, gmax)
        return
    flat = []
    for p in (0, 1):
        pieces_ = [(i, _mask(bit, piece), w, len(piece))
                   for i, law in enumerate(laws[p]) for piece, w in law]
        rows, masks, ws, sizes = zip(*pieces_)
        flat.append((np.array(rows), np.array(masks, dtype=np.int64), np.array(ws), np.array(sizes)))
    (r0, m0, w0, s0), (r1, m1, w1, s1) = flat
    ia, ib = _disjoint_pairs(m0, s0, m1, s1, gmax)
    w = p_merge * w0[ia] * w1[ib]
    np.add.at(total, (r0[ia], r1[ib]), w)
    universe = frozenset(bit)
    child = {_mask(bit, lab): c for lab, c in index.items() if lab <= universe}
    c = _lookup(np.array(list(child), dtype=np.int64), np.array(list(child.values()), dtype=np.int64),
                m0[ia] | m1[ib])
    hit = c >= 0
    np.add.at(table, (r0[ia][hit], r1[ib][hit], c[hit]), w[hit])


def _lookup(keys: np.ndarray, values: np.ndarray, query: np.ndarray) -> np.ndarray:
    """``values[keys == q]`` for each ``q`` of ``query`` (distinct ``keys``), -1 where none."""
    if keys.size == 0:
        return np.full(query.shape, -1, dtype=np.int64)
    order = np.argsort(keys)
    keys, values = keys[order], values[order]
    pos = np.minimum(np.searchsorted(keys, query), keys.size - 1)
    return np.where(keys[pos] == query, values[pos], -1)


def _merge_mass_loop(table: np.ndarray, total: np.ndarray, laws: list, index: dict, p_merge: float,
                     gmax: int) -> None:
    """:func:`_merge_mass` as a plain loop (any number of objects)."""
    for i, law1 in enumerate(laws[0]):
        for j, law2 in enumerate(laws[1]):
            for a, wa in law1:
                for b, wb in law2:
                    if a & b or len(a) + len(b) > gmax:
                        continue  # eq. 8: only disjoint unions (of admissible size)
                    total[i, j] += p_merge * wa * wb
                    c = index.get(a | b)
                    if c is not None:
                        table[i, j, c] += p_merge * wa * wb


def _join(table: np.ndarray, index: dict, new_label: Label, params: LabelParams) -> None:
    """Joins: every kept label ``a`` that can take one more object gives :math:`P_{join}`
    of its mass to :math:`a \\cup l_{new}` (kept or not); a label of ``max_group_size``
    objects keeps all of its mass."""
    moves = [(c, index.get(lab | new_label)) for lab, c in index.items()
             if not (lab & new_label) and len(lab) < params.max_group_size]
    if not moves:
        return
    src = [c for c, _ in moves]
    moved = params.p_join * table[..., src]
    table[..., src] *= 1.0 - params.p_join
    # distinct sources have distinct joins (``a | l_new``), none of them a source
    has = [t for t, (_, d) in enumerate(moves) if d is not None]
    if has:
        table[..., [moves[t][1] for t in has]] += moved[..., has]


def _new_mass(new_label: Label, params: LabelParams | None) -> float:
    """Sum of :func:`_new_column` over all admissible new labels (new groups only of up to
    ``max_group_size`` objects, and only where ``new_label`` is a single object)."""
    q = (1.0,) if params is None else params.new_group_probs[: params.max_group_size]
    return float(np.sum(q)) if len(new_label) == 1 else float(q[0])


def restriction_allows(a: Label, b: Label, nested: bool = False) -> bool:
    r"""Whether two children of one parent may have labels ``a`` and ``b`` (eq. 5).

    Seed 004: never a shared object, :math:`a \cap b = \emptyset`. Our addition, ``nested``:
    the child labelled ``a`` is also a parent of the child labelled ``b`` (a member seen
    alone for a moment, then the whole group again: a split whose parts merge back). The restriction
    then holds between the pieces the shared parent hands its two children: ``b`` is
    that parent's piece, which must miss ``a``, alone or united with ``a``. So ``a`` and
    ``b`` share nothing, or ``a`` is inside ``b`` (a part of ``a`` with its rest hidden,
    :math:`P_{part}`, is not admitted in ``b`` here).
    """
    return not (a & b) or (nested and a <= b)


def restriction_table(domain_i: Sequence[Label], domain_j: Sequence[Label], nested: bool = False,
                      parent_domain: Sequence[Label] | None = None, split_cover: Sequence[float] = (),
                      normalise: bool = False) -> np.ndarray:
    r"""CPD of structure (g), the restriction node :math:`r_{ij}` (eq. 5).

    ===============================  ==============  ==============
    parents                          :math:`r = 0`   :math:`r = 1`
    ===============================  ==============  ==============
    :math:`x_i \cap x_j = \emptyset`  0               1
    :math:`x_i \cap x_j \ne \emptyset` 1               0
    ===============================  ==============  ==============

    Observed :math:`r_{ij} = 1`, it forbids two children of one parent to share an object.
    With ``nested`` (node ``i`` is also a parent of node ``j``; our addition,
    :func:`restriction_allows`), :math:`x_i \subseteq x_j` is allowed too.

    With ``parent_domain`` (the labels :math:`x_p` of the children's shared parent; our
    addition, issue 16's sixteenth round), two disjoint labels weigh 1 if they hold all of
    the parent's people, :math:`x_p \subseteq x_i \cup x_j`, and :math:`w_{|x_p|}` if not
    (:func:`split_loss_weights` of ``split_cover``).
    The children's pieces are drawn independently (eq. 9), so without it, of two disjoint
    pieces of a group of 3 / 4 / 5 only 6 of 12 / 14 of 50 / 30 of 180 hold everyone: the
    prior expected a group's split to lose people, where on the training split most
    splits are partitions. Not with ``nested``.

    With ``normalise`` too (``LabelParams.split_normalise``; our addition, issue 16's
    twenty-third round), each parent label's slice is multiplied by
    :func:`split_pair_scale` of its size: observing :math:`r = 1` then no longer favours
    smaller groups.

    Returns
    -------
    ndarray, shape (len(domain_i), len(domain_j), 2), or with ``parent_domain``
    (len(parent_domain), len(domain_i), len(domain_j), 2)
    """
    ok = np.array([[restriction_allows(a, b, nested) for b in domain_j] for a in domain_i], dtype=np.float64)
    ok = ok.reshape(len(domain_i), len(domain_j))
    if parent_domain is not None and not nested:
        union = [[a | b for b in domain_j] for a in domain_i]
        cover = np.array([[[x <= u for u in row] for row in union] for x in parent_domain], dtype=np.float64)
        cover = cover.reshape(len(parent_domain), len(domain_i), len(domain_j))
        loss = _loss_weights_at(split_loss_weights(split_cover), [len(x) for x in parent_domain])[:, None, None]
        ok = ok * (cover + loss * (1.0 - cover))
        if normalise:
            ok = ok * split_pair_scale([len(x) for x in parent_domain], split_cover)[:, None, None]
    return np.stack([1.0 - ok, ok], axis=-1)


def split_pair_scale(sizes: Sequence[int], split_cover: Sequence[float] = ()) -> np.ndarray:
    r"""Scale of the restriction node given a group of each of ``sizes`` people
    (``LabelParams.split_normalise``): :math:`Z_{min} / Z_n`, with

    .. math::
        Z_n \propto \sum_{a, b} \pi(a)\,\pi(b)\,[a \cap b = \emptyset]\,w(a, b)
            = \frac{C_n + N_n w_n}{(2^n - 2)^2}

    the chance that two proper pieces of a group of ``n`` drawn independently (eq. 9, up
    to :math:`P_{split}^2`, the same for every ``n``) are compatible: disjoint, weighing 1
    if they hold everyone (:math:`C_n = 2^n - 2` ordered partitions) and :math:`w_n`
    (:func:`split_loss_weights`) if not (:math:`N_n` pairs). Where :math:`w_n < 1`,
    :math:`Z_n = 1 / (p_n (2^n - 2))`, so under the restricted law a split holds everyone
    with probability :math:`p_n` (``split_cover``) and weighs the group the same whatever
    its size; unscaled, it also weighed the group by :math:`Z_n`. A group's full piece
    is never disjoint from its other child's, so it adds nothing. One person's two pieces
    are never compatible, so ``n = 1`` is scaled as ``n = 2`` (seed 004's relation
    between a person and a pair is kept). At most 1; shape ``(len(sizes),)``.
    """
    n = np.maximum(np.asarray(sizes, dtype=np.int64).reshape(-1), 2)
    part, lose = 2.0**n - 2.0, 3.0**n - 3.0 * 2.0**n + 3.0
    z = (part + lose * _loss_weights_at(split_loss_weights(split_cover), n)) / part**2
    return z.min() / z if z.size else z


def _loss_weights_at(w: np.ndarray, sizes: Sequence[int] | np.ndarray) -> np.ndarray:
    """:math:`w_n` (:func:`split_loss_weights`, ``w``) for groups of each of ``sizes`` (>= 1)
    people: groups larger than ``len(w)`` take its last weight; 1 without a cover (empty
    ``w``). Shape ``(len(sizes),)``."""
    n = np.asarray(sizes, dtype=np.int64).reshape(-1)
    return w[np.minimum(n, len(w)) - 1] if len(w) else np.ones(n.shape)


def split_loss_weights(split_cover: Sequence[float]) -> np.ndarray:
    r""":math:`w_n`, the restriction's weight of two disjoint parts of a group of ``n`` that
    lose someone (1 for a partition), such that two pieces drawn as in eq. 9 hold everyone
    with probability ``split_cover[n - 1]``: :math:`w_n = C_n (1 - p_n) / (p_n N_n)`, with
    :math:`C_n = 2^n - 2` ordered partitions and :math:`N_n = 3^n - 3 \cdot 2^n + 3` ordered
    disjoint pairs that lose someone; at most 1, and 1 where :math:`N_n = 0`
    (:math:`n \le 2`). Shape ``(len(split_cover),)``."""
    p = np.asarray(split_cover, dtype=np.float64)
    n = np.arange(1, p.size + 1, dtype=np.float64)
    part, lose = 2.0**n - 2.0, 3.0**n - 3.0 * 2.0**n + 3.0
    with np.errstate(divide="ignore", invalid="ignore"):
        w = np.where(lose > 0, part * (1.0 - p) / (p * lose), 1.0)
    return np.minimum(w, 1.0)


def prune_labels(
    domain: Sequence[Label],
    posterior: np.ndarray,
    threshold: float,
    keep: Sequence[Label] = (),
    max_labels: int | None = None,
) -> list[Label]:
    """Labels whose posterior at the last inference is at least ``threshold`` (sec. 5).

    The labels in ``keep`` (the node's new label) stay; at most ``max_labels`` are kept,
    the most probable first; the original order is kept.

    Parameters
    ----------
    domain : sequence of Label, length num_labels
    posterior : ndarray, shape (num_labels,)
    threshold : float
    keep : sequence of Label
    max_labels : int, optional

    Returns
    -------
    list of Label
        Never empty: the most probable label always stays.
    """
    posterior = np.asarray(posterior, dtype=np.float64)
    if posterior.shape != (len(domain),):
        raise InputError(f"prune_labels: posterior shape {posterior.shape} for {len(domain)} labels")
    order = np.argsort(-posterior, kind="stable")
    chosen = {int(order[0])}
    chosen.update(int(i) for i in np.flatnonzero(posterior >= threshold))
    keep_set = set(keep)
    forced = {i for i, lab in enumerate(domain) if lab in keep_set}
    if max_labels is not None and len(chosen | forced) > max_labels:
        room = max(1, max_labels - len(forced))
        chosen = {int(i) for i in order if int(i) in chosen}
        chosen = set(sorted(chosen, key=lambda i: -posterior[i])[:room])
    chosen |= forced
    return [lab for i, lab in enumerate(domain) if i in chosen]
