"""Where a stroke's right label is lost (models.jorge.recall, issue 16): admissible given
its parents' labels, kept in its domain, chosen; checked on a hand-made stroke graph
whose right labels we know, and against the score on a labelled simulated meeting."""

from __future__ import annotations

import numpy as np
import pytest

from dbn.errors import InputError
from models.jorge.labels import LabelParams
from models.jorge.meeting import simulate_meeting
from models.jorge.network import LabelGraph, NetworkConfig
from models.jorge.online import OnlineConfig, label_online
from models.jorge.recall import domain_recall, result_recall
from models.jorge.reid import object_aliases, reidentify
from models.jorge.scoring import score
from models.jorge.strokes import build_strokes, make_stroke

A, B, C, D = 10, 11, 12, 13  # people
L = frozenset


def _graph(p_join: float = 0.0, seen_before: bool = False):
    """People A and B walk in apart (0, 1), meet (2: a merge), part (3, 4: a split); then
    A and B meet again (5) and a third person comes out of their region with them (6: a
    continuation of 5). Right labels: {0}, {1}, {0, 1}, {0}, {1}, {0, 1}; for 6 a join
    {0, 1, 6} when the third person is C, never seen before, and joins are admitted
    (``p_join``), else none. With ``seen_before``, the third person is D, who walked
    alone far off in a stroke of their own (6) before, and the continuation is stroke 7."""
    g = LabelGraph(NetworkConfig(labels=LabelParams(max_group_size=3, p_part=0.3, p_join=p_join)),
                   fps=25.0)
    third = D if seen_before else C
    strokes = [
        make_stroke(0, 0, 9, (0, 0), (9, 0), [0, 1, 2], {A}),
        make_stroke(1, 0, 9, (30, 0), (21, 0), [3, 4, 5], {B}),
        make_stroke(2, 10, 19, (15, 0), (15, 0), [0, 1, 3, 4], {A, B}),
        make_stroke(3, 20, 29, (10, 0), (0, 0), [0, 1, 2], {A}),
        make_stroke(4, 20, 29, (20, 0), (30, 0), [3, 4, 5], {B}),
        make_stroke(5, 30, 39, (15, 0), (15, 0), [0, 1, 3, 4], {A, B}),
    ]
    parents = [[], [], [0, 1], [2], [2], [3, 4]]
    if seen_before:
        strokes.append(make_stroke(6, 30, 35, (900, 0), (900, 0), [8, 9, 10], {D}))
        parents.append([])
    n = len(strokes)
    strokes.append(make_stroke(n, 40, 49, (15, 0), (15, 0), [0, 3, 6, 7], {A, B, third}))
    parents.append([5])
    for s, par in zip(strokes, parents):
        g.add_stroke(s, par)
    right = [L({0}), L({1}), L({0, 1}), L({0}), L({1}), L({0, 1})]
    right += [L({6})] if seen_before else []
    return g, strokes, right + [L({0, 1})]  # the last stroke labelled without its third


def test_right_labels_are_admissible_kept_and_chosen():
    g, strokes, labels = _graph()
    rec = domain_recall(strokes, g, labels)
    # stroke 6 is the only error: with right parents, no label of {0, 1}'s pieces and
    # a new object holds C (no joins, p_join 0)
    assert rec.chosen.tolist() == [True] * 6 + [False]
    assert rec.admissible.tolist() == [True] * 6 + [False]
    assert rec.kept.tolist() == [True] * 6 + [False]
    assert rec.parents_right.all()
    assert list(np.flatnonzero(~rec.chosen)) == list(score(strokes, labels).errors)


def test_a_newcomer_is_an_object_born_where_they_are_first_seen():
    g, strokes, labels = _graph(p_join=0.1)
    assert L({0, 1, 6}) in g.nodes[6].domain  # the join: A, B and an object born at 6
    rec = domain_recall(strokes, g, labels)
    assert rec.admissible[6] and rec.kept[6] and not rec.chosen[6]
    g, strokes, labels = _graph(p_join=0.1, seen_before=True)
    assert L({0, 1, 7}) in g.nodes[7].domain
    rec = domain_recall(strokes, g, labels)  # D has an object of their own: not a join
    assert rec.chosen[:7].all()
    assert not rec.admissible[7] and not rec.kept[7] and not rec.chosen[7]


def test_a_pruned_right_label_is_admissible_not_kept():
    g, strokes, labels = _graph()
    assert L({0}) in g.nodes[3].domain
    g.set_domain(3, [lab for lab in g.nodes[3].domain if lab != L({0})])
    labels[3] = L({3})  # the split part taken for someone new
    rec = domain_recall(strokes, g, labels)
    assert rec.admissible[3] and not rec.kept[3] and not rec.chosen[3]
    assert rec.parents_right[3]
    # its parent 3 is now wrong: 5's right label is no longer admissible given its
    # parents' labels (it was labelled by hand here, as a network could not have)
    assert not rec.parents_right[5] and not rec.admissible[5] and rec.chosen[5]
    assert ((rec.kept & rec.admissible).sum(), rec.admissible.sum()) == (4, 5)  # 3 pruned
    lost = rec.where_lost()  # the errors: 3 (pruned), 6 (C joined unseen)
    assert [list(np.flatnonzero(lost[k])) for k in ("unrepresentable", "pruned", "not_chosen")] \
        == [[6], [3], []]
    assert not rec.where_lost(np.arange(7) != 3)["pruned"].any()


def test_a_wrong_parent_is_carried():
    g, strokes, labels = _graph()
    labels[2] = L({0})  # the merge drops B
    rec = domain_recall(strokes, g, labels)
    assert not rec.chosen[2] and rec.admissible[2] and rec.kept[2]
    assert not rec.parents_right[3] and not rec.parents_right[4]
    # 4's parent says {0}: no piece of it stands for B
    assert not rec.admissible[4] and rec.admissible[3]


def test_aliases_rename_before_matching():
    g, strokes, labels = _graph()
    labels[3] = L({3})  # A taken for someone new at the split ...
    labels[5] = L({3, 1})  # ... and carried
    rec = domain_recall(strokes, g, labels)
    assert rec.chosen[:3].all() and not rec.chosen[3] and not rec.chosen[5]
    fixed = domain_recall(strokes, g, labels, {3: 0})  # re-identified as A
    assert fixed.chosen[:6].all() and fixed.parents_right[:6].all()


def test_bad_input_names_the_problem():
    g, strokes, labels = _graph()
    with pytest.raises(InputError, match="6 labels"):
        domain_recall(strokes, g, labels[:-1])
    with pytest.raises(InputError, match="node 0 holds stroke 0, not stroke 1"):
        domain_recall([strokes[1], strokes[0], *strokes[2:]], g, labels)
    with pytest.raises(InputError, match="node 2 has 2 parents"):
        g.admissible(2, [[L({0})]])
    with pytest.raises(InputError, match="no node 7"):
        g.admissible(7)


def test_chosen_is_the_score_on_a_labelled_meeting():
    """On a SIMULATED meeting of four, through the default labeller and its
    re-identification: the right labels are the score's, chosen implies kept, and a
    right label kept with a wrong parent is still counted."""
    strokes = build_strokes([0, 3], simulate_meeting(3, 4))
    cfg = OnlineConfig()
    res = label_online(strokes, cfg)
    g = res.labeller.graph
    aliases = object_aliases(g, res.network_labels, cfg.reid_prior)
    assert res.labeller.aliases == aliases  # the labeller's own re-identification pass
    assert reidentify(g, res.network_labels, cfg.reid_prior) == res.labels
    rec = domain_recall(strokes, g, res.network_labels, aliases)
    assert list(np.flatnonzero(~rec.chosen)) == list(score(strokes, res.labels).errors)
    assert not (rec.chosen & ~rec.kept).any()
    roots = np.array([not g.nodes[k].parents for k in range(len(g))])
    assert rec.parents_right[roots].all()
    again = result_recall(strokes, res)
    assert all(np.array_equal(getattr(again, f), getattr(rec, f)) for f in rec.__dataclass_fields__)
