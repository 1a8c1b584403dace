"""What a node remembers (:mod:`models.jorge.memo`) gives the numbers computing afresh gives,
bit for bit (issue 16, eighteenth round: speed without changing a label). Oracles:
``np.quantile``, :func:`~models.jorge.labels.child_table` on the smaller domains, the
evidence computed afresh, and the whole labelling with every memo switched off."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from models.jorge.labels import admissible_labels, child_table
from models.jorge.meeting import simulate_meeting
from models.jorge.memo import ChainMemo, EvidenceMemo, TableMemo
from models.jorge.network import LabelGraph, NetworkConfig, _linear_quantile
from models.jorge.online import OnlineConfig, OnlineLabeller, label_online
from models.jorge.strokes import build_strokes
from tests.models.jorge.test_jorge_truncate import _params, domain_strategy

F = frozenset


@settings(max_examples=200, deadline=None)
@given(values=st.lists(st.floats(-50, 50, allow_nan=False), min_size=1, max_size=40),
       q=st.one_of(st.sampled_from([0.0, 0.25, 0.5, 0.75, 1.0]), st.floats(0.0, 1.0)))
def test_linear_quantile_is_numpys_bit_for_bit(values, q):
    x = np.array(values)
    assert _linear_quantile(x, q) == float(np.quantile(x, q))


@settings(max_examples=80, deadline=None)
@given(doms=st.lists(domain_strategy, min_size=1, max_size=2), shared=st.lists(st.booleans(), min_size=2, max_size=2),
       p_new=st.floats(0.01, 0.4), p_merge=st.floats(0.0, 0.5), gmax=st.integers(3, 5),
       p_join=st.sampled_from([0.0, 0.1]), roots_only=st.booleans(), keep=st.randoms(use_true_random=False))
def test_a_truncated_table_of_smaller_domains_is_read_off_the_memo(doms, shared, p_new, p_merge, gmax, p_join,
                                                                    roots_only, keep):
    params = _params(p_new, p_merge, gmax, p_join, roots_only)
    flags, new = shared[: len(doms)], F({99})
    full = admissible_labels(doms, flags, new, gmax, partial=True, max_new=1 if roots_only else 3, join=p_join > 0)
    memo = TableMemo.of("cfg", flags, doms, full, child_table(doms, flags, full, new, params, truncate=True), False)
    # pruned and reordered domains (a parent keeps one label at least, the child its new label)
    sub_doms = [keep.sample(d, keep.randint(1, len(d))) for d in doms]
    sub = [new] + keep.sample([lab for lab in full if lab != new], keep.randint(0, len(full) - 1))
    got = memo.select("cfg", flags, sub_doms, sub)
    assert np.array_equal(got, child_table(sub_doms, flags, sub, new, params, truncate=True))
    # a label it does not hold, another config or other sharing: computed afresh instead
    assert memo.select("cfg", flags, sub_doms, [*sub, F({98})]) is None
    assert memo.select("other", flags, sub_doms, sub) is None
    assert memo.select("cfg", [not f for f in flags], sub_doms, sub) is None


def test_a_renormalised_table_is_read_off_only_for_the_same_domains():
    doms, flags, new = [[F({0}), F({1}), F({0, 1})]], [True], F({9})
    params = _params(0.1, 0.2, 3, 0.1, False)
    full = admissible_labels(doms, flags, new, 3, partial=True, max_new=3, join=True)
    table = child_table(doms, flags, full, new, params)
    memo = TableMemo.of("cfg", flags, doms, full, table, exact=True)
    assert np.array_equal(memo.select("cfg", flags, doms, full), table)
    assert memo.select("cfg", flags, doms, full[:-1]) is None  # the rows would renormalise
    assert memo.select("cfg", flags, doms, full[::-1]) is None


def _labelled_graph(k: int = 4, seed: int = 0) -> tuple[LabelGraph, list]:
    strokes = build_strokes([seed, 0], simulate_meeting(0, k))
    lab = OnlineLabeller(OnlineConfig(), strokes.fps)
    for s in strokes:
        lab.add_stroke(s)
    return lab.graph, strokes


def _afresh(g: LabelGraph, k: int, domain) -> tuple[np.ndarray, np.ndarray]:
    return g.colour_loglik(k, domain), g.palette_count_loglik(k, domain)


def test_evidence_of_a_smaller_domain_is_read_off_the_memo_while_the_records_hold():
    g, _ = _labelled_graph()
    rng = np.random.default_rng(0)
    checked = 0
    for k, node in enumerate(g.nodes):
        if node.frozen is not None or len(node.domain) < 3:
            continue
        dom = tuple(node.domain)
        g._colour_and_palette_loglik(k, dom)  # remembered
        sub = tuple(dom[i] for i in rng.permutation(len(dom))[: len(dom) - 1])
        memo = g._evidence_memo[k]
        records = g._palette_records(dom)
        hit = memo.select(g.config, g.structure(k), records, sub)
        assert hit is not None
        for a, b in zip(hit, _afresh(g, k, sub)):
            assert np.array_equal(a, b)
        # another palette record for one of the objects: not read off
        o = next(iter(sub[0]))
        changed = {**records, o: (k, None) if records[o][0] is None else (None, None)}
        assert memo.select(g.config, g.structure(k), changed, sub) is None
        assert memo.select(g.config, "OTHER", records, sub) is None
        checked += 1
    assert checked >= 3


def test_evidence_after_a_new_own_palette_is_computed_afresh():
    g, _ = _labelled_graph()
    k = next(k for k, nd in enumerate(g.nodes) if nd.frozen is None and any(len(lab) == 1 for lab in nd.domain)
             and nd.parents)
    dom = tuple(g.nodes[k].domain)
    before = g._colour_and_palette_loglik(k, dom)
    (o,) = next(lab for lab in dom if len(lab) == 1 and next(iter(lab)) != k)
    g._own[o] = g.nodes[k].parents[0]  # as freezing a stroke to ``o`` alone would record
    after = g._colour_and_palette_loglik(k, dom)
    for a, b in zip(after, _afresh(g, k, dom)):
        assert np.array_equal(a, b)
    assert isinstance(g._evidence_memo[k], EvidenceMemo)
    assert before[0] is not after[0]


@pytest.mark.parametrize("k, seed", [(3, 1), (5, 2)])
def test_labelling_is_the_same_with_every_memo_switched_off(monkeypatch, k, seed):
    strokes = build_strokes([seed, 1], simulate_meeting(1, k))
    cfg = OnlineConfig(network=NetworkConfig())
    on = label_online(strokes, cfg)
    monkeypatch.setattr(TableMemo, "select", lambda *a, **kw: None)
    monkeypatch.setattr(EvidenceMemo, "select", lambda *a, **kw: None)
    monkeypatch.setattr(ChainMemo, "select", lambda *a, **kw: (False, None))
    off = label_online(strokes, cfg)
    assert on.labels == off.labels and on.instant == off.instant and on.network_labels == off.network_labels
    assert [r.log_prob for r in on.records] == [r.log_prob for r in off.records]
    for node in on.labeller.beliefs:
        assert np.array_equal(on.labeller.beliefs[node], off.labeller.beliefs[node])

