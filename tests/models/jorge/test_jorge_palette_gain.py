"""Palette colour count given the palettes a label's objects already have (issue 16):
``palette_gain_log_likelihood`` reads ``log p(e | m)``, the fit's gain table is add-one
smoothed frequencies, and a merge of two people with disjoint palettes is not taken for
the pair plus a newcomer (a join), as the marginal count table took it; ``size_once``
counts a region's size once along an occlusion chain."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from dbn.errors import InputError, ModelError
from models.jorge.fit import fit_parameters
from models.jorge.labels import (
    LabelParams,
    gain_bins_rise,
    palette_gain_bin,
    palette_gain_log_likelihood,
)
from models.jorge.network import LabelGraph, NetworkConfig
from models.jorge.online import OnlineConfig, OnlineLabeller
from models.jorge.strokes import StrokeSet, make_stroke


def test_gain_likelihood_reads_gain_columns_by_newcomers_and_clips():
    rng = np.random.default_rng(1)
    table = np.log(rng.dirichlet(np.ones(9), size=3))  # m = 0..2, e = -4..4
    out = palette_gain_log_likelihood(
        6, np.array([6, 4, 0, 3, 0]), np.array([0, 1, 2, 5, 0]), table
    )
    np.testing.assert_array_equal(
        out, table[[0, 1, 2, 2, 0], [4, 6, 8, 7, 8]]
    )  # e = 0, 2, 6 -> 4, 3, 6 -> 4
    np.testing.assert_array_equal(
        palette_gain_log_likelihood(0, np.array([9]), np.array([0]), table), table[[0], 0]
    )
    np.testing.assert_array_equal(
        palette_gain_log_likelihood(3, np.array([1, 2]), np.array([0, 0]), np.zeros((0, 0))), 0.0
    )
    with pytest.raises(InputError):
        palette_gain_log_likelihood(3, np.array([-1]), np.array([0]), table)
    with pytest.raises(InputError):
        palette_gain_log_likelihood(3, np.array([1, 2]), np.array([0]), table)
    with pytest.raises(ModelError):  # an even number of gain columns has no zero in the middle
        palette_gain_log_likelihood(3, np.array([1]), np.array([0]), table[:, :8])
    with pytest.raises(ModelError):  # not log probabilities
        NetworkConfig(palette_gain_table=tuple(map(tuple, -table)))


def test_gain_likelihood_given_known_colours_reads_the_bin_of_u():
    rng = np.random.default_rng(2)
    table = np.log(rng.dirichlet(np.ones(9), size=(3, 3)))  # m = 0..2, u bins 0 / 1-5 / 6+, e = -4..4
    bins = (0, 1, 6)
    known, new = np.array([0, 1, 5, 6, 11, 3]), np.array([2, 1, 0, 0, 0, 7])
    out = palette_gain_log_likelihood(6, known, new, table, bins)
    cols = np.clip(6 - known + 4, 0, 8)
    np.testing.assert_array_equal(out, table[[2, 1, 0, 0, 0, 2], [0, 1, 1, 2, 2, 1], cols])
    with pytest.raises(ModelError):  # a 3-D table needs its bins
        palette_gain_log_likelihood(6, known, new, table)
    with pytest.raises(ModelError):  # a 2-D table has none
        palette_gain_log_likelihood(6, known, new, table[:, 0], bins)
    with pytest.raises(ModelError):  # one bin per row of axis 1, rising from 0
        palette_gain_log_likelihood(6, known, new, table, (0, 6))
    with pytest.raises(ModelError):
        palette_gain_log_likelihood(6, known, new, table, (1, 2, 6))
    cfg = tuple(tuple(map(tuple, block)) for block in table)
    with pytest.raises(ModelError, match="palette_gain_table"):
        NetworkConfig(palette_gain_table=cfg)  # default bins: five
    # the missing-colour table shares the bins (its default has five: left out here)
    assert NetworkConfig(palette_gain_table=cfg, palette_gain_bins=bins,
                         palette_missing_table=()).palette_gain_bins == bins
    with pytest.raises(ModelError, match="palette_gain_bins"):
        NetworkConfig(palette_gain_bins=(0, 3, 3, 8, 10))


def _merge(palettes=((0, 1, 2, 3, 4), (5, 6, 7, 8, 9))) -> StrokeSet:
    """Two people seen alone, then together (their palettes' union), then one again."""
    a, b = palettes
    strokes = [
        make_stroke(0, 0, 10, (0, 0), (10, 0), list(a), {0}, size=(20, 50)),
        make_stroke(1, 0, 10, (40, 0), (30, 0), list(b), {1}, size=(20, 50)),
        make_stroke(
            2, 12, 20, (20, 0), (20, 0), sorted(set(a) | set(b))[:5], {0, 1}, size=(40, 50)
        ),
    ]
    strokes[2] = replace(strokes[2], palette=np.array(sorted(set(a) | set(b))))
    return StrokeSet.from_strokes(strokes, fps=25.0)


def test_fitted_gain_table_is_smoothed_frequencies():
    cfg = fit_parameters(
        [_merge()], NetworkConfig(labels=LabelParams(max_group_size=3), gate="pixels")
    )
    p = np.exp(np.array(cfg.palette_gain_table))
    assert p.shape == (4, 5, 25)  # m, bin of the known colours u (0, 1-5, 6-7, 8-9, 10+), e
    np.testing.assert_allclose(p.sum(axis=2), 1.0)
    # the merge inherits both people (10 known colours, 10 seen: gain 0); the two roots
    # bring one newcomer each with 5 colours and nothing known
    assert p[0, 4, 12] == pytest.approx((1 + 1) / (1 + 25))
    assert p[1, 0, 17] == pytest.approx((2 + 1) / (2 + 25))
    np.testing.assert_allclose(p[2], 1 / 25)
    np.testing.assert_allclose(p[0, :4], 1 / 25)
    # one bin: the table given m alone, p(e | m)
    one = fit_parameters([_merge()], NetworkConfig(labels=LabelParams(max_group_size=3), gate="pixels",
                                                   palette_gain_table=(), palette_gain_bins=(0,),
                                                   palette_missing_table=()))
    p1 = np.exp(np.array(one.palette_gain_table))
    assert p1.shape == (4, 1, 25)
    assert p1[0, 0, 12] == pytest.approx((1 + 1) / (1 + 25))
    assert p1[1, 0, 17] == pytest.approx((2 + 1) / (2 + 25))


def _merge_label(gain: bool) -> frozenset:
    # marginal count table: 10 colours are rare for a random pair, common for three people
    count = np.full((3, 13), 1e-3)
    count[0, 5], count[1, 8], count[2, 10] = 1.0, 1.0, 1.0
    count = np.log(count / count.sum(axis=1, keepdims=True))
    gains = np.full((4, 25), 1e-3)
    gains[0, 12], gains[1, 17], gains[2, 20], gains[3, 22] = 1.0, 1.0, 1.0, 1.0
    gains = np.log(gains / gains.sum(axis=1, keepdims=True))
    labels = LabelParams(max_group_size=3, new_group_probs=(0.8, 0.2), p_join=0.1, p_new=0.05)
    cfg = NetworkConfig(
        labels=labels,
        size_evidence=False,
        gate="pixels",
        palette_count_table=() if gain else tuple(map(tuple, count)),
        palette_gain_table=tuple(map(tuple, gains)) if gain else (),
    )
    lab = OnlineLabeller(OnlineConfig(network=cfg, reid_prior=0.0), fps=25.0)
    for s in _merge():
        out = lab.add_stroke(s)
    return out


def test_a_merge_of_disjoint_palettes_is_not_a_join_given_the_known_palettes():
    assert _merge_label(gain=False) == frozenset({0, 1, 2})  # the marginal count: a join
    assert _merge_label(gain=True) == frozenset({0, 1})


def test_size_once_drops_the_size_evidence_of_an_occlusion_child_only():
    strokes = [
        make_stroke(0, 0, 10, (0, 0), (10, 0), [0, 1, 2], {0}, size=(20, 50)),
        make_stroke(1, 0, 10, (100, 0), (110, 0), [3, 4, 5], {1}, size=(20, 50)),
        make_stroke(2, 12, 20, (12, 0), (20, 0), [0, 1, 2], {0}, size=(40, 60)),
    ]
    for once in (False, True):
        g = LabelGraph(
            NetworkConfig(labels=LabelParams(max_group_size=3), gate="pixels", size_once=once), fps=25.0
        )
        for s in strokes:
            g.add_stroke(s)
        assert g.structure(2) == "OCCLUSION"
        two = [frozenset({0}), frozenset({0, 1})]  # a person and a pair
        assert np.ptp(g.size_loglik(1, two)) > 0  # a root keeps its size evidence
        assert (np.ptp(g.size_loglik(2, two)) == 0) == once


def test_palette_continued_weighs_the_count_evidence_of_an_occlusion_child_only():
    """``NetworkConfig.palette_continued`` scales the palette count and gain evidence
    where a region continues (an OCCLUSION child) and nowhere else; outside [0, 1] it is
    refused."""
    strokes = [
        make_stroke(0, 0, 10, (0, 0), (10, 0), [0, 1, 2], {0}),
        make_stroke(1, 0, 10, (100, 0), (110, 0), [3, 4, 5], {1}),
        make_stroke(2, 12, 20, (12, 0), (20, 0), [0, 1, 2, 7], {0}),
    ]
    graphs = {}
    for w in (1.0, 0.5, 0.0):
        g = LabelGraph(NetworkConfig(labels=LabelParams(max_group_size=3), gate="pixels", palette_continued=w), fps=25.0)
        for s in strokes:
            g.add_stroke(s)
        graphs[w] = g
    assert graphs[1.0].structure(2) == "OCCLUSION" and graphs[1.0].structure(1) == "ROOT"
    labels = [frozenset({0}), frozenset({0, 1}), frozenset({0, 2})]  # alone, a pair, a join
    full = graphs[1.0].palette_count_loglik(2, labels)
    assert np.ptp(full) > 0
    np.testing.assert_allclose(graphs[0.5].palette_count_loglik(2, labels), 0.5 * full, rtol=1e-12)
    assert np.all(graphs[0.0].palette_count_loglik(2, labels) == 0.0)
    root = [frozenset({1})]  # a root keeps its full weight
    np.testing.assert_array_equal(graphs[0.5].palette_count_loglik(1, root), graphs[1.0].palette_count_loglik(1, root))
    for bad in (-0.1, 1.5, float("nan")):
        with pytest.raises(ModelError, match="palette_continued"):
            NetworkConfig(palette_continued=bad)


def test_the_bin_of_u_is_the_last_edge_at_most_u():
    bins = (0, 1, 6, 8, 10)
    u = np.arange(14)
    want = [max(i for i, edge in enumerate(bins) if edge <= x) for x in u]
    assert palette_gain_bin(bins, u).tolist() == want
    assert int(palette_gain_bin(bins, 7)) == 2
    assert gain_bins_rise(bins) and gain_bins_rise((0,))
    for bad in ((), (1, 2), (0, 3, 3), (0, 5, 2), ((0, 1), (2, 3))):
        assert not gain_bins_rise(bad)
