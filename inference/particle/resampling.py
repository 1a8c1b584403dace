"""Resampling schemes with one signature ``(key, log_weights, n) -> ancestors``.

Every scheme takes *unnormalised log weights* of shape ``(num_particles,)`` and returns
``n`` ancestor indices (``int32``, shape ``(n,)``) drawn so that particle ``i`` is picked
``n * W_i`` times in expectation, ``W = softmax(log_weights)`` (the multinomial step of
seed 002, footnote 2 of section 1.3.1, and its lower-variance variants).

The weights are normalised in log space (max-shifted), so weights that all underflow
(``log_weights = -1e4``) resample exactly as their shifted values do; NaN counts as a
zero weight; when every weight is zero (all ``-inf`` or NaN) the schemes fall back to
uniform weights instead of returning garbage. All functions are pure and jit-able
(``n`` must be static under ``jax.jit``).
"""

from __future__ import annotations

from collections.abc import Callable

import jax
import jax.numpy as jnp
from jax import Array

__all__ = [
    "Resampler",
    "normalized_weights",
    "multinomial",
    "systematic",
    "stratified",
    "residual",
    "RESAMPLERS",
]

Resampler = Callable[[Array, Array, int], Array]


def normalized_weights(log_weights: Array) -> Array:
    r"""Normalised weights :math:`W_i = e^{\ell_i - \max_j \ell_j} / \sum_k e^{\ell_k - \max_j \ell_j}`.

    Parameters
    ----------
    log_weights : Array, shape (num_particles,)
        Unnormalised log weights; NaN is read as ``-inf`` (weight zero).

    Returns
    -------
    Array, shape (num_particles,)
        Non-negative weights summing to one, same float dtype. If every weight is zero
        (all ``-inf``/NaN) the result is uniform; if some are ``+inf`` those share the mass.
    """
    lw = jnp.where(jnp.isnan(log_weights), -jnp.inf, log_weights)
    m = jnp.max(lw)
    shift = jnp.where(jnp.isfinite(m), m, jnp.zeros_like(m))
    w = jnp.exp(lw - shift)
    w = jnp.where(m == jnp.inf, (lw == jnp.inf).astype(w.dtype), w)
    w = jnp.where(m == -jnp.inf, jnp.ones_like(w), w)
    return w / jnp.sum(w)


def _inverse_cdf(weights: Array, u: Array) -> Array:
    """Indices ``i`` with ``cdf[i-1] <= u < cdf[i]`` (never a zero-weight particle)."""
    cdf = jnp.cumsum(weights)
    idx = jnp.searchsorted(cdf, u * cdf[-1], side="right")
    # rounding can put u * cdf[-1] at cdf[-1]: clip to the last positive-weight particle
    num = weights.shape[0]
    last = num - 1 - jnp.argmax(weights[::-1] > 0)
    return jnp.minimum(idx, last).astype(jnp.int32)


def _uniform(key: Array, shape: tuple[int, ...], dtype) -> Array:
    return jax.random.uniform(key, shape, dtype=dtype)


def multinomial(key: Array, log_weights: Array, n: int) -> Array:
    """Multinomial resampling: ``n`` i.i.d. draws from ``softmax(log_weights)``.

    Parameters
    ----------
    key : PRNG key
    log_weights : Array, shape (num_particles,)
    n : int
        Number of ancestors to draw (static).

    Returns
    -------
    Array, shape (n,), int32
        Ancestor indices (unsorted).
    """
    w = normalized_weights(log_weights)
    return _inverse_cdf(w, _uniform(key, (n,), w.dtype))


def systematic(key: Array, log_weights: Array, n: int) -> Array:
    """Systematic resampling: one uniform ``U``, points ``(k + U) / n``, ``k = 0..n-1``.

    Each particle is picked ``floor(n W_i)`` or ``ceil(n W_i)`` times. Same parameters and
    return as :func:`multinomial` (ancestors sorted).
    """
    w = normalized_weights(log_weights)
    cdf = jnp.cumsum(w)
    cdf = cdf / cdf[-1]
    # point k = (k + U) / n lies below cdf_i  <=>  k < n cdf_i - U: count_i = ceil(n cdf_i - U);
    # the ancestor of point k is the number of particles whose count is <= k (O(n), no search)
    counts = jnp.clip(jnp.ceil(n * cdf - _uniform(key, (), w.dtype)), 0, n).astype(jnp.int32)
    marks = jnp.zeros(n + 1, jnp.int32).at[counts].add(1)
    anc = jnp.cumsum(marks[:n])
    last = w.shape[0] - 1 - jnp.argmax(w[::-1] > 0)
    return jnp.minimum(anc, last).astype(jnp.int32)


def stratified(key: Array, log_weights: Array, n: int) -> Array:
    """Stratified resampling: one uniform per stratum, points ``(k + U_k) / n``.

    Same parameters and return as :func:`multinomial` (ancestors sorted).
    """
    w = normalized_weights(log_weights)
    u = (jnp.arange(n, dtype=w.dtype) + _uniform(key, (n,), w.dtype)) / n
    return _inverse_cdf(w, u)


def residual(key: Array, log_weights: Array, n: int) -> Array:
    r"""Residual resampling: ``floor(n W_i)`` deterministic copies, the rest multinomial.

    The remaining :math:`R = n - \sum_i \lfloor n W_i \rfloor` ancestors are drawn from the
    residual weights :math:`n W_i - \lfloor n W_i \rfloor`. Same parameters and return as
    :func:`multinomial`.
    """
    w = normalized_weights(log_weights)
    scaled = n * w
    counts = jnp.floor(scaled)
    num_det = jnp.sum(counts).astype(jnp.int32)
    det = jnp.repeat(
        jnp.arange(w.shape[0], dtype=jnp.int32), counts.astype(jnp.int32), total_repeat_length=n
    )
    rest = jnp.clip(scaled - counts, 0.0, None)
    rest_log = jnp.where(rest > 0, jnp.log(jnp.where(rest > 0, rest, 1.0)), -jnp.inf)
    rnd = multinomial(key, rest_log, n)
    return jnp.where(jnp.arange(n) < num_det, det, rnd).astype(jnp.int32)


RESAMPLERS: dict[str, Resampler] = {
    "multinomial": multinomial,
    "systematic": systematic,
    "stratified": stratified,
    "residual": residual,
}
