r"""Categorical pieces of assumed-density filtering (seed 002, section 1.2.2): the KL
projection of a joint discrete posterior onto a product of marginals is the product of
its marginals; a mixture of categoricals projects to its weighted average."""

from __future__ import annotations

from collections.abc import Sequence

import jax.numpy as jnp
from jax.scipy.special import logsumexp

__all__ = ["normalize_log", "categorical_marginals", "mix_categoricals"]


def normalize_log(logw, axis: int = -1):
    r"""Normalise unnormalised log weights in log space.

    Parameters
    ----------
    logw : (..., num_states) log weights (``-inf`` allowed, not all ``-inf``)

    Returns
    -------
    probs : same shape, summing to 1 along ``axis``
    log_norm : (...) :math:`\log\sum\exp(\mathrm{logw})` (the one-step log likelihood
        when logw are joint log densities)
    """
    log_norm = logsumexp(logw, axis=axis, keepdims=True)
    probs = jnp.exp(logw - log_norm)
    return probs, jnp.squeeze(log_norm, axis=axis)


def categorical_marginals(joint, axes: Sequence[int] | None = None, log: bool = False):
    r"""Marginals of a joint categorical table: the KL-closest fully factorised
    distribution :math:`\prod_i q(x_i)` to :math:`\tilde q(x_1..x_n)` is the product of
    :math:`\tilde q`'s marginals (seed 002, section 1.2.2, after eq. 1.10).

    Parameters
    ----------
    joint : (n_1, ..., n_d) probabilities (or log probabilities if ``log``), any scale
    axes : which variables' marginals to return (default: all)

    Returns
    -------
    list of arrays (n_i,), each normalised to sum 1.
    """
    if log:
        probs, _ = normalize_log(joint.reshape(-1))
        probs = probs.reshape(joint.shape)
    else:
        probs = joint / jnp.sum(joint)
    d = probs.ndim
    axes = range(d) if axes is None else axes
    return [jnp.sum(probs, axis=tuple(j for j in range(d) if j != i)) for i in axes]


def mix_categoricals(weights, tables):
    r"""Weighted mixture of categoricals :math:`\sum_m w_m p_m(x)` (already in the family).

    weights (num_components,) nonnegative; tables (num_components, num_states) rows
    summing to 1 -> (num_states,)."""
    w = weights / jnp.sum(weights)
    return jnp.einsum("m,ms->s", w, tables)
