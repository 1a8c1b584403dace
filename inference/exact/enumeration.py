"""Brute-force enumeration of the joint: the oracle every exact engine is tested against.

Cost ``prod_v K_v``: meant for nets of a handful of variables.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from numpy.typing import ArrayLike

from dbn.bayesnet import BayesNet, check_discrete_net
from dbn.errors import EvidenceError, ModelError
from inference.exact.factor import Factor, product
from inference.exact.variable_elimination import evidence_factors

__all__ = ["joint_factor", "brute_force_marginals", "brute_force_map", "MAX_JOINT_SIZE"]

MAX_JOINT_SIZE = 2**22
"""Refuse to enumerate joints larger than this many configurations."""


def joint_factor(
    bn: BayesNet,
    evidence: Mapping[str, int | str] | None = None,
    soft_evidence: Mapping[str, ArrayLike] | None = None,
) -> Factor:
    """The unnormalised joint ``P(x, e) prod lambda`` over all unobserved variables,
    axes in ``bn.nodes`` order."""
    check_discrete_net(bn, "enumeration")
    size = float(np.prod([bn.cardinality(n) for n in bn.nodes]))
    if size > MAX_JOINT_SIZE:
        raise ModelError(f"joint of {size:.3g} configurations is too large to enumerate")
    factors, hard = evidence_factors(bn, evidence, soft_evidence)
    return product(factors).transpose([n for n in bn.nodes if n not in hard])


def brute_force_marginals(
    bn: BayesNet,
    evidence: Mapping[str, int | str] | None = None,
    soft_evidence: Mapping[str, ArrayLike] | None = None,
) -> tuple[dict[str, np.ndarray], float]:
    """Every unobserved node's posterior marginal and ``log P(e)`` by enumeration."""
    joint = joint_factor(bn, evidence, soft_evidence)
    logz = joint.log_normalizer()
    if not np.isfinite(logz):
        raise EvidenceError("the evidence has probability zero")
    marg = {v: joint.keep([v]).probabilities() for v in joint.variables}
    return marg, logz


def brute_force_map(
    bn: BayesNet,
    evidence: Mapping[str, int | str] | None = None,
    soft_evidence: Mapping[str, ArrayLike] | None = None,
) -> tuple[dict[str, int], float]:
    """The MAP configuration (lowest flat index among ties) and its log probability."""
    joint = joint_factor(bn, evidence, soft_evidence)
    flat = int(np.argmax(joint.log_values))
    best = float(joint.log_values.reshape(-1)[flat])
    if not np.isfinite(best):
        raise EvidenceError("the evidence has probability zero")
    idx = np.unravel_index(flat, joint.cards)
    return {v: int(i) for v, i in zip(joint.variables, idx)}, best
