r"""Scores of a recovered partition against the true one (seed 000, section 5.2).

Partitions are int label arrays (num_obs,) (any label values; only equality matters).
"""

from __future__ import annotations

import numpy as np

from dbn.errors import InputError, NonFiniteError, ShapeError

__all__ = ["partition_accuracy", "num_objects", "pairwise_prf", "contingency"]


def _labels(name: str, labels) -> np.ndarray:
    """``labels`` as a 1-D array of labels: not a scalar or a table (``None`` counted as
    one object, a 2-D array was flattened), no NaN or None among them (NaN labels matched
    any label: pred [0, nan] against true [0, 1] scored 1.0); else the library's error."""
    arr = np.asarray(labels)
    if arr.ndim != 1:
        raise ShapeError(f"{name}: expected a 1-D label array (num_obs,), got shape {arr.shape}")
    if arr.dtype.kind in "fc" and not np.isfinite(arr).all():
        k = int(np.argmax(~np.isfinite(arr)))
        raise NonFiniteError(f"{name}[{k}] = {arr[k]} is not a label")
    if arr.dtype.kind == "O" and any(x is None or x != x for x in arr.tolist()):
        k = next(i for i, x in enumerate(arr.tolist()) if x is None or x != x)
        raise InputError(f"{name}[{k}] = {arr[k]!r} is not a label")
    return arr


def contingency(pred: np.ndarray, true: np.ndarray) -> np.ndarray:
    """Contingency table N (num_pred_tracks, num_true_tracks): N[i, j] = |Y_i ∩ Y'_j|.

    Raises :class:`~dbn.errors.ShapeError` for label arrays of different lengths or not
    1-D, :class:`~dbn.errors.NonFiniteError` / :class:`~dbn.errors.InputError` for a NaN
    or None label."""
    pred, true = _labels("pred", pred), _labels("true", true)
    if pred.shape != true.shape:
        raise ShapeError(f"pred has {pred.shape[0]} observations, true has {true.shape[0]}")
    _, pi = np.unique(pred, return_inverse=True)
    _, ti = np.unique(true, return_inverse=True)
    N = np.zeros((pi.max() + 1 if pi.size else 0, ti.max() + 1 if ti.size else 0), np.int64)
    np.add.at(N, (pi, ti), 1)
    return N


def partition_accuracy(pred: np.ndarray, true: np.ndarray) -> float:
    r"""Partition accuracy :math:`q_\omega = \frac1{K_\omega}\sum_k \max_i |Y'_i\cap Y_k| / |Y_k|`
    (seed 000, eqs. 7-8), as a fraction in [0, 1] (the seed prints percent).

    Note: one track per observation scores 1; read it with :func:`pairwise_prf`."""
    N = contingency(pred, true)
    if N.size == 0:
        return 1.0
    return float((N.max(1) / N.sum(1)).mean())


def num_objects(labels: np.ndarray) -> int:
    """Number of distinct trajectories (seed 000, section 5.2, secondary criterion)."""
    return int(np.unique(_labels("labels", labels)).size)


def pairwise_prf(pred: np.ndarray, true: np.ndarray) -> tuple[float, float, float]:
    """Pairwise precision, recall and F1 over all pairs of observations: a pair is
    positive when both observations are on one track.

    Precision is 1 when the prediction puts no pair together; recall is 1 when the truth
    has no pair; F1 is their harmonic mean (0 when both are 0)."""
    N = contingency(pred, true)
    tp = float((N * (N - 1) // 2).sum())
    a = N.sum(1)
    b = N.sum(0)
    pred_pairs = float((a * (a - 1) // 2).sum())
    true_pairs = float((b * (b - 1) // 2).sum())
    precision = tp / pred_pairs if pred_pairs > 0 else 1.0
    recall = tp / true_pairs if true_pairs > 0 else 1.0
    f1 = 2 * precision * recall / (precision + recall) if precision + recall > 0 else 0.0
    return precision, recall, f1
