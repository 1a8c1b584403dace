"""A member seen alone for a moment, then the whole group again: the group's stroke is a
parent of the new one beside the member's (``NetworkConfig.nested_links``), and the
restriction between the two children of the group admits the member inside the new
stroke (:func:`models.jorge.labels.restriction_allows`, nested). Issue 16, twelfth
round: without both, the group came back as the member alone or the member plus a
newcomer, and the error was carried along the group's chain."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from models.jorge.fit import count_events
from models.jorge.labels import restriction_allows, restriction_table
from models.jorge.network import (
    FITTED_LABELS,
    LabelGraph,
    NetworkConfig,
    node_name,
    restriction_name,
)
from models.jorge.online import OnlineConfig, OnlineLabeller
from models.jorge.strokes import StrokeSet, make_stroke
from tests.models.jorge.test_jorge_groups import _check_window, _online

F = frozenset
CFG = NetworkConfig(labels=replace(FITTED_LABELS, max_group_size=2, new_group_probs=(0.7, 0.3), p_join=0.0))
"""The default network with groups of at most two and no joins (small domains)."""
OFF = replace(CFG, nested_links=0.0)

COLOURS = {0: [0, 1, 2], 1: [6, 7, 8]}


def _stroke(k, start, end, x0, x1, people):
    colours = sorted(set().union(*(COLOURS[p] for p in people)))
    return make_stroke(k, start, end, (x0, 100), (x1, 100), colours, people, size=(20.0 * len(people), 50.0))


def merge_back():
    """People 0 and 1 enter apart (strokes 0, 1) and meet (2); person 0 is seen alone for
    three frames (3), the other hidden, then the pair again (4)."""
    return [
        _stroke(0, 0, 10, 90, 100, {0}),
        _stroke(1, 0, 10, 130, 120, {1}),
        _stroke(2, 12, 30, 110, 110, {0, 1}),
        _stroke(3, 32, 34, 100, 100, {0}),
        _stroke(4, 36, 50, 110, 110, {0, 1}),
    ]


def _graph(cfg):
    g = LabelGraph(cfg, fps=25.0)
    for s in merge_back():
        g.add_stroke(s)
    return g


def test_restriction_admits_a_nested_sibling_inside_only():
    a, b, c = F({1}), F({1, 2}), F({2})
    assert not restriction_allows(a, b) and restriction_allows(a, c)  # the seed's eq. 5
    assert restriction_allows(a, b, nested=True)  # the member inside the group again
    assert not restriction_allows(b, F({1, 3}), nested=True)  # a part only: not admitted
    assert not restriction_allows(b, a, nested=True)  # nested is one way: i parent of j
    t = restriction_table([a, b], [b, c], nested=True)
    np.testing.assert_array_equal(t[..., 1], [[1.0, 1.0], [1.0, 0.0]])
    np.testing.assert_array_equal(t.sum(axis=-1), 1.0)


def test_the_link_rule_keeps_the_group_beside_its_part():
    assert _graph(CFG).nodes[4].parents == (2, 3)
    assert _graph(OFF).nodes[4].parents == (3,)  # the group superseded by its child


def test_a_lone_walker_gets_no_nested_link():
    """A person's stroke continued twice with the same box: the first is superseded by
    the second (the part test fails: equal boxes)."""
    strokes = [_stroke(0, 0, 10, 90, 100, {0}), _stroke(1, 12, 14, 102, 104, {0}), _stroke(2, 16, 30, 106, 120, {0})]
    g = LabelGraph(CFG, fps=25.0)
    for s in strokes:
        g.add_stroke(s)
    assert g.nodes[2].parents == (1,)


def test_nested_window_against_enumeration():
    g = _graph(CFG)
    g.freeze(0, F({0}))
    g.freeze(1, F({1}))
    win = g.window([2, 3, 4])
    assert win.bn.cpds[restriction_name(3, 4)].parents == (node_name(3), node_name(4))
    res = _check_window(win)
    assert [res.labels[k] for k in (2, 3, 4)] == [F({0, 1}), F({0}), F({0, 1})]


def test_the_group_comes_back_whole_on_line():
    truth = [F(s.truth) for s in merge_back()]
    assert [_online(merge_back(), CFG).labels[k] for k in range(5)] == truth
    # without the nested link stroke 4 inherits from stroke 3 alone: the pair there
    # needs stroke 3 to be the pair too (a join would add a newcomer, not person 1)
    off = _online(merge_back(), OFF)
    assert [off.labels[k] for k in range(5)] != truth


def test_the_instant_posterior_admits_the_member_inside_the_group():
    """Eq. 12 when stroke 4 starts, stroke 3 labelled person 0 alone: the pair keeps its
    mass (the seed's restriction would zero every label holding person 0)."""
    lab = OnlineLabeller(OnlineConfig(network=CFG, period_s=1e3, reid_prior=0.0), fps=25.0)
    for s in merge_back()[:4]:
        lab.add_stroke(s)
    lab.labels.update({0: F({0}), 1: F({1}), 2: F({0, 1}), 3: F({0})})
    lab.add_stroke(merge_back()[4])
    dom = lab.graph.nodes[4].domain
    post = lab.instant_posterior(4)
    assert post[dom.index(F({0, 1}))] > 0.5
    # were stroke 3 the pair, stroke 4 could not be a part of it (one way: 3 inside 4)
    lab.labels[3] = F({0, 1})
    post = lab.instant_posterior(4)
    parts = [i for i, x in enumerate(dom) if x & F({0, 1}) and not x >= F({0, 1})]
    assert parts and all(post[i] == 0.0 for i in parts) and post[dom.index(F({0, 1}))] > 0.0


def test_the_fit_counts_the_nested_piece_as_a_proper_part():
    """Stroke 4 takes person 1 from the pair (stroke 2, which splits) and person 0 from
    stroke 3: a merge of structure e, the pair handing a proper part, as stroke 3's was."""
    c = count_events(StrokeSet.from_strokes(merge_back(), fps=25.0), CFG)
    assert (c.merge[1], c.two_parent[1]) == (1, 1)
    assert (c.split_part, c.split_total) == (2, 2)
