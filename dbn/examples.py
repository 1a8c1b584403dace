"""Example DBN families for tests, benchmarks and tutorials (declarations only).

:func:`coupled_chains` is the family of the generic-engine benchmark: ``n`` binary chains
in a line, chain ``i`` at slice ``t`` depending on chains ``i`` and ``i - 1`` at ``t - 1``,
one noisy binary observation per chain. Its exact belief couples every chain, so the
interface has ``2**n`` states, while each CPD touches at most three variables.
"""

from __future__ import annotations

import numpy as np

from dbn.cpds import TabularCPD
from dbn.dbn import TwoSliceDBN, prev
from dbn.errors import ModelError
from dbn.variables import DiscreteVariable

__all__ = ["coupled_chains", "sample_coupled_chains"]


def _check_prob(name: str, value: float) -> float:
    value = float(value)
    if not 0.0 <= value <= 1.0:
        raise ModelError(f"{name} must be a probability in [0, 1], got {value!r}")
    return value


def coupled_chains(
    n: int, keep: float = 0.9, flip: float = 0.3, noise: float = 0.2, p_on: float = 0.5
) -> TwoSliceDBN:
    """``n`` coupled binary chains ``x0..x{n-1}`` with observations ``y0..y{n-1}``.

    Transition: chain ``i`` keeps its state with probability ``keep`` while its left
    neighbour ``x{i-1}[t-1]`` is off (state 0); while it is on (state 1), chain ``i`` flips
    with probability ``flip``. Chain 0 has no left neighbour and keeps with ``keep``.
    Observation: ``y{i}`` reports ``x{i}`` flipped with probability ``noise``.
    Slice 0: each chain on with probability ``p_on``, independently.

    Tables put the parents' axes first (``x{i}[t-1]``, then ``x{i-1}[t-1]``), the child last.
    """
    if isinstance(n, bool) or not isinstance(n, int | np.integer) or n < 1:
        raise ModelError(f"n (number of chains) must be an integer >= 1, got {n!r}")
    keep, flip = _check_prob("keep", keep), _check_prob("flip", flip)
    noise, p_on = _check_prob("noise", noise), _check_prob("p_on", p_on)
    stay = np.array([[keep, 1 - keep], [1 - keep, keep]])
    coupled = np.empty((2, 2, 2))
    coupled[:, 0, :] = stay  # left neighbour off
    coupled[:, 1, :] = [[1 - flip, flip], [flip, 1 - flip]]  # left neighbour on
    obs = np.array([[1 - noise, noise], [noise, 1 - noise]])
    variables, init, trans = [], [], []
    for i in range(int(n)):
        x, y = f"x{i}", f"y{i}"
        variables += [DiscreteVariable(x, 2), DiscreteVariable(y, 2)]
        init += [TabularCPD(x, [], [1 - p_on, p_on]), TabularCPD(y, [x], obs)]
        if i == 0:
            trans.append(TabularCPD(x, [prev(x)], stay))
        else:
            trans.append(TabularCPD(x, [prev(x), prev(f"x{i - 1}")], coupled))
        trans.append(TabularCPD(y, [x], obs))
    return TwoSliceDBN(variables, init, trans)


def sample_coupled_chains(
    rng: np.random.Generator,
    n: int,
    num_timesteps: int,
    keep: float = 0.9,
    flip: float = 0.3,
    noise: float = 0.2,
    p_on: float = 0.5,
) -> tuple[np.ndarray, np.ndarray]:
    """Simulate :func:`coupled_chains`: states and observations, each (num_timesteps, n) int.

    ``evidence = {f"y{i}": ys[:, i] for i in range(n)}`` is the columnar evidence the
    filters take.
    """
    coupled_chains(n, keep, flip, noise, p_on)  # validates the arguments
    xs = np.empty((num_timesteps, n), np.int64)
    x = (rng.random(n) < p_on).astype(np.int64)
    for t in range(num_timesteps):
        if t > 0:
            left_on = np.concatenate([[0], x[:-1]]) == 1
            p_flip = np.where(left_on, flip, 1 - keep)
            x = np.where(rng.random(n) < p_flip, 1 - x, x)
        xs[t] = x
    ys = np.where(rng.random((num_timesteps, n)) < noise, 1 - xs, xs)
    return xs, ys
