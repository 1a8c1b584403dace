"""Arguments of the particle filters and of the linear-Gaussian model: refused naming them
before any tracing, or taken as documented (a resampler by name, a singular ``Q``)."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from dbn.errors import InputError, ModelError, ShapeError
from inference.kalman import LinearGaussianParams, kalman_filter, lgssm_sample
from inference.particle import (
    RESAMPLERS,
    LinearGaussianSSM,
    auxiliary_filter,
    bootstrap_filter,
    run,
    weighted_mean,
)

I2 = np.eye(2)
PARAMS = LinearGaussianParams(F=np.array([[1.0, 0.1], [0.0, 1.0]]), Q=np.diag([0.05, 0.0]),
                              H=np.array([[1.0, 0.0]]), R=np.array([[0.2]]), m0=np.zeros(2),
                              P0=np.diag([1.0, 0.0]))  # fmt: skip


def test_a_resampler_by_name_is_that_resampler() -> None:
    from inference.particle.filters import check_resampler

    assert all(check_resampler(name) is fn for name, fn in RESAMPLERS.items())
    name = "stratified"  # not the default: the run below could tell them apart
    _, ys = lgssm_sample(0, PARAMS, 5)
    model, key = LinearGaussianSSM(PARAMS), jax.random.key(3)
    by_name = run(key, bootstrap_filter(model, 64, resampler=name, ess_threshold=1.0), ys)
    by_fn = run(key, bootstrap_filter(model, 64, resampler=RESAMPLERS[name], ess_threshold=1.0),
                ys)  # fmt: skip
    np.testing.assert_array_equal(by_name[2], by_fn[2])


@pytest.mark.parametrize(("kwargs", "needle"), [
    ({"resampler": "sytematic"}, "resampler must be one of"),
    ({"resampler": 3}, "resampler must be one of"),
    ({"dtype": jnp.int32}, "dtype must be a float dtype"),
    ({"dtype": "text"}, "dtype must be a float dtype"),
])  # fmt: skip
@pytest.mark.parametrize("algorithm", [bootstrap_filter, auxiliary_filter])
def test_bad_filter_arguments_are_refused_naming_them(algorithm, kwargs, needle) -> None:
    """A resampler's name was taken and then failed inside the traced step ("'str' object
    is not callable"); an int32 filter failed inside the model's first draw."""
    with pytest.raises(InputError, match=needle):
        algorithm(LinearGaussianSSM(PARAMS), 16, **kwargs)


def test_a_singular_transition_noise_filters_as_the_kalman_filter() -> None:
    """A noise-free component (``Q``, ``P0`` singular: positive semi-definite, as the
    Kalman filter takes them) raised numpy's LinAlgError from the model's Cholesky."""
    _, ys = lgssm_sample(1, PARAMS, 10)
    kf = kalman_filter(PARAMS, ys)
    pf = bootstrap_filter(LinearGaussianSSM(PARAMS), 20000)
    _, _, means = run(jax.random.key(0), pf, ys, summary=weighted_mean)
    sd = np.sqrt(np.diagonal(kf.filtered_covs, axis1=1, axis2=2)[:, 0])
    assert np.all(np.abs(np.asarray(means)[:, 0] - kf.filtered_means[:, 0]) < 4 * sd / 10)


@pytest.mark.parametrize(("field", "value", "error", "needle"), [
    ("Q", -I2, InputError, "Q is not positive semi-definite"),
    ("R", np.zeros((1, 1)), InputError, "R must be positive definite"),
    ("F", np.eye(3), ShapeError, "F has shape (3, 3)"),
    ("m0", [0.0, np.nan], InputError, "m0[1] = nan is not finite"),
])  # fmt: skip
def test_bad_model_parameters_are_refused_naming_them(field, value, error, needle) -> None:
    with pytest.raises(error) as exc:
        LinearGaussianSSM(PARAMS._replace(**{field: value}))
    assert needle in str(exc.value)


@pytest.mark.parametrize(("kwargs", "needle"), [
    ({"observations": np.zeros((4, 1)) + 0j}, "observations leaf 0 has dtype complex128"),
    ({"observations": np.full((4, 1), "x")}, "observations leaf 0 has dtype <U1"),
    ({"actions": np.full((4, 1), "x")}, "actions leaf 0 has dtype <U1"),
    ({"summary": "mean"}, "summary must be a function ParticleState -> pytree or None"),
])  # fmt: skip
def test_run_refuses_observations_that_are_not_real_numbers(kwargs, needle) -> None:
    """Complex observations ran (the likelihood took a complex residual), text raised jax's
    TypeError from lax.scan, and a summary of 'mean' Python's TypeError."""
    pf = bootstrap_filter(LinearGaussianSSM(PARAMS), 8)
    args = {"observations": np.zeros((4, 1)), **kwargs}
    with pytest.raises(InputError) as exc:
        run(jax.random.key(0), pf, **args)
    assert needle in str(exc.value)
    run(jax.random.key(0), pf, np.zeros((4, 1), dtype=int), summary=None)  # ints are numbers


def test_a_models_parameters_cannot_be_swapped_after_construction() -> None:
    """``model.params = other`` was accepted while the model kept drawing with the old
    square roots and matrices (and a compiled filter keeps them too): a silently wrong
    model. Now an InputError that says to build a new model; the model is unchanged."""
    model = LinearGaussianSSM(PARAMS)
    with pytest.raises(InputError, match="fixed at construction"):
        model.params = PARAMS._replace(F=2 * I2)
    assert model.params is not None and np.array_equal(model.params.F, PARAMS.F)
    x = jnp.ones((3, 2))
    assert np.allclose(model.transition_mean(x, None), x @ PARAMS.F.T)


def test_an_observation_of_another_dimension_is_refused() -> None:
    """``(T, 1)`` observations of a 2-D model broadcast against ``H s`` and ran."""
    two = PARAMS._replace(H=I2, R=0.1 * I2)
    with pytest.raises(ShapeError, match=r"an observation has shape \(1,\), expected \(2,\)"):
        run(jax.random.key(0), bootstrap_filter(LinearGaussianSSM(two), 8), np.zeros((4, 1)))


def test_lgssm_sample_checks_its_arguments() -> None:
    xs, ys = lgssm_sample(0, PARAMS, 0)
    assert xs.shape == (0, 2) and ys.shape == (0, 1)
    for args, needle in (((-1, PARAMS, 3), "seed"), ((jax.random.key(0), PARAMS, 3), "seed"),
                         ((0, PARAMS, -1), "num_timesteps"), ((0, PARAMS, 2.5), "num_timesteps"),
                         ((0, PARAMS._replace(Q=-I2), 2), "Q is not positive")):  # fmt: skip
        with pytest.raises(InputError, match=needle):
            lgssm_sample(*args)


class _Walk:
    """A model by duck typing (no StateSpaceModel base): a Gaussian random walk."""

    def sample_initial(self, key, num_particles, dtype):
        return jax.random.normal(key, (num_particles, 1), dtype)

    def sample_transition(self, key, particles, action):
        return particles + jax.random.normal(key, particles.shape, particles.dtype)

    def log_likelihood(self, particles, observation):
        return -0.5 * jnp.sum((particles - observation) ** 2, axis=-1)


def test_a_model_or_filter_of_another_kind_is_refused_naming_it() -> None:
    """bootstrap_filter(None) built a filter whose init raised AttributeError ('NoneType'
    object has no attribute 'sample_initial'); run(key, None) raised "no attribute
    'dtype'". A model needs the three methods a filter calls, whatever its class."""
    for bad in (None, 5, {}, object()):
        for algorithm in (bootstrap_filter, auxiliary_filter):
            with pytest.raises(ModelError, match="model must be a StateSpaceModel.*lacks"):
                algorithm(bad, 10)
        with pytest.raises(ModelError, match="pf must be a ParticleFilter"):
            run(jax.random.key(0), bad, np.zeros((3, 1)))
    _, _, means = run(jax.random.key(0), bootstrap_filter(_Walk(), 50), np.zeros((3, 1)))
    assert np.asarray(means).shape == (3, 1) and np.all(np.isfinite(np.asarray(means)))
