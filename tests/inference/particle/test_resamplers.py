"""Resamplers: one signature, unbiased counts, and survival of degenerate weights."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from inference.particle import RESAMPLERS, normalized_weights

NAMES = sorted(RESAMPLERS)


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("fill", [-jnp.inf, jnp.nan])
def test_all_zero_weights_fall_back_to_uniform(name: str, fill: float) -> None:
    n = 4000
    lw = jnp.full((8,), fill)
    anc = np.asarray(jax.jit(RESAMPLERS[name], static_argnums=2)(jax.random.key(3), lw, n))
    assert anc.shape == (n,) and anc.dtype == np.int32
    assert anc.min() >= 0 and anc.max() < 8
    counts = np.bincount(anc, minlength=8)
    # uniform: each count is n/8 = 500 with sd <= sqrt(500) ~ 22 (multinomial, the worst)
    assert np.all(np.abs(counts - n / 8) <= 5 * np.sqrt(n / 8))


@pytest.mark.parametrize("name", NAMES)
def test_underflowing_weights_resample_like_shifted_ones(name: str) -> None:
    # n * w stays away from integers, so float rounding of the shift cannot flip a floor
    lw = jnp.log(jnp.array([0.13, 0.0, 0.52, 0.35]))
    key = jax.random.key(11)
    a = RESAMPLERS[name](key, lw, 47)
    b = RESAMPLERS[name](key, lw - 1e4, 47)  # exp(-1e4) underflows to 0
    np.testing.assert_array_equal(np.asarray(a), np.asarray(b))
    assert not np.any(np.asarray(a) == 1)


@pytest.mark.parametrize("name", NAMES)
def test_single_positive_weight(name: str) -> None:
    lw = jnp.array([-jnp.inf, -jnp.inf, -3.0, -jnp.inf])
    anc = np.asarray(RESAMPLERS[name](jax.random.key(0), lw, 17))
    assert np.all(anc == 2)


@pytest.mark.parametrize("name", NAMES)
def test_counts_are_unbiased(name: str) -> None:
    w = np.array([0.05, 0.3, 0.0, 0.15, 0.27, 0.23])
    n, reps = 20, 4000
    lw = jnp.log(jnp.asarray(w))
    keys = jax.random.split(jax.random.key(5), reps)
    anc = np.asarray(jax.vmap(lambda k: RESAMPLERS[name](k, lw, n))(keys))
    counts = np.stack([np.bincount(a, minlength=w.size) for a in anc])
    mean = counts.mean(0)
    se = counts.std(0, ddof=1) / np.sqrt(reps)
    assert np.all(np.abs(mean - n * w) <= 4 * se + 1e-12), (mean, n * w, se)
    if name in ("systematic", "residual"):
        assert np.all(counts >= np.floor(n * w - 1e-9))
    if name == "systematic":
        assert np.all(counts <= np.ceil(n * w + 1e-9))


_JITTED = {name: jax.jit(fn, static_argnums=2) for name, fn in RESAMPLERS.items()}


@settings(max_examples=40, deadline=None)
@given(
    st.lists(st.one_of(st.floats(-800.0, 50.0), st.just(-np.inf)), min_size=16, max_size=16),
    st.sampled_from([1, 16, 33]),
    st.sampled_from(NAMES),
    st.integers(0, 2**31 - 1),
)
def test_property_valid_ancestors(raw: list[float], n: int, name: str, seed: int) -> None:
    # fixed sizes keep the number of compilations small; the values are what varies
    lw = jnp.asarray(raw, dtype=jnp.float64)
    anc = np.asarray(_JITTED[name](jax.random.key(seed), lw, n))
    assert anc.shape == (n,)
    assert anc.min() >= 0 and anc.max() < len(raw)
    w = np.asarray(normalized_weights(lw))
    assert np.isclose(w.sum(), 1.0)
    if np.any(np.isfinite(raw)):
        assert np.all(w[anc] > 0), "a zero-weight particle was picked"
