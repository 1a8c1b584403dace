r"""The Zajdel tracker's ADF step as the three hooks of :mod:`inference.adf.driver`
(seed 002, section 1.4.3; spec ``../shared/spec/zajdel_adf.md``, "One-slice update").

* :func:`predict`: the link prior (spec step 1) times the Student-t appearance
  predictive and the path model of every open slot, and of "a new person" (step 2,
  unnormalised, log space);
* :func:`condition`: normalise in log space (the link posterior and the one-step log
  likelihood);
* :func:`project`: label posterior, counter and pointers (steps 3-5), the new slice's
  NIW as the KL projection of the mixture over links (step 6) and, with
  ``old_update="seed"``, the seed's projection of the old slices; then the slot
  bookkeeping (insertion, eviction of the track end seen longest ago, pruning) and the
  step's report.

With ``ADFConfig(birth_leave=True)`` or ``"filter"`` (issue 17) the link prior is
that of people entering at a rate and leaving the building (:func:`_link_prior`;
:mod:`models.zajdel.birth_leave` has both forms and their measurements), and a track
end that can no longer be continued is closed before each step
(:func:`_close_expired`); ``"filter"`` also keeps all of the new end's mass and
evicts the end least likely to be continued (:func:`project`). The default keeps the
spec's label prior, bit for bit.

Each slot caches :math:`C^{-1}`, :math:`\log|C|`, the data-free part of its
Student-t predictive and the digamma sum of its updated NIW's :math:`E[\log|V|]`
(they change only when the slot's NIW does), and the path
model's camera-pair normalisers are computed once (``ADFParams.path_lognorm``): the
per-step work over the open slots needs no special function.
"""

from __future__ import annotations

from functools import cache, partial

import jax
import jax.numpy as jnp
from jax.scipy.special import logsumexp

from inference.adf.driver import ADFHooks
from inference.adf.niw import (
    niw_predictive_from_quad,
    niw_predictive_lognorm,
    niw_project_cached,
    niw_sum_digamma,
    niw_update_cached,
)
from models.zajdel.adf_types import ADFConfig, ADFInfo, ADFParams, ADFState
from models.zajdel.path import log_new_rate, log_p_delta_cached, log_stay_lookup

__all__ = ["predict", "condition", "project", "window_predict", "zajdel_hooks"]

_COUNTER_EPS = 1e-15  # counter tails below this are dropped (keeps its support bounded)


_TOPK_BLOCK = 16  # XLA's CPU top-k: a partial-sort kernel up to here, a full sort beyond


def _top(x, k):
    """Indices and values of the k largest entries of a vector of probabilities
    (float64, no NaN, no -inf), largest first, ties to the lower index. The ranking is
    done in float32 (XLA's CPU top-k is several times faster there; entries equal to
    float32 precision may swap places), the values returned are the float64 ones.
    ``k > 16`` is taken in blocks of 16 (each block's winners masked out before the
    next): the same ranking as one top-k, without the full sort XLA would use."""
    xf = x.astype(jnp.float32)
    parts = []
    for start in range(0, k, _TOPK_BLOCK):
        _, i = jax.lax.top_k(xf, min(_TOPK_BLOCK, k - start))
        parts.append(i)
        if start + _TOPK_BLOCK < k:
            xf = xf.at[i].set(-jnp.inf)
    i = parts[0] if len(parts) == 1 else jnp.concatenate(parts)
    return x[i], i


FILTER = "filter"  # ADFConfig.birth_leave: the filtering form (see _link_prior)
CLOSE_EPS = 1e-6  # birth-leave: a track end continued with less probability is closed


def _continuation(m: ADFParams, st: ADFState, te):
    """Birth-leave model: which slots can no longer be continued at time ``te``, (S,)
    bool: their probability of being continued, (1 - rho) S_j / (rho + (1 - rho) S_j)
    with S_j the probability that a staying person has not yet been seen again,
    decays with the time since they were last seen; below ``CLOSE_EPS`` (past
    ``m.close_horizon``, :func:`models.zajdel.path.continuation_horizon`) the end is
    closed."""
    return st.slot_valid & (te - st.slot_tq > m.close_horizon[st.slot_cam, st.slot_bq])


def _close_expired(m: ADFParams, st: ADFState, te, scatter: bool = True) -> ADFState:
    """Move the pointer mass of the slots that can no longer be continued
    (:func:`_continuation`) to ``closed`` and free them: every person's pointer row
    still sums to 1, and the open-track set holds only ends that may be continued.
    The scatter into ``closed`` runs only in steps where a slot closes
    (``scatter=False``: the slots are freed, ``closed`` is left as it is, enough for
    scoring)."""
    gone = _continuation(m, st, te)
    pprob = jnp.where(gone[:, None], 0.0, st.slot_pprob)
    st2 = st._replace(slot_valid=st.slot_valid & ~gone, slot_pprob=pprob)
    if not scatter:
        return st2

    def add(c):
        mass = jnp.where(gone[:, None], st.slot_pprob, 0.0).reshape(-1)
        return c.at[st.slot_person.reshape(-1)].add(mass)

    return st2._replace(closed=jax.lax.cond(jnp.any(gone), add, lambda c: c, st.closed))


def _log_stay(m: ADFParams, st: ADFState, t):
    """log g_j(t - t_j) of every slot (S,): the probability that slot j's person makes
    no further pass by time t (:func:`models.zajdel.path.log_stay_prob`, tabulated)."""
    return log_stay_lookup(m.stay_table, m.stay_step, st.slot_cam, st.slot_bq, t - st.slot_tq)


def _link_prior(m: ADFParams, uniform: bool, st: ADFState, birth_leave: bool = False, te=None):
    """Spec step 1: log P(link j) (S,), log P(new) (), and which slots are open (S,).

    ``birth_leave``: the prior of partitions of a marked point process in time (seed
    000's path model with people entering and leaving): new people arrive at rate
    lambda = ``path.new_rate`` (1/time); after each pass a person leaves the building
    with probability rho = ``path.leave_prob``, else is seen again after the
    truncated-normal travel time. A partition with P people and K - P links then has
    prior weight (lambda rho)^P (1 - rho)^(K - P) times the path and entry
    terms (every track eventually ends), so log P(new) = log(lambda rho) and log P(link
    j) = log open_j + log(1 - rho). Both sides are densities in time (rescaling time
    and lambda together leaves every posterior unchanged). Measured on the large
    setting (seed 0, 3,000 observations, 512 slots), the filtering form that puts the
    leave probability into the hazard instead (new: lambda, link:
    (1 - rho) p_delta / (rho + (1 - rho) S_j)) over-split: counter 415 for 280
    people; the causes were the new end's pointer mass lost to 'closed', too few open
    ends, the constant rate and the appearance prior, not the form (lowering the open
    mass of silent ends as time passes, coupled to the counter, under-counted badly:
    54 for 100 after 500 observations; see :mod:`models.zajdel.birth_leave`).
    ``birth_leave="filter"``: that filtering form,
    log P(new) = log lambda(t) (:func:`models.zajdel.path.log_new_rate`) and log
    P(link j) = log open_j + log(1 - rho) - log g_j(t) (:func:`_log_stay`), the
    path term p_delta added by :func:`predict`. A track end whose probability of being continued,
    (1 - rho) S_j / (rho + (1 - rho) S_j), falls below ``CLOSE_EPS`` is closed
    (:func:`_close_expired`).
    """
    open_ = jnp.sum(st.slot_pprob, axis=1)
    valid = st.slot_valid & (open_ > 0)
    safe_open = jnp.where(valid, open_, 1.0)
    if birth_leave == FILTER:
        rho = m.path.leave_prob
        lg = _log_stay(m, st, te)
        return jnp.log(safe_open) + jnp.log1p(-rho) - lg, log_new_rate(m.path, te), valid
    if birth_leave:
        rho = m.path.leave_prob
        return jnp.log(safe_open) + jnp.log1p(-rho), log_new_rate(m.path, te) + jnp.log(rho), valid
    if uniform:
        c = jnp.arange(st.counter.shape[0], dtype=st.counter.dtype)
        e = jnp.sum(st.counter / (c + 1.0))
        return jnp.log(e) + jnp.log(safe_open), jnp.log(e), valid
    tot = jnp.sum(jnp.where(valid, open_, 0.0))
    lp_link = jnp.log1p(-m.p_new) + jnp.log(safe_open) - jnp.log(jnp.where(tot > 0, tot, 1.0))
    return lp_link, jnp.where(tot > 0, jnp.log(m.p_new), 0.0), valid


def predict(m: ADFParams, st: ADFState, x, uniform: bool, birth_leave: bool = False):
    """Unnormalised log link weights ``(logw (S,), logw0 ())`` of observation
    ``x = (o, cam, be, bq, te, tq)`` (spec steps 1-2):
    :math:`\\log P(\\text{link } j) + \\log t(o_k|\\theta_j) + \\log p_\\delta(d_k|d_j)`
    and :math:`\\log P(\\text{new}) + \\log t(o_k|\\theta_0) + \\log p_{\\delta_0}(d_k)`
    (``birth_leave``: expired track ends closed first, no 1/W: see :func:`_link_prior`)."""
    o, cam, be, bq, te, tq = x
    r = o.shape[0]
    if birth_leave:
        st = _close_expired(m, st, te, scatter=False)
    lp_link, lp_new, valid = _link_prior(m, uniform, st, birth_leave, te)
    u = o - st.slot_a
    qf = jnp.einsum("si,sij,sj->s", u, st.slot_Cinv, u)
    app = niw_predictive_from_quad(qf, st.slot_kappa, st.slot_eta, st.slot_lognorm, r)
    path = log_p_delta_cached(
        m.path, m.path_lognorm, st.slot_cam, st.slot_bq, st.slot_tq, cam, be, te
    )
    logw = jnp.where(valid, lp_link + app + path, -jnp.inf)
    u0 = o - m.a0
    q0 = u0 @ m.Cinv0 @ u0
    logw0 = (
        lp_new
        + niw_predictive_from_quad(q0, m.k0, m.e0, m.lognorm0, r)
        + m.path.log_entry[cam, be]
        - (0.0 if birth_leave else jnp.log(m.path.window))
    )
    return logw, logw0


def condition(m: ADFParams, st: ADFState, x, scores):
    """Normalise the link weights in log space: ``(w (S,), w0 (), log Z (),
    impossible ())``; when nothing has positive density the observation is new."""
    logw, logw0 = scores
    allw = jnp.concatenate([logw, logw0[None]])
    lz = logsumexp(allw)
    impossible = ~jnp.isfinite(lz)
    p = jnp.where(impossible, 0.0, jnp.exp(allw - jnp.where(impossible, 0.0, lz)))
    p = p.at[-1].set(jnp.where(impossible, 1.0, p[-1]))
    return p[:-1], p[-1], lz, impossible


def _labels_counter_pointers(st: ADFState, w, w0, W: int):
    """Spec steps 3-5: label posterior q_k(l_k = n) (N,), counter (N + 1,), pointers
    of the old slots (S, W), never-seen (N,), and the new slot's top W persons."""
    N = st.never.shape[0]
    open_ = jnp.sum(st.slot_pprob, axis=1)
    ratio = jnp.where(open_ > 0, w / jnp.where(open_ > 0, open_, 1.0), 0.0)
    qlab = (
        jnp.zeros(N, w.dtype)
        .at[st.slot_person.reshape(-1)]
        .add((st.slot_pprob * ratio[:, None]).reshape(-1))
    )
    qlab = qlab + w0 * st.counter[:N]
    counter = (1.0 - w0) * st.counter + w0 * jnp.concatenate([jnp.zeros(1), st.counter[:-1]])
    counter = jnp.where(counter >= _COUNTER_EPS, counter, 0.0)  # bounded support
    counter = counter / jnp.sum(counter)
    pprob = st.slot_pprob * (1.0 - qlab[st.slot_person])
    never = st.never * (1.0 - qlab)
    new_p, new_n = _top(qlab, W)
    return qlab, counter, pprob, never, new_p, new_n


def _slot_niws(st: ADFState, idx=None):
    f = (st.slot_a, st.slot_kappa, st.slot_eta, st.slot_C, st.slot_Cinv, st.slot_logdetC)
    return f if idx is None else tuple(v[idx] for v in f)


def _new_slice_niw(m: ADFParams, st: ADFState, o, w, w0, Mx: int):
    """Spec step 6: the new slice's NIW, the KL projection of
    :math:`\\sum_j w_j NIW(\\theta_j \\oplus o_k) + w_0 NIW(\\theta_0 \\oplus o_k)` over the
    ``Mx`` most probable links (the others' weights are negligible and dropped).
    Returns the projection ``(a, kappa, eta, C, Cinv, logdetC)``, the updated
    components of those links and their slot indices."""
    _, itop = _top(w, Mx)
    comps = niw_update_cached(o, *_slot_niws(st, itop))
    prior = niw_update_cached(o, m.a0, m.k0, m.e0, m.C0, m.Cinv0, m.logdet0)
    ca, ck, ce, _, cCinv, cld = comps
    cat = lambda c, p: jnp.concatenate([c, p[None]])  # noqa: E731
    new = niw_project_cached(
        cat(w[itop], w0),
        cat(ca, prior[0]),
        cat(ck, prior[1]),
        cat(ce, prior[2]),
        cat(cCinv, prior[4]),
        cat(cld, prior[5]),
        cat(st.slot_psi_next[itop], m.psi0_next),
    )
    return new, comps, itop


def _old_slices_seed(st: ADFState, w, comps, itop, M: int):
    """The seed's old-slice update for the ``M`` most probable links j (the first of
    ``itop``): the projection of :math:`w_j NIW(\\theta_j \\oplus o_k) + (1 - w_j)
    NIW(\\theta_j)`. Returns the slots' six NIW arrays."""
    old = _slot_niws(st)
    it = itop[:M]
    wt = w[it]

    def proj2(wj, q, j):
        ww = jnp.stack([wj, 1.0 - wj])
        pick = [comps[i][q] for i in (0, 1, 2, 4, 5)]
        keep = [old[i][j] for i in (0, 1, 2, 4, 5)]
        return niw_project_cached(ww, *(jnp.stack([a, b]) for a, b in zip(pick, keep, strict=True)))

    projected = jax.vmap(proj2)(wt, jnp.arange(M), it)
    use = wt > 0

    def sel(new, cur):
        return cur.at[it].set(jnp.where(use.reshape((-1,) + (1,) * (new.ndim - 1)), new, cur[it]))

    return tuple(sel(n, c) for n, c in zip(projected, old, strict=True))


def _insert_slot(cfg: ADFConfig, st: ADFState, qlab, pprob, new_p, new_n, evict_key=None):
    """Slot bookkeeping: the new slot takes a free slot, else the track end seen
    longest ago is closed; pointer mass of persons left out of the new slot's top
    entries, of an evicted slot, and below ``prune_eps`` becomes a closed end (every
    person's pointer row still sums to 1). Returns (idx, valid, person, pprob, closed).

    Pruning the old slots scatters S x W entries; it runs only in steps where an old
    entry fell below ``prune_eps`` (adding zeros changes nothing)."""
    N = st.never.shape[0]
    closed = st.closed * (1.0 - qlab)
    closed = closed + qlab - jnp.zeros(N, qlab.dtype).at[new_n].add(new_p)
    valid = st.slot_valid & (jnp.sum(pprob, axis=1) > 0)
    free = ~valid
    key = st.slot_tq if evict_key is None else evict_key
    idx = jnp.where(jnp.any(free), jnp.argmax(free), jnp.argmin(jnp.where(valid, key, jnp.inf)))
    closed = closed.at[st.slot_person[idx]].add(jnp.where(valid[idx], pprob[idx], 0.0))
    pprob = pprob.at[idx].set(0.0)
    small_old = (pprob < cfg.prune_eps) & (pprob > 0)

    def prune_old(c):
        return c.at[st.slot_person.reshape(-1)].add(jnp.where(small_old, pprob, 0.0).reshape(-1))

    closed = jax.lax.cond(jnp.any(small_old), prune_old, lambda c: c, closed)
    small_new = new_p < cfg.prune_eps
    closed = closed.at[new_n].add(jnp.where(small_new, new_p, 0.0))
    pprob = jnp.where(small_old, 0.0, pprob).at[idx].set(jnp.where(small_new, 0.0, new_p))
    person = st.slot_person.at[idx].set(new_n)
    valid = valid.at[idx].set(True) & (jnp.sum(pprob, axis=1) > 0)
    return idx, valid, person, pprob, closed


def _report(cfg: ADFConfig, st: ADFState, post, qlab, counter, valid, itop, qtop) -> ADFInfo:
    """The step's report; ``itop`` (the mixture's ranking of the links) and ``qtop``
    (the new slot's ranking of the persons) are reused when they are long enough."""
    w, w0, lz, impossible = post
    S = w.shape[0]
    L = min(cfg.link_out, S)
    lp, li = (w[itop[:L]], itop[:L]) if L <= itop.shape[0] else _top(w, L)
    link_obs = jnp.where(lp > 0, st.slot_obs[li], -1)
    if L < cfg.link_out:
        link_obs = jnp.concatenate([link_obs, -jnp.ones(cfg.link_out - L, link_obs.dtype)])
        lp = jnp.concatenate([lp, jnp.zeros(cfg.link_out - L)])
    Lb = min(cfg.label_out, qlab.shape[0])
    bp, bn = (qlab[qtop[:Lb]], qtop[:Lb]) if Lb <= qtop.shape[0] else _top(qlab, Lb)
    cc = jnp.arange(counter.shape[0], dtype=counter.dtype)
    cm = jnp.sum(counter * cc)
    cs = jnp.sqrt(jnp.maximum(jnp.sum(counter * cc * cc) - cm * cm, 0.0))
    return ADFInfo(link_obs, lp, w0, bn, bp, cm, cs, lz, jnp.sum(valid), impossible)


def _filter_insert(m: ADFParams, st: ADFState, pprob, qlab, new_p, new_n, tq):
    """Birth-leave filtering form, the slot bookkeeping's inputs: the eviction key
    (S,), each old end's open mass times the probability that its person is still in
    the building, open_j (1 - rho / g_j), lowest evicted first; the new end's top-W
    persons rescaled to carry all of its mass (it is surely someone's latest end; the
    persons left out do not move it to 'closed', so person rows may exceed 1 there),
    and the label mass that ``_insert_slot`` takes out of 'closed' accordingly (N,)."""
    key = jnp.sum(pprob, axis=1) * (1.0 - m.path.leave_prob / jnp.exp(_log_stay(m, st, tq)))
    new_p = new_p * (jnp.sum(qlab) / jnp.maximum(jnp.sum(new_p), 1e-300))
    return key, jnp.zeros_like(qlab).at[new_n].add(new_p), new_p


def project(m: ADFParams, st: ADFState, x, posterior, cfg: ADFConfig):
    """Spec steps 3-6 and the slot bookkeeping: ``(new state, ADFInfo)``."""
    o, cam, be, bq, te, tq = x
    w, w0, _, _ = posterior
    if cfg.birth_leave:
        st = _close_expired(m, st, te)
    S, W = st.slot_pprob.shape
    r = o.shape[0]
    qlab, counter, pprob, never, new_p, new_n = _labels_counter_pointers(st, w, w0, W)
    Mx = min(cfg.mix_top, S)
    (na, nk, ne, nC, nCinv, nld), comps, itop = _new_slice_niw(m, st, o, w, w0, Mx)
    sa, sk, se, sC, sCinv, sld = _slot_niws(st)
    sln, spsi = st.slot_lognorm, st.slot_psi_next
    if cfg.old_update == "seed":
        M = min(cfg.old_update_top, Mx)
        sa, sk, se, sC, sCinv, sld = _old_slices_seed(st, w, comps, itop, M)
        sln = niw_predictive_lognorm(sk, se, sld, r)
        spsi = niw_sum_digamma(se + 1.0, r)
    key, qclose = None, qlab
    if cfg.birth_leave == FILTER:
        key, qclose, new_p = _filter_insert(m, st, pprob, qlab, new_p, new_n, tq)
    idx, valid, person, pprob, closed = _insert_slot(cfg, st, qclose, pprob, new_p, new_n, key)
    new_state = ADFState(
        k=st.k + 1,
        last_tq=tq,
        counter=counter,
        never=never,
        closed=closed,
        slot_valid=valid,
        slot_obs=st.slot_obs.at[idx].set(st.k),
        slot_cam=st.slot_cam.at[idx].set(cam),
        slot_bq=st.slot_bq.at[idx].set(bq),
        slot_tq=st.slot_tq.at[idx].set(tq),
        slot_a=sa.at[idx].set(na),
        slot_kappa=sk.at[idx].set(nk),
        slot_eta=se.at[idx].set(ne),
        slot_C=sC.at[idx].set(nC),
        slot_Cinv=sCinv.at[idx].set(nCinv),
        slot_logdetC=sld.at[idx].set(nld),
        slot_lognorm=sln.at[idx].set(niw_predictive_lognorm(nk, ne, nld, r)),
        slot_psi_next=spsi.at[idx].set(niw_sum_digamma(ne + 1.0, r)),
        slot_person=person,
        slot_pprob=pprob,
    )
    return new_state, _report(cfg, st, posterior, qlab, counter, valid, itop, new_n)


def window_predict(m: ADFParams, st: ADFState, xs, uniform: bool, birth_leave: bool = False):
    """Single-step link log weights of a window of observations against one belief
    ``(logw (L, S), logw0 (L,))``, and the link prior of a window-internal link (an
    open end of mass 1) for the fixed-lag revision."""
    logw, logw0 = jax.vmap(lambda x: predict(m, st, x, uniform, birth_leave))(xs)
    if birth_leave:  # a window-internal end seen just now: S = 1
        lp_win = jnp.log1p(-m.path.leave_prob)
    elif uniform:
        c = jnp.arange(st.counter.shape[0], dtype=st.counter.dtype)
        lp_win = jnp.log(jnp.sum(st.counter / (c + 1.0)))
    else:
        tot = jnp.sum(st.slot_pprob)
        lp_win = jnp.log1p(-m.p_new) - jnp.log(jnp.where(tot > 0, tot, 1.0))
    return logw, logw0, lp_win


def _record_counter(st: ADFState):
    return st.counter


@cache
def zajdel_hooks(cfg: ADFConfig, uniform: bool) -> ADFHooks:
    """The driver hooks for one configuration (cached: the same object per
    ``(cfg, uniform)``, so the driver's compiled functions are reused)."""
    return ADFHooks(
        predict=partial(predict, uniform=uniform, birth_leave=cfg.birth_leave),
        condition=condition,
        project=partial(project, cfg=cfg),
        record=_record_counter if cfg.record_counter else None,
        window_predict=partial(window_predict, uniform=uniform, birth_leave=cfg.birth_leave),
    )
