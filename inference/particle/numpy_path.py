"""The particle machinery in plain numpy, for models whose particles are not jax arrays.

Some particle models are ragged and data-dependent (seed 001's path-recovery filter looks
up each camera's observations with ``searchsorted``): they run on the host in numpy, with
a ``numpy.random.Generator`` for randomness. This module gives them the same engine as the
jax path of :mod:`inference.particle`: log weights normalised in log space, the effective
sample size, and resamplers with one signature ``(rng, log_weights, n) -> ancestors``
that follow :mod:`inference.particle.resampling` (NaN is a zero weight; all-zero weights
fall back to uniform; an ancestor is never a zero-weight particle). The step and the run
built on them are :mod:`inference.particle.numpy_filter`.

Every function is float64 numpy and consumes the generator in a fixed way (systematic:
one uniform; multinomial: ``n`` uniforms), so the same generator state gives the same
ancestors.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

__all__ = [
    "NumpyResampler",
    "log_normalise",
    "normalized_weights",
    "ess",
    "systematic",
    "multinomial",
    "NUMPY_RESAMPLERS",
]

NumpyResampler = Callable[[np.random.Generator, np.ndarray, int], np.ndarray]


def log_normalise(log_weights: np.ndarray) -> tuple[np.ndarray, float]:
    r"""Normalised log weights and :math:`\log\sum_i e^{\ell_i}` (max-shifted).

    Parameters
    ----------
    log_weights : (num_particles,) unnormalised log weights; NaN is read as ``-inf``.

    Returns
    -------
    (num_particles,) float64 normalised log weights (uniform ``-log N`` when every weight
    is zero) and the log of the total weight (``-inf`` when every weight is zero).
    """
    lw = np.where(np.isnan(log_weights), -np.inf, np.asarray(log_weights, dtype=np.float64))
    m = np.max(lw)
    if not np.isfinite(m):
        if m == np.inf:
            lw = np.where(lw == np.inf, 0.0, -np.inf)
            m = 0.0
        else:
            n = lw.size
            return np.full(n, -np.log(n)), -np.inf
    total = m + np.log(np.sum(np.exp(lw - m)))
    return lw - total, float(total)


def normalized_weights(log_weights: np.ndarray) -> np.ndarray:
    """Weights ``W = softmax(log_weights)`` (float64, summing to one; see :func:`log_normalise`)."""
    return np.exp(log_normalise(log_weights)[0])


def ess(log_weights: np.ndarray) -> float:
    r"""Effective sample size :math:`1 / \sum_i W_i^2` of the normalised weights."""
    w = normalized_weights(log_weights)
    return float(1.0 / np.sum(w * w))


def _inverse_cdf(w: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Indices ``i`` with ``cdf[i-1] <= u < cdf[i]``, never a zero-weight particle."""
    cum = np.cumsum(w)
    idx = np.searchsorted(cum, u * cum[-1], side="right")
    last = w.size - 1 - int(np.argmax(w[::-1] > 0))
    return np.minimum(idx, last).astype(np.int64)


def systematic(rng: np.random.Generator, log_weights: np.ndarray, n: int) -> np.ndarray:
    """Systematic resampling: one uniform ``U``, points ``(k + U) / n``; (n,) int64, sorted.

    Each particle is picked ``floor(n W_i)`` or ``ceil(n W_i)`` times.
    """
    w = normalized_weights(log_weights)
    return _inverse_cdf(w, (rng.random() + np.arange(n)) / n)


def multinomial(rng: np.random.Generator, log_weights: np.ndarray, n: int) -> np.ndarray:
    """Multinomial resampling: ``n`` i.i.d. draws from ``softmax(log_weights)``; (n,) int64."""
    w = normalized_weights(log_weights)
    return _inverse_cdf(w, rng.random(n))


NUMPY_RESAMPLERS: dict[str, NumpyResampler] = {"systematic": systematic, "multinomial": multinomial}
