r"""The same ADF as :mod:`models.zajdel.tracker`, written as a plain numpy loop over
candidate links and mixture components: the baseline of ``speedup_vs_numpy_loop`` in
``benchmarks/zajdel_adf.py``, and the regression oracle of the tracker's tests
(``tests/models/zajdel/test_zajdel_adf.py``). It is a frozen, independent
implementation of the tracker as it was before the ADF driver moved to
:mod:`inference.adf.driver` (own Student-t, own NIW update and projection with
scipy's digamma), so it lives here, outside the library.

It follows the tracker step by step (seed 002, section 1.4.3; spec "One-slice
update"): link prior, Student-t x path link weights, label posterior, counter,
pointers, KL projection of the new slice's NIW mixture (expected statistics summed
component by component, Newton on eta with scipy's digamma), the old-slice update,
slot insertion / eviction and pruning with the same rules. Deliberately unvectorised:
do not use it for real work.
"""

from __future__ import annotations

import numpy as np
from scipy.special import digamma, gammaln, logsumexp, polygamma

from models.zajdel.params import ZajdelParams
from models.zajdel.path import log_p_delta, log_p_delta0
from models.zajdel.tracker import ADFConfig

__all__ = ["NumpyLoopADF"]


def _t_logpdf(o, a, kappa, eta, C):
    r = o.shape[0]
    nu = eta - r + 1.0
    scale = C * (kappa + 1.0) / (kappa * nu)
    L = np.linalg.cholesky(scale)
    z = np.linalg.solve(L, o - a)
    return (
        gammaln(0.5 * (nu + r))
        - gammaln(0.5 * nu)
        - 0.5 * r * np.log(nu * np.pi)
        - np.log(np.diag(L)).sum()
        - 0.5 * (nu + r) * np.log1p(z @ z / nu)
    )


def _project(weights, comps, r):
    """KL projection of sum_m w_m NIW(a_m, kappa_m, eta_m, C_m): loop over components."""
    tot = sum(weights)
    P = np.zeros((r, r))
    h = np.zeros(r)
    s = 0.0
    g = 0.0
    i = np.arange(r)
    for w, (a, kappa, eta, C) in zip(weights, comps):
        if w <= 0:
            continue
        w = w / tot
        Cinv = np.linalg.inv(C)
        Pm = eta * Cinv
        P += w * Pm
        h += w * Pm @ a
        s += w * (r / kappa + a @ Pm @ a)
        g += w * (np.linalg.slogdet(C)[1] - r * np.log(2.0) - digamma(0.5 * (eta - i)).sum())
    P = 0.5 * (P + P.T)
    logdetP = np.linalg.slogdet(P)[1]
    gap = max(g + logdetP, 1e-300)
    x = np.log(max(r * (r + 1.0) / (2.0 * gap), 1e-8))
    target = g + logdetP + r * np.log(2.0)
    for _ in range(60):
        eta = (r - 1.0) + np.exp(x)
        f = r * np.log(eta) - digamma(0.5 * (eta - i)).sum() - target
        df = (r / eta - 0.5 * polygamma(1, 0.5 * (eta - i)).sum()) * (eta - (r - 1.0))
        step = np.clip(f / df, -2.0, 2.0)
        if not np.isfinite(step):
            break
        x -= step
        if abs(step) <= 1e-14:
            break
    eta = (r - 1.0) + np.exp(x)
    Pinv = np.linalg.inv(P)
    a = Pinv @ h
    kappa = r / (s - a @ h)
    return a, kappa, eta, eta * Pinv


class NumpyLoopADF:
    """Plain-loop numpy twin of :class:`models.zajdel.tracker.ZajdelADF` (same params,
    same :class:`ADFConfig`; ``num_persons`` fixed capacity)."""

    def __init__(self, params: ZajdelParams, config: ADFConfig, num_persons: int):
        self.p = params
        self.cfg = config
        self.N = num_persons
        self.r = params.obs_dim
        S, W = config.max_open, config.persons_per_slot
        pr = params.prior
        self.counter = np.zeros(num_persons + 1)
        self.counter[0] = 1.0
        self.never = np.ones(num_persons)
        self.closed = np.zeros(num_persons)
        self.valid = np.zeros(S, bool)
        self.sobs = -np.ones(S, np.int64)
        self.cam = np.zeros(S, np.int64)
        self.bq = np.zeros(S, np.int64)
        self.tq = np.zeros(S)
        self.niw = [
            (np.asarray(pr.a, float), float(pr.kappa), float(pr.eta), np.asarray(pr.C, float))
        ] * S
        self.person = np.zeros((S, W), np.int64)
        self.pprob = np.zeros((S, W))
        self.k = 0

    def step(self, o, cam, be, bq, te, tq):
        """One observation; returns (link_obs (S,), link_prob (S,), new_prob, loglik,
        label posterior q_k(l_k) (N,), counter mean)."""
        cfg, pr = self.cfg, self.p.prior
        prior = (np.asarray(pr.a, float), float(pr.kappa), float(pr.eta), np.asarray(pr.C, float))
        open_ = np.array([self.pprob[j].sum() for j in range(cfg.max_open)])
        w, w0, lz = self._link_weights(o, cam, be, te, prior, open_)
        qlab, pprob, new_n, new_p = self._labels_and_counter(w, w0, open_)
        new_niw, niw = self._new_slice(o, w, w0, prior)
        idx = self._insert_slot(qlab, pprob, new_n, new_p)
        link_obs = np.where(w > 0, self.sobs, -1)
        self.sobs[idx] = self.k
        self.cam[idx], self.bq[idx], self.tq[idx] = cam, bq, tq
        niw[idx] = new_niw
        self.niw = niw
        self.k += 1
        cmean = float(np.arange(self.counter.size) @ self.counter)
        return link_obs, w, w0, lz, qlab, cmean

    def _link_weights(self, o, cam, be, te, prior, open_):
        """Posterior of each candidate link (S,) and of a new person, and log p(o_k | past)."""
        p, S = self.p, self.cfg.max_open
        valid = self.valid & (open_ > 0)
        logw = np.full(S, -np.inf)
        if p.p_new is None:
            e = sum(self.counter[c] / (c + 1.0) for c in range(self.counter.size))
            lp_new = np.log(e)
        else:
            tot = sum(open_[j] for j in range(S) if valid[j])
            lp_new = np.log(p.p_new) if tot > 0 else 0.0
        for j in range(S):  # loop over candidate links
            if not valid[j]:
                continue
            if p.p_new is None:
                lp = np.log(e) + np.log(open_[j])
            else:
                lp = np.log1p(-p.p_new) + np.log(open_[j]) - np.log(tot)
            a, kappa, eta, C = self.niw[j]
            logw[j] = (
                lp
                + _t_logpdf(o, a, kappa, eta, C)
                + float(log_p_delta(p.path, self.cam[j], self.bq[j], self.tq[j], cam, be, te))
            )
        logw0 = lp_new + _t_logpdf(o, *prior) + float(log_p_delta0(p.path, cam, be))
        lz = logsumexp(np.append(logw, logw0))
        if not np.isfinite(lz):
            return np.zeros(S), 1.0, lz
        return np.exp(logw - lz), float(np.exp(logw0 - lz)), lz

    def _labels_and_counter(self, w, w0, open_):
        """Label posterior q_k (N,), the counter and never-seen updates (in place), the
        slots' person probabilities with q_k taken out, and the new slot's persons."""
        cfg, N = self.cfg, self.N
        qlab = np.zeros(N)
        for j in range(cfg.max_open):
            if open_[j] > 0:
                for i in range(cfg.persons_per_slot):
                    qlab[self.person[j, i]] += self.pprob[j, i] * (w[j] / open_[j])
        qlab += w0 * self.counter[:N]
        self.counter = (1.0 - w0) * self.counter + w0 * np.concatenate([[0.0], self.counter[:-1]])
        self.counter = np.where(self.counter >= 1e-15, self.counter, 0.0)
        self.counter = self.counter / self.counter.sum()
        pprob = self.pprob * (1.0 - qlab[self.person])
        self.never = self.never * (1.0 - qlab)
        order = np.argsort(-qlab.astype(np.float32), kind="stable")[: cfg.persons_per_slot]
        return qlab, pprob, order, qlab[order]

    def _new_slice(self, o, w, w0, prior):
        """KL projection of the new slice's mixture over links (loop over components), and
        the slots' NIWs after the old-slice update."""
        cfg, r, S = self.cfg, self.r, self.cfg.max_open
        comps, weights, upd = [], [], {}
        mix = np.argsort(-w.astype(np.float32), kind="stable")[: min(cfg.mix_top, S)]
        for j in mix:  # loop over the mixture components (the mix_top best links)
            a, kappa, eta, C = self.niw[j]
            d = o - a
            upd[j] = (
                a + d / (kappa + 1),
                kappa + 1,
                eta + 1,
                C + kappa / (kappa + 1) * np.outer(d, d),
            )
            comps.append(upd[j])
            weights.append(w[j])
        a, kappa, eta, C = prior
        d = o - a
        comps.append(
            (a + d / (kappa + 1), kappa + 1, eta + 1, C + kappa / (kappa + 1) * np.outer(d, d))
        )
        weights.append(w0)
        new_niw = _project(weights, comps, r)
        niw = list(self.niw)
        if cfg.old_update == "seed":
            top = np.argsort(-w.astype(np.float32), kind="stable")[: min(cfg.old_update_top, S)]
            for j in top:
                if w[j] > 0:
                    niw[j] = _project([w[j], 1.0 - w[j]], [upd[j], self.niw[j]], r)
        return new_niw, niw

    def _insert_slot(self, qlab, pprob, new_n, new_p):
        """Closed-person mass, slot insertion (a free slot, else the oldest) and pruning,
        in place; returns the new slot's index."""
        cfg, S = self.cfg, self.cfg.max_open
        closed = self.closed * (1.0 - qlab)
        closed = closed + qlab
        for n, q in zip(new_n, new_p):
            closed[n] -= q
        valid = self.valid & (pprob.sum(1) > 0)
        if (~valid).any():
            idx = int(np.argmax(~valid))
        else:
            idx = int(np.argmin(np.where(valid, self.tq, np.inf)))
        if valid[idx]:
            for i in range(cfg.persons_per_slot):
                closed[self.person[idx, i]] += pprob[idx, i]
        valid[idx] = True
        pprob[idx] = new_p
        self.person[idx] = new_n
        small = pprob < cfg.prune_eps
        for j in range(S):
            for i in range(cfg.persons_per_slot):
                if small[j, i]:
                    closed[self.person[j, i]] += pprob[j, i]
        pprob[small] = 0.0
        self.closed = closed
        self.valid = valid & (pprob.sum(1) > 0)
        self.pprob = pprob
        return idx

    def run(self, obs, full: bool = False):
        """Filter a batch; returns (link_obs (K, S), link_prob (K, S), new_prob (K,)) and
        with ``full`` also (loglik (K,), label posterior (K, N), counter mean (K,))."""
        out = [
            self.step(
                obs.appearance[k],
                obs.camera[k],
                obs.border_enter[k],
                obs.border_quit[k],
                obs.t_enter[k],
                obs.t_quit[k],
            )
            for k in range(obs.num_obs)
        ]
        res = (
            np.stack([o[0] for o in out]),
            np.stack([o[1] for o in out]),
            np.array([o[2] for o in out]),
        )
        if full:
            res = res + (
                np.array([o[3] for o in out]),
                np.stack([o[4] for o in out]),
                np.array([o[5] for o in out]),
            )
        return res
