r"""A precompiled sum-product plan over the factors of one DBN slice.

Boyen-Koller filtering (:mod:`inference.adf.boyen_koller`) needs, at every slice, the
marginals of a few small sets of variables (the clusters) under a product of small
factors (previous cluster beliefs, the slice's CPDs, evidence likelihoods), and the sum of
that product (the one-step likelihood). The structure of the factors is the same at every
slice; only their values change. :class:`SlicePlan` therefore triangulates the factor
graph once (greedy min-fill elimination), builds the elimination tree of cliques, assigns
each factor and each target set to a clique and precomputes the ``einsum`` subscripts; a
slice is then one upward and one downward pass of messages (Shafer-Shenoy), whose cost is
linear in the number of cliques and bounded by the largest clique, never by the joint.

With cliques :math:`C_k` (variable :math:`v_k` and its neighbours when eliminated),
potentials :math:`\psi_k` (product of the factors assigned to :math:`C_k`) and separators
:math:`S_k = C_k \setminus \{v_k\}`:

.. math::

    m_{k \to p}(S_k) = \sum_{v_k} \psi_k \prod_{j \in ch(k)} m_{j \to k}, \qquad
    Z = \prod_{\text{roots } r} \sum_{C_r} \psi_r \prod_{j \in ch(r)} m_{j \to r},

each upward message normalised with its log scale added to :math:`\log Z` (no underflow).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from itertools import combinations
from string import ascii_letters

import networkx as nx
import numpy as np

from dbn.errors import ModelError
from inference.exact.graph import elimination_order

__all__ = ["SlicePlan", "MAX_CLIQUE_SIZE"]

MAX_CLIQUE_SIZE = 2**22
"""Largest clique table (entries) a plan accepts."""


def _elimination_order(
    cards: Mapping[str, int], scopes: Sequence[tuple[str, ...]]
) -> list[tuple[str, tuple[str, ...]]]:
    """The greedy min-fill order of :func:`inference.exact.graph.elimination_order` (ties:
    smaller clique, then name) over the factors' interaction graph, each variable with its
    neighbours still present when it is eliminated: [(var, neighbours)]."""
    graph = nx.Graph()
    graph.add_nodes_from(cards)
    for s in scopes:
        graph.add_edges_from(combinations(s, 2))
    adj = {v: set(graph.neighbors(v)) for v in cards}
    remaining = set(cards)
    out = []
    for v in elimination_order(graph, cards):
        nb = tuple(sorted(adj[v] & remaining))
        for a in nb:
            adj[a].update(b for b in nb if b != a)
        remaining.remove(v)
        out.append((v, nb))
    return out


class SlicePlan:
    """Sum-product over fixed factor scopes: target marginals and ``log Z`` per call.

    Parameters
    ----------
    cards : mapping name -> int
        Cardinality of every variable (each must appear in some factor scope).
    factor_scopes : sequence of tuple of str
        Scope of each factor, in the axis order its values will have. An empty scope is
        a scalar factor (it only scales ``Z``).
    target_scopes : sequence of tuple of str
        Sets whose joint marginals :meth:`run` returns, axes in the given order.

    Raises
    ------
    ModelError
        A clique of the triangulation would exceed :data:`MAX_CLIQUE_SIZE` entries (the
        message quotes the size), or a scope names an unknown variable.
    """

    def __init__(
        self,
        cards: Mapping[str, int],
        factor_scopes: Sequence[tuple[str, ...]],
        target_scopes: Sequence[tuple[str, ...]],
    ) -> None:
        self.cards = dict(cards)
        for s in (*factor_scopes, *target_scopes):
            for v in s:
                if v not in self.cards:
                    raise ModelError(f"slice plan: scope {s} names unknown variable {v!r}")
        order = _elimination_order(self.cards, [*factor_scopes, *target_scopes])
        pos = {v: k for k, (v, _) in enumerate(order)}
        self.cliques = [(v, *nb) for v, nb in order]
        self.seps = [nb for _, nb in order]
        self.parent = [min((pos[u] for u in nb), default=-1) for _, nb in order]
        self.children: list[list[int]] = [[] for _ in order]
        for k, p in enumerate(self.parent):
            if p >= 0:
                self.children[p].append(k)
        self.max_clique_size = max(
            (int(np.prod([self.cards[u] for u in c])) for c in self.cliques), default=1
        )
        if self.max_clique_size > MAX_CLIQUE_SIZE:
            raise ModelError(
                f"the slice's triangulation has a clique of {self.max_clique_size} entries "
                f"(> {MAX_CLIQUE_SIZE}): use smaller clusters or a particle filter"
            )

        def home(scope: tuple[str, ...]) -> int:
            return min(pos[u] for u in scope) if scope else -1

        self.factor_home = [home(s) for s in factor_scopes]
        self.target_home = [home(s) for s in target_scopes]
        if any(h < 0 for h in self.target_home):
            raise ModelError("slice plan: a target scope is empty")
        self.factor_scopes = [tuple(s) for s in factor_scopes]
        self.target_scopes = [tuple(s) for s in target_scopes]
        self._compile()

    def _sub(self, scope: Sequence[str], letters: Mapping[str, str]) -> str:
        return "".join(letters[u] for u in scope)

    def _compile(self) -> None:
        """Precompute the einsum subscripts of potentials, messages and marginals."""
        n = len(self.cliques)
        self._letters = []
        self._psi_sub, self._up_sub, self._down_sub, self._marg_sub = [], [], {}, []
        for k in range(n):
            c = self.cliques[k]
            if len(c) > len(ascii_letters):
                raise ModelError(f"slice plan: a clique of {len(c)} variables is too wide")
            lt = {u: ascii_letters[i] for i, u in enumerate(c)}
            self._letters.append(lt)
            facs = [i for i, h in enumerate(self.factor_home) if h == k]
            subs = [self._sub(self.factor_scopes[i], lt) for i in facs]
            cs = self._sub(c, lt)
            self._psi_sub.append((facs, ",".join([*subs, cs]) + "->" + cs))
            ins = [self._sub(self.seps[j], lt) for j in self.children[k]]
            self._up_sub.append(
                ",".join([self._sub(c, lt), *ins]) + "->" + self._sub(self.seps[k], lt)
            )
        for k in range(n):
            p = self.parent[k]
            if p < 0:
                continue
            lt = self._letters[p]
            ops = [self._sub(self.cliques[p], lt)]
            if self.parent[p] >= 0:
                ops.append(self._sub(self.seps[p], lt))
            ops += [self._sub(self.seps[j], lt) for j in self.children[p] if j != k]
            self._down_sub[k] = ",".join(ops) + "->" + self._sub(self.seps[k], lt)
        for i, k in enumerate(self.target_home):
            lt = self._letters[k]
            ops = [self._sub(self.cliques[k], lt)]
            if self.parent[k] >= 0:
                ops.append(self._sub(self.seps[k], lt))
            ops += [self._sub(self.seps[j], lt) for j in self.children[k]]
            self._marg_sub.append(",".join(ops) + "->" + self._sub(self.target_scopes[i], lt))
        # the cliques that need a downward message: those on a path from a root to a target
        need = set()
        for k in self.target_home:
            while k >= 0 and k not in need:
                need.add(k)
                k = self.parent[k]
        self._need_down = sorted((k for k in need if self.parent[k] >= 0), reverse=True)
        self._ones = []
        for c in self.cliques:
            ones = np.ones(tuple(self.cards[u] for u in c))
            ones.setflags(write=False)
            self._ones.append(ones)
        # operands of each message, as clique indices (precomputed: a step is a tight loop)
        self._down_ops = {
            k: (
                self.parent[k],
                self.parent[self.parent[k]] >= 0,
                [j for j in self.children[self.parent[k]] if j != k],
            )
            for k in self._need_down
        }
        self._empty_factors = [i for i, h in enumerate(self.factor_home) if h < 0]

    def run(self, factors: Sequence[np.ndarray]) -> tuple[list[np.ndarray], float]:
        """Normalised target marginals and ``log Z`` of the product of ``factors``.

        Parameters
        ----------
        factors : sequence of ndarray
            One nonnegative array per factor scope, shape ``(cards of its scope)``.

        Returns
        -------
        marginals : list of ndarray
            One per target scope, summing to 1 (NaN if ``Z = 0``).
        log_z : float
            ``log sum prod factors`` (``-inf`` if the product is zero everywhere).
        """
        n = len(self.cliques)
        psi = []
        for k in range(n):
            facs, sub = self._psi_sub[k]
            if facs:
                psi.append(np.einsum(sub, *[factors[i] for i in facs], self._ones[k]))
            else:
                psi.append(self._ones[k])
        log_z = 0.0
        for i in self._empty_factors:
            log_z += float(np.log(factors[i]))
        up: list = [None] * n
        children = self.children
        for k in range(n):
            m = np.einsum(self._up_sub[k], psi[k], *[up[j] for j in children[k]])
            s = m.sum()
            if not s > 0.0:
                return [np.full(t.shape, np.nan) for t in self._target_shapes()], -np.inf
            log_z += np.log(s)
            up[k] = m / s
        down: list = [None] * n
        for k in self._need_down:
            p, has_down, sibs = self._down_ops[k]
            ops = [psi[p], down[p]] if has_down else [psi[p]]
            m = np.einsum(self._down_sub[k], *ops, *[up[j] for j in sibs])
            down[k] = m / m.sum()
        out = []
        for i, k in enumerate(self.target_home):
            ops = [psi[k], down[k]] if self.parent[k] >= 0 else [psi[k]]
            m = np.einsum(self._marg_sub[i], *ops, *[up[j] for j in children[k]])
            out.append(m / m.sum())
        return out, float(log_z)

    def _target_shapes(self) -> list[np.ndarray]:
        return [np.empty(tuple(self.cards[u] for u in s)) for s in self.target_scopes]
