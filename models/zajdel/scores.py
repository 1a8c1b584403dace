r"""Closed-form scores of tracks and partitions (seed 000, eqs. 1 and 3, with the NIW
appearance state and label prior of seed 002, eqs. 1.15-1.19).

A partition of ``num_obs`` observations is an int label array ``labels (num_obs,)`` in
canonical form (restricted growth: the first observation has label 0 and each new
person takes the next label, the ADF's person numbering). Batches of partitions are
``(num_partitions, num_obs)``. The link form ``links (num_obs,)`` gives for each
observation the index of the previous observation of the same person, or its own index
when it starts a new track (the diagonal of the link matrix means "new").

These functions are shared by the exact oracle, the greedy baseline, the tracker's
tests and the learn-search tracker.
"""

from __future__ import annotations

import numpy as np

from inference.adf.niw import NIW, niw_log_evidence_masked_np
from models.zajdel.params import ZajdelParams
from models.zajdel.path import pairwise_path_logprob

__all__ = [
    "canonical_labels",
    "labels_to_links",
    "links_to_labels",
    "track_masks",
    "appearance_log_evidence",
    "path_log_prob",
    "label_prior_log_prob",
    "partition_log_score",
]


def canonical_labels(labels: np.ndarray) -> np.ndarray:
    """Relabel (num_partitions, num_obs) or (num_obs,) label arrays in first-appearance order."""
    lab = np.atleast_2d(np.asarray(labels))
    out = np.empty_like(lab)
    for m in range(lab.shape[0]):
        _, first, inv = np.unique(lab[m], return_index=True, return_inverse=True)
        order = np.argsort(np.argsort(first))
        out[m] = order[inv]
    return out.reshape(np.shape(labels))


def labels_to_links(labels: np.ndarray) -> np.ndarray:
    """Link form of label arrays: previous observation of the same label, or self if new.

    labels (..., num_obs) -> links (..., num_obs) int."""
    lab = np.asarray(labels)
    K = lab.shape[-1]
    same = lab[..., :, None] == lab[..., None, :]  # [k, j]
    j = np.arange(K)
    earlier = same & (j[None, :] < j[:, None])
    cand = np.where(earlier, j[None, :], -1)
    prev = cand.max(-1)
    return np.where(prev >= 0, prev, j)


def links_to_labels(links: np.ndarray) -> np.ndarray:
    """Canonical labels from a link array (num_obs,) (each earlier observation continued
    at most once is NOT required: a link to an already continued one joins its track)."""
    links = np.asarray(links)
    K = links.shape[0]
    labels = np.empty(K, np.int64)
    nxt = 0
    for k in range(K):
        j = int(links[k])
        if j == k or j < 0:
            labels[k] = nxt
            nxt += 1
        else:
            labels[k] = labels[j]
    return labels


def track_masks(labels: np.ndarray) -> np.ndarray:
    """(num_partitions, num_obs) labels -> bool masks (num_partitions, num_obs, num_obs):
    ``masks[m, t, k]`` is True when observation k is on track t of partition m (tracks
    numbered by label; unused labels give empty masks)."""
    lab = np.atleast_2d(np.asarray(labels))
    K = lab.shape[1]
    return lab[:, None, :] == np.arange(K)[None, :, None]


def appearance_log_evidence(appearance: np.ndarray, masks: np.ndarray, prior: NIW) -> np.ndarray:
    r"""NIW evidence :math:`\log\int \prod_{k\in S} N(o_k; m, V)\,NIW(m, V;\theta_0)` of many
    tracks at once (closed form; seed 000 eq. 3 appearance integral).

    appearance (num_obs, r); masks bool (num_sets, num_obs) -> (num_sets,)."""
    return niw_log_evidence_masked_np(appearance, masks, prior)


def path_log_prob(logp0: np.ndarray, logpd: np.ndarray, masks: np.ndarray) -> np.ndarray:
    r"""Path log-probability of many tracks (seed 000 eq. 3, spatio-temporal factors):
    :math:`\log p_{\delta_0}(d_{first}) + \sum \log p_\delta(d_{next}\mid d_{prev})` along
    each track in time order.

    logp0 (num_obs,), logpd (num_obs, num_obs) from
    :func:`models.zajdel.path.pairwise_path_logprob`; masks bool (num_sets, num_obs).
    Returns (num_sets,); 0 for an empty set, -inf for an impossible track."""
    M = np.asarray(masks, bool)
    K = M.shape[1]
    idx = np.where(M, np.arange(K), -1)
    last = np.maximum.accumulate(idx, axis=1)
    prev = np.concatenate([np.full((M.shape[0], 1), -1), last[:, :-1]], axis=1)
    k = np.broadcast_to(np.arange(K), M.shape)
    step = np.where(prev >= 0, logpd[np.maximum(prev, 0), k], logp0[k])
    return np.where(M, step, 0.0).sum(1)


def label_prior_log_prob(labels: np.ndarray, p_new: float | None) -> np.ndarray:
    r"""Log prior of canonical label sequences under the tracker's label prior.

    Uniform (seed 002, eq. 1.16): :math:`\prod_k 1/(c_{k-1}+1)`. With ``p_new``: the first
    observation is new with probability 1, afterwards a new person has probability
    ``p_new`` and each of the :math:`c_{k-1}` known persons :math:`(1-p_{new})/c_{k-1}`.

    labels (..., num_obs) -> (...)."""
    lab = np.asarray(labels)
    cprev = np.concatenate(
        [np.zeros(lab.shape[:-1] + (1,), lab.dtype), np.maximum.accumulate(lab, -1)[..., :-1] + 1],
        axis=-1,
    )
    cprev[..., 0] = 0
    if p_new is None:
        return -np.log(cprev + 1.0).sum(-1)
    new = lab >= cprev
    with np.errstate(divide="ignore"):
        old = np.log1p(-p_new) - np.log(np.maximum(cprev, 1))
    term = np.where(new, np.log(p_new), old)
    term[..., 0] = 0.0
    return term.sum(-1)


def partition_log_score(labels: np.ndarray, obs, params: ZajdelParams) -> np.ndarray:
    r"""Unnormalised log posterior :math:`\log p(\omega) + \sum_t \log p(Y_t\mid\omega)` of
    partitions (seed 000 eq. 1 with eq. 3 per track; NIW appearance evidence, path model,
    label prior).

    labels (num_partitions, num_obs) or (num_obs,) canonical -> (num_partitions,) or ()."""
    lab = np.atleast_2d(np.asarray(labels))
    M, K = lab.shape
    masks = track_masks(lab).reshape(M * K, K)
    logp0, logpd = pairwise_path_logprob(obs, params.path)
    nonempty = masks.any(1)
    score = np.zeros(M * K)
    sub = masks[nonempty]
    score[nonempty] = appearance_log_evidence(obs.appearance, sub, params.prior) + path_log_prob(
        logp0, logpd, sub
    )
    out = score.reshape(M, K).sum(1) + label_prior_log_prob(lab, params.p_new)
    return out if np.ndim(labels) == 2 else out[0]
