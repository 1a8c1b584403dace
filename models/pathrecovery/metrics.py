"""Scores of seed 001, sec. 7.2, defined precisely.

For a step ``t >= 1`` (the initial state ``t = 0`` is given, never scored), a recovered
state is CORRECT when
    * the target is visible at ``t`` and the state is visible with the target's own
      observation of ``t`` as its associated observation (the right camera with a
      confuser's observation is wrong);
    * the target is hidden at ``t`` and the state is hidden (any destination and any
      time of arrival: "when the target is invisible at a given time step, any of the
      hidden states are considered correct").

``path_score`` is the fraction of steps ``t = 1 .. T - 1`` whose recovered state is
correct; ``visible`` and ``hidden`` restrict it to the steps where the target is visible
(resp. hidden). ``kbest_score(k)`` is the fraction of steps whose first ``k`` states
contain a correct one (``k = 1``: the top-1 score of the first phase).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from dbn.errors import InputError, ShapeError

__all__ = ["PathScore", "correct_states", "kbest_score", "path_score"]


class PathScore(NamedTuple):
    """Fractions of correct steps: all, target visible, target hidden (NaN if none)."""

    overall: float
    visible: float
    hidden: float


def correct_states(kind: np.ndarray, obs: np.ndarray, true_obs: np.ndarray) -> np.ndarray:
    """Which recovered states are correct (module docstring).

    Parameters
    ----------
    kind : (num_steps, ...) int: 0 visible, 1 hidden, -1 none.
    obs : (num_steps, ...) int: associated observation index (-1 for hidden / none).
    true_obs : (num_steps,) int: the target's observation index, -1 when hidden.

    Returns
    -------
    (num_steps, ...) bool.
    """
    kind = np.asarray(kind)
    obs = np.asarray(obs)
    true_obs = np.asarray(true_obs)
    if kind.shape != obs.shape or kind.shape[:1] != true_obs.shape:
        raise ShapeError(f"kind {kind.shape}, obs {obs.shape} and true_obs {true_obs.shape} disagree")
    extra = (slice(None),) + (None,) * (kind.ndim - 1)
    tv = true_obs[extra]
    return np.where(tv >= 0, (kind == 0) & (obs == tv), kind == 1)


def kbest_score(kind: np.ndarray, obs: np.ndarray, true_obs: np.ndarray, k: int) -> float:
    """Fraction of steps whose first ``k`` states hold a correct one (sec. 7.2).

    Parameters
    ----------
    kind, obs : (num_steps, K) k-best lists, best first, ``K >= k``.
    true_obs : (num_steps,) the target's observation index, -1 when hidden.
    k : how many of the best states count.
    """
    kind = np.asarray(kind)
    if kind.ndim != 2:
        raise ShapeError(f"kind must be (num_steps, K), got {kind.shape}")
    if not 1 <= k <= kind.shape[1]:
        raise InputError(f"k must lie in [1, {kind.shape[1]}], got {k!r}")
    if kind.shape[0] == 0:
        raise InputError("kind has no steps: a k-best score needs num_steps >= 1")
    ok = correct_states(kind[:, :k], np.asarray(obs)[:, :k], true_obs)
    return float(np.mean(np.any(ok, axis=1)))


def path_score(kind: np.ndarray, obs: np.ndarray, true_obs: np.ndarray) -> PathScore:
    """Score of a recovered path (sec. 7.2): overall, visible steps, hidden steps.

    Parameters
    ----------
    kind, obs : (num_steps,) the recovered state of every step.
    true_obs : (num_steps,) the target's observation index, -1 when hidden.
    """
    if np.size(kind) == 0:
        raise InputError("kind has no steps: a path score needs num_steps >= 1")
    ok = correct_states(np.asarray(kind), np.asarray(obs), true_obs)
    tv = np.asarray(true_obs) >= 0

    def frac(mask: np.ndarray) -> float:
        return float(np.mean(ok[mask])) if np.any(mask) else float("nan")

    return PathScore(float(np.mean(ok)), frac(tv), frac(~tv))
