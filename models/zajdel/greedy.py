r"""Single-hypothesis greedy baseline (the T = 1 tracker of seed 000, table 1): each
observation joins its best link (continue one of the current tracks or start a new
one) under the same model as the ADF: label prior, exact NIW Student-t predictive of
the track's appearances so far, and the path model from the track's last observation.
"""

from __future__ import annotations

import numpy as np

from inference.adf.niw import NIW, niw_predictive_logpdf_np, niw_update_np
from models.zajdel.data import validate_observations
from models.zajdel.params import ZajdelParams
from models.zajdel.path import log_p_delta, log_p_delta0

__all__ = ["greedy_labels"]


def greedy_labels(obs, params: ZajdelParams) -> np.ndarray:
    """Greedy partition of ``num_obs`` observations: canonical labels (num_obs,).

    Vectorised over the current tracks; one pass over the observations.
    """
    r = params.obs_dim
    obs = validate_observations(obs, r, params.path.num_cameras, params.path.num_borders)
    K = obs.num_obs
    prior = NIW(*(np.asarray(x, float) for x in params.prior))
    cap = max(K, 1)
    ta = np.zeros((cap, r))
    tk = np.ones(cap)
    te = np.full(cap, r + 2.0)
    tC = np.broadcast_to(np.eye(r), (cap, r, r)).copy()
    cam = np.zeros(cap, np.int64)
    bq = np.zeros(cap, np.int64)
    tq = np.zeros(cap)
    labels = np.empty(K, np.int64)
    T = 0
    for k in range(K):
        o = obs.appearance[k]
        s_new = niw_predictive_logpdf_np(o, prior) + log_p_delta0(
            params.path, obs.camera[k], obs.border_enter[k]
        )
        if params.p_new is None:
            lp_new = lp_old = -np.log(T + 1.0)
        else:
            lp_new = np.log(params.p_new) if T > 0 else 0.0
            lp_old = np.log1p(-params.p_new) - np.log(max(T, 1))
        best = -1
        best_score = s_new + lp_new
        if T > 0:
            th = NIW(ta[:T], tk[:T], te[:T], tC[:T])
            s = niw_predictive_logpdf_np(o[None, :], th) + log_p_delta(
                params.path, cam[:T], bq[:T], tq[:T], obs.camera[k], obs.border_enter[k], obs.t_enter[k]
            )
            s = s + lp_old
            j = int(np.argmax(s))
            if s[j] > best_score:
                best, best_score = j, s[j]
        if best < 0:
            best = T
            ta[T], tk[T], te[T], tC[T] = prior.a, prior.kappa, prior.eta, prior.C
            T += 1
        upd = niw_update_np(NIW(ta[best], tk[best], te[best], tC[best]), o)
        ta[best], tk[best], te[best], tC[best] = upd
        cam[best], bq[best], tq[best] = obs.camera[k], obs.border_quit[k], obs.t_quit[k]
        labels[k] = best
    return labels
