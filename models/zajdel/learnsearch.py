r"""EM learn-search over partitions (seed 000, sections 3-4, Fig. 4, Appendix A).

The generative model of seed 000, section 3, for one trajectory :math:`Y_k` (eq. 3):

* appearance: :math:`f \sim N(\mu, R)` per person, :math:`a_i = f + b(l_i) + \epsilon_i`,
  :math:`\epsilon_i \sim N(0, S(l_i))` (the *biased* model; :math:`b = 0` is the
  *unbiased* one, seed 000 section 5). The hidden :math:`f` is integrated in closed form
  per track (Appendix A, eq. A.2, a Kalman update in information form);
* arrival layout :math:`p(l_i, e_i \mid l_{i-1}, d_{i-1})` and start laws
  :math:`p(l_1)p(e_1 \mid l_1)` (the ``log_trans`` / ``log_entry`` tables of
  :class:`models.zajdel.path.PathModel`, given by the user from the building's layout);
* travel time: truncated normal per camera pair (eq. 2), ``travel_mean`` / ``travel_std``;
* start time: a uniform density ``1 / window`` (units 1/time, as the ADF's
  :math:`p_{\delta_0}`, so "continue" and "start" are both densities in time).

The partition prior :math:`p(\omega)` is seed 000's uniform prior when ``p_new`` is
None, or the sparse new-person prior of the ADF issue (:func:`models.zajdel.scores.
label_prior_log_prob`) when ``p_new`` is a probability.

Track evidence (eq. A.2 integrated). With :math:`z_i = a_i - b(l_i)`,
:math:`P = R^{-1} + \sum_i S_i^{-1}`, :math:`h = R^{-1}\mu + \sum_i S_i^{-1} z_i`,
:math:`c = \mu^T R^{-1}\mu + \log|2\pi R| + \sum_i (z_i^T S_i^{-1} z_i + \log|2\pi S_i|)`:

.. math::
    \log p(a_{1:n}) = -\tfrac12 c + \tfrac12 h^T P^{-1} h - \tfrac12 \log|P|
                      + \tfrac r2 \log 2\pi .

``(P, h, c)`` are sums over the track's observations, so extending a track by one
observation updates them in O(r^2) (no refit); scoring the extension costs one r x r
Cholesky factorisation, independent of the track's length.

The search (Fig. 4): all partitions of the first ``n0`` observations are enumerated, EM
runs to convergence on them (exact E step over that space), the ``T`` most probable are
kept; every later observation extends every kept partition in :math:`K_\omega + 1` ways
(join one of its tracks or start a new one), all children of all kept partitions are
scored in one array operation and the ``T`` best kept; after each batch of ``R``
observations one EM iteration (E step over the kept partitions, eq. 6; M step of
Appendix A) updates the parameters and the kept partitions are re-scored.

Data in this library's tests, benchmark and tutorial are SIMULATED
(:mod:`models.zajdel.simulate`).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from scipy.special import logsumexp

from dbn.checks import check_number_fields, real_array
from dbn.errors import InputError, ModelError
from models.zajdel.data import Observations, take, validate_observations
from models.zajdel.oracle import enumerate_partitions
from models.zajdel.params import ZajdelParams, check_p_new
from models.zajdel.path import PathModel, pairwise_path_logprob
from models.zajdel.scores import label_prior_log_prob, labels_to_links, path_log_prob

__all__ = [
    "IMPOSSIBLE_LOG_PROB",
    "LSParams",
    "LearnSearchConfig",
    "LearnSearchResult",
    "params_from_zajdel",
    "initial_params",
    "track_log_evidence",
    "partition_log_scores",
    "em_step",
    "learn_search",
]

_LOG2PI = float(np.log(2.0 * np.pi))

#: log-probability given to an impossible path factor (a zero transition or entry
#: probability): finite, so that the search and the sampler can rank and leave
#: impossible partitions; any feasible partition outranks an infeasible one unless their
#: feasible parts differ by more than 1e4 nats.
IMPOSSIBLE_LOG_PROB = -1.0e4


class LSParams(NamedTuple):
    """Parameters :math:`\\Theta` of seed 000's model (section 3), ``C`` cameras, ``r`` dims.

    Attributes
    ----------
    mean : (r,)            mu, prior mean of a person's hidden appearance f
    prior_cov : (r, r)     R, prior covariance of f
    bias : (C, r)          b(l), camera bias (zeros for the unbiased model)
    noise_cov : (C, r, r)  S(l), camera noise covariance
    path : PathModel       layout tables (given), travel_mean / travel_std (learned), window
    p_new : float or None  None: seed 000's uniform partition prior; else the sparse
        new-person prior of :func:`models.zajdel.scores.label_prior_log_prob`
    """

    mean: np.ndarray
    prior_cov: np.ndarray
    bias: np.ndarray
    noise_cov: np.ndarray
    path: PathModel
    p_new: float | None = None

    @property
    def obs_dim(self) -> int:
        return int(np.shape(self.mean)[0])


_MAX_PSEUDO_COUNT = 1e12  # beyond it the data weigh nothing, and the M step overflows


class LearnSearchConfig(NamedTuple):
    """Settings of :func:`learn_search`.

    Attributes
    ----------
    num_hypotheses : T, partitions kept (seed 000, eq. 6)
    n0 : observations of the initial exhaustive space (Bell(n0) partitions, n0 <= 8)
    batch : R, observations between two EM iterations
    learn : False uses the given parameters throughout (no EM)
    biased : learn the camera bias b(l) (seed 000's biased model); False keeps b = 0
    learn_appearance : learn mu, R, b(l), S(l)
    learn_travel : learn the travel-time means and variances per camera pair
    symmetric_travel : pool the travel statistics of (p, q) and (q, p)
    em_max_iter, em_tol : EM on the first n0 observations stops after em_max_iter
        iterations or when no parameter moves by more than em_tol (relative)
    shrinkage : pseudo-count of the regularised appearance M step: S(l) is shrunk
        toward the pooled noise covariance (itself toward the starting S), b(l) toward 0,
        R toward the starting R (0 = plain maximum likelihood, Appendix A; on the
        default simulated office it overfits and ends with one track per observation)
    travel_shrinkage : pseudo-count pulling each camera pair's travel-time mean and
        variance toward the starting values (0 = maximum likelihood)
    """

    num_hypotheses: int = 10
    n0: int = 6
    batch: int = 2
    learn: bool = True
    biased: bool = False
    learn_appearance: bool = True
    learn_travel: bool = True
    symmetric_travel: bool = False
    em_max_iter: int = 100
    em_tol: float = 1e-6
    shrinkage: float = 30.0
    travel_shrinkage: float = 2.0

    def validate(self) -> None:
        """Raise :class:`~dbn.errors.InputError` naming the first field the search cannot
        run with; called by :func:`learn_search` and the CLI."""
        check_number_fields(self, InputError)
        if self.num_hypotheses < 1:
            raise InputError(f"num_hypotheses = {self.num_hypotheses}: must be >= 1")
        if self.batch < 1:
            raise InputError(f"batch = {self.batch}: must be >= 1")
        if not 0 <= self.n0 <= 8:
            raise InputError(
                f"n0 = {self.n0}: must be in 0..8 (Bell(n0) partitions are enumerated)"
            )
        if self.em_max_iter < 0:
            raise InputError(f"em_max_iter = {self.em_max_iter}: must be >= 0")
        if not (np.isfinite(self.em_tol) and self.em_tol >= 0):
            raise InputError(f"em_tol = {self.em_tol}: must be a number >= 0")
        for name in ("shrinkage", "travel_shrinkage"):  # pseudo-counts of observations
            v = getattr(self, name)
            if not 0 <= v <= _MAX_PSEUDO_COUNT:
                raise InputError(f"{name} = {v}: must be in [0, {_MAX_PSEUDO_COUNT:g}]")


class LearnSearchResult(NamedTuple):
    """Output of :func:`learn_search`.

    Attributes
    ----------
    labels : (num_obs,) canonical labels of the MAP partition kept at the end
    hypotheses : (T', num_obs) the kept partitions, best first (T' <= T)
    log_scores : (T',) their unnormalised log posteriors under ``params``
    params : LSParams, final (learned or given) parameters
    map_history : list of (n,) canonical labels, the MAP partition of the first n
        observations after the initial phase and after each batch
    em_iterations : int, EM iterations run on the first n0 observations
    """

    labels: np.ndarray
    hypotheses: np.ndarray
    log_scores: np.ndarray
    params: LSParams
    map_history: list
    em_iterations: int


# --------------------------------------------------------------------------- parameters
def params_from_zajdel(params: ZajdelParams) -> LSParams:
    r"""Seed 000 parameters matched to an ADF parameter set (e.g. the simulator's).

    The NIW prior :math:`(a, \kappa, \eta, C)` has :math:`E[V] = C / (\eta - r - 1)`
    (within-person covariance) and :math:`\mathrm{Cov}(m) = E[V] / \kappa` (spread of
    people's means), so :math:`S(l) = E[V]` for every camera, :math:`R = E[V]/\kappa`,
    :math:`\mu = a`, :math:`b = 0`; the path model and ``p_new`` are copied.
    """
    a, kappa, eta, C = (np.asarray(x, float) for x in params.prior)
    r = a.shape[0]
    ev = C / (eta - r - 1.0)
    ncam = params.path.num_cameras
    return LSParams(
        a.copy(),
        ev / kappa,
        np.zeros((ncam, r)),
        np.broadcast_to(ev, (ncam, r, r)).copy(),
        params.path,
        params.p_new,
    )


def _travel_guess(obs: Observations) -> tuple[float, float]:
    te, tq = np.asarray(obs.t_enter), np.asarray(obs.t_quit)
    gaps = te[None, :] - tq[:, None]
    gaps = gaps[np.triu(np.ones(gaps.shape, bool), 1) & (gaps > 0)]
    if gaps.size == 0:
        span = float(max(tq.max() - te.min(), 1.0)) if te.size else 1.0
        return span, span
    m = float(np.mean(gaps))
    return m, 2.0 * float(max(np.std(gaps), m))


def initial_params(obs: Observations, path: PathModel, p_new: float | None,
                   travel_guess: tuple[float, float] | None = None) -> LSParams:
    r"""Deterministic moment-based starting point of EM (seed 000 starts at random).

    From the given observations (the first ``n0``): :math:`\mu` = their mean appearance;
    their variance (mean over dimensions) is split evenly between :math:`R` and
    :math:`S(l)` (isotropic); :math:`b = 0`; every camera pair gets the travel time ``travel_guess``
    (default: mean m of the positive gaps between one observation's quit and a later
    one's entry, and std 2 max(m, std of the gaps): broad, because the first
    observations are mostly entries and say little about walks between cameras; a narrow
    start rules long walks out before EM can learn them). The layout tables and window of ``path`` are kept.
    """
    app = np.asarray(obs.appearance, float)
    r = app.shape[1]
    v = float(app.var(0).mean()) if app.shape[0] > 1 else 1.0
    v = v if v > 0 else 1.0
    ncam = path.num_cameras
    tm, ts = travel_guess if travel_guess is not None else _travel_guess(obs)
    new_path = path._replace(
        travel_mean=np.full((ncam, ncam), float(tm)), travel_std=np.full((ncam, ncam), float(ts))
    )
    half = 0.5 * v * np.eye(r)
    return LSParams(app.mean(0), half, np.zeros((ncam, r)),
                    np.broadcast_to(half, (ncam, r, r)).copy(), new_path, p_new)


def _check_params(params: LSParams) -> None:
    r = params.obs_dim
    ncam = params.path.num_cameras
    shapes = {"mean": (r,), "prior_cov": (r, r), "bias": (ncam, r), "noise_cov": (ncam, r, r)}
    for name, shape in shapes.items():
        v = real_array(name, getattr(params, name), ModelError)  # complex ran, text raised
        if v.shape != shape:
            raise ModelError(f"{name}: expected shape {shape}, got {v.shape}")
        if not np.isfinite(v).all():
            raise ModelError(f"{name}: holds a non-finite value")
    for name in ("prior_cov", "noise_cov"):
        try:
            np.linalg.cholesky(np.asarray(getattr(params, name)))
        except np.linalg.LinAlgError as exc:
            raise ModelError(f"{name}: not symmetric positive definite") from exc
    check_p_new(params.p_new)


# --------------------------------------------------------------------------- evidence
class _Terms(NamedTuple):
    """Per-observation quantities under fixed parameters (information form)."""

    Sinv: np.ndarray  # (C, r, r) S(l)^{-1}
    Rinv: np.ndarray  # (r, r)
    h0: np.ndarray  # (r,) R^{-1} mu
    c0: float  # mu' R^{-1} mu + log|2 pi R|
    u: np.ndarray  # (K, r) S_l^{-1} (a - b_l)
    c: np.ndarray  # (K,) z' S^{-1} z + log|2 pi S_l|
    cam: np.ndarray  # (K,)
    logp0: np.ndarray  # (K,) start factor (floored)
    logpd: np.ndarray  # (K, K) link factor (floored; -inf for j >= k)
    single: np.ndarray  # (K,) log evidence of each observation alone (appearance only)
    onehot: np.ndarray  # (K, C) camera indicator


def _spd_inverse(A: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Inverse and log-determinant of SPD matrices (..., r, r) by Cholesky solves."""
    L = np.linalg.cholesky(A)
    eye = np.broadcast_to(np.eye(A.shape[-1]), A.shape)
    Linv = np.linalg.solve(L, eye)
    inv = np.swapaxes(Linv, -1, -2) @ Linv
    return 0.5 * (inv + np.swapaxes(inv, -1, -2)), 2.0 * np.log(np.diagonal(L, axis1=-2, axis2=-1)).sum(-1)


def _evidence(P: np.ndarray, h: np.ndarray, csum: np.ndarray, c0: float) -> np.ndarray:
    """Track log evidence from information-form sums; P (..., r, r), h (..., r), csum (...)."""
    r = h.shape[-1]
    L = np.linalg.cholesky(P)
    v = np.linalg.solve(L, h[..., None])[..., 0]
    logdet = 2.0 * np.log(np.diagonal(L, axis1=-2, axis2=-1)).sum(-1)
    return -0.5 * (csum + c0) + 0.5 * (v * v).sum(-1) - 0.5 * logdet + 0.5 * r * _LOG2PI


def _terms(obs: Observations, params: LSParams, floor: float = IMPOSSIBLE_LOG_PROB) -> _Terms:
    S = np.asarray(params.noise_cov, float)
    Sinv, logdetS = _spd_inverse(S)
    Rinv, logdetR = _spd_inverse(np.asarray(params.prior_cov, float))
    mu = np.asarray(params.mean, float)
    r = mu.shape[0]
    h0 = Rinv @ mu
    c0 = float(mu @ h0 + logdetR + r * _LOG2PI)
    cam = np.asarray(obs.camera, np.int64)
    z = np.asarray(obs.appearance, float) - np.asarray(params.bias, float)[cam]
    u = np.einsum("kij,kj->ki", Sinv[cam], z)
    c = (z * u).sum(1) + logdetS[cam] + r * _LOG2PI
    logp0, logpd = pairwise_path_logprob(obs, params.path)
    logp0 = np.maximum(logp0, floor)
    K = cam.shape[0]
    upper = np.triu(np.ones((K, K), bool), 1)
    logpd = np.where(upper, np.maximum(logpd, floor), -np.inf)
    single = _evidence(Rinv + Sinv[cam], h0 + u, c, c0)
    onehot = np.eye(Sinv.shape[0])[cam]
    return _Terms(Sinv, Rinv, h0, c0, u, c, cam, logp0, logpd, single, onehot)


def track_log_evidence(appearance: np.ndarray, camera: np.ndarray, masks: np.ndarray,
                       params: LSParams) -> np.ndarray:
    r"""Closed-form appearance evidence :math:`\log\int N(f;\mu,R)\prod_{i\in S}
    N(a_i; f + b(l_i), S(l_i))\,df` of many tracks (seed 000 eq. 3 integral, eq. A.2).

    Parameters
    ----------
    appearance : (num_obs, obs_dim)
    camera : (num_obs,) int
    masks : bool (num_sets, num_obs), each row a non-empty track

    Returns
    -------
    (num_sets,) log evidence.
    """
    K = np.shape(camera)[0]
    dummy = Observations(np.asarray(appearance, float), np.asarray(camera), np.zeros(K),
                         np.zeros(K), np.zeros(K, np.int64), np.zeros(K, np.int64))
    t = _terms(dummy, params)
    return _mask_evidence(t, np.asarray(masks, bool))


def _mask_evidence(t: _Terms, masks: np.ndarray) -> np.ndarray:
    """Evidence of tracks given as bool masks (..., K) over the observations of ``t``."""
    m = masks.astype(float)
    counts = m @ t.onehot  # (..., C)
    r = t.h0.shape[0]
    P = t.Rinv + (counts @ t.Sinv.reshape(t.Sinv.shape[0], r * r)).reshape(counts.shape[:-1] + (r, r))
    h = t.h0 + m @ t.u
    csum = m @ t.c
    return _evidence(P, h, csum, t.c0)


def _slot_masks(labels: np.ndarray) -> np.ndarray:
    K = labels.shape[-1]
    return labels[..., None, :] == np.arange(K)[:, None]


def _scores_from_terms(labels: np.ndarray, t: _Terms, p_new: float | None,
                       canonical: bool = False) -> np.ndarray:
    lab = np.atleast_2d(labels)
    M, K = lab.shape
    masks = _slot_masks(lab).reshape(M * K, K)
    nonempty = masks.any(1)
    out = np.zeros(M * K)
    sub = masks[nonempty]
    if sub.shape[0]:
        out[nonempty] = _mask_evidence(t, sub) + path_log_prob(t.logp0, t.logpd, sub)
    total = out.reshape(M, K).sum(1)
    if p_new is not None:
        total = total + label_prior_log_prob(lab if canonical else _canonical(lab), p_new)
    return total


def _canonical(labels: np.ndarray) -> np.ndarray:
    """Vectorised canonical relabelling of (M, K) label arrays (first-appearance order)."""
    lab = np.asarray(labels)
    K = lab.shape[-1]
    first = np.argmax(lab[..., :, None] == lab[..., None, :], axis=-1)  # first obs of same label
    is_first = first == np.arange(K)
    rank = np.cumsum(is_first, axis=-1) - 1
    return np.take_along_axis(rank, first, axis=-1)


def partition_log_scores(labels: np.ndarray, obs: Observations, params: LSParams) -> np.ndarray:
    r"""Unnormalised log posterior :math:`\log p(\omega) + \sum_k \log p(Y_k\mid\omega,\Theta)`
    of partitions (seed 000 eq. 1 with eq. 3 per track), computed from scratch.

    Parameters
    ----------
    labels : (num_partitions, num_obs) or (num_obs,) int labels in [0, num_obs)
        (canonical or not; the score depends only on the partition)
    obs : Observations (num_obs)
    params : LSParams

    Returns
    -------
    (num_partitions,) or () log scores. Impossible path factors count
    :data:`IMPOSSIBLE_LOG_PROB` each.
    """
    out = _scores_from_terms(np.asarray(labels), _terms(obs, params), params.p_new)
    return out if np.ndim(labels) == 2 else out[0]


# --------------------------------------------------------------------------- EM (App. A)
def _track_posteriors(labels: np.ndarray, t: _Terms):
    """Posterior mean / covariance of f for every non-empty slot of every partition
    (eq. A.2); empty slots get mean 0 and covariance 0."""
    M, K = labels.shape
    r = t.h0.shape[0]
    masks = _slot_masks(labels)  # (M, K, K)
    nonempty = masks.any(2)
    sub = masks[nonempty].astype(float)  # (S, K)
    counts = sub @ np.eye(t.Sinv.shape[0])[t.cam]
    P = t.Rinv + np.tensordot(counts, t.Sinv, axes=(1, 0))
    h = t.h0 + sub @ t.u
    cov_s, _ = _spd_inverse(P)
    mean = np.zeros((M, K, r))
    cov = np.zeros((M, K, r, r))
    mean[nonempty] = np.einsum("sij,sj->si", cov_s, h)
    cov[nonempty] = cov_s
    return nonempty, mean, cov


def em_step(obs: Observations, labels: np.ndarray, log_weights: np.ndarray, params: LSParams,
            config: LearnSearchConfig, anchor: LSParams) -> LSParams:
    r"""One EM iteration over a finite set of partitions (seed 000 eqs. 4-6, Appendix A).

    E step: :math:`q(\omega) \propto` ``exp(log_weights)`` over the given partitions and
    :math:`q(f_k\mid\omega) = N(\mu_k, R_k)` (eq. A.2). M step, with pseudo-count
    :math:`\nu` = ``config.shrinkage`` (:math:`\nu = 0`: Appendix A exactly, with the
    new :math:`\mu` in eq. A.9):

    * :math:`\mu = \sum_\omega q \sum_k \mu_k / \sum_\omega q K_\omega` (eq. A.8);
    * :math:`R = [\sum_\omega q \sum_k (R_k + (\mu_k-\mu)(\mu_k-\mu)^T) + \nu R_0] /
      [\sum_\omega q K_\omega + \nu]` (eq. A.9);
    * per camera l with :math:`n_l` observations and :math:`e_i = a_i - \mu_{k(i)}`:
      :math:`b(l) = \sum q \sum_{i: l_i = l} e_i / (n_l + \nu)` (biased model only),
      :math:`S(l) = [\sum q \sum_{i: l_i = l} ((e_i - b_l)(e_i - b_l)^T + R_{k(i)}) +
      \nu \bar S] / (n_l + \nu)`, :math:`\bar S` the same sum pooled over cameras,
      shrunk toward the anchor's mean :math:`S` with the same pseudo-count;
    * per camera pair (p, q), over links j -> i of the partitions with travel time
      :math:`x = t^e_i - t^q_j`, pseudo-count :math:`\nu_t` = ``config.travel_shrinkage``:
      :math:`\delta = (\nu_t\delta_0 + \sum q x)/(\nu_t + N)`,
      :math:`\sigma^2 = (\nu_t\sigma_0^2 + \sum q (x-\delta)^2)/(\nu_t + N)` (moments of the
      untruncated normal; the truncation at 0 of eq. 2 is ignored in the M step).

    Parameters
    ----------
    obs : Observations (n) the observations the partitions cover
    labels : (num_partitions, n) int labels
    log_weights : (num_partitions,) unnormalised log q(omega)
    params : current parameters; anchor : parameters the shrinkage pulls toward
        (R_0 = anchor.prior_cov, delta_0 / sigma_0 = anchor travel times)

    Returns
    -------
    LSParams, updated.
    """
    lab = np.atleast_2d(np.asarray(labels))
    M, n = lab.shape
    nu = float(config.shrinkage)
    t = _terms(obs, params)
    w = np.exp(np.asarray(log_weights, float) - logsumexp(log_weights))
    nonempty, mk, Rk = _track_posteriors(lab, t)
    wt = w[:, None] * nonempty  # (M, K)
    Kw = wt.sum()
    mu = np.einsum("mt,mti->i", wt, mk) / Kw
    dm = mk - mu
    wdm = wt[..., None] * dm
    Rsum = np.tensordot(wt, Rk, axes=([0, 1], [0, 1])) + wdm.reshape(-1, dm.shape[-1]).T @ dm.reshape(-1, dm.shape[-1])
    R = (Rsum + nu * np.asarray(anchor.prior_cov)) / (Kw + nu)
    # per observation: its track's posterior under each partition
    rows = np.arange(M)[:, None]
    m_obs = mk[rows, lab]  # (M, n, r)
    R_obs = Rk[rows, lab]  # (M, n, r, r)
    e = np.asarray(obs.appearance)[None] - m_obs
    cam = t.cam
    ncam = params.path.num_cameras
    onehot = np.eye(ncam)[cam]  # (n, C)
    n_l = onehot.sum(0)
    r = mu.shape[0]
    if config.biased:
        bsum = onehot.T @ np.tensordot(w, e, axes=(0, 0))
        bias = bsum / (n_l + nu)[:, None] if nu > 0 else bsum / np.maximum(n_l, 1)[:, None]
    else:
        bias = np.zeros((ncam, r))
    res = e - bias[cam][None]
    wres = w[:, None, None] * res  # (M, n, r)
    outer = np.einsum("mki,mkj->kij", wres, res) + np.tensordot(w, R_obs, axes=(0, 0))  # (n, r, r)
    Ssum = np.tensordot(onehot, outer, axes=(0, 0))  # (C, r, r)
    pooled = (Ssum.sum(0) + nu * np.asarray(anchor.noise_cov).mean(0)) / (n + nu)
    if nu > 0:
        S = (Ssum + nu * pooled) / (n_l + nu)[:, None, None]
    else:
        S = np.where((n_l > 0)[:, None, None], Ssum / np.maximum(n_l, 1)[:, None, None],
                     np.asarray(params.noise_cov))
    S = 0.5 * (S + np.swapaxes(S, -1, -2))
    R = 0.5 * (R + R.T)
    # floor (1e-9 of the anchor's scale) so that a degenerate fit stays positive definite
    eye = np.eye(r)
    S = S + 1e-9 * float(np.trace(np.asarray(anchor.noise_cov).mean(0))) / r * eye
    R = R + 1e-9 * float(np.trace(np.asarray(anchor.prior_cov))) / r * eye
    if not config.learn_appearance:
        mu, R, bias, S = params.mean, params.prior_cov, params.bias, params.noise_cov
    path = params.path
    if config.learn_travel:
        path = _travel_m_step(obs, lab, w, params.path, anchor.path, float(config.travel_shrinkage),
                              config.symmetric_travel)
    return LSParams(mu, R, bias, S, path, params.p_new)


def _travel_m_step(obs, lab, w, path, anchor, nu, symmetric):
    M, n = lab.shape
    links = labels_to_links(lab)  # (M, n)
    k = np.broadcast_to(np.arange(n), lab.shape)
    is_link = links != k
    cam = np.asarray(obs.camera)
    x = np.asarray(obs.t_enter)[k] - np.asarray(obs.t_quit)[links]
    ncam = path.num_cameras
    pair = cam[links] * ncam + cam[k]
    ww = np.broadcast_to(w[:, None], lab.shape) * is_link
    N = np.bincount(pair.ravel(), ww.ravel(), ncam * ncam).reshape(ncam, ncam)
    S1 = np.bincount(pair.ravel(), (ww * x).ravel(), ncam * ncam).reshape(ncam, ncam)
    S2 = np.bincount(pair.ravel(), (ww * x * x).ravel(), ncam * ncam).reshape(ncam, ncam)
    if symmetric:
        N, S1, S2 = N + N.T - np.diag(np.diag(N)), S1 + S1.T - np.diag(np.diag(S1)), S2 + S2.T - np.diag(np.diag(S2))
    d0 = np.asarray(anchor.travel_mean, float)
    s0 = np.asarray(anchor.travel_std, float)
    if nu > 0:
        mean = (nu * d0 + S1) / (nu + N)
        var = (nu * s0**2 + S2 - 2 * mean * S1 + mean**2 * N) / (nu + N)
    else:
        has = N > 1e-12
        mean = np.where(has, S1 / np.where(has, N, 1.0), path.travel_mean)
        var = np.where(has, S2 / np.where(has, N, 1.0) - mean**2, np.asarray(path.travel_std) ** 2)
    floor = 1e-6 * float(np.max(np.abs(d0))) + 1e-12
    std = np.sqrt(np.maximum(var, floor**2))
    return path._replace(travel_mean=mean, travel_std=std)


def _param_change(a: LSParams, b: LSParams) -> float:
    out = 0.0
    for x, y in ((a.mean, b.mean), (a.prior_cov, b.prior_cov), (a.bias, b.bias),
                 (a.noise_cov, b.noise_cov), (a.path.travel_mean, b.path.travel_mean),
                 (a.path.travel_std, b.path.travel_std)):
        x, y = np.asarray(x, float), np.asarray(y, float)
        scale = max(float(np.abs(y).max()), 1e-300)
        out = max(out, float(np.abs(x - y).max()) / scale)
    return out


# --------------------------------------------------------------------------- search state
class _Beam(NamedTuple):
    labels: np.ndarray  # (H, K) int, -1 beyond the processed prefix
    ntr: np.ndarray  # (H,)
    P: np.ndarray  # (H, K, r, r)
    h: np.ndarray  # (H, K, r)
    c: np.ndarray  # (H, K)
    E: np.ndarray  # (H, K) track appearance evidence
    last: np.ndarray  # (H, K) last observation of each track
    score: np.ndarray  # (H,)


def _beam_from_labels(labels: np.ndarray, n: int, K: int, t: _Terms, p_new) -> _Beam:
    """Search state of partitions of the first n observations (labels (H, n) canonical)."""
    H = labels.shape[0]
    r = t.h0.shape[0]
    full = np.full((H, K), -1, np.int64)
    full[:, :n] = labels
    masks = _slot_masks(labels)  # (H, n, n) slot x obs
    mf = masks.astype(float)
    counts = mf @ np.eye(t.Sinv.shape[0])[t.cam[:n]]
    P = np.broadcast_to(t.Rinv, (H, K, r, r)).copy()
    h = np.broadcast_to(t.h0, (H, K, r)).copy()
    c = np.zeros((H, K))
    P[:, :n] += np.einsum("mtc,cij->mtij", counts, t.Sinv)
    h[:, :n] += mf @ t.u[:n]
    c[:, :n] = mf @ t.c[:n]
    E = np.zeros((H, K))
    nonempty = np.zeros((H, K), bool)
    nonempty[:, :n] = masks.any(2)
    E[nonempty] = _evidence(P[nonempty], h[nonempty], c[nonempty], t.c0)
    idx = np.where(masks, np.arange(n), -1)
    last = np.zeros((H, K), np.int64)
    last[:, :n] = idx.max(2)
    score = _scores_from_terms_prefix(labels, t, n, p_new)
    ntr = labels.max(1) + 1 if n > 0 else np.zeros(H, np.int64)
    return _Beam(full, ntr.astype(np.int64), P, h, c, E, last, score)


def _scores_from_terms_prefix(labels, t: _Terms, n: int, p_new) -> np.ndarray:
    sub = _Terms(t.Sinv, t.Rinv, t.h0, t.c0, t.u[:n], t.c[:n], t.cam[:n], t.logp0[:n],
                 t.logpd[:n, :n], t.single[:n], t.onehot[:n])
    return _scores_from_terms(labels, sub, p_new, canonical=True)


def _extend(beam: _Beam, i: int, t: _Terms, T: int, p_new) -> _Beam:
    """Extend every kept partition by observation i in K_w + 1 ways; keep the T best
    (seed 000, Fig. 4). All children of all partitions are scored in one array operation."""
    H = beam.score.shape[0]
    smax = int(beam.ntr.max())
    l = t.cam[i]
    Pc = beam.P[:, :smax] + t.Sinv[l]
    hc = beam.h[:, :smax] + t.u[i]
    cc = beam.c[:, :smax] + t.c[i]
    Ec = _evidence(Pc, hc, cc, t.c0) if smax else np.zeros((H, 0))
    ntr = beam.ntr.astype(float)
    if p_new is None:
        pj = np.zeros(H)
        pn = np.zeros(H)
    else:
        pj = np.log1p(-p_new) - np.log(np.maximum(ntr, 1.0))
        pn = np.where(ntr > 0, np.log(p_new), 0.0)
    valid = np.arange(smax)[None, :] < beam.ntr[:, None]
    join = beam.score[:, None] + Ec - beam.E[:, :smax] + t.logpd[beam.last[:, :smax], i] + pj[:, None]
    new = beam.score + t.single[i] + t.logp0[i] + pn
    cand = np.concatenate([np.where(valid, join, -np.inf), new[:, None]], axis=1)
    flat = cand.ravel()
    order = np.argsort(-flat, kind="stable")[:T]
    order = order[np.isfinite(flat[order])]
    parent = order // (smax + 1)
    choice = order % (smax + 1)
    is_new = choice == smax
    slot = np.where(is_new, beam.ntr[parent], choice)
    rows = np.arange(order.shape[0])
    labels = beam.labels[parent].copy()
    labels[:, i] = slot
    P = beam.P[parent].copy()
    h = beam.h[parent].copy()
    c = beam.c[parent].copy()
    E = beam.E[parent].copy()
    last = beam.last[parent].copy()
    cj = np.minimum(choice, max(smax - 1, 0))
    if smax:
        P[rows, slot] = np.where(is_new[:, None, None], t.Rinv + t.Sinv[l], Pc[parent, cj])
        h[rows, slot] = np.where(is_new[:, None], t.h0 + t.u[i], hc[parent, cj])
        c[rows, slot] = np.where(is_new, t.c[i], cc[parent, cj])
        E[rows, slot] = np.where(is_new, t.single[i], Ec[parent, cj])
    else:
        P[rows, slot] = t.Rinv + t.Sinv[l]
        h[rows, slot] = t.h0 + t.u[i]
        c[rows, slot] = t.c[i]
        E[rows, slot] = t.single[i]
    last[rows, slot] = i
    ntr = beam.ntr[parent] + is_new
    return _Beam(labels, ntr, P, h, c, E, last, flat[order])


def _keep_best(beam: _Beam, T: int) -> _Beam:
    order = np.argsort(-beam.score, kind="stable")[:T]
    return _Beam(*(x[order] for x in beam))


# --------------------------------------------------------------------------- the search
def learn_search(obs: Observations, params: LSParams,
                 config: LearnSearchConfig | None = None, progress: bool = False) -> LearnSearchResult:
    r"""The learn-search tracker of seed 000 (Fig. 4): the T most probable partitions of
    all observations so far, with EM learning of :math:`\Theta` (Appendix A).

    Parameters
    ----------
    obs : Observations (num_obs), ordered by quit time
    params : LSParams; with ``config.learn`` the starting point of EM (only its layout
        tables, window and ``p_new`` matter if you build it with :func:`initial_params`),
        without it the fixed parameters of the search
    config : LearnSearchConfig (default: T = 10, n0 = 6, R = 2, learning on, unbiased)
    progress : show a tqdm bar over the observations

    Returns
    -------
    LearnSearchResult (MAP partition, kept partitions and scores, final parameters).

    Notes
    -----
    Deterministic (no randomness: the seed's random start of EM is replaced by
    :func:`initial_params`-style moments when the caller asks for it). Cost per
    observation: O(T K_w r^3) for the scores of all children (one batched Cholesky)
    plus O(T K r^2) to copy the kept states; one EM iteration per batch costs
    O(T K (C r^2 + r^3)).
    """
    cfg = LearnSearchConfig() if config is None else config
    cfg.validate()
    _check_params(params)
    obs = validate_observations(obs, params.obs_dim, params.path.num_cameras, params.path.num_borders)
    K = obs.num_obs
    T = int(cfg.num_hypotheses)
    n0 = min(cfg.n0, K)
    anchor = params
    theta = params
    em_iters = 0
    history = []
    if K == 0:
        return LearnSearchResult(np.zeros(0, np.int64), np.zeros((1, 0), np.int64), np.zeros(1),
                                 theta, history, 0)
    # initial space: every partition of the first n0 observations, EM to convergence
    parts = enumerate_partitions(max(n0, 1))
    pre = take(obs, slice(0, max(n0, 1)))
    if cfg.learn:
        for _ in range(cfg.em_max_iter):
            logw = partition_log_scores(parts, pre, theta)
            new = em_step(pre, parts, logw, theta, cfg, anchor)
            em_iters += 1
            delta = _param_change(new, theta)
            theta = new
            if delta < cfg.em_tol:
                break
    t = _terms(obs, theta)
    beam = _keep_best(_beam_from_labels(parts, max(n0, 1), K, t, theta.p_new), T)
    history.append(beam.labels[0, : max(n0, 1)].copy())
    it = range(max(n0, 1), K)
    if progress:
        from inference.progress import progress_bar

        it = progress_bar(it, desc=f"learn-search T={T}", unit="obs")
    since = 0
    for i in it:
        beam = _extend(beam, i, t, T, theta.p_new)
        since += 1
        if since == cfg.batch or i == K - 1:
            since = 0
            n = i + 1
            if cfg.learn:
                prefix = take(obs, slice(0, n))
                labs = beam.labels[:, :n]
                theta = em_step(prefix, labs, beam.score, theta, cfg, anchor)
                t = _terms(obs, theta)
                beam = _keep_best(_beam_from_labels(labs, n, K, t, theta.p_new), T)
            history.append(beam.labels[0, :n].copy())
    labels = _canonical(beam.labels)
    return LearnSearchResult(labels[0], labels, beam.score.copy(), theta, history, em_iters)
