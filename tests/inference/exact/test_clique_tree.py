"""The junction tree's clique tree: a maximum spanning tree of the clique graph, checked
against networkx (Kruskal, then breadth first from clique 0), and its running-intersection
property on triangulations of random nets."""

from __future__ import annotations

import networkx as nx
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from dbn.bayesnet import BayesNet
from dbn.cpds import TabularCPD
from dbn.variables import DiscreteVariable
from inference.exact import JunctionTree
from inference.exact.junction_tree import clique_tree_edges


def _networkx_tree(cliques):
    g = nx.Graph()
    g.add_nodes_from(range(len(cliques)))
    for i in range(len(cliques)):
        for j in range(i + 1, len(cliques)):
            g.add_edge(i, j, weight=len(cliques[i] & cliques[j]))
    tree = nx.maximum_spanning_tree(g, weight="weight")
    return list(nx.bfs_edges(tree, 0)) if len(cliques) > 1 else []


@settings(max_examples=80, deadline=None)
@given(st.lists(st.frozensets(st.integers(0, 9), max_size=5), min_size=1, max_size=12))
def test_same_tree_as_networkx_kruskal_and_bfs(cliques):
    assert clique_tree_edges(cliques) == _networkx_tree(cliques)


@settings(max_examples=40, deadline=None)
@given(n=st.integers(2, 12), density=st.floats(0.1, 0.7), seed=st.integers(0, 2**31 - 1))
def test_running_intersection_on_triangulated_graphs(n, density, seed):
    # maximal cliques of a chordal completion (min-degree elimination of a random graph)
    rng = np.random.default_rng(seed)
    g = {v: set() for v in range(n)}
    for a in range(n):
        for b in range(a + 1, n):
            if rng.random() < density:
                g[a].add(b)
                g[b].add(a)
    raw = []
    while g:
        v = min(g, key=lambda u: (len(g[u]), u))
        raw.append(frozenset({v} | g[v]))
        for a in g[v]:
            g[a] |= g[v] - {a}
            g[a].discard(v)
        del g[v]
    cliques = [c for i, c in enumerate(raw) if not any(c < d for d in raw) and c not in raw[:i]]
    edges = clique_tree_edges(cliques)
    assert len(edges) == len(cliques) - 1
    tree = nx.Graph(edges)
    tree.add_nodes_from(range(len(cliques)))
    assert nx.is_tree(tree)
    for v in set().union(*cliques):  # the cliques holding v form a connected subtree
        holding = [i for i, c in enumerate(cliques) if v in c]
        assert nx.is_connected(tree.subgraph(holding))


def _chain():
    rng = np.random.default_rng(0)
    cards = {"a": 2, "b": 3, "c": 4}
    variables = [DiscreteVariable(n, k) for n, k in cards.items()]
    cpds = [
        TabularCPD("a", [], np.full(2, 0.5)),
        TabularCPD("b", ["a"], rng.dirichlet(np.ones(3), size=2)),
        TabularCPD("c", ["b"], rng.dirichlet(np.ones(4), size=3)),
    ]
    return BayesNet(variables, cpds)


def test_the_tree_without_evidence_is_compiled_only_when_asked_for():
    jt = JunctionTree(_chain())
    cal = jt.calibrate({"b": 1})
    assert list(jt._cache) == [frozenset({"b"})]  # only the tree with b indexed away
    assert max(t.size for t in cal.clique_tables) == 4
    assert jt.max_clique_size == 12  # {b, c}: 3 x 4 entries
    assert sorted(map(sorted, jt.cliques)) == [["a", "b"], ["b", "c"]]
