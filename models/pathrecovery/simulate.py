"""Simulated data of seed 001, sec. 7.1: camera networks, moving objects, observations,
and the confusion measure of sec. 6 (eq. 10). Everything here is SIMULATED data.

Topologies (sec. 7.1.1, 7.2.1, 7.2.2)
    * :func:`manhattan_grid`: intersections are 4-camera cliques, joined by chains of
      street cameras. The default 7 x 7 intersections with horizontal chains of 4 and
      vertical chains of 3 cameras give 490 cameras with mean degree 3.74 counting the
      self loop (the paper: 502 cameras, 3.7).
    * :func:`street`: two rows of cameras along both sides of a street; a camera leads to
      the two next cameras on its own side and the two on the other side (4 neighbours,
      degree 5 with the self loop).

    Transitions: a self loop of probability ``p_self`` and the rest shared by the
    neighbours, with weight ``1 + bias`` on edges heading in one favoured direction and 1
    on the others ("a small weight is given for going in a certain direction").
    Travel times: a fraction ``gap_fraction`` (20 %) of the undirected non-self edges get
    a gap, ``T_ij ~ N(mu, 0.2 mu)`` with half of them ``mu = 7`` and half ``mu = 3``
    steps; all other edges take one step.

Objects (sec. 7.1.2)
    ``M`` objects start visible at random cameras and move with the prediction step of
    sec. 4.1.1 (:func:`models.pathrecovery.model.propagate`). Object ``i`` has a mean
    feature ``f_i`` and drifting features, eq. 11:
    ``f_t = gamma f_i + (1 - gamma) f~_{t-1}``, ``f~_{t-1} ~ N(f_{t-1}, Sigma)``,
    ``f_0 = f_i``, ``gamma = 0.8``. One object is the target.

How the feature spread is chosen (not hand-tuned)
    The paper does not say how the means ``f_i`` are drawn. We draw
    ``f_i = s L z_i`` with ``z_i ~ N(0, I)`` and ``Sigma = L L^T`` (``Sigma = I`` by
    default), so an observation is ``f_{i,t} = s L z_i + e_{i,t}`` where the drift
    ``e_{i,t} = f_{i,t} - f_i`` follows ``e_t = (1 - gamma)(e_{t-1} + eps_t)`` and does
    not depend on ``s``. Hence the target's similarities to ``f_0`` do not depend on ``s``
    and those of the other objects shrink as ``s`` grows: the confusion measure ``CM(s)``
    decreases with ``s``. The spread ``s`` is found by bisection on ``log s`` (60
    halvings of [1e-3, 1e3]) so that ``CM(s)`` of THIS data set (same draws, same paths)
    equals the requested value; the achieved ``CM`` is returned alongside.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from dbn.checks import check_count, make_rng
from dbn.errors import InputError, ModelError, ShapeError
from models.pathrecovery.model import CameraNetwork, propagate, sigma_cholesky, whiten

__all__ = [
    "ObservationDB",
    "Scene",
    "confusion_measure",
    "manhattan_grid",
    "simulate_scene",
    "similarity",
    "street",
]


# ---------------------------------------------------------------------------- networks
def _network_from_edges(
    rng: np.random.Generator,
    coords: np.ndarray,
    und_edges: np.ndarray,
    p_self: float,
    bias: float,
    direction: np.ndarray,
    gap_fraction: float,
    gap_means: tuple[float, float],
    name: str,
) -> CameraNetwork:
    """Build a :class:`CameraNetwork` from undirected edges (no self loops) and positions."""
    if not 0.0 < p_self < 1.0:
        raise ModelError(f"p_self must lie in (0, 1), got {p_self!r}")
    if bias < 0:
        raise ModelError(f"bias must be >= 0, got {bias!r}")
    if not 0.0 <= gap_fraction <= 1.0:
        raise ModelError(f"gap_fraction must lie in [0, 1], got {gap_fraction!r}")
    if len(gap_means) != 2 or min(gap_means) <= 1.0:
        raise ModelError(f"gap_means must be two means > 1 step, got {gap_means!r}")
    n = coords.shape[0]
    und = np.asarray(und_edges, dtype=np.int64)
    n_und = und.shape[0]
    # gaps on a random gap_fraction of the undirected edges, half of each mean
    und_gap = np.zeros(n_und)
    n_gap = int(round(gap_fraction * n_und))
    chosen = rng.permutation(n_und)[:n_gap]
    und_gap[chosen[: n_gap // 2]] = gap_means[0]
    und_gap[chosen[n_gap // 2 :]] = gap_means[1]
    src = np.concatenate([und[:, 0], und[:, 1], np.arange(n)])
    dst = np.concatenate([und[:, 1], und[:, 0], np.arange(n)])
    gap = np.concatenate([und_gap, und_gap, np.zeros(n)])
    order = np.lexsort((dst, src))
    src, dst, gap = src[order], dst[order], gap[order]
    is_self = src == dst
    heading = coords[dst] - coords[src]
    favoured = heading @ direction > 1e-9
    w = np.where(favoured, 1.0 + bias, 1.0)
    w[is_self] = 0.0
    row_w = np.bincount(src, weights=w, minlength=n)
    probs = np.where(is_self, p_self, (1.0 - p_self) * w / row_w[src])
    indptr = np.concatenate([[0], np.cumsum(np.bincount(src, minlength=n))])
    return CameraNetwork(indptr, dst, probs, gap, coords, name=name)


def manhattan_grid(
    seed: int | np.random.Generator,
    n_rows: int = 7,
    n_cols: int = 7,
    block: tuple[int, int] = (4, 3),
    p_self: float = 0.5,
    bias: float = 0.2,
    gap_fraction: float = 0.2,
    gap_means: tuple[float, float] = (7.0, 3.0),
) -> CameraNetwork:
    """Manhattan grid of cameras (seed 001, sec. 7.2.1, fig. 3a). SIMULATED topology.

    Every intersection is a clique of 4 cameras (its N, E, S, W corners); the E camera
    of an intersection is joined to the W camera of the next one by a chain of
    ``block[0]`` street cameras, and the S camera to the N camera below by a chain of
    ``block[1]``.

    Parameters
    ----------
    seed : int or numpy Generator (which edges get gaps).
    n_rows, n_cols : intersections per column and per row.
    block : street cameras between two intersections, (horizontal, vertical).
    p_self : self-loop probability of every camera.
    bias : extra relative weight of edges heading north-east (the favoured direction).
    gap_fraction : fraction of the undirected edges with a gap.
    gap_means : the two gap means in steps (half of the gaps each).

    Returns
    -------
    CameraNetwork with ``4 n_rows n_cols + block[0] n_rows (n_cols - 1)
    + block[1] n_cols (n_rows - 1)`` cameras.
    """
    rng = make_rng(seed)
    if n_rows < 1 or n_cols < 1 or min(block) < 1:
        raise ModelError(f"need n_rows, n_cols >= 1 and block >= 1, got {n_rows}, {n_cols}, {block}")
    bh, bv = int(block[0]), int(block[1])
    px, py = bh + 3.0, bv + 3.0  # pitch between intersection centres
    coords: list[tuple[float, float]] = []
    edges: list[tuple[int, int]] = []
    corner = np.zeros((n_rows, n_cols, 4), dtype=np.int64)  # N, E, S, W
    offsets = ((0.0, 0.5), (0.5, 0.0), (0.0, -0.5), (-0.5, 0.0))
    for r in range(n_rows):
        for c in range(n_cols):
            cx, cy = c * px, -r * py
            for k, (dx, dy) in enumerate(offsets):
                corner[r, c, k] = len(coords)
                coords.append((cx + dx, cy + dy))
            ids = corner[r, c]
            edges += [(int(ids[a]), int(ids[b])) for a in range(4) for b in range(a + 1, 4)]

    def chain(a: int, b: int, n: int) -> None:
        (ax, ay), (bx, by) = coords[a], coords[b]
        prev = a
        for i in range(1, n + 1):
            frac = i / (n + 1)
            coords.append((ax + frac * (bx - ax), ay + frac * (by - ay)))
            edges.append((prev, len(coords) - 1))
            prev = len(coords) - 1
        edges.append((prev, b))

    for r in range(n_rows):
        for c in range(n_cols - 1):
            chain(int(corner[r, c, 1]), int(corner[r, c + 1, 3]), bh)
    for r in range(n_rows - 1):
        for c in range(n_cols):
            chain(int(corner[r, c, 2]), int(corner[r + 1, c, 0]), bv)
    direction = np.array([1.0, 1.0]) / np.sqrt(2.0)
    return _network_from_edges(
        rng, np.array(coords), np.array(edges), p_self, bias, direction, gap_fraction, gap_means, "grid"
    )


def street(
    seed: int | np.random.Generator,
    n_per_side: int = 250,
    p_self: float = 0.5,
    bias: float = 0.2,
    gap_fraction: float = 0.2,
    gap_means: tuple[float, float] = (7.0, 3.0),
) -> CameraNetwork:
    """Cameras on both sides of a street (seed 001, sec. 7.2.2, fig. 3b). SIMULATED topology.

    Camera ``(side, i)`` leads to ``(side, i +- 1)`` and ``(1 - side, i +- 1)``: 4
    neighbours (2 at the ends), degree 5 with the self loop. The favoured direction is
    increasing ``i``.

    Parameters
    ----------
    seed : int or numpy Generator (which edges get gaps).
    n_per_side : cameras on each side (2 n_per_side in all).
    p_self, bias, gap_fraction, gap_means : as in :func:`manhattan_grid`.

    Returns
    -------
    CameraNetwork with ``2 n_per_side`` cameras; camera ``side * n_per_side + i``.
    """
    rng = make_rng(seed)
    if n_per_side < 2:
        raise ModelError(f"n_per_side must be >= 2, got {n_per_side!r}")
    n = n_per_side
    i = np.arange(n - 1)
    edges = np.concatenate(
        [
            np.stack([i, i + 1], axis=1),  # side 0 along
            np.stack([n + i, n + i + 1], axis=1),  # side 1 along
            np.stack([i, n + i + 1], axis=1),  # across, forward
            np.stack([n + i, i + 1], axis=1),  # across, forward
        ]
    )
    coords = np.concatenate(
        [np.stack([np.arange(n), np.zeros(n)], 1), np.stack([np.arange(n), np.ones(n)], 1)]
    ).astype(np.float64)
    return _network_from_edges(
        rng, coords, edges, p_self, bias, np.array([1.0, 0.0]), gap_fraction, gap_means, "street"
    )


# ---------------------------------------------------------------------------- similarity
def similarity(f1: np.ndarray, f2: np.ndarray, chol: np.ndarray) -> np.ndarray:
    """``P_s(f1, f2) = exp(-d_M^2 / 2)`` with the Mahalanobis distance (seed 001, eqs. 2-3).

    Parameters
    ----------
    f1, f2 : (..., feature_dim) arrays (broadcast).
    chol : (feature_dim, feature_dim) lower Cholesky factor ``L`` of ``Sigma``.

    Returns
    -------
    (...) array in (0, 1]. Uses a triangular solve, never ``Sigma^{-1}``.
    """
    diff = np.asarray(f1, dtype=np.float64) - np.asarray(f2, dtype=np.float64)
    white = whiten(chol, diff)
    return np.exp(-0.5 * np.sum(white * white, axis=-1))


def confusion_measure(sim_to_f0: np.ndarray, is_target: np.ndarray) -> float:
    """Confusion measure CM of seed 001, sec. 6, eq. 10 (with eqs. 8-9).

    ``Omega = {f : s(f, f0) >= a}`` with ``a = min_{f in GT} s(f, f0)`` (eq. 8) and
    ``CM = sum_{Omega \\ GT} s / sum_{Omega} s``: eq. 10 with the histograms ``f_DB`` and
    ``f_GT`` taken exactly (one bin per observation), so its integrals over
    ``J = [a, 1]`` are these sums.

    Parameters
    ----------
    sim_to_f0 : (num_obs,) similarities ``s(f, f0)`` of every observation in [0, 1].
    is_target : (num_obs,) bool, True for the target's observations GT.

    Returns
    -------
    float in [0, 1).
    """
    s = np.asarray(sim_to_f0, dtype=np.float64)
    gt = np.asarray(is_target, dtype=bool)
    if s.shape != gt.shape or s.ndim != 1:
        raise ShapeError(f"sim_to_f0 {s.shape} and is_target {gt.shape} must be equal 1-D shapes")
    if not np.any(gt):
        raise InputError("is_target has no True entry: the target is never observed")
    a = s[gt].min()
    omega = s >= a
    total = s[omega].sum()
    return float(s[omega & ~gt].sum() / total)


# ---------------------------------------------------------------------------- scenes
class ObservationDB(NamedTuple):
    """All observations of a scene (the ODB of sec. 7.1), sorted by time then camera.

    Attributes
    ----------
    time_ptr : (num_timesteps + 1,) int64: observations of step ``t`` are
        ``time_ptr[t]:time_ptr[t+1]``.
    cam : (num_obs,) int64 camera of each observation (sorted within a step).
    feat : (num_obs, feature_dim) float64 feature vectors.
    obj : (num_obs,) int64 ground-truth object id (for scoring only; the filter never
        reads it).
    """

    time_ptr: np.ndarray
    cam: np.ndarray
    feat: np.ndarray
    obj: np.ndarray

    @property
    def num_timesteps(self) -> int:
        return self.time_ptr.size - 1

    def at(self, t: int) -> tuple[np.ndarray, np.ndarray]:
        """``(cam, feat)`` views of the observations at step ``t``."""
        lo, hi = self.time_ptr[t], self.time_ptr[t + 1]
        return self.cam[lo:hi], self.feat[lo:hi]


class Scene(NamedTuple):
    """A simulated scene: network, observations and the target's ground truth.

    Attributes
    ----------
    network : CameraNetwork.
    odb : ObservationDB.
    target : int, the target's object id.
    c0 : int, the target's camera at ``t = 0``; ``f0`` : (feature_dim,) its feature.
    sigma : (feature_dim, feature_dim) typical feature covariance ``Sigma``.
    spread : float, the object-mean spread ``s`` (see the module docstring).
    cm : float, the achieved confusion measure (eq. 10).
    true_cam : (num_timesteps,) int64 target camera (destination while hidden).
    true_ta : (num_timesteps,) int64, 0 when visible, steps to go when hidden.
    true_obs : (num_timesteps,) int64 index into the ODB of the target's observation, -1
        while hidden.
    obj_cam, obj_ta : (num_objects, num_timesteps) int64 paths of all objects.
    """

    network: CameraNetwork
    odb: ObservationDB
    target: int
    c0: int
    f0: np.ndarray
    sigma: np.ndarray
    spread: float
    cm: float
    true_cam: np.ndarray
    true_ta: np.ndarray
    true_obs: np.ndarray
    obj_cam: np.ndarray
    obj_ta: np.ndarray

    @property
    def hidden_fraction(self) -> float:
        """Fraction of steps ``t >= 1`` with the target hidden."""
        return float(np.mean(self.true_ta[1:] > 0))


def _calibrate_spread(
    cm_target: float,
    z_obs: np.ndarray,
    e_obs: np.ndarray,
    z0: np.ndarray,
    is_target: np.ndarray,
    chol: np.ndarray,
) -> tuple[float, float]:
    """Bisection on ``log s`` so that the CM of ``s (z_obs - z0) + e_obs`` hits ``cm_target``."""
    # whitened: f - f0 = s L (z_i - z0) + e ; Mahalanobis uses L^{-1}
    dz = z_obs - z0  # in whitened units already (z ~ N(0, I))
    de = whiten(chol, e_obs)

    def cm_of(s: float) -> float:
        w = s * dz + de
        return confusion_measure(np.exp(-0.5 * np.einsum("ij,ij->i", w, w)), is_target)

    lo, hi = np.log(1e-3), np.log(1e3)
    cm_lo, cm_hi = cm_of(np.exp(lo)), cm_of(np.exp(hi))
    if not cm_hi <= cm_target <= cm_lo:
        raise InputError(
            f"cm={cm_target!r} is out of reach for this scene: CM ranges over [{cm_hi:.4f}, {cm_lo:.4f}]"
        )
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if cm_of(np.exp(mid)) > cm_target:
            lo = mid
        else:
            hi = mid
    # CM(s) is piecewise continuous with jumps where an observation crosses the threshold
    # a of eq. 8; the bisection ends at such a jump, so step 1e-6 (relative) off it to the
    # side closer to the request, where rounding cannot flip an observation
    candidates = [float(np.exp(lo)) * (1 - 1e-6), float(np.exp(hi)) * (1 + 1e-6)]
    s = min(candidates, key=lambda v: abs(cm_of(v) - cm_target))
    return s, cm_of(s)


def simulate_scene(
    seed: int | np.random.Generator,
    network: CameraNetwork,
    num_objects: int = 2000,
    num_timesteps: int = 100,
    cm: float | None = 0.17,
    spread: float | None = None,
    feature_dim: int = 4,
    gamma: float = 0.8,
    sigma: np.ndarray | None = None,
) -> Scene:
    """Simulate moving objects and their observations (seed 001, sec. 7.1.2). SIMULATED data.

    Parameters
    ----------
    seed : int or numpy Generator; the same seed gives the same scene.
    network : the camera network (e.g. :func:`manhattan_grid`).
    num_objects : ``M``, the number of moving objects (the target is one of them).
    num_timesteps : ``T``, steps ``t = 0 .. T - 1``.
    cm : requested confusion measure (eq. 10); the spread is calibrated by bisection
        (module docstring). Give ``cm=None`` and a ``spread`` to fix ``s`` instead.
    spread : the object-mean spread ``s`` (used only when ``cm`` is None).
    feature_dim : ``d``.
    gamma : eq. 11's ``gamma`` in (0, 1).
    sigma : (d, d) SPD ``Sigma``, identity by default.

    Returns
    -------
    Scene.
    """
    rng = make_rng(seed)
    sigma, chol = _check_scene(num_objects, num_timesteps, cm, spread, feature_dim, gamma, sigma)
    M, T, d = int(num_objects), int(num_timesteps), int(feature_dim)
    target = int(rng.integers(M))
    z = rng.standard_normal((M, d))
    obj_cam, obj_ta, time_ptr, o_cam, o_obj, o_e = _walk(rng, network, M, T, d, gamma, chol)
    is_target = o_obj == target
    if cm is not None:
        spread, _ = _calibrate_spread(cm, z[o_obj], o_e, z[target], is_target, chol)
    means = spread * z @ chol.T
    feat = means[o_obj] + o_e
    # report the CM of the features exactly as stored
    achieved = confusion_measure(similarity(feat, means[target], chol), is_target)
    true_obs = np.full(T, -1, dtype=np.int64)
    idx = np.flatnonzero(is_target)
    true_obs[np.searchsorted(time_ptr, idx, side="right") - 1] = idx
    return Scene(
        network=network,
        odb=ObservationDB(time_ptr, o_cam, feat, o_obj),
        target=target,
        c0=int(obj_cam[target, 0]),
        f0=means[target].copy(),
        sigma=sigma,
        spread=float(spread),
        cm=float(achieved),
        true_cam=obj_cam[target].copy(),
        true_ta=obj_ta[target].copy(),
        true_obs=true_obs,
        obj_cam=obj_cam,
        obj_ta=obj_ta,
    )


def _check_scene(
    num_objects: int,
    num_timesteps: int,
    cm: float | None,
    spread: float | None,
    feature_dim: int,
    gamma: float,
    sigma: np.ndarray | None,
) -> tuple[np.ndarray, np.ndarray]:
    """Validate :func:`simulate_scene`'s arguments; returns ``sigma`` as a (d, d) float64
    array (identity by default) and its lower Cholesky factor."""
    for name, value in (("num_objects", num_objects), ("num_timesteps", num_timesteps),
                        ("feature_dim", feature_dim)):  # fmt: skip
        check_count(name, value)  # NaN: numpy's "cannot convert float NaN"; 2.5 ran
    if num_timesteps < 2:
        raise InputError(f"need num_timesteps >= 2, got {num_timesteps}")
    if not 0.0 < gamma < 1.0:
        raise InputError(f"gamma must lie in (0, 1), got {gamma!r}")
    if (cm is None) == (spread is None):
        raise InputError(f"give exactly one of cm and spread, got cm={cm!r}, spread={spread!r}")
    if cm is not None and not 0.0 < cm < 1.0:
        raise InputError(f"cm must lie in (0, 1), got {cm!r}")
    if spread is not None and not spread > 0:
        raise InputError(f"spread must be > 0, got {spread!r}")
    return sigma_cholesky(np.eye(feature_dim) if sigma is None else sigma, feature_dim)


def _walk(
    rng: np.random.Generator,
    network: CameraNetwork,
    M: int,
    T: int,
    d: int,
    gamma: float,
    chol: np.ndarray,
) -> tuple[np.ndarray, ...]:
    """``M`` objects walk ``T`` steps from uniform cameras (:func:`propagate`) with
    eq. 11's appearance noise ``e``; the visible ones are observed, sorted by camera.

    Returns ``obj_cam``, ``obj_ta`` (M, T), ``time_ptr`` (T + 1,), and per observation its
    camera, object and noise ``e`` (num_obs,), (num_obs,), (num_obs, d).
    """
    cam = rng.integers(0, network.num_cameras, size=M)
    ta = np.zeros(M, dtype=np.int64)
    e = np.zeros((M, d))
    obj_cam = np.empty((M, T), dtype=np.int64)
    obj_ta = np.empty((M, T), dtype=np.int64)
    chunks_cam, chunks_obj, chunks_e, counts = [], [], [], []
    for t in range(T):
        if t > 0:
            cam, ta, _ = propagate(rng, network, cam, ta)
            e = (1.0 - gamma) * (e + rng.standard_normal((M, d)) @ chol.T)
        obj_cam[:, t], obj_ta[:, t] = cam, ta
        vis = np.flatnonzero(ta == 0)
        order = vis[np.argsort(cam[vis], kind="stable")]
        chunks_cam.append(cam[order])
        chunks_obj.append(order)
        chunks_e.append(e[order])
        counts.append(order.size)
    time_ptr = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    o_cam, o_obj, o_e = (np.concatenate(c) for c in (chunks_cam, chunks_obj, chunks_e))
    return obj_cam, obj_ta, time_ptr, o_cam, o_obj, o_e
