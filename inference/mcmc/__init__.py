"""Metropolis-Hastings and reversible-jump MCMC kernels (generic: no tracking inside).

The kernels follow the acceptance ratio of seed 003, eq. 11: a move ``m`` drawn with
probability ``p_m`` proposes ``x'`` from ``q_m(x' | x)``; its reverse move ``m'`` would
bring ``x'`` back to ``x``; the proposal is accepted with probability
``min(1, [pi(x') / pi(x)] [p_{m'} / p_m] [q_{m'}(x | x') / q_m(x' | x)])``.

Randomness comes from an explicit :class:`numpy.random.Generator` passed first; the same
generator state gives the same result. The step functions never mutate the state they are
given: they return the chosen state.
"""

from inference.mcmc.kernel import (
    MHInfo,
    Move,
    Proposal,
    RJInfo,
    log_acceptance_ratio,
    metropolis_accept,
    mh_step,
    rj_step,
    run_chain,
    select_move,
)

__all__ = [
    "MHInfo",
    "Move",
    "Proposal",
    "RJInfo",
    "log_acceptance_ratio",
    "metropolis_accept",
    "mh_step",
    "rj_step",
    "run_chain",
    "select_move",
]
