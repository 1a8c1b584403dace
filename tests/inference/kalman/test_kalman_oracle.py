"""Kalman filter against a direct solve of the joint Gaussian of states and observations."""

from __future__ import annotations

import re

import numpy as np
import pytest
from scipy.stats import multivariate_normal

from dbn.errors import InputError, ModelError, NonFiniteError, ShapeError
from inference.kalman import (
    LinearGaussianParams,
    kalman_filter,
    lgssm_joint_log_likelihood,
    lgssm_sample,
)


def _params(seed: int, d: int = 2, m: int = 2) -> LinearGaussianParams:
    rng = np.random.default_rng(seed)
    F = 0.9 * np.linalg.qr(rng.normal(size=(d, d)))[0]
    A = rng.normal(size=(d, d))
    B = rng.normal(size=(m, m))
    return LinearGaussianParams(
        F=F,
        Q=A @ A.T / d + 0.1 * np.eye(d),
        H=rng.normal(size=(m, d)),
        R=B @ B.T / m + 0.2 * np.eye(m),
        m0=rng.normal(size=d),
        P0=np.eye(d),
    )


def _joint(params: LinearGaussianParams, T: int):
    """Mean and covariance of (s_1..s_T, y_1..y_T) built from the linear map of the noises."""
    F, Q, H, R, m0, P0 = params
    d, m = F.shape[0], H.shape[0]
    nz = d + T * d + T * m
    mu_z = np.concatenate([m0, np.zeros(T * d + T * m)])
    cov_z = np.zeros((nz, nz))
    cov_z[:d, :d] = P0
    for k in range(T):
        cov_z[d + k * d : d + (k + 1) * d, d + k * d : d + (k + 1) * d] = Q
        o = d + T * d + k * m
        cov_z[o : o + m, o : o + m] = R
    Ms = np.zeros((T * d, nz))
    for k in range(1, T + 1):
        row = slice((k - 1) * d, k * d)
        Ms[row, :d] = np.linalg.matrix_power(F, k)
        for j in range(1, k + 1):
            Ms[row, d + (j - 1) * d : d + j * d] = np.linalg.matrix_power(F, k - j)
    My = np.kron(np.eye(T), H) @ Ms
    My[:, d + T * d :] += np.eye(T * m)
    M = np.vstack([Ms, My])
    return M @ mu_z, M @ cov_z @ M.T


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_kalman_matches_joint_gaussian(seed: int) -> None:
    params = _params(seed)
    T = 6
    _, ys = lgssm_sample(seed + 10, params, T)
    res = kalman_filter(params, ys)
    mu, cov = _joint(params, T)
    d, m = 2, 2
    ny = T * m
    y_all = ys.reshape(-1)
    total = multivariate_normal(mu[T * d :], cov[T * d :, T * d :]).logpdf(y_all)
    assert res.log_likelihood == pytest.approx(total, rel=1e-10, abs=1e-10)
    assert res.log_likelihood == pytest.approx(lgssm_joint_log_likelihood(params, ys), abs=1e-9)
    for k in range(1, T + 1):
        s_idx = np.arange((k - 1) * d, k * d)
        y_idx = T * d + np.arange(k * m)
        Syy = cov[np.ix_(y_idx, y_idx)]
        Ssy = cov[np.ix_(s_idx, y_idx)]
        gain = np.linalg.solve(Syy, Ssy.T).T
        mean = mu[s_idx] + gain @ (y_all[: k * m] - mu[y_idx])
        P = cov[np.ix_(s_idx, s_idx)] - gain @ Ssy.T
        np.testing.assert_allclose(res.filtered_means[k - 1], mean, rtol=1e-9, atol=1e-10)
        np.testing.assert_allclose(res.filtered_covs[k - 1], P, rtol=1e-9, atol=1e-10)
    assert ny == y_all.size


def test_kalman_bad_input() -> None:
    params = _params(0)
    _, ys = lgssm_sample(0, params, 4)
    ys_bad = ys.copy()
    ys_bad[2, 1] = np.nan
    with pytest.raises(NonFiniteError, match=r"observations\[2, 1\]"):
        kalman_filter(params, ys_bad)
    with pytest.raises(ShapeError, match="observations"):
        kalman_filter(params, ys[:, :1])


@pytest.mark.parametrize(
    ("edit", "error", "needle"),
    [
        (lambda p: p._replace(Q=-np.eye(2)), InputError, "Q is not positive semi-definite"),
        (lambda p: p._replace(P0=np.array([[1.0, 0.5], [0.0, 1.0]])), InputError,
         "P0 is not symmetric"),
        (lambda p: p._replace(R=np.full((2, 2), np.nan)), NonFiniteError, "R[0, 0] = nan"),
        (lambda p: p._replace(F=np.full((2, 2), "x")), InputError, "F is not an array of numbers"),
        (lambda p: tuple(p), InputError, "params must be a LinearGaussianParams"),
        (lambda p: p._replace(R=0 * p.R, Q=0 * p.Q, P0=0 * p.P0), ModelError,
         "innovation covariance H P H^T + R is singular"),
    ],
)
def test_kalman_bad_parameters_are_named(edit, error, needle) -> None:
    """A covariance that is not one (not symmetric, or negative) was used as given; the
    rest raised numpy's or scipy's own errors (LinAlgError, ValueError, AttributeError)."""
    params = _params(0)
    _, ys = lgssm_sample(0, params, 4)
    with pytest.raises(error, match=re.escape(needle)):
        kalman_filter(edit(params), ys)
