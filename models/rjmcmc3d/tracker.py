"""The seed 003 tracker: RJ-MCMC filtering of a varying number of people in 3-D.

Per frame (seed 003, eq. 2) a Markov chain over joint configurations ``(X, k)`` targets

.. math::

    \\pi(\\tilde X_t) \\propto p(Z_t | \\tilde X_t)\\; p_0(X_t | k_t)
      \\prod_i p(X_{i,t} | \\cdot)\\; p(k_t | k_{t-1}, X_{t-1})

with the likelihood of eqs. 8-10 (:mod:`models.rjmcmc3d.likelihood`), the interaction
prior ``p_0`` of sec. 3.2, and each person's previous-frame posterior summarised by a
Gaussian over ``(u, u_dot)`` predicted through eq. 7 (a moment-matched form of the sum
over chain samples in eq. 2). The six moves of sec. 3.4 (add/delete driven by the
detector, stay/leave for people of the previous frame, switch, update as a mixture of a
``Sigma(u) = C(u) C(u)^T`` random walk and a detection-driven jump) are accepted with
eq. 11 through :mod:`inference.mcmc`. The likelihood is incremental: a move recomputes
only the pixels of the people it changes (``likelihood="full"`` recomputes everything
per move, for the baseline; both give the same chain for the same seed). One frame's chain,
its target and its moves are in :mod:`models.rjmcmc3d.chain`; this module holds the
tracker: the state carried between frames and the posterior summary of each frame's samples.

The API is the trio ``init_state`` / ``step(seed, state, frame)`` / ``run``; ``step``
never mutates the state it is given.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from typing import NamedTuple

import numpy as np

from dbn.checks import check_type, make_rng
from dbn.errors import InputError
from inference.progress import progress_bar
from models.protocol import next_frame_index
from models.rjmcmc3d.chain import MOVE_NAMES, MOVES, FrameChain
from models.rjmcmc3d.frames import check_frame
from models.rjmcmc3d.likelihood import histograms_of
from models.rjmcmc3d.model import GroundNoiseMap, TrackerParams, ground_noise_map
from models.rjmcmc3d.projection import BoxProjector
from models.rjmcmc3d.types import Frame, Scene

__all__ = ["FrameChain", "FrameResult", "MOVES", "MOVE_NAMES", "RJMCMCTracker", "TrackState"]


class TrackState(NamedTuple):
    """Posterior summary carried between frames (one row per slot, M slots).

    Attributes
    ----------
    alive : ndarray, shape (M,), bool
        ``k_{i,t-1}``.
    label : ndarray, shape (M,), int
        Track identity of each slot (-1 when free).
    mean : ndarray, shape (M, 4)
        Posterior mean of ``(x, y, vx, vy)``.
    cov : ndarray, shape (M, 4, 4)
    h, alpha : ndarray, shape (M,)
        Height and orientation estimates.
    refs : ndarray, shape (M, 3, K, num_bins)
        Normalised reference colour histograms per body region.
    nref : ndarray, shape (M, 3), int
        Number of valid references.
    ref_weight : ndarray, shape (M, 3, K)
        Usage weights of the references.
    next_label : int
    frame : int
        Index of the last frame filtered (-1: none yet).
    """

    alive: np.ndarray
    label: np.ndarray
    mean: np.ndarray
    cov: np.ndarray
    h: np.ndarray
    alpha: np.ndarray
    refs: np.ndarray
    nref: np.ndarray
    ref_weight: np.ndarray
    next_label: int
    frame: int = -1


class FrameResult(NamedTuple):
    """Estimate of one frame.

    Attributes
    ----------
    ids : ndarray, shape (n,)
        Track labels.
    X : ndarray, shape (n, 6)
        ``(x, y, vx, vy, h, alpha)`` per track (seed 003, eq. 3).
    presence : ndarray, shape (n,)
        Posterior existence probability.
    accept_rate : ndarray, shape (6,)
        Acceptance rate of each move type (NaN if never tried).
    log_target : float
        Log target of the chain's last state (up to a constant).
    """

    ids: np.ndarray
    X: np.ndarray
    presence: np.ndarray
    accept_rate: np.ndarray
    log_target: float


class RJMCMCTracker:
    """Multi-camera multi-person 3-D tracker with RJ-MCMC (seed 003).

    Parameters
    ----------
    scene : Scene
        Calibrated cameras and floor.
    params : TrackerParams, optional
    noise : GroundNoiseMap, optional
        Precomputed ``C(u)`` (built from the scene if omitted).
    likelihood : {"incremental", "full"}
        ``"full"`` recomputes eqs. 8-10 from scratch at every move (baseline).

    Examples
    --------
    >>> tracker = RJMCMCTracker(scene)                                   # doctest: +SKIP
    >>> state = tracker.init_state()                                     # doctest: +SKIP
    >>> state, result = tracker.step(0, state, frame)                    # doctest: +SKIP
    """

    def __init__(
        self,
        scene: Scene,
        params: TrackerParams | None = None,
        noise: GroundNoiseMap | None = None,
        likelihood: str = "incremental",
    ) -> None:
        self.params = (TrackerParams() if params is None
                       else check_type("params", params, TrackerParams, InputError)).validate()
        if likelihood not in ("incremental", "full"):
            raise InputError(f"likelihood={likelihood!r} must be 'incremental' or 'full'")
        self.scene = check_type("scene", scene, Scene, InputError)
        self.noise = noise if noise is not None else ground_noise_map(scene, self.params)
        self.likelihood = likelihood
        self.num_bins = self.params.colour_levels**3
        self.projector = BoxProjector(scene)
        p = self.params
        if p.ground_noise:
            upd = self.noise.cov + p.min_sd**2 * np.eye(2)
        else:
            upd = np.broadcast_to(p.fixed_sd**2 * np.eye(2), self.noise.cov.shape)
        L = np.linalg.cholesky(upd)
        self._upd_a = np.ascontiguousarray(np.stack([L[..., 0, 0], L[..., 1, 0], L[..., 1, 1]], -1))
        self._upd = self._upd_a.tolist()
        self._origin_a = np.asarray(self.noise.origin, dtype=np.float64)
        self._origin = self.noise.origin.tolist()
        self._step = self.noise.step
        self._shape = self.noise.cov.shape[:2]

    def update_chol(self, x: float, y: float) -> tuple:
        """Cholesky factor ``(l00, l10, l11)`` of the update kernel ``Sigma(u)`` at ``(x, y)``.

        ``Sigma(u) = C(u) C(u)^T + min_sd^2 I`` (seed 003, sec. 3.4, update move), or
        ``fixed_sd^2 I`` without the ground-plane noise map.
        """
        i = min(max(int(round((x - self._origin[0]) / self._step)), 0), self._shape[0] - 1)
        j = min(max(int(round((y - self._origin[1]) / self._step)), 0), self._shape[1] - 1)
        return self._upd[i][j]

    def init_state(self) -> TrackState:
        """No one tracked yet."""
        M, K, nb = self.params.max_objects, self.params.num_refs, self.num_bins
        return TrackState(
            np.zeros(M, dtype=bool),
            np.full(M, -1, dtype=np.int64),
            np.zeros((M, 4)),
            np.tile(np.eye(4), (M, 1, 1)),
            np.full(M, self.params.h_mean),
            np.zeros(M),
            np.zeros((M, 3, K, nb)),
            np.zeros((M, 3), dtype=np.int64),
            np.zeros((M, 3, K)),
            0,
        )

    def frame_chain(
        self, state: TrackState, frame: Frame, likelihood: str | None = None
    ) -> FrameChain:
        """The chain of one frame before sampling (for benchmarks and diagnostics).

        Parameters
        ----------
        state : TrackState
            Previous posterior summary (not mutated).
        frame : Frame
        likelihood : {"incremental", "full"}, optional
            Default: the tracker's.
        """
        self._check_frame(frame)
        mode = self.likelihood if likelihood is None else likelihood
        if mode not in ("incremental", "full"):
            raise InputError(f"likelihood={mode!r} must be 'incremental' or 'full'")
        return FrameChain(self, state, frame, mode)

    def _check_frame(self, frame: Frame) -> None:
        check_frame(self.scene, frame)

    def step(self, seed: int, state: TrackState, frame: Frame) -> tuple[TrackState, FrameResult]:
        """Filter one frame: run the RJ-MCMC chain (seed 003, eqs. 2 and 11).

        Parameters
        ----------
        seed : int
            Seed of this frame's chain (explicit; same seed, same result).
        state : TrackState
            Previous posterior summary (not mutated).
        frame : Frame
            Observations (``D``, colour images, detections).

        Returns
        -------
        state : TrackState
        result : FrameResult
        """
        self._check_frame(frame)
        index = next_frame_index(int(state.frame), frame.t, "frame.t")
        rng = make_rng(seed)
        chain = FrameChain(self, state, frame, self.likelihood)
        out = chain.run(rng)
        new_state, result = self._posterior(state, chain, out)
        return new_state._replace(frame=index), result

    def _posterior(
        self, state: TrackState, chain: FrameChain, out: dict
    ) -> tuple[TrackState, FrameResult]:
        p = self.params
        exist = out["presence"] > 0.5
        cnt = np.maximum(out["cnt"], 1.0)
        mu = out["su"] / cnt[:, None]
        S = out["suu"] / cnt[:, None, None] - mu[:, :, None] * mu[:, None, :]
        S = 0.5 * (S + np.swapaxes(S, -1, -2)) + 0.02**2 * np.eye(2)
        h = out["sh"] / cnt
        alpha = np.arctan2(out["sc"][:, 1], out["sc"][:, 0])
        mean = np.zeros((p.max_objects, 4))
        cov = np.tile(np.eye(4), (p.max_objects, 1, 1))
        mean[:, :2] = mu
        cov[:, :2, :2] = S
        cont = exist & chain.prev
        G = chain.Gain
        mean[cont, 2:] = chain.m[cont, 2:] + np.einsum(
            "mij,mj->mi", G[cont], mu[cont] - chain.m[cont, :2]
        )
        P = chain.P[cont]
        GS = np.einsum("mij,mjk->mik", G[cont], S[cont])
        cov[cont, 2:, 2:] = (
            P[:, 2:, 2:]
            - np.einsum("mij,mkj->mik", G[cont], P[:, 2:, :2])
            + np.einsum("mij,mkj->mik", GS, G[cont])
        )
        cov[cont, 2:, :2] = GS
        cov[cont, :2, 2:] = np.swapaxes(GS, -1, -2)
        born = exist & ~chain.prev
        cov[born, 2:, 2:] = p.vbar**2 * np.eye(2)
        cov = 0.5 * (cov + np.swapaxes(cov, -1, -2))
        label = np.where(exist, state.label, -1)
        next_label = state.next_label
        for i in np.flatnonzero(born):
            label[i] = next_label
            next_label += 1
        refs, nref, rw = self._update_refs(chain, state, exist, mu, h, alpha)
        new_state = TrackState(
            exist, label, mean, cov, h, alpha, refs, nref, rw, next_label, state.frame
        )
        idx = np.flatnonzero(exist)
        X = np.concatenate([mean[idx], h[idx, None], alpha[idx, None]], axis=1)
        result = FrameResult(
            label[idx],
            X,
            out["presence"][idx],
            out["accept_rate"],
            chain.loglik + float(sum(chain.lp)),
        )
        return new_state, result

    def _update_refs(self, chain: FrameChain, state: TrackState, exist, mu, h, alpha):
        """Reference histogram update from the mean state (seed 003, sec. 3.3)."""
        p = self.params
        refs = np.where(exist[:, None, None, None], state.refs, 0.0)
        nref = np.where(exist[:, None], state.nref, 0)
        rw = np.where(exist[:, None, None], state.ref_weight, 0.0)
        if not exist.any():
            return refs, nref, rw
        S = np.stack([mu[:, 0], mu[:, 1], h, alpha], axis=1)
        cfg = chain._config(S, exist)
        hist = histograms_of(chain.data, cfg).sum(-2).astype(np.float64)  # (V, M, 3, nb)
        rw *= 0.95
        for v in range(hist.shape[0]):
            for i in np.flatnonzero(exist):
                for b in range(3):
                    n = hist[v, i, b].sum()
                    if n < 20:
                        continue
                    obs = hist[v, i, b] / n
                    k = nref[i, b]
                    if k:
                        bc = np.sqrt(refs[i, b, :k]) @ np.sqrt(obs)
                        best = int(np.argmax(bc))
                        if math.sqrt(max(0.0, 1 - bc[best])) < p.ref_match:
                            refs[i, b, best] = (1 - p.ref_rate) * refs[
                                i, b, best
                            ] + p.ref_rate * obs
                            rw[i, b, best] += 1.0
                            continue
                    if k < p.num_refs:
                        refs[i, b, k] = obs
                        rw[i, b, k] = 1.0
                        nref[i, b] = k + 1
                    else:
                        worst = int(np.argmin(rw[i, b]))
                        refs[i, b, worst] = obs
                        rw[i, b, worst] = 1.0
        return refs, nref, rw

    def run(
        self,
        seed: int,
        frames: Iterable[Frame],
        num_frames: int | None = None,
        progress: bool = False,
    ) -> list[FrameResult]:
        """Track a sequence; frame ``t`` uses the seed ``[seed, t]``.

        Parameters
        ----------
        seed : int
        frames : iterable of Frame
        num_frames : int, optional
            Length (for the progress bar).
        progress : bool
            Show a tqdm bar.
        """
        state = self.init_state()
        results = []
        it = progress_bar(frames, total=num_frames, disable=not progress, desc="rjmcmc3d")
        for t, frame in enumerate(it):
            state, res = self.step(
                int(np.random.SeedSequence([seed, t]).generate_state(1)[0]), state, frame
            )
            results.append(res)
        return results
