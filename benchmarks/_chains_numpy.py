"""Baseline of the generic-engine benchmark: a plain numpy forward pass over the joint
belief of :func:`dbn.examples.coupled_chains`, multiplying in one CPD at a time.

This is what a careful user would write by hand for that one family; the library's
engines are compared against it for speed (same run) and accuracy (exact marginals).
"""

from __future__ import annotations

import numpy as np


def chain_tables(keep: float = 0.9, flip: float = 0.3, noise: float = 0.2):
    """(stay (2, 2), coupled (2, 2, 2), obs (2, 2)) as in ``dbn.examples.coupled_chains``."""
    stay = np.array([[keep, 1 - keep], [1 - keep, keep]])
    coupled = np.empty((2, 2, 2))
    coupled[:, 0, :] = stay
    coupled[:, 1, :] = [[1 - flip, flip], [flip, 1 - flip]]
    obs = np.array([[1 - noise, noise], [noise, 1 - noise]])
    return stay, coupled, obs


def numpy_factored_filter(
    ys: np.ndarray, keep: float = 0.9, flip: float = 0.3, noise: float = 0.2, p_on: float = 0.5
) -> tuple[np.ndarray, np.ndarray]:
    """Exact filtering of the coupled chains, one CPD at a time on a (2,)*n joint.

    Parameters
    ----------
    ys : int array, shape (num_timesteps, n)
        Observed ``y_i`` per slice (no missing values).

    Returns
    -------
    marginals : ndarray, shape (num_timesteps, n, 2)
        ``P(x_{i,t} | y_{0:t})``.
    log_normalizers : ndarray, shape (num_timesteps,)
        ``log p(y_t | y_{0:t-1})``.
    """
    T, n = ys.shape
    stay, coupled, obs = chain_tables(keep, flip, noise)
    belief = np.ones((2,) * n)
    for i in range(n):
        shape = [1] * n
        shape[i] = 2
        belief = belief * np.array([1 - p_on, p_on]).reshape(shape)
    marg = np.empty((T, n, 2))
    logz = np.empty(T)
    for t in range(T):
        if t > 0:
            # new x_i needs old x_i and old x_{i-1}: go right to left so each old axis is
            # replaced by its new value just after its last use
            for i in range(n - 1, 0, -1):
                b = np.moveaxis(belief, (i, i - 1), (0, 1))
                b = np.einsum("ab...,abc->cb...", b, coupled)
                belief = np.moveaxis(b, (0, 1), (i, i - 1))
            belief = np.moveaxis(np.tensordot(belief, stay, axes=([0], [0])), -1, 0)
        for i in range(n):
            shape = [1] * n
            shape[i] = 2
            belief = belief * obs[:, ys[t, i]].reshape(shape)
        z = belief.sum()
        belief = belief / z
        logz[t] = np.log(z)
        for i in range(n):
            marg[t, i] = belief.sum(axis=tuple(a for a in range(n) if a != i))
    return marg, logz
