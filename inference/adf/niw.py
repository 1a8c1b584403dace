r"""Normal-Inverse-Wishart (NIW) densities: conjugate update, Student-t predictive,
closed-form evidence, expected sufficient statistics and the KL projection of a
weighted NIW mixture onto one NIW (the ADF projection of seed 002, section 1.4.3).

Parameterisation (seed 002, eq. 1.15; ``../shared/spec/zajdel_adf.md``):
:math:`\theta = (a, \kappa, \eta, C)`, :math:`V \sim \mathrm{IW}(\eta, C)` (density
:math:`\propto |V|^{-(\eta+r+1)/2} \exp(-\tfrac12 \mathrm{tr}(C V^{-1}))`, so
:math:`E[V^{-1}] = \eta C^{-1}`) and :math:`m \mid V \sim N(a, V/\kappa)`.

Shapes use ``obs_dim = r``; leading axes of every field are batch axes:
``a (..., r)``, ``kappa (...)``, ``eta (...)``, ``C (..., r, r)``.

Each formula is written once. The update and the Student-t run on numpy (``*_np``,
host code: the exact oracle, the greedy baseline, track scores) or on jax (jit-able)
through one array backend; the filter's hot loop (cached inverses, expected
statistics, the projection) is jax only. The plain-numpy projection used as the
projection's oracle lives in the tests (``tests/inference/adf/niw_oracle.py``).

Precision: the jax functions compute in the dtype of their inputs (the caller's
choice; filters use float64 inside ``jax.enable_x64``); :func:`niw_project` (a host
entry point) runs in float64 itself.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from jax.scipy.special import gammaln as _jgammaln
from scipy.special import gammaln as _gammaln
from scipy.special import multigammaln as _multigammaln

__all__ = [
    "NIW",
    "niw_update",
    "niw_update_np",
    "niw_log_evidence_np",
    "niw_log_evidence_masked_np",
    "niw_log_evidence_stats_np",
    "student_t_logpdf",
    "student_t_logpdf_np",
    "niw_predictive_logpdf",
    "niw_predictive_logpdf_np",
    "niw_predictive_lognorm",
    "niw_predictive_from_quad",
    "niw_update_cached",
    "niw_expected_stats",
    "niw_sum_digamma",
    "niw_from_stats",
    "niw_project",
    "niw_project_cached",
]

_LOG2 = float(np.log(2.0))
_LOGPI = float(np.log(np.pi))


class NIW(NamedTuple):
    """Parameters of a (batch of) Normal-Inverse-Wishart densities.

    Attributes
    ----------
    a : array (..., r)      mean of m
    kappa : array (...)     pseudo-count of the mean
    eta : array (...)       degrees of freedom of the inverse Wishart (> r - 1)
    C : array (..., r, r)   scale matrix of the inverse Wishart (SPD)
    """

    a: np.ndarray
    kappa: np.ndarray
    eta: np.ndarray
    C: np.ndarray


# ------------------------------------------------------------------ array backends
class _Ops(NamedTuple):
    """The array functions one formula needs, so that each formula is written once and
    runs on numpy (host code: oracle, greedy, scores) or jax (jit-able filters)."""

    xp: Any
    gammaln: Callable
    solve_lower: Callable  # solve L z = d for lower-triangular L (batched)


_JAX = _Ops(jnp, _jgammaln, lambda L, d: jax.scipy.linalg.solve_triangular(L, d, lower=True))
_NP = _Ops(np, _gammaln, np.linalg.solve)


def _as_np(*xs):
    return tuple(np.asarray(x, float) for x in xs)


# ----------------------------------------------------------------------------- update
def _niw_update(xp, theta: NIW, o) -> NIW:
    d = o - theta.a
    k1 = theta.kappa + 1.0
    a = theta.a + d / k1[..., None]
    C = theta.C + (theta.kappa / k1)[..., None, None] * d[..., :, None] * d[..., None, :]
    return NIW(a, k1, theta.eta + 1.0, C)


def niw_update(theta: NIW, o: jnp.ndarray) -> NIW:
    r"""Conjugate update of NIW(theta) with one vector ``o`` (jax; ``theta (+) o``).

    :math:`\kappa' = \kappa+1,\ \eta' = \eta+1,\ a' = (\kappa a + o)/(\kappa+1),\
    C' = C + \tfrac{\kappa}{\kappa+1}(o-a)(o-a)^T` (spec, "NIW").

    Parameters
    ----------
    theta : NIW with batch shape (...)
    o : array (..., r) broadcastable against ``theta.a``

    Returns
    -------
    NIW with the broadcast batch shape.
    """
    return _niw_update(jnp, NIW(*(jnp.asarray(x) for x in theta)), jnp.asarray(o))


def niw_update_np(theta: NIW, o: np.ndarray) -> NIW:
    """:func:`niw_update` on numpy arrays (float64; the same formula)."""
    return _niw_update(np, NIW(*_as_np(*theta)), np.asarray(o, float))


# --------------------------------------------------------------------------- evidence
def niw_log_evidence_np(X: np.ndarray, prior: NIW) -> float:
    r"""Closed-form log marginal likelihood :math:`\log \int \prod_i N(x_i; m, V)\,
    NIW(m, V; \theta_0)` of the rows of ``X (n, r)`` (the appearance term of seed 000,
    eq. 3, with the NIW state of seed 002, eq. 1.15). ``n = 0`` gives 0."""
    X = np.asarray(X, float).reshape(-1, np.shape(prior.a)[-1])
    mask = np.ones((1, X.shape[0]), bool)
    return float(niw_log_evidence_masked_np(X, mask, prior)[0])


def niw_log_evidence_masked_np(X: np.ndarray, masks: np.ndarray, prior: NIW) -> np.ndarray:
    r"""Batched closed-form NIW evidence of many subsets of the rows of ``X``.

    Parameters
    ----------
    X : array (num_obs, r)
    masks : bool array (num_sets, num_obs); row s selects the observations of set s
    prior : NIW with scalar batch shape (theta_0)

    Returns
    -------
    array (num_sets,)
        :math:`-\tfrac{nr}{2}\log\pi + \log\Gamma_r(\eta_n/2) - \log\Gamma_r(\eta/2)
        + \tfrac{\eta}{2}\log|C| - \tfrac{\eta_n}{2}\log|C_n| + \tfrac r2 \log(\kappa/\kappa_n)`;
        0 for an empty set.
    """
    X = np.asarray(X, float)
    M = np.asarray(masks, float)
    return niw_log_evidence_stats_np(
        M.sum(axis=1), M @ X, np.einsum("sk,ki,kj->sij", M, X, X), prior
    )


def niw_log_evidence_stats_np(n, S1, S2, prior: NIW) -> np.ndarray:
    r""":func:`niw_log_evidence_masked_np` from each set's sufficient statistics: its
    size ``n (num_sets,)``, sum ``S1 (num_sets, r)`` and sum of outer products
    ``S2 (num_sets, r, r)`` (the same formula; evaluating many priors on the same
    sets costs no pass over the data)."""
    n, S1, S2 = (np.asarray(v, float) for v in (n, S1, S2))
    r = S1.shape[1]
    a0 = np.asarray(prior.a, float)
    k0 = float(prior.kappa)
    e0 = float(prior.eta)
    C0 = np.asarray(prior.C, float)
    kn = k0 + n
    en = e0 + n
    an = (k0 * a0 + S1) / kn[:, None]
    Cn = C0 + S2 + k0 * np.outer(a0, a0) - kn[:, None, None] * an[:, :, None] * an[:, None, :]
    Cn = 0.5 * (Cn + np.swapaxes(Cn, -1, -2))
    L = np.linalg.cholesky(Cn)
    logdet_n = 2.0 * np.log(np.diagonal(L, axis1=-2, axis2=-1)).sum(-1)
    logdet_0 = 2.0 * np.log(np.diag(np.linalg.cholesky(C0))).sum()
    out = (
        -0.5 * n * r * _LOGPI
        + _multigammaln_vec(en / 2.0, r)
        - _multigammaln(e0 / 2.0, r)
        + 0.5 * e0 * logdet_0
        - 0.5 * en * logdet_n
        + 0.5 * r * (np.log(k0) - np.log(kn))
    )
    return np.where(n > 0, out, 0.0)


def _multigammaln_vec(x: np.ndarray, r: int) -> np.ndarray:
    i = np.arange(r)
    return 0.25 * r * (r - 1) * _LOGPI + _gammaln(x[..., None] - 0.5 * i).sum(-1)


# -------------------------------------------------------------------------- Student-t
def _student_t(ops: _Ops, x, nu, loc, scale):
    xp = ops.xp
    r = x.shape[-1]
    L = xp.linalg.cholesky(scale)
    d = xp.broadcast_to(x - loc, L.shape[:-1])
    z = ops.solve_lower(L, d[..., None])[..., 0]
    maha = (z * z).sum(-1)
    logdet = 2.0 * xp.log(xp.diagonal(L, axis1=-2, axis2=-1)).sum(-1)
    return (
        ops.gammaln(0.5 * (nu + r))
        - ops.gammaln(0.5 * nu)
        - 0.5 * r * (xp.log(nu) + _LOGPI)
        - 0.5 * logdet
        - 0.5 * (nu + r) * xp.log1p(maha / nu)
    )


def student_t_logpdf(x, nu, loc, scale):
    r"""Multivariate Student-t log density (jax, Cholesky solve); the formula and
    shapes of :func:`student_t_logpdf_np`."""
    return _student_t(_JAX, *(jnp.asarray(v) for v in (x, nu, loc, scale)))


def student_t_logpdf_np(x: np.ndarray, nu, loc: np.ndarray, scale: np.ndarray) -> np.ndarray:
    r"""Multivariate Student-t log density (numpy, Cholesky solve).

    :math:`\log\Gamma(\tfrac{\nu+r}2) - \log\Gamma(\tfrac\nu2) - \tfrac r2\log(\nu\pi)
    - \tfrac12\log|\Sigma| - \tfrac{\nu+r}{2}\log(1 + \delta/\nu)`,
    :math:`\delta = (x-\mu)^T\Sigma^{-1}(x-\mu)`.

    Parameters
    ----------
    x : (..., r); nu : (...); loc : (..., r); scale : (..., r, r) SPD

    Returns
    -------
    array (...)
    """
    return _student_t(_NP, *_as_np(x, nu, loc, scale))


def niw_predictive_logpdf_np(o: np.ndarray, theta: NIW) -> np.ndarray:
    r"""Predictive log density of ``o`` under NIW(theta) (numpy): Student-t with
    :math:`\nu = \eta - r + 1`, location a, scale :math:`C(\kappa+1)/(\kappa\nu)` (spec).

    Shapes: o (..., r) broadcast against theta's batch shape; returns (...)."""
    a = np.asarray(theta.a, float)
    r = a.shape[-1]
    kappa = np.asarray(theta.kappa, float)
    nu = np.asarray(theta.eta, float) - r + 1.0
    scale = np.asarray(theta.C, float) * ((kappa + 1.0) / (kappa * nu))[..., None, None]
    return student_t_logpdf_np(o, nu, a, scale)


def niw_predictive_lognorm(kappa, eta, logdetC, r: int):
    r"""The data-free part of the Student-t predictive of NIW(a, kappa, eta, C) (jax):
    :math:`\log\Gamma(\tfrac{\nu+r}2) - \log\Gamma(\tfrac\nu2) - \tfrac r2\log(\nu\pi)
    - \tfrac12\log|\Sigma|` with :math:`\nu = \eta-r+1`,
    :math:`\log|\Sigma| = \log|C| + r\log\tfrac{\kappa+1}{\kappa\nu}`.

    A filter that scores one observation against many stored NIWs keeps this per NIW
    (it changes only when the NIW does). Shapes: kappa, eta, logdetC (...); returns (...).
    """
    nu = eta - r + 1.0
    f = kappa * nu / (kappa + 1.0)
    return (
        _jgammaln(0.5 * (nu + r))
        - _jgammaln(0.5 * nu)
        - 0.5 * r * (jnp.log(nu) + _LOGPI)
        - 0.5 * (logdetC - r * jnp.log(f))
    )


def niw_predictive_from_quad(q, kappa, eta, lognorm, r: int):
    r"""Predictive log density from the quadratic form :math:`q = (o-a)^T C^{-1}(o-a)`
    and :func:`niw_predictive_lognorm`: :math:`\text{lognorm} - \tfrac{\nu+r}2
    \log(1 + \tfrac{\kappa}{\kappa+1} q)` (jax). Shapes: all (...); returns (...)."""
    nu = eta - r + 1.0
    f = kappa * nu / (kappa + 1.0)
    return lognorm - 0.5 * (nu + r) * jnp.log1p(f * q / nu)


def niw_predictive_logpdf(o: jnp.ndarray, a, kappa, eta, Cinv, logdetC) -> jnp.ndarray:
    r"""Predictive log density of ``o`` under NIW(a, kappa, eta, C) (jax), from cached
    :math:`C^{-1}` and :math:`\log|C|` (the tracker keeps them per slice).

    Student-t with :math:`\nu = \eta-r+1`, scale :math:`\Sigma = C(\kappa+1)/(\kappa\nu)`
    (:func:`niw_predictive_lognorm` + :func:`niw_predictive_from_quad`).

    Shapes: o (..., r), a (..., r), kappa/eta/logdetC (...), Cinv (..., r, r); returns (...).
    """
    r = a.shape[-1]
    d = o - a
    q = jnp.einsum("...i,...ij,...j->...", d, Cinv, d)
    return niw_predictive_from_quad(
        q, kappa, eta, niw_predictive_lognorm(kappa, eta, logdetC, r), r
    )


def niw_update_cached(o, a, kappa, eta, C, Cinv, logdetC):
    r"""Conjugate update ``theta (+) o`` carrying :math:`C^{-1}` and :math:`\log|C|`
    along (jax; Sherman-Morrison on the cached inverse, no factorisation):
    :math:`C'^{-1} = C^{-1} - \tfrac{\beta}{1+\beta q} C^{-1}uu^TC^{-1}`,
    :math:`\log|C'| = \log|C| + \log(1+\beta q)`, :math:`u = o - a`,
    :math:`\beta = \kappa/(\kappa+1)`, :math:`q = u^TC^{-1}u`; a, kappa, eta, C as
    :func:`niw_update`.

    Shapes: o (r,) or (..., r); a (..., r); kappa, eta, logdetC (...); C, Cinv
    (..., r, r). Returns ``(a, kappa, eta, C, Cinv, logdetC)`` with the batch shape.
    """
    u = o - a
    beta = kappa / (kappa + 1.0)
    Cu = jnp.einsum("...ij,...j->...i", Cinv, u)
    q = jnp.einsum("...i,...i->...", u, Cu)
    den = 1.0 + beta * q
    Cinv2 = Cinv - (beta / den)[..., None, None] * Cu[..., :, None] * Cu[..., None, :]
    a2 = a + u / (kappa + 1.0)[..., None]
    C2 = C + beta[..., None, None] * u[..., :, None] * u[..., None, :]
    return a2, kappa + 1.0, eta + 1.0, C2, Cinv2, logdetC + jnp.log(den)


# ------------------------------------------------------------- expected statistics
def _jdigamma(x):
    """psi(x) for x > 0: ten recurrence steps then the asymptotic series (|err| < 1e-14)."""
    acc = jnp.zeros_like(x)
    for i in range(10):
        acc = acc + 1.0 / (x + i)
    y = x + 10.0
    y2 = 1.0 / (y * y)
    series = y2 * (1 / 12 - y2 * (1 / 120 - y2 * (1 / 252 - y2 * (1 / 240 - y2 * (1 / 132)))))
    return jnp.log(y) - 0.5 / y - series - acc


def _jtrigamma(x):
    """psi'(x) for x > 0: ten recurrence steps then the asymptotic series."""
    acc = jnp.zeros_like(x)
    for i in range(10):
        acc = acc + 1.0 / ((x + i) * (x + i))
    y = x + 10.0
    iy = 1.0 / y
    y2 = iy * iy
    series = iy + 0.5 * y2 + iy * y2 * (1 / 6 - y2 * (1 / 30 - y2 * (1 / 42 - y2 * (1 / 30))))
    return series + acc


def _sum_digamma_j(eta, r):
    i = jnp.arange(r, dtype=jnp.asarray(eta).dtype)
    return _jdigamma(0.5 * (eta[..., None] - i)).sum(-1)


def _sum_trigamma_j(eta, r):
    i = jnp.arange(r, dtype=jnp.asarray(eta).dtype)
    return _jtrigamma(0.5 * (eta[..., None] - i)).sum(-1)


def niw_sum_digamma(eta, r: int):
    r""":math:`\sum_{i=1}^r \psi((\eta - i + 1)/2)` (jax), the special-function part of
    :math:`E[\log|V|]`; a filter may cache it per NIW and pass it to
    :func:`niw_expected_stats` / :func:`niw_project_cached`. Shapes: eta (...) -> (...)."""
    return _sum_digamma_j(eta, r)


def niw_expected_stats(a, kappa, eta, Cinv, logdetC, sum_digamma=None):
    r"""The four expected sufficient statistics of NIW(a, kappa, eta, C) (jax):

    :math:`E[V^{-1}] = \eta C^{-1}`, :math:`E[V^{-1}m] = \eta C^{-1}a`,
    :math:`E[m^TV^{-1}m] = r/\kappa + \eta a^TC^{-1}a`,
    :math:`E[\log|V|] = \log|C| - r\log2 - \sum_{i=1}^r\psi((\eta-i+1)/2)`.

    ``sum_digamma`` (...): :func:`niw_sum_digamma` of eta if cached by the caller.

    Shapes: a (..., r), kappa/eta/logdetC (...), Cinv (..., r, r). Returns
    ``(P (..., r, r), h (..., r), s (...), g (...))``.
    """
    r = a.shape[-1]
    P = eta[..., None, None] * Cinv
    h = jnp.einsum("...ij,...j->...i", P, a)
    s = r / kappa + jnp.einsum("...i,...i->...", a, h)
    psi = _sum_digamma_j(eta, r) if sum_digamma is None else sum_digamma
    g = logdetC - r * _LOG2 - psi
    return P, h, s, g


# ------------------------------------------------------------------ projection
_NEWTON_ITERS = 60


def niw_from_stats(P, h, s, g):
    r"""The NIW whose expected sufficient statistics are (P, h, s, g) (jax; the moment
    matching that minimises KL(mixture || NIW), spec "KL projection").

    Solves :math:`r\log\eta - \log|P| - r\log 2 - \sum_i\psi((\eta-i+1)/2) = g` for
    :math:`\eta > r-1` by Newton's method on :math:`x = \log(\eta - r + 1)` (the
    left side is monotone in eta), then :math:`C = \eta P^{-1}`,
    :math:`a = P^{-1}h`, :math:`\kappa = r/(s - a^TPa)`.

    Shapes: P (..., r, r), h (..., r), s (...), g (...). Returns
    ``(a, kappa, eta, C, Cinv, logdetC)`` with the batch shape.
    """
    r = h.shape[-1]
    Lp = jnp.linalg.cholesky(P)
    logdetP = 2.0 * jnp.log(jnp.diagonal(Lp, axis1=-2, axis2=-1)).sum(-1)
    gap = jnp.maximum(g + logdetP, 1e-300)  # Jensen gap >= 0
    eta0 = r * (r + 1.0) / (2.0 * gap) + (r - 1.0)
    x0 = jnp.log(jnp.maximum(eta0 - (r - 1.0), 1e-8))
    target = g + logdetP + r * _LOG2

    def f_and_df(x):
        eta = (r - 1.0) + jnp.exp(x)
        f = r * jnp.log(eta) - _sum_digamma_j(eta, r) - target
        dfe = r / eta - 0.5 * _sum_trigamma_j(eta, r)
        return f, dfe * (eta - (r - 1.0))

    def cond(carry):
        i, _, step = carry
        return (i < _NEWTON_ITERS) & jnp.any(jnp.abs(step) > 1e-14)

    def body(carry):
        i, x, _ = carry
        f, df = f_and_df(x)
        step = jnp.clip(f / df, -2.0, 2.0)
        step = jnp.where(jnp.isfinite(step), step, 0.0)
        return i + 1, x - step, step

    _, x, _ = jax.lax.while_loop(cond, body, (0, x0, jnp.ones_like(x0)))
    eta = (r - 1.0) + jnp.exp(x)
    eye = jnp.broadcast_to(jnp.eye(r, dtype=P.dtype), P.shape)
    Pinv = jax.scipy.linalg.cho_solve((Lp, True), eye)
    Pinv = 0.5 * (Pinv + jnp.swapaxes(Pinv, -1, -2))
    a = jnp.einsum("...ij,...j->...i", Pinv, h)
    kappa = r / (s - jnp.einsum("...i,...i->...", a, h))
    C = eta[..., None, None] * Pinv
    Cinv = P / eta[..., None, None]
    logdetC = r * jnp.log(eta) - logdetP
    return a, kappa, eta, C, Cinv, logdetC


def niw_project_cached(w, a, kappa, eta, Cinv, logdetC, sum_digamma=None):
    r"""KL projection of one weighted NIW mixture, components given with cached
    :math:`C^{-1}` and :math:`\log|C|` (jax, jit/vmap-able; the tracker's hot loop).

    Parameters
    ----------
    w : (num_components,) nonnegative weights (normalised inside; zero = padding)
    a : (num_components, r); kappa, eta, logdetC : (num_components,);
    Cinv : (num_components, r, r)
    sum_digamma : (num_components,) :func:`niw_sum_digamma` of eta, optional (cached)

    Returns
    -------
    (a, kappa, eta, C, Cinv, logdetC) of the projected NIW (no batch axis).
    """
    w = w / jnp.sum(w)
    # padding components may hold arbitrary finite values; zero weight removes them
    P, h, s, g = niw_expected_stats(a, kappa, eta, Cinv, logdetC, sum_digamma)
    Pm = jnp.einsum("m,mij->ij", w, P)
    hm = jnp.einsum("m,mi->i", w, h)
    sm = jnp.dot(w, jnp.where(w > 0, s, 0.0))
    gm = jnp.dot(w, jnp.where(w > 0, g, 0.0))
    return niw_from_stats(0.5 * (Pm + Pm.T), hm, sm, gm)


@jax.jit
def _project_batch(w, a, kappa, eta, C):
    L = jnp.linalg.cholesky(C)
    r = a.shape[-1]
    eye = jnp.broadcast_to(jnp.eye(r, dtype=C.dtype), C.shape)
    Cinv = jax.scipy.linalg.cho_solve((L, True), eye)
    Cinv = 0.5 * (Cinv + jnp.swapaxes(Cinv, -1, -2))
    logdetC = 2.0 * jnp.log(jnp.diagonal(L, axis1=-2, axis2=-1)).sum(-1)
    # padding (zero-weight) components: replace by a harmless copy of the first one
    ok = w > 0
    first = jnp.argmax(ok, axis=-1)

    def fill(x):
        ref = jnp.take_along_axis(
            x, first.reshape(first.shape + (1,) * (x.ndim - first.ndim)), axis=1
        )
        return jnp.where(ok.reshape(ok.shape + (1,) * (x.ndim - ok.ndim)), x, ref)

    a, kappa, eta, Cinv, logdetC = map(fill, (a, kappa, eta, Cinv, logdetC))
    return jax.vmap(niw_project_cached)(w, a, kappa, eta, Cinv, logdetC)


def niw_project(weights, theta: NIW) -> NIW:
    r"""KL projection of a batch of weighted NIW mixtures onto single NIWs (jax, jit,
    vmap over the batch, float64).

    Minimises :math:`KL(\sum_m w_m NIW(\theta_m)\,\|\,NIW(\theta))` by matching the four
    expected sufficient statistics (spec "KL projection of a NIW mixture"; the ADF
    projection of seed 002, section 1.4.3).

    Parameters
    ----------
    weights : (num_mixtures, num_components) nonnegative, each row not all zero
        (zero weight = padding component, ignored)
    theta : NIW with batch shape (num_mixtures, num_components)

    Returns
    -------
    NIW with batch shape (num_mixtures,)
    """
    with jax.enable_x64(True):
        out = _project_batch(
            jnp.asarray(weights, jnp.float64),
            jnp.asarray(theta.a, jnp.float64),
            jnp.asarray(theta.kappa, jnp.float64),
            jnp.asarray(theta.eta, jnp.float64),
            jnp.asarray(theta.C, jnp.float64),
        )
    a, kappa, eta, C = out[0], out[1], out[2], out[3]
    return NIW(np.asarray(a), np.asarray(kappa), np.asarray(eta), np.asarray(C))
