"""Graph helpers for exact inference: moral graph and greedy elimination orders."""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from itertools import combinations

import networkx as nx

from dbn.bayesnet import BayesNet

__all__ = ["moral_graph", "interaction_graph", "elimination_order"]


def moral_graph(bn: BayesNet) -> nx.Graph:
    """Undirected graph linking every node to its parents and co-parents."""
    g = nx.Graph()
    g.add_nodes_from(bn.nodes)
    for n in bn.nodes:
        parents = bn.parents(n)
        g.add_edges_from((n, p) for p in parents)
        g.add_edges_from(combinations(parents, 2))
    return g


def interaction_graph(scopes: Iterable[Sequence[str]]) -> nx.Graph:
    """Undirected graph with a clique per factor scope."""
    g = nx.Graph()
    for scope in scopes:
        g.add_nodes_from(scope)
        g.add_edges_from(combinations(scope, 2))
    return g


def elimination_order(
    graph: nx.Graph,
    cards: Mapping[str, int],
    nodes: Iterable[str] | None = None,
    heuristic: str = "min_fill",
) -> list[str]:
    """A greedy elimination order of ``nodes`` (default: all) in ``graph``.

    Parameters
    ----------
    heuristic : {"min_fill", "min_weight"}
        ``min_fill``: eliminate the node whose elimination adds the fewest fill-in edges,
        ties broken by the smallest clique weight (product of cardinalities), then by name.
        ``min_weight``: smallest clique weight first, ties by fill-in, then name.

    Notes
    -----
    Greedy and deterministic. A node's score depends only on its neighbourhood, so after
    each elimination only the eliminated node's neighbours and their neighbours are
    re-scored (the fill-in edges join the neighbours); the order is the one a full re-score
    at every step gives. (The structured engine's orders come from
    :func:`inference.exact.triangulation.greedy_order`: float weights, ties by position,
    randomised restarts.)
    """
    if heuristic not in ("min_fill", "min_weight"):
        raise ValueError(f"heuristic must be 'min_fill' or 'min_weight', got {heuristic!r}")
    g = {n: set(graph.neighbors(n)) for n in graph.nodes}
    todo = set(g) if nodes is None else set(nodes)
    order: list[str] = []

    def score(n: str) -> tuple[int, int, str]:
        nb = g[n]
        fill = sum(1 for a, b in combinations(nb, 2) if b not in g[a])
        # exact (Python int): a float sum of logs depends on the order of the set ``nb``,
        # i.e. on string hashing, and turned ties on the weight into hash-order choices
        weight = math.prod(int(cards[m]) for m in (n, *nb))
        return (fill, weight, n) if heuristic == "min_fill" else (weight, fill, n)

    scores = {n: score(n) for n in todo}
    while scores:
        n = min(scores, key=scores.__getitem__)
        nb = g[n]
        for a, b in combinations(nb, 2):
            g[a].add(b)
            g[b].add(a)
        for m in nb:
            g[m].discard(n)
        del g[n], scores[n]
        order.append(n)
        touched = set(nb).union(*(g[m] for m in nb))
        for m in touched & scores.keys():
            scores[m] = score(m)
    return order
