"""Run one reversible-jump chain and record it: acceptance per move, samples, best state.

The loop of seed 003's per-frame sampler (eq. 11 applied ``num_steps`` times, the first
``burn_in`` samples discarded) for any :class:`~inference.mcmc.kernel.MoveKernel`.
Samples are handed to the caller in run-length form: a chain that rejects keeps its
state, so ``record(state, count)`` is called once per distinct kept state with the
number of consecutive kept samples equal to it (the sum of the counts is
``num_steps - burn_in``). A Monte-Carlo average ``sum_s f(x_s) / n`` is then
``sum count * f(state) / n`` without touching the rejected steps, which is what makes a
state updated in place cheap to record.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, NamedTuple

import numpy as np

from dbn.checks import check_size
from dbn.errors import InputError
from inference.mcmc.kernel import MoveKernel, check_run, check_start_value

__all__ = ["ChainRecord", "sample"]


class ChainRecord(NamedTuple):
    """What :func:`sample` recorded.

    Attributes
    ----------
    state : Any
        The chain's last state.
    log_target : float
        ``log pi`` of the last state (up to the constant of the initial value).
    tried : ndarray, shape (num_moves,)
        How many times each move was selected.
    accepted : ndarray, shape (num_moves,)
        How many of those proposals were accepted.
    best_state : Any
        The state of highest ``log pi`` visited (the initial state included); ``None``
        for a state updated in place without a ``snapshot`` function.
    best_log_target : float
    best_step : int
        Step after which the best state was reached (-1: the initial state).
    """

    state: Any
    log_target: float
    tried: np.ndarray
    accepted: np.ndarray
    best_state: Any
    best_log_target: float
    best_step: int

    @property
    def accept_rate(self) -> np.ndarray:
        """Acceptance rate of each move, shape (num_moves,) (NaN if never tried)."""
        with np.errstate(invalid="ignore", divide="ignore"):
            return self.accepted / self.tried


def sample(
    rng: np.random.Generator,
    kernel: MoveKernel,
    state: Any,
    num_steps: int,
    log_target_value: float,
    log_target: Callable[[Any], float] | None = None,
    *,
    burn_in: int = 0,
    record: Callable[[Any, int], None] | None = None,
    snapshot: Callable[[Any], Any] | None = None,
) -> ChainRecord:
    """Run ``num_steps`` steps of ``kernel`` from ``state`` (seed 003, eq. 11).

    Parameters
    ----------
    rng : numpy.random.Generator
        Explicit source of randomness (the only one).
    kernel : MoveKernel
        Moves, their probabilities and the commit rule.
    state : Any
        Initial state (updated in place if the kernel's ``commit`` does so).
    num_steps : int
        Number of steps (>= 1).
    log_target_value : float
        ``log pi(state)``, up to a constant (the moves' ``log_target_delta`` are added).
    log_target : callable, optional
        ``log pi``, for moves that do not give ``log_target_delta``.
    burn_in : int
        Samples (states after steps ``0 .. burn_in - 1``) not passed to ``record``.
    record : callable, optional
        ``record(state, count)``: a kept state and the number of consecutive kept samples
        equal to it, called before the state changes and once at the end.
    snapshot : callable, optional
        ``snapshot(state) -> copy``, to keep the best state of a chain updated in place.

    Returns
    -------
    ChainRecord
    """
    num_steps = check_run(rng, num_steps)
    if check_size("burn_in", burn_in) > num_steps:
        raise InputError(f"burn_in={burn_in} must be in [0, num_steps={num_steps}]")
    check_start_value(log_target_value)
    num_moves = len(kernel.moves)
    tried = [0] * num_moves
    accepted = [0] * num_moves
    keep_best = snapshot is not None or kernel.commit is None
    value = float(log_target_value)
    best_value, best_step = value, -1
    best = (snapshot(state) if snapshot is not None else state) if keep_best else None
    last = int(burn_in)  # first kept sample not yet recorded
    decide, apply = kernel.decide, kernel.apply
    for it in range(num_steps):
        proposal, info = decide(rng, state, value, log_target)
        tried[info.move] += 1
        if not info.accepted:
            continue
        accepted[info.move] += 1
        if it >= last:  # the old state held the kept samples last .. it - 1
            if record is not None and it > last:
                record(state, it - last)
            last = it
        state, value = apply(state, proposal), info.log_target
        if value > best_value or (best_value == -math.inf and value > -math.inf):
            best_value, best_step = value, it
            if keep_best:
                best = snapshot(state) if snapshot is not None else state
    if record is not None and num_steps > last:
        record(state, num_steps - last)
    return ChainRecord(
        state,
        value,
        np.asarray(tried, dtype=np.int64),
        np.asarray(accepted, dtype=np.int64),
        best,
        best_value,
        best_step,
    )
