"""The numpy SIR step and run (inference.particle.numpy_filter): against an HMM's exact
filter (checked itself by enumerating every path), replayed by hand, and on properties."""

from __future__ import annotations

import itertools
import textwrap
from typing import NamedTuple

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.special import logsumexp

from dbn.errors import InputError, ShapeError
from inference.particle import ParticleState
from inference.particle.numpy_filter import run_steps, sir_step, take_rows
from inference.particle.numpy_path import NUMPY_RESAMPLERS, multinomial, systematic

# a 3-state HMM with Gaussian emissions
P0 = np.array([0.5, 0.3, 0.2])
A = np.array([[0.8, 0.15, 0.05], [0.1, 0.7, 0.2], [0.25, 0.25, 0.5]])
MEANS = np.array([-1.0, 0.5, 2.0])
Y = np.array([0.3, -1.2, 1.9, 2.4, 0.1])


def log_emission(y: float, x: np.ndarray) -> np.ndarray:
    return -0.5 * (y - MEANS[x]) ** 2 - 0.5 * np.log(2 * np.pi)


def exact_filter(ys: np.ndarray) -> tuple[np.ndarray, float]:
    """Filtered marginals (T, 3) and log p(y_1:T), x_0 ~ P0 unobserved, x_t ~ A[x_{t-1}]."""
    alpha, loglik, out = P0, 0.0, []
    for y in ys:
        a = (alpha @ A) * np.exp(log_emission(y, np.arange(3)))
        loglik += np.log(a.sum())
        alpha = a / a.sum()
        out.append(alpha)
    return np.array(out), loglik


def test_exact_filter_equals_enumeration() -> None:
    ys = Y[:4]
    last, total = np.zeros(3), 0.0
    for path in itertools.product(range(3), repeat=5):  # x_0 .. x_4
        p = P0[path[0]] * np.prod([A[path[t], path[t + 1]] for t in range(4)])
        p *= np.exp(sum(log_emission(ys[t], np.array(path[t + 1])) for t in range(4)))
        total += p
        last[path[-1]] += p
    marg, loglik = exact_filter(ys)
    assert loglik == pytest.approx(np.log(total), rel=1e-12)
    np.testing.assert_allclose(marg[-1], last / total, rtol=1e-10)


def predict(rng: np.random.Generator, x: np.ndarray) -> np.ndarray:
    cdf = np.cumsum(A, axis=1)[x]
    return np.minimum((rng.random(x.size)[:, None] >= cdf).sum(1), 2)


def hmm_step(rng, state, y, resample=systematic):
    return sir_step(rng, state, predict, lambda r, x: (x, log_emission(y, x), None), resample=resample)


@pytest.mark.parametrize("name", sorted(NUMPY_RESAMPLERS))
def test_sir_matches_the_exact_hmm_filter(name: str) -> None:
    n = 200_000
    rng = np.random.default_rng(0)
    state = ParticleState(rng.choice(3, size=n, p=P0), np.full(n, -np.log(n)))
    exact, loglik = exact_filter(Y)
    log_score = 0.0
    for t, y in enumerate(Y):
        state, info = hmm_step(rng, state, y, NUMPY_RESAMPLERS[name])
        w = np.exp(info.log_weights)
        marg = np.bincount(info.particles, weights=w, minlength=3)
        np.testing.assert_allclose(marg, exact[t], atol=0.008)
        # the resampled cloud is an unweighted sample of the same marginal
        np.testing.assert_allclose(np.bincount(state.particles, minlength=3) / n, exact[t], atol=0.01)
        log_score += info.log_score
    assert log_score == pytest.approx(loglik, abs=0.02)


class Pair(NamedTuple):
    pos: np.ndarray
    vel: np.ndarray


def test_step_order_replayed_by_hand_and_inputs_untouched() -> None:
    n = 7
    parts = Pair(np.arange(n, dtype=float), np.ones((n, 2)))
    lw = np.log(np.array([0.1, 0.2, 0.05, 0.25, 0.1, 0.2, 0.1]))
    state = ParticleState(parts, lw)
    copies = (parts.pos.copy(), parts.vel.copy(), lw.copy())
    log_g = np.array([0.0, -1.0, -np.inf, 0.5, np.nan, -2.0, 0.3])

    def pred(r, p):
        return Pair(p.pos + r.normal(size=n), p.vel * 2)

    def weigh(r, p):
        return p._replace(vel=p.vel + r.random()), log_g, "aux"

    def move(r, p):
        return p._replace(pos=p.pos + 100 * r.random(n))

    new, info = sir_step(np.random.default_rng(5), state, pred, weigh, resample=multinomial, move=move)
    # replay: predict, weigh, resample, move consume one generator in this order
    r = np.random.default_rng(5)
    pos = parts.pos + r.normal(size=n)
    vel = parts.vel * 2 + r.random()
    lw_new = lw + np.where(np.isnan(log_g), -np.inf, log_g)
    expect_w = lw_new - logsumexp(lw_new)
    anc = multinomial(r, expect_w, n)
    np.testing.assert_array_equal(info.ancestors, anc)
    np.testing.assert_allclose(info.log_weights, expect_w)
    assert info.log_score == pytest.approx(logsumexp(lw_new)) and info.aux == "aux"
    np.testing.assert_allclose(info.particles.pos, pos)
    np.testing.assert_allclose(new.particles.pos, pos[anc] + 100 * r.random(n))
    np.testing.assert_allclose(new.particles.vel, vel[anc])
    np.testing.assert_allclose(new.log_weights, -np.log(n))
    assert not np.isin(anc, [2, 4]).any()  # zero weights (-inf, NaN) are never ancestors
    for before, after in zip(copies, (parts.pos, parts.vel, lw), strict=True):
        np.testing.assert_array_equal(before, after)


@settings(max_examples=60, deadline=None)
@given(
    st.integers(1, 40),
    st.integers(0, 2**31 - 1),
    st.floats(0.0, 0.7),
    st.sampled_from(sorted(NUMPY_RESAMPLERS)),
    st.floats(0.0, 1.5),
)
def test_weights_normalise_and_score_is_the_log_total(n, seed, p_zero, name, tau) -> None:
    rng = np.random.default_rng(seed)
    lw = rng.normal(size=n) * 5 - 300
    lw[rng.random(n) < p_zero / 2] = -np.inf
    log_g = rng.normal(size=n) * 10
    log_g[rng.random(n) < p_zero / 2] = -np.inf
    parts = {"x": rng.normal(size=(n, 3)), "k": np.arange(n)}
    state = ParticleState(parts, lw)
    new, info = sir_step(
        rng,
        state,
        lambda r, p: p,
        lambda r, p: (p, log_g, None),
        resample=NUMPY_RESAMPLERS[name],
        ess_threshold=tau,
    )
    total = logsumexp(lw + log_g)
    assert info.resampled == (tau >= 1 or info.ess < tau * n)
    expect_lw = np.full(n, -np.log(n)) if info.resampled else info.log_weights
    np.testing.assert_array_equal(new.log_weights, expect_lw)
    assert set(new.particles) == {"x", "k"} and new.particles["x"].shape == (n, 3)
    np.testing.assert_array_equal(new.particles["x"], parts["x"][info.ancestors])
    if np.isfinite(total):
        assert info.log_score == pytest.approx(total, rel=1e-12)
        assert logsumexp(info.log_weights) == pytest.approx(0.0, abs=1e-9)
        if info.resampled:  # a kept step keeps its zero weights in their rows
            assert np.all(np.isfinite(info.log_weights[info.ancestors]))
        assert 1.0 - 1e-9 <= info.ess <= n + 1e-9
    else:  # every weight zero: uniform fallback
        assert info.log_score == -np.inf
        np.testing.assert_allclose(info.log_weights, -np.log(n))


def test_bad_shapes_name_the_function() -> None:
    n = 4
    state = ParticleState(np.zeros(n), np.full(n, -np.log(n)))
    ok = lambda r, p: (p, np.zeros(n), None)  # noqa: E731
    rng = np.random.default_rng(0)
    with pytest.raises(ShapeError, match="predict"):
        sir_step(rng, state, lambda r, p: p[:3], ok)
    with pytest.raises(ShapeError, match="log_g"):
        sir_step(rng, state, lambda r, p: p, lambda r, p: (p, np.zeros(n + 1), None))
    with pytest.raises(ShapeError, match="weight"):
        sir_step(rng, state, lambda r, p: p, lambda r, p: (p[:2], np.zeros(n), None))
    with pytest.raises(ShapeError, match="move"):
        sir_step(rng, state, lambda r, p: p, ok, move=lambda r, p: p[:1])
    with pytest.raises(ShapeError, match="state.particles"):
        sir_step(rng, ParticleState(np.zeros(3), np.zeros(n)), lambda r, p: p, ok)
    with pytest.raises(ShapeError, match="log_weights"):
        sir_step(rng, ParticleState(np.zeros(0), np.zeros(0)), lambda r, p: p, ok)


def test_run_steps_equals_stepping_by_hand() -> None:
    n = 500
    x0 = np.random.default_rng(1).choice(3, size=n, p=P0)
    state = ParticleState(x0, np.full(n, -np.log(n)))
    final, infos, secs = run_steps(np.random.default_rng(3), hmm_step, state, Y)
    rng, s = np.random.default_rng(3), state
    for y, info in zip(Y, infos, strict=True):
        s, mine = hmm_step(rng, s, y)
        np.testing.assert_array_equal(mine.particles, info.particles)
        assert mine.log_score == info.log_score
    np.testing.assert_array_equal(final.particles, s.particles)
    assert secs.shape == (Y.size,) and np.all(secs >= 0)
    _, infos_p, _ = run_steps(np.random.default_rng(3), hmm_step, state, list(Y), progress=True)
    assert [i.log_score for i in infos_p] == [i.log_score for i in infos]
    with pytest.raises(InputError, match="rng"):
        run_steps(3, hmm_step, state, Y)


def test_take_rows_keeps_the_structure() -> None:
    p = Pair(np.arange(5), np.arange(10).reshape(5, 2))
    out = take_rows(p, np.array([4, 4, 0]))
    assert isinstance(out, Pair)
    np.testing.assert_array_equal(out.vel, [[8, 9], [8, 9], [0, 1]])


def test_the_module_usage_block_runs() -> None:
    import inference.particle.numpy_filter as mod

    doc = mod.__doc__
    code = doc[doc.index("Usage") :].split("::", 1)[1]
    namespace: dict = {}
    exec(compile(textwrap.dedent(code), "numpy_filter usage", "exec"), namespace)  # noqa: S102
    p1 = namespace["p_state1"]
    assert len(p1) == 3 and p1[1] > 0.5 > p1[2]  # y = 1.1 favours state 1, y = -0.9 state 0


@pytest.mark.parametrize("tau", [0.5, 0.0])
def test_adaptive_resampling_matches_the_exact_hmm_filter(tau: float) -> None:
    """ESS-triggered resampling (0.5: three steps keep their weights, two resample) and
    none at all (0: sequential importance sampling) still give the exact filter."""
    n = 200_000
    rng = np.random.default_rng(0)
    state = ParticleState(rng.choice(3, size=n, p=P0), np.full(n, -np.log(n)))
    exact, loglik = exact_filter(Y)
    log_score, flags = 0.0, []
    for t, y in enumerate(Y):
        prev = state
        state, info = sir_step(
            rng, state, predict, lambda r, x, y=y: (x, log_emission(y, x), None), ess_threshold=tau
        )
        assert info.resampled == (info.ess < tau * n)
        flags.append(info.resampled)
        marg = np.bincount(state.particles, weights=np.exp(state.log_weights), minlength=3)
        np.testing.assert_allclose(marg, exact[t], atol=0.008)
        if not info.resampled:  # rows and weights carried: the weights go on accumulating
            np.testing.assert_array_equal(info.ancestors, np.arange(n))
            np.testing.assert_array_equal(state.log_weights, info.log_weights)
            assert np.ptp(state.log_weights) > 0 and prev.particles.shape == state.particles.shape
        log_score += info.log_score
    assert log_score == pytest.approx(loglik, abs=0.02)
    assert (sum(flags), len(flags)) == ((2, 5) if tau else (0, 5))


def test_a_step_that_keeps_its_weights_is_replayed_by_hand() -> None:
    """No resampling: ``resample`` is not called, the generator goes from weight to move,
    and ``move`` sees the weighted particles in their own rows."""
    n = 6
    lw = np.full(n, -np.log(n))
    log_g = np.array([0.0, -0.2, 0.1, -0.1, 0.05, 0.0])  # ESS near n: above 0.5 n

    def never(r, w, k):
        raise AssertionError("resample must not run")

    def pred(r, x):
        return x + r.normal(size=n)

    def move(r, x):
        return x + r.random(n)

    x0 = np.arange(n, dtype=float)
    new, info = sir_step(
        np.random.default_rng(2), ParticleState(x0, lw), pred,
        lambda r, x: (x, log_g, None), resample=never, move=move, ess_threshold=0.5,
    )
    r = np.random.default_rng(2)
    x = x0 + r.normal(size=n)
    assert not info.resampled
    np.testing.assert_allclose(new.particles, x + r.random(n))
    np.testing.assert_allclose(new.log_weights, log_g - logsumexp(log_g))
    np.testing.assert_allclose(info.particles, x)


@pytest.mark.parametrize("bad", [-0.1, float("nan"), "0.5", True, None])
def test_a_bad_threshold_is_refused_before_anything_is_drawn(bad) -> None:
    n = 3
    state = ParticleState(np.zeros(n), np.full(n, -np.log(n)))
    rng = np.random.default_rng(0)
    before = rng.bit_generator.state

    def pred(r, x):
        raise AssertionError("predict must not run")

    with pytest.raises(InputError, match="ess_threshold"):
        sir_step(rng, state, pred, lambda r, x: (x, np.zeros(n), None), ess_threshold=bad)
    assert rng.bit_generator.state == before
