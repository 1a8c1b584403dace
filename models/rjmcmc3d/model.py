"""The declared model of seed 003: parameters, dynamics, priors and the ground-plane
uncertainty map ``C(u)`` of eq. 7.

State of one person (seed 003, eq. 3): ``X_i = (x, y, vx, vy, h, alpha)``; the joint
state (eq. 4) adds existence flags ``k_i``. The dynamics (eqs. 5-7) are Langevin motion
on the ground plane with the location-dependent noise ``C(u) w`` (2-D-to-3-D foot
localisation uncertainty, propagated from each view by an unscented transform and fused
over the views that see ``u``), a height prior pulled to a steady state, and an
orientation prior mixing smoothness and alignment with the walking direction.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from dbn.checks import MAX_SCALE, check_number_fields
from dbn.errors import InputError, ModelError
from models.rjmcmc3d.geometry import ground_homography
from models.rjmcmc3d.projection import visible_views
from models.rjmcmc3d.types import Scene

__all__ = [
    "GroundNoiseMap",
    "MAX_NOISE_CELLS",
    "TrackerParams",
    "gauss2_logpdf",
    "ground_noise_map",
    "interaction_penalty",
    "predict",
]

LOG_2PI = math.log(2.0 * math.pi)




class TrackerParams(NamedTuple):
    """Parameters of the seed 003 tracker (all documented with the equation they enter).

    Dynamics (eq. 7): ``tau`` frame interval (s), ``beta`` speed damping (1/s),
    ``vbar`` steady-state rms speed (m/s). Height: steady state ``h_mean``, birth sd
    ``h_sd0``, pull ``h_rho``, step sd ``h_sd``. Orientation: von Mises concentration
    ``alpha_kappa``. Interaction prior (sec. 3.2): ``lambda_g``, person ellipse
    ``shape_sd`` (sd along facing, across). Existence (eq. 5): ``log_p_birth`` per new
    person, ``p_leave_inside`` per person and frame, ``leave_ramp`` (m) over which the
    leave probability rises to one outside the floor. Foreground likelihood (eq. 9):
    ``c1 = lambda_fg + lambda_bar_fg``, ``c2 = lambda_fg / c1``. Colour likelihood
    (eq. 10): ``lambda_im``, ``lambda_f``, ``d_min``, ``num_refs`` (K),
    ``ref_rate`` and ``ref_match`` (reference update). Ground-plane noise:
    ``ground_noise`` (False: ``C(u) = 0``, the ablation of seed fig. 6),
    ``unseen_sd`` (m) where no camera sees the floor, ``fixed_sd`` (m) the update
    kernel without the map, ``min_sd`` (m) floor of the update kernel. RJ-MCMC
    (sec. 3.4): ``move_probs`` (add, delete, stay, leave, switch, update),
    ``num_moves``, ``burn_in``, ``max_objects`` (M), ``add_gate`` and ``det_gate``
    (Mahalanobis gates), ``p_det_update`` (weight of the detection-driven update),
    ``switch_dist`` (m).
    """

    tau: float = 0.2
    beta: float = 0.5
    vbar: float = 1.0
    h_mean: float = 1.72
    h_sd0: float = 0.08
    h_rho: float = 0.9
    h_sd: float = 0.02
    alpha_kappa: float = 2.0
    lambda_g: float = 2.0
    shape_sd: tuple[float, float] = (0.2, 0.3)
    log_p_birth: float = math.log(0.1)
    p_leave_inside: float = 0.01
    leave_ramp: float = 0.4
    c1: float = 0.4
    c2: float = 0.45
    lambda_im: float = 0.1
    lambda_f: float = 0.5
    d_min: float = 0.3
    num_refs: int = 3
    ref_rate: float = 0.1
    ref_match: float = 0.3
    colour_levels: int = 4
    ground_noise: bool = True
    unseen_sd: float = 1.0
    fixed_sd: float = 0.1
    min_sd: float = 0.04
    move_probs: tuple[float, ...] = (0.1, 0.08, 0.08, 0.08, 0.04, 0.62)
    num_moves: int = 1500
    burn_in: int = 500
    max_objects: int = 24
    add_gate: float = 3.0
    det_gate: float = 3.0
    p_det_update: float = 0.5
    switch_dist: float = 1.0

    def validate(self) -> TrackerParams:
        """Raise :class:`~dbn.errors.InputError` naming a bad field; return ``self``."""
        check_number_fields(self, InputError)
        for name in ("num_moves", "max_objects", "num_refs", "colour_levels", "burn_in"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int | np.integer):
                raise InputError(f"TrackerParams.{name}={v!r} must be an int")
        for name, v in self._asdict().items():  # lengths, times, weights: squared somewhere
            if isinstance(v, float | np.floating) and not abs(v) < MAX_SCALE:
                raise InputError(
                    f"TrackerParams.{name}={v!r} must be finite, |x| < {MAX_SCALE:g}"
                )
        for name in ("h_mean", "d_min", "leave_ramp", "add_gate", "det_gate"):
            if not getattr(self, name) > 0:
                raise InputError(f"TrackerParams.{name}={getattr(self, name)} must be > 0")
        for name in ("alpha_kappa", "lambda_g", "lambda_im", "lambda_f", "switch_dist", "min_sd"):
            if not getattr(self, name) >= 0:  # 0 switches a term off (ablations)
                raise InputError(f"TrackerParams.{name}={getattr(self, name)} must be >= 0")
        for name in ("h_rho", "p_leave_inside", "ref_rate", "ref_match", "p_det_update"):
            if not 0 <= getattr(self, name) <= 1:
                raise InputError(f"TrackerParams.{name}={getattr(self, name)} must be in [0, 1]")
        if not (self.log_p_birth <= 0):
            raise InputError(f"TrackerParams.log_p_birth={self.log_p_birth} must be <= 0")
        sd = np.asarray(self.shape_sd, dtype=float)
        if sd.shape != (2,) or not np.all(sd > 0):
            raise InputError(f"TrackerParams.shape_sd={self.shape_sd} must be 2 values > 0")
        for name in ("tau", "beta", "vbar", "h_sd0", "h_sd", "c1", "unseen_sd", "fixed_sd"):
            if not getattr(self, name) > 0:
                raise InputError(f"TrackerParams.{name}={getattr(self, name)} must be > 0")
        if not 0 < self.c2 < 1:
            raise InputError(f"TrackerParams.c2={self.c2} must be in (0, 1)")
        probs = np.asarray(self.move_probs, dtype=float)
        if probs.shape != (6,) or np.any(probs < 0) or abs(probs.sum() - 1) > 1e-9:
            raise InputError(f"TrackerParams.move_probs={self.move_probs} must be 6 probabilities")
        if not 0 <= self.burn_in < self.num_moves:
            raise InputError(
                f"TrackerParams.burn_in={self.burn_in} must be in [0, num_moves={self.num_moves})"
            )
        if self.max_objects < 1 or self.num_refs < 1 or self.colour_levels < 1:
            raise InputError("TrackerParams.max_objects, num_refs and colour_levels must be >= 1")
        return self

    @property
    def a(self) -> float:
        """Velocity decay ``a = exp(-beta tau)`` of eq. 7."""
        return math.exp(-self.beta * self.tau)

    @property
    def b(self) -> float:
        """Velocity noise ``b = vbar sqrt(1 - a^2)`` of eq. 7."""
        return self.vbar * math.sqrt(1.0 - self.a**2)


class GroundNoiseMap(NamedTuple):
    """The precomputed 2-D-to-3-D localisation uncertainty of seed 003, eq. 7 and fig. 2.

    Attributes
    ----------
    origin : ndarray, shape (2,)
        Ground coordinates of cell (0, 0)'s centre.
    step : float
        Cell size (m).
    cov : ndarray, shape (nx, ny, 2, 2)
        Fused covariance ``C(u) C(u)^T`` (unseen cells: ``unseen_sd^2 I``).
    chol : ndarray, shape (nx, ny, 2, 2)
        Its Cholesky factor ``C(u)``.
    view_cov : ndarray, shape (num_views, nx, ny, 2, 2)
        Single-view covariances (for detection-driven proposals).
    view_seen : ndarray, shape (num_views, nx, ny), bool
    num_seen : ndarray, shape (nx, ny), int
    """

    origin: np.ndarray
    step: float
    cov: np.ndarray
    chol: np.ndarray
    view_cov: np.ndarray
    view_seen: np.ndarray
    num_seen: np.ndarray

    def index(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Cell indices of ground points ``u`` (..., 2), clipped to the map."""
        ij = np.rint((np.asarray(u) - self.origin) / self.step).astype(np.int64)
        return (
            np.clip(ij[..., 0], 0, self.cov.shape[0] - 1),
            np.clip(ij[..., 1], 0, self.cov.shape[1] - 1),
        )


def _chol2(S: np.ndarray) -> np.ndarray:
    """Cholesky factors of 2x2 SPD matrices (..., 2, 2), closed form."""
    L = np.zeros_like(S)
    l11 = np.sqrt(S[..., 0, 0])
    L[..., 0, 0] = l11
    L[..., 1, 0] = S[..., 1, 0] / l11
    L[..., 1, 1] = np.sqrt(np.maximum(S[..., 1, 1] - L[..., 1, 0] ** 2, 1e-12))
    return L


def gauss2_logpdf(x: np.ndarray, mean: np.ndarray, L: np.ndarray) -> np.ndarray:
    """``log N(x; mean, L L^T)`` for 2-D points by a Cholesky (triangular) solve.

    Parameters
    ----------
    x, mean : ndarray, shape (..., 2)
    L : ndarray, shape (..., 2, 2)
        Lower Cholesky factors.

    Returns
    -------
    ndarray, shape (...)
    """
    d = np.asarray(x) - np.asarray(mean)
    z1 = d[..., 0] / L[..., 0, 0]
    z2 = (d[..., 1] - L[..., 1, 0] * z1) / L[..., 1, 1]
    return -0.5 * (z1 * z1 + z2 * z2) - np.log(L[..., 0, 0] * L[..., 1, 1]) - LOG_2PI


MAX_NOISE_CELLS = 2**22
"""Most cells of the ground noise map (:func:`ground_noise_map`; 4.2e6 cells of 0.1 m,
134 MB of 2 x 2 covariances)."""


def ground_noise_map(
    scene: Scene, params: TrackerParams, step: float = 0.1, margin: float = 1.0
) -> GroundNoiseMap:
    """Precompute ``C(u)`` of seed 003, eq. 7 over the floor (fig. 2, right).

    For each view that sees a person standing at ``u`` whole, the foot's image position
    ``x = H_v u`` gets Gaussian noise ``N(0, sigma_px^2 I)``; its unscented transform
    (2-D, ``kappa = 1``: sigma points ``x``, ``x +- sqrt(3) sigma_px e_k``) through the
    image-to-ground homography ``H_v^{-1}`` gives the single-view covariance
    ``Sigma_v(u)``. Views are fused by adding informations,
    ``Sigma(u) = (sum_v Sigma_v(u)^{-1})^{-1}``; ``C(u)`` is its Cholesky factor.

    Parameters
    ----------
    scene : Scene
    params : TrackerParams
        ``unseen_sd`` is used where no view sees ``u``.
    step : float
        Cell size (m).
    margin : float
        Extension of the map beyond the floor (m).

    Returns
    -------
    GroundNoiseMap
    """
    lo = scene.floor[[0, 2]] - margin
    hi = scene.floor[[1, 3]] + margin
    nx, ny = (float(v) for v in np.floor((hi - lo) / step) + 1)
    cells = nx * ny  # a Python float: inf past 1e308, without numpy's overflow warning
    if not cells <= MAX_NOISE_CELLS:  # a floor of 1e200 m: numpy's "Maximum allowed size"
        raise ModelError(
            f"floor {scene.floor.tolist()} (m) with a {margin:g} m margin makes a ground "
            f"noise map of {cells:.3g} cells of {step:g} m, more than {MAX_NOISE_CELLS:,} "
            "(about 200 m x 200 m): give the floor the cameras see, in metres"
        )
    xs = np.arange(lo[0], hi[0] + step / 2, step)
    ys = np.arange(lo[1], hi[1] + step / 2, step)
    gx, gy = np.meshgrid(xs, ys, indexing="ij")
    u = np.stack([gx, gy], axis=-1)  # (nx, ny, 2)
    flat = u.reshape(-1, 2)
    seen = visible_views(scene, flat).reshape(scene.num_views, *gx.shape)
    k = math.sqrt(3.0)
    offsets = np.array([[0.0, 0.0], [k, 0.0], [-k, 0.0], [0.0, k], [0.0, -k]])
    weights = np.array([1.0 / 3.0, 1 / 6, 1 / 6, 1 / 6, 1 / 6])
    info = np.zeros((*gx.shape, 2, 2))
    view_cov = np.zeros((scene.num_views, *gx.shape, 2, 2))
    for v in range(scene.num_views):
        Hg = ground_homography(scene.P[v])
        hom = np.concatenate([flat, np.ones((flat.shape[0], 1))], axis=1) @ Hg.T
        px = hom[:, :2] / hom[:, 2:3]
        sig = px[:, None, :] + scene.sigma_px[v] * offsets[None, :, :]  # (n, 5, 2)
        back = np.linalg.solve(
            Hg, np.concatenate([sig, np.ones((*sig.shape[:2], 1))], -1).reshape(-1, 3).T
        ).T.reshape(*sig.shape[:2], 3)
        g = back[..., :2] / back[..., 2:3]
        mean = (weights[None, :, None] * g).sum(1)
        d = g - mean[:, None, :]
        cov = np.einsum("k,nki,nkj->nij", weights, d, d).reshape(*gx.shape, 2, 2)
        cov = cov + 1e-8 * np.eye(2)
        view_cov[v] = np.where(seen[v][..., None, None], cov, params.unseen_sd**2 * np.eye(2))
        inv = np.linalg.solve(cov, np.broadcast_to(np.eye(2), cov.shape))
        info += np.where(seen[v][..., None, None], inv, 0.0)
    num_seen = seen.sum(0)
    fused = np.where(
        (num_seen > 0)[..., None, None],
        np.linalg.solve(
            info + (num_seen == 0)[..., None, None] * np.eye(2),
            np.broadcast_to(np.eye(2), info.shape),
        ),
        params.unseen_sd**2 * np.eye(2),
    )
    fused = 0.5 * (fused + np.swapaxes(fused, -1, -2))
    return GroundNoiseMap(lo.copy(), float(step), fused, _chol2(fused), view_cov, seen, num_seen)


def predict(
    params: TrackerParams,
    noise: GroundNoiseMap,
    mean: np.ndarray,
    cov: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Gaussian prediction of ``(u, u_dot)`` under the Langevin dynamics of seed 003, eq. 7.

    ``u_dot_t = a u_dot_{t-1} + b w_1``, ``u_t = u_{t-1} + tau u_dot_t + C(u_{t-1}) w_2``
    with ``C`` evaluated at the mean (``C = 0`` when ``params.ground_noise`` is False).

    Parameters
    ----------
    mean : ndarray, shape (num, 4)
        ``(x, y, vx, vy)`` posterior means.
    cov : ndarray, shape (num, 4, 4)

    Returns
    -------
    mean, cov : ndarray, shapes (num, 4) and (num, 4, 4)
    """
    a, b, tau = params.a, params.b, params.tau
    F = np.eye(4)
    F[0, 2] = F[1, 3] = tau * a
    F[2, 2] = F[3, 3] = a
    Q = np.zeros((4, 4))
    Q[0, 0] = Q[1, 1] = (tau * b) ** 2
    Q[0, 2] = Q[2, 0] = Q[1, 3] = Q[3, 1] = tau * b * b
    Q[2, 2] = Q[3, 3] = b * b
    m = mean @ F.T
    P = F @ cov @ F.T + Q
    if params.ground_noise and mean.shape[0]:
        i, j = noise.index(mean[:, :2])
        P[:, :2, :2] += noise.cov[i, j]
    return m, 0.5 * (P + np.swapaxes(P, -1, -2))


def interaction_penalty(
    params: TrackerParams,
    u_i: np.ndarray,
    alpha_i: np.ndarray,
    upr_i: np.ndarray,
    u_j: np.ndarray,
    alpha_j: np.ndarray,
    upr_j: np.ndarray,
) -> np.ndarray:
    """Pair penalty ``g(X_i, X_j)`` of seed 003, sec. 3.2 (broadcast over pairs).

    ``g = g_p(X_i, X_j) + g_p(X_i^pr, X_j^pr)`` with
    ``g_p = psi(d_{m,i}) + psi(d_{m,j})``, ``d_{m,i}`` the Mahalanobis distance of
    ``u_i - u_j`` under person ``i``'s oriented ellipse (sd ``shape_sd`` along and
    across its facing direction) and ``psi(d) = exp(-d^2 / 2)``. ``upr`` are predicted
    positions ``u + tau a u_dot``.
    """
    s_along, s_across = params.shape_sd

    def psi(d: np.ndarray, alpha: np.ndarray) -> np.ndarray:
        c, s = np.cos(alpha), np.sin(alpha)
        along = d[..., 0] * c + d[..., 1] * s
        across = -d[..., 0] * s + d[..., 1] * c
        return np.exp(-0.5 * ((along / s_along) ** 2 + (across / s_across) ** 2))

    d_now = u_i - u_j
    d_pr = upr_i - upr_j
    return psi(d_now, alpha_i) + psi(d_now, alpha_j) + psi(d_pr, alpha_i) + psi(d_pr, alpha_j)
