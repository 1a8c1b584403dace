"""A continuation or merge node gets back the label its parents' new labels pass on
(``OnlineConfig.restore_successors``; issue 16, twenty-first round): its domain was capped
when its stroke started, on its parents' instant beliefs, and the window that relabels the
parents could otherwise only give it a new object."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from dbn.errors import InputError
from models.jorge.labels import LabelParams
from models.jorge.meeting import simulate_meeting
from models.jorge.network import FITTED_LABELS, NetworkConfig
from models.jorge.online import OnlineConfig, OnlineLabeller, label_online
from models.jorge.strokes import build_strokes, make_stroke

A, B = frozenset({0}), frozenset({1})
STROKES = [
    make_stroke(0, 0, 10, (0, 0), (10, 0), [0, 1, 2, 3, 4], {0}),
    make_stroke(1, 0, 10, (40, 0), (30, 0), [5, 6, 7, 8, 9], {1}),
    make_stroke(2, 12, 20, (20, 0), (20, 0), [0, 1, 5, 6, 7], {0, 1}),  # merge of 0 and 1
    make_stroke(3, 22, 30, (20, 0), (22, 0), [0, 2, 5, 6, 8], {0, 1}),  # the group goes on
]


def _labeller() -> OnlineLabeller:
    net = NetworkConfig(labels=LabelParams(max_group_size=3), gate="pixels", size_evidence=False,
                        palette_count_table=(), palette_gain_table=(), palette_missing_table=())
    cfg = OnlineConfig(network=net, period_s=100.0, reid_prior=0.0, restore_successors=True)
    lab = OnlineLabeller(cfg, fps=25.0)
    for s in STROKES:
        lab.add_stroke(s)
    assert lab.graph.structure(2) == "MERGE" and lab.graph.structure(3) == "OCCLUSION"
    return lab


def _stale(lab: OnlineLabeller, k: int, keep: list) -> None:
    """Cap node ``k``'s domain to ``keep`` as if its parents had looked different."""
    lab.graph.set_domain(k, keep)
    dom = lab.graph.nodes[k].domain
    lab.beliefs[k] = np.full(len(dom), 1.0 / len(dom))
    lab.labels[k] = frozenset({k})


def test_a_merge_and_its_continuation_get_the_union_back_and_the_window_takes_it():
    lab = _labeller()
    assert lab.labels[0] == A and lab.labels[1] == B and lab.labels[2] == A | B
    _stale(lab, 2, [frozenset({2}), A])
    _stale(lab, 3, [frozenset({3}), frozenset({2}), A])
    assert lab.restore_successors(range(4)) == [2, 3]  # 3 gets it from 2, down the chain
    for k in (2, 3):
        dom = lab.graph.nodes[k].domain
        assert dom[-1] == A | B and lab.beliefs[k][-1] == 0.0
        assert lab.beliefs[k].shape == (len(dom),) and lab.beliefs[k].sum() == pytest.approx(1.0)
    assert lab.restore_successors(range(4)) == []  # nothing left to give back
    lab.infer(31)
    assert lab.labels[2] == lab.labels[3] == A | B


def test_without_it_the_stale_domain_leaves_only_a_new_object():
    lab = _labeller()
    lab.config = replace(lab.config, restore_successors=False)
    _stale(lab, 2, [frozenset({2}), A])
    _stale(lab, 3, [frozenset({3}), frozenset({2}), A])
    lab.infer(31)
    assert lab.labels[2] != A | B


def test_at_the_cap_the_lowest_belief_label_makes_room_never_the_current_one():
    lab = _labeller()
    lab.config = replace(lab.config, max_labels=3)
    _stale(lab, 2, [frozenset({2}), A, B])
    lab.labels[2] = A
    lab.beliefs[2] = np.array([0.5, 0.1, 0.4])  # the current label A has the lowest belief
    assert lab.restore_successors([2]) == [2]
    dom = lab.graph.nodes[2].domain
    assert dom == (frozenset({2}), A, A | B)  # B (belief 0.4) made room, not A
    np.testing.assert_allclose(lab.beliefs[2], [0.5 / 0.6, 0.1 / 0.6, 0.0])


def test_with_no_room_at_the_cap_nothing_is_given_back():
    lab = _labeller()
    lab.config = replace(lab.config, max_labels=2)
    _stale(lab, 2, [frozenset({2}), A])
    lab.labels[2] = A
    assert lab.restore_successors([2]) == []
    assert lab.graph.nodes[2].domain == (frozenset({2}), A) and lab.beliefs[2].shape == (2,)


def test_widen_adds_only_admissible_new_labels_and_refuses_a_frozen_node():
    lab = _labeller()
    g = lab.graph
    _stale(lab, 2, [frozenset({2})])
    assert g.widen(2, [A | B, A | B, frozenset({7})]) == [A | B]  # {7}: no such object
    assert g.widen(2, [A | B]) == []
    g.freeze(0, A)
    with pytest.raises(InputError, match="frozen"):
        g.widen(0, [B])


@pytest.mark.parametrize("scene, merge, later", [(401, 64, 65), (403, 35, 37)])
def test_a_simulated_meeting_of_four_keeps_its_group_through_a_short_split(scene, merge, later):
    """SIMULATED meetings of four (training side): the group splits for a few frames and
    merges again (stroke ``merge``, its parents the two pieces); the stroke ``later``
    continues it. The pieces' instant labels were wrong, the window corrected them, and
    without the restored union the merge became a new person, the group's identity lost
    for the rest of the scene. In scene 403 the group's next stroke starts before the
    following inference: the union is chosen only because the window runs again at once.
    Under seed 004's eq. 5 (``split_cover`` off, the default when the fault was found): the
    default split cover, which came later, also finds scene 403's union without the
    restore; and without the clash-free rank of the cap (``clash_free_rank`` off, the default
    until issue 16's thirtieth round): with it, the pieces' children keep the union in their
    capped domains, and both scenes keep it without the restore; and without the
    missing-colour evidence (``palette_missing_table`` empty, the default until the
    thirty-fourth round), with which both merges keep the union without the restore."""
    strokes = build_strokes(scene, simulate_meeting(scene, 4))
    network = NetworkConfig(labels=replace(FITTED_LABELS, split_cover=()), palette_missing_table=())
    for restore in (False, True):
        cfg = OnlineConfig(network=network, restore_successors=restore, clash_free_rank=False)
        res = label_online(strokes, cfg)
        a, b = res.labeller.graph.nodes[merge].parents
        assert len(strokes[merge].truth) == 4 and strokes[merge].truth == strokes[a].truth | strokes[b].truth
        union = res.network_labels[a] | res.network_labels[b]
        assert len(union) == 4
        assert (res.network_labels[merge] == union) is restore
        assert (res.network_labels[later] == union) is restore
