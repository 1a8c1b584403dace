"""The linear-Gaussian state-space model as a particle-filter model (for the Kalman oracle)."""

from __future__ import annotations

import math
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from inference.kalman import LinearGaussianParams
from inference.particle.model import StateSpaceModel

__all__ = ["LinearGaussianSSM"]


class LinearGaussianSSM(StateSpaceModel):
    r"""``s_k = F s_{k-1} + N(0, Q)``, ``y_k = H s_k + N(0, R)``, ``s_0 ~ N(m0, P0)``.

    The same law as :func:`inference.kalman.kalman_filter`; the look-ahead point is the
    transition mean :math:`F s_{k-1}` (seed 002, eq. 1.12). Observations are arrays of
    shape ``(obs_dim,)``; actions are ignored.
    """

    def __init__(self, params: LinearGaussianParams) -> None:
        self.params = params
        self._F = np.asarray(params.F, dtype=np.float64)
        self._H = np.asarray(params.H, dtype=np.float64)
        self._m0 = np.asarray(params.m0, dtype=np.float64)
        self._L0 = np.linalg.cholesky(np.asarray(params.P0, dtype=np.float64))
        self._LQ = np.linalg.cholesky(np.asarray(params.Q, dtype=np.float64))
        LR = np.linalg.cholesky(np.asarray(params.R, dtype=np.float64))
        self._LR = LR
        self._R_logdet = 2.0 * float(np.sum(np.log(np.diag(LR))))

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
        resid = jnp.asarray(observation, dt) - particles @ jnp.asarray(self._H.T, dt)
        sol = jax.scipy.linalg.solve_triangular(jnp.asarray(self._LR, dt), resid.T, lower=True)
        m = self._H.shape[0]
        return -0.5 * (jnp.sum(sol**2, axis=0) + self._R_logdet + m * math.log(2 * math.pi))
