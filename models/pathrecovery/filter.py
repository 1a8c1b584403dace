"""First phase of seed 001 (sec. 4.1): the modified particle filter over visible and hidden
states, producing at every step the k best distinct states.

A particle is a location - a visible camera, or a hidden state ``(destination, ta)``
(eq. 4) - with a feature vector. One :func:`step` does, vectorised over particles:

1. prediction (sec. 4.1.1): a visible particle walks one step on ``G_mc`` and draws a
   travel time; a hidden one counts down (:func:`models.pathrecovery.model.propagate`);
2. evaluation (sec. 4.1.3): among the ``N_fc`` cameras holding most visible particles,
   the support of every observation in a particle's camera, eqs. 5-6,
   ``P = beta (alpha W^p(C_{x_{t-1}}, C_{x_t}) + (1 - alpha) P_s(f_x, f_z))
   + (1 - beta) P_s(f_0, f_z)``, and the weight ``w = max_z P`` (eq. 7) with its
   associated observation ``z*``; with probability ``P_update`` the particle's feature
   becomes ``f_{z*}``;
3. normalisation over visible and hidden particles (sec. 4.1.4), the k best distinct
   states (sec. 4.1.5): a visible particle stands for its associated observation;
4. resampling (sec. 4.1.6), diffusion of the locations of visible particles by
   ``G_mcd`` (self loops twice as likely) and feature switching with probability
   ``P_switch`` to an observation of the camera drawn proportionally to
   ``P_s(f_0, f_z)``.

Only the rows of the cameras that hold particles are read (CSR look-ups, ``searchsorted``
into the step's observations sorted by camera), so a step costs the same on 500 or 5,000
cameras.

Two weightings (``FilterConfig.faithful``)
    ``faithful=True`` - the paper as written: a hidden particle keeps the weight it had
    when it entered the gap (sec. 4.1.4: "the initial weight of a hidden particle is
    taken to be its weight when it entered the hidden state"), all weights are
    normalised together, a state's rank is the largest weight of its particles, hidden
    states are distinct by ``(destination, ta)``, multinomial resampling.

    ``faithful=False`` (default) - a sampling-importance-resampling reading: after
    resampling every particle carries the same predicted mass ``1/N``; a visible particle
    is weighted by its support (eq. 7) and a hidden particle by a constant
    ``hidden_likelihood`` ``q`` (the support of "not seen here": the observations at the
    cameras are all someone else's) instead of its stale weight; both are raised to a
    power ``kappa`` (``sharpness``), i.e. ``w = P^kappa`` and ``q^kappa``. A state's mass
    is the SUM of its particles' weights, hidden states are merged by destination (ranked
    by the total mass of the hidden particles heading there), systematic resampling.

    Why. With stale weights, hidden states keep the support they had when they left and
    crowd the k-best lists while the target is in plain view. The support of eqs. 5-6 is
    an additive mixture: any observation in a particle's camera gives at least
    ``alpha beta W^p`` and a particle whose feature was switched to a passer-by's gets
    ``~0.4`` from that passer-by at every step, against ``~0.75`` for the target: a
    likelihood ratio of 2 is too flat to hold 250 particles on the target, and ``q`` is
    meaningless unless it sits between the two. ``kappa = 6`` turns 0.75 : 0.4 : 0.5 (the
    hidden level) into 0.18 : 0.004 : 0.016. The values ``kappa = 6``, ``q = 0.5`` were
    chosen by measurement on seeds 100-105 (not the benchmark's), over ``kappa`` in
    {1, 3, 4, 5, 6, 8} and ``q`` in {0.1, ..., 0.6}, on the grid at CM 0.17, 0.3, 0.63
    and the street at CM 0.63: mean second-phase score 0.99 (``kappa = 1`` with the best
    ``q = 0.3``: 0.80; the faithful reading: 0.58). ``benchmarks/pathrecovery.py``
    reports the faithful and the default side by side.

Readings common to both: sec. 2 says the resampling "distinguishes between two sets of
particles and resamples from one of them" while sec. 4.1.6 describes plain factored
sampling by the weights; we resample all particles together by their normalised weights
(hidden ones are duplicated in proportion to their weight). Diffusion moves visible
particles one step on ``G_mcd`` whatever the edge (as written, also across a gap edge);
hidden particles are neither diffused nor switched. A visible particle outside the
``N_fc`` evaluated cameras, or in a camera without observations, weighs 0.

``FilterConfig.gaps=False`` disables gap modelling: every edge takes one step and no
particle is ever hidden (the "without gap modelling" runs of sec. 7.2.1).

The particle machinery is the library's (:mod:`inference.particle`, numpy path): a step is
:func:`inference.particle.numpy_filter.sir_step` (predict, weigh, normalise in log space,
resample with :func:`inference.particle.numpy_path.systematic` / ``multinomial``, move), a
run is :func:`inference.particle.numpy_filter.run_steps`, the state is an
:class:`inference.particle.ParticleState` whose ``particles`` are the
:class:`PathParticles` arrays, and the k best states are
:func:`inference.particle.kbest.k_best_states`. This module holds only the model:
prediction, the support of eqs. 5-7, diffusion and feature switching.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from dbn.checks import check_count, check_number_fields, check_type, make_rng, real_array
from dbn.errors import InputError, NonFiniteError, ShapeError
from inference.particle.filters import ParticleState
from inference.particle.kbest import k_best_states
from inference.particle.numpy_filter import run_steps, sir_step
from inference.particle.numpy_path import multinomial, systematic
from models.pathrecovery.model import (
    CameraNetwork,
    check_cameras,
    propagate,
    sigma_cholesky,
    whiten,
)

__all__ = [
    "FilterConfig",
    "KBestLists",
    "MAX_FEATURE",
    "check_features",
    "ParticleState",
    "PathParticles",
    "StepInfo",
    "PathFilterModel",
    "init",
    "make_model",
    "observation_support",
    "run_filter",
    "step",
]

VISIBLE, HIDDEN, NONE = 0, 1, -1


class FilterConfig(NamedTuple):
    """Settings of the first phase (seed 001, sec. 4.1; paper values as defaults).

    Attributes
    ----------
    num_particles : ``N`` (250 in sec. 7.2.1).
    k : length of the k-best lists produced (the second phase may use fewer).
    alpha, beta : eqs. 5-6 (0.5, 0.5).
    p_update : ``P_update`` of sec. 4.1.3 (0.5).
    p_switch : ``P_switch`` of sec. 4.1.6 (0.5).
    n_fc : ``N_fc``, most cameras evaluated per step (30).
    faithful : the paper's weighting (see the module docstring) instead of the default.
    gaps : model gaps (hidden states); False = every edge takes one step.
    hidden_likelihood : default weighting only: the weight of a hidden particle, on the
        scale of the supports of eq. 7.
    merge_hidden : default weighting only: list hidden states by destination (True) or
        by ``(destination, ta)`` (False).
    sharpness : default weighting only: ``kappa``, the power the weights (visible support
        and ``hidden_likelihood`` alike) are raised to.
    """

    num_particles: int = 250
    k: int = 10
    alpha: float = 0.5
    beta: float = 0.5
    p_update: float = 0.5
    p_switch: float = 0.5
    n_fc: int = 30
    faithful: bool = False
    gaps: bool = True
    hidden_likelihood: float = 0.5
    merge_hidden: bool = True
    sharpness: float = 6.0

    def validate(self) -> None:
        """Raise :class:`InputError` naming the first bad field."""
        check_number_fields(self, InputError)
        for name in ("num_particles", "k", "n_fc"):
            check_count(f"FilterConfig.{name}", getattr(self, name))  # True was read as 1
        for name in ("alpha", "beta", "p_update", "p_switch"):
            v = getattr(self, name)
            if not 0.0 <= float(v) <= 1.0:
                raise InputError(f"FilterConfig.{name} must lie in [0, 1], got {v!r}")
        if not float(self.hidden_likelihood) > 0.0 or not np.isfinite(self.hidden_likelihood):
            raise InputError(f"FilterConfig.hidden_likelihood must be > 0, got {self.hidden_likelihood!r}")
        if not float(self.sharpness) > 0.0 or not np.isfinite(self.sharpness):
            raise InputError(f"FilterConfig.sharpness must be > 0, got {self.sharpness!r}")


class PathFilterModel(NamedTuple):
    """What the filter needs to know: network, target's initial state, features' metric.

    Attributes
    ----------
    network : CameraNetwork.
    c0 : int, the target's camera at ``t = 0``.
    f0 : (feature_dim,) the target's feature at ``t = 0``.
    chol : (feature_dim, feature_dim) lower Cholesky factor of ``Sigma`` (eq. 2).
    u0 : (feature_dim,) whitened ``f0`` (``L^{-1} f0``).
    config : FilterConfig.
    """

    network: CameraNetwork
    c0: int
    f0: np.ndarray
    chol: np.ndarray
    u0: np.ndarray
    config: FilterConfig


class PathParticles(NamedTuple):
    """The particles' values (arrays of shape (num_particles, ...)); never mutated in place.

    The filter's state is ``inference.particle.ParticleState(particles=PathParticles,
    log_weights)``: after every step's resampling the weights are uniform (``-log N``).

    Attributes
    ----------
    cam : (N,) int64 camera (visible) or destination (hidden).
    ta : (N,) int64, 0 when visible, steps to arrival when hidden.
    src : (N,) int64 the particle's last visible camera before its current one (for the
        ``W^p`` term of eq. 5).
    feat : (N, feature_dim) whitened feature vectors ``L^{-1} f``.
    raw : (N,) float64 the particle's last eq. 7 weight (the stale weight the faithful
        reading gives a hidden particle).
    """

    cam: np.ndarray
    ta: np.ndarray
    src: np.ndarray
    feat: np.ndarray
    raw: np.ndarray


class StepInfo(NamedTuple):
    """The k best distinct states of one step, best first (sec. 4.1.5), and diagnostics.

    Attributes
    ----------
    kind : (k,) int8: 0 visible, 1 hidden, -1 no state (fewer than k states).
    cam : (k,) int64 camera (visible) or destination (hidden), -1 for no state.
    ta : (k,) int64 steps to arrival of a hidden state (0 for visible).
    obs : (k,) int64 index of the associated observation (offset by ``obs_offset``),
        -1 for hidden states.
    mass : (k,) float64 normalised weight of the state (0 for no state).
    num_tracked_cameras : cameras evaluated this step (at most ``N_fc``).
    ess : effective sample size of the normalised weights.
    log_score : the step's log mean unnormalised weight
        ``log sum_i exp(log_w_prev_i + log g_i)`` with ``g`` the weighting function of
        the reading (eq. 7 support raised to ``kappa``, or the faithful raw weight):
        the particle estimate of the step's (unnormalised) evidence; ``-inf`` when every
        particle weighs zero.
    """

    kind: np.ndarray
    cam: np.ndarray
    ta: np.ndarray
    obs: np.ndarray
    mass: np.ndarray
    num_tracked_cameras: int
    ess: float
    log_score: float = float("nan")


class KBestLists(NamedTuple):
    """The first phase's output over a run: step ``i`` holds time ``t = i + 1``.

    Attributes
    ----------
    kind, cam, ta, obs : (num_timesteps - 1, k) int arrays (see :class:`StepInfo`).
    mass : (num_timesteps - 1, k) float64.
    num_tracked_cameras : (num_timesteps - 1,) int64.
    step_seconds : (num_timesteps - 1,) wall time of every :func:`step`.
    """

    kind: np.ndarray
    cam: np.ndarray
    ta: np.ndarray
    obs: np.ndarray
    mass: np.ndarray
    num_tracked_cameras: np.ndarray
    step_seconds: np.ndarray


# ------------------------------------------------------------------------------ set-up
def make_model(
    network: CameraNetwork,
    c0: int,
    f0: np.ndarray,
    sigma: np.ndarray,
    config: FilterConfig | None = None,
) -> PathFilterModel:
    """Check and bundle the filter's inputs.

    Parameters
    ----------
    network : CameraNetwork.
    c0 : the target's initial camera ``C_0``.
    f0 : (feature_dim,) the target's initial feature ``f_0``.
    sigma : (feature_dim, feature_dim) SPD covariance of a typical feature vector (eq. 2).
    config : FilterConfig (defaults when None).

    Returns
    -------
    PathFilterModel.
    """
    check_type("network", network, CameraNetwork, InputError)
    config = FilterConfig() if config is None else check_type("config", config, FilterConfig,
                                                                InputError)  # fmt: skip
    config.validate()
    f0 = real_array("f0", f0)
    if f0.ndim != 1:
        raise ShapeError(f"f0 must be 1-D, got shape {f0.shape}")
    if not np.all(np.isfinite(f0)):
        raise NonFiniteError(f"f0 holds non-finite values: {f0!r}")
    _, chol = sigma_cholesky(sigma, f0.size)
    if isinstance(c0, bool) or not isinstance(c0, int | np.integer):  # True was camera 1
        raise InputError(f"c0 must be an int camera id, got {c0!r}")
    check_cameras("c0", np.array([c0]), network)
    u0 = whiten(chol, f0)
    return PathFilterModel(network, int(c0), f0, chol, u0, config)


def init(model: PathFilterModel) -> ParticleState:
    """All particles at ``C_0`` with ``f_0``, equally weighted (sec. 4.1), at ``t = 0``."""
    n = model.config.num_particles
    particles = PathParticles(
        cam=np.full(n, model.c0, dtype=np.int64),
        ta=np.zeros(n, dtype=np.int64),
        src=np.full(n, model.c0, dtype=np.int64),
        feat=np.tile(model.u0, (n, 1)),
        raw=np.ones(n),
    )
    return ParticleState(particles, np.full(n, -np.log(n)))


def _check_observations(model: PathFilterModel, obs_cam: np.ndarray, obs_feat: np.ndarray) -> None:
    """Validate one step's observations: shapes, finiteness, cameras, sorted by camera."""
    if obs_cam.ndim != 1:
        raise ShapeError(f"obs_cam must be 1-D, got shape {obs_cam.shape}")
    d = model.f0.size
    if obs_feat.shape != (obs_cam.size, d):
        raise ShapeError(f"obs_feat must have shape ({obs_cam.size}, {d}), got {obs_feat.shape}")
    if not np.issubdtype(obs_cam.dtype, np.integer):
        raise InputError(f"obs_cam must hold integer camera ids, got dtype {obs_cam.dtype}")
    check_cameras("obs_cam", obs_cam, model.network)
    if obs_cam.size > 1 and np.any(obs_cam[1:] < obs_cam[:-1]):
        i = int(np.flatnonzero(obs_cam[1:] < obs_cam[:-1])[0])
        raise InputError(f"obs_cam must be sorted by camera; obs_cam[{i}:{i + 2}] = {obs_cam[i:i + 2]}")
    check_features("obs_feat", obs_feat)


#: Largest accepted ``|feature|`` entry. Appearance features are expected of order 1-1000
#: (they are whitened by the model's ``sigma``); beyond 1e6 they are a unit or scale
#: mistake and are rejected (issue 14).
MAX_FEATURE = 1e6


def check_features(name: str, feat) -> None:
    """Raise unless ``feat`` holds real, finite numbers with ``|x| <= MAX_FEATURE``."""
    a = np.asarray(feat)
    if not (np.issubdtype(a.dtype, np.floating) or np.issubdtype(a.dtype, np.integer)):
        raise InputError(f"{name} must hold real numbers, got dtype {a.dtype}")
    if not np.all(np.isfinite(a)):
        raise NonFiniteError(f"{name} holds NaN or infinite values")
    if a.size and np.abs(a).max() > MAX_FEATURE:
        raise InputError(
            f"{name} holds |value| = {np.abs(a).max():g} > {MAX_FEATURE:g} (features are "
            "expected of order 1-1000; rescale them)"
        )


# ------------------------------------------------------------------------------ helpers
def _segments(lo: np.ndarray, cnt: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Flatten ragged ranges ``lo[i] : lo[i] + cnt[i]`` (all ``cnt > 0``).

    Returns ``(owner, item, starts)``: for every flat pair its owner row and item index,
    and the start of every row's run in the flat arrays.
    """
    starts = np.cumsum(cnt) - cnt
    owner = np.repeat(np.arange(cnt.size), cnt)
    item = lo[owner] + np.arange(owner.size) - starts[owner]
    return owner, item, starts


def _observations_at(
    obs_cam: np.ndarray, cams: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The observations seen at each of ``cams`` (``obs_cam`` sorted by camera).

    Returns ``(has, owner, item, starts)``: ``has`` marks the cameras with at least one
    observation; the rest is :func:`_segments` over those cameras' observation ranges.
    """
    lo = np.searchsorted(obs_cam, cams, side="left")
    hi = np.searchsorted(obs_cam, cams, side="right")
    has = hi > lo
    return (has, *_segments(lo[has], (hi - lo)[has]))


def _segment_argmax(values: np.ndarray, owner: np.ndarray, starts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Max and first argmax (flat index) of ``values`` over each contiguous run."""
    seg_max = np.maximum.reduceat(values, starts)
    hit = np.flatnonzero(values == seg_max[owner])
    _, first = np.unique(owner[hit], return_index=True)
    return seg_max, hit[first]


def _whiten(model: PathFilterModel, feats: np.ndarray) -> np.ndarray:
    return whiten(model.chol, feats)


# ------------------------------------------------------------------------------ the step
def observation_support(
    model: PathFilterModel, u_x: np.ndarray, u_z: np.ndarray, w_p: np.ndarray
) -> np.ndarray:
    """Support of an observation for a particle in its camera (seed 001, eqs. 5-6).

    ``P(x = z | f_0) = beta (alpha W^p + (1 - alpha) P_s(f_x, f_z)) + (1 - beta) P_s(f_0, f_z)``
    with ``P_s = exp(-d_M^2 / 2)`` (eqs. 2-3).

    Parameters
    ----------
    model : PathFilterModel (``alpha``, ``beta``, whitened ``f_0``).
    u_x : (n, feature_dim) whitened particle features ``L^{-1} f_x``.
    u_z : (n, feature_dim) whitened observation features ``L^{-1} f_z``.
    w_p : (n,) ``W^p(C_{x_{t-1}}, C_{x_t})``.

    Returns
    -------
    (n,) float64 in [0, 1].
    """
    cfg = model.config
    dx = u_x - u_z
    d0 = model.u0 - u_z
    ps_x = np.exp(-0.5 * np.einsum("ij,ij->i", dx, dx))
    ps_0 = np.exp(-0.5 * np.einsum("ij,ij->i", d0, d0))
    return cfg.beta * (cfg.alpha * w_p + (1 - cfg.alpha) * ps_x) + (1 - cfg.beta) * ps_0


def step(
    rng: np.random.Generator,
    model: PathFilterModel,
    state: ParticleState,
    obs_cam: np.ndarray,
    obs_feat: np.ndarray,
    obs_offset: int = 0,
    check: bool = True,
) -> tuple[ParticleState, StepInfo]:
    """One step of the modified particle filter (seed 001, sec. 4.1, eqs. 5-7).

    The library's SIR step (:func:`inference.particle.numpy_filter.sir_step`) with this
    model's prediction (:func:`_predict`), weighting (:func:`_weigh`) and post-resampling
    move (:func:`_move`); the resampler is multinomial for the faithful reading, systematic
    otherwise.

    Parameters
    ----------
    rng : numpy Generator (the step's randomness; same state, same result).
    model : PathFilterModel from :func:`make_model`.
    state : ParticleState (particles :class:`PathParticles`) at ``t - 1``.
    obs_cam : (num_obs,) int camera of every observation at ``t``, sorted ascending.
    obs_feat : (num_obs, feature_dim) their feature vectors.
    obs_offset : added to observation indices in the output (e.g. the ODB's
        ``time_ptr[t]``).
    check : validate the observations (skip only when already validated).

    Returns
    -------
    (ParticleState at ``t``, StepInfo with the k best states of ``t``).

    Raises
    ------
    ShapeError, NonFiniteError, InputError
        On bad observations, before anything is computed; ``state`` is never modified.
    """
    obs_cam = np.asarray(obs_cam)
    if check:
        check_features("obs_feat", obs_feat)
        if isinstance(obs_offset, bool) or not isinstance(obs_offset, int | np.integer) or obs_offset < 0:
            raise InputError(f"obs_offset must be an int >= 0, got {obs_offset!r}")
    obs_feat = np.asarray(obs_feat, dtype=np.float64)
    if check:
        _check_observations(model, obs_cam, obs_feat)
    new_state, sir = sir_step(
        rng,
        state,
        lambda r, p: _predict(r, model, p),
        lambda r, p: _weigh(r, model, p, obs_cam, obs_feat),
        resample=multinomial if model.config.faithful else systematic,
        move=lambda r, p: _move(r, model, p, obs_cam, obs_feat),
    )
    assoc, num_tracked = sir.aux
    valid = np.isfinite(sir.log_weights) & np.isfinite(sir.log_score)
    parts, wn = sir.particles, np.exp(sir.log_weights)
    info = _kbest(model, parts.cam, parts.ta, assoc, wn, valid, obs_offset, num_tracked, sir.ess)
    return new_state, info._replace(log_score=sir.log_score)


def _predict(rng: np.random.Generator, model: PathFilterModel, prev: PathParticles) -> PathParticles:
    """Prediction (sec. 4.1.1): locations move (:func:`propagate`); ``src`` follows."""
    cam, ta, moved_from = propagate(rng, model.network, prev.cam, prev.ta, gaps=model.config.gaps)
    src = np.where(moved_from >= 0, moved_from, prev.src)
    return PathParticles(cam, ta, src, prev.feat, prev.raw)


def _tracked(cfg: FilterConfig, cam: np.ndarray, vis_idx: np.ndarray) -> tuple[np.ndarray, int]:
    """The visible particles in the ``N_fc`` cameras holding most of them, and how many
    cameras that is (sec. 4.1.3)."""
    ucams, counts = np.unique(cam[vis_idx], return_counts=True)
    if ucams.size <= cfg.n_fc:
        return vis_idx, int(ucams.size)
    tracked_cams = np.sort(ucams[np.argsort(-counts, kind="stable")[: cfg.n_fc]])
    return vis_idx[np.isin(cam[vis_idx], tracked_cams, assume_unique=False)], cfg.n_fc


def _weigh(
    rng: np.random.Generator,
    model: PathFilterModel,
    parts: PathParticles,
    obs_cam: np.ndarray,
    obs_feat: np.ndarray,
) -> tuple[PathParticles, np.ndarray, tuple[np.ndarray, int]]:
    """Evaluation (sec. 4.1.3, eqs. 5-7) and the log weight of either reading (4.1.4).

    Returns the particles (features updated with probability ``P_update``, ``raw`` the
    eq. 7 weight of visible particles), the (N,) log potential, and ``(assoc, number of
    evaluated cameras)`` with ``assoc`` (N,) the associated observation (-1 for none).
    """
    cfg, net = model.config, model.network
    n = parts.cam.size
    vis = parts.ta == 0
    considered, num_tracked = _tracked(cfg, parts.cam, np.flatnonzero(vis))
    feat = parts.feat.copy()
    w = np.zeros(n)
    assoc = np.full(n, -1, dtype=np.int64)
    has, owner, item, starts = _observations_at(obs_cam, parts.cam[considered])
    p_idx = considered[has]
    if p_idx.size:
        uz = _whiten(model, obs_feat[item])
        wp = net.transition_prob(parts.src[p_idx], parts.cam[p_idx])[owner]
        support = observation_support(model, feat[p_idx][owner], uz, wp)  # eqs. 5-6
        seg_max, best = _segment_argmax(support, owner, starts)  # eq. 7
        w[p_idx] = seg_max
        assoc[p_idx] = item[best]
        upd = rng.random(p_idx.size) < cfg.p_update
        feat[p_idx[upd]] = uz[best[upd]]
    raw = np.where(vis, w, parts.raw)  # a hidden particle keeps its stale weight in ``raw``
    with np.errstate(divide="ignore"):
        if cfg.faithful:
            log_g = np.log(raw)
        else:
            log_g = cfg.sharpness * np.log(np.where(vis, w, cfg.hidden_likelihood))
    return parts._replace(feat=feat, raw=raw), log_g, (assoc, num_tracked)


def _move(
    rng: np.random.Generator,
    model: PathFilterModel,
    parts: PathParticles,
    obs_cam: np.ndarray,
    obs_feat: np.ndarray,
) -> PathParticles:
    """After resampling (sec. 4.1.6): visible locations diffuse by ``G_mcd``, then a
    visible particle's feature switches with probability ``P_switch`` to an observation
    of its camera drawn proportionally to ``P_s(f_0, f_z)``."""
    vis_idx = np.flatnonzero(parts.ta == 0)
    if not vis_idx.size:
        return parts
    net = model.network
    cam, feat = parts.cam.copy(), parts.feat.copy()
    edges = net.sample_edges(rng, cam[vis_idx], diffusion=True)
    cam[vis_idx] = net.indices[edges]
    sw = vis_idx[rng.random(vis_idx.size) < model.config.p_switch]
    has, owner, item, starts = _observations_at(obs_cam, cam[sw])
    sw = sw[has]
    if sw.size:
        uz = _whiten(model, obs_feat[item])
        d0 = model.u0 - uz
        # draw z with probability proportional to P_s(f0, f_z): Gumbel-max per particle
        score = -0.5 * np.einsum("ij,ij->i", d0, d0) + rng.gumbel(size=item.size)
        _, best = _segment_argmax(score, owner, starts)
        feat[sw] = uz[best]
    return parts._replace(cam=cam, feat=feat)


def _kbest(
    model: PathFilterModel,
    cam: np.ndarray,
    ta: np.ndarray,
    assoc: np.ndarray,
    wn: np.ndarray,
    valid: np.ndarray,
    obs_offset: int,
    num_tracked: int,
    ess: float,
) -> StepInfo:
    """The k distinct states of largest mass (sec. 4.1.5); see the module docstring."""
    cfg = model.config
    k = cfg.k
    idx = np.flatnonzero(valid)
    width = model.network.max_delay + 1
    hidden = ta[idx] > 0
    if cfg.faithful or not cfg.merge_hidden:
        hkey = -(1 + cam[idx] * width + ta[idx])
    else:
        hkey = -(1 + cam[idx] * width)
    key = np.where(hidden, hkey, assoc[idx])
    # a state's rank: its largest particle weight (faithful) or its total mass (default)
    best, mass = k_best_states(key, wn[idx], k, combine="max" if cfg.faithful else "sum")
    m = best.size
    out_kind = np.full(k, NONE, dtype=np.int8)
    out_cam = np.full(k, -1, dtype=np.int64)
    out_ta = np.zeros(k, dtype=np.int64)
    out_obs = np.full(k, -1, dtype=np.int64)
    out_mass = np.zeros(k)
    r = idx[best]
    is_h = ta[r] > 0
    out_kind[:m] = np.where(is_h, HIDDEN, VISIBLE)
    out_cam[:m] = cam[r]
    out_ta[:m] = ta[r]
    out_obs[:m] = np.where(is_h, -1, assoc[r] + obs_offset)
    out_mass[:m] = mass
    return StepInfo(out_kind, out_cam, out_ta, out_obs, out_mass, num_tracked, ess)


# ------------------------------------------------------------------------------ a run
def run_filter(
    seed: int | np.random.Generator,
    model: PathFilterModel,
    odb,
    progress: bool = False,
) -> KBestLists:
    """Run the first phase over every step ``t = 1 .. T - 1`` of an observation database.

    Parameters
    ----------
    seed : int or numpy Generator; the same seed gives the same lists.
    model : PathFilterModel.
    odb : :class:`models.pathrecovery.simulate.ObservationDB` (or anything with
        ``time_ptr``, ``cam`` and ``feat`` laid out the same way).
    progress : show a tqdm progress bar.

    Returns
    -------
    KBestLists.
    """
    rng = make_rng(seed)
    time_ptr = np.asarray(odb.time_ptr)
    if time_ptr.ndim != 1 or time_ptr.size < 3 or np.any(np.diff(time_ptr) < 0):
        raise InputError("odb.time_ptr must be 1-D, non-decreasing, with at least 2 steps")
    if not np.issubdtype(time_ptr.dtype, np.integer):
        raise InputError(f"odb.time_ptr must hold integers, got dtype {time_ptr.dtype}")
    num_obs = len(odb.cam)
    if len(odb.feat) != num_obs or time_ptr[0] != 0 or time_ptr[-1] != num_obs:
        raise InputError(
            f"odb.time_ptr must run from 0 to the number of observations ({num_obs}, "
            f"feat rows {len(odb.feat)}), got {int(time_ptr[0])}..{int(time_ptr[-1])}"
        )
    T = time_ptr.size - 1
    # validate every step up front: a bad step raises before any filtering is done
    for t in range(1, T):
        lo, hi = time_ptr[t], time_ptr[t + 1]
        _check_observations(model, np.asarray(odb.cam[lo:hi]), np.asarray(odb.feat[lo:hi]))
    steps = [(int(time_ptr[t]), int(time_ptr[t + 1])) for t in range(1, T)]

    def one(r: np.random.Generator, state: ParticleState, lohi: tuple[int, int]):
        lo, hi = lohi
        return step(r, model, state, odb.cam[lo:hi], odb.feat[lo:hi], obs_offset=lo, check=False)

    _, infos, secs = run_steps(
        rng, one, init(model), steps, progress=progress, desc="path-recovery filter"
    )
    fields = ("kind", "cam", "ta", "obs", "mass")
    kind, cam, ta, obs, mass = (np.stack([getattr(i, f) for i in infos]) for f in fields)
    tracked = np.array([i.num_tracked_cameras for i in infos], dtype=np.int64)
    return KBestLists(kind, cam, ta, obs, mass, tracked, secs)
