"""Second phase of seed 001 (sec. 4.2): the path through the layered graph of each step's
k best states, by dynamic programming (:mod:`inference.exact.layered_dp`).

Layer 0 is the given initial state (visible at ``C_0``); layer ``t`` holds the first
``k`` states of step ``t``. An edge joins two states of consecutive layers when the
transition is legal in the network's spatial and temporal topology:

* visible ``a`` -> visible ``b``: an edge ``a -> b`` whose travel time can be one step;
* visible ``a`` -> hidden ``(j, ta)``: an edge ``a -> j`` whose travel time can be
  ``ta + 1`` (``faithful``), or can exceed one step (default);
* hidden ``(j, ta)`` -> hidden ``(j', ta')``: ``j' = j`` and ``ta' = ta - 1``
  (``faithful``), or just ``j' = j`` (default: the filter merges hidden states by
  destination, so the reported ``ta`` is only the heaviest particle's);
* hidden ``(j, ta)`` -> visible ``b``: ``b = j`` and ``ta = 1`` (``faithful``), or just
  ``b = j`` (default).

Costs. ``faithful``: the paper's "weight of an edge is the priority of the state it is
directed to", priorities ``1 .. k`` (1 = best), and the optimum minimises their sum.
Default: a state costs ``-log`` of its normalised mass from the first phase, so that a
step's cost reflects how much better the best state is than the others, not only their
order (a chain of unlikely hidden states, always legal as a countdown, then costs what it
should); and an edge between two visible states costs ``-log P_s(f_a, f_b) = d_M^2 / 2``
(eq. 3) between their observations' features (*feature continuity*: consecutive
observations of one object drift slowly, eq. 11, so a path that hops from one passer-by
to another pays for it - the "higher order information" of the paper's conclusion). The
default was chosen by measurement (seeds 100-105, see :mod:`models.pathrecovery.filter`).
Disconnected layers restart from the best state so far (the paper's fallback, see
:func:`inference.exact.layered_dp.layered_shortest_path`).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from dbn.errors import InputError, ShapeError
from inference.exact.layered_dp import LayeredPath, layered_shortest_path
from models.pathrecovery.filter import (
    HIDDEN,
    NONE,
    VISIBLE,
    KBestLists,
    PathFilterModel,
    check_features,
)
from models.pathrecovery.model import CameraNetwork, whiten

__all__ = ["RecoveredPath", "legal_transitions", "recover_path"]

#: cost of a state of zero reported mass (never happens for listed states; a guard)
_MIN_MASS = 1e-300


class RecoveredPath(NamedTuple):
    """The second phase's path, one state per step ``t = 1 .. T - 1``.

    Attributes
    ----------
    kind : (num_steps,) int8: 0 visible, 1 hidden, -1 none (empty list).
    cam, ta, obs : (num_steps,) int64 as in :class:`models.pathrecovery.filter.StepInfo`.
    rank : (num_steps,) int64 position of the chosen state in its k-best list (0 = best).
    jumped : (num_steps,) bool, steps entered through a disconnection restart.
    """

    kind: np.ndarray
    cam: np.ndarray
    ta: np.ndarray
    obs: np.ndarray
    rank: np.ndarray
    jumped: np.ndarray


def legal_transitions(
    network: CameraNetwork,
    kind_a: np.ndarray,
    cam_a: np.ndarray,
    ta_a: np.ndarray,
    kind_b: np.ndarray,
    cam_b: np.ndarray,
    ta_b: np.ndarray,
    faithful: bool = False,
    gaps: bool = True,
) -> np.ndarray:
    """Which transitions from the states of one layer to the next are legal (module docstring).

    Parameters
    ----------
    network : CameraNetwork.
    kind_a, cam_a, ta_a : (m,) states of layer t (kind 0 visible, 1 hidden).
    kind_b, cam_b, ta_b : (n,) states of layer t + 1.
    faithful : exact ``ta`` countdown (True) or destination-only hidden states (False).
    gaps : when False no edge can be a gap (every travel time is one step).

    Returns
    -------
    (m, n) bool.
    """
    A = (np.asarray(kind_a)[:, None], np.asarray(cam_a)[:, None], np.asarray(ta_a)[:, None])
    B = (np.asarray(kind_b)[None, :], np.asarray(cam_b)[None, :], np.asarray(ta_b)[None, :])
    ka, ca, ta = np.broadcast_arrays(*A, B[0])[:3]
    kb, cb, tb = np.broadcast_arrays(*B, A[0])[:3]
    ok = np.zeros(ka.shape, dtype=bool)
    vv = (ka == VISIBLE) & (kb == VISIBLE)
    vh = (ka == VISIBLE) & (kb == HIDDEN)
    hh = (ka == HIDDEN) & (kb == HIDDEN)
    hv = (ka == HIDDEN) & (kb == VISIBLE)
    if np.any(vv):
        if gaps:
            ok[vv] = network.delay_prob(ca[vv], cb[vv], np.ones(np.count_nonzero(vv), dtype=np.int64)) > 0
        else:
            ok[vv] = network.edge_index(ca[vv], cb[vv]) >= 0
    if gaps:
        if np.any(vh):
            if faithful:
                ok[vh] = network.delay_prob(ca[vh], cb[vh], tb[vh] + 1) > 0
            else:
                ok[vh] = network.gap_prob(ca[vh], cb[vh]) > 0
        ok[hh] = (cb[hh] == ca[hh]) & ((tb[hh] == ta[hh] - 1) if faithful else True)
        ok[hv] = (cb[hv] == ca[hv]) & ((ta[hv] == 1) if faithful else True)
    return ok


def recover_path(
    model: PathFilterModel,
    lists: KBestLists,
    obs_feat: np.ndarray,
    k: int = 7,
    faithful: bool | None = None,
    costs: str | None = None,
    countdown: bool | None = None,
    continuity: bool | None = None,
) -> RecoveredPath:
    """Second phase (seed 001, sec. 4.2): best legal path through the k-best lists.

    Parameters
    ----------
    model : the PathFilterModel the lists were produced with (network, ``C_0``, ``f_0``,
        ``Sigma``, and whether gaps were modelled).
    lists : KBestLists from :func:`models.pathrecovery.filter.run_filter`.
    obs_feat : (num_obs, feature_dim) the features the lists' observation indices point
        into (``odb.feat``); only the listed rows are read.
    k : how many of each step's best states form a layer (``k <= lists.kind.shape[1]``).
    faithful : the paper's second phase (rank priorities, exact countdown, no feature
        term); by default ``model.config.faithful``.
    costs : override the node costs: ``"rank"`` (the paper's priorities ``1..k``) or
        ``"logmass"`` (``-log`` mass).
    countdown : override the hidden legality: True = exact ``ta`` countdown, False =
        destination only.
    continuity : override the feature-continuity edge cost (module docstring).

    Returns
    -------
    RecoveredPath over steps ``t = 1 .. T - 1``. Cost ``O(k^2 T)`` (sec. 5).

    Raises
    ------
    ShapeError, InputError on lists or features that do not fit.
    """
    faithful = model.config.faithful if faithful is None else bool(faithful)
    kind, obs_feat = _check_inputs(model, lists, obs_feat, k)
    costs = ("rank" if faithful else "logmass") if costs is None else costs
    if costs not in ("rank", "logmass"):
        raise InputError(f"costs must be 'rank' or 'logmass', got {costs!r}")
    countdown = faithful if countdown is None else bool(countdown)
    continuity = (not faithful) if continuity is None else bool(continuity)
    steps = kind.shape[0]
    cols = [np.flatnonzero(kind[s, :k] != NONE) for s in range(steps)]
    layers = (
        [np.array([VISIBLE])] + [kind[s, c] for s, c in enumerate(cols)],
        [np.array([model.c0])] + [lists.cam[s, c] for s, c in enumerate(cols)],
        [np.array([0])] + [lists.ta[s, c] for s, c in enumerate(cols)],
    )
    node_costs = [np.zeros(1)]
    for s, c in enumerate(cols):
        if costs == "rank":
            node_costs.append((c + 1).astype(np.float64))
        else:
            node_costs.append(-np.log(np.maximum(lists.mass[s, c], _MIN_MASS)))
    layers_w = _layer_features(model, lists, obs_feat, cols) if continuity else None
    edge_costs = [_edge_cost(model, layers, layers_w, t, countdown) for t in range(steps)]
    res = layered_shortest_path(node_costs, edge_costs)
    return _path(lists, kind, cols, res)


def _check_inputs(
    model: PathFilterModel, lists: KBestLists, obs_feat: np.ndarray, k: int
) -> tuple[np.ndarray, np.ndarray]:
    """Validate :func:`recover_path`'s lists, ``k`` and features; returns ``lists.kind``
    and the features as float64 arrays."""
    kind = np.asarray(lists.kind)
    if kind.ndim != 2:
        raise ShapeError(f"lists.kind must be (num_steps, K), got {kind.shape}")
    for name in ("cam", "ta", "obs", "mass"):
        if np.shape(getattr(lists, name)) != kind.shape:
            raise ShapeError(f"lists.{name} has shape {np.shape(getattr(lists, name))}, expected {kind.shape}")
    if not isinstance(k, int | np.integer) or not 1 <= k <= kind.shape[1]:
        raise InputError(f"k must be an int in [1, {kind.shape[1]}], got {k!r}")
    check_features("obs_feat", obs_feat)  # NaN would silently lower the score
    obs_feat = np.asarray(obs_feat, dtype=np.float64)
    if obs_feat.ndim != 2 or obs_feat.shape[1] != model.f0.size:
        raise ShapeError(f"obs_feat must be (num_obs, {model.f0.size}), got {obs_feat.shape}")
    if np.any(lists.obs >= obs_feat.shape[0]):
        raise InputError(f"lists.obs points past obs_feat (max {int(np.max(lists.obs))}, rows {obs_feat.shape[0]})")
    return kind, obs_feat


def _layer_features(
    model: PathFilterModel, lists: KBestLists, obs_feat: np.ndarray, cols: list[np.ndarray]
) -> list[np.ndarray]:
    """Whitened features of every layer's listed observations (``f_0`` for the first
    layer); NaN rows for hidden states. Only the listed rows of ``obs_feat`` are read."""
    layers_w = [model.u0[None, :]]
    for s, c in enumerate(cols):
        o = lists.obs[s, c]
        w = np.full((c.size, model.f0.size), np.nan)
        v = o >= 0
        if np.any(v):
            w[v] = whiten(model.chol, obs_feat[o[v]])
        layers_w.append(w)
    return layers_w


def _edge_cost(
    model: PathFilterModel,
    layers: tuple[list[np.ndarray], list[np.ndarray], list[np.ndarray]],
    layers_w: list[np.ndarray] | None,
    t: int,
    countdown: bool,
) -> np.ndarray:
    """Costs between layers ``t`` and ``t + 1``: ``inf`` for an illegal transition, plus
    ``-log P_s`` of consecutive observations when ``layers_w`` is given (continuity)."""
    kinds, cams, tas = layers
    ok = legal_transitions(
        model.network,
        kinds[t], cams[t], tas[t],
        kinds[t + 1], cams[t + 1], tas[t + 1],
        faithful=countdown, gaps=model.config.gaps,
    )  # fmt: skip
    ec = np.where(ok, 0.0, np.inf)
    if layers_w is not None:
        diff = layers_w[t][:, None, :] - layers_w[t + 1][None, :, :]
        d2 = 0.5 * np.sum(diff * diff, axis=2)  # -log P_s of consecutive observations
        ec = ec + np.where(np.isnan(d2), 0.0, d2)
    return ec


def _path(
    lists: KBestLists, kind: np.ndarray, cols: list[np.ndarray], res: LayeredPath
) -> RecoveredPath:
    """The :class:`RecoveredPath` of a layered shortest path over the listed states."""
    steps = kind.shape[0]
    out_kind = np.full(steps, NONE, dtype=np.int8)
    out_cam = np.full(steps, -1, dtype=np.int64)
    out_ta = np.zeros(steps, dtype=np.int64)
    out_obs = np.full(steps, -1, dtype=np.int64)
    rank = np.full(steps, -1, dtype=np.int64)
    for s, c in enumerate(cols):
        j = res.path[s + 1]
        if j < 0:
            continue
        col = c[j]
        out_kind[s], out_cam[s], out_ta[s] = kind[s, col], lists.cam[s, col], lists.ta[s, col]
        out_obs[s], rank[s] = lists.obs[s, col], col
    return RecoveredPath(out_kind, out_cam, out_ta, out_obs, rank, res.jumped[1:].copy())
