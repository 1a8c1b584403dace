"""A member of a new group who continues alone is matched against the parent stroke's
palette, their latest view alone (``NetworkConfig.chain_palette``, issue 16, eleventh
round): the correction against its definition (the evidence the member would have with
that stroke frozen alone), the window with it against dense enumeration, and the
re-identification pass in birth order."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from models.jorge.labels import new_objects
from models.jorge.network import FITTED_LABELS, LabelGraph, NetworkConfig, kept_name, node_name
from models.jorge.reid import reidentify
from models.jorge.strokes import make_stroke
from tests.models.jorge.test_jorge_groups import _check_window

F = frozenset
BASE = NetworkConfig(labels=replace(FITTED_LABELS, max_group_size=2, new_group_probs=(0.7, 0.3), p_join=0.0),
                     chain_palette=False)
CFG = replace(BASE, chain_palette=True)
"""The default network (12-colour pool, fitted palette count and gain tables, new groups
at roots) with groups of at most two and no joins, so that the domains stay small enough
to enumerate; ``BASE`` with the chain off, ``CFG`` on (the default)."""

COLOURS = {0: [0, 1, 2], 1: [6, 7, 8], 9: [3, 4, 5]}


def _stroke(k, start, end, x0, x1, people):
    colours = sorted(set().union(*(COLOURS[p] for p in people)))
    return make_stroke(k, start, end, (x0, 100), (x1, 100), colours, people, size=(20.0 * len(people), 50.0))


def pair_leaves():
    """A lone walker far off (stroke 0), people 0 and 1 enter together (1), part (2:
    person 0, 3: person 1) and walk on alone after a short gap (4: person 0, 5: person 1)."""
    return [
        _stroke(0, 0, 40, 300, 300, {9}),
        _stroke(1, 0, 10, 100, 100, {0, 1}),
        _stroke(2, 12, 20, 95, 80, {0}),
        _stroke(3, 12, 20, 105, 120, {1}),
        _stroke(4, 23, 30, 78, 60, {0}),
        _stroke(5, 23, 30, 122, 140, {1}),
    ]


def _graph(cfg=CFG):
    g = LabelGraph(cfg, fps=25.0)
    for s in pair_leaves():
        g.add_stroke(s)
    return g


def test_the_correction_is_the_evidence_with_the_parent_stroke_frozen_alone():
    a, b = sorted(new_objects(1, 2))
    g = _graph()
    assert g.nodes[4].parents == (2,)
    corr = g.chain_log_ratio(4)
    dom_p, dom = g.current_domain(2), g.nodes[4].domain
    i, j = dom_p.index(F({a})), dom.index(F({a}))
    assert corr.shape == (len(dom_p), len(dom))
    same = np.array([[len(x) == 1 and x == y for y in dom] for x in dom_p])
    assert np.all(corr[~same] == 0.0)  # only where both are the same person alone
    assert corr[dom_p.index(F({b})), dom.index(F({b}))] != 0.0
    # the definition: the evidence of stroke 4 for {a} once stroke 2 is frozen to {a}
    # (a's own palette, LabelGraph.freeze), minus the evidence with the pair's palette
    frozen = _graph()
    frozen.freeze(1, new_objects(1, 2))
    frozen.freeze(2, F({a}))
    assert frozen.palette_stroke(a) == 2
    want = frozen.evidence_loglik(4, [F({a})])[0] - g.evidence_loglik(4, [F({a})])[0]
    assert corr[i, j] == pytest.approx(want, abs=1e-12)
    assert corr[i, j] > 0  # stroke 4 shows person 0's colours only, as stroke 2 did
    # nothing to correct once the member has a palette of their own, or with the chain off
    assert frozen.chain_log_ratio(4) is None
    assert _graph(BASE).chain_log_ratio(4) is None


def test_lone_newcomers_keep_their_birth_palette():
    """A person born alone has a palette of their own from birth: no correction (the
    members of the pair stroke 0 might have been are corrected)."""
    g = LabelGraph(CFG, fps=25.0)
    for s in [_stroke(0, 0, 10, 100, 100, {0}), _stroke(1, 12, 20, 95, 80, {0}),
              _stroke(2, 23, 30, 78, 60, {0})]:
        g.add_stroke(s)
    assert g.nodes[2].parents == (1,)
    corr = g.chain_log_ratio(2)  # stroke 0 might have been a pair: its members' cells
    dom_p, dom = g.current_domain(1), g.nodes[2].domain
    assert corr[dom_p.index(F({0})), dom.index(F({0}))] == 0.0
    a, _ = sorted(new_objects(0, 2))
    assert corr[dom_p.index(F({a})), dom.index(F({a}))] != 0.0


def _pair_window(cfg):
    """The window of strokes 2-5, the walker and the pair frozen (a new group of two)."""
    g = _graph(cfg)
    g.freeze(0, F({0}))
    g.freeze(1, new_objects(1, 2))
    return g.window([2, 3, 4, 5])


def test_window_with_the_chain_against_enumeration():
    win, off = _pair_window(CFG), _pair_window(BASE)
    # the chain factor is folded into x4's CPD rows, their scale into the observed m4
    assert win.bn.cpds[kept_name(4)].parents == (node_name(2),)
    assert not np.allclose(win.bn.cpds[node_name(4)].table, off.bn.cpds[node_name(4)].table)
    res = _check_window(win)
    assert res.labels[2] | res.labels[3] == new_objects(1, 2)  # the members part
    assert (res.labels[4], res.labels[5]) == (res.labels[2], res.labels[3])  # and walk on


def test_the_members_who_walk_on_alone_are_not_newcomers():
    """Without the chain, "a new object born at stroke 2" is scored at stroke 4 on stroke
    2's palette and "member a" on the pair's: both members vanish at the split and two
    newcomers walk on (the fault the chain mends). With it both hypotheses are scored
    on a view alone and the prior decides for the members."""
    off = _check_window(_pair_window(BASE)).labels
    assert (off[2], off[3]) == (F({2}), F({3}))
    on = _check_window(_pair_window(CFG)).labels
    assert on[2] | on[3] == new_objects(1, 2)


def test_reidentification_examines_objects_in_birth_order():
    """Person 0 (colours 0-2) is seen alone (stroke 0), enters again with person 1 as a
    new pair (stroke 1, a missed link), walks on alone (stroke 2) and comes back a third
    time (stroke 4, another missed link). Both later objects are person 0; in id order
    the lone newcomer of stroke 4 came before the pair's member born at stroke 1, took
    person 0's object first and left the member nothing to continue."""
    g = LabelGraph(CFG, with_domains=False, fps=25.0)
    strokes = [
        (_stroke(0, 0, 10, 300, 310, {0}), ()),
        (_stroke(1, 20, 30, 100, 100, {0, 1}), ()),
        (_stroke(2, 32, 40, 95, 80, {0}), (1,)),
        (_stroke(3, 32, 40, 105, 120, {1}), (1,)),
        (_stroke(4, 60, 70, 300, 310, {0}), ()),
    ]
    for s, parents in strokes:
        g.add_stroke(s, parents)
    a, b = sorted(new_objects(1, 2))
    assert a > 4  # a new group's ids come after every lone newcomer's
    labels = [F({0}), F({a, b}), F({a}), F({b}), F({4})]
    assert reidentify(g, labels, 0.5) == [F({0}), F({0, b}), F({0}), F({b}), F({0})]
