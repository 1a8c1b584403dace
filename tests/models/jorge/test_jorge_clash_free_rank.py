"""``OnlineConfig.clash_free_rank`` (issue 16, thirtieth round): a new node's domain is capped
on a posterior that leaves out the siblings' instant clash up its chain, so a label that a
parent's sibling excludes for the moment (belief 0) is not the first the cap drops from the
parent's children, for good. The eq. 12 labels themselves do not change."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from models.jorge.labels import LabelParams
from models.jorge.network import NetworkConfig
from models.jorge.online import OnlineConfig, OnlineLabeller
from models.jorge.strokes import make_stroke

A, B = [0, 1, 2, 3, 4], [5, 6, 7, 8, 9]
# person 0 (palette A) and person 1 (palette B) merge and split; both parts look like B,
# the first part takes {1}, so the second part's {1} clashes with it (belief 0); the
# second part's continuation shows B's palette exactly
STROKES = [
    (make_stroke(0, 0, 10, (0, 0), (10, 0), A, {0}), None),
    (make_stroke(1, 0, 10, (40, 0), (30, 0), B, {1}), None),
    (make_stroke(2, 12, 20, (20, 0), (20, 0), [0, 1, 5, 6, 7], {0, 1}), [0, 1]),
    (make_stroke(3, 22, 30, (25, 0), (35, 0), [5, 6, 7, 8, 10], {1}), [2]),
    (make_stroke(4, 22, 30, (15, 0), (5, 0), [5, 6, 7, 11, 10], {0}), [2]),
    (make_stroke(5, 32, 40, (5, 0), (0, 0), B, {0}), [4]),
]
ONE = frozenset({1})


def _labeller(clash_free_rank: bool) -> OnlineLabeller:
    labels = LabelParams(max_group_size=3, p_join=0.1, p_part=0.3)
    net = NetworkConfig(labels=labels, gate="pixels", size_evidence=False, palette_count_table=(),
                        palette_gain_table=(), palette_missing_table=())
    cfg = OnlineConfig(network=net, period_s=100.0, reid_prior=0.0, clash_free_rank=clash_free_rank)
    lab = OnlineLabeller(cfg, fps=25.0)
    for s, parents in STROKES[:5]:
        lab.add_stroke(s, parents)
    return lab


def _cap_and_add_last(lab: OnlineLabeller) -> list:
    lab.config = replace(lab.config, max_labels=3)
    lab.add_stroke(*STROKES[5])
    return lab.graph.nodes[5].domain


def test_free_belief_keeps_what_the_sibling_clash_excludes():
    lab = _labeller(True)
    assert lab.labels[3] == ONE
    i = lab.graph.nodes[4].domain.index(ONE)
    assert lab.beliefs[4][i] == 0.0  # eq. 12: {1} clashes with the sibling's instant label
    free = lab.free_beliefs[4]
    assert free.shape == lab.beliefs[4].shape and np.isclose(free.sum(), 1.0)
    assert free[i] == free.max()  # without the clash the colours favour it
    assert 3 not in lab.free_beliefs  # no labelled sibling when it was added: the same belief


def test_the_cap_keeps_a_label_excluded_only_by_a_parents_sibling():
    off, on = _labeller(False), _labeller(True)
    assert off.free_beliefs == {}
    assert ONE not in _cap_and_add_last(off)  # ranked on the parent's belief 0: dropped
    kept = _cap_and_add_last(on)
    assert len(kept) == 3 and ONE in kept
    assert on.labels == off.labels  # the eq. 12 labels are the same; the window decides


def test_an_inference_drops_the_free_beliefs():
    lab = _labeller(True)
    assert lab.free_beliefs
    lab.infer(31)
    assert lab.free_beliefs == {}
