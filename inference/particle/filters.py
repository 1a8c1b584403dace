r"""Bootstrap (SIR) and auxiliary particle filters as ``init`` / ``step`` / ``run``.

The algorithms follow seed 002, section 1.3.1: the bootstrap filter samples the
predictive mixture (eq. 1.8) and weights by the likelihood (eq. 1.9); the auxiliary filter
(Pitt & Shephard) first resamples ancestors with the look-ahead weights
:math:`\pi_{k-1}^i p(y_k|\mu_k^i)` (eq. 1.12) and then weights the moved particles by
:math:`p(y_k|s_k^j) / p(y_k|\mu_k^{i_j})` (eq. 1.13).

Both resample adaptively: only when the effective sample size (of the first-stage weights
for the auxiliary filter) falls below ``ess_threshold * num_particles``;
``ess_threshold >= 1`` resamples at every step. Weights are kept as normalised log
weights, and each step's info carries the one-step log-likelihood estimate
:math:`\log \hat p(y_k | y_{1:k-1})` (the ``logsumexp(logw) - log N`` form), whose
exponential is unbiased.

Steps are pure and jit-able; :func:`run` scans a step over time with ``lax.scan``.
The float dtype (float32 or float64) is chosen by ``dtype`` and kept throughout; with
float64 (the default) ``init``, ``step`` and :func:`run` enter jax's 64-bit mode themselves
(:func:`inference.precision.precision_scope`), whatever the global configuration.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from functools import partial
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array
from jax.scipy.special import logsumexp

from dbn.checks import check_count, check_nonnegative
from dbn.errors import InputError, ModelError, ShapeError
from inference.particle.model import StateSpaceModel
from inference.particle.resampling import RESAMPLERS, Resampler, systematic
from inference.precision import precision_scope, scoped

__all__ = [
    "ParticleState",
    "ParticleInfo",
    "ParticleFilter",
    "bootstrap_filter",
    "auxiliary_filter",
    "run",
    "run_model",
    "ess",
    "weighted_mean",
    "weighted_cov",
]


class ParticleState(NamedTuple):
    """Weighted particle cloud approximating :math:`p(s_k | y_{1:k})` (seed 002, eq. 1.7).

    Attributes
    ----------
    particles : Array, shape (num_particles, state_dim)
    log_weights : Array, shape (num_particles,)
        Normalised: ``logsumexp(log_weights) == 0``.
    """

    particles: Array
    log_weights: Array


class ParticleInfo(NamedTuple):
    """What one step did.

    Attributes
    ----------
    log_likelihood : Array, shape ()
        :math:`\\log \\hat p(y_k | y_{1:k-1})` (``-inf`` if every particle got weight zero).
    ess : Array, shape ()
        Effective sample size that decided the resampling (first-stage weights for the
        auxiliary filter), in particles.
    ancestors : Array, shape (num_particles,), int32
        Index at step ``k-1`` of each particle's parent (``arange`` if not resampled).
    resampled : Array, shape (), bool
    """

    log_likelihood: Array
    ess: Array
    ancestors: Array
    resampled: Array


class ParticleFilter(NamedTuple):
    """An algorithm as a pair of pure functions (blackjax style).

    ``init(key) -> ParticleState``;
    ``step(key, state, observation, action=None) -> (ParticleState, ParticleInfo)``;
    ``dtype`` is the float dtype they compute in (``None``: jax's current default). Both
    functions enter 64-bit mode themselves when ``dtype`` is float64.
    """

    init: Callable[..., ParticleState]
    step: Callable[..., tuple[ParticleState, ParticleInfo]]
    dtype: Any = None


def ess(log_weights: Array) -> Array:
    r"""Effective sample size :math:`(\sum_i w_i)^2 / \sum_i w_i^2` from log weights.

    Parameters
    ----------
    log_weights : Array, shape (num_particles,)
        Unnormalised log weights.

    Returns
    -------
    Array, shape ()
        In ``[1, num_particles]``; 0 when every weight is zero.
    """
    value = jnp.exp(2.0 * logsumexp(log_weights) - logsumexp(2.0 * log_weights))
    return jnp.where(jnp.isfinite(value), value, jnp.zeros_like(value))


def _lse_and_ess(log_weights: Array) -> tuple[Array, Array]:
    """``(logsumexp(log_weights), ess(log_weights))`` in one max pass and one exp pass."""
    m = jnp.max(log_weights)
    safe = jnp.where(jnp.isfinite(m), m, jnp.zeros_like(m))
    w = jnp.exp(log_weights - safe)
    s1 = jnp.sum(w)
    s2 = jnp.sum(w * w)
    lse = jnp.where(s1 > 0, safe + jnp.log(s1), -jnp.inf)
    value = s1 * s1 / s2
    return lse, jnp.where(jnp.isfinite(value), value, jnp.zeros_like(value))


def weighted_mean(state: ParticleState) -> Array:
    r"""Filtered mean :math:`\sum_i W_i s^i`; shape ``(state_dim,)``."""
    w = jnp.exp(state.log_weights)
    return w @ state.particles


def weighted_cov(state: ParticleState) -> Array:
    r"""Filtered covariance :math:`\sum_i W_i (s^i - m)(s^i - m)^T`; shape ``(state_dim, state_dim)``."""
    w = jnp.exp(state.log_weights)
    d = state.particles - w @ state.particles
    return (d * w[:, None]).T @ d


def _clean(log_w: Array) -> Array:
    return jnp.where(jnp.isnan(log_w), -jnp.inf, log_w)


def _normalise(log_w: Array) -> tuple[Array, Array]:
    """(normalised log weights, logsumexp); uniform weights when all are zero."""
    total = logsumexp(log_w)
    ok = jnp.isfinite(total)
    uniform = jnp.full_like(log_w, -math.log(log_w.shape[0]))
    return jnp.where(ok, log_w - jnp.where(ok, total, 0.0), uniform), total


def _init(key: Array, model: StateSpaceModel, num_particles: int, dtype: Any) -> ParticleState:
    x = jnp.asarray(model.sample_initial(key, num_particles, dtype), dtype=dtype)
    if x.ndim != 2 or x.shape[0] != num_particles:
        raise ModelError(
            f"model.sample_initial returned shape {x.shape}; expected ({num_particles}, state_dim)"
        )
    lw = jnp.full((num_particles,), -math.log(num_particles), dtype=dtype)
    return ParticleState(x, lw)


def _resample_predicate(cur_ess: Array, ess_threshold: float, n: int) -> Array:
    """Whether to resample. For ``ess_threshold >= 1`` the predicate is ``ess >= 0``, always
    true at run time but not a compile-time constant: the resampling branch of ``lax.cond``
    then stays a separate computation. That matters for speed on CPU: XLA de-vectorises a
    fusion that mixes the ancestor gather with the transition sampler (4x slower)."""
    if ess_threshold >= 1.0:
        return cur_ess >= 0.0
    return cur_ess < ess_threshold * n


def check_threshold(ess_threshold: Any) -> None:
    """Raise :class:`InputError` unless ``ess_threshold`` is a real number >= 0 (not a bool)."""
    check_nonnegative("ess_threshold", ess_threshold)


def check_resampler(resampler: Any) -> Resampler:
    """A resampler: a callable ``(key, log_weights, n) -> ancestors`` or the name of one in
    :data:`~inference.particle.resampling.RESAMPLERS`; else :class:`InputError` (a name
    was taken, then raised "'str' object is not callable" inside the traced step)."""
    if isinstance(resampler, str) and resampler in RESAMPLERS:
        return RESAMPLERS[resampler]
    if isinstance(resampler, str) or not callable(resampler):
        raise InputError(f"resampler must be one of {sorted(RESAMPLERS)} or a callable "
                         f"(key, log_weights, n) -> ancestors, got {resampler!r}")  # fmt: skip
    return resampler


def check_float_dtype(dtype: Any) -> None:
    """Raise :class:`InputError` unless ``dtype`` is a float dtype (an int32 filter was
    built, then failed inside the model's first draw with jax's own ValueError)."""
    try:
        kind = np.dtype(dtype).kind
    except TypeError:
        kind = None
    if kind != "f":
        raise InputError(f"dtype must be a float dtype (jnp.float32 or jnp.float64), "
                         f"got {dtype!r}")  # fmt: skip


MAX_PARTICLES = 2**31 - 1
"""The most particles a filter takes: jax indexes them with int32."""


def check_num_particles(num_particles: Any) -> int:
    """``num_particles`` as an int in [1, :data:`MAX_PARTICLES`] (an int, not a bool or a
    fractional float); else :class:`InputError`."""
    n = check_count("num_particles", num_particles)
    if n > MAX_PARTICLES:
        raise InputError(f"num_particles must be at most 2**31 - 1, got {num_particles!r}")
    return n


MODEL_METHODS = ("sample_initial", "sample_transition", "log_likelihood")
"""What a particle filter calls on its model (a :class:`StateSpaceModel` declares them)."""


def check_model(model: Any) -> None:
    """Raise :class:`ModelError` unless ``model`` declares :data:`MODEL_METHODS` (a
    :class:`StateSpaceModel` or any object with them): a filter built on anything else
    failed at its first ``init`` with Python's ``AttributeError``."""
    missing = [m for m in MODEL_METHODS if not callable(getattr(model, m, None))]
    if missing:
        raise ModelError(f"model must be a StateSpaceModel (declare {', '.join(MODEL_METHODS)})"
                         f"; {type(model).__name__} lacks {', '.join(missing)}")  # fmt: skip


def check_key(key: Any) -> None:
    """Raise :class:`InputError` unless ``key`` is one jax PRNG key: a typed key
    (``jax.random.key(seed)``, shape ``()``) or a legacy one (``jax.random.PRNGKey(seed)``,
    uint32, shape ``(2,)``). Else jax fails deep inside the filter, naming no argument."""
    dtype, shape = getattr(key, "dtype", None), getattr(key, "shape", None)
    if dtype is not None and shape is not None:
        if jax.dtypes.issubdtype(dtype, jax.dtypes.prng_key) and tuple(shape) == ():
            return
        if np.dtype(dtype) == np.uint32 and tuple(shape) == (2,):
            return
    got = type(key).__name__ + ("" if dtype is None else f" of dtype {dtype}, shape {shape}")
    raise InputError(f"key must be one jax PRNG key (jax.random.key(seed)), got {got}")


def check_run_inputs(observations: Any, actions: Any) -> int:
    """The number of steps of a run: the leading axis every leaf of ``observations`` and of
    ``actions`` (None: none) shares. No leaves, a scalar leaf, a leaf of another length or
    no steps is an :class:`InputError` / :class:`ShapeError` naming the leaf (else
    ``lax.scan`` fails naming none)."""
    leaves = [(f"observations leaf {i}", a)
              for i, a in enumerate(jax.tree_util.tree_leaves(observations))]  # fmt: skip
    if not leaves:
        raise InputError("observations hold no arrays: a run needs leaves of leading axis "
                         "num_timesteps")  # fmt: skip
    leaves += [(f"actions leaf {i}", a) for i, a in enumerate(jax.tree_util.tree_leaves(actions))]
    for name, a in leaves:
        if np.ndim(a) == 0:
            raise ShapeError(f"{name} is a scalar: a run needs leading axis num_timesteps")
        _check_leaf_dtype(name, a)
    num_steps = np.shape(leaves[0][1])[0]
    for name, a in leaves:
        if np.shape(a)[0] != num_steps:
            raise ShapeError(f"{name} has shape {np.shape(a)}: every observation and action "
                             f"leaf needs the leading axis num_timesteps = {num_steps}")  # fmt: skip
    if num_steps == 0:
        raise InputError("observations have no steps (leading axis 0)")
    return int(num_steps)


def _check_leaf_dtype(name: str, leaf: Any) -> None:
    """An :class:`InputError` naming ``name`` unless ``leaf`` holds real numbers or bools:
    text raised jax's TypeError from ``lax.scan``, and complex observations ran, the
    likelihood taking a complex residual."""
    dtype = getattr(leaf, "dtype", None)
    dtype = np.asarray(leaf).dtype if dtype is None else dtype
    if jnp.issubdtype(dtype, jnp.complexfloating) or not (
            jnp.issubdtype(dtype, jnp.number) or jnp.issubdtype(dtype, jnp.bool_)):  # fmt: skip
        raise InputError(f"{name} has dtype {dtype}: a run needs real numbers")


# A first stage: ``(state, observation, action) -> (log_weights, ess, base)``: the log
# weights ancestors are drawn from, their ESS (which decides the resampling), and
# ``base(ancestors)``, the log weights of the drawn particles before the new likelihood.
FirstStage = Callable[[ParticleState, Any, Any], tuple[Array, Array, Callable[[Array], Array]]]


def _bootstrap_stage(model: StateSpaceModel, log_n: float, dtype: Any) -> FirstStage:
    r"""Eq. 1.8: ancestors from :math:`\pi_{k-1}`; the drawn particles weigh :math:`1/N`."""

    def stage(state: ParticleState, observation: Any, action: Any):
        lw = state.log_weights
        _, cur_ess = _lse_and_ess(lw)
        return lw, cur_ess, lambda anc: jnp.full_like(lw, -log_n)

    return stage


def _auxiliary_stage(model: StateSpaceModel, log_n: float, dtype: Any) -> FirstStage:
    r"""Eqs. 1.12-1.13: ancestors from :math:`\pi_{k-1}^i \eta^i`; a drawn particle weighs
    :math:`\sum_i \pi_{k-1}^i\eta^i / (N \eta^{a^j})`."""

    def stage(state: ParticleState, observation: Any, action: Any):
        lw = state.log_weights
        log_eta = _clean(model.log_eta(state.particles, observation, action).astype(dtype))
        lw1 = lw + log_eta
        lse1, cur_ess = _lse_and_ess(lw1)
        # a look-ahead that gives every particle weight zero carries no information: ignore it
        eta_ok = jnp.isfinite(lse1)
        log_eta = jnp.where(eta_ok, log_eta, jnp.zeros_like(log_eta))
        lw1 = jnp.where(eta_ok, lw1, lw)
        lse1 = jnp.where(eta_ok, lse1, jnp.zeros_like(lse1))
        cur_ess = jnp.where(eta_ok, cur_ess, _lse_and_ess(lw)[1])
        return lw1, cur_ess, lambda anc: (lse1 - log_n) - log_eta[anc]

    return stage


def _particle_filter(
    model: StateSpaceModel,
    num_particles: int,
    resampler: Resampler,
    ess_threshold: float,
    dtype: Any,
    first_stage: Callable[[StateSpaceModel, float, Any], FirstStage],
) -> ParticleFilter:
    """The filter both algorithms share: a first stage (:data:`FirstStage`), adaptive
    resampling on its ESS, propagation and weighting by the likelihood."""
    check_model(model)
    check_threshold(ess_threshold)
    check_float_dtype(dtype)
    resampler = check_resampler(resampler)
    n = check_num_particles(num_particles)
    stage = first_stage(model, math.log(n), dtype)

    @scoped(dtype)
    def init(key: Array) -> ParticleState:
        return _init(key, model, n, dtype)

    @scoped(dtype)
    def step(
        key: Array, state: ParticleState, observation: Any, action: Any = None
    ) -> tuple[ParticleState, ParticleInfo]:
        k_res, k_move = jax.random.split(key)
        lw1, cur_ess, base_of = stage(state, observation, action)

        def resample(_):
            anc = resampler(k_res, lw1, n)
            return anc, state.particles[anc], base_of(anc)

        def keep(_):
            return jnp.arange(n, dtype=jnp.int32), state.particles, state.log_weights

        do = _resample_predicate(cur_ess, ess_threshold, n)
        anc, x, base = jax.lax.cond(do, resample, keep, None)
        x_new = model.sample_transition(k_move, x, action).astype(dtype)
        log_w = _clean(base + model.log_likelihood(x_new, observation).astype(dtype))
        new_lw, total = _normalise(log_w)
        return ParticleState(x_new, new_lw), ParticleInfo(total, cur_ess, anc, do)

    return ParticleFilter(init, step, dtype)


def bootstrap_filter(
    model: StateSpaceModel,
    num_particles: int,
    *,
    resampler: Resampler = systematic,
    ess_threshold: float = 0.5,
    dtype: Any = jnp.float64,
) -> ParticleFilter:
    r"""The bootstrap / SIR particle filter (seed 002, eqs. 1.7-1.9).

    Step :math:`k`: if :math:`\mathrm{ESS}(\pi_{k-1}) < \tau N`, resample ancestors
    :math:`a^j \sim \pi_{k-1}`; propagate :math:`s_k^j \sim p(s_k|s_{k-1}^{a^j}, u_k)`; weight
    :math:`\pi_k^j \propto \pi_{k-1}^{a^j} p(y_k|s_k^j)`.

    Parameters
    ----------
    model : StateSpaceModel
        Declares ``sample_initial``, ``sample_transition``, ``log_likelihood``.
    num_particles : int
        :math:`N` (static).
    resampler : callable or str
        ``(key, log_weights, n) -> ancestors`` (:mod:`inference.particle.resampling`), or
        the name of one in :data:`~inference.particle.resampling.RESAMPLERS`.
    ess_threshold : float
        :math:`\tau`; resample when ESS < tau N; ``>= 1`` resamples every step.
    dtype : float dtype
        ``jnp.float32`` or ``jnp.float64`` for particles and weights.

    Returns
    -------
    ParticleFilter
        ``init(key)`` and ``step(key, state, observation, action=None)``.
    """
    return _particle_filter(model, num_particles, resampler, ess_threshold, dtype, _bootstrap_stage)


def auxiliary_filter(
    model: StateSpaceModel,
    num_particles: int,
    *,
    resampler: Resampler = systematic,
    ess_threshold: float = 0.5,
    dtype: Any = jnp.float64,
) -> ParticleFilter:
    r"""The auxiliary particle filter of Pitt & Shephard (seed 002, eqs. 1.11-1.13).

    Step :math:`k`: first-stage weights :math:`\pi_{k-1}^i \eta^i` with
    :math:`\eta^i = p(y_k|\mu_k^i)` (``model.log_eta``, by default the likelihood at the
    transition mean, eq. 1.12). If their ESS is below :math:`\tau N`, resample ancestors
    :math:`a^j` from them, propagate :math:`s_k^j \sim p(s_k|s_{k-1}^{a^j}, u_k)` and weight
    :math:`\pi_k^j \propto p(y_k|s_k^j) / \eta^{a^j}` (eq. 1.13); otherwise propagate every
    particle and weight :math:`\pi_k^i \propto \pi_{k-1}^i p(y_k|s_k^i)`. The one-step
    log-likelihood is
    :math:`\log\sum_i \pi_{k-1}^i\eta^i + \log \frac1N\sum_j p(y_k|s_k^j)/\eta^{a^j}`
    after resampling.

    Parameters and return as :func:`bootstrap_filter`; the model must also declare a
    look-ahead (``transition_mean``, ``lookahead`` or ``log_eta``).
    """
    return _particle_filter(model, num_particles, resampler, ess_threshold, dtype, _auxiliary_stage)


def _scan(
    key: Array,
    state: ParticleState,
    observations: Any,
    actions: Any,
    pf: ParticleFilter,
    summary: Callable[[ParticleState], Any] | None,
    keep_ancestors: bool,
):
    num_steps = jax.tree_util.tree_leaves(observations)[0].shape[0]
    keys = jax.random.split(key, num_steps)
    # Prefetch: the loop carries step k's inputs and slices step k+1's. Consumers then read
    # a loop-carried buffer instead of a dynamic slice, which XLA on CPU would otherwise fuse
    # into every per-particle loop (measured 1.8x slower).
    inputs = (observations, actions)
    first = jax.tree_util.tree_map(lambda a: a[0], inputs)
    shifted = jax.tree_util.tree_map(lambda a: jnp.concatenate([a[1:], a[:1]]), inputs)

    def body(carry, inp):
        state, (obs, act) = carry
        k, nxt = inp
        new, info = pf.step(k, state, obs, act)
        if not keep_ancestors:
            info = info._replace(ancestors=None)
        out = summary(new) if summary is not None else None
        return (new, nxt), (info, out)

    (final, _), (infos, outs) = jax.lax.scan(body, (state, first), (keys, shifted))
    return final, infos, outs


_run = partial(jax.jit, static_argnames=("pf", "summary", "keep_ancestors"))(_scan)
_STATIC = ("algorithm", "num_particles", "resampler", "ess_threshold", "dtype", "summary",
           "keep_ancestors")  # fmt: skip


@partial(jax.jit, static_argnames=_STATIC)
def _run_model(key, state, observations, actions, model, algorithm, num_particles, resampler,
               ess_threshold, dtype, summary, keep_ancestors):  # fmt: skip
    pf = algorithm(model, num_particles, resampler=resampler, ess_threshold=ess_threshold,
                   dtype=dtype)  # fmt: skip
    return _scan(key, state, observations, actions, pf, summary, keep_ancestors)


def run(
    key: Array,
    pf: ParticleFilter,
    observations: Any,
    actions: Any = None,
    *,
    initial_state: ParticleState | None = None,
    summary: Callable[[ParticleState], Any] | None = weighted_mean,
    keep_ancestors: bool = False,
) -> tuple[ParticleState, ParticleInfo, Any]:
    """Run a filter over ``num_timesteps`` steps with ``lax.scan`` (jit-compiled).

    Parameters
    ----------
    key : PRNG key
        Split into the initial draw (unless ``initial_state`` is given) and one key per step.
    pf : ParticleFilter
        From :func:`bootstrap_filter` or :func:`auxiliary_filter`.
    observations : pytree of arrays, leading axis num_timesteps
    actions : pytree of arrays with leading axis num_timesteps, or None
    initial_state : ParticleState, optional
        Start here instead of ``pf.init``.
    summary : callable, optional
        ``ParticleState -> pytree`` recorded after every step (default the weighted mean,
        shape ``(num_timesteps, state_dim)``); ``None`` records nothing.
    keep_ancestors : bool
        Keep the ``(num_timesteps, num_particles)`` ancestor table in the infos.

    Returns
    -------
    final_state : ParticleState
    infos : ParticleInfo
        Stacked over time (``ancestors`` is None unless ``keep_ancestors``).
    summaries : pytree
        ``summary`` of each filtered state, stacked over time.

    Raises
    ------
    InputError, ShapeError, ModelError
        A bad key (:func:`check_key`), observations and actions without one leading
        axis of at least one step (:func:`check_run_inputs`), or ``pf`` not a
        :class:`ParticleFilter`.
    """
    check_key(key)
    if not isinstance(pf, ParticleFilter):  # else AttributeError: no attribute 'dtype'
        raise ModelError(f"pf must be a ParticleFilter (bootstrap_filter, auxiliary_filter), "
                         f"got {type(pf).__name__}")  # fmt: skip
    check_run_inputs(observations, actions)
    if summary is not None and not callable(summary):  # else Python's TypeError in the scan
        raise InputError(f"summary must be a function ParticleState -> pytree or None, got "
                         f"{summary!r:.60}")  # fmt: skip
    with precision_scope(pf.dtype):
        k0, k_steps = jax.random.split(key)
        state = pf.init(k0) if initial_state is None else initial_state
        return _run(k_steps, state, observations, actions, pf, summary, keep_ancestors)


def run_model(
    key: Array,
    model: StateSpaceModel,
    observations: Any,
    actions: Any = None,
    *,
    algorithm: Callable[..., ParticleFilter] = bootstrap_filter,
    num_particles: int,
    resampler: Resampler = systematic,
    ess_threshold: float = 0.5,
    dtype: Any = jnp.float64,
    initial_state: ParticleState | None = None,
    summary: Callable[[ParticleState], Any] | None = weighted_mean,
    keep_ancestors: bool = False,
) -> tuple[ParticleState, ParticleInfo, Any]:
    """:func:`run` of ``algorithm(model, num_particles, ...)`` with the model's parameters
    traced, not compiled in: one compilation serves every model of a registered class
    (:func:`~inference.particle.model.register_model`) for each shape of the inputs and
    each setting (a parameter search over ``M`` models compiles once, not ``M`` times).

    The same keys as :func:`run` (``key`` split into the initial draw, made here before
    tracing, and one key per step), so the same filter up to rounding: constants folded
    by the compiler and traced values may differ in the last bit.

    Parameters
    ----------
    model : StateSpaceModel
        An instance of a class registered with :func:`~inference.particle.model.register_model`.
    algorithm : callable
        :func:`bootstrap_filter` or :func:`auxiliary_filter` (static, as are
        ``num_particles``, ``resampler``, ``ess_threshold``, ``dtype`` and ``summary``: pass
        module-level functions, a new lambda each call recompiles).
    Others as :func:`run`.

    Returns
    -------
    As :func:`run`.

    Raises
    ------
    ModelError
        ``model``'s class is not registered (use :func:`run`).
    InputError, ShapeError
        As :func:`run`.
    """
    from inference.particle.model import is_registered_model

    if not is_registered_model(model):
        raise ModelError(f"run_model: {type(model).__name__} is not registered as a pytree "
                         "(inference.particle.model.register_model); use run")  # fmt: skip
    check_key(key)
    check_run_inputs(observations, actions)
    # the settings checked on the host, before tracing
    pf = algorithm(model, num_particles, resampler=resampler, ess_threshold=ess_threshold,
                   dtype=dtype)  # fmt: skip
    with precision_scope(dtype):
        k0, k_steps = jax.random.split(key)
        state = pf.init(k0) if initial_state is None else initial_state
        return _run_model(k_steps, state, observations, actions, model, algorithm,
                          check_num_particles(num_particles), resampler, float(ess_threshold),
                          dtype, summary, keep_ancestors)  # fmt: skip
