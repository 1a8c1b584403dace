"""Particle filters: bootstrap (SIR) and auxiliary (seed 002, section 1.3.1), resamplers, ESS.

Usage::

    pf = auxiliary_filter(model, num_particles=1000, dtype=jnp.float32)
    final, infos, means = run(jax.random.key(0), pf, observations, actions)
    log_evidence = infos.log_likelihood.sum()

A model class registered with :func:`register_model` (its parameters as pytree leaves) runs
through :func:`run_model` instead: ``run_model(key, model, observations, actions,
algorithm=auxiliary_filter, num_particles=1000)`` traces the parameters, so a search over
many models of the class compiles once per shape of its data.

Models whose particles are ragged host data (numpy) use the same machinery from
:mod:`inference.particle.numpy_path` (log normalisation, ESS, resamplers with a numpy
``Generator``), :mod:`inference.particle.numpy_filter` (the SIR step
:func:`~inference.particle.numpy_filter.sir_step` over the model's predict, weight and
move functions, and :func:`~inference.particle.numpy_filter.run_steps`) and
:func:`k_best_states` (the k distinct states of largest mass).
"""

from inference.particle.filters import (
    ParticleFilter,
    ParticleInfo,
    ParticleState,
    auxiliary_filter,
    bootstrap_filter,
    ess,
    run,
    run_model,
    weighted_cov,
    weighted_mean,
)
from inference.particle.kbest import k_best_states
from inference.particle.linear_gaussian import LinearGaussianSSM
from inference.particle.model import StateSpaceModel, is_registered_model, register_model
from inference.particle.resampling import (
    RESAMPLERS,
    multinomial,
    normalized_weights,
    residual,
    stratified,
    systematic,
)

__all__ = [
    "ParticleFilter",
    "ParticleInfo",
    "ParticleState",
    "StateSpaceModel",
    "LinearGaussianSSM",
    "auxiliary_filter",
    "bootstrap_filter",
    "ess",
    "run",
    "run_model",
    "register_model",
    "is_registered_model",
    "weighted_cov",
    "k_best_states",
    "weighted_mean",
    "RESAMPLERS",
    "multinomial",
    "normalized_weights",
    "residual",
    "stratified",
    "systematic",
]
