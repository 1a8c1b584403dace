"""Reversible-jump steps for many independent chains at once (vectorised over chains).

The same acceptance rule as :mod:`inference.mcmc.kernel` (seed 003, eq. 11), for
``num_chains`` chains that each draw their own move type: a move type shared by all
chains would make them dependent. Each move proposes for the rows (chains) that drew it,
vectorised; the model scores all candidates at once; the kernel accepts with one uniform
per chain (:func:`~inference.mcmc.kernel.metropolis_accept_batch`).

A batch state is a NamedTuple of arrays whose leading axis is the chain (a pytree, as in
blackjax); a candidate is one such NamedTuple too (whatever fields the model's moves
produce), so the kernel can gather the moves' row blocks and keep each chain's best state
without knowing the model.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any, NamedTuple

import numpy as np

from dbn.errors import InputError
from inference.mcmc.kernel import (
    _check_move_probs,
    check_run,
    check_start_value,
    metropolis_accept_batch,
)

__all__ = [
    "BatchInfo",
    "BatchKernel",
    "BatchMove",
    "BatchProposal",
    "BatchRecord",
    "run_batch",
    "tree_where",
]


class BatchProposal(NamedTuple):
    """Proposals of one move type for ``n`` chains.

    Attributes
    ----------
    candidate : NamedTuple of arrays, leading axis n
        The proposed states (or what the model needs to score and apply them).
    log_q_forward, log_q_reverse : ndarray, shape (n,)
        ``log q_m(x' | x)`` and ``log q_{m'}(x | x')``.
    possible : ndarray, shape (n,), bool
        False where the move cannot be made (counted as a rejection).
    """

    candidate: Any
    log_q_forward: np.ndarray
    log_q_reverse: np.ndarray
    possible: np.ndarray


class BatchMove(NamedTuple):
    """A move type: ``propose(rng, state, rows) -> BatchProposal`` for chains ``rows``."""

    name: str
    propose: Callable[[np.random.Generator, Any, np.ndarray], BatchProposal]
    reverse: int


class BatchInfo(NamedTuple):
    """What one batch step did: move (num_chains,) int, accepted (num_chains,) bool,
    log_accept_ratio (num_chains,)."""

    move: np.ndarray
    accepted: np.ndarray
    log_accept_ratio: np.ndarray


def tree_where(mask: np.ndarray, a: Any, b: Any) -> Any:
    """Per chain, ``a`` where ``mask`` else ``b`` (NamedTuples of arrays, leading axis)."""
    return type(a)(
        *(np.where(mask.reshape(-1, *([1] * (np.ndim(x) - 1))), x, y) for x, y in zip(a, b))
    )


def _gather(blocks: list[tuple[np.ndarray, Any]], num: int) -> Any:
    """Assemble per-move candidate blocks (rows, NamedTuple) into one of ``num`` rows."""
    if len(blocks) == 1:
        return blocks[0][1]
    first = blocks[0][1]
    out = [np.empty((num, *np.shape(f)[1:]), dtype=np.asarray(f).dtype) for f in first]
    for rows, cand in blocks:
        for o, f in zip(out, cand):
            o[rows] = f
    return type(first)(*out)


class BatchKernel:
    """Move types with selection probabilities and the model's scoring and commit hooks.

    Parameters
    ----------
    moves : sequence of BatchMove
    move_probs : array-like, shape (num_moves,)
        ``p_m`` (non-negative, summing to one).
    log_target_delta : callable
        ``log_target_delta(state, candidate) -> (delta (num_chains,), scored)``:
        ``log pi(x') - log pi(x)`` per chain and whatever ``commit`` needs.
    commit : callable
        ``commit(state, scored, accepted (num_chains,) bool) -> state``.
    """

    def __init__(
        self,
        moves: Sequence[BatchMove],
        move_probs: np.ndarray | Sequence[float],
        log_target_delta: Callable[[Any, Any], tuple[np.ndarray, Any]],
        commit: Callable[[Any, Any, np.ndarray], Any],
    ) -> None:
        self.moves = tuple(moves)
        self.probs = _check_move_probs(np.asarray(move_probs), len(self.moves))
        for m, mv in enumerate(self.moves):
            if not 0 <= int(mv.reverse) < len(self.moves):
                raise InputError(f"moves[{m}].reverse={mv.reverse} is not a move index")
        with np.errstate(divide="ignore", invalid="ignore"):  # never-drawn moves: NaN unused
            log_p = np.log(self.probs)
            self.log_p_ratio = log_p[[mv.reverse for mv in self.moves]] - log_p
        cdf = np.cumsum(self.probs)
        self.cdf = cdf / cdf[-1]
        self.log_target_delta = log_target_delta
        self.commit = commit

    def select(self, rng: np.random.Generator, num_chains: int) -> np.ndarray:
        """One move index per chain (one uniform each), shape (num_chains,)."""
        idx = np.searchsorted(self.cdf, rng.random(num_chains), side="right")
        return np.minimum(idx, len(self.moves) - 1)

    def step(
        self,
        rng: np.random.Generator,
        state: Any,
        num_chains: int,
        move: int | None = None,
    ) -> tuple[Any, BatchInfo, np.ndarray]:
        """One step of every chain: select, propose, score, accept, commit.

        Parameters
        ----------
        rng : numpy.random.Generator
            Explicit source of randomness: ``num_chains`` uniforms for the moves (not
            drawn when ``move`` is forced), the moves' draws in move order, then
            ``num_chains`` uniforms for the acceptance.
        state : NamedTuple of arrays, leading axis num_chains
        num_chains : int
        move : int, optional
            Force this move type for every chain.

        Returns
        -------
        state, info, delta : new state, BatchInfo, and ``log pi`` change (0 if rejected)
        """
        if move is None:
            moves = self.select(rng, num_chains)
        else:
            moves = np.full(num_chains, int(move))
        blocks, lq, possible = [], np.zeros(num_chains), np.zeros(num_chains, bool)
        for mv in np.unique(moves):
            rows = np.nonzero(moves == mv)[0]
            prop = self.moves[int(mv)].propose(rng, state, rows)
            blocks.append((rows, prop.candidate))
            lq[rows] = prop.log_q_reverse - prop.log_q_forward + self.log_p_ratio[int(mv)]
            possible[rows] = prop.possible
        candidate = _gather(blocks, num_chains)
        delta, scored = self.log_target_delta(state, candidate)
        log_a = np.where(possible, delta + lq, -np.inf)
        accepted = metropolis_accept_batch(rng, log_a)
        new_state = self.commit(state, scored, accepted)
        return new_state, BatchInfo(moves, accepted, log_a), np.where(accepted, delta, 0.0)


class BatchRecord(NamedTuple):
    """What :func:`run_batch` recorded.

    Attributes
    ----------
    state : NamedTuple of arrays
        Last state of every chain.
    log_target : ndarray, shape (num_chains,)
        ``log pi`` of the last states (up to the constant of the initial values).
    tried, accepted : ndarray, shape (num_moves,)
        Selections and acceptances of each move type, over all chains and steps.
    best_state : NamedTuple of arrays
        Per chain, the state of highest ``log pi`` visited (initial state included).
    best_log_target : ndarray, shape (num_chains,)
    trace : ndarray, shape (num_steps, num_chains)
        ``log pi`` after each step.
    """

    state: Any
    log_target: np.ndarray
    tried: np.ndarray
    accepted: np.ndarray
    best_state: Any
    best_log_target: np.ndarray
    trace: np.ndarray

    @property
    def accept_rate(self) -> np.ndarray:
        """Acceptance rate of each move type (NaN if never tried)."""
        with np.errstate(invalid="ignore", divide="ignore"):
            return self.accepted / self.tried


def run_batch(
    rng: np.random.Generator,
    kernel: BatchKernel,
    state: Any,
    num_steps: int,
    log_target_value: np.ndarray,
    *,
    on_step: Callable[[int, Any, BatchInfo, np.ndarray, Any], None] | None = None,
    progress: bool = False,
) -> BatchRecord:
    """Run ``num_steps`` steps of ``num_chains`` independent chains (seed 003, eq. 11).

    Parameters
    ----------
    rng : numpy.random.Generator
        Explicit source of randomness (the only one).
    kernel : BatchKernel
    state : NamedTuple of arrays, leading axis num_chains
    num_steps : int
        Steps per chain (>= 1).
    log_target_value : ndarray, shape (num_chains,)
        ``log pi`` of the initial states.
    on_step : callable, optional
        ``on_step(step, state, info, best_log_target, best_state)`` after each step, to
        record what the model needs (co-occurrence counts, checkpoints).
    progress : bool
        Show a tqdm bar over the steps.

    Returns
    -------
    BatchRecord
    """
    num_steps = check_run(rng, num_steps)
    check_start_value(log_target_value)
    value = np.asarray(log_target_value, dtype=np.float64).copy()
    num_chains = value.shape[0]
    num_moves = len(kernel.moves)
    tried = np.zeros(num_moves)
    accepted = np.zeros(num_moves)
    trace = np.empty((num_steps, num_chains))
    best_value, best = value.copy(), state
    steps = range(num_steps)
    if progress:
        from inference.progress import progress_bar

        steps = progress_bar(steps, desc="MCMC", unit="step")
    for s in steps:
        state, info, delta = kernel.step(rng, state, num_chains)
        value = value + delta
        tried += np.bincount(info.move, minlength=num_moves)
        accepted += np.bincount(info.move, weights=info.accepted, minlength=num_moves)
        trace[s] = value
        better = value > best_value
        if better.any():
            best_value = np.where(better, value, best_value)
            best = tree_where(better, state, best)
        if on_step is not None:
            on_step(s, state, info, best_value, best)
    return BatchRecord(state, value, tried, accepted, best, best_value, trace)
