r"""Fixed-lag revision of the Zajdel ADF (spec "Fixed-lag revision", beyond the seed):
the ``revise`` hook of :func:`inference.adf.driver.adf_filter_lag`.

y_k's link posterior is taken from an exact enumeration of the links of the window
y_k..y_{k+L} under the current factorised belief: each window observation continues
one of its ``lag_branch`` best open slots, an earlier window observation, or is new;
a slot or window observation is continued at most once. Appearance predictives along
each hypothesised chain are exact conjugate NIW updates; the single-step scores
(link prior, appearance, path) come from the model's ``window_predict`` hook.
"""

from __future__ import annotations

import numpy as np
from scipy.special import logsumexp

from inference.adf.niw import NIW, niw_predictive_logpdf_np
from models.zajdel.adf_types import ADFConfig, ADFState
from models.zajdel.data import Observations
from models.zajdel.params import ZajdelParams
from models.zajdel.path import log_p_delta

__all__ = ["lag_revision"]


def _enumerate_parents(cand, cand_ok, n: int, S: int) -> np.ndarray:
    """Every joint choice of parents of the n window observations, (num_hyp, n): code
    s in [0, S) a slot, S + i' window observation i', -1 new; no parent used twice."""
    combos = np.zeros((1, 0), np.int64)
    for i in range(n):  # window positions (<= lag + 1), vectorised over combos
        opts = np.concatenate([cand[i][cand_ok[i]], S + np.arange(i), [-1]])
        combos = np.concatenate(
            [np.repeat(combos, opts.size, 0), np.tile(opts, combos.shape[0])[:, None]], axis=1
        )
        par = combos[:, -1]
        dup = (combos[:, :-1] == par[:, None]) & (par[:, None] >= 0)
        combos = combos[~dup.any(1)]
    return combos


def _chain_predictive(prior: NIW, slot, pos, app, origin, members, o):
    """log Student-t of o under NIW(origin) updated with the window members
    (closed-form batch conjugate update). origin (U,) slot id or -1 (prior),
    members (U,) bitmask over the window rows of ``app``."""
    n = app.shape[0]
    M = ((members[:, None] >> np.arange(n)[None, :]) & 1).astype(float)  # (U, n)
    pri = origin < 0
    oi = np.where(pri, 0, pos[np.maximum(origin, 0)])
    a = np.where(pri[:, None], prior.a, slot["slot_a"][oi])
    kap = np.where(pri, prior.kappa, slot["slot_kappa"][oi])
    eta = np.where(pri, prior.eta, slot["slot_eta"][oi])
    C = np.where(pri[:, None, None], prior.C, slot["slot_C"][oi])
    cnt = M.sum(1)
    S1 = M @ app
    S2 = np.einsum("uk,ki,kj->uij", M, app, app)
    kn = kap + cnt
    an = (kap[:, None] * a + S1) / kn[:, None]
    Cn = (
        C
        + S2
        + kap[:, None, None] * a[:, :, None] * a[:, None, :]
        - kn[:, None, None] * an[:, :, None] * an[:, None, :]
    )
    Cn = 0.5 * (Cn + np.swapaxes(Cn, 1, 2))
    return niw_predictive_logpdf_np(o[None, :], NIW(an, kn, eta + cnt, Cn))


def _score_hypotheses(
    params: ZajdelParams, st: ADFState, o: Observations, idx, combos, cand, logw, logw0, lp_win
):
    """Log score of every window hypothesis (num_hyp,)."""
    n, S = len(idx), logw.shape[1]
    used = np.unique(np.concatenate([cand.reshape(-1), [0]]))  # slot 0: a finite filler
    slot = {
        f: np.asarray(getattr(st, f))[used] for f in ("slot_a", "slot_kappa", "slot_eta", "slot_C")
    }
    pos = np.full(S, -1)
    pos[used] = np.arange(used.size)
    app = o.appearance[idx]
    N = combos.shape[0]
    rows = np.arange(N)
    origin = np.zeros((N, n), np.int64)
    members = np.zeros((N, n), np.int64)
    score = np.zeros(N)
    for i in range(n):
        par = combos[:, i]
        is_slot, is_win, is_new = (par >= 0) & (par < S), par >= S, par < 0
        ip = np.where(is_win, par - S, 0)
        origin[:, i] = np.where(is_slot, par, np.where(is_win, origin[rows, ip], -1))
        members[:, i] = np.where(is_win, members[rows, ip] | (1 << ip), 0)
        # direct slot links and new: the single-step scores (prior, appearance, path)
        score[is_slot] += logw[i, par[is_slot]]
        score[is_new] += logw0[i]
        if is_win.any():  # a chain through earlier window members: prior + path + NIW
            j, k = idx[:i], idx[i]  # the path density depends only on which member (< i)
            pd = log_p_delta(params.path, o.camera[j], o.border_quit[j], o.t_quit[j],
                             o.camera[k], o.border_enter[k], o.t_enter[k])  # fmt: skip
            score[is_win] += lp_win + pd[ip[is_win]]
            # one predictive per distinct (origin, members): origin in [-1, S), members < 2**n
            code = (origin[is_win, i] + 1) * (1 << n) + members[is_win, i]
            uc, inv = np.unique(code, return_inverse=True)
            vals = _chain_predictive(params.prior, slot, pos, app, uc // (1 << n) - 1,
                                     uc % (1 << n), app[i])  # fmt: skip
            score[is_win] += vals[inv.reshape(-1)]
    return score


def lag_revision(
    params: ZajdelParams, cfg: ADFConfig, st: ADFState, o: Observations, idx, logw, logw0, lp_win
):
    """y_k's revised link weights from the window ``idx = (k, .., k + n - 1)``.

    Parameters
    ----------
    params, cfg : the tracker's parameters and configuration
    st : the belief before y_k
    o : the run's observations (validated); ``idx`` (n,) the window's indices into it
    logw (n, S), logw0 (n,) : single-step link log weights of the window observations
    lp_win : log link prior of a window-internal link (an open end of mass 1)

    Returns
    -------
    (w (S,), w0, log normaliser of y_k's single-step weights). The enumerated
    candidates of y_k share their single-step mass in proportion to the window
    posterior; the other links keep their single-step weights.
    """
    n = len(idx)
    S = logw.shape[1]
    allw = np.concatenate([logw[0], logw0[:1]])
    if not np.isfinite(allw).any():
        return np.zeros(S), 1.0, -np.inf
    lz0 = float(logsumexp(allw))
    w_all = np.exp(allw - lz0)
    if n == 1:
        return w_all[:S], float(w_all[S]), lz0
    B = min(cfg.lag_branch, S)
    cand = np.argsort(-logw, axis=1)[:, :B]  # (n, B) slot ids per window obs
    cand_ok = np.take_along_axis(np.isfinite(logw), cand, 1)
    combos = _enumerate_parents(cand, cand_ok, n, S)
    score = _score_hypotheses(
        params, st, o, idx, combos, np.where(cand_ok, cand, 0), logw, logw0, lp_win
    )
    post = np.exp(score - logsumexp(score))
    p0 = combos[:, 0]
    top = np.zeros(S + 1)
    np.add.at(top, np.where(p0 >= 0, p0, S), post)
    sel = np.concatenate([cand[0][cand_ok[0]], [S]])
    mass = w_all[sel].sum()
    w_all[sel] = top[sel] / top[sel].sum() * mass
    return w_all[:S], float(w_all[S]), lz0
