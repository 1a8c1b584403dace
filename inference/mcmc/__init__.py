"""Metropolis-Hastings and reversible-jump MCMC kernels (generic: no tracking inside).

The kernels follow the acceptance ratio of seed 003, eq. 11: a move ``m`` drawn with
probability ``p_m`` proposes ``x'`` from ``q_m(x' | x)``; its reverse move ``m'`` would
bring ``x'`` back to ``x``; the proposal is accepted with probability
``min(1, [pi(x') / pi(x)] [p_{m'} / p_m] [q_{m'}(x | x') / q_m(x' | x)])``.

A model declares its moves (:class:`Move`: a proposal with its forward and reverse log
proposal densities and, optionally, the incremental change of the log target); the
kernel (:class:`MoveKernel`, one chain; :class:`BatchKernel`, many independent chains
vectorised) picks moves, accepts (the library's only accept rule) and the runners
(:func:`sample`, :func:`run_chain`, :func:`run_batch`) record acceptance per move,
samples and the best state.

Randomness comes from an explicit :class:`numpy.random.Generator` passed first; the same
generator state gives the same result.
"""

from inference.mcmc.batch import (
    BatchInfo,
    BatchKernel,
    BatchMove,
    BatchProposal,
    BatchRecord,
    run_batch,
    tree_where,
)
from inference.mcmc.chain import ChainRecord, sample
from inference.mcmc.kernel import (
    MHInfo,
    Move,
    MoveKernel,
    Proposal,
    RJInfo,
    log_acceptance_ratio,
    metropolis_accept,
    metropolis_accept_batch,
    mh_step,
    rj_step,
    run_chain,
    select_move,
)

__all__ = [
    "BatchInfo",
    "BatchKernel",
    "BatchMove",
    "BatchProposal",
    "BatchRecord",
    "ChainRecord",
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
    "run_batch",
    "run_chain",
    "sample",
    "select_move",
    "tree_where",
]
