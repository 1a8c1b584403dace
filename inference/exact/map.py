"""Most probable explanation (MAP over all unobserved variables) by max-product."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from numpy.typing import ArrayLike

from dbn.bayesnet import BayesNet
from dbn.errors import EvidenceError
from inference.exact.graph import elimination_order, interaction_graph
from inference.exact.variable_elimination import eliminate, evidence_factors

__all__ = ["map_assignment"]


def map_assignment(
    bn: BayesNet,
    evidence: Mapping[str, int | str] | None = None,
    soft_evidence: Mapping[str, ArrayLike] | None = None,
    heuristic: str = "min_fill",
) -> tuple[dict[str, int], float]:
    """The most probable configuration of every unobserved variable.

    .. math:: x^* = \\arg\\max_x P(x, e) \\prod_v \\lambda_v(x_v)

    by max-product variable elimination, then a traceback in reverse elimination order
    (each eliminated variable takes its argmax given the variables eliminated after it).

    Returns
    -------
    assignment : dict name -> state index
        Every variable not in ``evidence``. Ties are broken towards the lowest index.
    log_prob : float
        ``log P(x*, e) + sum_v log lambda_v(x*_v)``.

    Raises
    ------
    EvidenceError
        The evidence has probability zero.
    """
    factors, hard = evidence_factors(bn, evidence, soft_evidence)
    cards = {n: bn.cardinality(n) for n in bn.nodes}
    hidden = [n for n in bn.nodes if n not in hard]
    graph = interaction_graph(f.variables for f in factors)
    graph.add_nodes_from(hidden)
    order = elimination_order(graph, cards, hidden, heuristic)
    remaining, trace = eliminate(factors, order, "max")
    log_prob = float(np.sum([f.log_values for f in remaining]))
    if not np.isfinite(log_prob):
        raise EvidenceError("the evidence has probability zero: no MAP configuration")
    assignment: dict[str, int] = {}
    for var, combined in reversed(trace):
        index = tuple(slice(None) if v == var else assignment[v] for v in combined.variables)
        assignment[var] = int(np.argmax(combined.log_values[index]))
    for n in hidden:  # a hidden variable in no factor cannot occur in a BN, but be total
        assignment.setdefault(n, 0)
    return {n: assignment[n] for n in bn.nodes if n in assignment}, log_prob
