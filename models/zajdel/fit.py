r"""The multi-camera trackers' parameters fitted on passes whose people are known.

With the people known, the path model's hidden links are observed: a person's passes in
time order are one entry and a chain of moves, so the maximum-likelihood parameters of
the path model (seed 000, eq. 2; seed 002, eq. 1.19) are frequencies and moments of those
moves, and the appearance scales are the variances within and between people. No EM, no
search: :func:`pass_counts` gathers the sufficient statistics of one file,
:func:`fit_counts` turns their sum over files into parameters.

With :math:`\lambda` pseudo-observations (``strength``; 0: the plain maximum likelihood):

* transitions, per row :math:`(l_j, b^q_j)`:
  :math:`P(l_k, b^e_k \mid l_j, b^q_j) = (n_{jk} + \lambda / (CB)) / (n_j + \lambda)`, a
  uniform Dirichlet prior of total mass :math:`\lambda` (a row without moves is uniform);
* entries: :math:`P(l, b^e) = (n_{lb} + \lambda / (CB)) / (P + \lambda)` over the first
  passes of the :math:`P` people;
* travel time per camera pair (:math:`N` moves, times :math:`x`), pulled toward the moments
  :math:`\delta_0, \sigma_0^2` of every move with :math:`\lambda` pseudo-moves (the EM's
  rule, :func:`models.zajdel.learnsearch.em_step`):
  :math:`\delta = (\lambda\delta_0 + \sum x) / (\lambda + N)`,
  :math:`\sigma^2 = (\lambda\sigma_0^2 + \sum (x - \delta)^2) / (\lambda + N)`; a pair
  without moves takes :math:`\delta_0, \sigma_0` (a spread of 0 is floored at
  :math:`10^{-6}\sigma_0`);
* ``p_new`` = :math:`(P + \lambda / 2) / (n + \lambda)` over the :math:`n` passes;
* appearance: ``within_std`` the square root of the pooled variance of the passes about
  their person's mean (per dimension, averaged over dimensions), ``between_std`` that of
  the people's means about theirs, less the part the within-person noise explains
  (:math:`\sigma_w^2 \overline{1/n_p}`), floored at :math:`10^{-6}\sigma_w`: the scales of
  :func:`models.zajdel.params.default_prior` (the appearance is not shrunk).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

from dbn.errors import InputError
from models.zajdel.data import Observations

__all__ = ["PassCounts", "PassFit", "pass_counts", "sum_counts", "fit_counts", "fit_passes"]

_FLOOR = 1e-6  # relative floor of a spread, and of p_new's distance from 0 and 1


class PassCounts(NamedTuple):
    """Sufficient statistics of passes with known people (add them with :meth:`plus`).

    Attributes
    ----------
    trans : ndarray, shape (C, B, C, B): moves from quit (camera, border) to enter
    entry : ndarray, shape (C, B): first passes of people
    travel : ndarray, shape (3, C, C): per camera pair the moves' count, sum and sum of
        squares of the travel time (enter minus the previous quit)
    passes, people : int
    within : ndarray, shape (2,): the squared deviations of the passes from their person's
        mean (summed over passes and dimensions), and their degrees of freedom
    means : ndarray, shape (P, r): each person's mean appearance
    inverse_sizes : ndarray, shape (P,): 1 / each person's number of passes
    """

    trans: np.ndarray
    entry: np.ndarray
    travel: np.ndarray
    passes: int
    people: int
    within: np.ndarray
    means: np.ndarray
    inverse_sizes: np.ndarray

    def plus(self, other: PassCounts) -> PassCounts:
        """The statistics of both sets of passes (the same cameras, borders and dimensions)."""
        return PassCounts(self.trans + other.trans, self.entry + other.entry,
                          self.travel + other.travel, self.passes + other.passes,
                          self.people + other.people, self.within + other.within,
                          np.concatenate([self.means, other.means]),
                          np.concatenate([self.inverse_sizes, other.inverse_sizes]))  # fmt: skip


class PassFit(NamedTuple):
    """Fitted parameters (:func:`fit_counts`), in the units of ``dbntrack track``'s config.

    Attributes
    ----------
    trans : (C, B, C, B); entry : (C, B); travel_mean, travel_std : (C, C)
    p_new, within_std, between_std : float
    """

    trans: np.ndarray
    entry: np.ndarray
    travel_mean: np.ndarray
    travel_std: np.ndarray
    p_new: float
    within_std: float
    between_std: float


def pass_counts(obs: Observations, person: np.ndarray, num_cameras: int, num_borders: int,
                ids: np.ndarray | None = None) -> PassCounts:
    """The statistics of ``obs`` (n passes) whose people are ``person`` (n,) ints.

    Each person's passes in order of entry time are an entry and a chain of moves. A pass
    that enters before the person's previous pass quit (one person in two places) is an
    :class:`~dbn.errors.InputError` naming both (by ``ids`` (n,), default their 0-based
    quit-time order), as is a camera or border beyond the counts."""
    person = np.asarray(person)
    n = obs.num_obs
    if person.shape != (n,):
        raise InputError(f"person: expected shape ({n},), got {person.shape}")
    cam, be, bq = (np.asarray(x, np.int64) for x in (obs.camera, obs.border_enter,
                                                     obs.border_quit))  # fmt: skip
    C, B = int(num_cameras), int(num_borders)
    if n and (cam.max() >= C or max(be.max(), bq.max()) >= B):
        raise InputError(f"camera ids up to {cam.max()} and borders up to "
                         f"{max(be.max(), bq.max())} do not fit {C} cameras x {B} borders")
    te, tq = np.asarray(obs.t_enter, float), np.asarray(obs.t_quit, float)
    order = np.lexsort((te, person))  # by person, then by entry time
    p_sorted = person[order]
    first = np.r_[True, p_sorted[1:] != p_sorted[:-1]]
    j, k = order[:-1][~first[1:]], order[1:][~first[1:]]  # consecutive passes of one person
    x = te[k] - tq[j]
    if np.any(x < 0):
        i = int(np.argmax(x < 0))
        name = np.arange(n) if ids is None else np.asarray(ids)
        raise InputError(f"person {person[k[i]]}: pass {name[k[i]]} enters at {te[k[i]]:g}, "
                         f"before pass {name[j[i]]} quits at {tq[j[i]]:g}; the trackers "
                         "follow one person in one camera at a time")  # fmt: skip
    trans = np.zeros((C, B, C, B))
    np.add.at(trans, (cam[j], bq[j], cam[k], be[k]), 1.0)
    entry = np.zeros((C, B))
    np.add.at(entry, (cam[order[first]], be[order[first]]), 1.0)
    travel = np.zeros((3, C, C))
    for row, w in enumerate((np.ones_like(x), x, x * x)):
        np.add.at(travel[row], (cam[j], cam[k]), w)
    return PassCounts(trans, entry, travel, n, int(first.sum()), *_appearance(obs, person))


def _appearance(obs: Observations, person: np.ndarray):
    """Within-person squared deviations and dof, people's means, 1 / passes per person."""
    app = np.asarray(obs.appearance, float)
    _, inv, sizes = np.unique(person, return_inverse=True, return_counts=True)
    sums = np.zeros((sizes.size, app.shape[1]))
    np.add.at(sums, inv, app)
    means = sums / sizes[:, None]
    dev = float(np.sum((app - means[inv]) ** 2))
    dof = float((person.size - sizes.size) * app.shape[1])
    return np.array([dev, dof]), means, 1.0 / sizes


def fit_counts(counts: PassCounts, strength: float = 1.0) -> PassFit:
    """Parameters from summed statistics with ``strength`` pseudo-observations (module
    docstring). Fewer than two people, or no pass with a second pass of its person
    (no within-person spread), is an :class:`~dbn.errors.InputError`."""
    lam = float(strength)
    if not (np.isfinite(lam) and lam >= 0):
        raise InputError(f"strength = {strength!r}: expected a finite number >= 0")
    if counts.people < 2 or counts.within[1] <= 0:
        raise InputError(f"{counts.people} people over {counts.passes} passes: the fit needs "
                         "two people or more and someone seen twice")  # fmt: skip
    C, B = counts.entry.shape
    rows = counts.trans.reshape(C * B, C * B)
    prior = lam / (C * B)
    trans = np.where(rows.sum(1, keepdims=True) + lam > 0,
                     (rows + prior) / np.maximum(rows.sum(1, keepdims=True) + lam, 1e-300),
                     1.0 / (C * B)).reshape(C, B, C, B)  # fmt: skip
    entry = (counts.entry + prior) / (counts.people + lam)
    mean, std = _travel(counts.travel, lam)
    p_new = (counts.people + lam / 2) / (counts.passes + lam)
    within = counts.within[0] / counts.within[1]
    r = counts.means.shape[1]
    spread = float(np.sum(np.var(counts.means, axis=0, ddof=1))) / r
    between = max(spread - within * float(np.mean(counts.inverse_sizes)), _FLOOR**2 * within)
    return PassFit(trans, entry, mean, std, float(np.clip(p_new, _FLOOR, 1 - _FLOOR)),
                   float(np.sqrt(within)), float(np.sqrt(between)))  # fmt: skip


def _travel(travel: np.ndarray, lam: float) -> tuple[np.ndarray, np.ndarray]:
    """Per camera pair travel-time mean and spread pulled toward the pooled moments."""
    N, S1, S2 = travel
    total = N.sum()  # > 0: fit_counts asks for someone seen twice
    d0 = S1.sum() / total
    s0 = np.sqrt(max(S2.sum() / total - d0 * d0, 0.0))
    if s0 == 0:
        s0 = max(abs(d0), 1.0)  # one travel time only: a spread of its size
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.where(N + lam > 0, (lam * d0 + S1) / (lam + N), d0)
        spread = (lam * s0**2 + S2 - 2 * mean * S1 + mean**2 * N) / (lam + N)
        var = np.where(N + lam > 0, spread, s0**2)
    return mean, np.sqrt(np.maximum(var, (_FLOOR * s0) ** 2))


def fit_passes(sets: Sequence[tuple[Observations, np.ndarray]], num_cameras: int,
               num_borders: int, strength: float = 1.0) -> PassFit:
    """:func:`fit_counts` of the summed :func:`pass_counts` of ``(obs, person)`` sets."""
    if not sets:
        raise InputError("no passes to fit on")
    return fit_counts(sum_counts([pass_counts(o, p, num_cameras, num_borders)
                                  for o, p in sets]), strength)  # fmt: skip


def sum_counts(parts: Sequence[PassCounts]) -> PassCounts:
    """The statistics of several sets of passes together (:meth:`PassCounts.plus`); sets
    of different appearance dimensions are an :class:`~dbn.errors.InputError`."""
    dims = {part.means.shape[1] for part in parts}
    if len(dims) > 1:
        raise InputError(f"the sets' appearance dimensions differ: {sorted(dims)}")
    total = parts[0]
    for part in parts[1:]:
        total = total.plus(part)
    return total
