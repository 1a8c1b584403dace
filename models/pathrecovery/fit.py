r"""Seed 001's network parameters counted from the objects' observed moves.

Where every observation's object is known (the ``object`` column of an observations
file), each object's consecutive observations, at camera ``a`` at step ``t`` and camera
``b`` at step ``t' > t``, are one move along the edge ``a -> b`` of ``G_mc`` with the
delay ``d = t' - t`` (sec. 3.1, 4.1.1: ``d = 1`` visible at ``b`` at the next step, ``d >
1`` hidden in between). With ``n_e`` moves along edge ``e`` out of ``n_a`` moves leaving
camera ``a`` and ``D_e`` their summed delays, the fit keeps the network's edges (its
topology and which edges have a gap are the user's declaration) and estimates

.. math:: W^p_e = \frac{n_e + \lambda W^p_{0,e}}{n_a + \lambda}, \qquad
          \mu_e = \frac{D_e + \lambda \mu_{0,e}}{n_e + \lambda} \;(\mu_{0,e} > 0),

the counts' maximum-likelihood values shrunk towards the given network (``W^p_0``,
``mu_0``) by ``lambda`` pseudo-moves per camera and per gap edge: a camera nothing left
keeps its given probabilities. The gap mean is the mean delay (the mean of
``T_ij = N(mu, (0.2 mu)^2)`` rounded, :mod:`models.pathrecovery.model`); edges without a
gap (``mu_0 = 0``) keep exactly one step. Moves no edge of the network explains (along an
edge it does not list, or of a delay above 1 along an edge without a gap, e.g. a missed
detection) are counted apart and left out. An object's last observation starts no move:
a gap still open at the recording's end is not seen, so long gaps near the end are
under-represented.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

from dbn.errors import InputError

__all__ = ["MoveCounts", "count_moves", "pool_moves", "fitted_network", "PRIOR_MOVES"]

PRIOR_MOVES = 1.0
"""``lambda``: pseudo-moves per camera (and per gap edge) at the given network's values,
declared, not chosen on data."""


class MoveCounts(NamedTuple):
    """Moves of one run (or several pooled) along the edges of one network.

    Attributes
    ----------
    edge_moves : (num_edges,) moves along each edge (``n_e``).
    delay_sums : (num_edges,) their summed delays in steps (``D_e``).
    unexplained : moves no edge of the network explains (left out).
    """

    edge_moves: np.ndarray
    delay_sums: np.ndarray
    unexplained: int


def count_moves(net, t: np.ndarray, cam: np.ndarray, obj: np.ndarray) -> MoveCounts:
    """The moves of every object (module docstring).

    Parameters
    ----------
    net : :class:`~models.pathrecovery.model.CameraNetwork`.
    t, cam, obj : (num_obs,) int arrays: each observation's step, camera and object.

    Raises
    ------
    InputError
        An object observed twice at one step (naming the object and the step).
    """
    t, cam, obj = (np.asarray(a, dtype=np.int64) for a in (t, cam, obj))
    order = np.lexsort((t, obj))
    t, cam, obj = t[order], cam[order], obj[order]
    same = np.flatnonzero(obj[1:] == obj[:-1])
    a, b, d = cam[same], cam[same + 1], t[same + 1] - t[same]
    if np.any(d == 0):
        i = same[int(np.argmax(d == 0))]
        raise InputError(f"object {obj[i]} is observed twice at t = {t[i]}")
    edge = net.edge_index(a, b)  # -1: no such edge
    ok = (edge >= 0) & ((d == 1) | (net.gap_mean[np.maximum(edge, 0)] > 0))
    e = edge[ok]
    return MoveCounts(np.bincount(e, minlength=net.num_edges).astype(np.float64),
                      np.bincount(e, weights=d[ok], minlength=net.num_edges),
                      int(np.count_nonzero(~ok)))  # fmt: skip


def pool_moves(counts: Sequence[MoveCounts]) -> MoveCounts:
    """The sum of several runs' counts (of one network)."""
    return MoveCounts(sum(c.edge_moves for c in counts), sum(c.delay_sums for c in counts),
                      sum(c.unexplained for c in counts))  # fmt: skip


def fitted_network(net, counts: MoveCounts, strength: float = PRIOR_MOVES):
    """The network with ``W^p`` and the gap means estimated from ``counts`` (module
    docstring; ``strength`` is ``lambda`` > 0). Returns a new
    :class:`~models.pathrecovery.model.CameraNetwork` (same edges, coordinates, name)."""
    from models.pathrecovery.model import CameraNetwork

    if not strength > 0:
        raise InputError(f"strength must be > 0 (pseudo-moves per camera), got {strength!r}")
    leaving = np.bincount(net.rows, weights=counts.edge_moves, minlength=net.num_cameras)
    probs = (counts.edge_moves + strength * net.probs) / (leaving[net.rows] + strength)
    gap = np.asarray(net.gap_mean, dtype=np.float64)
    mean = (counts.delay_sums + strength * gap) / (counts.edge_moves + strength)
    return CameraNetwork(net.indptr, net.indices, probs, np.where(gap > 0, mean, 0.0),
                         net.coords, name=net.name)  # fmt: skip
