"""A compiled clique tree over evidence-reduced CPD factors, and its message passing.

:func:`compile_tree` turns a set of requisite factors (see :mod:`inference.exact.pruning`)
and an elimination order (see :mod:`inference.exact.triangulation`) into the elimination
tree of its cliques (clique ``C_v`` hangs under the clique of the first variable of
``C_v \\ {v}`` to be eliminated; a clique contained in a child's is merged into it). The
same tree serves both engines:

- variable elimination: :meth:`CliqueTree.collect` to the root only, the root clique
  holding the query variables (they are eliminated last);
- junction tree: :meth:`CliqueTree.calibrate`, Hugin's collect then distribute, every
  clique then holding ``P(C | e)`` up to a constant.

Tables live in linear space, every message rescaled to a maximum of 1 (the scales are
what a log-space computation would add; nothing underflows along a long chain). Every
product and sum is one :func:`numpy.einsum` over the clique's axes.
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from dbn.errors import EvidenceError, MemoryLimitError
from inference.exact.pruning import NetIndex
from inference.exact.triangulation import Triangulation

__all__ = ["CliqueTree", "compile_tree"]

_PATH_ABOVE = 2e4  # cliques this large contract pairwise along a cached einsum path
_MAX_OPERANDS = 30  # numpy's einsum takes at most 64 operands (32 before numpy 2)


@dataclass(frozen=True, eq=False)
class CliqueTree:
    """Compiled structure (no numbers): cliques, tree edges, factor placement.

    Attributes
    ----------
    cliques : tuple of tuple of int
        Variable ids of every clique; einsum subscript ``k`` is ``cliques[c][k]``.
    parent : tuple of int
        Parent clique (-1 for a root; a forest when the factors fall apart).
    postorder : tuple of int
        Children before parents.
    sep : tuple of tuple of int
        ``sep[c]``: the separator with the parent, as subscripts of clique ``c``.
    sep_in_parent : tuple of tuple of int
        The same separator as subscripts of the parent clique.
    factors : tuple of (int, int, tuple of int)
        ``(clique, node, subscripts)`` for every CPD factor, in the clique's subscripts.
    home : dict int -> int
        A clique holding each variable.
    sizes : tuple of int
        Table entries of every clique.
    """

    cliques: tuple[tuple[int, ...], ...]
    parent: tuple[int, ...]
    postorder: tuple[int, ...]
    sep: tuple[tuple[int, ...], ...]
    sep_in_parent: tuple[tuple[int, ...], ...]
    factors: tuple[tuple[int, int, tuple[int, ...]], ...]
    home: dict[int, int]
    sizes: tuple[int, ...]
    net: NetIndex
    observed: frozenset[int]
    _paths: dict = field(default_factory=dict, repr=False)

    @property
    def total_size(self) -> int:
        return int(sum(self.sizes))

    @property
    def max_size(self) -> int:
        return int(max(self.sizes, default=1))

    def clique_names(self, c: int) -> tuple[str, ...]:
        return tuple(self.net.names[v] for v in self.cliques[c])

    # --- numbers ------------------------------------------------------------------------
    def _potentials_ops(
        self, tables: Mapping[int, np.ndarray], evidence: Mapping[int, int]
    ) -> list[list[tuple[np.ndarray, tuple[int, ...]]]]:
        """Per clique, the evidence-reduced factor tables assigned to it."""
        ops: list[list[tuple[np.ndarray, tuple[int, ...]]]] = [[] for _ in self.cliques]
        net = self.net
        for c, n, sub in self.factors:
            scope = (*net.parents[n], n)
            idx = tuple(evidence[v] if v in evidence else slice(None) for v in scope)
            ops[c].append((tables[n][idx], sub))
        return ops

    def _operands(
        self, c: int, ops: list[tuple[np.ndarray, tuple[int, ...]]]
    ) -> list[tuple[np.ndarray, tuple[int, ...]]]:
        """``ops`` plus a vector of ones for every clique variable no operand covers, the
        first ones folded into the full clique while there are too many for einsum."""
        clique = self.cliques[c]
        covered = {s for _, sub in ops for s in sub}
        ops = ops + [
            (np.ones(int(self.net.cards[clique[k]])), (k,))
            for k in range(len(clique))
            if k not in covered
        ]
        while len(ops) > _MAX_OPERANDS:
            head, ops = ops[:_MAX_OPERANDS], ops[_MAX_OPERANDS:]
            full = tuple(range(len(clique)))
            ops.insert(0, (np.einsum(*_interleave(head), full), full))
        return ops

    def _path(self, c: int, args: list[object], ops: list, out: tuple[int, ...]) -> tuple:
        """(path, FLOP estimate) of a pairwise contraction, found once per operand layout."""
        key = (c, out, tuple(sub for _, sub in ops))
        found = self._paths.get(key)
        if found is None:
            path, text = np.einsum_path(*args, optimize="greedy")
            match = re.search(r"Optimized FLOP count:\s*([0-9.eE+-]+)", text)
            flops = float(match.group(1)) if match else float(self.sizes[c] * len(ops))
            found = self._paths[key] = (path, flops)
        return found

    def _contract(
        self, c: int, ops: list[tuple[np.ndarray, tuple[int, ...]]], out: Sequence[int]
    ) -> np.ndarray:
        """``sum_{C \\ out} prod ops`` over clique ``c`` (a variable no operand covers
        counts as a factor of ones)."""
        ops = self._operands(c, ops)
        out = tuple(out)
        args = _interleave(ops) + [out]
        if len(ops) < 3 or self.sizes[c] < _PATH_ABOVE:
            return np.einsum(*args)
        return np.einsum(*args, optimize=self._path(c, args, ops, out)[0])

    def calibrate_cost(self) -> float:
        """Predicted entry-operations of :meth:`calibrate`: every clique table is built from
        its factors and incoming messages, then summed, multiplied and divided a few
        times (``size * (operands + 3)`` per clique)."""
        operands = [1 + sum(1 for p in self.parent if p == c) for c in range(len(self.cliques))]
        for c, _, _ in self.factors:
            operands[c] += 1
        return float(sum(size * (k + 3) for size, k in zip(self.sizes, operands)))

    def collect_cost(self, root: int) -> float:
        """Predicted multiply-adds of :meth:`collect` to ``root`` (big cliques: the cached
        pairwise einsum path's FLOP count; it is reused by the run)."""
        net = self.net
        ops: list[list[tuple[np.ndarray, tuple[int, ...]]]] = [[] for _ in self.cliques]
        for c, _, sub in self.factors:
            shape = tuple(int(net.cards[self.cliques[c][k]]) for k in sub)
            ops[c].append((np.broadcast_to(1.0, shape), sub))
        cost = 0.0
        for c in self.postorder:
            p = self.parent[c]
            out = tuple(range(len(self.cliques[c]))) if c == root else self.sep[c]
            operands = self._operands(c, ops[c])
            if len(operands) < 3 or self.sizes[c] < _PATH_ABOVE:
                cost += float(self.sizes[c]) * len(operands)
            else:
                args = _interleave(operands) + [out]
                cost += self._path(c, args, operands, out)[1]
            if c == root:
                break
            if p >= 0:
                shape = tuple(int(net.cards[self.cliques[c][k]]) for k in self.sep[c])
                ops[p].append((np.broadcast_to(1.0, shape), self.sep_in_parent[c]))
        return cost

    def collect(
        self, root: int, tables: Mapping[int, np.ndarray], evidence: Mapping[int, int]
    ) -> np.ndarray:
        """Unnormalised table of clique ``root`` after messages from its whole subtree
        (variable elimination; max-1 rescaled, zero mass is an error)."""
        ops = self._potentials_ops(tables, evidence)
        for c in self.postorder:
            p = self.parent[c]
            if c == root:
                return self._contract(c, ops[c], range(len(self.cliques[c])))
            if p < 0:
                continue
            msg = _rescaled(self._contract(c, ops[c], self.sep[c]))
            ops[p].append((msg, self.sep_in_parent[c]))
        raise ValueError(f"clique {root} is not in the tree")

    def calibrate(
        self, tables: Mapping[int, np.ndarray], evidence: Mapping[int, int]
    ) -> list[np.ndarray]:
        """Hugin collect/distribute: every clique's table proportional to ``P(C, e)``."""
        ops = self._potentials_ops(tables, evidence)
        pots: list[np.ndarray] = [np.empty(0)] * len(self.cliques)
        up: dict[int, np.ndarray] = {}
        for c in self.postorder:
            pots[c] = self._contract(c, ops[c], range(len(self.cliques[c])))
            p = self.parent[c]
            if p >= 0:
                full = tuple(range(len(self.cliques[c])))
                up[c] = _rescaled(np.einsum(pots[c], full, self.sep[c]))
                ops[p].append((up[c], self.sep_in_parent[c]))
            elif not pots[c].any():
                raise EvidenceError("the evidence has probability zero")
        for c in reversed(self.postorder):
            p = self.parent[c]
            if p < 0:
                continue
            pfull = tuple(range(len(self.cliques[p])))
            msg = np.einsum(pots[p], pfull, self.sep_in_parent[c])
            sent = up[c]
            ratio = np.divide(msg, sent, out=np.zeros_like(msg), where=sent > 0)
            full = tuple(range(len(self.cliques[c])))
            pots[c] = np.einsum(pots[c], full, ratio, self.sep[c], full)
        return pots

    def marginal(self, pots: Sequence[np.ndarray], v: int) -> np.ndarray:
        """Normalised ``P(X_v | e)`` from calibrated tables."""
        c = self.home[v]
        m = np.einsum(pots[c], tuple(range(len(self.cliques[c]))), (self.cliques[c].index(v),))
        return m / m.sum()


def _interleave(ops: Sequence[tuple[np.ndarray, Sequence[int]]]) -> list[object]:
    out: list[object] = []
    for arr, sub in ops:
        out += [arr, tuple(sub)]
    return out


def _rescaled(msg: np.ndarray) -> np.ndarray:
    top = msg.max() if msg.size else 1.0
    if not top > 0.0:
        raise EvidenceError("the evidence has probability zero")
    return msg / top


def compile_tree(
    net: NetIndex,
    factors: Sequence[int],
    observed: frozenset[int],
    tri: Triangulation,
    limit: float,
    root_var: int | None = None,
) -> CliqueTree:
    """The clique tree of ``tri`` over the evidence-reduced CPDs of ``factors``.

    With ``root_var``, the tree is re-rooted at the clique holding that variable (the
    query of a variable-elimination tree: :meth:`CliqueTree.collect` ends there).

    Raises
    ------
    MemoryLimitError
        A clique table would hold more than ``limit`` entries (checked before any table
        is allocated; the message names the clique's variables and its size).
    """
    if tri.max_size > limit:
        c = max(tri.cliques, key=lambda q: float(np.prod([float(net.cards[v]) for v in q])))
        names = [net.names[v] for v in c]
        raise MemoryLimitError(
            f"clique {names} would hold {tri.max_size:.3g} entries, over the limit of "
            f"{limit:.3g} (max_table_size); query fewer variables or raise the limit"
        )
    pos = {v: i for i, v in enumerate(tri.order)}
    cliques: list[tuple[int, ...]] = []
    kids_of: dict[int, list[int]] = {}  # variable -> clique ids waiting for it as parent
    node_of: dict[int, int] = {}
    parent: list[int] = []
    for v, clique in zip(tri.order, tri.cliques):
        kids = kids_of.pop(v, [])
        cset = set(clique)
        absorb = next((k for k in kids if cset <= set(cliques[k])), None)
        node = absorb if absorb is not None else len(cliques)
        if absorb is None:
            cliques.append(tuple(clique))
            parent.append(-1)
        for k in kids:
            if k != node:
                parent[k] = node
        node_of[v] = node
        rest = clique[1:]
        if rest:
            kids_of.setdefault(min(rest, key=pos.__getitem__), []).append(node)
    if root_var is not None:
        parent = _rerooted(parent, node_of[root_var])
    return _finish(net, factors, observed, cliques, parent, node_of, pos)


def _rerooted(parent: list[int], root: int) -> list[int]:
    """Parent pointers of the same tree hung from ``root`` (other trees unchanged)."""
    path = [root]
    while parent[path[-1]] >= 0:
        path.append(parent[path[-1]])
    out = list(parent)
    out[root] = -1
    for child, up in zip(path, path[1:]):  # reverse the edges on the path to the old root
        out[up] = child
    return out


def _finish(
    net: NetIndex,
    factors: Sequence[int],
    observed: frozenset[int],
    cliques: list[tuple[int, ...]],
    parent: list[int],
    node_of: dict[int, int],
    pos: dict[int, int],
) -> CliqueTree:
    children: list[list[int]] = [[] for _ in cliques]
    for c, p in enumerate(parent):
        if p >= 0:
            children[p].append(c)
    postorder: list[int] = []
    for r in (c for c, p in enumerate(parent) if p < 0):
        stack = [(r, False)]
        while stack:
            c, done = stack.pop()
            if done:
                postorder.append(c)
                continue
            stack.append((c, True))
            stack.extend((k, False) for k in children[c])
    sep, sep_p = [], []
    for c, p in enumerate(parent):
        shared = [v for v in cliques[c] if p >= 0 and v in cliques[p]]
        sep.append(tuple(cliques[c].index(v) for v in shared))
        sep_p.append(tuple(cliques[p].index(v) for v in shared) if p >= 0 else ())
    placed = []
    for n in factors:
        scope = [v for v in (*net.parents[n], n) if v not in observed]
        c = node_of[min(scope, key=pos.__getitem__)]
        placed.append((c, n, tuple(cliques[c].index(v) for v in scope)))
    sizes = tuple(int(np.prod([int(net.cards[v]) for v in c])) for c in cliques)
    return CliqueTree(
        cliques=tuple(cliques),
        parent=tuple(parent),
        postorder=tuple(postorder),
        sep=tuple(sep),
        sep_in_parent=tuple(sep_p),
        factors=tuple(placed),
        home=dict(node_of),
        sizes=sizes,
        net=net,
        observed=observed,
    )
