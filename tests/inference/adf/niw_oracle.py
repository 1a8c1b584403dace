"""Plain-numpy oracle of the NIW projection (expected statistics with scipy's digamma,
Newton on eta with scipy's trigamma): an independent implementation to check
:mod:`inference.adf.niw`'s jax projection against (tests only)."""

from __future__ import annotations

import numpy as np
from scipy.special import digamma as _digamma
from scipy.special import polygamma

from inference.adf.niw import NIW

__all__ = ["niw_expected_stats_np", "niw_project_np"]

_LOG2 = float(np.log(2.0))


def niw_expected_stats_np(theta: NIW):
    """The four expected statistics from C (Cholesky solve, scipy digamma): the oracle of
    :func:`inference.adf.niw.niw_expected_stats`. Returns (P, h, s, g)."""
    a = np.asarray(theta.a, float)
    kappa = np.asarray(theta.kappa, float)
    eta = np.asarray(theta.eta, float)
    C = np.asarray(theta.C, float)
    r = a.shape[-1]
    L = np.linalg.cholesky(C)
    eye = np.broadcast_to(np.eye(r), C.shape)
    Linv = np.linalg.solve(L, eye)
    Cinv = np.swapaxes(Linv, -1, -2) @ Linv
    logdetC = 2.0 * np.log(np.diagonal(L, axis1=-2, axis2=-1)).sum(-1)
    P = eta[..., None, None] * Cinv
    h = np.einsum("...ij,...j->...i", P, a)
    s = r / kappa + np.einsum("...i,...i->...", a, h)
    i = np.arange(r)
    g = logdetC - r * _LOG2 - _digamma(0.5 * (eta[..., None] - i)).sum(-1)
    return P, h, s, g


def niw_project_np(weights: np.ndarray, theta: NIW, iters: int = 60) -> NIW:
    """Plain numpy KL projection of ONE NIW mixture (the oracle of :func:`niw_project`).

    weights (num_components,); theta batch shape (num_components,). Returns an NIW
    with scalar batch shape."""
    w = np.asarray(weights, float)
    w = w / w.sum()
    keep = w > 0
    theta = NIW(*(np.asarray(x, float)[keep] for x in theta))
    w = w[keep]
    r = theta.a.shape[-1]
    P, h, s, g = niw_expected_stats_np(theta)
    Pm = np.einsum("m,mij->ij", w, P)
    Pm = 0.5 * (Pm + Pm.T)
    hm = w @ h
    sm = float(w @ s)
    gm = float(w @ g)
    L = np.linalg.cholesky(Pm)
    logdetP = 2.0 * np.log(np.diag(L)).sum()
    gap = max(gm + logdetP, 1e-300)
    eta0 = r * (r + 1.0) / (2.0 * gap) + (r - 1.0)
    x = np.log(max(eta0 - (r - 1.0), 1e-8))
    target = gm + logdetP + r * _LOG2
    i = np.arange(r)
    for _ in range(iters):
        eta = (r - 1.0) + np.exp(x)
        f = r * np.log(eta) - _digamma(0.5 * (eta - i)).sum() - target
        dfe = r / eta - 0.5 * polygamma(1, 0.5 * (eta - i)).sum()
        step = np.clip(f / (dfe * (eta - (r - 1.0))), -2.0, 2.0)
        if not np.isfinite(step):
            break
        x = x - step
    eta = (r - 1.0) + np.exp(x)
    Pinv = np.linalg.solve(L.T, np.linalg.solve(L, np.eye(r)))
    Pinv = 0.5 * (Pinv + Pinv.T)
    a = Pinv @ hm
    kappa = r / (sm - a @ hm)
    return NIW(a, np.float64(kappa), np.float64(eta), eta * Pinv)
