"""Shortest path through a layered graph by dynamic programming (a Viterbi over short
candidate lists), with a restart rule for disconnected layers.

The graph has layers ``t = 0 .. T - 1`` of ``k_t >= 0`` nodes each; node ``j`` of layer
``t`` costs ``node_costs[t][j]`` and the edge ``i -> j`` from layer ``t`` to ``t + 1``
costs ``edge_costs[t][i, j]`` (``+inf``: no edge). A path picks one node in every
non-empty layer and its cost is the sum of its node and edge costs. This is the second
phase of seed 001 (sec. 4.2, fig. 1): "the optimal path is computed using an online
shortest path algorithm in a layered graph", with node costs the priorities of the
states.

Disconnection (seed 001, sec. 4.2: "two layers might be disconnected due to errors. In
this case, the highest prioritized node from the next level is chosen")
    When no node of a layer can be reached by an edge from a reachable node of the
    previous non-empty layer (or a layer follows an empty one), every node of the layer
    is entered by a zero-cost *jump* from the best node reached so far. Among the paths
    through the jump the cheapest picks the cheapest (highest-priority) node of the new
    layer unless later layers make another node better. Formally, the allowed paths are
    those whose every step is an edge, or a jump into a disconnected layer; a layer is
    disconnected when no allowed prefix ending in the previous non-empty layer has an
    edge into it. :func:`layered_shortest_path` returns the cheapest allowed path.

Cost: ``O(sum_t k_t k_{t+1})``, a few vectorised numpy operations per layer.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

from dbn.checks import real_array
from dbn.errors import InputError, NonFiniteError, ShapeError

__all__ = ["LayeredPath", "layered_shortest_path"]


class LayeredPath(NamedTuple):
    """Result of :func:`layered_shortest_path`.

    Attributes
    ----------
    path : (num_layers,) int64 node index chosen in every layer, -1 for empty layers.
    cost : float, the path's total cost (``inf`` only when every layer is empty).
    jumped : (num_layers,) bool, True for layers entered through a disconnection jump.
    """

    path: np.ndarray
    cost: float
    jumped: np.ndarray


def _check(node_costs: Sequence[np.ndarray], edge_costs: Sequence[np.ndarray]) -> tuple[list, list]:
    for name, seq in (("node_costs", node_costs), ("edge_costs", edge_costs)):
        layers = isinstance(seq, Sequence) or (isinstance(seq, np.ndarray) and seq.ndim > 0)
        if isinstance(seq, str) or not layers:
            raise InputError(f"{name} must be a sequence of arrays, one per "
                             f"{'layer' if name == 'node_costs' else 'pair of layers'}, got "
                             f"{type(seq).__name__}")  # fmt: skip
    nodes = [real_array(f"node_costs[{t}]", c) for t, c in enumerate(node_costs)]
    if len(edge_costs) != max(len(nodes) - 1, 0):
        raise ShapeError(
            f"edge_costs must hold num_layers - 1 = {max(len(nodes) - 1, 0)} matrices, got {len(edge_costs)}"
        )
    edges = []
    for t, c in enumerate(nodes):
        if c.ndim != 1:
            raise ShapeError(f"node_costs[{t}] must be 1-D, got shape {c.shape}")
        if not np.all(np.isfinite(c)):
            raise NonFiniteError(f"node_costs[{t}] holds non-finite values: {c!r}")
    for t, e in enumerate(edge_costs):
        e = real_array(f"edge_costs[{t}]", e)
        want = (nodes[t].size, nodes[t + 1].size)
        if e.shape != want:
            raise ShapeError(f"edge_costs[{t}] must have shape {want}, got {e.shape}")
        if np.any(np.isnan(e)) or np.any(e == -np.inf):
            raise NonFiniteError(f"edge_costs[{t}] holds NaN or -inf")
        edges.append(e)
    return nodes, edges


def layered_shortest_path(
    node_costs: Sequence[np.ndarray], edge_costs: Sequence[np.ndarray]
) -> LayeredPath:
    """Cheapest path through a layered graph, restarting on disconnection (module docstring).

    Parameters
    ----------
    node_costs : sequence of num_layers arrays, layer ``t`` of shape ``(k_t,)``, finite.
    edge_costs : sequence of num_layers - 1 arrays, ``(k_t, k_{t+1})``; ``+inf`` = no edge.

    Returns
    -------
    LayeredPath. Ties are broken towards the lower node index.

    Notes
    -----
    The recursion (seed 001, sec. 4.2) is
    ``D_{t+1}[j] = c_{t+1}[j] + min_i (D_t[i] + e_t[i, j])``, and, when every
    ``D_{t+1}`` is infinite (disconnection), ``D_{t+1}[j] = c_{t+1}[j] + min_i D_t[i]``.
    """
    nodes, edges = _check(node_costs, edge_costs)
    T = len(nodes)
    back: list[np.ndarray | None] = [None] * T
    back_layer = np.full(T, -1, dtype=np.int64)  # the layer each layer's back pointers refer to
    jumped = np.zeros(T, dtype=bool)
    prev_t = -1
    prev_d: np.ndarray | None = None
    for t in range(T):
        c = nodes[t]
        if c.size == 0:
            continue
        if prev_d is None:
            d = c.copy()
        else:
            if prev_t == t - 1:
                tot = prev_d[:, None] + edges[t - 1]
                arg = np.argmin(tot, axis=0)
                best = tot[arg, np.arange(c.size)]
            else:
                best = np.full(c.size, np.inf)
                arg = np.zeros(c.size, dtype=np.int64)
            if np.all(np.isinf(best)):  # disconnected: jump from the best node so far
                i = int(np.argmin(prev_d))
                best = np.full(c.size, prev_d[i])
                arg = np.full(c.size, i, dtype=np.int64)
                jumped[t] = True
            d = c + best
            back[t] = arg
            back_layer[t] = prev_t
        prev_t, prev_d = t, d
    path = np.full(T, -1, dtype=np.int64)
    if prev_d is None:
        return LayeredPath(path, float("inf"), jumped)
    j = int(np.argmin(prev_d))
    cost = float(prev_d[j])
    t = prev_t
    while t >= 0:
        path[t] = j
        if back[t] is None:
            break
        j = int(back[t][j])
        t = int(back_layer[t])
    return LayeredPath(path, cost, jumped)
