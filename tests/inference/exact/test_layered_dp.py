"""The layered-graph DP against brute-force enumeration of every allowed path."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dbn.errors import InputError, NonFiniteError, ShapeError
from inference.exact.layered_dp import layered_shortest_path


def brute_force(node_costs, edge_costs):
    """Cheapest allowed path by enumerating every choice (semantics of the module doc).

    A step between consecutive non-empty layers is allowed when it is an edge (layers
    adjacent, finite cost) or when the new layer is disconnected: no allowed prefix
    ending in the previous non-empty layer has an edge into it.
    """
    T = len(node_costs)
    nonempty = [t for t in range(T) if len(node_costs[t])]
    if not nonempty:
        return np.inf, None
    # prefixes: dict node -> list of (cost, path) ; enumerate all of them explicitly
    prefixes = [
        (float(node_costs[nonempty[0]][j]), (j,)) for j in range(len(node_costs[nonempty[0]]))
    ]
    prev = nonempty[0]
    for t in nonempty[1:]:
        adjacent = t == prev + 1
        connected = adjacent and any(
            np.isfinite(edge_costs[prev][p[-1], j])
            for _, p in prefixes
            for j in range(len(node_costs[t]))
        )
        new = []
        for cost, p in prefixes:
            for j in range(len(node_costs[t])):
                if connected:
                    e = edge_costs[prev][p[-1], j]
                    if not np.isfinite(e):
                        continue
                    new.append((cost + e + node_costs[t][j], p + (j,)))
                else:
                    new.append((cost + node_costs[t][j], p + (j,)))
        prefixes = new
        prev = t
    best = min(prefixes, key=lambda cp: cp[0])
    return best[0], best[1]


def path_cost(node_costs, edge_costs, path):
    """Cost of a DP path, with jumps free (its allowedness is checked by the oracle's cost)."""
    total, prev = 0.0, None
    for t, j in enumerate(path):
        if j < 0:
            continue
        total += node_costs[t][j]
        if prev is not None and prev[0] == t - 1 and np.isfinite(edge_costs[t - 1][prev[1], j]):
            total += edge_costs[t - 1][prev[1], j]
        prev = (t, j)
    return total


@st.composite
def layered_graphs(draw):
    T = draw(st.integers(1, 5))
    sizes = [draw(st.integers(0, 3)) for _ in range(T)]
    rng = np.random.default_rng(draw(st.integers(0, 2**31 - 1)))
    p_edge = draw(st.sampled_from([0.2, 0.5, 0.9]))
    nodes = [rng.integers(1, 8, size=k).astype(float) for k in sizes]
    edges = []
    for t in range(T - 1):
        e = rng.integers(0, 3, size=(sizes[t], sizes[t + 1])).astype(float)
        e[rng.random(e.shape) > p_edge] = np.inf
        edges.append(e)
    return nodes, edges


@settings(max_examples=300, deadline=None)
@given(layered_graphs())
def test_dp_matches_brute_force(graph):
    nodes, edges = graph
    res = layered_shortest_path(nodes, edges)
    want, want_path = brute_force(nodes, edges)
    if want_path is None:
        assert np.all(res.path == -1) and res.cost == np.inf
        return
    assert res.cost == pytest.approx(want)
    # the returned path picks a node exactly in the non-empty layers and costs what it says
    for t, j in enumerate(res.path):
        assert (j >= 0) == (len(nodes[t]) > 0)
    assert path_cost(nodes, edges, res.path) == pytest.approx(res.cost)
    # every step into a layer that was not entered by a jump is a legal edge
    for t in range(1, len(nodes)):
        if res.path[t] >= 0 and not res.jumped[t] and res.path[t - 1] >= 0:
            assert np.isfinite(edges[t - 1][res.path[t - 1], res.path[t]])


def test_disconnection_restarts_from_best_and_picks_highest_priority():
    nodes = [np.array([1.0, 2.0]), np.array([3.0, 1.0, 2.0])]
    edges = [np.full((2, 3), np.inf)]
    res = layered_shortest_path(nodes, edges)
    assert res.jumped.tolist() == [False, True]
    assert res.path.tolist() == [0, 1]
    assert res.cost == pytest.approx(2.0)


def test_legality_beats_priority():
    # the cheap node of layer 1 is unreachable; the path must take the legal one
    nodes = [np.array([0.0]), np.array([1.0, 5.0]), np.array([1.0])]
    edges = [np.array([[np.inf, 0.0]]), np.array([[0.0], [0.0]])]
    res = layered_shortest_path(nodes, edges)
    assert res.path.tolist() == [0, 1, 0]
    assert not res.jumped.any()


def test_bad_input():
    with pytest.raises(ShapeError):
        layered_shortest_path([np.zeros(2), np.zeros(2)], [np.zeros((2, 3))])
    with pytest.raises(ShapeError):
        layered_shortest_path([np.zeros(2), np.zeros(2)], [])
    with pytest.raises(NonFiniteError):
        layered_shortest_path([np.array([np.nan])], [])
    with pytest.raises(NonFiniteError):
        layered_shortest_path([np.zeros(1), np.zeros(1)], [np.array([[-np.inf]])])


@pytest.mark.parametrize(("nodes", "edges", "needle"), [
    ([["a"]], [], "node_costs[0] is not an array of numbers"),
    ([np.array([1.0 + 1j])], [], "node_costs[0] holds complex numbers"),
    ([[1.0], [1.0]], [[["x"]]], "edge_costs[0] is not an array of numbers"),
    ([[1.0], [1.0]], [np.array([[1j]])], "edge_costs[0] holds complex numbers"),
    (5, [], "node_costs must be a sequence of arrays, one per layer, got int"),
    ([[1.0]], None, "edge_costs must be a sequence of arrays, one per pair of layers"),
])  # fmt: skip
def test_costs_that_are_not_real_numbers_are_refused_naming_the_layer(nodes, edges, needle):
    """Strings raised numpy's ValueError, a non-sequence Python's TypeError, and complex
    costs lost their imaginary parts (a ComplexWarning)."""
    with pytest.raises(InputError) as exc:
        layered_shortest_path(nodes, edges)
    assert needle in str(exc.value)


def test_layers_may_come_as_the_rows_of_an_array():
    """Equal-size layers stacked in one array are still a sequence of layers."""
    res = layered_shortest_path(np.array([[1.0, 0.0], [0.0, 2.0]]), np.zeros((1, 2, 2)))
    assert res.path.tolist() == [1, 0] and res.cost == 0.0
