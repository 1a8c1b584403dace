"""Exact inference on discrete Bayes nets and DBNs, in log space.

- :class:`Factor`: log-space factors with value semantics.
- :func:`variable_elimination`, :func:`log_evidence`: sum-product VE (min-fill order).
- :class:`JunctionTree`: every single-node marginal in one calibration.
- :func:`map_assignment`: most probable explanation by max-product with traceback.
- :class:`ExactInference`, :func:`posterior_marginals`: marginals on large nets (pruned
  per-query VE or a pruned junction tree, chosen automatically; compiled trees cached).
- :mod:`inference.exact.enumeration`: the brute-force oracle.
- :mod:`inference.exact.dbn_filter`: forward filter (online ``init``/``step`` and
  vectorised), forward-backward smoother and Viterbi for discrete two-slice DBNs.
"""

from inference.exact.engine import ExactInference, Marginals, posterior_marginals
from inference.exact.factor import Factor, logsumexp, product
from inference.exact.junction_tree import Calibration, JunctionTree, marginals
from inference.exact.map import map_assignment
from inference.exact.variable_elimination import log_evidence, variable_elimination

__all__ = [
    "Calibration",
    "ExactInference",
    "Factor",
    "JunctionTree",
    "log_evidence",
    "logsumexp",
    "map_assignment",
    "Marginals",
    "marginals",
    "posterior_marginals",
    "product",
    "variable_elimination",
]
