"""A member of a new group gets a palette of its own once it is frozen alone (issue 16):
the group's birth palette holds every member's colours, so before this the members of a
pair that entered together stayed exchangeable and each later split was a coin toss."""

from __future__ import annotations

import numpy as np
import pytest

from models.jorge.fit import fit_parameters
from models.jorge.labels import LabelParams, known_objects, new_objects
from models.jorge.network import LabelGraph, NetworkConfig
from models.jorge.online import OnlineConfig, label_online
from models.jorge.strokes import StrokeSet, make_stroke

POOL = 40
PARAMS = LabelParams(max_group_size=3, new_group_probs=(0.7, 0.3), p_join=0.0, child_new_groups=False)
CFG = NetworkConfig(pool_size=POOL, labels=PARAMS, size_min_reference=2, size_reference_neighbours=0,
                    size_reference_quantile=0.0, size_mu_single=0.0, size_slope=1.0, size_sigma=0.3,
                    palette_count_table=(), palette_gain_table=(), palette_missing_table=())
"""New groups at roots only (the search's ``"roots"``), exact region sizes (20 wide per
person), no palette count, gain or missing-colour evidence: colours alone tell the members
apart."""


def _colours(people) -> list[int]:
    """Person ``p`` shows their colours ``5p .. 5p + 4``; the pair {0, 1} shows colours of both."""
    if len(people) == 1:
        (p,) = people
        return list(range(5 * p, 5 * p + 5))
    return [0, 1, 2, 5, 6]


def _stroke(k, start, end, x0, x1, people):
    return make_stroke(k, start, end, (x0, 100), (x1, 100), _colours(people), people, pool_size=POOL,
                       size=(20.0 * len(people), 50.0))


def pair_strokes(second: tuple[int, int]) -> list:
    """Two lone walkers far off (strokes 0, 1: the size reference), then people 0 (colours
    0-4) and 1 (colours 5-9) enter together (stroke 2), split (3: person 0, 4: person 1),
    merge (5) and split again (6, 7: the people ``second``)."""
    return [
        _stroke(0, 0, 60, 400, 400, {6}),
        _stroke(1, 0, 60, 500, 500, {7}),
        _stroke(2, 0, 10, 100, 100, {0, 1}),
        _stroke(3, 12, 20, 95, 80, {0}),
        _stroke(4, 12, 20, 105, 120, {1}),
        _stroke(5, 22, 40, 100, 100, {0, 1}),
        _stroke(6, 42, 60, 95, 80, {second[0]}),
        _stroke(7, 42, 60, 105, 120, {second[1]}),
    ]


def _graph(strokes):
    g = LabelGraph(CFG, fps=25.0)
    for s in strokes:
        g.add_stroke(s)
    return g


def test_a_member_frozen_alone_takes_that_strokes_palette():
    g = _graph(pair_strokes((1, 0)))
    a, b = sorted(new_objects(2, 2))
    assert g.nodes[3].parents == (2,) and g.nodes[6].parents == (5,)
    assert g.palette_stroke(a) == g.palette_stroke(b) == 2
    before = g.colour_loglik(6, [frozenset({a}), frozenset({b})])
    assert before[0] == before[1]  # exchangeable: both carry the pair's palette
    g.freeze(2, new_objects(2, 2))
    g.freeze(3, frozenset({a}))
    g.freeze(4, frozenset({b}))
    assert (g.palette_stroke(a), g.palette_stroke(b)) == (3, 4)
    np.testing.assert_array_equal(np.flatnonzero(g.palettes([frozenset({b})])[0]), np.arange(5, 10))
    after = g.colour_loglik(6, [frozenset({a}), frozenset({b})])
    assert after[1] > after[0]  # stroke 6 is person 1, whose colours b took at stroke 4
    assert known_objects(frozenset({a}), 6, own={a}) == [a]
    assert known_objects(frozenset({a}), 6) == []
    g.freeze(5, new_objects(2, 2))
    g.freeze(6, frozenset({a}))  # a later stroke alone does not move the palette
    assert g.palette_stroke(a) == 3


def test_a_lone_newcomer_keeps_its_birth_palette():
    g = _graph(pair_strokes((0, 1)))
    g.freeze(2, frozenset({2}))
    g.freeze(3, frozenset({2}))
    assert g.palette_stroke(2) == 2


@pytest.mark.parametrize("second", [(0, 1), (1, 0)])
def test_the_second_split_follows_the_colours(second):
    """Either order of the people at the second split gets the objects of the first split
    (a tie broken by domain order would get one order wrong). With three active nodes, the
    last inference freezes the first split and solves the merge and the second split."""
    strokes = pair_strokes(second)
    cfg = OnlineConfig(period_s=0.5, max_active=3, reid_prior=0.0, network=CFG)
    labels = label_online(StrokeSet.from_strokes(strokes, pool_size=POOL, fps=25.0), cfg, fps=25.0).labels
    assert labels[2] == labels[5] == new_objects(2, 2)
    person = {next(iter(strokes[k].truth)): labels[k] for k in (3, 4)}
    assert labels[3] != labels[4]
    assert labels[6] == person[second[0]] and labels[7] == person[second[1]]


def test_the_fit_counts_a_member_seen_alone_as_known():
    """The gain table's counts mirror the network: once seen alone, each member of the pair
    is known with that stroke's palette."""
    strokes = StrokeSet.from_strokes(pair_strokes((1, 0)), pool_size=POOL, fps=25.0)
    p = np.exp(np.array(fit_parameters([strokes], CFG).palette_gain_table))
    assert p.shape == (4, 5, 2 * POOL + 1)  # m, bin of the known colours u, e
    # (m, u, e) per stroke: walkers (1, 0, 5) twice; pair (2, 0, 5); first split (1, 0, 5)
    # twice (part of a cohort: unknown); merge (0, 10, 5 - 10) (each known with five
    # colours of their own); second split (0, 5, 0) twice. Bins of u: 0, 1-5, 6-7, 8-9, 10+
    zero = POOL
    assert p[0, 1, zero] == pytest.approx((2 + 1) / (2 + 2 * POOL + 1))
    assert p[0, 4, zero - 5] == pytest.approx((1 + 1) / (1 + 2 * POOL + 1))
    assert p[1, 0, zero + 5] == pytest.approx((4 + 1) / (4 + 2 * POOL + 1))
    assert p[2, 0, zero + 5] == pytest.approx((1 + 1) / (1 + 2 * POOL + 1))
    np.testing.assert_allclose(p[0, 0], 1 / (2 * POOL + 1))  # no stroke: add-one uniform
