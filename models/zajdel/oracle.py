r"""Exact posterior of the multi-camera tracking model by enumeration of every partition
(spec "Exact oracle"; seed 000, eq. 1 with eq. 3 per track).

For ``num_obs <= 8`` observations (Bell(8) = 4140 partitions) every partition is
scored in closed form: NIW evidence of each track's appearances, the path model along
each track, and the label prior of the sequence. Track scores depend only on the set of
observations on the track, so they are computed once per subset (2^K - 1 subsets) and
a partition's score is a sum of table entries.

The posterior of links (which earlier observation each one continues, or new) and of
labels (canonical person numbering = the ADF's) follow exactly; :func:`exact_filtering`
gives them given y_1..y_k for every k (the filtering posterior the ADF approximates).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from scipy.special import logsumexp

from dbn.errors import InputError
from models.zajdel.params import ZajdelParams
from models.zajdel.path import pairwise_path_logprob
from models.zajdel.scores import (
    appearance_log_evidence,
    label_prior_log_prob,
    labels_to_links,
    path_log_prob,
)

__all__ = [
    "MAX_ORACLE_OBS",
    "enumerate_partitions",
    "subset_log_scores",
    "OraclePosterior",
    "exact_posterior",
    "exact_filtering",
]

MAX_ORACLE_OBS = 8


def enumerate_partitions(num_obs: int) -> np.ndarray:
    """Every partition of ``num_obs`` items as canonical label arrays (restricted growth
    strings), shape (Bell(num_obs), num_obs), in lexicographic order."""
    parts = np.zeros((1, 1), np.int64) if num_obs > 0 else np.zeros((1, 0), np.int64)
    for _ in range(1, num_obs):
        nxt = parts.max(1) + 2  # children per row: labels 0..max+1
        rows = np.repeat(parts, nxt, axis=0)
        starts = np.repeat(np.cumsum(nxt) - nxt, nxt)
        new = np.arange(rows.shape[0]) - starts
        parts = np.concatenate([rows, new[:, None]], axis=1)
    return parts


def subset_log_scores(obs, params: ZajdelParams) -> np.ndarray:
    """Log score of every subset of the observations as one track (appearance evidence +
    path), indexed by bitmask (bit k = observation k): shape (2**num_obs,), entry 0 = 0."""
    K = obs.num_obs
    ids = np.arange(1 << K)
    masks = ((ids[:, None] >> np.arange(K)[None, :]) & 1).astype(bool)
    logp0, logpd = pairwise_path_logprob(obs, params.path)
    out = np.zeros(1 << K)
    out[1:] = appearance_log_evidence(obs.appearance, masks[1:], params.prior) + path_log_prob(
        logp0, logpd, masks[1:]
    )
    return out


class OraclePosterior(NamedTuple):
    """Exact posterior given a batch of observations.

    Attributes
    ----------
    partitions : (num_partitions, num_obs) canonical labels
    log_joint : (num_partitions,) unnormalised log posterior of each partition
    log_evidence : float, logsumexp of log_joint
    link_post : (num_obs, num_obs) link_post[k, j] = P(obs k continues obs j) for j < k,
        link_post[k, k] = P(obs k is a new person); rows sum to 1
    label_post : (num_obs, num_obs) label_post[k, n] = P(label of obs k = n)
    counter_post : (num_obs + 1,) P(number of persons = c)
    """

    partitions: np.ndarray
    log_joint: np.ndarray
    log_evidence: float
    link_post: np.ndarray
    label_post: np.ndarray
    counter_post: np.ndarray


def _posterior_from_table(parts: np.ndarray, table: np.ndarray, p_new) -> OraclePosterior:
    M, K = parts.shape
    bits = np.zeros((M, K), np.int64)
    for t in range(K):  # loop over track labels (<= 8), vectorised over partitions
        bits[:, t] = ((parts == t) << np.arange(K)).sum(1)
    log_joint = table[bits].sum(1) + label_prior_log_prob(parts, p_new)
    logZ = float(logsumexp(log_joint))
    p = np.exp(log_joint - logZ)
    links = labels_to_links(parts)
    link_post = np.zeros((K, K))
    label_post = np.zeros((K, K))
    kk = np.broadcast_to(np.arange(K), parts.shape)
    np.add.at(link_post, (kk, links), np.broadcast_to(p[:, None], parts.shape))
    np.add.at(label_post, (kk, parts), np.broadcast_to(p[:, None], parts.shape))
    counter = np.bincount(parts.max(1) + 1, weights=p, minlength=K + 1)
    return OraclePosterior(parts, log_joint, logZ, link_post, label_post, counter)


def _check(obs) -> int:
    K = obs.num_obs
    if K > MAX_ORACLE_OBS:
        raise InputError(f"num_obs = {K}: the exact oracle enumerates at most {MAX_ORACLE_OBS}")
    if K < 1:
        raise InputError("num_obs = 0: the oracle needs at least one observation")
    return K


def exact_posterior(obs, params: ZajdelParams) -> OraclePosterior:
    """Exact posterior of partitions, links, labels and counter given all ``num_obs <= 8``
    observations (enumeration of every partition; seed 000 eq. 1)."""
    K = _check(obs)
    return _posterior_from_table(enumerate_partitions(K), subset_log_scores(obs, params), params.p_new)


class OracleFiltering(NamedTuple):
    """Exact filtering posteriors: row k conditions on observations 0..k only.

    link_post (num_obs, num_obs), label_post (num_obs, num_obs), counter_post
    (num_obs, num_obs + 1), log_evidence (num_obs,) = log p(y_1..y_k)."""

    link_post: np.ndarray
    label_post: np.ndarray
    counter_post: np.ndarray
    log_evidence: np.ndarray


def exact_filtering(obs, params: ZajdelParams) -> OracleFiltering:
    """Exact filtering posterior of each observation's link and label given the
    observations up to it (what the ADF approximates; spec "Exact oracle")."""
    K = _check(obs)
    table = subset_log_scores(obs, params)
    link = np.zeros((K, K))
    label = np.zeros((K, K))
    counter = np.zeros((K, K + 1))
    logev = np.zeros(K)
    for k in range(1, K + 1):  # prefixes (<= 8)
        post = _posterior_from_table(enumerate_partitions(k), table, params.p_new)
        link[k - 1, :k] = post.link_post[k - 1]
        label[k - 1, :k] = post.label_post[k - 1]
        counter[k - 1, : k + 1] = post.counter_post
        logev[k - 1] = post.log_evidence
    return OracleFiltering(link, label, counter, logev)
