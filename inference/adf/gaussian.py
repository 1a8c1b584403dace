r"""Gaussian moment matching: the KL projection :math:`\arg\min_q KL(\sum_m w_m N(\mu_m,
\Sigma_m) \| q)` over Gaussians q matches mean and covariance (the continuous ADF
projection of seed 002, section 1.2.2)."""

from __future__ import annotations

import jax
import jax.numpy as jnp

__all__ = ["gaussian_moment_match"]


@jax.jit
def gaussian_moment_match(weights, means, covs):
    r"""Moment-matched Gaussian of a batch of Gaussian mixtures (jax, jit; batch axes in
    front are vectorised).

    :math:`\mu = \sum_m w_m\mu_m`, :math:`\Sigma = \sum_m w_m(\Sigma_m + (\mu_m-\mu)
    (\mu_m-\mu)^T)`, weights normalised inside.

    Parameters
    ----------
    weights : (..., num_components) nonnegative
    means : (..., num_components, state_dim)
    covs : (..., num_components, state_dim, state_dim)

    Returns
    -------
    mean (..., state_dim), cov (..., state_dim, state_dim) (symmetrised)
    """
    w = weights / jnp.sum(weights, axis=-1, keepdims=True)
    mu = jnp.einsum("...m,...mi->...i", w, means)
    d = means - mu[..., None, :]
    cov = jnp.einsum("...m,...mij->...ij", w, covs + d[..., :, None] * d[..., None, :])
    return mu, 0.5 * (cov + jnp.swapaxes(cov, -1, -2))
