"""The reversible-jump kernel samples a known trans-dimensional target (seed 003, eq. 11).

Oracles: a mixture over model dimension k = 0..3 whose posterior over k and whose moments
are known in closed form; a Gaussian target under a non-symmetric proposal (the Hastings
correction); detailed balance of the acceptance ratio checked exactly (hypothesis).
Monte Carlo tolerances come from batch-means standard errors of the chain.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dbn.errors import InputError, NegativeProbabilityError, NotNormalizedError
from inference.mcmc import (
    Move,
    Proposal,
    log_acceptance_ratio,
    mh_step,
    rj_step,
    run_chain,
    select_move,
)

WEIGHTS = np.array([1.0, 2.0, 3.0, 1.5])  # unnormalised prior mass of dimension k
MU = np.array([1.0, -0.5, 2.0])
SIGMA = np.array([0.7, 1.2, 0.5])
BIRTH_SD = 2.0
MOVE_PROBS = np.array([0.45, 0.2, 0.35])  # birth, death, update: deliberately p_b != p_d


def _log_normal(x: float, mu: float, sd: float) -> float:
    return -0.5 * ((x - mu) / sd) ** 2 - math.log(sd) - 0.5 * math.log(2 * math.pi)


def log_target(x: tuple[float, ...]) -> float:
    k = len(x)
    if k > 3:
        return -math.inf
    return math.log(WEIGHTS[k]) + sum(_log_normal(v, MU[j], SIGMA[j]) for j, v in enumerate(x))


def birth(rng: np.random.Generator, x: tuple[float, ...]) -> Proposal | None:
    if len(x) == 3:
        return None
    new = float(rng.normal(0.0, BIRTH_SD))
    return Proposal(x + (new,), _log_normal(new, 0.0, BIRTH_SD), 0.0)


def death(rng: np.random.Generator, x: tuple[float, ...]) -> Proposal | None:
    if len(x) == 0:
        return None
    return Proposal(x[:-1], 0.0, _log_normal(x[-1], 0.0, BIRTH_SD))


def update(rng: np.random.Generator, x: tuple[float, ...]) -> Proposal | None:
    if len(x) == 0:
        return None
    j = int(rng.integers(len(x)))
    y = list(x)
    y[j] += float(rng.normal(0.0, 0.8))
    return Proposal(tuple(y), 0.0, 0.0)


MOVES = [Move("birth", birth, 1), Move("death", death, 0), Move("update", update, 2)]


def _batch_means(values: np.ndarray, num_batches: int = 50) -> tuple[np.ndarray, np.ndarray]:
    """Mean and batch-means standard error along axis 0."""
    n = (len(values) // num_batches) * num_batches
    batches = values[:n].reshape(num_batches, n // num_batches, *values.shape[1:]).mean(axis=1)
    return batches.mean(axis=0), batches.std(axis=0, ddof=1) / math.sqrt(num_batches)


@pytest.fixture(scope="module")
def chain() -> list[tuple[float, ...]]:
    states, infos = run_chain(np.random.default_rng(123), (), 60_000, MOVES, log_target, MOVE_PROBS)
    assert 0.05 < np.mean([i.accepted for i in infos]) < 0.95
    return states[2_000:]


def test_posterior_over_dimension(chain: list[tuple[float, ...]]) -> None:
    dims = np.array([len(s) for s in chain])
    onehot = (dims[:, None] == np.arange(4)[None, :]).astype(float)
    mean, se = _batch_means(onehot)
    truth = WEIGHTS / WEIGHTS.sum()
    z = np.abs(mean - truth) / se
    assert np.all(z < 4.5), f"P(k) {mean} vs {truth}, z={z}"
    # The test has power: forgetting p_{m'}/p_m would target w_k (p_b/p_d)^k instead.
    wrong = WEIGHTS * (MOVE_PROBS[0] / MOVE_PROBS[1]) ** np.arange(4)
    wrong = wrong / wrong.sum()
    assert np.max(np.abs(wrong - truth) / se) > 20


def test_moments_within_dimension(chain: list[tuple[float, ...]]) -> None:
    for j in range(3):
        vals = np.array([s[j] for s in chain if len(s) > j])
        mean, se = _batch_means(vals)
        assert abs(mean - MU[j]) < 4.5 * se, (j, mean, MU[j], se)
        second, se2 = _batch_means(vals**2)
        truth2 = MU[j] ** 2 + SIGMA[j] ** 2
        assert abs(second - truth2) < 4.5 * se2, (j, second, truth2, se2)


def test_mh_hastings_correction() -> None:
    """Non-symmetric proposal x' ~ N(0.5 x, 1): only the q-ratio makes it correct."""

    def target(x: float) -> float:
        return _log_normal(x, 2.0, 1.5)

    def propose(rng: np.random.Generator, x: float) -> Proposal:
        y = float(rng.normal(0.5 * x, 1.0))
        return Proposal(y, _log_normal(y, 0.5 * x, 1.0), _log_normal(x, 0.5 * y, 1.0))

    rng = np.random.default_rng(7)
    x, value, out = 0.0, target(0.0), []
    for _ in range(40_000):
        x, info = mh_step(rng, x, propose, target, value)
        value = info.log_target
        out.append(x)
    vals = np.array(out[1000:])
    mean, se = _batch_means(vals)
    var, se_v = _batch_means((vals - 2.0) ** 2)
    assert abs(mean - 2.0) < 4.5 * se
    assert abs(var - 2.25) < 4.5 * se_v


@settings(max_examples=200, deadline=None)
@given(
    lt=st.tuples(*[st.floats(-50, 50)] * 2),
    lq=st.tuples(*[st.floats(-30, 30)] * 2),
    pm=st.tuples(*[st.floats(0.01, 1.0)] * 2),
)
def test_detailed_balance_of_ratio(lt, lq, pm) -> None:
    """pi(x) p_m q_m(x'|x) alpha(x->x') == pi(x') p_m' q_m'(x|x') alpha(x'->x)."""
    (lx, ly), (qf, qr), (pf, pr) = lt, lq, pm
    fwd = log_acceptance_ratio(ly - lx, qf, qr, math.log(pf), math.log(pr))
    rev = log_acceptance_ratio(lx - ly, qr, qf, math.log(pr), math.log(pf))
    flow_fwd = lx + math.log(pf) + qf + min(0.0, fwd)
    flow_rev = ly + math.log(pr) + qr + min(0.0, rev)
    assert flow_fwd == pytest.approx(flow_rev, abs=1e-9)


def test_impossible_states() -> None:
    assert log_acceptance_ratio(-math.inf, 0.0, 0.0) == -math.inf
    assert log_acceptance_ratio(math.inf, 0.0, 0.0) == math.inf
    # A chain started in an impossible state leaves it at the first finite proposal.
    rng = np.random.default_rng(0)

    def target(x: float) -> float:
        return 0.0 if abs(x) < 1 else -math.inf

    def propose(rng: np.random.Generator, x: float) -> Proposal:
        return Proposal(0.0, 0.0, 0.0)

    x, info = mh_step(rng, 5.0, propose, target)
    assert x == 0.0 and info.accepted and info.log_target == 0.0


def test_same_seed_same_chain_and_bad_input() -> None:
    a, _ = run_chain(np.random.default_rng(5), (), 300, MOVES, log_target, MOVE_PROBS)
    b, _ = run_chain(np.random.default_rng(5), (), 300, MOVES, log_target, MOVE_PROBS)
    assert a == b
    state = (0.5,)
    with pytest.raises(NotNormalizedError, match="move_probs"):
        rj_step(np.random.default_rng(0), state, MOVES, log_target, np.array([0.5, 0.5, 0.5]))
    with pytest.raises(InputError, match="move_probs"):
        rj_step(np.random.default_rng(0), state, MOVES, log_target, np.array([0.5, 0.5]))
    bad = [Move("birth", birth, 7), MOVES[1], MOVES[2]]
    with pytest.raises(InputError, match="reverse"):
        rj_step(np.random.default_rng(0), state, bad, log_target, MOVE_PROBS)
    assert state == (0.5,)


def test_select_move_draws_by_the_probabilities_and_refuses_bad_ones_before_drawing() -> None:
    """Frequencies within 5 binomial standard errors of ``move_probs``; probabilities that
    are NaN, negative, not summing to one, complex or not one axis of numbers are refused
    before the uniform is drawn (NaN was silently never chosen, a sum of 2 skewed every
    draw, complex ones lost their imaginary parts)."""
    rng = np.random.default_rng(4)
    n = 20000
    counts = np.bincount([select_move(rng, MOVE_PROBS) for _ in range(n)], minlength=3)
    se = np.sqrt(MOVE_PROBS * (1 - MOVE_PROBS) / n)
    assert np.all(np.abs(counts / n - MOVE_PROBS) < 5 * se), counts
    for bad, error in (([0.5, 1.5], NotNormalizedError), ([np.nan, 1.0], NegativeProbabilityError),
                       ([-0.5, 1.5], NegativeProbabilityError), ("ab", InputError),
                       ([[0.5, 0.5]], InputError), (1.0, InputError), ([], NotNormalizedError),
                       (np.array([0.5 + 1j, 0.5]), InputError)):  # fmt: skip
        rng = np.random.default_rng(0)
        with pytest.raises(error, match="move_probs"):
            select_move(rng, bad)
        assert rng.random() == np.random.default_rng(0).random(), bad  # nothing drawn


def test_incremental_target_delta_gives_the_same_chain() -> None:
    """A proposal that reports log pi(x') - log pi(x) itself drives the identical chain."""

    def with_delta(move):
        def propose(rng: np.random.Generator, x: tuple[float, ...]) -> Proposal | None:
            prop = move(rng, x)
            if prop is None:
                return None
            return prop._replace(log_target_delta=log_target(prop.state) - log_target(x))

        return propose

    moves_inc = [Move(m.name, with_delta(m.propose), m.reverse) for m in MOVES]
    a, ia = run_chain(np.random.default_rng(9), (), 2000, MOVES, log_target, MOVE_PROBS)
    b, ib = run_chain(np.random.default_rng(9), (), 2000, moves_inc, log_target, MOVE_PROBS)
    assert a == b
    assert [i.accepted for i in ia] == [i.accepted for i in ib]
    assert ib[-1].log_target == pytest.approx(log_target(b[-1]))
