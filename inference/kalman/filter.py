r"""Kalman filter in float64 numpy with Cholesky solves: the oracle of the particle tests.

The linear-Gaussian state-space model (one time convention shared with
:mod:`inference.particle`: the prior is at step 0, observations start at step 1):

.. math::

    s_0 \sim N(m_0, P_0), \quad s_k = F s_{k-1} + q_k,\ q_k \sim N(0, Q), \quad
    y_k = H s_k + r_k,\ r_k \sim N(0, R), \quad k = 1..T.

This is the Gaussian instance of the Bayesian filter of seed 002, eqs. 1.3-1.4
(predict with eq. 1.3, condition with eq. 1.4; :math:`L_k` is the one-step likelihood).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from scipy.linalg import cho_factor, cho_solve

from dbn.checks import check_size, make_rng, real_array
from dbn.errors import InputError, ModelError, NonFiniteError, ShapeError

__all__ = [
    "LinearGaussianParams",
    "KalmanResult",
    "kalman_filter",
    "check_params",
    "lgssm_sample",
    "lgssm_joint_log_likelihood",
]


class LinearGaussianParams(NamedTuple):
    """Parameters of a linear-Gaussian state-space model.

    Attributes
    ----------
    F : (state_dim, state_dim) transition matrix
    Q : (state_dim, state_dim) transition noise covariance
    H : (obs_dim, state_dim) observation matrix
    R : (obs_dim, obs_dim) observation noise covariance
    m0 : (state_dim,) prior mean
    P0 : (state_dim, state_dim) prior covariance
    """

    F: np.ndarray
    Q: np.ndarray
    H: np.ndarray
    R: np.ndarray
    m0: np.ndarray
    P0: np.ndarray


class KalmanResult(NamedTuple):
    """Output of :func:`kalman_filter`.

    Attributes
    ----------
    filtered_means : (num_timesteps, state_dim)
    filtered_covs : (num_timesteps, state_dim, state_dim)
    predicted_means : (num_timesteps, state_dim)
    predicted_covs : (num_timesteps, state_dim, state_dim)
    log_likelihoods : (num_timesteps,) one-step :math:`\\log p(y_k|y_{1:k-1})`
    log_likelihood : float, :math:`\\log p(y_{1:T})`
    """

    filtered_means: np.ndarray
    filtered_covs: np.ndarray
    predicted_means: np.ndarray
    predicted_covs: np.ndarray
    log_likelihoods: np.ndarray
    log_likelihood: float


def _real(name: str, value) -> np.ndarray:
    """A parameter or the observations as a finite float64 array, else the library's error."""
    arr = real_array(name, value)
    if not np.all(np.isfinite(arr)):
        bad = tuple(int(i) for i in np.argwhere(~np.isfinite(arr))[0])
        raise NonFiniteError(f"{name}{list(bad)} = {arr[bad]} is not finite")
    return arr


def _check_covariances(params: LinearGaussianParams) -> None:
    """Q, R and P0 (float arrays) symmetric and positive semi-definite (within rounding)."""
    for name in ("Q", "R", "P0"):
        S = getattr(params, name)
        scale = max(1.0, float(np.abs(S).max(initial=0.0)))
        if not np.allclose(S, S.T, rtol=0.0, atol=1e-9 * scale):
            raise InputError(f"{name} is not symmetric")
        if S.size and np.linalg.eigvalsh(S).min() < -1e-9 * scale:
            raise InputError(f"{name} is not positive semi-definite (a covariance)")


def check_params(params: LinearGaussianParams) -> LinearGaussianParams:
    """``params`` as finite float64 arrays of consistent shapes, ``Q``, ``R`` and ``P0``
    covariances (symmetric, positive semi-definite); else the library's error naming the
    field (:class:`InputError`, :class:`ShapeError`, :class:`NonFiniteError`)."""
    if not isinstance(params, LinearGaussianParams):
        raise InputError(f"params must be a LinearGaussianParams, got {type(params).__name__}")
    p = LinearGaussianParams(*(_real(name, v) for name, v in zip(params._fields, params)))
    d = p.m0.shape[0] if p.m0.ndim == 1 else -1
    if d < 0:
        raise ShapeError(f"m0 has shape {p.m0.shape}, expected (state_dim,)")
    shapes = {"F": (d, d), "Q": (d, d), "P0": (d, d)}
    for name, shape in shapes.items():
        if getattr(p, name).shape != shape:
            raise ShapeError(f"{name} has shape {getattr(p, name).shape}, expected {shape}")
    m = p.H.shape[0] if p.H.ndim else -1
    if p.H.shape != (m, d) or p.R.shape != (m, m):
        raise ShapeError(f"H {p.H.shape} / R {p.R.shape} do not fit state_dim {d}")
    _check_covariances(p)
    return p


def _check(
    params: LinearGaussianParams, observations: np.ndarray
) -> tuple[LinearGaussianParams, np.ndarray]:
    """:func:`check_params` and the observations as a finite ``(num_timesteps, obs_dim)``
    array."""
    p = check_params(params)
    m = p.H.shape[0]
    y = real_array("observations", observations)
    if y.ndim != 2 or y.shape[1] != m:
        raise ShapeError(f"observations has shape {y.shape}, expected (num_timesteps, {m})")
    return p, _real("observations", y)


def _predict(m: np.ndarray, P: np.ndarray, F: np.ndarray, Q: np.ndarray):
    m = F @ m
    P = F @ P @ F.T + Q
    return m, 0.5 * (P + P.T)


def _condition_on(m: np.ndarray, P: np.ndarray, H: np.ndarray, R: np.ndarray, y: np.ndarray):
    S = H @ P @ H.T + R
    try:
        c = cho_factor(0.5 * (S + S.T), lower=True)
    except np.linalg.LinAlgError:  # R singular where H P H^T is too (e.g. R = 0, P0 = 0)
        raise ModelError("the innovation covariance H P H^T + R is singular: give R (or "
                         "P0 and Q) positive definite") from None  # fmt: skip
    resid = y - H @ m
    K = cho_solve(c, H @ P).T  # P H^T S^-1  (S symmetric)
    m_new = m + K @ resid
    IKH = np.eye(m.shape[0]) - K @ H
    P_new = IKH @ P @ IKH.T + K @ R @ K.T  # Joseph form
    logdet = 2.0 * np.sum(np.log(np.diag(c[0])))
    ll = -0.5 * (resid @ cho_solve(c, resid) + logdet + y.shape[0] * math.log(2 * math.pi))
    return m_new, 0.5 * (P_new + P_new.T), float(ll)


def kalman_filter(params: LinearGaussianParams, observations: np.ndarray) -> KalmanResult:
    r"""Filtered moments and log-likelihood of a linear-Gaussian model (seed 002, eqs. 1.3-1.4).

    Parameters
    ----------
    params : LinearGaussianParams
    observations : array, shape (num_timesteps, obs_dim)
        :math:`y_1..y_T`.

    Returns
    -------
    KalmanResult
        Moments of :math:`p(s_k|y_{1:k})` and :math:`p(s_k|y_{1:k-1})`, the one-step
        log-likelihoods :math:`\log L_k` and their sum :math:`\log p(y_{1:T})`.

    Raises
    ------
    InputError, ShapeError, NonFiniteError
        Before any work: params not a :class:`LinearGaussianParams`, a field or the
        observations not finite numbers of the right shapes, ``Q``, ``R`` or ``P0`` not a
        covariance (symmetric, positive semi-definite).
    ModelError
        A singular innovation covariance (``R`` and the predicted ``H P H^T`` both singular).
    """
    p, y = _check(params, observations)
    F, Q, H, R = p[:4]
    m, P = p.m0, p.P0
    T, d = y.shape[0], m.shape[0]
    fm, fP = np.zeros((T, d)), np.zeros((T, d, d))
    pm, pP = np.zeros((T, d)), np.zeros((T, d, d))
    lls = np.zeros(T)
    for k in range(T):
        m, P = _predict(m, P, F, Q)
        pm[k], pP[k] = m, P
        m, P, lls[k] = _condition_on(m, P, H, R, y[k])
        fm[k], fP[k] = m, P
    return KalmanResult(fm, fP, pm, pP, lls, float(lls.sum()))


def lgssm_sample(
    seed: int, params: LinearGaussianParams, num_timesteps: int
) -> tuple[np.ndarray, np.ndarray]:
    """Simulate states ``(num_timesteps, state_dim)`` and observations ``(num_timesteps, obs_dim)``.

    Parameters
    ----------
    seed : int >= 0
        Seed of a local ``numpy.random.Generator``.
    params : LinearGaussianParams
        Checked as :func:`kalman_filter` checks them.
    num_timesteps : int >= 0

    Raises
    ------
    InputError, ShapeError, NonFiniteError
        A bad seed, count or parameter, naming it.
    """
    rng = make_rng(seed)
    num_timesteps = check_size("num_timesteps", num_timesteps)
    params = check_params(params)
    s = rng.multivariate_normal(params.m0, params.P0)
    xs, ys = np.zeros((num_timesteps, len(s))), np.zeros((num_timesteps, params.H.shape[0]))
    for k in range(num_timesteps):
        s = params.F @ s + rng.multivariate_normal(np.zeros(len(s)), params.Q)
        xs[k] = s
        ys[k] = params.H @ s + rng.multivariate_normal(np.zeros(params.H.shape[0]), params.R)
    return xs, ys


def lgssm_joint_log_likelihood(params: LinearGaussianParams, observations: np.ndarray) -> float:
    r""":math:`\log p(y_{1:T})` by a direct solve of the joint Gaussian (brute force, O(T^3)).

    Builds the mean and covariance of the stacked :math:`(y_1..y_T)` and evaluates the
    multivariate normal density with a Cholesky factor. For checking :func:`kalman_filter`.
    """
    p, y = _check(params, observations)
    F, Q, H, R = p[:4]
    T, m = y.shape[0], H.shape[0]
    # s_k = F^k s_0 + sum_{j<=k} F^{k-j} q_j
    Fp = [np.linalg.matrix_power(F, k) for k in range(T + 1)]
    mean = np.concatenate([H @ Fp[k + 1] @ p.m0 for k in range(T)])
    cov = np.zeros((T * m, T * m))
    for a in range(T):
        for b in range(T):
            ka, kb = a + 1, b + 1
            c = Fp[ka] @ p.P0 @ Fp[kb].T
            for j in range(1, min(ka, kb) + 1):
                c = c + Fp[ka - j] @ Q @ Fp[kb - j].T
            cov[a * m : (a + 1) * m, b * m : (b + 1) * m] = H @ c @ H.T + (R if a == b else 0.0)
    c = cho_factor(cov, lower=True)
    r = y.reshape(-1) - mean
    logdet = 2.0 * np.sum(np.log(np.diag(c[0])))
    return float(-0.5 * (r @ cho_solve(c, r) + logdet + T * m * math.log(2 * math.pi)))
