"""The split prior that prefers partitions (issue 16, sixteenth round): the restriction
node of two children of one group also takes the group as its parent, and two disjoint
labels that lose one of its people weigh :math:`w_n` (``LabelParams.split_cover``)
against 1 for a partition; checked against enumeration of the pieces, the definition of
the table, brute force over a window, and pgmpy."""

from __future__ import annotations

import itertools
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dbn.errors import ModelError
from models.jorge.fit import EventCounts, _count_splits, fit_parameters, fit_split_cover
from models.jorge.labels import (
    LabelParams,
    proper_subsets,
    restriction_allows,
    restriction_table,
    split_loss_weights,
)
from models.jorge.network import (
    FITTED_LABELS,
    FITTED_SPLIT_COVER,
    LabelGraph,
    NetworkConfig,
    node_name,
)
from models.jorge.online import OnlineConfig, OnlineLabeller
from models.jorge.strokes import StrokeSet, make_stroke
from tests.models.jorge.test_jorge_groups import _check_window, _dense_log_joint

SEED_LABELS = replace(FITTED_LABELS, new_group_probs=(1.0,), p_join=0.0, split_cover=(),
                      split_normalise=False)  # eq. 5 alone; the cover unscaled (test_jorge_split_normalise)


def _cover_share(n: int, w: float) -> float:
    """P(two disjoint proper pieces of a group of n hold everyone), pieces drawn uniformly
    and independently (eq. 9), disjoint pairs weighted 1 (partition) or w."""
    group = frozenset(range(n))
    cover = lose = 0.0
    for a, b in itertools.product(proper_subsets(group), repeat=2):
        if a & b:
            continue
        if a | b == group:
            cover += 1.0
        else:
            lose += w
    return cover / (cover + lose)


@settings(max_examples=30, deadline=None)
@given(n=st.integers(3, 5), p=st.floats(0.01, 1.0))
def test_the_weights_give_the_cover_probability(n, p):
    w = split_loss_weights([1.0] * (n - 1) + [p])[n - 1]
    floor = _cover_share(n, 1.0)  # eq. 5 alone; w is at most 1
    assert 0 <= w <= 1
    assert _cover_share(n, w) == pytest.approx(max(p, floor), rel=1e-9)


def test_eq5_alone_expects_groups_to_lose_people():
    assert [round(_cover_share(n, 1.0), 4) for n in (3, 4, 5)] == [
        round(6 / 12, 4), round(14 / 50, 4), round(30 / 180, 4)]
    assert np.all(split_loss_weights([1.0, 1.0]) == 1.0)  # two disjoint parts of a pair always cover


def _labels(draw_sets):
    return [frozenset(s) for s in draw_sets]


RESTRICTION_CASES = given(  # two children's domains, their group's, and p_n (shared with test_jorge_split_normalise)
    di=st.lists(st.sets(st.integers(0, 4), min_size=1, max_size=3), min_size=1, max_size=4),
    dj=st.lists(st.sets(st.integers(0, 4), min_size=1, max_size=3), min_size=1, max_size=4),
    dp=st.lists(st.sets(st.integers(0, 4), min_size=1, max_size=5), min_size=1, max_size=4),
    cover=st.lists(st.floats(0.05, 1.0), min_size=1, max_size=5))


@settings(max_examples=30, deadline=None)
@RESTRICTION_CASES
def test_the_table_is_its_definition(di, dj, dp, cover):
    di, dj, dp = _labels(di), _labels(dj), _labels(dp)
    t = restriction_table(di, dj, False, dp, cover)
    w = split_loss_weights(cover)
    assert t.shape == (len(dp), len(di), len(dj), 2)
    for (x, xp), (y, a), (z, b) in itertools.product(enumerate(dp), enumerate(di), enumerate(dj)):
        want = 0.0 if a & b else (1.0 if xp <= a | b else w[min(len(xp), len(w)) - 1])
        assert t[x, y, z, 1] == pytest.approx(want)
        assert t[x, y, z, 0] == pytest.approx(1.0 - want)
    # without a parent, or nested, it is eq. 5 (nested: our restriction_allows)
    np.testing.assert_array_equal(restriction_table(di, dj, False, None, cover), restriction_table(di, dj))
    np.testing.assert_array_equal(restriction_table(di, dj, True, dp, cover), restriction_table(di, dj, True))
    assert all(t[:, y, z, 1].max() <= float(restriction_allows(a, b)) for (y, a), (z, b)
               in itertools.product(enumerate(di), enumerate(dj)))


def _split_graph(split_cover) -> LabelGraph:
    """Three people walk in together (stroke 0, a new group), the group splits into strokes 1
    and 2."""
    g = LabelGraph(NetworkConfig(labels=_split_labels(split_cover)), fps=25.0)
    for s in _split_strokes():
        g.add_stroke(s)
    return g


def _split_labels(split_cover) -> LabelParams:
    return replace(SEED_LABELS, max_group_size=3, new_group_probs=(0.4, 0.3, 0.3), split_cover=split_cover)


def _split_strokes() -> list:
    return [make_stroke(0, 0, 10, (50, 50), (60, 50), [0, 1, 2, 3, 4, 5], {0, 1, 2}, size=(60, 50)),
            make_stroke(1, 12, 20, (50, 50), (40, 50), [0, 1, 2], {0}, size=(20, 50)),
            make_stroke(2, 12, 20, (70, 50), (80, 50), [3, 4, 5], {1, 2}, size=(40, 50))]


def test_the_restriction_node_takes_the_group_as_parent():
    g = _split_graph((1.0, 1.0, 0.9))
    win = g.window([0, 1, 2])
    cpd = win.bn.cpd("r1_2")
    assert list(cpd.parents) == [node_name(0), node_name(1), node_name(2)]
    assert list(_split_graph(()).window([0, 1, 2]).bn.cpd("r1_2").parents) == [node_name(1), node_name(2)]


@pytest.mark.parametrize("split_cover", [(), (1.0, 1.0, 0.9), (1.0, 1.0, 0.2)])
def test_window_against_brute_force(split_cover):
    # MAP, evidence and marginals against the dense enumeration oracle of test_jorge_groups
    _check_window(_split_graph(split_cover).window([0, 1, 2]))


def test_window_same_as_pgmpy(assert_window_matches_pgmpy):
    assert_window_matches_pgmpy(_split_graph((1.0, 1.0, 0.9)).window([0, 1, 2]), 3)


def test_the_posterior_of_a_partition_rises_with_the_cover_probability():
    def p_partition(split_cover):
        win = _split_graph(split_cover).window([0, 1, 2])
        names, lj = _dense_log_joint(win)
        dom = [win.domains[n] for n in names]
        cover = np.array([len(dom[0][x]) == 3 and dom[0][x] <= dom[1][y] | dom[2][z]
                          for x, y, z in np.ndindex(lj.shape)]).reshape(lj.shape)
        w = np.exp(lj - lj.max())
        return float(w[cover].sum() / w.sum())
    eq5 = p_partition(())
    probs = [p_partition((1.0, 1.0, p)) for p in (0.6, 0.9, 0.99)]
    assert p_partition((1.0, 1.0, 0.2)) == pytest.approx(eq5)  # below eq. 5's share: w = 1
    assert eq5 < probs[0] < probs[1] < probs[2]


def _two_splits():
    """A group of 3 splits into all of its people (strokes 1, 2); another loses one (4, 5)."""
    return [
        make_stroke(0, 0, 10, (50, 50), (60, 50), [0, 1, 2], {0, 1, 2}, size=(60, 50)),
        make_stroke(1, 12, 20, (50, 50), (40, 50), [0], {0}, size=(20, 50)),
        make_stroke(2, 12, 20, (70, 50), (80, 50), [1, 2], {1, 2}, size=(40, 50)),
        make_stroke(3, 30, 40, (250, 50), (260, 50), [3, 4, 5], {3, 4, 5}, size=(60, 50)),
        make_stroke(4, 42, 50, (250, 50), (240, 50), [3], {3}, size=(20, 50)),
        make_stroke(5, 42, 50, (270, 50), (280, 50), [4], {4}, size=(20, 50)),  # person 5 lost
    ]


def test_fit_counts_partitions_per_group_size():
    g = LabelGraph(NetworkConfig(labels=replace(SEED_LABELS, max_group_size=3)), fps=25.0)
    for s in _two_splits():
        g.add_stroke(s)
    assert [g.nodes[k].parents for k in (1, 2, 4, 5)] == [(0,), (0,), (3,), (3,)]
    c = EventCounts()
    _count_splits(c, g)
    assert sorted(c.splits) == [(3, False), (3, True)]
    assert fit_split_cover(c.splits, 4) == (1.0, 1.0, 0.5, 0.5)  # add-one: (1 + 1) / (2 + 2); none of 4


def test_fit_parameters_fits_it_only_where_it_is_on():
    sets = [StrokeSet.from_strokes(_two_splits(), fps=25.0)]
    on = NetworkConfig(labels=replace(SEED_LABELS, max_group_size=3, split_cover=(1.0,)))
    assert fit_parameters(sets, on).labels.split_cover == (1.0, 1.0, 0.5)
    off = NetworkConfig(labels=replace(SEED_LABELS, max_group_size=3))
    assert fit_parameters(sets, off).labels.split_cover == ()
    # the default network weighs a split that loses people (issue 16, twenty-second round)
    assert FITTED_LABELS.split_cover == FITTED_SPLIT_COVER
    assert len(FITTED_SPLIT_COVER) == FITTED_LABELS.max_group_size


@pytest.mark.parametrize("bad", [(0.0,), (1.0, 1.5), (float("nan"),), ((0.5, 0.5),)])
def test_bad_split_cover_raises_naming_the_field(bad):
    with pytest.raises(ModelError, match="split_cover"):
        LabelParams(split_cover=bad)


def _instant_oracle(lab: OnlineLabeller, k: int, sib: int, parent: int, w: np.ndarray) -> np.ndarray:
    """Eq. 12 posterior of ``k`` by its definition: evidence and prior (``_log_score``)
    times, for the sibling's current label, 0 for a shared object, 1 for a partition of
    the parent's current label and ``w[n - 1]`` for two disjoint labels that lose someone
    of a parent of n people."""
    other, group = lab.labels[sib], lab.labels[parent]
    weight = np.array([0.0 if x & other else 1.0 if group <= x | other else w[len(group) - 1]
                       for x in lab.graph.nodes[k].domain])
    with np.errstate(divide="ignore"):
        score = lab._log_score(k) + np.log(weight)
    post = np.exp(score - score.max())
    return post / post.sum()


def _known_people_split() -> list:
    """Three people seen alone (strokes 0-2) merge (3, then 4) and split: one alone (5), two
    together (6); with their links."""
    a, b, c = [0, 1, 2, 3, 4], [5, 6, 7, 8, 9], [10, 11, 0, 5, 6]
    ab, abc, bc = sorted({*a, *b}), sorted({*a, *b, *c}), sorted({*b, *c})
    strokes = [make_stroke(0, 0, 10, (10, 50), (40, 50), a, {0}, size=(20, 50)),
               make_stroke(1, 0, 10, (90, 50), (60, 50), b, {1}, size=(20, 50)),
               make_stroke(2, 0, 30, (50, 10), (50, 40), c, {2}, size=(20, 50)),
               make_stroke(3, 12, 25, (50, 50), (50, 50), ab, {0, 1}, size=(40, 50)),
               make_stroke(4, 32, 50, (50, 50), (50, 50), abc, {0, 1, 2}, size=(60, 50)),
               make_stroke(5, 52, 60, (40, 50), (20, 50), a, {0}, size=(20, 50)),
               make_stroke(6, 52, 60, (60, 50), (80, 50), bc, {1, 2}, size=(40, 50))]
    return list(zip(strokes, ((), (), (), (0, 1), (3, 2), (4,), (4,))))


@pytest.mark.parametrize("split_cover", [(), (1.0, 1.0, 0.9), (1.0, 1.0, 0.2)])
def test_instant_labels_weigh_the_split_as_the_window_does(split_cover):
    lab = OnlineLabeller(OnlineConfig(network=NetworkConfig(labels=_split_labels(split_cover))), fps=25.0)
    for s, parents in _known_people_split():
        lab.add_stroke(s, parents)
    assert len(lab.labels[4]) == 3 and len(lab.labels[5]) == 1  # the group, the one who left
    w = split_loss_weights(split_cover) if split_cover else np.ones(3)
    expected = _instant_oracle(lab, 6, 5, 4, w)
    assert np.allclose(lab.instant_posterior(6), expected, rtol=1e-9, atol=0)
    dom = lab.graph.nodes[6].domain
    loses = np.array([not (x & lab.labels[5]) and not lab.labels[4] <= x | lab.labels[5] for x in dom])
    assert loses.any()
    eq5 = _instant_oracle(lab, 6, 5, 4, np.ones(3))[loses].sum()
    if w[2] < 1:  # the labels of the rest that lose someone lose mass
        assert expected[loses].sum() < eq5
    else:
        assert expected[loses].sum() == pytest.approx(eq5)
