"""Junction-tree calibration: every single-node posterior marginal in one pass.

Build once per net (:class:`JunctionTree`), calibrate per evidence set
(:meth:`JunctionTree.calibrate`). Shafer-Shenoy message passing in log space on a tree of
the maximal cliques of a min-fill triangulation of the moral graph: a collect pass to the
root and a distribute pass back, ``2 (num_cliques - 1)`` messages in all.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import networkx as nx
import numpy as np
from numpy.typing import ArrayLike

from dbn.bayesnet import BayesNet, check_evidence
from dbn.errors import EvidenceError, ModelError
from inference.exact.factor import Factor, logsumexp, product
from inference.exact.graph import elimination_order, moral_graph

__all__ = ["JunctionTree", "Calibration", "marginals"]


@dataclass(frozen=True)
class Calibration:
    """Result of one calibration.

    Attributes
    ----------
    marginals : dict name -> ndarray (cardinality,)
        ``P(X_v | e)`` for every node (a point mass for hard-evidence nodes).
    log_evidence : float
        ``log P(e)`` with soft-evidence likelihoods multiplied in.
    clique_beliefs : tuple of Factor
        Normalised posterior of every clique.
    """

    marginals: dict[str, np.ndarray]
    log_evidence: float
    clique_beliefs: tuple[Factor, ...]


@dataclass(frozen=True)
class _Edge:
    src: int
    dst: int
    sum_axes: tuple[int, ...]  # axes of the source clique summed out
    perm: tuple[int, ...]  # order the separator's remaining axes into dst order
    shape: tuple[int, ...]  # broadcast shape in the destination clique


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
        The maximal cliques (variables of each in axis order).
    tree : networkx.Graph
        Edges between clique indices, with the separator as edge attribute ``sep``.
    max_clique_size : int
        Number of entries of the largest clique table.
    """

    def __init__(self, bn: BayesNet, heuristic: str = "min_fill") -> None:
        if not bn.is_discrete:
            raise ModelError("a junction tree needs a discrete Bayes net")
        self.bn = bn
        cards = {n: bn.cardinality(n) for n in bn.nodes}
        self._cards = cards
        moral = moral_graph(bn)
        order = elimination_order(moral, cards, heuristic=heuristic)
        g = {n: set(moral.neighbors(n)) for n in moral.nodes}
        raw: list[frozenset[str]] = []
        for n in order:
            raw.append(frozenset({n} | g[n]))
            for a in g[n]:
                g[a] |= g[n] - {a}
                g[a].discard(n)
            del g[n]
        maximal = [c for c in raw if not any(c < d for d in raw)]
        cliques: list[tuple[str, ...]] = []
        for c in maximal:
            t = tuple(sorted(c, key=bn.nodes.index))
            if t not in cliques:
                cliques.append(t)
        self.cliques = tuple(cliques)

        full = nx.Graph()
        full.add_nodes_from(range(len(cliques)))
        for i in range(len(cliques)):
            for j in range(i + 1, len(cliques)):
                sep = set(cliques[i]) & set(cliques[j])
                full.add_edge(i, j, weight=len(sep), sep=tuple(v for v in cliques[i] if v in sep))
        self.tree = nx.maximum_spanning_tree(full, weight="weight") if len(cliques) > 1 else full
        self.max_clique_size = max(int(np.prod([cards[v] for v in c])) for c in cliques)

        # assign every CPD family to the smallest clique that holds it
        potentials = [Factor((), np.zeros(())) for _ in cliques]
        assigned: list[list[Factor]] = [[] for _ in cliques]
        for n in bn.nodes:
            family = set(bn.parents(n)) | {n}
            home = min(
                (i for i, c in enumerate(cliques) if family <= set(c)),
                key=lambda i: (len(cliques[i]), i),
            )
            assigned[home].append(Factor.from_table((*bn.parents(n), n), bn.table(n)))
        for i, c in enumerate(cliques):
            base = Factor(c, np.zeros([cards[v] for v in c]))
            potentials[i] = product([base, *assigned[i]]).transpose(c)
        self._potentials = tuple(p.log_values for p in potentials)
        self._home = {
            n: min((i for i, c in enumerate(cliques) if n in c), key=lambda i: (len(cliques[i]), i))
            for n in bn.nodes
        }

        # message schedule: collect towards clique 0, then distribute
        self._root = 0
        bfs = list(nx.bfs_edges(self.tree, self._root)) if len(cliques) > 1 else []
        self._collect = [self._edge(j, i) for i, j in reversed(bfs)]
        self._distribute = [self._edge(i, j) for i, j in bfs]
        self._neighbours = {i: set(self.tree.neighbors(i)) for i in range(len(cliques))}

    def _edge(self, src: int, dst: int) -> _Edge:
        cs, cd = self.cliques[src], self.cliques[dst]
        sep = [v for v in cs if v in cd]
        sum_axes = tuple(i for i, v in enumerate(cs) if v not in cd)
        perm = tuple(sorted(range(len(sep)), key=lambda k: cd.index(sep[k])))
        shape = tuple(self._cards[v] if v in sep else 1 for v in cd)
        return _Edge(src, dst, sum_axes, perm, shape)

    def __repr__(self) -> str:
        return f"JunctionTree({len(self.cliques)} cliques, largest table {self.max_clique_size})"

    def calibrate(
        self,
        evidence: Mapping[str, int | str] | None = None,
        soft_evidence: Mapping[str, ArrayLike] | None = None,
    ) -> Calibration:
        """Posterior marginal of every node and the log evidence.

        Raises
        ------
        EvidenceError
            Invalid evidence, or evidence of probability zero.
        """
        hard, soft = check_evidence(self.bn, evidence, soft_evidence)
        pots = list(self._potentials)
        for name, state in hard.items():
            i = self._home[name]
            ind = np.full(self._cards[name], -np.inf)
            ind[state] = 0.0
            pots[i] = pots[i] + self._along(i, name, ind)
        for name, lik in soft.items():
            i = self._home[name]
            with np.errstate(divide="ignore"):
                pots[i] = pots[i] + self._along(i, name, np.log(lik))

        messages: dict[tuple[int, int], np.ndarray] = {}

        def send(e: _Edge) -> None:
            belief = pots[e.src]
            for k in self._neighbours[e.src]:
                if k != e.dst:
                    belief = belief + messages[(k, e.src)]
            msg = logsumexp(belief, axis=e.sum_axes) if e.sum_axes else belief
            messages[(e.src, e.dst)] = np.transpose(msg, e.perm).reshape(e.shape)

        for e in self._collect:
            send(e)
        for e in self._distribute:
            send(e)

        beliefs = []
        for i in range(len(self.cliques)):
            b = pots[i]
            for k in self._neighbours[i]:
                b = b + messages[(k, i)]
            beliefs.append(b)
        log_z = float(logsumexp(beliefs[self._root]))
        if not np.isfinite(log_z):
            raise EvidenceError("the evidence has probability zero")
        marg: dict[str, np.ndarray] = {}
        for n in self.bn.nodes:
            i = self._home[n]
            ax = self.cliques[i].index(n)
            others = tuple(a for a in range(len(self.cliques[i])) if a != ax)
            lm = logsumexp(beliefs[i], axis=others) if others else beliefs[i]
            p = np.exp(lm - logsumexp(lm))
            marg[n] = p / p.sum()
        clique_beliefs = tuple(Factor(c, b - log_z) for c, b in zip(self.cliques, beliefs))
        return Calibration(marg, log_z, clique_beliefs)

    def _along(self, clique: int, name: str, vec: np.ndarray) -> np.ndarray:
        c = self.cliques[clique]
        shape = [1] * len(c)
        shape[c.index(name)] = vec.shape[0]
        return vec.reshape(shape)


def marginals(
    bn: BayesNet,
    evidence: Mapping[str, int | str] | None = None,
    soft_evidence: Mapping[str, ArrayLike] | None = None,
) -> dict[str, np.ndarray]:
    """Every node's posterior marginal (builds a :class:`JunctionTree` and calibrates it)."""
    return JunctionTree(bn).calibrate(evidence, soft_evidence).marginals
