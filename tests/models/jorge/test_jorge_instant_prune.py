"""The instant (eq. 12) domain cap does not drop a label only because it clashes with a
sibling's instant label (issue 16): that label is a point guess the next inference may
revise (the two parts of a split swapped for good once joins widened the domains past
the cap)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from models.jorge.labels import LabelParams
from models.jorge.network import NetworkConfig
from models.jorge.online import OnlineConfig, OnlineLabeller
from models.jorge.strokes import make_stroke

STROKES = [
    make_stroke(0, 0, 10, (0, 0), (10, 0), [0, 1, 2, 3, 4], {0}),
    make_stroke(1, 0, 10, (40, 0), (30, 0), [5, 6, 7, 8, 9], {1}),
    make_stroke(2, 12, 20, (20, 0), (20, 0), [0, 1, 5, 6, 7], {0, 1}),
    make_stroke(3, 22, 30, (15, 0), (5, 0), [0, 1, 5, 6, 10], {1}),
]


def test_the_cap_ranks_labels_without_the_sibling_clash():
    labels = LabelParams(max_group_size=3, p_join=0.1, p_part=0.3)
    net = NetworkConfig(labels=labels, gate="pixels", size_evidence=False, palette_count_table=(),
                        palette_gain_table=(), palette_missing_table=())
    lab = OnlineLabeller(OnlineConfig(network=net, period_s=100.0, reid_prior=0.0), fps=25.0)
    for s in STROKES:
        lab.add_stroke(s)
    dom = lab.graph.nodes[3].domain
    assert len(dom) > 4
    lab.config = replace(lab.config, max_labels=3)
    with_clash = np.full(len(dom), 1e-3)
    with_clash[1], with_clash[2] = 0.9, 0.0  # label 2 excluded by a sibling's instant label
    without = with_clash.copy()
    without[2] = 0.95  # ... which the colours favour
    lab._posterior = lambda k, score, siblings: (
        (with_clash if siblings else without) / ((with_clash if siblings else without).sum())
    )
    lab._relabel(3)
    kept = lab.graph.nodes[3].domain
    assert len(kept) < len(dom) and dom[2] in kept and dom[1] in kept and dom[0] in kept
    assert lab.labels[3] == dom[1]  # the label is still the eq. 12 MAP with the clash
