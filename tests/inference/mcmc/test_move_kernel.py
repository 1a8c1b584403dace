"""The move-set kernel, its chain recorder and its vectorised form against oracles.

Oracles: the chain of :func:`run_chain` (every state kept) for the run-length records of
:func:`sample`; an in-place (mutable) state must give the same chain as an immutable one;
the exact stationary distribution of a small discrete birth/death/jump target for the
vectorised :class:`BatchKernel` (multinomial chi-square, fixed seeds).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
import pytest
from scipy import stats

from dbn.errors import InputError, NotNormalizedError
from inference.mcmc import (
    BatchKernel,
    BatchMove,
    BatchProposal,
    Move,
    MoveKernel,
    Proposal,
    metropolis_accept_batch,
    run_batch,
    run_chain,
    sample,
)

# ------------------------------------------------------------------ a scalar chain on Z
LOG_W = np.log(np.array([1.0, 3.0, 0.5, 2.0, 4.0, 1.5]))  # target on {0, ..., 5}


def log_target(x: int) -> float:
    return float(LOG_W[x]) if 0 <= x < len(LOG_W) else -math.inf


def up(rng: np.random.Generator, x: int) -> Proposal | None:
    return Proposal(x + 1, 0.0, 0.0)


def down(rng: np.random.Generator, x: int) -> Proposal | None:
    return None if x == 0 else Proposal(x - 1, 0.0, 0.0)


def jump(rng: np.random.Generator, x: int) -> Proposal:
    y = int(rng.integers(len(LOG_W)))
    return Proposal(y, 0.0, 0.0, log_target(y) - log_target(x))  # incremental delta


MOVES = [Move("up", up, 1), Move("down", down, 0), Move("jump", jump, 2)]
PROBS = np.array([0.5, 0.2, 0.3])  # p_up != p_down: the p_{m'}/p_m factor matters


def test_sample_records_equal_the_kept_states() -> None:
    n, burn = 3000, 400
    states, infos = run_chain(np.random.default_rng(3), 2, n, MOVES, log_target, PROBS)
    counts = np.zeros(len(LOG_W))

    def record(x: int, c: int) -> None:
        counts[x] += c

    kernel = MoveKernel(MOVES, PROBS)
    rec = sample(
        np.random.default_rng(3),
        kernel,
        2,
        n,
        log_target(2),
        log_target,
        burn_in=burn,
        record=record,
    )
    assert rec.state == states[-1]
    np.testing.assert_array_equal(counts, np.bincount(states[burn:], minlength=len(LOG_W)))
    moves = np.array([i.move for i in infos])
    acc = np.array([i.accepted for i in infos])
    np.testing.assert_array_equal(rec.tried, np.bincount(moves, minlength=3))
    np.testing.assert_array_equal(rec.accepted, np.bincount(moves[acc], minlength=3))
    assert rec.best_state == int(np.argmax(LOG_W))
    assert rec.best_log_target == pytest.approx(LOG_W.max() - 0.0)
    assert rec.log_target == pytest.approx(log_target(rec.state))


class Box:
    """A mutable state: the kernel's commit updates it in place."""

    def __init__(self, x: int) -> None:
        self.x = x


def test_in_place_state_gives_the_same_chain() -> None:
    def wrap(f):
        def propose(rng, box):
            return f(rng, box.x)

        return propose

    def commit(box: Box, x: int) -> Box:
        box.x = x
        return box

    moves = [Move(m.name, wrap(m.propose), m.reverse) for m in MOVES]
    seen: list[tuple[int, int]] = []
    rec = sample(
        np.random.default_rng(9),
        MoveKernel(moves, PROBS, commit),
        Box(0),
        500,
        log_target(0),
        log_target,  # evaluated on the proposal's state (here the new x)
        burn_in=100,
        record=lambda b, c: seen.append((b.x, c)),
        snapshot=lambda b: b.x,
    )
    ref: list[tuple[int, int]] = []
    rec2 = sample(
        np.random.default_rng(9),
        MoveKernel(MOVES, PROBS),
        0,
        500,
        log_target(0),
        log_target,
        burn_in=100,
        record=lambda x, c: ref.append((x, c)),
    )
    assert seen == ref and rec.state.x == rec2.state and rec.best_state == rec2.best_state
    assert sum(c for _, c in seen) == 400


def test_kernel_rejects_bad_declarations() -> None:
    with pytest.raises(InputError):
        MoveKernel([Move("a", up, 3)], [1.0])
    with pytest.raises(NotNormalizedError):
        MoveKernel(MOVES, [0.5, 0.5, 0.5])
    with pytest.raises(InputError):
        sample(np.random.default_rng(0), MoveKernel(MOVES, PROBS), 0, 0, 0.0, log_target)
    with pytest.raises(InputError):  # a move without delta needs log_target
        sample(np.random.default_rng(0), MoveKernel(MOVES, PROBS), 0, 50, 0.0)


def test_batch_accept_never_takes_impossible() -> None:
    rng = np.random.default_rng(0)
    log_a = np.array([-np.inf, 0.0, 5.0, np.nan, -np.inf])
    for _ in range(20):
        got = metropolis_accept_batch(rng, log_a)
        assert got.tolist() == [False, True, True, False, False]


# ------------------------------------------------------------------ vectorised chains
class Pos(NamedTuple):
    x: np.ndarray  # (num_chains,) int
    value: np.ndarray  # (num_chains,) log target


def _b_up(rng, st: Pos, rows):
    x = st.x[rows] + 1
    n = len(rows)
    ok = x < len(LOG_W)  # impossible proposals still carry a valid candidate
    return BatchProposal(Pos(np.where(ok, x, x - 1), np.zeros(n)), np.zeros(n), np.zeros(n), ok)


def _b_down(rng, st: Pos, rows):
    x = st.x[rows] - 1
    n = len(rows)
    return BatchProposal(Pos(np.maximum(x, 0), np.zeros(n)), np.zeros(n), np.zeros(n), x >= 0)


def _b_jump(rng, st: Pos, rows):
    x = rng.integers(len(LOG_W), size=len(rows))
    n = len(rows)
    return BatchProposal(Pos(x, np.zeros(n)), np.zeros(n), np.zeros(n), np.ones(n, bool))


def test_batch_chains_reach_the_exact_stationary_law() -> None:
    moves = [
        BatchMove("up", _b_up, 1),
        BatchMove("down", _b_down, 0),
        BatchMove("jump", _b_jump, 2),
    ]

    def delta(st, cand):
        new = LOG_W[cand.x]
        return new - st.value, (cand, new)

    def commit(st, scored, keep):
        cand, new = scored
        return Pos(np.where(keep, cand.x, st.x), np.where(keep, new, st.value))

    kernel = BatchKernel(moves, [0.5, 0.2, 0.3], delta, commit)
    C = 4000
    x0 = np.zeros(C, np.int64)
    rec = run_batch(np.random.default_rng(1), kernel, Pos(x0, LOG_W[x0]), 60, LOG_W[x0])
    pi = np.exp(LOG_W - LOG_W.max())
    pi /= pi.sum()
    cnt = np.bincount(rec.state.x, minlength=len(LOG_W))
    chi2 = float(((cnt - C * pi) ** 2 / (C * pi)).sum())
    assert stats.chi2.sf(chi2, len(LOG_W) - 1) > 1e-4, (cnt, C * pi)
    np.testing.assert_allclose(rec.log_target, LOG_W[rec.state.x], atol=1e-12)
    np.testing.assert_allclose(rec.best_log_target, LOG_W[rec.best_state.x], atol=1e-12)
    assert rec.tried.sum() == 60 * C and 0 < rec.accepted.sum() < rec.tried.sum()
    # power: dropping the p_{m'} / p_m factor would target w_k (p_up / p_down)^k
    wrong = np.exp(LOG_W) * (0.5 / 0.2) ** np.arange(len(LOG_W))
    wrong /= wrong.sum()
    assert ((cnt - C * wrong) ** 2 / (C * wrong)).sum() > 100


def _batch_kernel() -> BatchKernel:
    def prop(rng, x):
        return BatchProposal(x, np.zeros(len(x)), np.zeros(len(x)), np.zeros(len(x)))

    return BatchKernel([BatchMove("stay", prop, 0)], [1.0], lambda st, cand: (
        np.zeros(len(st)), cand), lambda st, scored, keep: st)  # fmt: skip


@pytest.mark.parametrize(("run", "needle"), [
    (lambda rng: sample(rng, MoveKernel(MOVES, PROBS), 0, 2.5, 0.0, log_target),
     "num_steps must be an integer >= 1, got 2.5"),
    (lambda rng: sample(0, MoveKernel(MOVES, PROBS), 0, 5, 0.0, log_target),
     "rng must be a numpy Generator"),
    (lambda rng: sample(rng, MoveKernel(MOVES, PROBS), 0, 5, 0.0, log_target, burn_in=1.5),
     "burn_in must be an integer >= 0, got 1.5"),
    (lambda rng: sample(rng, MoveKernel(MOVES, PROBS), 0, 5, math.nan, log_target),
     "log_target_value is NaN"),
    (lambda rng: run_chain(rng, 0, 3.0, MOVES, log_target, PROBS), "num_steps must be"),
    (lambda rng: run_chain(rng, 0, 3, MOVES, lambda x: math.nan, PROBS), "is NaN"),
    (lambda rng: run_batch(rng, _batch_kernel(), np.zeros(2), 2.5, np.zeros(2)),
     "num_steps must be"),
    (lambda rng: run_batch(rng, _batch_kernel(), np.zeros(2), 3, np.array([0.0, math.nan])),
     "is NaN"),
    (lambda rng: MoveKernel([up], [1.0]), "moves[0] must be a Move(name, propose, reverse)"),
])  # fmt: skip
def test_runners_refuse_bad_arguments_naming_them(run, needle) -> None:
    """2.5 steps ran 2, an int rng raised AttributeError at the first draw, a NaN start
    ran a chain that never moved, a bare function as a move raised AttributeError."""
    with pytest.raises(InputError) as exc:
        run(np.random.default_rng(0))
    assert needle in str(exc.value)
