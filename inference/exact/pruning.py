"""Query-driven pruning of a Bayes net: the factors a query actually needs.

For a query set ``Q`` and hard-evidence variables ``E`` the posterior ``P(Q | e)`` depends
only on the *requisite* factors:

1. **Barren nodes** go first: a node that is not an ancestor of ``Q u E`` (itself
   included) sums out to 1 and is dropped with its CPD.
2. **d-separation**: on the remaining (ancestral) net, every CPD is reduced by the
   evidence (observed axes indexed away), which cuts the observed nodes out of the moral
   graph. A factor whose reduced scope lies in a connected component holding no query
   variable is d-separated from ``Q`` given ``E`` and contributes a constant; it is
   dropped. This is what Bayes-ball finds (Shachter 1998), computed on the moralised
   ancestral graph (Lauritzen et al. 1990).

The kept factors, multiplied and summed over the kept non-query variables, are
proportional to ``P(Q, e)``. :func:`requisite` works on variable indices (see
:class:`NetIndex`) and is cheap: ``O(size of the ancestral net)`` per call.
"""

from __future__ import annotations

import weakref
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from dbn.bayesnet import BayesNet, check_discrete_net

__all__ = ["NetIndex", "Pruned", "net_index", "requisite", "barren"]


@dataclass(frozen=True, eq=False)
class NetIndex:
    """Integer view of a discrete net's structure, shared by the pruning and the engines.

    Attributes
    ----------
    names : tuple of str
        Node names; node ``i`` is ``names[i]``.
    index : dict str -> int
    parents : tuple of tuple of int
        Parent indices of each node, in CPD axis order.
    children : tuple of tuple of int
    cards : ndarray of int, shape ``(n,)``
    fingerprint : tuple
        ``(names, parents, cards)``: equal for two nets of the same structure.
    """

    names: tuple[str, ...]
    index: dict[str, int]
    parents: tuple[tuple[int, ...], ...]
    children: tuple[tuple[int, ...], ...]
    cards: np.ndarray
    fingerprint: tuple

    @classmethod
    def of(cls, bn: BayesNet) -> NetIndex:
        check_discrete_net(bn, "exact inference")
        names = bn.nodes
        index = {n: i for i, n in enumerate(names)}
        parents = tuple(tuple(index[p] for p in bn.parents(n)) for n in names)
        children: list[list[int]] = [[] for _ in names]
        for i, ps in enumerate(parents):
            for p in ps:
                children[p].append(i)
        cards = np.array([bn.cardinality(n) for n in names], dtype=np.int64)
        cards.setflags(write=False)
        fp = (names, parents, tuple(int(k) for k in cards))
        return cls(names, index, parents, tuple(map(tuple, children)), cards, fp)


_INDEX: weakref.WeakKeyDictionary[BayesNet, NetIndex] = weakref.WeakKeyDictionary()


def net_index(bn: BayesNet) -> NetIndex:
    """The :class:`NetIndex` of ``bn``, built once per net object (nets are immutable)."""
    found = _INDEX.get(bn)
    if found is None:
        found = _INDEX[bn] = NetIndex.of(bn)
    return found


@dataclass(frozen=True)
class Pruned:
    """The requisite part of a net for one query.

    Attributes
    ----------
    factors : tuple of int
        Nodes whose (evidence-reduced) CPD is kept; their reduced scopes are non-empty.
    hidden : tuple of int
        Unobserved variables in the kept factors (the query variables included).
    removed : frozenset of int
        Nodes whose CPD was dropped (barren or d-separated).
    """

    factors: tuple[int, ...]
    hidden: tuple[int, ...]
    removed: frozenset[int]


def barren(net: NetIndex, keep: Iterable[int]) -> set[int]:
    """The ancestral set of ``keep`` (themselves included): every other node is barren."""
    seen = set(keep)
    stack = list(seen)
    parents = net.parents
    while stack:
        for p in parents[stack.pop()]:
            if p not in seen:
                seen.add(p)
                stack.append(p)
    return seen


def requisite(
    net: NetIndex, query: Iterable[int], observed: Iterable[int], anchors: Iterable[int] = ()
) -> Pruned:
    """Barren-node and d-separation pruning for ``P(query | observed)``.

    Parameters
    ----------
    query : iterable of int
        Query variables (not observed).
    observed : iterable of int
        Hard-evidence variables.
    anchors : iterable of int
        Unobserved variables carrying soft evidence (a likelihood factor on the variable
        alone): they and their ancestors are not barren.
    """
    query = set(query)
    obs = set(observed)
    ancestral = barren(net, query | obs | set(anchors))
    parents = net.parents
    # reduced scope of every ancestral CPD; link the hidden variables sharing a scope
    by_var: dict[int, list[int]] = {}
    for n in ancestral:
        for v in (*parents[n], n):
            if v not in obs:
                by_var.setdefault(v, []).append(n)
    reached = set(query)
    stack = list(query)
    kept: set[int] = set()
    while stack:  # connected component of the query in the reduced interaction graph
        v = stack.pop()
        for n in by_var.get(v, ()):
            if n in kept:
                continue
            kept.add(n)
            for u in (*parents[n], n):
                if u not in obs and u not in reached:
                    reached.add(u)
                    stack.append(u)
    factors = tuple(sorted(kept))
    removed = frozenset(range(len(net.names))) - kept
    return Pruned(factors, tuple(sorted(reached)), removed)
