"""Greedy elimination orders: ties on the clique weight are exact and broken by name, so
the order does not depend on how a set of node names happens to iterate (string hashing)."""

from __future__ import annotations

import math
from itertools import combinations

import networkx as nx
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from inference.exact.graph import elimination_order


@pytest.mark.parametrize("heuristic", ["min_fill", "min_weight"])
def test_equal_clique_weights_tie_by_name(heuristic):
    # every node's elimination clique has 48 entries and no fill-in: a (2) - w (24); b (2) in
    # the clique {b, x (2), y (3), z (4)}. A float sum of logs makes b's 2 * 2 * 3 * 4
    # smaller than a's 2 * 24 in every summation order, and b went first
    g = nx.Graph([("a", "w"), ("b", "x"), ("b", "y"), ("b", "z"), ("x", "y"), ("x", "z"), ("y", "z")])
    cards = {"a": 2, "w": 24, "b": 2, "x": 2, "y": 3, "z": 4}
    order = elimination_order(g, cards, heuristic=heuristic)
    assert order[0] == "a"
    assert sorted(order) == sorted(cards)


def test_smaller_clique_goes_first_without_fill():
    g = nx.Graph([("a", "b"), ("c", "d")])
    assert elimination_order(g, {"a": 3, "b": 3, "c": 2, "d": 3})[0] == "c"


def _full_rescore_order(graph: nx.Graph, cards, nodes, heuristic):
    """Oracle: the greedy order re-scoring every remaining node at every step."""
    g = {n: set(graph.neighbors(n)) for n in graph.nodes}
    todo, order = set(nodes), []

    def score(n):
        fill = sum(1 for a, b in combinations(g[n], 2) if b not in g[a])
        weight = math.prod(cards[m] for m in (n, *g[n]))
        return (fill, weight, n) if heuristic == "min_fill" else (weight, fill, n)

    while todo:
        n = min(todo, key=score)
        for a, b in combinations(g[n], 2):
            g[a].add(b)
            g[b].add(a)
        for m in g.pop(n):
            g[m].discard(n)
        todo.discard(n)
        order.append(n)
    return order


@settings(max_examples=60, deadline=None)
@given(
    n=st.integers(1, 14),
    density=st.floats(0.0, 0.6),
    seed=st.integers(0, 2**31 - 1),
    heuristic=st.sampled_from(["min_fill", "min_weight"]),
    subset=st.booleans(),
)
def test_incremental_rescoring_gives_the_full_rescore_order(n, density, seed, heuristic, subset):
    rng = np.random.default_rng(seed)
    graph = nx.gnp_random_graph(n, density, seed=int(seed))
    graph = nx.relabel_nodes(graph, {i: f"v{i}" for i in graph.nodes})
    cards = {v: int(rng.integers(1, 5)) for v in graph.nodes}
    nodes = [v for v in graph.nodes if not subset or rng.random() < 0.6]
    assert elimination_order(graph, cards, nodes, heuristic) == _full_rescore_order(graph, cards, nodes, heuristic)
