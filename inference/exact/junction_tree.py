"""Junction-tree calibration: every single-node marginal in one pass.

Build once per net (:class:`JunctionTree`), calibrate per evidence set
(:meth:`JunctionTree.calibrate`). The tree is compiled for the set of hard-evidence
*variables* (observed nodes are indexed away before triangulating, so evidence shrinks the
cliques) and cached: calibrating again with the same variables observed, whatever their
values, reuses it.

Message passing is Hugin's collect/distribute schedule on a tree of the maximal cliques of
a min-fill triangulation, ``2 (num_cliques - 1)`` messages in all. Tables are kept in
linear space *scaled to a maximum of 1*, with the log scales summed separately: a log-space
computation in effect (nothing underflows however long the chain of messages), at the
cost of plain sums and products instead of logsumexp.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import networkx as nx
import numpy as np
from numpy.typing import ArrayLike

from dbn.bayesnet import BayesNet, check_discrete_net, check_evidence
from dbn.errors import EvidenceError
from inference.exact.factor import Factor
from inference.exact.graph import elimination_order, interaction_graph

__all__ = ["JunctionTree", "Calibration", "marginals", "clique_tree_edges"]


@dataclass(frozen=True)
class Calibration:
    """Result of one calibration.

    Attributes
    ----------
    marginals : dict name -> ndarray (cardinality,)
        ``P(X_v | e)`` for every node (a point mass for hard-evidence nodes).
    log_evidence : float
        ``log P(e)`` with soft-evidence likelihoods multiplied in.
    cliques : tuple of tuple of str
        Variables of every clique of the tree used (observed variables excluded).
    clique_tables : tuple of ndarray
        Normalised posterior of every clique, axes in ``cliques`` order.
    """

    marginals: dict[str, np.ndarray]
    log_evidence: float
    cliques: tuple[tuple[str, ...], ...]
    clique_tables: tuple[np.ndarray, ...]

    def clique_belief(self, i: int) -> Factor:
        """Posterior of clique ``i`` as a log-space :class:`Factor`."""
        return Factor.from_table(self.cliques[i], self.clique_tables[i])


@dataclass(frozen=True)
class _Edge:
    src: int
    dst: int
    sum_axes: tuple[int, ...]  # axes of the source clique summed out
    kept_shape: tuple[int, ...]  # separator shape in the source's order
    perm: tuple[int, ...]  # order the separator's axes into the destination's order
    shape: tuple[int, ...]  # broadcast shape in the destination clique


@dataclass(frozen=True)
class _Placement:
    """Where a CPD goes: its home clique, the hard-evidence index, and the layout."""

    node: str
    home: int
    index: tuple[object, ...]  # per CPD axis: slice(None) or the name of an observed var
    perm: tuple[int, ...]
    shape: tuple[int, ...]


@dataclass(frozen=True)
class _Structure:
    cliques: tuple[tuple[str, ...], ...]
    placements: tuple[_Placement, ...]
    home: dict[str, int]
    collect: tuple[_Edge, ...]
    distribute: tuple[_Edge, ...]
    max_clique_size: int


def clique_tree_edges(cliques: Sequence[frozenset]) -> list[tuple[int, int]]:
    """The edges ``(parent, child)`` of a junction tree of ``cliques``, breadth first from
    clique 0.

    A maximum spanning tree of the clique graph weighted by separator sizes (Kruskal: pairs
    ``(i, j), i < j`` in lexicographic order, stably sorted by decreasing weight, so ties go
    to the earlier pair): when the cliques are the maximal cliques of a chordal graph it has
    the running-intersection property (Jensen & Jensen 1994). Disconnected parts are joined
    by empty separators. Neighbours are visited in the order their edges were accepted.

    Parameters
    ----------
    cliques : sequence of frozenset, length C >= 1

    Returns
    -------
    list of (int, int), length C - 1
    """
    n = len(cliques)
    pairs = sorted(((i, j) for i in range(n) for j in range(i + 1, n)),
                   key=lambda e: len(cliques[e[0]] & cliques[e[1]]), reverse=True)
    root = list(range(n))

    def find(i: int) -> int:
        while root[i] != i:
            root[i] = root[root[i]]
            i = root[i]
        return i

    adjacent: list[list[int]] = [[] for _ in range(n)]
    for i, j in pairs:
        ri, rj = find(i), find(j)
        if ri != rj:
            root[ri] = rj
            adjacent[i].append(j)
            adjacent[j].append(i)
    edges, queue, seen = [], [0], {0}
    for u in queue:
        for v in adjacent[u]:
            if v not in seen:
                seen.add(v)
                edges.append((u, v))
                queue.append(v)
    return edges


class JunctionTree:
    """A junction tree of a discrete Bayes net.

    Parameters
    ----------
    bn : BayesNet
        A discrete net.
    heuristic : {"min_fill", "min_weight"}
        Triangulation (elimination order) heuristic.

    Attributes
    ----------
    cliques : tuple of tuple of str
        The maximal cliques of the tree with no evidence (compiled on first use: a net
        only ever calibrated with evidence never needs this tree).
    max_clique_size : int
        Number of entries of its largest clique table.
    """

    def __init__(self, bn: BayesNet, heuristic: str = "min_fill") -> None:
        check_discrete_net(bn, "a junction tree")
        self.bn = bn
        self.heuristic = heuristic
        self._cards = {n: bn.cardinality(n) for n in bn.nodes}
        self._cache: dict[frozenset[str], _Structure] = {}

    @property
    def cliques(self) -> tuple[tuple[str, ...], ...]:
        return self._structure(frozenset()).cliques

    @property
    def max_clique_size(self) -> int:
        return self._structure(frozenset()).max_clique_size

    def __repr__(self) -> str:
        return f"JunctionTree({len(self.cliques)} cliques, largest table {self.max_clique_size})"

    # --- compilation --------------------------------------------------------------------
    def _structure(self, observed: frozenset[str]) -> _Structure:
        """The clique tree for this set of observed nodes (cached): cliques of a
        triangulation of the hidden nodes' interaction graph, each CPD's home clique, and
        the collect and distribute schedules."""
        cached = self._cache.get(observed)
        if cached is not None:
            return cached
        bn, cards = self.bn, self._cards
        nodes = bn.nodes
        scopes = {n: tuple(v for v in (*bn.parents(n), n) if v not in observed) for n in nodes}
        hidden = [n for n in nodes if n not in observed]
        graph = interaction_graph(scopes.values())
        graph.add_nodes_from(hidden)
        order = elimination_order(graph, cards, hidden, self.heuristic)
        cliques = _elimination_cliques(graph, order, {n: i for i, n in enumerate(nodes)})
        sets = [frozenset(c) for c in cliques]
        placements = tuple(
            _place(n, (*bn.parents(n), n), scopes[n], cliques, sets, cards, observed) for n in nodes
        )
        bfs = clique_tree_edges(sets)
        structure = _Structure(
            cliques=tuple(cliques),
            placements=placements,
            home={n: _smallest_holding(cliques, sets, {n}) for n in hidden},
            collect=tuple(_edge(cliques, cards, j, i) for i, j in reversed(bfs)),
            distribute=tuple(_edge(cliques, cards, i, j) for i, j in bfs),
            max_clique_size=max(int(np.prod([cards[v] for v in c])) for c in cliques),
        )
        self._cache[observed] = structure
        return structure

    # --- calibration --------------------------------------------------------------------
    def calibrate(
        self,
        evidence: Mapping[str, int | str] | None = None,
        soft_evidence: Mapping[str, ArrayLike] | None = None,
    ) -> Calibration:
        """Posterior marginal of every node and the log evidence.

        Parameters
        ----------
        evidence, soft_evidence
            See :func:`dbn.bayesnet.check_evidence`.

        Raises
        ------
        EvidenceError
            Invalid evidence, or evidence of probability zero.
        """
        hard, soft = check_evidence(self.bn, evidence, soft_evidence)
        st = self._structure(frozenset(hard))
        pots, log_scale = self._potentials(st, hard, soft)
        log_scale = _hugin(st, pots, log_scale)
        root_sum = float(pots[0].sum())
        if root_sum <= 0.0:
            raise EvidenceError("the evidence has probability zero")
        log_z = log_scale + float(np.log(root_sum))
        marg = {n: self._marginal(st, pots, hard, n) for n in self.bn.nodes}
        tables = tuple(p / p.sum() for p in pots)
        return Calibration(marg, log_z, st.cliques, tables)

    def _potentials(
        self, st: _Structure, hard: dict[str, int], soft: dict[str, np.ndarray]
    ) -> tuple[list[np.ndarray], float]:
        """Clique potentials with every CPD (sliced at the hard evidence) and the soft
        likelihoods multiplied in, each rescaled to max 1; and the log of the scales."""
        cards = self._cards
        pots = [np.ones([cards[v] for v in c]) for c in st.cliques]
        for pl in st.placements:
            idx = tuple(hard[i] if isinstance(i, str) else i for i in pl.index)
            table = self.bn.table(pl.node)[idx]
            pots[pl.home] = pots[pl.home] * np.transpose(table, pl.perm).reshape(pl.shape)
        log_scale = 0.0
        for name, lik in soft.items():
            top = float(lik.max())
            log_scale += np.log(top)
            if name in hard:  # a constant factor lambda(observed state)
                if lik[hard[name]] <= 0.0:
                    raise EvidenceError(
                        f"soft evidence on {name!r} gives its observed state likelihood zero"
                    )
                log_scale += float(np.log(lik[hard[name]] / top))
                continue
            i = st.home[name]
            shape = [1] * len(st.cliques[i])
            shape[st.cliques[i].index(name)] = lik.shape[0]
            pots[i] = pots[i] * (lik / top).reshape(shape)
        for i, p in enumerate(pots):
            top = p.max()
            if top <= 0.0:
                raise EvidenceError("the evidence has probability zero")
            pots[i] = p / top
            log_scale += float(np.log(top))
        return pots, log_scale

    def _marginal(
        self, st: _Structure, pots: list[np.ndarray], hard: dict[str, int], n: str
    ) -> np.ndarray:
        """Node ``n``'s posterior marginal from the calibrated potentials."""
        if n in hard:
            m = np.zeros(self._cards[n])
            m[hard[n]] = 1.0
            return m
        i = st.home[n]
        others = tuple(a for a, v in enumerate(st.cliques[i]) if v != n)
        m = pots[i].sum(axis=others) if others else pots[i]
        return m / m.sum()


def _hugin(st: _Structure, pots: list[np.ndarray], log_scale: float) -> float:
    """Hugin message passing in place on ``pots``: collect (children before parents), then
    distribute, dividing out what the receiving child sent during collect. Collect
    messages are rescaled to max 1; returns ``log_scale`` plus the log of those scales."""
    up: dict[int, np.ndarray] = {}
    for e in st.collect:
        kept = pots[e.src].sum(axis=e.sum_axes, keepdims=True)
        top = kept.max()
        if top <= 0.0:
            raise EvidenceError("the evidence has probability zero")
        kept = kept / top
        log_scale += float(np.log(top))
        up[e.src] = kept  # in the sender's layout: the shape its parent's reply will have
        msg = np.transpose(kept.reshape(e.kept_shape), e.perm).reshape(e.shape)
        pots[e.dst] = pots[e.dst] * msg
    for e in st.distribute:
        kept = pots[e.src].sum(axis=e.sum_axes)
        msg = np.transpose(kept, e.perm).reshape(e.shape)
        sent = up[e.dst]
        ratio = np.divide(msg, sent, out=np.zeros_like(msg), where=sent > 0)
        pots[e.dst] = pots[e.dst] * ratio
    return log_scale


def _elimination_cliques(
    graph: nx.Graph, order: Sequence[str], position: dict[str, int]
) -> list[tuple[str, ...]]:
    """The maximal cliques created by eliminating ``order`` from ``graph`` (its node and
    neighbours at each elimination), first-seen order, each sorted by ``position``;
    ``[()]`` when nothing is hidden."""
    g = {n: set(graph.neighbors(n)) for n in graph.nodes}
    raw: list[frozenset[str]] = []
    for n in order:
        raw.append(frozenset({n} | g[n]))
        for a in g[n]:
            g[a] |= g[n] - {a}
            g[a].discard(n)
        del g[n]
    cliques: list[tuple[str, ...]] = []
    seen: set[frozenset[str]] = set()
    for c in raw:
        if c not in seen and not any(c < d for d in raw):
            seen.add(c)
            cliques.append(tuple(sorted(c, key=position.__getitem__)))
    return cliques or [()]


def _smallest_holding(
    cliques: list[tuple[str, ...]], sets: list[frozenset], vars_: set[str]
) -> int:
    """Index of the smallest clique holding ``vars_`` (first on ties)."""
    return min((i for i, c in enumerate(sets) if vars_ <= c), key=lambda i: (len(cliques[i]), i))


def _place(
    node: str,
    full: tuple[str, ...],
    kept: tuple[str, ...],
    cliques: list[tuple[str, ...]],
    sets: list[frozenset],
    cards: dict[str, int],
    observed: frozenset[str],
) -> _Placement:
    """Where ``node``'s CPD (axes ``full``; ``kept`` the hidden ones) goes and its layout."""
    home = _smallest_holding(cliques, sets, set(kept))
    clique = cliques[home]
    perm = tuple(sorted(range(len(kept)), key=lambda k: clique.index(kept[k])))
    shape = tuple(cards[v] if v in kept else 1 for v in clique)
    index = tuple(v if v in observed else slice(None) for v in full)
    return _Placement(node, home, index, perm, shape)


def _edge(cliques: list[tuple[str, ...]], cards: dict[str, int], src: int, dst: int) -> _Edge:
    """The message from clique ``src`` to clique ``dst``: axes summed, separator layout."""
    cs, cd = cliques[src], cliques[dst]
    sep = [v for v in cs if v in cd]
    return _Edge(
        src,
        dst,
        tuple(i for i, v in enumerate(cs) if v not in cd),
        tuple(cards[v] for v in sep),
        tuple(sorted(range(len(sep)), key=lambda k: cd.index(sep[k]))),
        tuple(cards[v] if v in sep else 1 for v in cd),
    )


def marginals(
    bn: BayesNet,
    evidence: Mapping[str, int | str] | None = None,
    soft_evidence: Mapping[str, ArrayLike] | None = None,
) -> dict[str, np.ndarray]:
    """Every node's posterior marginal (builds a :class:`JunctionTree` and calibrates it)."""
    return JunctionTree(bn).calibrate(evidence, soft_evidence).marginals
