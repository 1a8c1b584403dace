"""Greedy elimination orders: ties on the clique weight are exact and broken by name, so
the order does not depend on how a set of node names happens to iterate (string hashing)."""

from __future__ import annotations

import networkx as nx
import pytest

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
