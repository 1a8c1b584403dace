"""Bootstrap and auxiliary particle filters against the Kalman filter (the oracle).

Monte Carlo tolerances come from the spread over independent seeds: a seed-averaged
estimate must lie within 4 standard errors of the Kalman value.
"""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from inference.kalman import LinearGaussianParams, kalman_filter, lgssm_sample
from inference.particle import (
    LinearGaussianSSM,
    StateSpaceModel,
    auxiliary_filter,
    bootstrap_filter,
    run,
    systematic,
    weighted_cov,
    weighted_mean,
)

ALGOS = {"sir": bootstrap_filter, "apf": auxiliary_filter}


def _params() -> LinearGaussianParams:
    return LinearGaussianParams(
        F=np.array([[1.0, 0.5], [0.0, 0.8]]),
        Q=np.array([[0.2, 0.05], [0.05, 0.3]]),
        H=np.array([[1.0, 0.0]]),
        R=np.array([[0.4]]),
        m0=np.array([0.5, -0.3]),
        P0=np.array([[1.0, 0.2], [0.2, 0.5]]),
    )


@pytest.fixture(scope="module")
def lg_data():
    params = _params()
    _, ys = lgssm_sample(42, params, 12)
    return params, ys, kalman_filter(params, ys)


def _moments(state):
    return weighted_mean(state), weighted_cov(state)


@pytest.mark.parametrize("algo", sorted(ALGOS))
def test_filtered_moments_match_kalman(algo: str, lg_data) -> None:
    params, ys, kf = lg_data
    pf = ALGOS[algo](LinearGaussianSSM(params), 2000, ess_threshold=0.5)
    reps = 32
    keys = jax.random.split(jax.random.key(1), reps)
    _, infos, (means, covs) = jax.vmap(lambda k: run(k, pf, jnp.asarray(ys), summary=_moments))(
        keys
    )
    means, covs = np.asarray(means), np.asarray(covs)
    for est, ref in ((means, kf.filtered_means), (covs, kf.filtered_covs)):
        avg = est.mean(0)
        se = est.std(0, ddof=1) / np.sqrt(reps)
        z = np.abs(avg - ref) / se
        assert np.all(z < 4.0), f"max z-score {z.max():.2f}"
    # and a single run is close too: within 5 posterior sd / sqrt(ESS-ish N/10)
    sd = np.sqrt(np.diagonal(kf.filtered_covs, axis1=1, axis2=2))
    assert np.all(np.abs(means[0] - kf.filtered_means) < 5 * sd / np.sqrt(200))
    assert bool(np.any(np.asarray(infos.resampled)))


@pytest.mark.parametrize("algo", sorted(ALGOS))
def test_likelihood_estimate_is_unbiased(algo: str, lg_data) -> None:
    params, ys, kf = lg_data
    pf = ALGOS[algo](LinearGaussianSSM(params), 200, ess_threshold=0.5)
    reps = 400
    keys = jax.random.split(jax.random.key(7), reps)
    _, infos, _ = jax.vmap(lambda k: run(k, pf, jnp.asarray(ys), summary=None))(keys)
    log_z = np.asarray(infos.log_likelihood).sum(axis=1)
    ratio = np.exp(log_z - kf.log_likelihood)  # E[Z_hat / Z] = 1
    se = ratio.std(ddof=1) / np.sqrt(reps)
    assert abs(ratio.mean() - 1.0) <= 3 * se, (ratio.mean(), se)
    # log Z_hat is biased downward but close: a sanity check that could fail
    assert abs(np.median(log_z) - kf.log_likelihood) < 0.5


@pytest.mark.parametrize("algo", sorted(ALGOS))
def test_step_jit_equals_eager(algo: str, lg_data) -> None:
    params, ys, _ = lg_data
    pf = ALGOS[algo](LinearGaussianSSM(params), 64, ess_threshold=1.0, resampler=systematic)
    state = pf.init(jax.random.key(0))
    key = jax.random.key(9)
    eager_state, eager_info = pf.step(key, state, jnp.asarray(ys[0]))
    jit_state, jit_info = jax.jit(pf.step)(key, state, jnp.asarray(ys[0]))
    np.testing.assert_allclose(eager_state.particles, jit_state.particles, rtol=1e-12)
    np.testing.assert_allclose(eager_state.log_weights, jit_state.log_weights, atol=1e-12)
    np.testing.assert_array_equal(eager_info.ancestors, jit_info.ancestors)
    assert float(eager_info.log_likelihood) == pytest.approx(float(jit_info.log_likelihood))
    assert bool(eager_info.resampled)
    assert float(jax.scipy.special.logsumexp(eager_state.log_weights)) == pytest.approx(
        0.0, abs=1e-12
    )


@pytest.mark.parametrize("algo", sorted(ALGOS))
def test_float32_is_kept_and_same_seed_same_result(algo: str, lg_data) -> None:
    params, ys, kf = lg_data
    pf = ALGOS[algo](LinearGaussianSSM(params), 5000, dtype=jnp.float32)
    final, infos, means = run(jax.random.key(3), pf, jnp.asarray(ys, jnp.float32))
    assert final.particles.dtype == jnp.float32 and final.log_weights.dtype == jnp.float32
    assert means.dtype == jnp.float32
    sd = np.sqrt(np.diagonal(kf.filtered_covs, axis1=1, axis2=2))
    assert np.all(np.abs(np.asarray(means) - kf.filtered_means) < 5 * sd / np.sqrt(500))
    _, infos2, means2 = run(jax.random.key(3), pf, jnp.asarray(ys, jnp.float32))
    np.testing.assert_array_equal(np.asarray(means), np.asarray(means2))


def test_never_resampling_is_importance_sampling(lg_data) -> None:
    params, ys, _ = lg_data
    pf = bootstrap_filter(LinearGaussianSSM(params), 100, ess_threshold=0.0)
    _, infos, _ = run(jax.random.key(0), pf, jnp.asarray(ys), keep_ancestors=True)
    assert not np.any(np.asarray(infos.resampled))
    np.testing.assert_array_equal(
        np.asarray(infos.ancestors), np.tile(np.arange(100), (len(ys), 1))
    )


class _Hopeless(LinearGaussianSSM):
    """Every particle gets likelihood zero: the filter must not produce NaN."""

    def log_likelihood(self, particles, observation):
        return jnp.full(particles.shape[0], -jnp.inf, particles.dtype)


@pytest.mark.parametrize("algo", sorted(ALGOS))
def test_all_zero_likelihoods_do_not_poison_the_state(algo: str, lg_data) -> None:
    params, ys, _ = lg_data
    pf = ALGOS[algo](_Hopeless(params), 50)
    final, infos, means = run(jax.random.key(0), pf, jnp.asarray(ys[:3]))
    assert np.all(np.isneginf(np.asarray(infos.log_likelihood)))
    assert np.all(np.isfinite(np.asarray(final.particles)))
    np.testing.assert_allclose(np.asarray(final.log_weights), -np.log(50))


def test_apf_needs_a_lookahead() -> None:
    class NoMean(StateSpaceModel):
        def sample_initial(self, key, num_particles, dtype):
            return jnp.zeros((num_particles, 1), dtype)

        def sample_transition(self, key, particles, action):
            return particles

        def log_likelihood(self, particles, observation):
            return jnp.zeros(particles.shape[0], particles.dtype)

    pf = auxiliary_filter(NoMean(), 4)
    with pytest.raises(NotImplementedError, match="transition_mean"):
        pf.step(jax.random.key(0), pf.init(jax.random.key(1)), jnp.zeros(1))


@pytest.mark.parametrize("bad", [float("nan"), -1.0, "0.5", True])
def test_bad_threshold(bad) -> None:
    with pytest.raises(ValueError, match="ess_threshold"):
        bootstrap_filter(LinearGaussianSSM(_params()), 10, ess_threshold=bad)


# ~8 s each (both filters' Kalman moments, unbiased likelihoods and the bootstrap
# equivalence stay in the default run): CI runs them
@pytest.mark.heavy
@pytest.mark.parametrize("algo", ["apf", "sir"])
def test_error_shrinks_like_one_over_n(algo: str, lg_data) -> None:
    """Mean squared error of the filtered mean against Kalman falls ~16x for 16x particles."""
    params, ys, kf = lg_data
    reps = 24
    keys = jax.random.split(jax.random.key(11), reps)
    mse = []
    for n in (150, 2400):
        pf = ALGOS[algo](LinearGaussianSSM(params), n)
        _, _, means = jax.vmap(lambda k, pf=pf: run(k, pf, jnp.asarray(ys)))(keys)
        mse.append(np.mean((np.asarray(means) - kf.filtered_means) ** 2))
    # 1/N scaling predicts a ratio of 16; accept anything above 6 (Monte Carlo spread)
    assert mse[0] / mse[1] > 6.0, mse


class _FlatLookahead(LinearGaussianSSM):
    """A look-ahead that says nothing: eta = 1 for every particle."""

    def log_eta(self, particles, observation, action):
        return jnp.zeros(particles.shape[0], particles.dtype)


@functools.cache
def _sir_and_flat_apf(threshold: float) -> tuple:
    """One pair of filters per threshold, so that the examples share their compiled runs."""
    params = _params()
    return (bootstrap_filter(LinearGaussianSSM(params), 64, ess_threshold=threshold),
            auxiliary_filter(_FlatLookahead(params), 64, ess_threshold=threshold))


@settings(max_examples=12, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), threshold=st.sampled_from([0.0, 0.5, 1.0]))
def test_apf_with_a_flat_lookahead_is_the_bootstrap_filter(seed: int, threshold: float) -> None:
    """Eqs. 1.12-1.13 with eta = 1: first-stage weights are pi_{k-1}, a drawn particle
    weighs 1/N, so the auxiliary filter makes the bootstrap filter's draws (same keys,
    same ancestors) and its weights up to the rounding of logsumexp(pi_{k-1}) = 0."""
    _, ys = lgssm_sample(seed % 1000, _params(), 8)
    key = jax.random.key(seed)
    runs = [run(key, pf, jnp.asarray(ys), keep_ancestors=True) for pf in _sir_and_flat_apf(threshold)]
    (sir_final, sir_infos, sir_means), (apf_final, apf_infos, apf_means) = runs
    np.testing.assert_array_equal(np.asarray(sir_infos.ancestors), np.asarray(apf_infos.ancestors))
    np.testing.assert_array_equal(np.asarray(sir_infos.resampled), np.asarray(apf_infos.resampled))
    np.testing.assert_allclose(np.asarray(apf_final.log_weights), np.asarray(sir_final.log_weights),
                               atol=1e-9)
    np.testing.assert_allclose(np.asarray(apf_infos.log_likelihood),
                               np.asarray(sir_infos.log_likelihood), atol=1e-9)
    np.testing.assert_allclose(np.asarray(apf_means), np.asarray(sir_means), atol=1e-9)
