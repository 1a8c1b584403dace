"""Generic Metropolis-Hastings and reversible-jump Metropolis-Hastings steps.

Seed 003, eq. 11 (after Green's reversible jump, the form used by Khan et al. and Smith
et al.): a move type ``m`` is chosen with probability ``p_m``, a new state ``x'`` is
drawn from ``q_m(x' | x)``, and it is accepted with probability ``min(1, a)`` where

.. math::

    a = \\frac{\\pi(x')}{\\pi(x)} \\, \\frac{p_{m'}}{p_m} \\,
        \\frac{q_{m'}(x ; x')}{q_m(x' ; x)},

``m'`` being the reverse move of ``m`` (the move that can bring ``x'`` back to ``x``).
Dimension-changing moves whose new coordinates are drawn directly from ``q`` (birth and
death style, as in seed 003) have unit Jacobian, which is what this kernel assumes; a
move with a deterministic non-volume-preserving map folds its log-Jacobian into
``log_q_reverse``.

States are opaque: any Python object. A proposal function returns a :class:`Proposal`
holding the new state, ``log q_m(x' | x)``, ``log q_{m'}(x | x')`` and, optionally, the
log target difference ``log pi(x') - log pi(x)`` when the caller can compute it
incrementally (seed 003's incremental likelihood); otherwise the kernel calls
``log_target``.

Conventions for impossible states: a move from a state of target ``-inf`` to a state of
finite target is always accepted (the chain leaves an impossible state as soon as it
can); a proposal to a state of target ``-inf`` is always rejected. A move that cannot be
made from ``x`` (its proposal returns ``None``) counts as a rejection, which keeps
detailed balance as long as the reverse move is equally impossible or its proposal
probability accounts for it.
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Callable, Sequence
from typing import Any, NamedTuple

import numpy as np

from dbn.checks import check_count, real_array
from dbn.errors import InputError, NegativeProbabilityError, NotNormalizedError

__all__ = [
    "MHInfo",
    "Move",
    "MoveKernel",
    "Proposal",
    "RJInfo",
    "log_acceptance_ratio",
    "metropolis_accept",
    "metropolis_accept_batch",
    "mh_step",
    "rj_step",
    "run_chain",
    "select_move",
]


class Proposal(NamedTuple):
    """A proposed state with the two proposal log densities (seed 003, eq. 11).

    Attributes
    ----------
    state : Any
        The proposed state ``x'``.
    log_q_forward : float
        ``log q_m(x' | x)``: log density (or probability) of proposing ``x'`` from ``x``.
    log_q_reverse : float
        ``log q_{m'}(x | x')``: that of the reverse move proposing ``x`` back from ``x'``.
    log_target_delta : float or None
        ``log pi(x') - log pi(x)`` when the proposal computed it (incrementally);
        ``None`` makes the kernel evaluate ``log_target`` on both states.
    """

    state: Any
    log_q_forward: float
    log_q_reverse: float
    log_target_delta: float | None = None


class Move(NamedTuple):
    """One move type of a reversible-jump sampler, paired with its reverse move.

    Attributes
    ----------
    name : str
        Human-readable name (``"birth"``, ``"update"``, ...).
    propose : callable
        ``propose(rng, state) -> Proposal | None``; ``None`` when the move cannot be made
        from ``state`` (counted as a rejection).
    reverse : int
        Index, in the move list, of the move that undoes this one (itself for a
        dimension-preserving move such as a random-walk update or a swap).
    """

    name: str
    propose: Callable[[np.random.Generator, Any], Proposal | None]
    reverse: int


class MHInfo(NamedTuple):
    """What a Metropolis-Hastings step did.

    Attributes
    ----------
    accepted : bool
        Whether the proposal was accepted.
    log_accept_ratio : float
        ``log a`` of the proposal (``-inf`` when impossible).
    log_target : float
        ``log pi`` of the state returned.
    """

    accepted: bool
    log_accept_ratio: float
    log_target: float


class RJInfo(NamedTuple):
    """What a reversible-jump step did: the move index, then as :class:`MHInfo`."""

    move: int
    accepted: bool
    log_accept_ratio: float
    log_target: float


def _target_delta(log_target_new: float, log_target_old: float) -> float:
    """``log pi(x') - log pi(x)`` with the impossible-state conventions of this module."""
    if log_target_new == -math.inf:
        return -math.inf
    if log_target_old == -math.inf:
        return math.inf
    return log_target_new - log_target_old


def log_acceptance_ratio(
    log_target_delta: float,
    log_q_forward: float,
    log_q_reverse: float,
    log_p_move: float = 0.0,
    log_p_reverse_move: float = 0.0,
) -> float:
    """Log of the reversible-jump acceptance ratio ``a`` (seed 003, eq. 11).

    .. math::

        \\log a = [\\log\\pi(x') - \\log\\pi(x)] + [\\log p_{m'} - \\log p_m]
                  + [\\log q_{m'}(x; x') - \\log q_m(x'; x)]

    Parameters
    ----------
    log_target_delta : float
        ``log pi(x') - log pi(x)`` (``+inf`` leaves an impossible state, ``-inf`` enters
        one).
    log_q_forward, log_q_reverse : float
        Proposal log densities of the move and of its reverse.
    log_p_move, log_p_reverse_move : float
        Log selection probabilities ``log p_m`` and ``log p_{m'}``.

    Returns
    -------
    float
        ``log a``; may be ``+inf`` or ``-inf``, never NaN.
    """
    if log_target_delta == -math.inf or log_q_reverse == -math.inf:
        return -math.inf
    if log_target_delta == math.inf:
        return math.inf
    value = log_target_delta + (log_p_reverse_move - log_p_move) + (log_q_reverse - log_q_forward)
    return -math.inf if math.isnan(value) else float(value)


def metropolis_accept(rng: np.random.Generator, log_accept_ratio: float) -> bool:
    """Accept with probability ``min(1, exp(log_accept_ratio))``.

    Parameters
    ----------
    rng : numpy.random.Generator
        Explicit source of randomness (one uniform is drawn, always, so the stream does
        not depend on the value of the ratio).
    log_accept_ratio : float
        ``log a`` from :func:`log_acceptance_ratio`.
    """
    u = rng.random()
    if log_accept_ratio >= 0.0:
        return True
    if u == 0.0:
        return log_accept_ratio > -math.inf
    return math.log(u) < log_accept_ratio


def metropolis_accept_batch(rng: np.random.Generator, log_accept_ratio: np.ndarray) -> np.ndarray:
    """:func:`metropolis_accept` for independent chains: one uniform per chain.

    Parameters
    ----------
    rng : numpy.random.Generator
        Explicit source of randomness (``rng.random(num_chains)`` is drawn, always).
    log_accept_ratio : ndarray, shape (num_chains,)
        ``log a`` of each chain's proposal (``-inf``: impossible, never accepted).

    Returns
    -------
    ndarray, shape (num_chains,), bool
    """
    log_a = np.asarray(log_accept_ratio, dtype=np.float64)
    u = rng.random(log_a.shape[0])
    if u.min(initial=1.0) > 0.0:
        return (log_a >= 0.0) | (np.log(u) < log_a)
    with np.errstate(divide="ignore"):  # log(0) = -inf: accepted only if log a >= 0
        return (log_a >= 0.0) | (np.log(u) < log_a)


def check_run(rng: Any, num_steps: Any) -> int:
    """``num_steps`` as an int >= 1 (2.5 ran 2 steps), after checking that ``rng`` is a
    numpy ``Generator`` (an int raised AttributeError at the first draw); else
    :class:`InputError` naming the argument. Shared by the runners."""
    if not isinstance(rng, np.random.Generator):
        raise InputError(f"rng must be a numpy Generator (np.random.default_rng(seed)), "
                         f"got {type(rng).__name__}")  # fmt: skip
    return check_count("num_steps", num_steps)


def check_start_value(log_target_value: Any) -> None:
    """Raise :class:`InputError` if the start's log target is NaN anywhere: the chain
    would never accept a move (its log acceptance ratios are NaN)."""
    if np.isnan(np.asarray(log_target_value, dtype=np.float64)).any():
        raise InputError("log_target_value is NaN: the chain could never accept a move")


def _check_move_probs(move_probs: Any, num_moves: int | None = None) -> np.ndarray:
    """``move_probs`` as float64 of shape ``(num_moves,)`` (``None``: any length) that are
    finite, >= 0 and sum to 1 within 1e-9; else a :mod:`dbn.errors` class naming it."""
    probs = real_array("move_probs", move_probs)  # complex ones lost their imaginary parts
    if num_moves is None and probs.ndim != 1:
        raise InputError(f"move_probs has shape {probs.shape}, expected one axis (num_moves,)")
    if num_moves is None:
        num_moves = probs.shape[0]
    if probs.shape != (num_moves,):
        raise InputError(f"move_probs has shape {probs.shape}, expected ({num_moves},)")
    if np.any(~np.isfinite(probs)) or np.any(probs < 0):
        raise NegativeProbabilityError(f"move_probs={probs.tolist()} has a negative or NaN entry")
    if abs(probs.sum() - 1.0) > 1e-9:
        raise NotNormalizedError(f"move_probs={probs.tolist()} sums to {probs.sum()}, not 1")
    return probs


class MoveKernel:
    """A move set with its selection probabilities, validated once (seed 003, eq. 11).

    The kernel picks a move (``p_m``), asks it for a :class:`Proposal`, applies the
    acceptance rule of :func:`log_acceptance_ratio` / :func:`metropolis_accept` and, when
    accepted, moves to the proposed state. Two kinds of state are supported:

    * immutable states (tuples, arrays): the proposal's ``state`` is the new state;
    * a state updated in place (a working object the moves read): ``commit(state,
      proposal_state) -> state`` applies an accepted proposal (``proposal_state`` is then
      whatever the move needs to apply it, e.g. a pending change).

    Parameters
    ----------
    moves : sequence of Move, length num_moves
        ``moves[m].reverse`` indexes the move that undoes move ``m``.
    move_probs : array-like, shape (num_moves,)
        Selection probabilities ``p_m`` (non-negative, summing to one).
    commit : callable, optional
        ``commit(state, proposal_state) -> state`` (default: the proposal's state).

    Raises
    ------
    InputError, NegativeProbabilityError, NotNormalizedError
        On a bad move list or probabilities.
    """

    def __init__(
        self,
        moves: Sequence[Move],
        move_probs: np.ndarray | Sequence[float],
        commit: Callable[[Any, Any], Any] | None = None,
    ) -> None:
        self.moves = tuple(moves)
        if not self.moves:
            raise InputError("moves is empty: a kernel needs at least one move")
        for m, mv in enumerate(self.moves):
            if not isinstance(mv, Move):
                raise InputError(f"moves[{m}] must be a Move(name, propose, reverse), got "
                                 f"{type(mv).__name__}")  # fmt: skip
        self.probs = _check_move_probs(np.asarray(move_probs), len(self.moves))
        for m, mv in enumerate(self.moves):
            if not 0 <= int(mv.reverse) < len(self.moves):
                raise InputError(f"moves[{m}].reverse={mv.reverse} is not a move index")
        with np.errstate(divide="ignore"):
            log_p = np.log(self.probs)
        self.log_p = log_p.tolist()
        self.log_p_reverse = [self.log_p[mv.reverse] for mv in self.moves]
        self.cum = np.cumsum(self.probs).tolist()
        self.last = len(self.moves) - 1
        self.commit = commit

    def select(self, rng: np.random.Generator) -> int:
        """Draw a move index (one uniform; the same draw as :func:`select_move`)."""
        m = bisect.bisect_right(self.cum, rng.random())
        return m if m < self.last else self.last

    def step(
        self,
        rng: np.random.Generator,
        state: Any,
        log_target_value: float,
        log_target: Callable[[Any], float] | None = None,
    ) -> tuple[Any, RJInfo]:
        """One reversible-jump step: :meth:`decide`, then :meth:`apply` if accepted.

        Parameters and randomness as in :meth:`decide`.

        Returns
        -------
        state : Any
        info : RJInfo
        """
        proposal, info = self.decide(rng, state, log_target_value, log_target)
        return (self.apply(state, proposal), info) if info.accepted else (state, info)

    def apply(self, state: Any, proposal: Proposal) -> Any:
        """The state after an accepted ``proposal`` (``commit`` or its state)."""
        return proposal.state if self.commit is None else self.commit(state, proposal.state)

    def decide(
        self,
        rng: np.random.Generator,
        state: Any,
        log_target_value: float,
        log_target: Callable[[Any], float] | None = None,
    ) -> tuple[Proposal | None, RJInfo]:
        """Select a move, propose, and accept or reject (seed 003, eq. 11); no commit.

        Parameters
        ----------
        rng : numpy.random.Generator
            Explicit source of randomness: one uniform for the move, the move's own
            draws, one uniform for the acceptance (drawn even for an impossible move, so
            the stream does not depend on the outcome).
        state : Any
            Current state.
        log_target_value : float
            ``log pi(state)`` (up to a constant shared by all states).
        log_target : callable, optional
            ``log pi``; needed only by moves whose proposals leave ``log_target_delta``
            as ``None``.

        Returns
        -------
        proposal : Proposal or None
            The proposal (``None`` if the move could not be made).
        info : RJInfo
            ``info.log_target`` is that of the state after :meth:`apply` if accepted.
        """
        m = self.select(rng)
        proposal = self.moves[m].propose(rng, state)
        if proposal is None:
            rng.random()  # keep the random stream aligned with an evaluated proposal
            return None, RJInfo(m, False, -math.inf, log_target_value)
        if proposal.log_target_delta is not None:
            delta = float(proposal.log_target_delta)
            if math.isfinite(log_target_value):
                new_value = log_target_value + delta
            else:
                new_value = math.inf if delta == math.inf else -math.inf
        elif proposal.log_q_reverse == -math.inf:
            delta = new_value = -math.inf  # rejected whatever the target: not evaluated
        else:
            if log_target is None:
                raise InputError(
                    f"move {self.moves[m].name!r} gave no log_target_delta and no "
                    "log_target was passed"
                )
            new_value = float(log_target(proposal.state))
            delta = _target_delta(new_value, log_target_value)
        log_a = log_acceptance_ratio(
            delta,
            proposal.log_q_forward,
            proposal.log_q_reverse,
            self.log_p[m],
            self.log_p_reverse[m],
        )
        if not metropolis_accept(rng, log_a):
            return proposal, RJInfo(m, False, log_a, log_target_value)
        return proposal, RJInfo(m, True, log_a, new_value)


def select_move(rng: np.random.Generator, move_probs: np.ndarray) -> int:
    """Draw a move index with probabilities ``move_probs`` (``p_m`` of seed 003, eq. 11).

    Parameters
    ----------
    rng : numpy.random.Generator
        Explicit source of randomness (one uniform is drawn).
    move_probs : ndarray, shape (num_moves,)
        Selection probabilities, summing to one.

    Raises
    ------
    InputError, NegativeProbabilityError, NotNormalizedError
        ``move_probs`` not one axis of numbers, negative or NaN, or not summing to one
        (before any draw; a NaN was chosen never and weights summing to 2 put every draw
        on the first moves).
    """
    move_probs = _check_move_probs(move_probs)
    u = rng.random()
    idx = int(np.searchsorted(np.cumsum(move_probs), u, side="right"))
    return min(idx, len(move_probs) - 1)


def mh_step(
    rng: np.random.Generator,
    state: Any,
    propose: Callable[[np.random.Generator, Any], Proposal | None],
    log_target: Callable[[Any], float],
    log_target_value: float | None = None,
) -> tuple[Any, MHInfo]:
    """One Metropolis-Hastings step (seed 003, eq. 11 with a single move type).

    Parameters
    ----------
    rng : numpy.random.Generator
        Explicit source of randomness.
    state : Any
        Current state ``x`` (not mutated).
    propose : callable
        ``propose(rng, state) -> Proposal | None``: new state with
        ``(log q(x'|x), log q(x|x'))`` and optionally the log target difference.
    log_target : callable
        Unnormalised log target ``log pi(x)``.
    log_target_value : float, optional
        ``log pi(state)`` if already known (saves one evaluation).

    Returns
    -------
    state : Any
        ``x'`` if accepted, else ``state``.
    info : MHInfo
    """
    one = Move("mh", propose, 0)
    new_state, info = rj_step(rng, state, [one], log_target, np.ones(1), log_target_value)
    return new_state, MHInfo(info.accepted, info.log_accept_ratio, info.log_target)


def rj_step(
    rng: np.random.Generator,
    state: Any,
    moves: Sequence[Move],
    log_target: Callable[[Any], float],
    move_probs: np.ndarray,
    log_target_value: float | None = None,
) -> tuple[Any, RJInfo]:
    """One reversible-jump Metropolis-Hastings step (seed 003, eq. 11).

    Chooses move ``m`` with probability ``move_probs[m]``, proposes with
    ``moves[m].propose`` and accepts with :func:`log_acceptance_ratio`, using
    ``p_{m'} = move_probs[moves[m].reverse]``.

    Parameters
    ----------
    rng : numpy.random.Generator
        Explicit source of randomness (the only one used).
    state : Any
        Current state (not mutated).
    moves : sequence of Move, length num_moves
        The move types; ``moves[m].reverse`` indexes the reverse move.
    log_target : callable
        Unnormalised log target ``log pi(x)``; may return ``-inf``.
    move_probs : ndarray, shape (num_moves,)
        Move selection probabilities ``p_m`` (sum to one).
    log_target_value : float, optional
        ``log pi(state)`` if known.

    Returns
    -------
    state : Any
        The next state of the chain.
    info : RJInfo
        Move index, acceptance, ``log a`` and ``log pi`` of the returned state.
    """
    kernel = MoveKernel(moves, move_probs)
    current = float(log_target(state)) if log_target_value is None else float(log_target_value)
    return kernel.step(rng, state, current, log_target)


def run_chain(
    rng: np.random.Generator,
    state: Any,
    num_steps: int,
    moves: Sequence[Move],
    log_target: Callable[[Any], float],
    move_probs: np.ndarray,
) -> tuple[list[Any], list[RJInfo]]:
    """Run ``num_steps`` reversible-jump steps (seed 003, eq. 11) from ``state``.

    Parameters
    ----------
    rng : numpy.random.Generator
        Explicit source of randomness.
    state : Any
        Initial state.
    num_steps : int
        Number of steps (>= 1).
    moves, log_target, move_probs
        As in :func:`rj_step`.

    Returns
    -------
    states : list, length num_steps
        The chain after each step.
    infos : list of RJInfo, length num_steps
    """
    num_steps = check_run(rng, num_steps)
    kernel = MoveKernel(moves, move_probs)
    value = float(log_target(state))
    check_start_value(value)
    states, infos = [], []
    for _ in range(num_steps):
        state, info = kernel.step(rng, state, value, log_target)
        value = info.log_target
        states.append(state)
        infos.append(info)
    return states, infos
