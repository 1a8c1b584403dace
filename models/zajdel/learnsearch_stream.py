r"""Learn-search on streams: a fixed-lag (sliding-window) form of seed 000's search.

Seed 000's search (Fig. 4, :func:`models.zajdel.learnsearch.learn_search`) keeps the T
most probable partitions of *all* observations so far and runs one EM iteration over the
whole prefix after each batch: memory and time per observation grow with the stream.
Here the hypotheses cover only the last ``window`` observations:

* **fixed lag (N-scan pruning).** When a new observation makes the window longer than
  ``window``, its oldest observation is committed to the label it has in the best
  hypothesis, and the hypotheses that label it differently are dropped: every kept
  hypothesis then agrees on the whole committed past, which is stored once;
* **track summaries.** A track is summarised by parameter-free sufficient statistics per
  camera l (count :math:`n_l`, :math:`\sum a_i`, :math:`\sum a_i a_i^T`) and its last
  observation's camera, quit border and quit time; from them the information-form sums
  :math:`(P, h, c)` of eq. A.2 are rebuilt under any parameters, so the evidence of
  tracks that reach into the committed past is exact after every EM update;
* **closed tracks.** A committed track whose last quit is more than
  :math:`\max_{p,q}(\delta_{pq} + z\,\sigma_{pq})` (``close_z`` = z) before the current
  observation's entry can no longer be continued with a non-negligible travel-time
  density (eq. 2); it leaves the hypotheses (people leave the building). The partition
  prior still counts it (the number of tracks so far, :func:`models.zajdel.scores.
  label_prior_log_prob`), so scores are those of the plain search;
* **on-line EM.** After every batch of ``batch`` observations one EM iteration
  (:func:`models.zajdel.learnsearch.em_step`, eqs. 4-6 and Appendix A) runs over the
  kept hypotheses restricted to the window (tracks truncated at the window's start),
  shrunk toward the starting parameters as in the plain search. No truth is used.

With ``window`` >= the stream length and ``close_z = None`` nothing is committed or closed
and the result is the plain search's (tested). Per observation the work is
O(T (K_open + 1) r^3) for the children's scores, with K_open the open tracks (bounded by
the people present plus the tracks born in the window), and one EM iteration per batch
costs O(T window (C r^2 + r^3)): both independent of the stream length.

Data in this library's tests and benchmarks are SIMULATED (:mod:`models.zajdel.simulate`).
"""

from __future__ import annotations

import copy
from typing import NamedTuple

import numpy as np

from dbn.checks import check_count
from dbn.errors import InputError
from models.zajdel.data import Observations, concat_observations, take, validate_observations
from models.zajdel.learnsearch import (
    IMPOSSIBLE_LOG_PROB,
    LearnSearchConfig,
    LSParams,
    _canonical,
    _check_params,
    _evidence,
    _param_change,
    _spd_inverse,
    em_step,
    partition_log_scores,
)
from models.zajdel.oracle import enumerate_partitions
from models.zajdel.path import log_p_delta, log_p_delta0
from models.zajdel.scores import canonical_labels

__all__ = ["StreamResult", "StreamSearch", "stream_learn_search"]

_LOG2PI = float(np.log(2.0 * np.pi))


class StreamResult(NamedTuple):
    """Output of :func:`stream_learn_search`.

    Attributes
    ----------
    labels : (num_obs,) canonical labels (committed past + best hypothesis of the window)
    params : LSParams, final parameters
    log_scores : (T',) scores of the final kept hypotheses (window part; differences are
        those of the full posterior); equal to the full scores when nothing was committed
    max_candidates : most children scored for one observation (T (K_open + 1))
    max_open_tracks : most open tracks (columns) held at once
    max_window : most observations held in the hypotheses at once
    em_iterations : EM iterations of the initial phase
    """

    labels: np.ndarray
    params: LSParams
    log_scores: np.ndarray
    max_candidates: int
    max_open_tracks: int
    max_window: int
    em_iterations: int


class _Par(NamedTuple):
    """Per-parameter quantities (information form)."""

    Sinv: np.ndarray  # (C, r, r)
    logdetS: np.ndarray  # (C,)
    Rinv: np.ndarray
    h0: np.ndarray
    c0: float
    bias: np.ndarray  # (C, r)


def _par(theta: LSParams) -> _Par:
    Sinv, logdetS = _spd_inverse(np.asarray(theta.noise_cov, float))
    Rinv, logdetR = _spd_inverse(np.asarray(theta.prior_cov, float))
    mu = np.asarray(theta.mean, float)
    h0 = Rinv @ mu
    return _Par(
        Sinv,
        logdetS,
        Rinv,
        h0,
        float(mu @ h0 + logdetR + mu.shape[0] * _LOG2PI),
        np.asarray(theta.bias, float),
    )


# Per-hypothesis arrays (leading axis H): window part (H, W) and track columns (H, S, ...).
_WIN = ("lab", "wpath", "wprior", "wpc", "wpb", "wpt")
_COL = ("col_id", "cnt", "A", "Q", "P", "h", "c", "E", "lcam", "lbq", "ltq", "lidx")


def _obs_terms(par: _Par, obs: Observations, i: int):
    """u_i = S^{-1}(a_i - b), c_i, the evidence of observation i alone, its camera."""
    l = int(obs.camera[i])
    z = np.asarray(obs.appearance[i], float) - par.bias[l]
    u = par.Sinv[l] @ z
    c = float(z @ u + par.logdetS[l] + z.shape[0] * _LOG2PI)
    single = float(_evidence(par.Rinv + par.Sinv[l], par.h0 + u, np.asarray(c), par.c0))
    return u, c, single, l


def _sums(par: _Par, cnt, A, Q):
    """Information-form sums (P, h, c) of eq. A.2 from per-camera statistics
    cnt (..., C), A (..., C, r) = sum a, Q (..., C, r, r) = sum a a^T."""
    r = par.h0.shape[0]
    P = par.Rinv + np.tensordot(cnt, par.Sinv, axes=(-1, 0))
    Sb = np.einsum("lij,lj->li", par.Sinv, par.bias)  # (C, r) S^{-1} b
    SA = np.einsum("lij,...lj->...li", par.Sinv, A)
    h = par.h0 + (SA - cnt[..., None] * Sb).sum(-2)
    quad = np.einsum("lij,...lji->...l", par.Sinv, Q) - 2.0 * np.einsum("lj,...lj->...l", Sb, A)
    per = (par.bias * Sb).sum(-1) + par.logdetS + r * _LOG2PI  # (C,)
    c = (quad + cnt * per).sum(-1)
    return P, h, c


def _floor(x):
    return np.maximum(x, IMPOSSIBLE_LOG_PROB)


def _init_state(labels: np.ndarray, obs: Observations, theta: LSParams, par: _Par) -> dict:
    """State of the partitions ``labels`` (H, n) of the first n observations."""
    H, n = labels.shape
    C = theta.path.num_cameras
    r = theta.obs_dim
    S = n
    st = {k: np.zeros((H, n)) for k in ("wpath", "wprior")}
    st["lab"] = labels.astype(np.int64)
    for k in ("wpc", "wpb"):
        st[k] = np.full((H, n), -1, np.int64)
    st["wpt"] = np.zeros((H, n))
    st["col_id"] = np.broadcast_to(np.arange(S), (H, S)).copy()
    st["cnt"] = np.zeros((H, S, C))
    st["A"] = np.zeros((H, S, C, r))
    st["Q"] = np.zeros((H, S, C, r, r))
    for k in ("lcam", "lbq", "lidx"):
        st[k] = np.full((H, S), -1, np.int64)
    st["ltq"] = np.zeros((H, S))
    ntr = np.zeros(H, np.int64)
    rows = np.arange(H)
    for i in range(n):
        s = labels[:, i]
        new = s >= ntr
        st["wpc"][:, i] = np.where(new, -1, st["lcam"][rows, s])
        st["wpb"][:, i] = np.where(new, -1, st["lbq"][rows, s])
        st["wpt"][:, i] = np.where(new, 0.0, st["ltq"][rows, s])
        if theta.p_new is not None and i > 0:
            old = np.log1p(-theta.p_new) - np.log(np.maximum(ntr, 1))
            st["wprior"][:, i] = np.where(new, np.log(theta.p_new), old)
        _add_obs(st, rows, s, obs, i, i)
        ntr = np.maximum(ntr, s + 1)
    st["ncol"] = ntr.copy()
    st["ntr"] = ntr
    st["win_start"] = 0
    _rebuild(st, obs, theta, par)
    return st


def _add_obs(st: dict, rows, s, obs: Observations, j: int, i: int) -> None:
    """Add observation ``obs[j]`` (stream index i) to column s[h] of every hypothesis rows[h]
    (statistics, last observation)."""
    l = int(obs.camera[j])
    a = np.asarray(obs.appearance[j], float)
    st["cnt"][rows, s, l] += 1.0
    st["A"][rows, s, l] += a
    st["Q"][rows, s, l] += np.outer(a, a)
    st["lcam"][rows, s] = l
    st["lbq"][rows, s] = int(obs.border_quit[j])
    st["ltq"][rows, s] = float(obs.t_quit[j])
    st["lidx"][rows, s] = i


def _rebuild(st: dict, win: Observations, theta: LSParams, par: _Par) -> None:
    """Recompute (P, h, c, E), the window's path terms and the scores under ``theta``
    (``win``: the window's observations, as many as ``st["lab"]`` has columns)."""
    P, h, c = _sums(par, st["cnt"], st["A"], st["Q"])
    S = P.shape[1]
    active = np.arange(S)[None, :] < st["ncol"][:, None]
    E = np.zeros(active.shape)
    E[active] = _evidence(P[active], h[active], c[active], par.c0)
    st["P"], st["h"], st["c"], st["E"] = P, h, c, E
    cam, be, te = (np.asarray(x) for x in (win.camera, win.border_enter, win.t_enter))
    start = st["wpc"] < 0
    lpd = log_p_delta(
        theta.path,
        np.maximum(st["wpc"], 0),
        np.maximum(st["wpb"], 0),
        st["wpt"],
        cam[None],
        be[None],
        te[None],
    )
    st["wpath"] = np.where(start, _floor(log_p_delta0(theta.path, cam, be))[None], _floor(lpd))
    st["score"] = E.sum(1) + st["wpath"].sum(1) + st["wprior"].sum(1)


def _grow(st: dict, need: int) -> None:
    """Make room for ``need`` columns (pad the column arrays)."""
    S = st["col_id"].shape[1]
    if need <= S:
        return
    extra = max(need - S, 4)
    for k in _COL:
        pad = [(0, 0)] * st[k].ndim
        pad[1] = (0, extra)
        st[k] = np.pad(
            st[k], pad, constant_values=-1 if k in ("col_id", "lcam", "lbq", "lidx") else 0
        )


def _gather(st: dict, parent: np.ndarray) -> dict:
    out = {k: st[k][parent] for k in _WIN + _COL + ("ncol", "ntr")}  # fancy index: a copy
    out["win_start"] = st["win_start"]
    return out


def _path_and_prior(
    st: dict, obs: Observations, j: int, l: int, theta: LSParams, smax: int
) -> tuple[np.ndarray, float, np.ndarray, np.ndarray]:
    """The path and label-prior log terms of placing ``obs[j]`` (camera ``l``) in each
    hypothesis (H rows): ``lpd`` (H, smax) after each open track's last observation,
    ``lp0`` as a new track's first, and the prior ``pj`` (H,) of joining one of ``ntr``
    tracks, ``pn`` (H,) of starting a new one (zeros without ``p_new``)."""
    be, te = int(obs.border_enter[j]), float(obs.t_enter[j])
    lpd = _floor(
        log_p_delta(
            theta.path,
            np.maximum(st["lcam"][:, :smax], 0),
            np.maximum(st["lbq"][:, :smax], 0),
            st["ltq"][:, :smax],
            l,
            be,
            te,
        )
    )
    lp0 = float(_floor(log_p_delta0(theta.path, l, be)))
    ntr = st["ntr"].astype(float)
    if theta.p_new is None:
        return lpd, lp0, np.zeros(ntr.shape[0]), np.zeros(ntr.shape[0])
    pj = np.log1p(-theta.p_new) - np.log(np.maximum(ntr, 1.0))
    pn = np.where(ntr > 0, np.log(theta.p_new), 0.0)
    return lpd, lp0, pj, pn


def _extend(st: dict, obs: Observations, j: int, i: int, theta: LSParams, par: _Par, T: int) -> int:
    """Extend every kept hypothesis by observation ``obs[j]`` (stream index i) in K_open + 1
    ways and keep the T best (seed 000, Fig. 4); returns the number of children scored."""
    _grow(st, int(st["ncol"].max()) + 1)
    H = st["score"].shape[0]
    smax = int(st["ncol"].max())
    u, ci, single, l = _obs_terms(par, obs, j)
    Pc = st["P"][:, :smax] + par.Sinv[l]
    hc = st["h"][:, :smax] + u
    cc = st["c"][:, :smax] + ci
    Ec = _evidence(Pc, hc, cc, par.c0) if smax else np.zeros((H, 0))
    lpd, lp0, pj, pn = _path_and_prior(st, obs, j, l, theta, smax)
    valid = np.arange(smax)[None, :] < st["ncol"][:, None]
    join = st["score"][:, None] + Ec - st["E"][:, :smax] + lpd + pj[:, None]
    new = st["score"] + single + lp0 + pn
    flat = np.concatenate([np.where(valid, join, -np.inf), new[:, None]], axis=1).ravel()
    order = np.argsort(-flat, kind="stable")[:T]
    order = order[np.isfinite(flat[order])]
    parent, choice = order // (smax + 1), order % (smax + 1)
    is_new = choice == smax
    col = np.where(is_new, st["ncol"][parent], choice)
    rows = np.arange(order.shape[0])
    cj = np.minimum(choice, max(smax - 1, 0))
    out = _gather(st, parent)
    label = np.where(is_new, out["ntr"], out["col_id"][rows, col])
    step_path = np.where(is_new, lp0, lpd[parent, cj] if smax else lp0)
    step_prior = np.where(is_new, pn[parent], pj[parent])
    pc = np.where(is_new, -1, out["lcam"][rows, col])
    pb = np.where(is_new, -1, out["lbq"][rows, col])
    pt = np.where(is_new, 0.0, out["ltq"][rows, col])
    for k, v in zip(_WIN, (label, step_path, step_prior, pc, pb, pt)):
        out[k] = np.concatenate([out[k], v[:, None]], axis=1)
    if smax:
        out["P"][rows, col] = np.where(
            is_new[:, None, None], par.Rinv + par.Sinv[l], Pc[parent, cj]
        )
        out["h"][rows, col] = np.where(is_new[:, None], par.h0 + u, hc[parent, cj])
        out["c"][rows, col] = np.where(is_new, ci, cc[parent, cj])
        out["E"][rows, col] = np.where(is_new, single, Ec[parent, cj])
    else:
        out["P"][rows, col], out["h"][rows, col] = par.Rinv + par.Sinv[l], par.h0 + u
        out["c"][rows, col], out["E"][rows, col] = ci, single
    out["col_id"][rows, col] = label
    _add_obs(out, rows, col, obs, j, i)
    out["ncol"] = out["ncol"] + is_new
    out["ntr"] = out["ntr"] + is_new
    out["score"] = flat[order]
    st.clear()
    st.update(out)
    return int(H * (smax + 1))


def _commit(st: dict, committed: list) -> None:
    """Commit the window's oldest observation to its label in the best hypothesis and
    drop the hypotheses that disagree (N-scan pruning); its terms leave the scores."""
    keep = st["lab"][:, 0] == st["lab"][0, 0]
    committed.append(int(st["lab"][0, 0]))
    if not keep.all():
        for k in _WIN + _COL + ("ncol", "ntr", "score"):
            st[k] = st[k][keep]
    st["score"] = st["score"] - st["wpath"][:, 0] - st["wprior"][:, 0]
    for k in _WIN:
        st[k] = st[k][:, 1:]
    st["win_start"] += 1


def _close(st: dict, te: float, gap: float) -> None:
    """Drop the committed columns whose last quit is more than ``gap`` before ``te`` in
    every hypothesis (columns of committed tracks are aligned across hypotheses)."""
    S = st["col_id"].shape[1]
    active = np.arange(S)[None, :] < st["ncol"][:, None]
    old = active & (st["lidx"] < st["win_start"]) & (te - st["ltq"] > gap)
    drop = old.all(0)
    if not drop.any():
        return
    st["score"] = st["score"] - st["E"][:, drop].sum(1)
    keep = ~drop
    keep[int(st["ncol"].max()) :] = False  # trim the spare capacity too
    for k in _COL:
        st[k] = st[k][:, keep]
    st["ncol"] = st["ncol"] - int(drop.sum())


def _close_gap(theta: LSParams, close_z: float | None) -> float:
    if close_z is None:
        return np.inf
    p = theta.path
    return float(np.max(np.asarray(p.travel_mean) + close_z * np.asarray(p.travel_std)))


def _check_stream_args(cfg: LearnSearchConfig, window: int, close_z: float | None) -> None:
    check_count("window", window)
    if close_z is not None and not (np.isfinite(close_z) and close_z > 0):
        raise InputError(f"close_z = {close_z}: must be None or a finite number > 0")
    cfg.validate()


def _initial_em(pre: Observations, parts: np.ndarray, theta: LSParams, cfg: LearnSearchConfig):
    anchor, iters = theta, 0
    if cfg.learn:
        for _ in range(cfg.em_max_iter):
            new = em_step(pre, parts, partition_log_scores(parts, pre, theta), theta, cfg, anchor)
            iters += 1
            delta = _param_change(new, theta)
            theta = new
            if delta < cfg.em_tol:
                break
    return theta, iters


class StreamSearch:
    """The fixed-lag search fed one observation at a time (the working state of
    :func:`stream_learn_search` and of the streaming protocol adapter).

    Holds only the window: the kept hypotheses over the last ``window`` observations
    (``buf``, the window's observations), the open track columns and the parameters, so
    memory is independent of the stream length; labels of committed observations are
    handed out by :meth:`pop_committed`. Mutable; :meth:`copy` is cheap (no array is ever
    written in place: every update builds new arrays, so a copy of the dict suffices).
    """

    def __init__(
        self,
        params: LSParams,
        config: LearnSearchConfig | None,
        window: int,
        close_z: float | None = 5.0,
    ) -> None:
        self.cfg = LearnSearchConfig() if config is None else config
        _check_stream_args(self.cfg, window, close_z)
        _check_params(params)
        self.start_params, self.theta, self.par = params, params, None
        self.window, self.close_z = int(window), close_z
        self.n0 = max(min(self.cfg.n0, self.window), 1)
        r = params.obs_dim
        self.buf = Observations(np.zeros((0, r)), np.zeros(0, np.int64), np.zeros(0),
                                np.zeros(0), np.zeros(0, np.int64), np.zeros(0, np.int64))  # fmt: skip
        self.st: dict | None = None
        self.committed: list = []
        self.num_seen = self.since = self.em_iterations = 0
        self.max_candidates = self.max_open_tracks = self.max_window = 0

    def copy(self) -> StreamSearch:
        """An independent copy (the protocol adapter's steps are pure)."""
        new = copy.copy(self)
        new.st = None if self.st is None else dict(self.st)
        new.committed = list(self.committed)
        return new

    def push(self, one: Observations) -> None:
        """Add one (validated) observation: extend, commit past the lag, close, learn."""
        self.buf = concat_observations([self.buf, one])
        self.num_seen += 1
        if self.st is None:
            if self.buf.num_obs >= self.n0:
                self._start()
            return
        st, T = self.st, int(self.cfg.num_hypotheses)
        j, i = self.buf.num_obs - 1, self.num_seen - 1
        cand = _extend(st, self.buf, j, i, self.theta, self.par, T)
        self.max_candidates = max(self.max_candidates, cand)
        self.max_open_tracks = max(self.max_open_tracks, int(st["ncol"].max()))
        self.max_window = max(self.max_window, st["lab"].shape[1])
        before = len(self.committed)
        while st["lab"].shape[1] > self.window:
            _commit(st, self.committed)
        self.buf = take(self.buf, slice(len(self.committed) - before, None))
        _close(st, float(self.buf.t_enter[-1]), _close_gap(self.theta, self.close_z))
        self.since += 1
        if self.since == self.cfg.batch:
            self._learn()

    def finish(self) -> None:
        """End of a batch stream: start on fewer than n0 observations, or run the last
        batch's EM iteration (as the plain search does after its last observation)."""
        if self.st is None:
            if self.buf.num_obs:
                self._start()
        elif self.since:
            self._learn()

    def _start(self) -> None:
        parts = enumerate_partitions(self.buf.num_obs)
        self.theta, self.em_iterations = _initial_em(self.buf, parts, self.theta, self.cfg)
        self.par = _par(self.theta)
        st = _init_state(parts, self.buf, self.theta, self.par)
        self.st = st
        self._keep_best()
        self.max_window = self.buf.num_obs

    def _learn(self) -> None:
        """One on-line EM iteration over the window's kept hypotheses (seed 000, eqs. 4-6)."""
        self.since = 0
        if not self.cfg.learn:
            return
        st = self.st
        self.use_params(em_step(
            self.buf, _canonical(st["lab"]), st["score"], self.theta, self.cfg, self.start_params
        ))  # fmt: skip
        _rebuild(st, self.buf, self.theta, self.par)
        self._keep_best()

    def use_params(self, theta: LSParams) -> None:
        """Take ``theta`` as the parameters, with the terms the scores precompute of them
        (:func:`_par`) once the search has started (a checkpoint's restore, an EM step)."""
        self.theta = theta
        self.par = _par(theta) if self.st is not None else None

    def _keep_best(self) -> None:
        st = self.st
        order = np.argsort(-st["score"], kind="stable")[: int(self.cfg.num_hypotheses)]
        self.st = {**_gather(st, order), "score": st["score"][order]}

    def pop_committed(self) -> np.ndarray:
        """Labels of the observations committed since the last call (in stream order)."""
        out, self.committed = np.asarray(self.committed, np.int64), []
        return out

    def window_labels(self) -> np.ndarray:
        """(W,) labels of the window's observations in the best hypothesis (the labels of
        the observations not yet started on when fewer than n0 have been seen: none)."""
        return np.zeros(0, np.int64) if self.st is None else self.st["lab"][0].copy()

    def log_scores(self) -> np.ndarray:
        """(T',) scores of the kept hypotheses (window part; see :class:`StreamResult`)."""
        return np.zeros(1) if self.st is None else self.st["score"].copy()


def stream_learn_search(
    obs: Observations,
    params: LSParams,
    config: LearnSearchConfig | None,
    window: int,
    close_z: float | None = 5.0,
) -> StreamResult:
    r"""Seed 000's learn-search over a sliding window of the stream (fixed lag ``window``).

    Parameters
    ----------
    obs : Observations (num_obs), ordered by quit time (a stream, read in order)
    params : LSParams, the starting point of EM (or the fixed parameters without learning)
    config : LearnSearchConfig (T, n0, batch R, EM settings; as :func:`learn_search`)
    window : observations held in the hypotheses (the lag); >= num_obs with
        ``close_z = None`` gives :func:`models.zajdel.learnsearch.learn_search` exactly
    close_z : a committed track closes when its last quit is more than
        max(travel_mean + close_z travel_std) before the current entry; None: never

    Returns
    -------
    StreamResult; memory and work per observation are independent of num_obs (see the
    module docstring), ``max_candidates`` / ``max_open_tracks`` / ``max_window`` count them.
    """
    search = StreamSearch(params, config, window, close_z)
    obs = validate_observations(
        obs, params.obs_dim, params.path.num_cameras, params.path.num_borders
    )
    for i in range(obs.num_obs):
        search.push(take(obs, slice(i, i + 1)))
    search.finish()
    if search.st is None:
        return StreamResult(np.zeros(0, np.int64), params, np.zeros(1), 0, 0, 0, 0)
    labels = canonical_labels(np.concatenate([search.pop_committed(), search.window_labels()]))
    return StreamResult(
        labels,
        search.theta,
        search.log_scores(),
        search.max_candidates,
        search.max_open_tracks,
        search.max_window,
        search.em_iterations,
    )
