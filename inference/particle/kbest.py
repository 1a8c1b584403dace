"""The k distinct states of largest mass in a weighted particle set (host-side numpy).

A particle filter over a discrete or partly discrete state can report, at every step, a
short list of the most probable *distinct* states instead of a mean: several particles
stand for one state (same camera, same associated observation, ...), and a state's mass
is the sum of its particles' normalised weights (the particle estimate of its posterior
probability) or, as some papers rank them, the largest weight among them (seed 001,
sec. 4.1.5). The model says which particles are the same state by an integer id.
"""

from __future__ import annotations

import numpy as np

from dbn.checks import check_count, real_array
from dbn.errors import InputError, ShapeError

__all__ = ["k_best_states"]


def k_best_states(
    state_ids: np.ndarray, weights: np.ndarray, k: int, combine: str = "sum"
) -> tuple[np.ndarray, np.ndarray]:
    """The ``k`` distinct states of largest mass, best first.

    Parameters
    ----------
    state_ids : (m,) int
        Identity of the state each particle stands for.
    weights : (m,) float
        Non-negative particle weights (normalised or not: masses are on their scale).
    k : int
        Longest list returned.
    combine : {'sum', 'max'}
        A state's mass: the sum of its particles' weights or the largest one.

    Returns
    -------
    rep : (min(k, num_states),) int64
        For each listed state, the index of its heaviest particle (the first one among
        equals).
    mass : (min(k, num_states),) float64
        The listed states' masses, non-increasing; ties go to the smaller state id.

    Raises
    ------
    ShapeError, InputError
        Mismatched shapes, ``k < 1``, an unknown ``combine``, negative or NaN weights.
    """
    ids = np.asarray(state_ids)
    w = real_array("weights", weights)
    if ids.ndim != 1 or w.shape != ids.shape:
        raise ShapeError(f"state_ids {ids.shape} and weights {w.shape} must be equal 1-D shapes")
    check_count("k", k)  # True was read as 1
    if combine not in ("sum", "max"):
        raise InputError(f"combine = {combine!r}, expected 'sum' or 'max'")
    if np.any(np.isnan(w)) or np.any(w < 0):
        raise InputError("weights must be non-negative numbers")
    if ids.size == 0:
        return np.zeros(0, np.int64), np.zeros(0)
    order = np.argsort(-w, kind="stable")
    uniq, first = np.unique(ids[order], return_index=True)
    rep = order[first]  # heaviest particle of every distinct state
    if combine == "max":
        mass = w[rep]
    else:
        mass = np.bincount(np.searchsorted(uniq, ids), weights=w, minlength=uniq.size)
    top = np.argsort(-mass, kind="stable")[:k]
    return rep[top].astype(np.int64), mass[top]
