"""The linear-Gaussian state-space model as a particle-filter model (for the Kalman oracle)."""

from __future__ import annotations

import math
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from dbn.errors import InputError, ShapeError
from inference.kalman import LinearGaussianParams
from inference.kalman.filter import check_params
from inference.particle.model import StateSpaceModel

__all__ = ["LinearGaussianSSM"]


def _square_root(S: np.ndarray) -> np.ndarray:
    """``L`` with ``L L^T = S`` for a covariance: Cholesky, or (``S`` singular, as a noise-
    free component makes it) ``V sqrt(max(w, 0))`` from ``S = V diag(w) V^T``."""
    try:
        return np.linalg.cholesky(S)
    except np.linalg.LinAlgError:
        w, V = np.linalg.eigh(S)
        return V * np.sqrt(np.clip(w, 0.0, None))


class LinearGaussianSSM(StateSpaceModel):
    r"""``s_k = F s_{k-1} + N(0, Q)``, ``y_k = H s_k + N(0, R)``, ``s_0 ~ N(m0, P0)``.

    The same law as :func:`inference.kalman.kalman_filter`; the look-ahead point is the
    transition mean :math:`F s_{k-1}` (seed 002, eq. 1.12). Observations are arrays of
    shape ``(obs_dim,)``; actions are ignored.

    Raises
    ------
    InputError, ShapeError, NonFiniteError
        Parameters :func:`~inference.kalman.filter.check_params` refuses (a raw
        ``LinAlgError`` before), or an ``R`` that is not positive definite (the likelihood
        needs its inverse; ``Q`` and ``P0`` may be singular: their draws use a square root).
    """

    def __init__(self, params: LinearGaussianParams) -> None:
        params = check_params(params)
        L0, LQ = _square_root(params.P0), _square_root(params.Q)
        try:
            LR = np.linalg.cholesky(params.R)
        except np.linalg.LinAlgError:
            raise InputError("R must be positive definite: the particle likelihood "
                             "N(y; H s, R) needs its inverse") from None  # fmt: skip
        self._params = params
        self._F, self._H, self._m0 = params.F, params.H, params.m0
        self._L0, self._LQ, self._LR = L0, LQ, LR
        self._R_logdet = 2.0 * float(np.sum(np.log(np.diag(LR))))

    @property
    def params(self) -> LinearGaussianParams:
        """The checked parameters, fixed at construction (a filter compiles them in)."""
        return self._params

    @params.setter
    def params(self, params: LinearGaussianParams) -> None:
        raise InputError("LinearGaussianSSM.params is fixed at construction (the model's "
                         "square roots and every compiled filter are built from it): build "
                         "LinearGaussianSSM(new_params) instead")  # fmt: skip

    def sample_initial(self, key: Array, num_particles: int, dtype: Any) -> Array:
        """``(num_particles, state_dim)`` draws from ``N(m0, P0)``."""
        z = jax.random.normal(key, (num_particles, self._m0.shape[0]), dtype=dtype)
        return jnp.asarray(self._m0, dtype) + z @ jnp.asarray(self._L0.T, dtype)

    def transition_mean(self, particles: Array, action: Any) -> Array:
        """``F s`` per particle; shape ``(num_particles, state_dim)``."""
        return particles @ jnp.asarray(self._F.T, particles.dtype)

    def sample_transition(self, key: Array, particles: Array, action: Any) -> Array:
        """``F s + N(0, Q)`` per particle."""
        z = jax.random.normal(key, particles.shape, dtype=particles.dtype)
        return self.transition_mean(particles, action) + z @ jnp.asarray(
            self._LQ.T, particles.dtype
        )

    def log_likelihood(self, particles: Array, observation: Array) -> Array:
        """``log N(y; H s, R)`` per particle, by a triangular solve with chol(R)."""
        dt = particles.dtype
        if jnp.shape(observation) != (self._H.shape[0],):  # static under jit: checked once
            raise ShapeError(f"an observation has shape {jnp.shape(observation)}, expected "
                             f"({self._H.shape[0]},) (obs_dim)")  # fmt: skip
        resid = jnp.asarray(observation, dt) - particles @ jnp.asarray(self._H.T, dt)
        sol = jax.scipy.linalg.solve_triangular(jnp.asarray(self._LR, dt), resid.T, lower=True)
        m = self._H.shape[0]
        return -0.5 * (jnp.sum(sol**2, axis=0) + self._R_logdet + m * math.log(2 * math.pi))
