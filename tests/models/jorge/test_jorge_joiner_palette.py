"""A joiner's palette (issue 16, tenth round): a newcomer who joins an inherited label is
born at a stroke whose palette holds the inherited people's colours too, so, like a member
of a new group, it is known (its palette on record for the palette gain evidence) only in
a label holding its whole birth label, until a stroke frozen to it alone gives it a
palette of its own. Before, a joiner counted as born alone and was credited with the whole
region's colours, so the stroke of that person leaving the group later looked less like
them than like a new object."""

from __future__ import annotations

import numpy as np

from models.jorge.fit import EventCounts, _count_palette_gains
from models.jorge.labels import LabelParams, label_objects, new_objects
from models.jorge.network import LabelGraph, NetworkConfig
from models.jorge.strokes import make_stroke

POOL = 40
CFG = NetworkConfig(pool_size=POOL, labels=LabelParams(max_group_size=3, p_join=0.1), size_evidence=False,
                    palette_count_table=())


def _stroke(k, start, end, x0, x1, people, width=20.0):
    """Person ``p`` shows colours ``5p .. 5p + 4``; a region of two shows 3 of each."""
    cols = sorted({c for p in people for c in range(5 * p, 5 * p + (5 if len(people) == 1 else 3))})
    return make_stroke(k, start, end, (x0, 100), (x1, 100), cols, people, pool_size=POOL, size=(width, 50.0))


def join_strokes() -> list:
    """Person 0 walks alone (stroke 0); person 1 appears inside their region (1, a join);
    the two part (2: person 1 alone, 3: person 0) and meet again (4: one region spanning
    both, the merge test's ``merge_area`` and ``merge_cover``)."""
    return [
        _stroke(0, 0, 10, 100, 100, {0}),
        _stroke(1, 12, 20, 100, 100, {0, 1}),
        _stroke(2, 22, 30, 95, 80, {1}),
        _stroke(3, 22, 30, 105, 120, {0}),
        _stroke(4, 32, 40, 100, 100, {0, 1}, width=60.0),
    ]


def _graph():
    g = LabelGraph(CFG, fps=25.0)
    for s in join_strokes():
        g.add_stroke(s)
    return g


def test_a_frozen_join_makes_its_newcomer_known_only_with_the_whole_birth_label():
    g = _graph()
    assert g.nodes[1].parents == (0,) and g.nodes[2].parents == (1,) and set(g.nodes[4].parents) == {2, 3}
    joiner, alone = frozenset({1}), frozenset({0})
    before = label_objects([joiner, alone | joiner], 2, g._own, g._joined)
    assert before.known_counts.tolist() == [1, 2]  # not frozen yet: counted as born alone
    g.freeze(0, alone)
    g.freeze(1, alone | joiner)
    after = label_objects([joiner, alone | joiner], 2, g._own, g._joined)
    assert after.known_counts.tolist() == [0, 2]  # alone it is unknown; with its birth label known
    assert g.palette_stroke(1) == 1
    g.freeze(2, joiner)  # seen alone: its own palette from then on
    assert g.palette_stroke(1) == 2
    assert label_objects([joiner], 4, g._own, g._joined).known_counts.tolist() == [1]
    np.testing.assert_array_equal(np.flatnonzero(g.palettes([joiner])[0]), np.arange(5, 10))


def test_a_newcomer_born_alone_is_not_a_joiner():
    g = _graph()
    g.freeze(0, frozenset({0}))
    assert g._joined == {}
    assert label_objects([frozenset({0})], 2, g._own, g._joined).known_counts.tolist() == [1]


def test_a_new_group_that_joins_inherited_objects_records_each_member():
    """With new groups anywhere, two newcomers may join an inherited label at once: both
    are joiners, known together only with the inherited object too."""
    g = _graph()
    pair = new_objects(1, 2)
    g.freeze(0, frozenset({0}))
    if frozenset({0}) | pair not in g.nodes[1].domain:  # p_join only: add the label by hand
        g.nodes[1].domain = (*g.nodes[1].domain, frozenset({0}) | pair)
    g.freeze(1, frozenset({0}) | pair)
    assert set(g._joined) == set(pair)
    known = label_objects([pair, frozenset({0}) | pair], 2, g._own, g._joined).known_counts
    assert known.tolist() == [0, 3]


def test_the_fit_counts_a_joiner_as_unknown_until_seen_alone():
    """(m, u, e) per stroke as :func:`_count_palette_gains` counts them on the true labels:
    at stroke 2 person 1 (the joiner) is not known (m = 1, nothing known, all 5 colours
    new); at stroke 3 the person seen alone is known with 5 colours and adds none; at
    stroke 4 both are known, person 1 with the palette of stroke 2."""
    g = LabelGraph(CFG, fps=25.0)
    for s in join_strokes():
        g.add_stroke(s)
    c = EventCounts()
    _count_palette_gains(c, g)
    assert c.palette_gains[2] == (1, 0, 5)
    assert c.palette_gains[3] == (0, 5, 0)
    assert c.palette_gains[4][:2] == (0, 10)
