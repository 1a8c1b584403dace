r"""Decoding the Zajdel ADF's output (spec "Decoding a partition"): the per-observation
result of a run (:class:`RunResult`), on-line MAP labels (seed 002) and chain decoding
of links (each observation continues at most one earlier one, an earlier observation
is continued at most once)."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from dbn.errors import InputError

__all__ = ["RunResult", "chain_decode"]


class RunResult(NamedTuple):
    """Per-observation output of :meth:`ZajdelADF.run` (numpy; ``K`` observations).

    link_obs (K, link_out), link_prob (K, link_out), new_prob (K,), label_person
    (K, label_out), label_prob (K, label_out), counter_mean (K,), counter_std (K,),
    loglik (K,), num_open (K,), impossible (K,), counter (K, N + 1) or None,
    first_index: global index of the first observation of this run, pruned_mass (K,)
    or None: open-track mass closed by ``ADFConfig.slot_mass_eps`` at each step.
    """

    link_obs: np.ndarray
    link_prob: np.ndarray
    new_prob: np.ndarray
    label_person: np.ndarray
    label_prob: np.ndarray
    counter_mean: np.ndarray
    counter_std: np.ndarray
    loglik: np.ndarray
    num_open: np.ndarray
    impossible: np.ndarray
    counter: np.ndarray | None
    first_index: int
    pruned_mass: np.ndarray | None = None

    @property
    def num_obs(self) -> int:
        return int(self.new_prob.shape[0])

    def link_matrix(self) -> np.ndarray:
        """Dense link posterior (K, K) of a run started from an empty state:
        [k, j] = P(obs k continues obs j), [k, k] = P(new)."""
        K = self.num_obs
        out = np.zeros((K, K))
        kk = np.repeat(np.arange(K), self.link_obs.shape[1])
        jj = self.link_obs.reshape(-1) - self.first_index
        ok = jj >= 0
        np.add.at(out, (kk[ok], jj[ok]), self.link_prob.reshape(-1)[ok])
        out[np.arange(K), np.arange(K)] += self.new_prob
        return out

    def label_matrix(self) -> np.ndarray:
        """Dense label posterior (K, max person + 1): [k, n] = q_k(l_k = n)."""
        K = self.num_obs
        pos = self.label_prob > 0
        n = int(self.label_person[pos].max()) + 1 if pos.any() else 1
        out = np.zeros((K, max(n, 1)))
        kk = np.repeat(np.arange(K), self.label_person.shape[1])[pos.reshape(-1)]
        np.add.at(out, (kk, self.label_person[pos]), self.label_prob[pos])
        return out

    def labels_online(self) -> np.ndarray:
        """On-line MAP labels (seed 002): each observation's most probable person when it
        arrived; canonical labels (K,)."""
        best = self.label_person[np.arange(self.num_obs), np.argmax(self.label_prob, axis=1)]
        _, first, inv = np.unique(best, return_index=True, return_inverse=True)
        return np.argsort(np.argsort(first))[inv]

    def labels_chain(self, use_counter: bool = True, method: str = "matching") -> np.ndarray:
        """Chain decoding (spec "Decoding a partition", (b)): canonical labels (K,).

        With ``use_counter`` the number of tracks is the filter's final estimate of the
        number of people (the rounded counter mean), see :func:`chain_decode`."""
        n = int(round(float(self.counter_mean[-1]))) if (use_counter and self.num_obs) else None
        if n is not None and self.first_index > 0:
            n = None  # a continued run: the counter also counts earlier people
        return chain_decode(
            self.link_obs - self.first_index, self.link_prob, self.new_prob, n, method
        )


def _links_to_canonical(link: np.ndarray) -> np.ndarray:
    K = link.shape[0]
    labels = np.empty(K, np.int64)
    nxt = 0
    for k in range(K):  # one pass in time order (decoding, not the filter)
        if link[k] == k:
            labels[k] = nxt
            nxt += 1
        else:
            labels[k] = labels[link[k]]
    return labels


def _candidates(link_obs, link_prob, new_prob):
    K, L = link_obs.shape
    kk = np.repeat(np.arange(K), L)
    jj = link_obs.reshape(-1)
    pp = link_prob.reshape(-1)
    ok = (jj >= 0) & (jj < kk) & (pp > 0)
    kk = np.concatenate([kk[ok], np.arange(K)])
    jj = np.concatenate([jj[ok], np.arange(K)])
    pp = np.concatenate([pp[ok], np.maximum(new_prob, 1e-300)])
    return kk, jj, pp


def _match(kk, jj, cost, K):
    """Min-cost assignment of every observation to one candidate: column j < K is
    "continue observation j" (used at most once), column K + k is "k is new"."""
    from scipy.sparse import csr_matrix
    from scipy.sparse.csgraph import min_weight_full_bipartite_matching

    cols = np.where(jj == kk, K + kk, jj)
    g = csr_matrix((cost + 1.0, (kk, cols)), shape=(K, 2 * K))  # +1: keep zero costs explicit
    _, col = min_weight_full_bipartite_matching(g)
    return np.where(col >= K, np.arange(K), col)


def chain_decode(
    link_obs: np.ndarray,
    link_prob: np.ndarray,
    new_prob: np.ndarray,
    num_tracks: int | None = None,
    method: str = "matching",
) -> np.ndarray:
    r"""Chain decoding of link posteriors (spec "Decoding a partition", (b)): each
    observation continues one earlier observation or starts a track, and an earlier
    observation is continued at most once (a track is a chain).

    ``method="matching"`` (default) maximises :math:`\sum_k \log P(\text{link}_k)` over all
    such assignments (a sparse min-cost bipartite matching); with ``num_tracks`` the
    number of new tracks is fixed to that value by a Lagrange penalty on "new" found by
    bisection (the tracker passes the counter's estimate). ``method="greedy"`` takes the
    candidates in decreasing probability instead.

    Parameters
    ----------
    link_obs : (K, L) int, candidate earlier observations (indices into this batch, < 0 none)
    link_prob : (K, L), their probabilities; new_prob : (K,) P(new)
    num_tracks : wanted number of tracks (None: free)

    Returns
    -------
    canonical labels (K,)
    """
    K = link_obs.shape[0]
    if K == 0:
        return np.zeros(0, np.int64)
    kk, jj, pp = _candidates(link_obs, link_prob, new_prob)
    if method == "greedy":
        order = np.lexsort((kk, -pp))
        link = np.full(K, -1)
        used = np.zeros(K, bool)
        for t in order:  # decoding pass over sorted candidates (not part of the filter)
            k, j = kk[t], jj[t]
            if link[k] >= 0:
                continue
            if j == k:
                link[k] = k
            elif not used[j]:
                link[k] = j
                used[j] = True
        return _links_to_canonical(link)
    if method != "matching":
        raise InputError(f"method = {method!r}: must be 'matching' or 'greedy'")
    cost = -np.log(pp)
    is_new = jj == kk
    link = _match(kk, jj, cost, K)
    if num_tracks is None:
        return _links_to_canonical(link)
    target = int(np.clip(num_tracks, 1, K))
    if int((link == np.arange(K)).sum()) != target:
        lo, hi = -60.0, 60.0
        for _ in range(40):  # bisection on the penalty of a new track
            lam = 0.5 * (lo + hi)
            link = _match(kk, jj, cost + np.where(is_new, lam, 0.0) + 60.0, K)
            n_new = int((link == np.arange(K)).sum())
            if n_new == target:
                break
            if n_new > target:
                lo = lam
            else:
                hi = lam
    return _links_to_canonical(link)
