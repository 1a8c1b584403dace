"""One frame's RJ-MCMC chain of the seed 003 tracker: its target (eq. 2 with the
likelihood of eqs. 8-10 and the interaction prior of sec. 3.2) and its six moves (sec. 3.4:
add / delete driven by the detector, stay / leave, switch, update), declared to
:mod:`inference.mcmc`, which runs the chain and accepts with eq. 11.

:class:`FrameChain` holds the working state of one frame (updated in place by the
accepted moves); :data:`MOVES` declares the moves to :class:`inference.mcmc.MoveKernel`.
:class:`models.rjmcmc3d.tracker.RJMCMCTracker` builds a chain per frame and turns its
samples into the next frame's state. Moved here from :mod:`models.rjmcmc3d.tracker`, which
still exports :class:`FrameChain`, :data:`MOVES` and :data:`MOVE_NAMES`; no behaviour change.
"""

from __future__ import annotations

import functools
import math
import time
from typing import TYPE_CHECKING

import numpy as np
from scipy.special import i0e

from inference.mcmc import Move, MoveKernel, Proposal, sample
from models.rjmcmc3d import compiled
from models.rjmcmc3d.compiled import (
    add_log_q,
    far_detections,
    interaction_row,
    update_log_q_at,
    update_log_q_pair,
)
from models.rjmcmc3d.likelihood import Config, IncrementalLikelihood, full_loglik, prepare_frame
from models.rjmcmc3d.model import LOG_2PI, gauss2_logpdf, predict
from models.rjmcmc3d.types import Frame

if TYPE_CHECKING:
    from models.rjmcmc3d.tracker import RJMCMCTracker, TrackState

__all__ = ["ADD", "DELETE", "STAY", "LEAVE", "SWITCH", "UPDATE", "MOVE_NAMES", "REVERSE", "MOVES",
           "FrameChain"]

MOVE_NAMES = ("add", "delete", "stay", "leave", "switch", "update")
ADD, DELETE, STAY, LEAVE, SWITCH, UPDATE = range(6)
REVERSE = (DELETE, ADD, LEAVE, STAY, SWITCH, UPDATE)


class FrameChain:
    """Working state of one frame's chain (updated in place by the accepted moves).

    Built by :meth:`models.rjmcmc3d.tracker.RJMCMCTracker.frame_chain`; :meth:`run` samples it.
    """

    def __init__(self, tracker: RJMCMCTracker, state: TrackState, frame: Frame, likelihood: str):
        p = tracker.params
        self.p = p
        self.t = tracker
        self.M = p.max_objects
        self.scene = tracker.scene
        self.proj = tracker.projector
        self.data = prepare_frame(p, frame)
        self.likelihood = likelihood
        fl = self.scene.floor
        self.floor = fl.tolist()
        self.log_area = math.log((fl[1] - fl[0]) * (fl[3] - fl[2]))
        self.ta = p.tau * p.a
        self._predict(state)
        self._detections(frame)
        # colour references
        self.refs = state.refs
        self.nref = state.nref
        self.sref = np.sqrt(state.refs)
        self._initial_configuration()
        self.probs = np.asarray(p.move_probs)
        self._kernel_memo = {}
        self.lik_time = 0.0  # seconds spent projecting boxes and evaluating the likelihood

    def _predict(self, state: TrackState) -> None:
        """Previous-frame summary -> prediction (eq. 7), height, orientation, leave terms."""
        p = self.p
        self.prev = state.alive.copy()
        self.prev_l = self.prev.tolist()
        m, P = predict(p, self.t.noise, state.mean, state.cov)
        self.m = m
        self.P = P
        Puu = P[:, :2, :2] + 1e-9 * np.eye(2)
        self.Luu = np.linalg.cholesky(Puu)
        # gain of u_dot given u: G = P_vu P_uu^{-1} (Cholesky solve)
        self.Gain = np.swapaxes(np.linalg.solve(Puu, np.swapaxes(P[:, 2:, :2], -1, -2)), -1, -2)
        self.m_l = m.tolist()
        self.Luu_l = self.Luu.tolist()
        self.Gain_l = self.Gain.tolist()
        self.h_pred = p.h_mean + p.h_rho * (state.h - p.h_mean)
        speed = np.hypot(m[:, 2], m[:, 3])
        wv = np.minimum(speed / 0.5, 2.0)
        self.alpha_pred = np.arctan2(
            np.sin(state.alpha) + wv * m[:, 3] / np.maximum(speed, 1e-9),
            np.cos(state.alpha) + wv * m[:, 2] / np.maximum(speed, 1e-9),
        )
        inside = self._signed_inside(m[:, :2])
        z = np.clip(inside / (p.leave_ramp / 4.0), -50, 50)
        self.p_leave = p.p_leave_inside + (0.999 - p.p_leave_inside) / (1.0 + np.exp(z))
        self.log_vm = -math.log(2 * math.pi * i0e(p.alpha_kappa))
        self.h_pred_l = self.h_pred.tolist()
        self.alpha_pred_l = self.alpha_pred.tolist()
        self.p_leave_l = self.p_leave.tolist()

    def _detections(self, frame: Frame) -> None:
        """Detections inside the floor, with their single-view covariances (sec. 3.4)."""
        p = self.p
        sel = self._signed_inside(frame.det_ground) > 0
        self.det = frame.det_ground[sel]
        self.det_l = self.det.tolist()
        dv = frame.det_view[sel]
        if p.ground_noise:
            i, j = self.t.noise.index(self.det)
            cov = self.t.noise.view_cov[dv, i, j] + p.min_sd**2 * np.eye(2)
        else:
            cov = np.broadcast_to(p.fixed_sd**2 * np.eye(2), (len(dv), 2, 2)).copy()
        self.det_L = np.linalg.cholesky(cov) if len(dv) else np.zeros((0, 2, 2))
        gate_cov = cov + 0.3**2 * np.eye(2)
        self.det_gate_L = np.linalg.cholesky(gate_cov) if len(dv) else np.zeros((0, 2, 2))

    def _initial_configuration(self) -> None:
        """Previous people at their predicted means if inside; priors, boxes, likelihood."""
        p, M = self.p, self.M
        self.present = self.prev & (self._signed_inside(self.m[:, :2]) > 0)
        self.S = np.zeros((M, 4))  # x, y, h, alpha
        self.S[:, :2] = self.m[:, :2]
        self.S[:, 2] = np.where(self.prev, self.h_pred, p.h_mean)
        self.S[:, 3] = self.alpha_pred
        self.lp = [self._slot_prior(i, self.S[i].tolist(), bool(self.present[i])) for i in range(M)]
        self.upr = [self._upr(i, self.S[i, 0], self.S[i, 1]) for i in range(M)]
        self.upr_a = np.array(self.upr, dtype=np.float64)  # array mirror (compiled loops)
        self.boxdata = [self.proj.one(*self.S[i].tolist()) for i in range(M)]
        self.S_l = self.S.tolist()  # list mirrors of S and present (the per-move code)
        self.present_l = self.present.tolist()
        self.alive = [j for j in range(M) if self.present_l[j]]
        cfg = self._config_from_boxdata(self.boxdata, self.present)
        self.G = self._interaction_matrix()
        if self.likelihood == "incremental":
            self.lik = IncrementalLikelihood(p, self.data, cfg, self.sref, self.nref)
            self.loglik = self.lik.total
        else:
            self.lik = None
            self.loglik = full_loglik(p, self.data, cfg, self.sref, self.nref)

    # ---- geometry helpers --------------------------------------------------------------
    def _signed_inside(self, u: np.ndarray) -> np.ndarray:
        fl = self.floor
        u = np.asarray(u).reshape(-1, 2)
        return np.minimum.reduce(
            [u[:, 0] - fl[0], fl[1] - u[:, 0], u[:, 1] - fl[2], fl[3] - u[:, 1]]
        )

    def _inside(self, x: float, y: float) -> bool:
        fl = self.floor
        return fl[0] < x < fl[1] and fl[2] < y < fl[3]

    def _config_from_boxdata(self, boxdata: list, present: np.ndarray) -> Config:
        boxes = np.array([b[0] for b in boxdata], dtype=np.int64).swapaxes(0, 1)
        bbox = np.array([b[1] for b in boxdata], dtype=np.int64).swapaxes(0, 1)
        depth = np.array([b[2] for b in boxdata]).T
        return Config(boxes, bbox, depth, present.copy())

    def _config(self, S: np.ndarray, present: np.ndarray) -> Config:
        return self._config_from_boxdata([self.proj.one(*row) for row in S.tolist()], present)

    # ---- prior pieces --------------------------------------------------------------------
    def _upr(self, i: int, x: float, y: float) -> tuple[float, float]:
        """Predicted next position ``u + tau a u_dot`` with ``u_dot = E[u_dot | u]``."""
        if not self.prev_l[i]:
            return (x, y)
        m = self.m_l[i]
        G = self.Gain_l[i]
        dx, dy = x - m[0], y - m[1]
        vx = m[2] + G[0][0] * dx + G[0][1] * dy
        vy = m[3] + G[1][0] * dx + G[1][1] * dy
        return (x + self.ta * vx, y + self.ta * vy)

    def _slot_prior(self, i: int, s: list, present: bool) -> float:
        """log of the prior factors of slot ``i`` (eqs. 5-7 and the existence term)."""
        p = self.p
        if not present:
            return math.log(self.p_leave_l[i]) if self.prev_l[i] else 0.0
        x, y, h, a = s
        if not self._inside(x, y) or not 0.5 < h < 2.5:
            return -math.inf
        if self.prev_l[i]:
            L = self.Luu_l[i]
            m = self.m_l[i]
            z1 = (x - m[0]) / L[0][0]
            z2 = (y - m[1] - L[1][0] * z1) / L[1][1]
            lu = -0.5 * (z1 * z1 + z2 * z2) - math.log(L[0][0] * L[1][1]) - LOG_2PI
            zh = (h - self.h_pred_l[i]) / p.h_sd
            lh = -0.5 * zh * zh - math.log(p.h_sd) - 0.5 * LOG_2PI
            la = p.alpha_kappa * (math.cos(a - self.alpha_pred_l[i]) - 1.0) + self.log_vm
            return lu + lh + la + math.log1p(-self.p_leave_l[i])
        zh = (h - p.h_mean) / p.h_sd0
        lh = -0.5 * zh * zh - math.log(p.h_sd0) - 0.5 * LOG_2PI
        return -self.log_area + lh - LOG_2PI + p.log_p_birth

    def _pair(self, si: list, upi: tuple, sj: list, upj: tuple) -> float:
        """``g(X_i, X_j)`` of sec. 3.2 (see :func:`interaction_penalty`), scalar."""
        s_al, s_ac = self.p.shape_sd
        total = 0.0
        for dx, dy in ((si[0] - sj[0], si[1] - sj[1]), (upi[0] - upj[0], upi[1] - upj[1])):
            if dx * dx + dy * dy > 9.0:  # psi < 1e-21 beyond 3 m
                continue
            for a in (si[3], sj[3]):
                c, s = math.cos(a), math.sin(a)
                al = (dx * c + dy * s) / s_al
                ac = (-dx * s + dy * c) / s_ac
                total += math.exp(-0.5 * (al * al + ac * ac))
        return total

    def _interaction_matrix(self) -> list:
        S = self.S.tolist()
        pr = self.present.tolist()
        G = [[0.0] * self.M for _ in range(self.M)]
        for i in range(self.M):
            for j in range(i + 1, self.M):
                if pr[i] and pr[j]:
                    G[i][j] = G[j][i] = self._pair(S[i], self.upr[i], S[j], self.upr[j])
        return G

    # ---- the move machinery ------------------------------------------------------------
    def _evaluate(self, S_new: np.ndarray, present_new: np.ndarray, changed: list[int]):
        """Log target change of a proposal changing ``changed`` slots, and what to commit."""
        if len(changed) == 1 and compiled.AVAILABLE:
            return self._evaluate_one(S_new, present_new, changed[0])
        rows_s = {i: S_new[i].tolist() for i in changed}
        pr_new = present_new.tolist()
        lp_new = {i: self._slot_prior(i, rows_s[i], pr_new[i]) for i in changed}
        d_prior = sum(lp_new[i] - self.lp[i] for i in changed)
        if d_prior == -math.inf:
            return -math.inf, None
        upr_new = {i: self._upr(i, rows_s[i][0], rows_s[i][1]) for i in changed}
        rows, d_e = self._interaction_rows(rows_s, upr_new, pr_new, changed)
        d_int = -2.0 * self.p.lambda_g * d_e
        t0 = time.perf_counter()
        boxdata, d_lik, pending = self._likelihood_change(rows_s, pr_new, present_new, changed)
        self.lik_time += time.perf_counter() - t0
        commit = (S_new, present_new, changed, lp_new, upr_new, rows, boxdata, pending, d_lik)
        return d_prior + d_int + d_lik, commit

    def _interaction_rows(
        self, rows_s: dict, upr_new: dict, pr_new: list, changed: list[int]
    ) -> tuple[dict, float]:
        """The changed slots' new rows of the interaction matrix ``G`` and the change of the
        interaction energy (pairs counted once)."""
        S_l = self.S_l
        rows = {}
        d_e = 0.0
        live = [j for j in self.alive if pr_new[j]] + [
            c for c in changed if pr_new[c] and not self.present_l[c]
        ]
        for c in changed:
            row = [0.0] * self.M
            if pr_new[c] and compiled.AVAILABLE and len(changed) == 1:
                others = np.array([j for j in live if j != c], dtype=np.int64)
                row = interaction_row(
                    np.array(rows_s[c]),
                    np.array(upr_new[c]),
                    self.S,
                    self.upr_a,
                    others,
                    *self.p.shape_sd,
                ).tolist()
            elif pr_new[c]:
                sc, uc = rows_s[c], upr_new[c]
                for j in live:
                    if j == c:
                        continue
                    if j in rows_s:
                        row[j] = self._pair(sc, uc, rows_s[j], upr_new[j])
                    else:
                        row[j] = self._pair(sc, uc, S_l[j], self.upr[j])
            rows[c] = row
            old = self.G[c]
            d_e += sum(row) - sum(old) - sum(row[j] - old[j] for j in changed)
        if len(changed) == 2:
            a, b = changed
            d_e += rows[a][b] - self.G[a][b]
        return rows, d_e

    def _likelihood_change(
        self, rows_s: dict, pr_new: list, present_new: np.ndarray, changed: list[int]
    ) -> tuple[dict, float, object]:
        """The changed slots' image geometry, the log-likelihood change and the pending
        incremental update (None with the full likelihood)."""
        # a row that is some changed slot's current row (delete, leave: the same; switch:
        # the other's) reuses its projection
        S_l = self.S_l
        boxdata = {}
        for i in changed:
            row = rows_s[i]
            for j in changed:
                if S_l[j] == row:
                    boxdata[i] = self.boxdata[j]
                    break
            else:
                boxdata[i] = self.proj.one(*row)
        if self.lik is not None:
            ov = {i: (pr_new[i], *boxdata[i]) for i in changed}
            d_lik, pending = self.lik.propose(ov)
        else:
            bd = [boxdata.get(i, self.boxdata[i]) for i in range(self.M)]
            cfg = self._config_from_boxdata(bd, present_new)
            new_total = full_loglik(self.p, self.data, cfg, self.sref, self.nref)
            d_lik, pending = new_total - self.loglik, None
        return boxdata, d_lik, pending

    def _evaluate_one(self, S_new: np.ndarray, present_new: np.ndarray, c: int):
        """:meth:`_evaluate` for one changed slot ``c`` (the same arithmetic, fewer steps)."""
        row_s = S_new[c].tolist()
        pr_c = bool(present_new[c])
        lp_c = self._slot_prior(c, row_s, pr_c)
        d_prior = lp_c - self.lp[c]
        if d_prior == -math.inf:
            return -math.inf, None
        upr_c = self._upr(c, row_s[0], row_s[1])
        old = self.G[c]
        if pr_c:
            row = interaction_row(
                S_new[c], upr_c, self.S, self.upr_a, self.present, c, *self.p.shape_sd
            ).tolist()
        else:
            row = [0.0] * self.M
        d_e = sum(row) - sum(old) - (row[c] - old[c])
        d_int = -2.0 * self.p.lambda_g * d_e
        t0 = time.perf_counter()
        if self.S_l[c] == row_s:  # delete, leave: the current geometry
            boxdata = self.boxdata[c]
        elif self.lik is not None:  # arrays only; lists made if accepted (_commit)
            boxdata = (None, None, None, *self.proj.arrays(*row_s))
        else:
            boxdata = self.proj.one_arrays(*row_s)
        if self.lik is not None:
            d_lik, pending = self.lik.propose({c: (pr_c, *boxdata)})
        else:
            bd = self.boxdata.copy()
            bd[c] = boxdata
            cfg = self._config_from_boxdata(bd, present_new)
            new_total = full_loglik(self.p, self.data, cfg, self.sref, self.nref)
            d_lik, pending = new_total - self.loglik, None
        self.lik_time += time.perf_counter() - t0
        commit = (
            S_new,
            present_new,
            [c],
            {c: lp_c},
            {c: upr_c},
            {c: row},
            {c: boxdata},
            pending,
            d_lik,
        )
        return d_prior + d_int + d_lik, commit

    def _commit(self, commit) -> None:
        S_new, present_new, changed, lp_new, upr_new, rows, boxdata, pending, d_lik = commit
        self.S = S_new
        self.present = present_new
        for i in changed:
            self.S_l[i] = S_new[i].tolist()
            self.present_l[i] = bool(present_new[i])
            self.lp[i] = lp_new[i]
            self.upr[i] = upr_new[i]
            self.upr_a[i] = upr_new[i]
            self.boxdata[i] = _with_lists(boxdata[i])
            row = rows[i]
            self.G[i] = row
            for j in range(self.M):
                self.G[j][i] = row[j]
        self.alive = [j for j in range(self.M) if self.present_l[j]]
        if self.lik is not None:
            self.lik.commit(pending)
        self.loglik += d_lik

    # ---- proposal densities -------------------------------------------------------------
    def _eligible(self, present: np.ndarray) -> np.ndarray:
        """Detections far (Mahalanobis) from every present person (the add move)."""
        nd = self.det.shape[0]
        if nd == 0:
            return np.zeros(0, dtype=bool)
        idx = np.flatnonzero(present)
        if idx.size == 0:
            return np.ones(nd, dtype=bool)
        if compiled.AVAILABLE:
            return far_detections(self.det, self.det_gate_L, self.S[idx, :2], self.p.add_gate**2)
        lp = gauss2_logpdf(self.S[None, idx, :2], self.det[:, None, :], self.det_gate_L[:, None])
        L = self.det_gate_L
        maha2 = -2.0 * (lp + np.log(L[:, 0, 0] * L[:, 1, 1])[:, None] + LOG_2PI)
        return np.all(maha2 > self.p.add_gate**2, axis=1)

    def _log_q_add(self, u: np.ndarray, h: float, elig: np.ndarray) -> float:
        if compiled.AVAILABLE:
            p = self.p
            return add_log_q(
                float(u[0]), float(u[1]), h, self.det, self.det_L, elig, p.h_mean, p.h_sd0
            )
        if not elig.any():
            return -math.inf
        lp = gauss2_logpdf(u[None, :], self.det[elig], self.det_L[elig])
        mx = lp.max()
        lq = mx + math.log(np.exp(lp - mx).mean())
        zh = (h - self.p.h_mean) / self.p.h_sd0
        return float(lq) - 0.5 * zh * zh - math.log(self.p.h_sd0) - 0.5 * LOG_2PI - LOG_2PI

    def _log_pred(self, i: int, s: list) -> float:
        L = self.Luu_l[i]
        m = self.m_l[i]
        z1 = (s[0] - m[0]) / L[0][0]
        z2 = (s[1] - m[1] - L[1][0] * z1) / L[1][1]
        lu = -0.5 * (z1 * z1 + z2 * z2) - math.log(L[0][0] * L[1][1]) - LOG_2PI
        zh = (s[2] - self.h_pred_l[i]) / self.p.h_sd
        lh = -0.5 * zh * zh - math.log(self.p.h_sd) - 0.5 * LOG_2PI
        la = self.p.alpha_kappa * (math.cos(s[3] - self.alpha_pred_l[i]) - 1.0) + self.log_vm
        return lu + lh + la

    def _near(self, x: float, y: float, L: tuple) -> list:
        """Detections within the Mahalanobis gate of ``Sigma(u)`` around ``(x, y)``."""
        l00, l10, l11 = L
        g2 = self.p.det_gate**2
        out = []
        for dx, dy in self.det_l:
            z1 = (dx - x) / l00
            z2 = (dy - y - l10 * z1) / l11
            if z1 * z1 + z2 * z2 < g2:
                out.append((dx, dy))
        return out

    def _kernel_at(self, x: float, y: float) -> tuple[tuple, list]:
        """Update kernel factor and gated detections at ``(x, y)`` (memoised per frame)."""
        key = (x, y)
        got = self._kernel_memo.get(key)
        if got is None:
            L = self.t.update_chol(x, y)
            got = self._kernel_memo[key] = (L, self._near(x, y, L))
        return got

    @staticmethod
    def _lg(x: float, y: float, mx: float, my: float, L: tuple) -> float:
        l00, l10, l11 = L
        z1 = (x - mx) / l00
        z2 = (y - my - l10 * z1) / l11
        return -0.5 * (z1 * z1 + z2 * z2) - math.log(l00 * l11) - LOG_2PI

    def _log_q_update(self, x1: float, y1: float, x0: float, y0: float) -> float:
        """``log q(u1 | u0)`` of the update mixture (random walk + detection-driven)."""
        if compiled.AVAILABLE:  # one compiled call (kernel lookup, gating and mixture)
            t = self.t
            g2 = self.p.det_gate**2
            w = self.p.p_det_update
            return update_log_q_at(x1, y1, x0, y0, t._upd_a, t._origin_a, t._step, self.det, g2, w)
        L, near = self._kernel_at(x0, y0)
        l_rw = self._lg(x1, y1, x0, y0, L)
        if not near:
            return l_rw
        ls = [self._lg(x1, y1, dx, dy, L) for dx, dy in near]
        mx = max(max(ls), l_rw)
        w = self.p.p_det_update
        mix = (1 - w) * math.exp(l_rw - mx) + w * sum(math.exp(v - mx) for v in ls) / len(ls)
        return mx + math.log(mix)

    # ---- the six moves (seed 003, sec. 3.4) ---------------------------------------------
    def propose(self, rng: np.random.Generator, move: int):
        """Return ``(S_new, present_new, changed, log_q_fwd, log_q_rev)`` or ``None``.

        ``move`` indexes :data:`MOVE_NAMES` (seed 003, sec. 3.4); the proposal densities
        count only the choices possible from the current state.
        """
        return _PROPOSALS[move](self, rng)

    def _add(self, rng: np.random.Generator):
        """Add: a newborn near a detection far from every present person."""
        p = self.p
        present = self.present
        free = np.flatnonzero(~present & ~self.prev)
        elig = self._eligible(present)
        if free.size == 0 or not elig.any():
            return None
        cand = np.flatnonzero(elig)
        d = int(cand[int(rng.random() * cand.size)])
        i = int(free[0])
        u = self.det[d] + self.det_L[d] @ rng.normal(size=2)
        h = p.h_mean + p.h_sd0 * rng.normal()
        a = rng.uniform(-math.pi, math.pi)
        S = self.S.copy()
        S[i] = (u[0], u[1], h, a)
        pr = present.copy()
        pr[i] = True
        n_born = int((pr & ~self.prev).sum())
        return S, pr, [i], self._log_q_add(u, h, elig), -math.log(n_born)

    def _delete(self, rng: np.random.Generator):
        """Delete: remove a person born in this frame (reverse of add)."""
        present = self.present
        born = np.flatnonzero(present & ~self.prev)
        if born.size == 0:
            return None
        i = int(born[int(rng.random() * born.size)])
        pr = present.copy()
        pr[i] = False
        lq_rev = self._log_q_add(self.S[i, :2], float(self.S[i, 2]), self._eligible(pr))
        return self.S.copy(), pr, [i], -math.log(born.size), lq_rev

    def _stay(self, rng: np.random.Generator):
        """Stay: bring back a person of the previous frame, drawn from its prediction."""
        p = self.p
        present = self.present
        left = np.flatnonzero(self.prev & ~present)
        if left.size == 0:
            return None
        i = int(left[int(rng.random() * left.size)])
        u = self.m[i, :2] + self.Luu[i] @ rng.normal(size=2)
        h = self.h_pred_l[i] + p.h_sd * rng.normal()
        a = float(rng.vonmises(self.alpha_pred_l[i], p.alpha_kappa))
        S = self.S.copy()
        S[i] = (u[0], u[1], h, a)
        pr = present.copy()
        pr[i] = True
        n_stay = int((pr & self.prev).sum())
        lq = -math.log(left.size) + self._log_pred(i, S[i].tolist())
        return S, pr, [i], lq, -math.log(n_stay)

    def _leave(self, rng: np.random.Generator):
        """Leave: a person of the previous frame leaves (reverse of stay)."""
        present = self.present
        stay = np.flatnonzero(self.prev & present)
        if stay.size == 0:
            return None
        i = int(stay[int(rng.random() * stay.size)])
        pr = present.copy()
        pr[i] = False
        n_left = int((self.prev & ~pr).sum())
        lq_rev = -math.log(n_left) + self._log_pred(i, self.S[i].tolist())
        return self.S.copy(), pr, [i], -math.log(stay.size), lq_rev

    def _switch(self, rng: np.random.Generator):
        """Switch: exchange the states of two close people (symmetric)."""
        present = self.present
        idx = np.flatnonzero(present)
        if idx.size < 2:
            return None
        U = self.S[idx, :2]
        dist = np.hypot(U[:, None, 0] - U[None, :, 0], U[:, None, 1] - U[None, :, 1])
        ii, jj = np.nonzero(np.triu(dist < self.p.switch_dist, 1))
        if ii.size == 0:
            return None
        k = int(rng.random() * ii.size)
        a, b = int(idx[ii[k]]), int(idx[jj[k]])
        S = self.S.copy()
        S[[a, b]] = S[[b, a]]
        return S, present.copy(), [a, b], 0.0, 0.0

    def _update(self, rng: np.random.Generator):
        """Update: a ``Sigma(u)`` random walk or a jump to a gated detection (mixture)."""
        alive = self.alive
        if not alive:
            return None
        i = alive[int(rng.random() * len(alive))]
        x0, y0, h0, a0 = self.S_l[i]
        L, near = self._kernel_at(x0, y0)
        if near and rng.random() < self.p.p_det_update:
            cx, cy = near[int(rng.random() * len(near))]
        else:
            cx, cy = x0, y0
        w1, w2, w3, w4 = rng.normal(size=4).tolist()
        x1 = cx + L[0] * w1
        y1 = cy + L[1] * w1 + L[2] * w2
        S = self.S.copy()
        S[i] = (x1, y1, h0 + 0.01 * w3, (a0 + 0.3 * w4 + math.pi) % (2 * math.pi) - math.pi)
        if not self._inside(x1, y1):
            return S, self.present.copy(), [i], 0.0, -math.inf  # impossible: rejected
        if compiled.AVAILABLE:  # both densities in one compiled call
            t, p = self.t, self.p
            lq_f, lq_r = update_log_q_pair(
                x1, y1, x0, y0, t._upd_a, t._origin_a, t._step, self.det, p.det_gate**2,
                p.p_det_update,
            )  # fmt: skip
        else:
            lq_f = self._log_q_update(x1, y1, x0, y0)
            lq_r = self._log_q_update(x0, y0, x1, y1)
        return S, self.present.copy(), [i], lq_f, lq_r

    def full_loglik(self) -> float:
        """Eqs. 8-10 of the current configuration recomputed from scratch (the oracle)."""
        return full_loglik(
            self.p, self.data, self._config(self.S, self.present), self.sref, self.nref
        )

    def record(self, count: int) -> None:
        """Add the current configuration, held for ``count`` kept samples, to the sums."""
        pm = self.present.astype(float) * count
        self.cnt += pm
        self.su += pm[:, None] * self.S[:, :2]
        self.suu += pm[:, None, None] * self.S[:, :2, None] * self.S[:, None, :2]
        self.sh += pm * self.S[:, 2]
        self.sc[:, 0] += pm * np.cos(self.S[:, 3])
        self.sc[:, 1] += pm * np.sin(self.S[:, 3])

    def run(self, rng: np.random.Generator) -> dict:
        """Run the frame's chain through :func:`inference.mcmc.sample` (seed 003, eq. 11).

        Returns the moment sums of the kept samples (``presence``, ``cnt``, ``su``,
        ``suu``, ``sh``, ``sc``) and the acceptance rate of each move.
        """
        p = self.p
        M = self.M
        self.cnt, self.su, self.suu = np.zeros(M), np.zeros((M, 2)), np.zeros((M, 2, 2))
        self.sh, self.sc = np.zeros(M), np.zeros((M, 2))
        kernel = MoveKernel(MOVES, self.probs, commit=_commit)
        rec = sample(rng, kernel, self, p.num_moves, 0.0, burn_in=p.burn_in, record=_record)
        return {
            "presence": self.cnt / (p.num_moves - p.burn_in),
            "cnt": self.cnt,
            "su": self.su,
            "suu": self.suu,
            "sh": self.sh,
            "sc": self.sc,
            "accept_rate": rec.accept_rate,
        }


def _with_lists(boxdata: tuple) -> tuple:
    """A projection ``(boxes, bbox, depth, *arrays)`` with its nested lists filled in."""
    if boxdata[0] is not None:
        return boxdata
    b, bb, d = boxdata[3:6]
    return (b.tolist(), bb.tolist(), d.tolist(), b, bb, d)


def _propose_move(move: int, rng: np.random.Generator, chain: FrameChain) -> Proposal | None:
    """Declaration of move ``move`` for :class:`inference.mcmc.MoveKernel`: the proposal,
    its two log densities and the incremental log target change (eqs. 2 and 8-10)."""
    prop = _PROPOSALS[move](chain, rng)
    if prop is None:
        return None
    S_new, pr_new, changed, lq_f, lq_r = prop
    if lq_r == -math.inf:  # impossible reverse: rejected without evaluating the target
        return Proposal(None, lq_f, lq_r, -math.inf)
    delta, pending = chain._evaluate(S_new, pr_new, changed)
    return Proposal(pending, lq_f, lq_r, delta)


def _commit(chain: FrameChain, pending: tuple) -> FrameChain:
    chain._commit(pending)
    return chain


def _record(chain: FrameChain, count: int) -> None:
    chain.record(count)


_PROPOSALS = (
    FrameChain._add,
    FrameChain._delete,
    FrameChain._stay,
    FrameChain._leave,
    FrameChain._switch,
    FrameChain._update,
)

#: the six moves of seed 003, sec. 3.4, in the order of ``TrackerParams.move_probs``
MOVES = tuple(
    Move(name, functools.partial(_propose_move, m), REVERSE[m]) for m, name in enumerate(MOVE_NAMES)
)
