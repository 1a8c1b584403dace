"""A Bayes net: variables, one CPD each, on a networkx DAG, validated at construction."""

from __future__ import annotations

import heapq
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import networkx as nx
import numpy as np
from numpy.typing import ArrayLike

from dbn.checks import (
    check_mapping,
    check_size,
    evidence_mapping,
    evidence_state,
    from_package,
    make_rng,
    real_array,
)
from dbn.cpds import ContinuousCPD, DeterministicCPD, LinearGaussianCPD, TabularCPD
from dbn.errors import (
    CPDShapeError,
    CycleError,
    DuplicateNameError,
    EvidenceError,
    ModelError,
    UnknownVariableError,
)
from dbn.variables import ContinuousVariable, DiscreteVariable, Variable

__all__ = ["BayesNet", "CPD", "check_discrete_net", "check_evidence", "check_sequence"]

CPD = TabularCPD | DeterministicCPD | LinearGaussianCPD | ContinuousCPD


def check_sequence(what: str, items: Any) -> list:
    """``items`` as a list; a string, None or another non-iterable is a :class:`ModelError`."""
    if isinstance(items, str) or not isinstance(items, Iterable):
        raise ModelError(f"{what} must be a sequence, got {items!r}")
    return list(items)


def _index_variables(variables: Sequence[Variable]) -> dict[str, Variable]:
    """Name -> variable, in declaration order; names unique."""
    vars_: dict[str, Variable] = {}
    for v in check_sequence("variables", variables):
        if not isinstance(v, DiscreteVariable | ContinuousVariable):
            raise ModelError(f"not a variable: {v!r}")
        if v.name in vars_:
            raise DuplicateNameError(f"two variables are named {v.name!r}")
        vars_[v.name] = v
    return vars_


def _index_cpds(cpds: Sequence[CPD], vars_: Mapping[str, Variable]) -> dict[str, CPD]:
    """Name -> CPD: exactly one CPD per declared variable."""
    cpd_map: dict[str, CPD] = {}
    for c in check_sequence("cpds", cpds):
        name = getattr(c, "variable", None)
        if name not in vars_:
            raise UnknownVariableError(f"CPD for unknown variable {name!r}")
        if name in cpd_map:
            raise DuplicateNameError(f"two CPDs are given for variable {name!r}")
        cpd_map[name] = c
    missing = [n for n in vars_ if n not in cpd_map]
    if missing:
        raise ModelError(f"no CPD for variable(s) {missing}")
    return cpd_map


def _acyclic_graph(vars_: Mapping[str, Variable], cpd_map: Mapping[str, CPD]) -> nx.DiGraph:
    """The DAG parent -> child of the CPDs' parents (known names, no directed cycle)."""
    graph = nx.DiGraph()
    graph.add_nodes_from(vars_)
    for name, c in cpd_map.items():
        for p in c.parents:
            if p not in vars_:
                raise UnknownVariableError(f"CPD of {name!r}: unknown parent {p!r}")
            graph.add_edge(p, name)
    if nx.is_directed_acyclic_graph(graph):  # the common case, without building a cycle
        return graph
    cycle = nx.find_cycle(graph)
    path = " -> ".join([u for u, _ in cycle] + [cycle[0][0]])
    raise CycleError(f"the graph has a directed cycle: {path}")


def _lexicographic_order(graph: nx.DiGraph) -> tuple[str, ...]:
    """The topological order of a DAG that takes the smallest name among the nodes whose
    parents are all placed (Kahn's algorithm with a heap): the order of networkx's
    ``lexicographical_topological_sort``, without its per-node bookkeeping."""
    indegree = {n: d for n, d in graph.in_degree()}
    ready = [n for n, d in indegree.items() if d == 0]
    heapq.heapify(ready)
    order = []
    while ready:
        n = heapq.heappop(ready)
        order.append(n)
        for c in graph.successors(n):
            indegree[c] -= 1
            if indegree[c] == 0:
                heapq.heappush(ready, c)
    return tuple(order)


def _tables(vars_: Mapping[str, Variable], cpd_map: Mapping[str, CPD]) -> dict[str, np.ndarray]:
    """The read-only dense table of every discrete variable's CPD, after checking that
    CPD kinds fit their variables (discrete: tabular or deterministic with discrete
    parents; continuous: neither, and a linear-Gaussian CPD of the variable's dimension)."""
    tables: dict[str, np.ndarray] = {}
    for name, c in cpd_map.items():
        v = vars_[name]
        if isinstance(v, DiscreteVariable):
            if not isinstance(c, TabularCPD | DeterministicCPD):
                raise ModelError(
                    f"discrete variable {name!r} needs a TabularCPD or DeterministicCPD, "
                    f"got {type(c).__name__}"
                )
            for p in c.parents:
                if not isinstance(vars_[p], DiscreteVariable):
                    raise ModelError(f"discrete variable {name!r} has a continuous parent {p!r}")
            pcards = [vars_[p].cardinality for p in c.parents]  # type: ignore[union-attr]
            table = np.asarray(c.to_table(pcards, v.cardinality), dtype=np.float64)
            table.setflags(write=False)
            tables[name] = table
        elif isinstance(c, TabularCPD | DeterministicCPD):
            raise ModelError(f"continuous variable {name!r} has a discrete CPD")
        elif isinstance(c, LinearGaussianCPD) and c.dim != v.dim:
            raise CPDShapeError(
                f"CPD of {name!r}: dimension {c.dim}, but the variable has dim {v.dim}"
            )
    return tables


class BayesNet:
    """A Bayes net on a directed acyclic graph.

    Parameters
    ----------
    variables : sequence of DiscreteVariable or ContinuousVariable
        Names must be unique.
    cpds : sequence of CPD
        Exactly one per variable; the CPD's parents define the edges.

    Raises
    ------
    DuplicateNameError, UnknownVariableError, CycleError, CPDShapeError, ModelError
        Each naming the node and the value at fault. A discrete child must have discrete
        parents and a tabular or deterministic CPD whose table has the shape
        ``(*parent_cardinalities, cardinality)``.

    Notes
    -----
    The object is immutable: ``tables`` (the dense table of every discrete CPD, including
    the 0/1 tables of deterministic CPDs) is computed once here.
    """

    def __init__(self, variables: Sequence[Variable], cpds: Sequence[CPD]) -> None:
        vars_ = _index_variables(variables)
        cpd_map = _index_cpds(cpds, vars_)
        graph = _acyclic_graph(vars_, cpd_map)
        tables = _tables(vars_, cpd_map)
        self._variables = vars_
        self._cpds = cpd_map
        self._graph = graph
        self._tables = tables
        self._order = _lexicographic_order(graph)

    # --- read-only views ----------------------------------------------------------------
    @property
    def variables(self) -> Mapping[str, Variable]:
        """Name -> variable, in declaration order."""
        return dict(self._variables)

    @property
    def cpds(self) -> Mapping[str, CPD]:
        """Name -> CPD."""
        return dict(self._cpds)

    @property
    def graph(self) -> nx.DiGraph:
        """A copy of the DAG (edges parent -> child)."""
        return self._graph.copy()

    @property
    def nodes(self) -> tuple[str, ...]:
        return tuple(self._variables)

    @property
    def is_discrete(self) -> bool:
        """True when every variable is discrete (exact engines need this)."""
        return all(isinstance(v, DiscreteVariable) for v in self._variables.values())

    def __contains__(self, name: object) -> bool:
        return name in self._variables

    def __len__(self) -> int:
        return len(self._variables)

    def __repr__(self) -> str:
        return f"BayesNet({len(self)} variables, {self._graph.number_of_edges()} edges)"

    def variable(self, name: str) -> Variable:
        try:
            return self._variables[name]
        except KeyError:
            raise UnknownVariableError(f"unknown variable {name!r}") from None

    def cpd(self, name: str) -> CPD:
        self.variable(name)
        return self._cpds[name]

    def parents(self, name: str) -> tuple[str, ...]:
        return tuple(self.cpd(name).parents)

    def children(self, name: str) -> tuple[str, ...]:
        self.variable(name)
        return tuple(self._graph.successors(name))

    def cardinality(self, name: str) -> int:
        v = self.variable(name)
        if not isinstance(v, DiscreteVariable):
            raise ModelError(f"variable {name!r} is continuous: it has no cardinality")
        return v.cardinality

    def table(self, name: str) -> np.ndarray:
        """Dense table ``(*parent_cardinalities, cardinality)`` of a discrete node (read-only)."""
        self.variable(name)
        try:
            return self._tables[name]
        except KeyError:
            raise ModelError(f"variable {name!r} is continuous: it has no table") from None

    def topological_order(self) -> tuple[str, ...]:
        """Parents before children (ties broken by name, so the order is reproducible)."""
        return self._order

    # --- sampling and joint probability ---------------------------------------------------
    def log_joint(self, assignment: Mapping[str, int | str]) -> float:
        """``log P(x)`` of a full assignment of a discrete net (states by index or name)."""
        if not self.is_discrete:
            raise ModelError("log_joint needs a discrete net")
        check_mapping("assignment", assignment)  # a list of pairs raised AttributeError
        x = {n: self.variable(n).index(s) for n, s in (assignment or {}).items()}  # type: ignore[union-attr]
        missing = [n for n in self._variables if n not in x]
        if missing:
            raise EvidenceError(f"assignment misses variable(s) {missing}")
        total = 0.0
        with np.errstate(divide="ignore"):
            for n in self._variables:
                idx = tuple(x[p] for p in self._cpds[n].parents) + (x[n],)
                total += float(np.log(self._tables[n][idx]))
        return total

    def sample(self, rng: np.random.Generator | int, num_samples: int) -> dict[str, np.ndarray]:
        """Ancestral samples of a discrete net: name -> int array of shape ``(num_samples,)``.

        ``rng`` is a numpy ``Generator`` or an int seed (``np.random.default_rng(seed)``);
        ``num_samples >= 0``. Anything else is an :class:`InputError` naming it."""
        if not self.is_discrete:
            raise ModelError("sample needs a discrete net")
        rng = make_rng(rng, "rng")
        num_samples = check_size("num_samples", num_samples)
        out: dict[str, np.ndarray] = {}
        for n in self._order:
            table = self._tables[n]
            rows = (
                table[tuple(out[p] for p in self._cpds[n].parents)]
                if self._cpds[n].parents
                else np.broadcast_to(table, (num_samples, table.shape[-1]))
            )
            u = rng.random(num_samples)[:, None]
            out[n] = np.minimum((np.cumsum(rows, axis=-1) < u).sum(axis=-1), table.shape[-1] - 1)
        return out


def check_discrete_net(bn: Any, what: str) -> None:
    """Raise :class:`ModelError` unless ``bn`` is a discrete :class:`BayesNet`; ``what``
    (e.g. "a junction tree") needs it. A pgmpy model (or anything else) raised Python's
    ``AttributeError``; the message says how to convert one."""
    if not isinstance(bn, BayesNet):
        how = (" (convert a pgmpy model with dbn.pgmpy_adapter.from_pgmpy)"
               if from_package(bn, "pgmpy") else "")
        raise ModelError(f"{what} needs a dbn BayesNet, got {type(bn).__name__}{how}")
    if not bn.is_discrete:
        raise ModelError(f"{what} needs a discrete Bayes net (all variables discrete)")


def check_evidence(
    bn: BayesNet,
    evidence: Mapping[str, int | str] | None = None,
    soft_evidence: Mapping[str, ArrayLike] | None = None,
) -> tuple[dict[str, int], dict[str, np.ndarray]]:
    """Validate hard and soft (virtual) evidence against a discrete net.

    Parameters
    ----------
    evidence : mapping name -> state index or state name, optional
        Hard evidence ``X = x``; ``None``, ``-1``, NaN or pandas' ``NA`` = unobserved, a
        whole-number float an index, as a DBN slice reads them
        (:func:`dbn.checks.evidence_state`); or a pandas ``Series`` (a case of a
        ``DataFrame``).
    soft_evidence : mapping name -> array_like of shape ``(cardinality,)``, optional
        Virtual evidence: a likelihood ``lambda(x) = p(observation | X = x)`` per state,
        nonnegative, finite and not all zero (its scale does not matter for posteriors but
        enters the log evidence).

    Returns
    -------
    hard : dict name -> int
    soft : dict name -> float array (cardinality,)

    Raises
    ------
    EvidenceError
        Unknown variable, state out of range, wrong length, negative/NaN/all-zero vector.
    """
    evidence = evidence_mapping(evidence)
    check_mapping("evidence", evidence)
    check_mapping("soft evidence", soft_evidence)
    hard: dict[str, int] = {}
    for name, state in (evidence or {}).items():
        if name not in bn:
            raise EvidenceError(f"evidence on unknown variable {name!r}")
        v = bn.variable(name)
        if not isinstance(v, DiscreteVariable):
            raise EvidenceError(
                f"hard evidence on continuous variable {name!r} is not supported here"
            )
        state = evidence_state(state)
        if state is not None:
            hard[name] = v.index(state)
    soft: dict[str, np.ndarray] = {}
    for name, lik in (soft_evidence or {}).items():
        if name not in bn:
            raise EvidenceError(f"soft evidence on unknown variable {name!r}")
        soft[name] = check_likelihood(name, bn.cardinality(name), lik)
    return hard, soft


def check_likelihood(name: str, cardinality: int, lik: Any) -> np.ndarray:
    """A validated virtual-evidence vector of shape ``(cardinality,)``."""
    arr = real_array(f"soft evidence on {name!r}", lik, EvidenceError)
    if arr.shape != (cardinality,):
        raise EvidenceError(
            f"soft evidence on {name!r} has shape {arr.shape}, expected ({cardinality},)"
        )
    if not (np.isfinite(arr).all() and arr.min() >= 0):  # methods: no dispatch wrapper
        raise EvidenceError(f"soft evidence on {name!r} must be finite and nonnegative, got {arr}")
    if not arr.max() > 0:
        raise EvidenceError(f"soft evidence on {name!r} is all zero")
    return arr
