"""Sum-product variable elimination (queries) and the log evidence.

Every engine in this package turns a discrete :class:`~dbn.bayesnet.BayesNet` and its
evidence into log-space factors the same way, with :func:`evidence_factors`.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence

import numpy as np
from numpy.typing import ArrayLike

from dbn.bayesnet import BayesNet, check_discrete_net, check_evidence
from dbn.errors import EvidenceError, InputError, ModelError, UnknownVariableError
from inference.exact.factor import Factor, product
from inference.exact.graph import elimination_order, interaction_graph
from inference.exact.pruning import barren, net_index, requisite

__all__ = ["evidence_factors", "variable_elimination", "log_evidence", "eliminate"]


def evidence_factors(
    bn: BayesNet,
    evidence: Mapping[str, int | str] | None = None,
    soft_evidence: Mapping[str, ArrayLike] | None = None,
) -> tuple[list[Factor], dict[str, int]]:
    """The CPD factors of ``bn`` conditioned on the evidence.

    Returns
    -------
    factors : list of Factor
        One per CPD, with the hard-evidence axes indexed away, plus one factor
        ``log lambda_v`` per soft-evidence variable that is not also hard evidence
        (for those the likelihood of the observed state is a constant factor).
    hard : dict name -> int
        The validated hard evidence.
    """
    check_discrete_net(bn, "exact inference")
    hard, soft = check_evidence(bn, evidence, soft_evidence)
    factors = [Factor.from_table((*bn.parents(n), n), bn.table(n)).reduce(hard) for n in bn.nodes]
    for name, lik in soft.items():
        f = Factor.from_table((name,), lik)
        factors.append(f.reduce(hard))
    return factors, hard


def eliminate(
    factors: list[Factor],
    order: Sequence[str],
    mode: str = "sum",
) -> tuple[list[Factor], list[tuple[str, Factor]]]:
    """Eliminate ``order`` from a factor list (sum- or max-product).

    Returns the remaining factors and, per eliminated variable, the combined factor it was
    eliminated from (max mode uses those for the traceback).
    """
    factors = list(factors)
    trace: list[tuple[str, Factor]] = []
    for var in order:
        touching = [f for f in factors if var in f.variables]
        if not touching:
            continue
        factors = [f for f in factors if var not in f.variables]
        combined = product(touching)
        trace.append((var, combined))
        factors.append(combined.marginalize([var]) if mode == "sum" else combined.maximize([var]))
    return factors, trace


def variable_elimination(
    bn: BayesNet,
    query: Sequence[str],
    evidence: Mapping[str, int | str] | None = None,
    soft_evidence: Mapping[str, ArrayLike] | None = None,
    heuristic: str = "min_fill",
) -> Factor:
    """Posterior joint ``P(query | evidence)`` by variable elimination.

    Parameters
    ----------
    bn : BayesNet
        A discrete net.
    query : sequence of str
        Variables to keep (not hard evidence).
    evidence, soft_evidence
        See :func:`dbn.bayesnet.check_evidence`.
    heuristic : {"min_fill", "min_weight"}
        Elimination order heuristic on the interaction graph of the reduced factors.

    Returns
    -------
    Factor
        Normalised, over ``query`` in the given order.

    Raises
    ------
    EvidenceError
        The evidence has probability zero, or a query variable is observed.
    """
    check_discrete_net(bn, "exact inference")
    if isinstance(query, str):  # one name, as the DBN engines read it
        query = [query]
    if not isinstance(query, Iterable):
        raise InputError(f"query must be a sequence of variable names, got {query!r}")
    query = list(query)
    for q in query:
        if q not in bn:
            raise UnknownVariableError(f"query of unknown variable {q!r}")
    factors, hard = evidence_factors(bn, evidence, soft_evidence)
    clash = [q for q in query if q in hard]
    if clash:
        raise EvidenceError(f"query variable(s) {clash} are observed")
    if len(set(query)) != len(query):
        raise EvidenceError(f"query lists a variable twice: {query}")
    factors = _requisite_factors(bn, factors, query, hard, soft_evidence)
    graph = interaction_graph(f.variables for f in factors)
    cards = {n: bn.cardinality(n) for n in bn.nodes}
    hidden = [n for n in graph.nodes if n not in query]
    order = elimination_order(graph, cards, hidden, heuristic)
    remaining, _ = eliminate(factors, order, "sum")
    joint = product(remaining)
    missing = [q for q in query if q not in joint.variables]
    if missing:  # a query variable in no factor cannot happen in a BN; keep it safe
        raise ModelError(f"query variables {missing} are in no factor")
    return joint.normalize().transpose(query)


def _requisite_factors(
    bn: BayesNet,
    factors: list[Factor],
    query: Sequence[str],
    hard: Mapping[str, int],
    soft_evidence: Mapping[str, ArrayLike] | None,
) -> list[Factor]:
    """The factors ``P(query | evidence)`` needs: barren and d-separated ones dropped (see
    :mod:`inference.exact.pruning`); ``factors`` is :func:`evidence_factors`' list.

    The d-separated, non-barren factors do not change the posterior but their sum is
    ``P(e)`` of their part: it is eliminated (on its own) to check that it is not zero.
    """
    net = net_index(bn)
    soft = [n for n in (soft_evidence or {}) if n not in hard]
    q = [net.index[n] for n in query]
    obs = [net.index[n] for n in hard]
    pr = requisite(net, q, obs, [net.index[n] for n in soft])
    hidden = {net.names[i] for i in pr.hidden}
    soft_factors = list(zip(factors[len(net.names) :], soft_evidence or {}))
    keep = [factors[i] for i in pr.factors]  # the CPD factors come first, in node order
    keep += [f for f, n in soft_factors if n not in hard and n in hidden]
    kept = set(pr.factors)
    ancestral = barren(net, {*q, *obs, *(net.index[n] for n in soft)})
    rest = [factors[i] for i in ancestral if i not in kept]
    rest += [f for f, n in soft_factors if n in hard or n not in hidden]
    if rest:
        graph = interaction_graph(f.variables for f in rest)
        order = elimination_order(graph, {n: bn.cardinality(n) for n in graph.nodes})
        remaining, _ = eliminate(rest, order, "sum")
        if not np.isfinite(np.sum([f.log_normalizer() for f in remaining])):
            raise EvidenceError("the evidence has probability zero")
    return keep


def log_evidence(
    bn: BayesNet,
    evidence: Mapping[str, int | str] | None = None,
    soft_evidence: Mapping[str, ArrayLike] | None = None,
) -> float:
    """``log P(evidence)`` (soft-evidence likelihoods multiplied in): ``-inf`` if impossible."""
    factors, _ = evidence_factors(bn, evidence, soft_evidence)
    graph = interaction_graph(f.variables for f in factors)
    cards = {n: bn.cardinality(n) for n in bn.nodes}
    order = elimination_order(graph, cards)
    remaining, _ = eliminate(factors, order, "sum")
    return float(np.sum([f.log_normalizer() for f in remaining]))
