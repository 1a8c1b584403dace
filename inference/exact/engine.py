"""Exact posterior marginals at the scale of real networks: prune, triangulate, cache.

:class:`ExactInference` answers ``P(X_q | e)`` for a set of query nodes with one of two
engines over the *pruned* net (:mod:`inference.exact.pruning`):

- ``"ve"``: variable elimination per query, on the factors that query needs (barren and
  d-separated nodes removed), the tree rooted at the query's clique (collect only);
- ``"jt"``: one junction tree over the factors all the queries need, calibrated once.

``engine="auto"`` picks ``"ve"`` for a handful of queries; otherwise it takes a junction
tree outright when that tree is small (1e5 entries), and else compares its predicted
work (clique entries times operands, per contraction) with that of per-query
elimination (the FLOP counts of the einsum paths each query's collect will use,
estimated on a stratified sample of the queries). Queries whose requisite factors are
the same share one calibrated tree. The choice is reported in the result. Orders come
from :func:`~inference.exact.triangulation.triangulate` (min-fill and min-weight,
randomised restarts, smallest total table).

Compiled trees are cached per ``(set of observed variables, query set, engine)``; the
numbers (evidence values, CPD tables) are read at every call, so a repeat with other
evidence values is a pure einsum pass. Assigning a net of another structure to
:attr:`ExactInference.bn` empties the cache. A tree whose largest clique would exceed
``max_table_size`` entries raises :class:`~dbn.errors.MemoryLimitError` before allocating.

CPD rows are divided by their sums (a net accepts rows within 1e-9 of 1; exact sums make
dropping barren nodes exact). Evidence of probability zero raises
:class:`~dbn.errors.EvidenceError` whenever it lies in the part of the net a query needs,
so always when every marginal is asked for; with a few queries, an impossible
observation d-separated from all of them goes unnoticed (as with pgmpy's pruning).
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

import numpy as np

from dbn.bayesnet import BayesNet, check_evidence
from dbn.checks import check_count, check_size, from_package
from dbn.errors import EvidenceError, InputError, MemoryLimitError, UnknownVariableError
from inference.exact.cliquetree import CliqueTree, compile_tree
from inference.exact.pruning import NetIndex, requisite
from inference.exact.triangulation import Triangulation, triangulate
from inference.model_cache import ModelCache

__all__ = ["ExactInference", "Marginals", "default_table_limit", "posterior_marginals"]

ENGINES = ("auto", "ve", "jt")
_HANDFUL = 4  # at most this many queries: always per-query elimination
_CLIQUE_OVERHEAD = 5e3  # table entries one einsum call's Python overhead is worth
_JT_UNIT = 4.0  # one entry-operand of a materialised einsum product, in einsum-path FLOPs
_SMALL_TREE = 1e5  # a junction tree this small (entries) is taken without comparing
_GROUP_RESTART_ABOVE = 1e7  # per-query trees are many and small: restart only huge ones
_SAMPLE = 16  # queries compiled to estimate the cost of per-query elimination


def default_table_limit() -> int:
    """Largest clique table (entries) allowed by default: an eighth of physical memory
    in float64 (a calibration holds a few tables of the largest size at once)."""
    try:
        mem = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (ValueError, OSError, AttributeError):
        mem = 8 * 2**30
    return int(mem // 8 // 8)


@dataclass(frozen=True)
class Marginals:
    """Answer of :meth:`ExactInference.marginals`.

    Attributes
    ----------
    marginals : dict name -> ndarray (cardinality,)
        ``P(X_v | e)`` per requested node (a point mass for an observed one).
    engine : str
        ``"ve"`` or ``"jt"``: the engine that answered.
    max_table_size : int
        Entries of the largest clique table used.
    total_table_size : int
        Entries of all clique tables used (summed over queries for ``"ve"``).
    compiled : bool
        Whether this call compiled (a cache miss) rather than reused a compiled tree.
    """

    marginals: dict[str, np.ndarray]
    engine: str
    max_table_size: int
    total_table_size: int
    compiled: bool


class ExactInference:
    """Pruned, cached exact inference on a discrete :class:`~dbn.bayesnet.BayesNet`.

    Parameters
    ----------
    bn : BayesNet or pgmpy DiscreteBayesianNetwork
        A discrete net (its acyclicity is checked when it is built); a pgmpy model is
        converted by :func:`dbn.pgmpy_adapter.from_pgmpy` when given (here or to
        :attr:`bn`): a later change to the pgmpy model is not seen until it is given again.
    max_table_size : int >= 1, optional
        Largest clique table (entries) any engine may allocate; default
        :func:`default_table_limit`.
    restarts : int >= 0
        Randomised triangulation restarts per heuristic (for trees above 1e5 entries).

    Raises
    ------
    InputError
        ``max_table_size`` or ``restarts`` not an integer in range (before any work).
    ModelError
        Not a discrete Bayes net.
    """

    def __init__(self, bn: BayesNet, max_table_size: int | None = None, restarts: int = 2) -> None:
        self.max_table_size = (default_table_limit() if max_table_size is None
                               else check_count("max_table_size", max_table_size))  # fmt: skip
        self.restarts = check_size("restarts", restarts)  # "a": int()'s ValueError; -1 ran
        self._net: NetIndex | None = None
        self.bn = bn

    # --- the network and the cache ------------------------------------------------------
    @property
    def bn(self) -> BayesNet:
        return self._bn

    @bn.setter
    def bn(self, bn: BayesNet) -> None:
        if from_package(bn, "pgmpy"):  # as inference.filter takes a pgmpy DBN
            from dbn.pgmpy_adapter import from_pgmpy

            bn = from_pgmpy(bn)
        net = NetIndex.of(bn)
        if self._net is None or net.fingerprint != self._net.fingerprint:
            self.clear_cache()  # another structure: every compiled tree is stale
        self._bn, self._net = bn, net
        # rows are accepted within 1e-9 of summing to 1; dividing by the sums makes
        # barren-node pruning exact (else it shifts answers by up to ~1e-9 x nodes)
        self._tables = {}
        for i, n in enumerate(net.names):
            t = bn.table(n)
            self._tables[i] = t / t.sum(axis=-1, keepdims=True)

    def clear_cache(self) -> None:
        """Forget every compiled tree."""
        self._plans: dict[tuple, tuple[str, object]] = {}
        self._ve: dict[tuple, CliqueTree] = {}
        self._tri: dict[tuple, Triangulation] = {}
        self.compiles = 0

    @property
    def cache_size(self) -> int:
        return len(self._plans) + len(self._ve) + len(self._tri)

    # --- public API ---------------------------------------------------------------------
    def marginals(
        self,
        evidence: Mapping[str, int | str] | None = None,
        nodes: Iterable[str] | None = None,
        engine: str = "auto",
    ) -> Marginals:
        """Posterior marginal of each of ``nodes`` (default: every unobserved node).

        Raises
        ------
        EvidenceError
            Unknown evidence variable or state, or evidence of probability zero (in the
            part of the net the queries need).
        UnknownVariableError
            A queried node is not in the net.
        InputError
            ``nodes`` neither a name nor a sequence of names; an unknown ``engine``.
        MemoryLimitError
            The chosen (or, for ``"auto"``, every) engine needs a table over the limit.
        """
        if engine not in ENGINES:
            raise InputError(f"engine must be one of {ENGINES}, got {engine!r}")
        if isinstance(nodes, str):  # one name ("lung" was read as 'l', 'u', 'n', 'g')
            nodes = [nodes]
        if nodes is not None and not isinstance(nodes, Iterable):
            raise InputError(f"nodes must be a variable name or a sequence of names, got "
                             f"{type(nodes).__name__} {nodes!r}")  # fmt: skip
        net = self._net
        hard, _ = check_evidence(self._bn, evidence)
        ev = {net.index[n]: s for n, s in hard.items()}
        wanted = [n for n in net.names if n not in hard] if nodes is None else list(nodes)
        for n in wanted:
            if n not in net.index:
                raise UnknownVariableError(f"query of unknown variable {n!r}")
        queries = tuple(sorted({net.index[n] for n in wanted} - set(ev)))
        observed = frozenset(ev)
        if nodes is None or len(queries) == len(net.names) - len(ev):
            self._check_constants(ev)
        key = (observed, queries, engine)
        compiled = key not in self._plans
        if compiled:
            self._plans[key] = self._compile(observed, queries, engine)
        kind, plan = self._plans[key]
        out = self._run_ve(plan, ev) if kind == "ve" else self._run_jt(plan, ev)  # type: ignore[arg-type]
        trees = [t for _, t in plan] if kind == "ve" else [plan]  # type: ignore[union-attr]
        result = {}
        for n in wanted:
            i = net.index[n]
            if i in ev:
                m = np.zeros(int(net.cards[i]))
                m[ev[i]] = 1.0
                result[n] = m
            else:
                result[n] = out[i]
        return Marginals(
            result,
            kind,
            max(t.max_size for t in trees) if trees else 1,  # type: ignore[union-attr]
            sum(t.total_size for t in trees),  # type: ignore[union-attr]
            compiled,
        )

    # --- compilation --------------------------------------------------------------------
    def _compile(
        self, observed: frozenset[int], queries: tuple[int, ...], engine: str
    ) -> tuple[str, object]:
        self.compiles += 1
        if not queries:
            return "ve", []
        if engine == "ve" or (engine == "auto" and len(queries) <= _HANDFUL):
            return "ve", [
                self._group_tree(observed, f, qs) for f, qs in self._groups(observed, queries)
            ]
        net = self._net
        pr = requisite(net, queries, observed)
        scopes = [self._scope(n, observed) for n in pr.factors]
        tri = triangulate(scopes, net.cards, pr.hidden, self.restarts)
        if engine == "jt" or tri.total_size <= _SMALL_TREE:
            return "jt", compile_tree(net, pr.factors, observed, tri, self.max_table_size)
        jt = compile_tree(net, pr.factors, observed, tri, np.inf)
        jt_cost = _JT_UNIT * jt.calibrate_cost() + _CLIQUE_OVERHEAD * len(jt.cliques)
        if tri.max_size > self.max_table_size:
            jt_cost = np.inf
        groups = self._groups(observed, queries)
        # stratified sample: groups sorted by size, evenly spaced picks, each standing
        # for its share of the groups
        groups.sort(key=lambda g: -len(g[0]))
        picks = sorted({int(k) for k in np.linspace(0, len(groups) - 1, _SAMPLE)})
        try:
            costs = [self._group_cost(self._group_tree(observed, *groups[i])) for i in picks]
            ve_cost = float(np.mean(costs)) * len(groups)
        except MemoryLimitError:
            ve_cost = np.inf
        if ve_cost == np.inf and jt_cost == np.inf:  # raise the guard's error, naming the clique
            compile_tree(net, pr.factors, observed, tri, self.max_table_size)
        if jt_cost <= ve_cost:
            return "jt", jt
        return "ve", [self._group_tree(observed, f, qs) for f, qs in groups]

    def _scope(self, n: int, observed: frozenset[int]) -> tuple[int, ...]:
        return tuple(v for v in (*self._net.parents[n], n) if v not in observed)

    def _groups(
        self, observed: frozenset[int], queries: tuple[int, ...]
    ) -> list[tuple[tuple[int, ...], tuple[int, ...]]]:
        """Queries grouped by their requisite factor set (one tree answers a group)."""
        groups: dict[tuple[int, ...], list[int]] = {}
        for q in queries:
            groups.setdefault(requisite(self._net, (q,), observed).factors, []).append(q)
        return [(f, tuple(qs)) for f, qs in groups.items()]

    @staticmethod
    def _group_cost(group: tuple[tuple[int, ...], CliqueTree]) -> float:
        """Predicted work of one group: a calibration, or one collect to the query."""
        queries, tree = group
        overhead = _CLIQUE_OVERHEAD * (len(tree.cliques) + 4)
        if len(queries) > 1:
            return _JT_UNIT * tree.calibrate_cost() + overhead
        return tree.collect_cost(tree.home[queries[0]]) + overhead

    def _group_tree(
        self, observed: frozenset[int], factors: tuple[int, ...], queries: tuple[int, ...]
    ) -> tuple[tuple[int, ...], CliqueTree]:
        """The tree over ``factors`` for ``queries``: rooted at the query's clique for one
        (variable elimination, collect only), calibrated for several."""
        root = queries[0] if len(queries) == 1 else None
        key = (observed, factors, root)
        tree = self._ve.get(key)
        if tree is None:
            net = self._net
            scopes = [self._scope(n, observed) for n in factors]
            tri_key = (observed, factors)
            tri = self._tri.get(tri_key)
            if tri is None:
                hidden = {v for sc in scopes for v in sc}
                tri = self._tri[tri_key] = triangulate(
                    scopes, net.cards, hidden, self.restarts, restart_above=_GROUP_RESTART_ABOVE
                )
            tree = self._ve[key] = compile_tree(
                net, factors, observed, tri, self.max_table_size, root_var=root
            )
        return queries, tree

    # --- running ------------------------------------------------------------------------
    def _check_constants(self, ev: Mapping[int, int]) -> None:
        """CPDs whose every variable is observed are constants: zero is impossible evidence."""
        net = self._net
        for n in ev:
            scope = (*net.parents[n], n)
            if all(v in ev for v in scope) and self._tables[n][tuple(ev[v] for v in scope)] <= 0:
                raise EvidenceError(
                    f"the evidence has probability zero: P({net.names[n]} | parents) = 0"
                )

    def _run_ve(
        self, groups: list[tuple[tuple[int, ...], CliqueTree]], ev: Mapping[int, int]
    ) -> dict[int, np.ndarray]:
        out = {}
        for queries, tree in groups:
            if len(queries) > 1:
                pots = tree.calibrate(self._tables, ev)
                out.update((q, tree.marginal(pots, q)) for q in queries)
                continue
            q = queries[0]
            root = tree.home[q]  # the tree is rooted at q's clique
            table = tree.collect(root, self._tables, ev)
            m = np.einsum(table, tuple(range(table.ndim)), (tree.cliques[root].index(q),))
            z = m.sum()
            if not z > 0:
                raise EvidenceError("the evidence has probability zero")
            out[q] = m / z
        return out

    def _run_jt(self, tree: CliqueTree, ev: Mapping[int, int]) -> dict[int, np.ndarray]:
        pots = tree.calibrate(self._tables, ev)
        return {v: tree.marginal(pots, v) for v in tree.home}


#: bounded: an engine refers to its net (a weak-key cache would keep every net alive)
_ENGINES: ModelCache[ExactInference] = ModelCache(maxsize=8)


def posterior_marginals(
    bn: BayesNet,
    evidence: Mapping[str, int | str] | None = None,
    nodes: Iterable[str] | None = None,
    engine: str = "auto",
) -> Marginals:
    """:meth:`ExactInference.marginals` on a per-net engine kept for the last few nets
    used (:class:`inference.model_cache.ModelCache`), so that repeated calls on one net
    reuse its compiled trees. A pgmpy model is converted at each call, not kept (a change
    to it would not be seen)."""
    if from_package(bn, "pgmpy"):
        return ExactInference(bn).marginals(evidence, nodes, engine)
    inf = _ENGINES.get(bn, lambda: ExactInference(bn))
    return inf.marginals(evidence, nodes, engine)
