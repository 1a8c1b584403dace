"""The numpy particle path (log normalisation, ESS, resamplers) and the k best distinct
states, against direct formulas and a brute-force oracle."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.special import logsumexp

from dbn.errors import InputError, ShapeError
from inference.particle.kbest import k_best_states
from inference.particle.numpy_path import NUMPY_RESAMPLERS, ess, log_normalise, normalized_weights

NAMES = sorted(NUMPY_RESAMPLERS)


def test_log_normalise_matches_logsumexp() -> None:
    lw = np.random.default_rng(0).normal(size=50) * 30 - 2000.0  # all underflow in linear space
    out, total = log_normalise(lw)
    assert total == pytest.approx(logsumexp(lw), rel=1e-12)
    np.testing.assert_allclose(out, lw - logsumexp(lw), atol=1e-9)
    w = normalized_weights(lw)
    assert ess(lw) == pytest.approx(1.0 / np.sum(w**2), rel=1e-12)
    # NaN is a zero weight; all zero -> uniform and total -inf
    out, total = log_normalise(np.array([np.nan, 0.0, -np.inf]))
    np.testing.assert_allclose(np.exp(out), [0.0, 1.0, 0.0])
    out, total = log_normalise(np.full(4, -np.inf))
    assert total == -np.inf and np.allclose(np.exp(out), 0.25)


@pytest.mark.parametrize("name", NAMES)
def test_counts_are_unbiased_and_zero_weights_never_drawn(name: str) -> None:
    w = np.array([0.05, 0.3, 0.0, 0.15, 0.27, 0.23])
    n, reps = 20, 3000
    with np.errstate(divide="ignore"):
        lw = np.log(w) - 700.0  # shifted: the scheme works in log space
    rng = np.random.default_rng(1)
    counts = np.stack(
        [np.bincount(NUMPY_RESAMPLERS[name](rng, lw, n), minlength=w.size) for _ in range(reps)]
    )
    assert counts[:, 2].max() == 0
    mean, se = counts.mean(0), counts.std(0, ddof=1) / np.sqrt(reps)
    assert np.all(np.abs(mean - n * w) <= 4 * se + 1e-12), (mean, n * w, se)
    if name == "systematic":
        assert np.all(counts >= np.floor(n * w)) and np.all(counts <= np.ceil(n * w))


@pytest.mark.parametrize("name", NAMES)
def test_same_generator_state_same_ancestors_and_uniform_fallback(name: str) -> None:
    lw = np.log(np.array([0.2, 0.5, 0.3]))
    a = NUMPY_RESAMPLERS[name](np.random.default_rng(7), lw, 11)
    b = NUMPY_RESAMPLERS[name](np.random.default_rng(7), lw, 11)
    assert np.array_equal(a, b) and a.shape == (11,)
    anc = NUMPY_RESAMPLERS[name](np.random.default_rng(2), np.full(8, -np.inf), 8000)
    counts = np.bincount(anc, minlength=8)
    assert np.all(np.abs(counts - 1000) <= 5 * np.sqrt(1000))


def _oracle(ids: np.ndarray, w: np.ndarray, k: int, combine: str):
    states: dict[int, list[int]] = {}
    for i, s in enumerate(ids.tolist()):
        states.setdefault(s, []).append(i)
    rows = []
    for s, members in states.items():
        mass = sum(w[members]) if combine == "sum" else max(w[members])
        heaviest = min(members, key=lambda i: (-w[i], i))
        rows.append((-mass, s, heaviest, mass))
    rows.sort()
    return [r[2] for r in rows[:k]], [r[3] for r in rows[:k]]


@settings(max_examples=60, deadline=None)
@given(
    seed=st.integers(0, 2**31 - 1),
    m=st.integers(1, 40),
    k=st.integers(1, 8),
    combine=st.sampled_from(["sum", "max"]),
)
def test_k_best_states_equal_brute_force(seed: int, m: int, k: int, combine: str) -> None:
    rng = np.random.default_rng(seed)
    ids = rng.integers(-5, 6, size=m)
    # weights on a coarse grid so that ties happen and their rule is exercised
    w = rng.integers(0, 5, size=m) / 4.0
    rep, mass = k_best_states(ids, w, k, combine)
    want_rep, want_mass = _oracle(ids, w, k, combine)
    np.testing.assert_allclose(mass, want_mass, atol=1e-12)
    assert rep.tolist() == want_rep


def test_k_best_states_bad_input() -> None:
    with pytest.raises(ShapeError):
        k_best_states(np.zeros(3, int), np.zeros(2), 2)
    for k in (0, True, 2.0):  # True was read as 1
        with pytest.raises(InputError, match="k must be an integer >= 1"):
            k_best_states(np.zeros(3, int), np.zeros(3), k)
    with pytest.raises(InputError, match="combine"):
        k_best_states(np.zeros(3, int), np.zeros(3), 2, "mean")
    with pytest.raises(InputError, match="non-negative"):
        k_best_states(np.zeros(3, int), np.array([0.1, np.nan, 0.2]), 2)
    # complex weights lost their imaginary parts; strings raised numpy's ValueError
    with pytest.raises(InputError, match="weights holds complex numbers"):
        k_best_states(np.zeros(2, int), np.array([1 + 1j, 1.0]), 1)
    with pytest.raises(InputError, match="weights is not an array of numbers"):
        k_best_states(np.zeros(2, int), ["a", "b"], 1)
