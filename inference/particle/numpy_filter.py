r"""Sequential importance resampling (SIR) for numpy particle models: one step and a run.

Some particle models are ragged host data (seed 001's path-recovery filter: cameras, look-ups
of each camera's observations, features). They supply three functions and this module
does the rest, the same way at every step. With particles :math:`x^{1:N}_{t-1}` and
normalised log weights :math:`\log W_{t-1}` (a :class:`ParticleState`), one
:func:`sir_step` does, in this order (the order the generator is consumed in):

1. **predict**: :math:`x^i_t \sim f(\cdot | x^i_{t-1})`, the model's
   ``predict(rng, particles) -> particles``;
2. **weight**: :math:`\log g^i_t`, the model's
   ``weight(rng, particles) -> (particles, log_g, aux)``. It may change particle fields
   as it weighs them (seed 001, sec. 4.1.3: a particle's feature becomes its associated
   observation's with probability ``P_update``) and may return anything as ``aux``;
3. **normalise** in log space: :math:`\log w^i = \log W^i_{t-1} + \log g^i_t`,
   :math:`\log W^i_t = \log w^i - \log \sum_j w^j`. The step's score
   :math:`\log \sum_i w^i` estimates :math:`\log p(y_t | y_{1:t-1})`
   (seed 002, eq. 1.7; ``-inf`` when every weight is zero, and then the weights fall
   back to uniform);
4. **resample** when :math:`\mathrm{ESS}(W_t) < \tau N` (``ess_threshold`` :math:`\tau`;
   the default :math:`\tau = 1` resamples at every step, as seed 001's filter does):
   ancestors :math:`a \sim` ``resample(rng, log W_t, N)`` (any
   :data:`inference.particle.numpy_path.NUMPY_RESAMPLERS` entry), :math:`x \leftarrow x^a`,
   weights uniform :math:`-\log N`. Otherwise the particles keep their rows and weights
   :math:`\log W_t` (ancestors :math:`0..N-1`) and the generator is not drawn from;
5. **move** (optional): the model's ``move(rng, particles) -> particles`` applied to the
   particles after step 4, resampled or not (seed 001, sec. 4.1.6: diffusion and feature
   switching; an MCMC move that leaves the filtering law invariant).

Particles are any pytree of numpy arrays whose leaves share the leading axis
``num_particles`` (a NamedTuple of arrays, a dict, one array); rows are taken with
``leaf[ancestors]``. Nothing is modified in place: the model's functions must return new
arrays, and the step never writes into its inputs.

:func:`run_steps` calls a step function over a sequence of observations with one
generator, and records every step's info and wall time.

Usage (a 2-state HMM with Gaussian emissions)::

    import numpy as np
    from inference.particle import ParticleState
    from inference.particle.numpy_filter import run_steps, sir_step

    A = np.array([[0.9, 0.1], [0.2, 0.8]])  # transition matrix
    means = np.array([-1.0, 1.0])

    def predict(rng, x):  # x: (N,) int states
        return (rng.random(x.size) < A[x, 1]).astype(np.int64)

    def step(rng, state, y):
        weight = lambda r, x: (x, -0.5 * (y - means[x]) ** 2, None)
        return sir_step(rng, state, predict, weight)

    n = 1000
    state = ParticleState(np.zeros(n, np.int64), np.full(n, -np.log(n)))
    final, infos, seconds = run_steps(np.random.default_rng(0), step, state, [0.8, 1.1, -0.9])
    p_state1 = [np.exp(i.log_weights) @ i.particles for i in infos]  # P(x_t = 1 | y_1:t)
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable
from typing import Any, NamedTuple

import jax
import numpy as np

from dbn.errors import InputError, ShapeError
from inference.particle.filters import ParticleState, check_threshold
from inference.particle.numpy_path import NumpyResampler, ess, log_normalise, systematic

__all__ = ["SIRInfo", "sir_step", "run_steps", "take_rows"]

Predict = Callable[[np.random.Generator, Any], Any]
Weight = Callable[[np.random.Generator, Any], tuple[Any, np.ndarray, Any]]
Move = Callable[[np.random.Generator, Any], Any]


class SIRInfo(NamedTuple):
    """What one :func:`sir_step` did.

    Attributes
    ----------
    particles : pytree, leading axis num_particles
        The weighted particles of step ``t`` before resampling (as ``weight`` returned them).
    log_weights : (num_particles,) float64
        Their normalised log weights :math:`\\log W_t` (``-inf`` for a zero weight; uniform
        when every weight is zero).
    log_score : float
        :math:`\\log \\sum_i W^i_{t-1} g^i_t`; ``-inf`` when every weight is zero.
    ess : float
        Effective sample size of :math:`W_t`, in particles.
    ancestors : (num_particles,) int64
        Row of ``particles`` each new particle was taken from (``0..N-1`` when the step
        did not resample).
    aux : Any
        What the model's ``weight`` returned beside the weights.
    resampled : bool
        Whether the step resampled (always, for ``ess_threshold >= 1``).
    """

    particles: Any
    log_weights: np.ndarray
    log_score: float
    ess: float
    ancestors: np.ndarray
    aux: Any
    resampled: bool = True


def _num_rows(particles: Any, who: str, n: int) -> None:
    """Raise :class:`ShapeError` unless every leaf of ``particles`` has ``n`` rows."""
    for leaf in jax.tree_util.tree_leaves(particles):
        shape = np.shape(leaf)
        if not shape or shape[0] != n:
            raise ShapeError(f"{who} returned a particle array of shape {shape}; expected {n} rows")


def take_rows(particles: Any, rows: np.ndarray) -> Any:
    """``particles`` with every leaf indexed by ``rows`` (same pytree structure)."""
    return jax.tree_util.tree_map(lambda leaf: np.asarray(leaf)[rows], particles)


def sir_step(
    rng: np.random.Generator,
    state: ParticleState,
    predict: Predict,
    weight: Weight,
    *,
    resample: NumpyResampler = systematic,
    move: Move | None = None,
    ess_threshold: float = 1.0,
) -> tuple[ParticleState, SIRInfo]:
    r"""One SIR step (module docstring: predict, weight, normalise, resample, move).

    Parameters
    ----------
    rng : numpy Generator, consumed by ``predict``, ``weight``, ``resample``, ``move`` in
        that order (same generator state, same result).
    state : ParticleState whose ``particles`` is a pytree of (num_particles, ...) numpy
        arrays and ``log_weights`` their (num_particles,) normalised log weights.
    predict : ``(rng, particles) -> particles``, the transition.
    weight : ``(rng, particles) -> (particles, log_g, aux)``: ``log_g`` is the
        (num_particles,) log potential (NaN is read as ``-inf``).
    resample : ``(rng, log_weights, n) -> ancestors`` (default systematic).
    move : ``(rng, particles) -> particles`` applied after step 4, or None.
    ess_threshold : float >= 0
        Resample when the ESS of :math:`W_t` is below ``ess_threshold * num_particles``;
        ``>= 1`` (the default) resamples at every step, 0 never does.

    Returns
    -------
    (ParticleState at ``t``: uniform weights after resampling, :math:`\log W_t` otherwise;
    :class:`SIRInfo`).

    Raises
    ------
    ShapeError
        When ``state``'s weights or a function's particles or ``log_g`` do not have
        ``num_particles`` rows (``state`` is never modified).
    InputError
        When ``ess_threshold`` is not a number >= 0, before anything is drawn.
    """
    check_threshold(ess_threshold)
    log_prev = np.asarray(state.log_weights, dtype=np.float64)
    if log_prev.ndim != 1 or log_prev.size == 0:
        raise ShapeError(f"state.log_weights must be 1-D and non-empty, got shape {log_prev.shape}")
    n = log_prev.size
    _num_rows(state.particles, "state.particles", n)
    particles = predict(rng, state.particles)
    _num_rows(particles, "predict", n)
    particles, log_g, aux = weight(rng, particles)
    _num_rows(particles, "weight", n)
    log_g = np.asarray(log_g, dtype=np.float64)
    if log_g.shape != (n,):
        raise ShapeError(f"weight returned log_g of shape {log_g.shape}; expected ({n},)")
    log_w, log_score = log_normalise(log_prev + log_g)
    cur_ess = ess(log_w)
    resampled = bool(ess_threshold >= 1.0 or cur_ess < ess_threshold * n)
    if resampled:
        ancestors = np.asarray(resample(rng, log_w, n))
        if ancestors.shape != (n,):
            shape = ancestors.shape
            raise ShapeError(f"resample returned ancestors of shape {shape}; expected ({n},)")
        new, new_lw = take_rows(particles, ancestors), np.full(n, -np.log(n))
    else:
        ancestors, new, new_lw = np.arange(n, dtype=np.int64), particles, log_w
    if move is not None:
        new = move(rng, new)
        _num_rows(new, "move", n)
    info = SIRInfo(particles, log_w, log_score, cur_ess, ancestors, aux, resampled)
    return ParticleState(new, new_lw), info


def run_steps(
    rng: np.random.Generator,
    step: Callable[[np.random.Generator, Any, Any], tuple[Any, Any]],
    state: Any,
    observations: Iterable[Any],
    *,
    progress: bool = False,
    desc: str = "particle filter",
) -> tuple[Any, list[Any], np.ndarray]:
    """Run ``step(rng, state, obs) -> (state, info)`` over ``observations`` in order.

    Parameters
    ----------
    rng : numpy Generator shared by every step (one stream: the same seed, the same run).
    step : one filter step, e.g. a closure over :func:`sir_step` and a model.
    state : the state before the first observation.
    observations : iterable of per-step observations (a sized one gives a progress total).
    progress : show a tqdm progress bar named ``desc``.

    Returns
    -------
    (final state, list of every step's info, (num_steps,) float64 wall seconds per step).
    """
    if not isinstance(rng, np.random.Generator):
        raise InputError(f"rng must be a numpy Generator, got {type(rng).__name__}")
    if progress:
        from inference.progress import progress_bar

        observations = progress_bar(observations, desc=desc)
    infos, seconds = [], []
    for obs in observations:
        t0 = time.perf_counter()
        state, info = step(rng, state, obs)
        seconds.append(time.perf_counter() - t0)
        infos.append(info)
    return state, infos, np.asarray(seconds, dtype=np.float64)
