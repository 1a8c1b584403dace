r"""Boyen-Koller assumed-density filtering for discrete two-slice DBNs.

The belief over the interface (the variables with a child in the next slice) is kept as a
product of cluster marginals, :math:`\tilde p(I_{t-1}) = \prod_c \beta_c(C_{c,t-1})`. One
step propagates this product *exactly* through the transition template and the slice's
evidence, and projects the result back onto the clusters; the KL projection
:math:`\arg\min_q KL(p \| \prod_c q_c)` of a discrete distribution onto a product of
disjoint clusters is the product of its cluster marginals (seed 002, section 1.2.2):

.. math::

    \beta_c(C_{c,t}) \propto \sum_{\text{rest}} \prod_{c'} \beta_{c'}(C_{c',t-1})
    \prod_{v \in \text{slice } t} P(x_{v,t} \mid \mathrm{pa}(x_{v,t})) \lambda_{v,t}(x_{v,t}),

and the one-step log-likelihood is the log of the same sum over everything. The sum is
never formed over the joint: :class:`inference.adf.slice_plan.SlicePlan` compiles, once,
a tree of small cliques over the factors (previous cluster beliefs, CPDs, evidence
likelihoods; a variable of the slice that is neither in the interface nor queried and has
no child in the slice, typically an observation, is first reduced to a likelihood over its
parents), and each step is one pass of messages up and down that tree. For the coupled
chains of :func:`dbn.examples.coupled_chains` with one cluster per chain every clique holds
at most three binary variables, so a step costs time linear in the number of chains.

With one cluster holding the whole interface the filter is exact. Boyen and Koller (1998)
show the projection error stays bounded over time when the process mixes (errors
contract); the tests measure it against :class:`inference.exact.dbn_filter.DBNFilter`.

Automatic clusters (``clusters=None``): interface variables joined by an intra-slice edge
(in either slice's template), directly or through hidden variables of the slice, share a
cluster; edges through slice *leaves* (variables outside the interface without children
in the slice, e.g. observations) do not join. For :func:`dbn.examples.coupled_chains` this
gives one cluster per chain.

API: :class:`BoyenKoller` (``init`` / ``step``, pure, :class:`BKState`) and
:func:`bk_filter` (columnar evidence, returns :class:`inference.results.DBNFilterResult`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import NamedTuple

import networkx as nx
import numpy as np
from numpy.typing import ArrayLike

from dbn.bayesnet import BayesNet, check_likelihood
from dbn.dbn import TwoSliceDBN, check_two_slice, prev, unprev
from dbn.errors import EvidenceError, ModelError, UnknownEvidenceError, UnknownVariableError
from dbn.variables import DiscreteVariable
from inference.adf.slice_plan import SlicePlan
from inference.evidence_columns import check_columns, check_query, slice_states
from inference.results import DBNFilterResult

__all__ = ["BKState", "BoyenKoller", "bk_filter", "auto_clusters"]


class BKState(NamedTuple):
    """Boyen-Koller belief after slice ``t``.

    Attributes
    ----------
    t : int
        Last slice absorbed (0 after ``init``).
    beliefs : tuple of ndarray
        One per cluster, shape ``(cardinalities of the cluster's variables)``, sums to 1.
    marginals : dict name -> ndarray (cardinality,)
        Filtered marginals of the queried variables outside the interface at slice ``t``.
    log_likelihood : float
        Running ``log p~(e_{0:t})`` (exact with one cluster).
    step_log_likelihood : float
        ``log p~(e_t | e_{0:t-1})`` of the last step.
    """

    t: int
    beliefs: tuple[np.ndarray, ...]
    marginals: dict[str, np.ndarray]
    log_likelihood: float
    step_log_likelihood: float


def _leaves(net: BayesNet, names: Sequence[str], interface: Sequence[str]) -> set[str]:
    """Slice variables outside the interface with no child in the slice."""
    return {v for v in names if v not in interface and not net.children(v)}


def auto_clusters(dbn: TwoSliceDBN) -> tuple[tuple[str, ...], ...]:
    """The automatic clusters of ``dbn`` (rule in the module docstring)."""
    g = nx.Graph()
    g.add_nodes_from(dbn.names)
    for net in (dbn.initial_net, dbn.transition_net):
        leaves = _leaves(net, dbn.names, dbn.interface)
        for v in dbn.names:
            for p in net.parents(v):
                if p in g and v not in leaves and p not in leaves:
                    g.add_edge(p, v)
    order = {n: i for i, n in enumerate(dbn.interface)}
    out = []
    for comp in nx.connected_components(g):
        members = sorted((v for v in comp if v in order), key=order.__getitem__)
        if members:
            out.append(tuple(members))
    return tuple(sorted(out, key=lambda c: order[c[0]]))


def _check_clusters(dbn: TwoSliceDBN, clusters) -> tuple[tuple[str, ...], ...]:
    if isinstance(clusters, str) or not isinstance(clusters, Sequence):
        raise ModelError(f"clusters must be a sequence of sequences of names, got {clusters!r}")
    out, seen = [], {}
    for k, c in enumerate(clusters):
        c = (c,) if isinstance(c, str) else tuple(c)
        if not c:
            raise ModelError(f"cluster {k} is empty")
        for v in c:
            if v not in dbn.names:
                raise UnknownVariableError(f"cluster {k} names unknown variable {v!r}")
            if v not in dbn.interface:
                raise ModelError(f"cluster {k}: {v!r} is not an interface variable {dbn.interface}")
            if v in seen:
                raise ModelError(f"{v!r} is in clusters {seen[v]} and {k}: clusters are disjoint")
            seen[v] = k
        out.append(c)
    missing = [v for v in dbn.interface if v not in seen]
    if missing:
        raise ModelError(
            f"clusters do not cover the interface: {missing} belong to no cluster "
            f"(interface {dbn.interface})"
        )
    return tuple(out)


class _SliceSpec(NamedTuple):
    """How one slice's factors are built: plan and per-variable recipe."""

    plan: SlicePlan
    tables: tuple[np.ndarray, ...]  # per slice variable, CPD table (*parents, K)
    absorbed: tuple[bool, ...]  # reduced to a likelihood over its parents


class BoyenKoller:
    """Boyen-Koller filter of a discrete :class:`~dbn.dbn.TwoSliceDBN`, compiled once.

    Parameters
    ----------
    dbn : TwoSliceDBN
        All variables discrete.
    clusters : sequence of sequence of str, optional
        Disjoint sets of interface variables covering the interface; default
        :func:`auto_clusters`.
    query : sequence of str, optional
        Variables outside the interface whose marginals the state should carry.

    Raises
    ------
    ModelError
        A continuous variable; clusters that are not disjoint, name a non-interface
        variable or miss one (the message names them); a clique too large.
    UnknownVariableError
        A cluster or the query names an unknown variable.
    """

    def __init__(
        self,
        dbn: TwoSliceDBN,
        clusters: Sequence[Sequence[str]] | None = None,
        query: Sequence[str] | None = None,
    ) -> None:
        check_two_slice(dbn, "Boyen-Koller")
        for v in dbn.variables:
            if not isinstance(v, DiscreteVariable):
                raise ModelError(
                    f"variable {v.name!r} is continuous: Boyen-Koller needs a discrete DBN "
                    "(use the particle or Rao-Blackwellised particle filter)"
                )
        self.dbn = dbn
        self.cards = {v.name: v.cardinality for v in dbn.variables}
        self.clusters = auto_clusters(dbn) if clusters is None else _check_clusters(dbn, clusters)
        self.extra = tuple(q for q in check_query(dbn, query, ()) if q not in dbn.interface)
        self._cluster_of = {v: (k, c.index(v)) for k, c in enumerate(self.clusters) for v in c}
        self._initial = self._spec(dbn.initial_net, first=True)
        self._transition = self._spec(dbn.transition_net, first=False)

    def __repr__(self) -> str:
        return f"BoyenKoller(clusters={[list(c) for c in self.clusters]})"

    def _spec(self, net: BayesNet, first: bool) -> _SliceSpec:
        names = self.dbn.names
        keep = set(self.dbn.interface) | set(self.extra)
        leaves = _leaves(net, names, tuple(keep))
        scopes = [] if first else [tuple(prev(v) for v in c) for c in self.clusters]
        absorbed = tuple(v in leaves for v in names)
        for v, a in zip(names, absorbed):
            pa = net.parents(v)
            scopes.append(tuple(pa) if a else (*pa, v))
        cards = {u: self.cards[unprev(u)] for s in scopes for u in s}
        targets = [*self.clusters, *((q,) for q in self.extra)]
        plan = SlicePlan(cards, scopes, targets)
        tables = tuple(net.table(v) for v in names)
        return _SliceSpec(plan, tables, absorbed)

    @property
    def max_clique_size(self) -> int:
        """Entries of the largest clique table of a step (the cost bound)."""
        return max(self._initial.plan.max_clique_size, self._transition.plan.max_clique_size)

    # --- evidence -----------------------------------------------------------------------
    def _lambdas(
        self, evidence: Mapping[str, int | str] | None, soft: Mapping[str, ArrayLike] | None
    ) -> dict[str, np.ndarray]:
        """Per-variable likelihood vectors of one slice (validated, nothing changed)."""
        lam: dict[str, np.ndarray] = {}
        variables = {v.name: v for v in self.dbn.variables}
        for name, state in slice_states(variables, evidence).items():
            lam[name] = np.eye(self.cards[name])[state]
        for name, vec in (soft or {}).items():
            if name not in variables:
                raise UnknownEvidenceError(f"soft evidence on unknown variable {name!r}")
            v = check_likelihood(name, self.cards[name], vec)
            lam[name] = lam[name] * v if name in lam else v
        return lam

    def _absorb(
        self, spec: _SliceSpec, beliefs: tuple[np.ndarray, ...], lam: Mapping[str, np.ndarray]
    ) -> tuple[tuple[np.ndarray, ...], dict[str, np.ndarray], float]:
        factors = list(beliefs)
        for v, table, absorbed in zip(self.dbn.names, spec.tables, spec.absorbed):
            vec = lam.get(v)
            if absorbed:
                factors.append(table.sum(axis=-1) if vec is None else table @ vec)
            else:
                factors.append(table if vec is None else table * vec)
        margs, log_z = spec.plan.run(factors)
        if not np.isfinite(log_z):
            raise EvidenceError("the evidence of this slice has probability zero given the past")
        m = len(self.clusters)
        return tuple(margs[:m]), dict(zip(self.extra, (a for a in margs[m:]))), log_z

    # --- on-line filtering --------------------------------------------------------------
    def init(
        self,
        evidence: Mapping[str, int | str] | None = None,
        soft_evidence: Mapping[str, ArrayLike] | None = None,
    ) -> BKState:
        """Absorb slice 0 (hard evidence: name -> state, ``-1`` or None = unobserved)."""
        beliefs, extra, log_z = self._absorb(
            self._initial, (), self._lambdas(evidence, soft_evidence)
        )
        return BKState(0, beliefs, extra, log_z, log_z)

    def step(
        self,
        state: BKState,
        evidence: Mapping[str, int | str] | None = None,
        soft_evidence: Mapping[str, ArrayLike] | None = None,
    ) -> BKState:
        """Absorb the next slice; returns a new state (``state`` is left as it was).

        Raises
        ------
        EvidenceError
            Bad evidence, or evidence of probability zero under the approximate belief.
        """
        beliefs, extra, log_z = self._absorb(
            self._transition, state.beliefs, self._lambdas(evidence, soft_evidence)
        )
        return BKState(state.t + 1, beliefs, extra, state.log_likelihood + log_z, log_z)

    def marginal(self, state: BKState, name: str) -> np.ndarray:
        """Filtered marginal of ``name`` (an interface or a queried variable)."""
        if name in self._cluster_of:
            k, axis = self._cluster_of[name]
            b = state.beliefs[k]
            return b.sum(axis=tuple(a for a in range(b.ndim) if a != axis))
        if name in state.marginals:
            return state.marginals[name]
        raise UnknownVariableError(
            f"{name!r} is neither an interface variable {self.dbn.interface} nor queried"
        )


def bk_filter(
    dbn: TwoSliceDBN,
    evidence: Mapping[str, ArrayLike],
    query: Sequence[str] | None = None,
    *,
    clusters: Sequence[Sequence[str]] | None = None,
    soft_evidence: Mapping[str, ArrayLike] | None = None,
) -> DBNFilterResult:
    """Boyen-Koller filtering of a whole sequence.

    Parameters
    ----------
    dbn : TwoSliceDBN
        Discrete.
    evidence : mapping name -> array (num_timesteps,)
        Observed states, ``-1`` = unobserved (or state names, None = unobserved).
    query : sequence of str, optional
        Variables whose marginals are returned (default: every variable without an
        evidence column).
    clusters : sequence of sequence of str, optional
        Default :func:`auto_clusters`.
    soft_evidence : mapping name -> array (num_timesteps, cardinality), optional
        Likelihood vectors per slice.

    Returns
    -------
    DBNFilterResult
        ``method="bk"``; ``info`` holds ``clusters`` and ``max_clique_size``.
    """
    check_two_slice(dbn, "Boyen-Koller")
    cols = check_columns(dbn, evidence, soft_evidence)
    hidden = tuple(n for n in dbn.names if n not in cols.discrete and n not in cols.continuous)
    query = check_query(dbn, query, hidden)
    bk = BoyenKoller(dbn, clusters, query=query)
    T = cols.num_timesteps
    out = {q: np.empty((T, bk.cards[q])) for q in query}
    lls = np.empty(T)
    state = None
    for t in range(T):
        ev = {n: int(c[t]) for n, c in cols.discrete.items() if c[t] >= 0}
        soft = {n: c[t] for n, c in cols.soft.items()}
        spec = bk._initial if t == 0 else bk._transition
        try:
            lam = bk._lambdas(ev, soft)
            beliefs, extra, log_z = bk._absorb(spec, () if t == 0 else state.beliefs, lam)
        except EvidenceError as exc:
            raise EvidenceError(f"slice {t}: {exc}") from None
        state = BKState(t, beliefs, extra, 0.0, log_z)
        lls[t] = log_z
        for q in query:
            out[q][t] = bk.marginal(state, q)
    info = {"clusters": [list(c) for c in bk.clusters], "max_clique_size": bk.max_clique_size}
    return DBNFilterResult(marginals=out, log_likelihoods=lls, method="bk", info=info)
