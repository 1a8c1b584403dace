"""The split's pair of pieces as a draw from the restricted law (issue 16, twenty-third
round; ``LabelParams.split_normalise``): the restriction node of two children of one group
divides by :math:`Z_n`, the chance that two independent pieces of a group of ``n`` are
compatible, so observing the restriction no longer tilts the group's own label towards
fewer people; checked against enumeration of the pieces, the table's definition, brute
force over a window and pgmpy."""

from __future__ import annotations

import itertools
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from models.jorge.labels import proper_subsets, restriction_table, split_pair_scale
from models.jorge.network import FITTED_LABELS, FITTED_SPLIT_COVER, LabelGraph, NetworkConfig
from models.jorge.strokes import make_stroke
from tests.models.jorge.test_jorge_groups import _check_window, _dense_log_joint
from tests.models.jorge.test_jorge_split_cover import RESTRICTION_CASES

GROUPS = [frozenset(range(n)) for n in range(1, 6)]
PIECES = sorted({p for g in GROUPS for p in proper_subsets(g)} | set(GROUPS), key=sorted)


def _compatible_mass(table: np.ndarray) -> np.ndarray:
    """For each parent label x of GROUPS: sum over two proper pieces a, b of x, each drawn
    uniformly (eq. 9), of the r = 1 column: P(r = 1 | x) up to the constant P_split^2."""
    out = []
    for x, group in enumerate(GROUPS):
        sub = [PIECES.index(p) for p in proper_subsets(group)]
        out.append(sum(table[x, a, b, 1] for a, b in itertools.product(sub, sub)) / max(len(sub), 1) ** 2)
    return np.array(out)


@settings(max_examples=30, deadline=None)
@given(cover=st.lists(st.floats(0.05, 1.0), min_size=1, max_size=5))
def test_normalised_every_group_is_as_likely_to_split_compatibly(cover):
    plain = _compatible_mass(restriction_table(PIECES, PIECES, False, GROUPS, cover))
    scaled = _compatible_mass(restriction_table(PIECES, PIECES, False, GROUPS, cover, normalise=True))
    assert plain[0] == 0.0  # one person's two pieces are both the person: never compatible
    assert scaled[1:] == pytest.approx(np.full(4, scaled[1]), rel=1e-9)  # normalised: equal
    scale = split_pair_scale([len(g) for g in GROUPS], cover)
    assert scale.max() == pytest.approx(1.0) and np.all(scale > 0)
    assert scale[0] == scale[1]  # one person is scaled as a pair


@pytest.mark.parametrize("cover", [(1.0,), (1.0, 1.0, 1.0, 1.0, 1.0), FITTED_SPLIT_COVER])
def test_unnormalised_larger_groups_pay_more(cover):
    # eq. 5 alone (every disjoint pair weighs 1): 2 / 4, 12 / 36, 50 / 196, 180 / 900;
    # partitions only: 1 / (2^n - 2); the fitted cover in between
    plain = _compatible_mass(restriction_table(PIECES, PIECES, False, GROUPS, cover))
    assert np.all(np.diff(plain[1:]) < 0)
    if cover == (1.0,):
        assert plain[1:] == pytest.approx([2 / 4, 12 / 36, 50 / 196, 180 / 900])
    if cover == (1.0,) * 5:
        assert plain[1:] == pytest.approx([1 / 2, 1 / 6, 1 / 14, 1 / 30])


@settings(max_examples=30, deadline=None)
@RESTRICTION_CASES
def test_the_table_is_the_cover_table_times_the_scale(di, dj, dp, cover):
    di, dj, dp = ([frozenset(s) for s in d] for d in (di, dj, dp))
    plain = restriction_table(di, dj, False, dp, cover)
    scaled = restriction_table(di, dj, False, dp, cover, normalise=True)
    scale = split_pair_scale([len(x) for x in dp], cover)
    np.testing.assert_allclose(scaled[..., 1], plain[..., 1] * scale[:, None, None], rtol=1e-12)
    np.testing.assert_allclose(scaled.sum(-1), 1.0)
    assert np.all(scaled[..., 1] <= 1.0)
    # without the group (eq. 5 alone) or nested there is nothing to scale
    np.testing.assert_array_equal(restriction_table(di, dj, True, None, cover, normalise=True),
                                  restriction_table(di, dj, True))


def _four_in_four_out(normalise: bool) -> LabelGraph:
    """Four people walk in together (stroke 0, a new group); one steps out (stroke 1) while the
    other three go on (stroke 2)."""
    labels = replace(FITTED_LABELS, split_normalise=normalise)
    g = LabelGraph(NetworkConfig(labels=labels), fps=25.0)
    for s in [make_stroke(0, 0, 10, (50, 50), (60, 50), list(range(8)), {0, 1, 2, 3}, size=(80, 50)),
              make_stroke(1, 12, 20, (30, 50), (20, 50), [0, 1], {0}, size=(20, 50)),
              make_stroke(2, 12, 20, (70, 50), (80, 50), list(range(2, 8)), {1, 2, 3}, size=(60, 50))]:
        g.add_stroke(s)
    return g


@pytest.mark.parametrize("normalise", [False, True])
def test_window_against_brute_force(normalise):
    _check_window(_four_in_four_out(normalise).window([0, 1, 2]))


def test_window_same_as_pgmpy(assert_window_matches_pgmpy):
    assert_window_matches_pgmpy(_four_in_four_out(True).window([0, 1, 2]), 3)


def test_the_group_keeps_its_people_through_a_split():
    def p_four(normalise):
        win = _four_in_four_out(normalise).window([0, 1, 2])
        names, lj = _dense_log_joint(win)
        size = np.array([len(x) for x in win.domains[names[0]]])
        w = np.exp(lj - lj.max())
        return float(w[size == 4].sum() / w.sum())
    assert p_four(True) > p_four(False)


def test_without_the_split_cover_it_does_nothing():
    # eq. 5 alone has no group in the restriction's scope, so there is nothing to scale
    def table(normalise):
        labels = replace(FITTED_LABELS, split_cover=(), split_normalise=normalise)
        g = LabelGraph(NetworkConfig(labels=labels), fps=25.0)
        for s in _four_in_four_out(True).nodes:
            g.add_stroke(s.stroke)
        return g.window([0, 1, 2]).bn.cpd("r1_2")
    on, off = table(True), table(False)
    assert list(on.parents) == list(off.parents) == ["x1", "x2"]
    np.testing.assert_array_equal(on.table, off.table)
    assert FITTED_LABELS.split_cover == FITTED_SPLIT_COVER and FITTED_LABELS.split_normalise
