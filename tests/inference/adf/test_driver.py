"""The generic ADF driver on a toy model whose family is exact (driver = exact filter).

Toy model: a hidden Markov chain x_k in {0..n-1} (transition T, emission E, initial
x_0 ~ pi, no observation at 0) and the number m_k of visits to state 0 at steps 1..k.
The belief is the exact joint q(x_k, m_k) (n, capacity); m_k's support grows by one
per step, so the capacity must grow. The oracle enumerates every path.
"""

from __future__ import annotations

import itertools
from functools import cache
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from jax.scipy.special import logsumexp
from scipy.special import logsumexp as np_logsumexp

from dbn.errors import InputError
from inference.adf.checkpoint import load_state, save_state
from inference.adf.driver import ADFHooks, adf_filter, adf_filter_lag, adf_step


class ToyParams(NamedTuple):
    logT: jnp.ndarray  # (n, n)
    logE: jnp.ndarray  # (n, num_symbols)


class ToyState(NamedTuple):
    k: jnp.ndarray  # ()
    b: jnp.ndarray  # (n, capacity) q(x_k, m_k)


class ToyInfo(NamedTuple):
    px: jnp.ndarray  # (n,) q(x_k | y_1..k)
    loglik: jnp.ndarray  # () log p(y_k | y_1..k-1)


def predict(p: ToyParams, s: ToyState, y):
    pred = jnp.einsum("xm,xz->zm", s.b, jnp.exp(p.logT))
    shifted = jnp.concatenate([jnp.zeros(1), pred[0, :-1]])  # x' = 0: one more visit
    pred = pred.at[0].set(shifted)
    return jnp.log(pred) + p.logE[:, y][:, None]


def condition(p, s, y, logj):
    lz = logsumexp(logj)
    return jnp.exp(logj - lz), lz


def project(p, s, y, post):
    b, lz = post
    return ToyState(s.k + 1, b), ToyInfo(b.sum(1), lz)


def window_predict(p, s, ys):
    return jax.vmap(lambda y: predict(p, s, y))(ys)


@cache
def hooks(record: bool = False) -> ADFHooks:
    return ADFHooks(
        predict, condition, project, (lambda s: s.b) if record else None, window_predict
    )


def grow(s: ToyState, margin: int) -> ToyState:
    used = np.flatnonzero(np.asarray(s.b).sum(0) > 0)
    M = s.b.shape[1]
    newM = M
    while int(used[-1]) + margin + 1 >= newM:
        newM *= 2
    return s if newM == M else s._replace(b=jnp.pad(s.b, ((0, 0), (0, newM - M))))


def toy(seed: int, n: int = 3, num_symbols: int = 4, K: int = 6):
    rng = np.random.default_rng(seed)
    T = rng.dirichlet(np.ones(n), size=n)
    E = rng.dirichlet(np.ones(num_symbols), size=n)
    pi = rng.dirichlet(np.ones(n))
    ys = rng.integers(0, num_symbols, K)
    with jax.enable_x64(True):
        params = ToyParams(jnp.log(jnp.asarray(T)), jnp.log(jnp.asarray(E)))
        b0 = np.zeros((n, 2))
        b0[:, 0] = pi
        state = ToyState(jnp.asarray(0, jnp.int64), jnp.asarray(b0))
    return params, state, ys, (T, E, pi)


def oracle(T, E, pi, ys):
    """Every path x_0..x_K: filtered q(x_k, m_k | y_1..k) (K, n, K + 1) and log p(y_1..k)."""
    n, K = T.shape[0], len(ys)
    joint = np.zeros((K, n, K + 1))
    logz = np.zeros(K)
    for path in itertools.product(range(n), repeat=K + 1):
        w = pi[path[0]]
        m = 0
        for k in range(K):
            w *= T[path[k], path[k + 1]] * E[path[k + 1], ys[k]]
            m += path[k + 1] == 0
            joint[k, path[k + 1], m] += w
    for k in range(K):  # each prefix was counted once per continuation: n^(K-1-k) times
        logz[k] = np.log(joint[k].sum()) - (K - 1 - k) * np.log(n)
        joint[k] /= joint[k].sum()
    return joint, logz


def _padded(rec, width):
    return np.concatenate([np.pad(r, ((0, 0), (0, 0), (0, width - r.shape[2]))) for r in rec])


@settings(max_examples=4, deadline=None)
@given(seed=st.integers(0, 10_000), chunk=st.sampled_from([1, 4]))
def test_driver_equals_exact_oracle(seed, chunk):
    params, state, ys, (T, E, pi) = toy(seed)
    out = adf_filter(hooks(True), params, state, ys, chunk=chunk, grow=grow)
    joint, logz = oracle(T, E, pi, ys)
    np.testing.assert_allclose(out.infos.px, joint.sum(2), atol=1e-12)
    np.testing.assert_allclose(np.cumsum(out.infos.loglik), logz, rtol=1e-12)
    width = max(r.shape[2] for r in out.records)
    rec = _padded(out.records, max(width, len(ys) + 1))
    np.testing.assert_allclose(rec[:, :, : len(ys) + 1], joint, atol=1e-12)
    assert out.infos.px.dtype == np.float64  # float64 without any global jax setting


def test_capacity_grows_and_without_growth_mass_is_lost():
    params, state, ys, (T, E, pi) = toy(3, K=9)
    out = adf_filter(hooks(), params, state, ys, chunk=4, grow=grow)
    assert out.state.b.shape[1] > 9
    assert float(out.state.b.sum()) == pytest.approx(1.0, abs=1e-12)
    joint, logz = oracle(T, E, pi, ys)
    np.testing.assert_allclose(np.cumsum(out.infos.loglik), logz, rtol=1e-12)
    fixed = adf_filter(hooks(), params, state, ys, chunk=4)  # capacity 2: m > 1 dropped
    assert not np.allclose(np.cumsum(fixed.infos.loglik), logz, rtol=1e-6)


def test_split_run_resumes_bit_identically(tmp_path):
    params, state, ys, _ = toy(7, K=11)
    full = adf_filter(hooks(), params, state, ys, chunk=4, grow=grow)
    first = adf_filter(hooks(), params, state, ys[:5], chunk=4, grow=grow)
    save_state(tmp_path / "s.npz", first.state, "toy-v1", {"note": "test"})
    loaded = load_state(tmp_path / "s.npz", ToyState, "toy-v1")
    second = adf_filter(hooks(), params, loaded, ys[5:], chunk=4, grow=grow)
    np.testing.assert_array_equal(np.asarray(full.state.b), np.asarray(second.state.b))
    for f in ToyInfo._fields:
        a = getattr(full.infos, f)
        np.testing.assert_array_equal(
            a, np.concatenate([getattr(first.infos, f), getattr(second.infos, f)])
        )
    with pytest.raises(InputError):
        load_state(tmp_path / "s.npz", ToyState, "other-format")


def test_step_equals_scan_jitted_and_eager():
    params, state, ys, _ = toy(11, K=5)
    state = grow(state, len(ys))
    out = adf_filter(hooks(), params, state, ys, chunk=8)
    s = state
    for k, y in enumerate(ys):
        s, info = adf_step(hooks(), params, s, y)
        np.testing.assert_allclose(np.asarray(info.px), out.infos.px[k], atol=1e-14)
    with jax.disable_jit(), jax.enable_x64(True):
        s2 = state
        for y in ys:
            s2, info2 = hooks().project(
                params, s2, y, condition(params, s2, y, predict(params, s2, y))
            )
    np.testing.assert_allclose(np.asarray(s2.b), np.asarray(s.b), atol=1e-14)


@pytest.mark.parametrize("lag", [0, 2])
def test_fixed_lag_windows_and_revision(lag):
    params, state, ys, _ = toy(5, K=7)
    seen = []

    def revise(s, k, n, scores):
        """Exact conditioning of the window's first observation (numpy)."""
        seen.append((k, n, scores.shape))
        lz = np_logsumexp(scores[0])
        return jnp.asarray(np.exp(scores[0] - lz)), jnp.asarray(lz)

    plain = adf_filter(hooks(True), params, state, ys, chunk=4, grow=grow)
    lagged = adf_filter_lag(hooks(True), params, state, ys, lag, revise, chunk=4, grow=grow)
    np.testing.assert_allclose(lagged.infos.px, plain.infos.px, atol=1e-12)
    np.testing.assert_allclose(lagged.infos.loglik, plain.infos.loglik, atol=1e-12)
    assert len(lagged.records) == len(ys)
    K = len(ys)
    assert [(k, n) for k, n, _ in seen] == [(k, min(K, k + lag + 1) - k) for k in range(K)]
    assert all(shape[0] == lag + 1 for _, _, shape in seen)


def test_bad_arguments_raise():
    params, state, ys, _ = toy(0)
    with pytest.raises(InputError):
        adf_filter(hooks(), params, state, ys, chunk=0)
    with pytest.raises(InputError):
        adf_filter_lag(hooks(), params, state, ys, -1, lambda *a: None, chunk=4)
    with pytest.raises(InputError):
        adf_filter(hooks(), params, state, (ys, ys[:-1]), chunk=4)
    with pytest.raises(InputError):
        adf_filter_lag(ADFHooks(predict, condition, project), params, state, ys, 1, None, chunk=4)


def test_runs_in_float64_with_x64_switched_off():
    params, state, ys, _ = toy(9)
    ref = adf_filter(hooks(), params, state, ys, chunk=4, grow=grow)
    with jax.enable_x64(False):
        out = adf_filter(hooks(), params, state, ys, chunk=4, grow=grow)
    assert out.infos.loglik.dtype == np.float64 and out.state.b.dtype == np.float64
    np.testing.assert_array_equal(out.infos.loglik, ref.infos.loglik)


def _identity_prune(p, s):
    return s, s.b.sum()


@pytest.mark.parametrize("lag", [None, 1])
def test_prune_hook_reports_and_overflow_reruns_the_chunk(lag):
    params, state, ys, (T, E, pi) = toy(5, K=7)
    base = hooks()
    pruned = base._replace(prune=_identity_prune)
    retried = []

    def overflow(before, after, reports):
        assert reports.shape[0] in ((1,) if lag else (3, len(ys) % 3))  # the unit's steps
        if retried:
            return None
        retried.append(before.b.shape[1])
        return before._replace(b=jnp.pad(before.b, ((0, 0), (0, 2))))

    def go(h, **kw):
        if lag is None:
            return adf_filter(h, params, state, ys, chunk=3, grow=grow, **kw)
        rev = lambda s, k, n, scores: condition(params, s, None, scores[0])  # noqa: E731
        return adf_filter_lag(h, params, state, ys, lag, rev, chunk=3, grow=grow, **kw)

    plain = go(base)
    out = go(pruned, overflow=overflow)
    assert plain.reports is None and len(retried) == 1
    np.testing.assert_allclose(out.reports, 1.0, atol=1e-12)  # one report per step
    assert out.reports.shape == (len(ys),)
    for f in ToyInfo._fields:  # the re-run chunk (larger capacity) gives the same answer
        np.testing.assert_allclose(getattr(out.infos, f), getattr(plain.infos, f), atol=1e-12)
