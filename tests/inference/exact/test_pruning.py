"""Query-driven pruning removes what it should and never changes an answer; the
triangulation's bookkeeping matches a plain re-elimination; the fast BIF reader equals
pgmpy's."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dbn import pgmpy_adapter as pa
from dbn.bayesnet import BayesNet
from dbn.cpds import TabularCPD
from dbn.errors import CycleError
from dbn.variables import DiscreteVariable
from inference.exact.enumeration import brute_force_marginals, joint_factor
from inference.exact.factor import Factor, product
from inference.exact.pruning import net_index, requisite
from inference.exact.triangulation import greedy_order, triangulate

TOL = 1e-9


def _net(edges: dict[str, list[str]]) -> BayesNet:
    """Binary net with the given parents and arbitrary positive tables."""
    rng = np.random.default_rng(0)
    cpds = []
    for n, ps in edges.items():
        t = rng.random((*([2] * len(ps)), 2)) + 0.1
        cpds.append(TabularCPD(n, ps, t / t.sum(-1, keepdims=True)))
    return BayesNet([DiscreteVariable(n, 2) for n in edges], cpds)


def _kept(bn: BayesNet, query: list[str], observed: list[str]) -> set[str]:
    net = net_index(bn)
    pr = requisite(net, [net.index[q] for q in query], [net.index[o] for o in observed])
    assert pr.removed == frozenset(range(len(bn))) - set(pr.factors)
    return {net.names[i] for i in pr.factors}


def test_barren_and_d_separated_nodes_are_removed() -> None:
    chain = _net({"a": [], "b": ["a"], "c": ["b"]})
    assert _kept(chain, ["a"], []) == {"a"}  # b, c barren
    assert _kept(chain, ["a"], ["c"]) == {"a", "b", "c"}
    assert _kept(chain, ["a"], ["b"]) == {"a", "b"}  # c barren
    assert _kept(chain, ["c"], ["b"]) == {"c"}  # a and P(b|a) d-separated by b
    vee = _net({"a": [], "b": [], "c": ["a", "b"]})
    assert _kept(vee, ["a"], []) == {"a"}  # marginally independent causes
    assert _kept(vee, ["a"], ["c"]) == {"a", "b", "c"}  # explaining away
    fork = _net({"a": [], "b": ["a"], "c": ["a"], "d": ["c"]})
    assert _kept(fork, ["b"], ["a"]) == {"b"}
    assert _kept(fork, ["b"], ["d"]) == {"a", "b", "c", "d"}
    assert _kept(fork, ["d"], ["c"]) == {"d"}


@settings(max_examples=150, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), ev_seed=st.integers(0, 2**31 - 1))
def test_pruned_factors_give_the_same_posterior(factories, seed: int, ev_seed: int) -> None:
    bn = factories.random_bn(seed)
    hard, _ = factories.random_evidence(ev_seed, bn, p_soft=0.0)
    if not np.isfinite(joint_factor(bn, hard).log_normalizer()):
        return
    expected, _ = brute_force_marginals(bn, hard)
    net = net_index(bn)
    observed = [net.index[n] for n in hard]
    for q in (n for n in bn.nodes if n not in hard):
        pr = requisite(net, [net.index[q]], observed)
        factors = [
            Factor.from_table(
                (*bn.parents(net.names[i]), net.names[i]), bn.table(net.names[i])
            ).reduce(hard)
            for i in pr.factors
        ]
        assert all(f.variables for f in factors)
        assert set(pr.hidden) == {net.index[v] for f in factors for v in f.variables}
        got = product(factors).keep([q]).probabilities()
        np.testing.assert_allclose(got, expected[q], atol=TOL, rtol=0)


def _replay(order, cliques, cards, scopes) -> tuple[float, float]:
    """Total and largest clique table of eliminating ``order`` (plain recomputation)."""
    adj: dict[int, set[int]] = {v: set() for v in range(len(cards))}
    for sc in scopes:
        for v in sc:
            adj[v].update(u for u in sc if u != v)
    total, biggest = 0.0, 0.0
    for v, clique in zip(order, cliques):
        nb = adj.pop(v)
        assert set(clique) == {v} | nb and clique[0] == v
        size = math.prod(int(cards[u]) for u in clique)
        total, biggest = total + size, max(biggest, size)
        for a in nb:
            adj[a] |= nb - {a}
            adj[a].discard(v)
    return total, biggest


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**31 - 1))
def test_triangulation_bookkeeping_and_restarts(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 25))
    cards = rng.integers(1, 6, size=n)
    scopes = [
        tuple(rng.choice(n, size=int(rng.integers(1, min(n, 3) + 1)), replace=False))
        for _ in range(n)
    ]
    scopes = [tuple(int(v) for v in sc) for sc in scopes]
    best = triangulate(scopes, cards, range(n), restarts=3, restart_above=0)
    assert sorted(best.order) == list(range(n))
    total, biggest = _replay(best.order, best.cliques, cards, scopes)
    assert total == pytest.approx(best.total_size) and biggest == pytest.approx(best.max_size)
    adj = {v: set() for v in range(n)}
    for sc in scopes:
        for v in sc:
            adj[v].update(u for u in sc if u != v)
    logk = {v: math.log(int(cards[v])) for v in range(n)}
    for h in ("min_fill", "min_weight"):
        assert best.total_size <= greedy_order(adj, logk, h).total_size * (1 + 1e-12)
    last = greedy_order(adj, logk, "min_fill", last=frozenset({0}))
    assert last.order[-1] == 0


@pytest.mark.parametrize("name", ["asia", "sachs"])
def test_fast_bif_reader_equals_pgmpy(name: str) -> None:
    _same_net(pa.bundled_network(name), pa.example_network(name))


@pytest.mark.slow
@pytest.mark.parametrize("name", pa.bundled_networks())
def test_fast_bif_reader_equals_pgmpy_everywhere(name: str) -> None:
    _same_net(pa.bundled_network(name), pa.example_network(name))


def _same_net(a: BayesNet, b: BayesNet) -> None:
    assert a.nodes == b.nodes
    for n in a.nodes:
        assert a.parents(n) == b.parents(n)
        assert a.variable(n).state_names == b.variable(n).state_names
        # pgmpy parses numbers through pandas, which may differ from float() in the last bit
        np.testing.assert_allclose(a.table(n), b.table(n), atol=1e-15, rtol=0)


def test_bif_with_a_cycle_is_rejected() -> None:
    text = """network x {}
variable a { type discrete [ 2 ] { y, n }; }
variable b { type discrete [ 2 ] { y, n }; }
probability ( a | b ) { (y) 0.5, 0.5; (n) 0.5, 0.5; }
probability ( b | a ) { (y) 0.5, 0.5; (n) 0.5, 0.5; }
"""
    with pytest.raises(CycleError, match="cycle"):
        pa.parse_bif(text)
