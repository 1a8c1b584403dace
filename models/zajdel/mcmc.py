r"""Metropolis-Hastings over partitions: the MCMC baseline of seed 000, section 5.4 (after
Pasula et al., seed 000 ref. 25), with moves that change the number of objects.

Target: :math:`\pi(\omega) \propto p(\omega)\prod_k p(Y_k\mid\omega,\Theta)` (seed 000,
eq. 1 with eq. 3 per track), the score of :func:`models.zajdel.learnsearch.
partition_log_scores` under fixed parameters :math:`\Theta`.

A state is a label array with labels used as *slots* in ``[0, num_obs)`` (not
canonical during the run); at each step every chain draws a move type (a random-scan
mixture whose split and merge halves are each other's reverse) and proposes:

* **swap** (seed 000, section 5.4): pick uniformly one of the :math:`D(\omega)` pairs of
  observations on different tracks and exchange their tracks. Track sizes are kept, so
  :math:`D(\omega') = D(\omega)`: the proposal is symmetric, ratio 1.
* **move** (single-observation reassignment): pick an observation i uniformly, then
  uniformly one of its :math:`n_t(\omega, i) = (m - 1) + [|Y_{k(i)}| \ge 2]` targets
  (another track, or a new track when i is not alone). :math:`n_t(\omega, i)` is the
  number of tracks of the other observations, the same in :math:`\omega` and
  :math:`\omega'`, so the ratio :math:`n_t(\omega, i)/n_t(\omega', i)` is 1.
* **split**: pick uniformly one of the :math:`s(\omega)` tracks with at least 2
  observations (size n) and one of its :math:`2^{n-1}-1` splits into two non-empty parts
  uniformly. Reverse: a merge of these two parts among the :math:`\binom{m+1}{2}` pairs
  of the :math:`m+1` tracks of :math:`\omega'`. Ratio
  :math:`\frac{p_{merge}/\binom{m+1}{2}}{p_{split}/(s(\omega)(2^{n-1}-1))}`.
* **merge**: pick uniformly one of the :math:`\binom{m}{2}` pairs of tracks and join
  them (size n'). Ratio :math:`\frac{p_{split}/(s(\omega')(2^{n'-1}-1))}{p_{merge}/\binom{m}{2}}`.

A move impossible from the current state (e.g. a swap with one track) leaves it
unchanged (counted as a rejection); this keeps detailed balance because the move-type
probabilities are fixed and the reverse proposal probabilities above count only
possible proposals. Acceptance: :math:`\min(1, \frac{\pi(\omega')}{\pi(\omega)}\cdot`
ratio) (seed 003 eq. 11), by the library's vectorised kernel
:class:`inference.mcmc.BatchKernel` run by :func:`inference.mcmc.run_batch`: every chain
steps at once, so the detailed-balance test can run tens of thousands of chains. This
module holds only the moves, the target and the bookkeeping of an accepted move.

Initialisation: ``"random"`` (each observation gets a uniformly random slot; seed 000's
"purely random" start) or ``"greedy"`` (the single-hypothesis search, T = 1, under the
same parameters: seed 000's "MHT with only one hypothesis"). Impossible path factors
(zero transition or entry probability) count
:data:`models.zajdel.learnsearch.IMPOSSIBLE_LOG_PROB` each, so a chain can start in an
impossible partition and climb out of it. The result holds the sample of highest score
(likelihood times partition prior: seed 000's criterion, the data likelihood, under its
uniform prior ``p_new = None``) and the co-assignment frequencies of every pair of
observations.

Data in this library's tests, benchmark and tutorial are SIMULATED.
"""

from __future__ import annotations

import time
from typing import NamedTuple

import numpy as np

from dbn.checks import check_number_fields, make_rng
from dbn.errors import InputError
from inference.mcmc import BatchKernel, BatchMove, BatchProposal, run_batch
from models.zajdel.data import Observations, validate_observations
from models.zajdel.learnsearch import (
    LearnSearchConfig,
    LSParams,
    _canonical,
    _check_params,
    _mask_evidence,
    _Terms,
    _terms,
    learn_search,
)
from models.zajdel.scores import path_log_prob

__all__ = [
    "MOVES",
    "MCMCConfig",
    "ChainState",
    "MCMCResult",
    "chain_init",
    "chain_step",
    "partition_kernel",
    "partition_mcmc",
]

#: move types, in the order of :attr:`MCMCConfig.move_probs`
MOVES = ("swap", "move", "split", "merge")
_LOG2 = float(np.log(2.0))


class MCMCConfig(NamedTuple):
    """Settings of :func:`partition_mcmc`.

    Attributes
    ----------
    move_probs : probabilities of (swap, move, split, merge); seed 000's sampler is
        (1, 0, 0, 0), which never changes the number of objects
    init : "greedy" or "random"
    burn_in : steps discarded from the co-assignment frequencies
    """

    move_probs: tuple[float, float, float, float] = (0.25, 0.25, 0.25, 0.25)
    init: str = "greedy"
    burn_in: int = 0


class ChainState(NamedTuple):
    """State of ``num_chains`` chains over partitions of ``num_obs`` observations.

    Attributes
    ----------
    labels : (num_chains, num_obs) int slots in [0, num_obs)
    track_score : (num_chains, num_obs) log p(Y_slot | omega) of each slot (0 if empty)
    prior : (num_chains,) log p(omega)
    score : (num_chains,) log pi(omega) up to a constant = track_score.sum + prior
    """

    labels: np.ndarray
    track_score: np.ndarray
    prior: np.ndarray
    score: np.ndarray


class MCMCResult(NamedTuple):
    """Output of :func:`partition_mcmc`.

    Attributes
    ----------
    best_labels : (num_obs,) canonical labels of the highest-scoring sample
    best_score : float, its log score
    coassign : (num_obs, num_obs) fraction of kept samples (all chains) in which two
        observations share a track
    accept_rate : (4,) acceptance rate of each move type (nan if never tried)
    final : ChainState after the last step
    score_trace : (num_samples, num_chains) log score after each step
    best_at : dict n -> (canonical labels (num_obs,), score, seconds) of the best sample
        among the first n steps and the wall time since the call started, for each
        requested checkpoint n (what a run of n samples with the same seed returns)
    """

    best_labels: np.ndarray
    best_score: float
    coassign: np.ndarray
    accept_rate: np.ndarray
    final: ChainState
    score_trace: np.ndarray
    best_at: dict


# ----------------------------------------------------------------------------- scores
def _slot_prior(labels: np.ndarray, p_new: float | None) -> np.ndarray:
    """Label prior of slot-labelled partitions (same value as the canonical form's)."""
    M, K = labels.shape
    if p_new is None:
        return np.zeros(M)
    key = (labels + K * np.arange(M)[:, None]).ravel()
    firsts = np.full(M * K, K)
    np.minimum.at(firsts, key, np.tile(np.arange(K), M))
    new = firsts[key].reshape(M, K) == np.arange(K)  # (M, K) first observation of its track
    cprev = np.cumsum(new, axis=1) - new  # tracks among 0..k-1
    term = np.where(new, np.log(p_new), np.log1p(-p_new) - np.log(np.maximum(cprev, 1)))
    term[:, 0] = 0.0
    return term.sum(1)


def _set_scores(t: _Terms, masks: np.ndarray) -> np.ndarray:
    """Track scores (appearance evidence + path) of masks (..., K); 0 for empty sets."""
    shape = masks.shape[:-1]
    flat = masks.reshape(-1, masks.shape[-1])
    out = np.zeros(flat.shape[0])
    ne = flat.any(1)
    if ne.any():
        sub = flat[ne]
        out[ne] = _mask_evidence(t, sub) + path_log_prob(t.logp0, t.logpd, sub)
    return out.reshape(shape)


def chain_init(labels: np.ndarray, obs: Observations, params: LSParams) -> ChainState:
    """Chain state from label arrays (num_chains, num_obs) (any labels in [0, num_obs))."""
    lab = np.atleast_2d(np.asarray(labels, np.int64))
    K = lab.shape[1]
    if lab.min() < 0 or lab.max() >= K:
        raise InputError(f"labels: values must lie in [0, {K}), got [{lab.min()}, {lab.max()}]")
    t = _terms(obs, params)
    masks = lab[:, None, :] == np.arange(K)[None, :, None]
    ts = _set_scores(t, masks)
    prior = _slot_prior(lab, params.p_new)
    return ChainState(lab.copy(), ts, prior, ts.sum(1) + prior)


# ----------------------------------------------------------------------------- proposals
def _sizes(lab: np.ndarray) -> np.ndarray:
    M, K = lab.shape
    return np.bincount((lab + K * np.arange(M)[:, None]).ravel(), minlength=M * K).reshape(M, K)


def _pick(rng: np.random.Generator, weights: np.ndarray) -> np.ndarray:
    """Index of one uniformly chosen True entry per row of a bool array (M, J);
    rows without one give 0 (callers mask them)."""
    cnt = weights.sum(1)
    u = np.floor(rng.random(weights.shape[0]) * np.maximum(cnt, 1)).astype(np.int64)
    cum = np.cumsum(weights, axis=1)
    return (cum <= u[:, None]).sum(1).clip(max=weights.shape[1] - 1)


def _first_free(n: np.ndarray) -> np.ndarray:
    return np.argmax(n == 0, axis=1)


def _log_splits(n: np.ndarray) -> np.ndarray:
    """log(2^(n-1) - 1) for n >= 2 (number of splits of n items into 2 non-empty parts)."""
    k = np.maximum(n - 1, 1).astype(float)
    return k * _LOG2 + np.log1p(-np.exp(-k * _LOG2))


class _Candidate(NamedTuple):
    """Proposed labels (n, num_obs) and the two slots whose tracks change (n, 2)."""

    labels: np.ndarray
    slots: np.ndarray


def _proposal(lab, new, slots, ok, log_q_forward, log_q_reverse) -> BatchProposal:
    ok = ok & (slots[:, 0] != slots[:, 1])
    n = lab.shape[0]
    return BatchProposal(
        _Candidate(new, slots),
        log_q_forward if np.ndim(log_q_forward) else np.full(n, log_q_forward),
        log_q_reverse if np.ndim(log_q_reverse) else np.full(n, log_q_reverse),
        ok,
    )


def _swap(rng: np.random.Generator, state: ChainState, rows: np.ndarray) -> BatchProposal:
    """Exchange the tracks of one of the D(omega) pairs on different tracks (symmetric)."""
    lab = state.labels[rows]
    M, K = lab.shape
    r = np.arange(M)
    j = np.arange(K)
    diff = (lab[:, :, None] != lab[:, None, :]) & (j[None, :, None] < j[None, None, :])
    flat = diff.reshape(M, K * K)
    ok = flat.any(1)
    idx = _pick(rng, flat)
    a, b = idx // K, idx % K
    sa, sb = lab[r, a], lab[r, b]
    new = lab.copy()
    new[r, a] = np.where(ok, sb, sa)
    new[r, b] = np.where(ok, sa, sb)
    return _proposal(lab, new, np.stack([sa, sb], 1), ok, 0.0, 0.0)


def _move_one(rng: np.random.Generator, state: ChainState, rows: np.ndarray) -> BatchProposal:
    """Reassign one observation to another track or a new one (symmetric: n_t is kept)."""
    lab = state.labels[rows]
    M, K = lab.shape
    r = np.arange(M)
    n = _sizes(lab)
    m = (n > 0).sum(1)
    i = rng.integers(K, size=M)
    own = lab[r, i]
    alone = n[r, own] == 1
    others = n > 0
    others[r, own] = False
    nt = (m - 1) + (~alone)
    ok = nt > 0
    u = np.floor(rng.random(M) * np.maximum(nt, 1)).astype(np.int64)
    to_new = u >= m - 1
    cum = np.cumsum(others, axis=1)
    existing = (cum <= u[:, None]).sum(1).clip(max=K - 1)
    target = np.where(to_new, _first_free(n), existing)
    new = lab.copy()
    new[r, i] = np.where(ok, target, own)
    # n_t(omega', i) = n_t(omega, i): both count the tracks of the other observations
    return _proposal(lab, new, np.stack([own, target], 1), ok, 0.0, 0.0)


def _split(rng: np.random.Generator, state: ChainState, rows: np.ndarray) -> BatchProposal:
    """Split one of the s(omega) tracks of size n >= 2 uniformly in two; reverse: merge."""
    lab = state.labels[rows]
    M, K = lab.shape
    r = np.arange(M)
    n = _sizes(lab)
    m = (n > 0).sum(1)
    big = n >= 2
    s = big.sum(1)
    ok = s > 0
    t = _pick(rng, big)
    mem = lab == t[:, None]  # (M, K)
    first = np.argmax(mem, axis=1)
    side = np.zeros((M, K), bool)
    todo = ok.copy()
    while todo.any():  # uniform over the 2^(n-1) - 1 non-trivial splits, by rejection
        bits = rng.random((M, K)) < 0.5
        bits &= mem
        bits[r, first] = False
        side = np.where(todo[:, None], bits, side)
        todo = todo & ~side.any(1)
    free = _first_free(n)
    new = np.where(side & ok[:, None], free[:, None], lab)
    lq_f = -np.log(np.maximum(s, 1)) - _log_splits(n[r, t])
    lq_r = -np.log((m + 1) * m / 2.0)
    return _proposal(lab, new, np.stack([t, free], 1), ok, lq_f, lq_r)


def _merge(rng: np.random.Generator, state: ChainState, rows: np.ndarray) -> BatchProposal:
    """Join one of the C(m, 2) pairs of tracks; reverse: the split of the joined track."""
    lab = state.labels[rows]
    M = lab.shape[0]
    r = np.arange(M)
    n = _sizes(lab)
    m = (n > 0).sum(1)
    ok = m >= 2
    ne = n > 0
    a = _pick(rng, ne)
    ne_b = ne.copy()
    ne_b[r, a] = False
    b = _pick(rng, ne_b)
    new = np.where((lab == b[:, None]) & ok[:, None], a[:, None], lab)
    n_new = n[r, a] + n[r, b]
    s_after = (n >= 2).sum(1) - (n[r, a] >= 2) - (n[r, b] >= 2) + 1
    lq_f = -np.log(np.maximum(m * (m - 1) / 2.0, 1))
    lq_r = -np.log(np.maximum(s_after, 1)) - _log_splits(n_new)
    return _proposal(lab, new, np.stack([a, b], 1), ok, lq_f, lq_r)


#: the move declarations, in the order of :data:`MOVES` (split and merge reverse each other)
MOVE_SET = (
    BatchMove("swap", _swap, 0),
    BatchMove("move", _move_one, 1),
    BatchMove("split", _split, 3),
    BatchMove("merge", _merge, 2),
)


def partition_kernel(
    t: _Terms, p_new: float | None, move_probs=(0.25, 0.25, 0.25, 0.25)
) -> BatchKernel:
    """The partition sampler as a :class:`inference.mcmc.BatchKernel`: the four moves,
    the target of seed 000 eq. 1 (track scores and label prior) scored incrementally on
    the two changed slots, and the bookkeeping of an accepted move."""

    def log_target_delta(state: ChainState, cand: _Candidate):
        rows = np.arange(cand.labels.shape[0])[:, None]
        masks = cand.labels[:, None, :] == cand.slots[:, :, None]  # (M, 2, K)
        ts_new = _set_scores(t, masks)  # (M, 2)
        prior_new = _slot_prior(cand.labels, p_new)
        old = state.track_score[rows, cand.slots]
        delta = ts_new.sum(1) - old.sum(1) + prior_new - state.prior
        return delta, (cand, ts_new, prior_new, delta)

    def commit(state: ChainState, scored, keep: np.ndarray) -> ChainState:
        cand, ts_new, prior_new, delta = scored
        labels = np.where(keep[:, None], cand.labels, state.labels)
        track = state.track_score.copy()
        acc_rows = np.nonzero(keep)[0]
        track[acc_rows[:, None], cand.slots[acc_rows]] = ts_new[acc_rows]
        prior = np.where(keep, prior_new, state.prior)
        score = np.where(keep, state.score + delta, state.score)
        return ChainState(labels, track, prior, score)

    return BatchKernel(MOVE_SET, move_probs, log_target_delta, commit)


def chain_step(
    rng: np.random.Generator,
    state: ChainState,
    t: _Terms,
    p_new: float | None,
    move_probs=(0.25, 0.25, 0.25, 0.25),
    move: int | None = None,
):
    """One Metropolis-Hastings step of every chain (seed 000 section 5.4; seed 003 eq. 11),
    through :func:`partition_kernel`.

    Each chain draws its own move type with ``move_probs`` (independent chains: a move
    type shared by all chains would make them dependent, and split or merge alone does
    not leave the posterior invariant, only their mixture does).

    Parameters
    ----------
    rng : numpy Generator (the only randomness)
    state : ChainState (num_chains, num_obs)
    t : observation terms under the parameters (``learnsearch._terms``)
    p_new : the partition prior's new-person probability (None: uniform)
    move_probs : (4,) probabilities of swap, move, split, merge
    move : force this move type (index into :data:`MOVES`) for every chain

    Returns
    -------
    (ChainState, moves (num_chains,) int, accepted (num_chains,) bool)
    """
    kernel = partition_kernel(t, p_new, move_probs)
    new, info, _ = kernel.step(rng, state, state.labels.shape[0], move)
    return new, info.move, info.accepted


def _check_config(cfg: MCMCConfig, num_samples: int, num_chains: int) -> np.ndarray:
    """Validated move probabilities (4,); raises InputError naming the bad field."""
    check_number_fields(cfg)
    if cfg.burn_in < 0:
        raise InputError(f"burn_in = {cfg.burn_in}: must be >= 0")
    probs = np.asarray(cfg.move_probs, float)
    if probs.shape != (4,) or (probs < 0).any() or abs(probs.sum() - 1.0) > 1e-9:
        raise InputError(f"move_probs = {cfg.move_probs}: need 4 non-negative numbers summing to 1")
    if (probs[2] > 0) != (probs[3] > 0):
        raise InputError(
            f"move_probs = {cfg.move_probs}: split and merge are each other's "
            "reverse; give both a positive probability or neither"
        )
    if cfg.init not in ("greedy", "random"):
        raise InputError(f"init = {cfg.init!r}: must be 'greedy' or 'random'")
    if num_samples < 1 or num_chains < 1:
        raise InputError(f"num_samples = {num_samples}, num_chains = {num_chains}: must be >= 1")
    return probs


def _initial_labels(
    rng,
    obs: Observations,
    params: LSParams,
    cfg: MCMCConfig,
    num_chains: int,
    init_labels: np.ndarray | None,
) -> np.ndarray:
    """Starting labels (num_chains, num_obs): given, greedy (T = 1 search) or random."""
    K = obs.num_obs
    if init_labels is not None:
        return np.broadcast_to(np.asarray(init_labels, np.int64), (num_chains, K))
    if cfg.init == "greedy":
        g = learn_search(obs, params, LearnSearchConfig(num_hypotheses=1, learn=False, n0=1)).labels
        return np.broadcast_to(g, (num_chains, K))
    return rng.integers(K, size=(num_chains, K))


# ----------------------------------------------------------------------------- driver
class _Recorder:
    """The ``on_step`` of :func:`partition_mcmc`; it records and never changes a chain.

    ``co`` sums, over the kept steps (after ``burn_in``) and the chains, how often two
    observations share a track (``kept`` counts them); ``best_at[n]`` is the best sample
    of the first ``n`` steps, for each checkpoint ``n`` in ``marks``.
    """

    def __init__(self, labels: np.ndarray, marks: set[int], burn_in: int, start: float):
        self.marks, self.burn_in, self.start = marks, burn_in, start
        self.num_chains, num_obs = labels.shape
        self.co = np.zeros((num_obs, num_obs))
        self.co_now = (labels[:, :, None] == labels[:, None, :]).sum(0)
        self.kept = 0
        self.best_at: dict = {}

    def __call__(self, s: int, st: ChainState, info, best_score: np.ndarray, best) -> None:
        if s + 1 in self.marks:
            c = int(np.argmax(best_score))
            self.best_at[s + 1] = (
                _canonical(best.labels[c][None])[0],
                float(best_score[c]),
                time.perf_counter() - self.start,
            )
        if info.accepted.any():
            self.co_now = (st.labels[:, :, None] == st.labels[:, None, :]).sum(0)
        if s >= self.burn_in:
            self.co += self.co_now
            self.kept += self.num_chains


def partition_mcmc(
    seed,
    obs: Observations,
    params: LSParams,
    num_samples: int,
    config: MCMCConfig | None = None,
    num_chains: int = 1,
    init_labels: np.ndarray | None = None,
    checkpoints=(),
    progress: bool = False,
) -> MCMCResult:
    """Metropolis-Hastings sampling of partitions (seed 000, section 5.4, with split,
    merge and move so the number of objects can change).

    Parameters
    ----------
    seed : int or numpy Generator, first, the only source of randomness
    obs : Observations (num_obs)
    params : LSParams, fixed during sampling
    num_samples : MH steps per chain
    config : MCMCConfig (move probabilities, init "greedy" / "random", burn-in)
    num_chains : chains run side by side (vectorised)
    init_labels : (num_obs,) or (num_chains, num_obs) starting labels, overriding init
    checkpoints : step counts n at which the best sample so far is recorded (the result
        of a shorter run with the same seed)
    progress : tqdm bar over the steps

    Returns
    -------
    MCMCResult: best sample (canonical labels) and score, co-assignment frequencies,
    acceptance rate per move, final state, score trace (num_samples, num_chains).
    """
    cfg = MCMCConfig() if config is None else config
    probs = _check_config(cfg, num_samples, num_chains)
    _check_params(params)
    obs = validate_observations(
        obs, params.obs_dim, params.path.num_cameras, params.path.num_borders
    )
    K = obs.num_obs
    if K < 1:
        raise InputError("num_obs = 0: nothing to sample")
    start = time.perf_counter()
    rng = make_rng(seed)  # a Generator as is
    lab0 = _initial_labels(rng, obs, params, cfg, num_chains, init_labels)
    t = _terms(obs, params)
    state = chain_init(lab0, obs, params)
    marks = {int(n) for n in checkpoints if 1 <= int(n) <= num_samples}
    record = _Recorder(state.labels, marks, cfg.burn_in, start)
    rec = run_batch(
        rng,
        partition_kernel(t, params.p_new, probs),
        state,
        num_samples,
        state.score,
        on_step=record,
        progress=progress,
    )
    c = int(np.argmax(rec.best_log_target))
    return MCMCResult(
        _canonical(rec.best_state.labels[c][None])[0],
        float(rec.best_log_target[c]),
        record.co / max(record.kept, 1),
        rec.accept_rate,
        rec.state,
        rec.trace,
        record.best_at,
    )
