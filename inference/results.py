"""The one result type of DBN filtering, whatever the method (exact, bk, particle, rbpf).

:func:`inference.filter` returns a :class:`DBNFilterResult`; every method fills the same
fields, so code that reads marginals does not care which engine produced them.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["DBNFilterResult"]


@dataclass(frozen=True)
class DBNFilterResult:
    """Per-slice filtered marginals of the requested variables of a two-slice DBN.

    Attributes
    ----------
    marginals : dict[str, ndarray]
        Discrete variable name -> shape (T, cardinality): ``P(x_t | e_{0:t})`` per slice.
    means : dict[str, ndarray]
        Continuous variable name -> shape (T, dim): filtered mean ``E[x_t | e_{0:t}]``.
    covariances : dict[str, ndarray]
        Continuous variable name -> shape (T, dim, dim): filtered covariance.
    log_likelihoods : ndarray, shape (T,)
        ``log p(e_t | e_{0:t-1})`` per slice (an estimate for the particle methods).
    method : str
        The method that ran: ``"exact"``, ``"bk"``, ``"particle"`` or ``"rbpf"``.
    info : dict
        Method-specific details (the chosen clusters, predicted frontier size, number of
        particles, ESS per slice, why ``auto`` chose what it chose, ...).
    """

    marginals: dict[str, np.ndarray]
    log_likelihoods: np.ndarray
    method: str
    means: dict[str, np.ndarray] = field(default_factory=dict)
    covariances: dict[str, np.ndarray] = field(default_factory=dict)
    info: dict[str, Any] = field(default_factory=dict)

    @property
    def log_likelihood(self) -> float:
        """``log p(e_{0:T-1})``: the sum of the per-slice terms."""
        return float(np.sum(self.log_likelihoods))

    @property
    def num_timesteps(self) -> int:
        """Number of slices ``T``."""
        return int(np.shape(self.log_likelihoods)[0])
