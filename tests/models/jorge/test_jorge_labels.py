"""Admissible labels and the CPDs of the seven basic structures (models/jorge/labels.py)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dbn.errors import ModelError
from models.jorge.labels import (
    LabelParams,
    admissible_labels,
    child_table,
    colour_log_likelihood,
    proper_subsets,
    prune_labels,
    restriction_table,
    root_table,
    structure_of,
)

F = frozenset
P = LabelParams(p_new=0.1, p_merge=0.3, p_split=0.6, max_group_size=3)


def test_table_2_of_the_seed():
    """Seed 004 Table 2: labels of the merge/occlusion/split example of fig. 2."""
    l1, l2 = [F({1})], [F({2})]
    l3 = admissible_labels([l1, l2], [False, False], F({3}), 3)
    assert set(l3) == {F({1}), F({2}), F({1, 2}), F({3})}
    l4 = admissible_labels([l3], [False], F({4}), 3)
    assert set(l4) == set(l3) | {F({4})}
    l5 = admissible_labels([l4], [True], F({5}), 3)  # 4 splits into 5 and 6
    assert set(l5) == set(l4) | {F({5})}
    assert l5[0] == F({5})


def test_max_group_size_and_disjoint_unions():
    dom = admissible_labels([[F({1, 2})], [F({2}), F({3})]], [False, False], F({9}), 3)
    assert F({1, 2, 3}) in dom and F({1, 2}) in dom
    assert all(len(x) <= 3 for x in dom)
    small = admissible_labels([[F({1, 2})], [F({3})]], [False, False], F({9}), 2)
    assert F({1, 2, 3}) not in small


def test_eq10_occlusion_and_eq4_merge_exactly():
    dom = [F({5}), F({1}), F({2})]
    t = child_table([[F({1}), F({2})]], [False], dom, F({5}), P)
    np.testing.assert_allclose(t, [[0.1, 0.9, 0.0], [0.1, 0.0, 0.9]])
    p0 = LabelParams(p_new=0.2, p_merge=0.0)
    dom = [F({9}), F({1}), F({2}), F({1, 2})]
    t = child_table([[F({1})], [F({2})]], [False, False], dom, F({9}), p0)
    np.testing.assert_allclose(t[0, 0], [0.2, 0.4, 0.4, 0.0])  # eq. 3 and eq. 4


def test_split_rows():
    dom = [F({7}), F({1}), F({2}), F({1, 2})]
    t = child_table([[F({1, 2})]], [True], dom, F({7}), P)
    np.testing.assert_allclose(t[0], [0.1, 0.9 * 0.3, 0.9 * 0.3, 0.9 * 0.4])


labels_strategy = st.frozensets(st.integers(0, 5), min_size=1, max_size=3)
domain_strategy = st.lists(labels_strategy, min_size=1, max_size=4, unique=True)


@settings(max_examples=60, deadline=None)
@given(
    doms=st.lists(domain_strategy, min_size=1, max_size=2),
    shared=st.lists(st.booleans(), min_size=2, max_size=2),
    p_new=st.floats(0.01, 0.5),
    p_merge=st.floats(0.0, 0.45),
    p_split=st.floats(0.0, 1.0),
    gmax=st.integers(1, 4),
)
def test_every_row_sums_to_one(doms, shared, p_new, p_merge, p_split, gmax):
    params = LabelParams(p_new, p_merge, p_split, gmax)
    flags = shared[: len(doms)]
    new = F({99})
    child = admissible_labels(doms, flags, new, gmax)
    t = child_table(doms, flags, child, new, params)
    assert t.shape == (*[len(d) for d in doms], len(child))
    np.testing.assert_allclose(t.sum(-1), 1.0, atol=1e-12)
    assert np.all(t >= 0)
    assert np.all(t[..., 0] >= p_new - 1e-12)  # the new label keeps at least P_new
    assert structure_of(len(doms), flags) in (
        "OCCLUSION", "SPLIT", "MERGE", "MERGE_ONE_SPLITTING", "MERGE_BOTH_SPLITTING")


@settings(max_examples=40, deadline=None)
@given(a=domain_strategy, b=domain_strategy)
def test_restriction_rows(a, b):
    t = restriction_table(a, b)
    np.testing.assert_allclose(t.sum(-1), 1.0)
    for i, x in enumerate(a):
        for j, y in enumerate(b):
            assert t[i, j, 1] == float(not (x & y))


def test_root_and_structures():
    np.testing.assert_array_equal(root_table([F({0})], F({0})), [1.0])
    assert structure_of(0, []) == "ROOT"
    assert structure_of(2, [True, True]) == "MERGE_BOTH_SPLITTING"
    with pytest.raises(ModelError):
        structure_of(3, [False] * 3)
    with pytest.raises(ModelError):
        LabelParams(p_new=0.6, p_merge=0.5)


def test_proper_subsets():
    assert len(proper_subsets(F({1, 2, 3}))) == 6
    assert proper_subsets(F({1})) == []


def test_eq6_as_written_prefers_four_matches_and_ratio_does_not():
    colours = np.array([0, 1, 2, 3, 4])
    pal = np.zeros((2, 12), bool)
    pal[0, [0, 1, 2, 3, 4]] = True  # all five match
    pal[1, [0, 1, 2, 3, 9]] = True  # four match
    new = np.zeros(2, bool)
    eq6 = colour_log_likelihood(colours, pal, new, 0.8, 12, mode="eq6")
    ratio = colour_log_likelihood(colours, pal, new, 0.8, 12, mode="ratio")
    assert eq6[1] > eq6[0]  # 5 * 0.8^4 * 0.2 > 0.8^5
    assert ratio[0] > ratio[1]


def test_prune_keeps_map_and_forced():
    dom = [F({k}) for k in range(5)]
    post = np.array([0.0001, 0.6, 0.3, 0.0999, 0.0])
    kept = prune_labels(dom, post, 0.05, keep=[F({0})])
    assert kept == [F({0}), F({1}), F({2}), F({3})]
    assert prune_labels(dom, post, 0.05, keep=[F({0})], max_labels=2) == [F({0}), F({1})]


def test_cohort_size_and_known_objects():
    """Objects of a new group of m carry m in their ids; a label holding part of a cohort
    knows none of its palettes (issue 16: the palette recorded at a group's birth is the
    group's, not one member's)."""
    from models.jorge.labels import cohort_size, known_objects, new_objects

    for m in range(1, 6):
        group = new_objects(7, m)
        assert len(group) == m and all(cohort_size(o) == m for o in group)
    assert new_objects(7, 1) == F({7})
    assert all(not (new_objects(7, a) & new_objects(7, b)) for a in range(1, 6) for b in range(a + 1, 6))
    pair, trio = sorted(new_objects(3, 2)), sorted(new_objects(4, 3))
    assert sorted(known_objects(F(pair), 9)) == pair  # the whole cohort
    assert known_objects(F(pair[:1]), 9) == []  # half of it
    assert sorted(known_objects(F({5, *trio}), 9)) == sorted([5, *trio])
    assert sorted(known_objects(F({5, trio[0]}), 9)) == [5]
    assert known_objects(F({9}), 9) == []  # born at the stroke itself: no record yet


def test_evidence_names_still_importable_from_labels():
    """The soft-evidence likelihoods moved to ``models.jorge.evidence``; the names users
    imported from ``models.jorge.labels`` are the same objects."""
    from models.jorge import evidence, labels

    for name in evidence.__all__:
        assert getattr(labels, name) is getattr(evidence, name), name
        assert name in labels.__all__, name


# objects of strokes 1-4 (the stroke under test is 3): lone newcomers and members of new
# groups of 2 and 3 (models.jorge.labels.new_objects)
def _objects():
    from models.jorge.labels import new_objects

    return sorted({o for b in range(1, 5) for m in (1, 2, 3) for o in new_objects(b, m)})


@settings(max_examples=60, deadline=None)
@given(data=st.data())
def test_label_objects_follows_known_objects(data):
    """Every label of a domain, in :func:`label_objects`' flattened arrays, against the
    plain definition: its objects' palette strokes in the label's order, the known ones
    those of :func:`known_objects` (with palettes of their own and joiners' birth labels
    drawn at random), and whether it holds an object born at the stroke. (The two differ
    for a new group's member taken as a joiner, which the network never makes.)"""
    from models.jorge.labels import NEW_STRIDE, birth_stroke, known_objects, label_objects

    objs = _objects()
    labels_ = st.frozensets(st.sampled_from(objs), min_size=1, max_size=4)
    domain = data.draw(st.lists(labels_, min_size=1, max_size=6, unique=True))
    own = data.draw(st.dictionaries(st.sampled_from(objs), st.integers(5, 9), max_size=4))
    # a joiner is a lone newcomer (LabelGraph._replace_joiners: the object born at a join
    # label's stroke, {k}); a member of a new group never is
    lone = [o for o in objs if o < NEW_STRIDE]
    joined = data.draw(st.dictionaries(st.sampled_from(lone), labels_, max_size=3))
    k = 3
    got = label_objects(domain, k, own, joined)
    assert got.sizes.tolist() == [len(lab) for lab in domain]
    strokes = [own.get(o, birth_stroke(o)) for lab in domain for o in lab]
    assert got.palette_strokes.tolist() == strokes
    assert got.is_new.tolist() == [any(birth_stroke(o) == k for o in lab) for lab in domain]
    ends = np.cumsum(got.known_counts)
    for i, lab in enumerate(domain):
        known = got.known_strokes[ends[i] - got.known_counts[i]: ends[i]]
        expect = [own.get(o, birth_stroke(o)) for o in known_objects(lab, k, own, joined)]
        assert sorted(known.tolist()) == sorted(expect), lab


@settings(max_examples=60, deadline=None)
@given(first=st.lists(st.frozensets(st.integers(0, 80), min_size=1, max_size=4), max_size=12),
       second=st.lists(st.frozensets(st.integers(0, 80), min_size=1, max_size=4), max_size=12),
       max_size=st.integers(1, 6))
def test_disjoint_unions_is_the_pairwise_loop(first, second, max_size):
    """Eq. 8's merged labels, vectorised with bit masks (and the loop past 62 objects),
    against the plain loop over every pair."""
    from models.jorge.labels import _disjoint_unions

    expect = {a | b for a in first for b in second if not (a & b) and len(a) + len(b) <= max_size}
    assert _disjoint_unions(first, second, max_size) == expect
