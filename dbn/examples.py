"""Example DBN families for tests, benchmarks and tutorials (declarations only).

:func:`coupled_chains` is the family of the generic-engine benchmark: ``n`` binary chains
in a line, chain ``i`` at slice ``t`` depending on chains ``i`` and ``i - 1`` at ``t - 1``,
one noisy binary observation per chain. Its exact belief couples every chain, so the
interface has ``2**n`` states, while each CPD touches at most three variables.
"""

from __future__ import annotations

import numpy as np

from dbn.checks import check_count
from dbn.cpds import TabularCPD
from dbn.dbn import TwoSliceDBN, prev
from dbn.errors import ModelError
from dbn.variables import DiscreteVariable

__all__ = ["coupled_chains", "sample_coupled_chains", "switching_lds", "sample_switching_lds"]


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
    n = check_count("n (number of chains)", n, ModelError)
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
    num_timesteps = check_count("num_timesteps", num_timesteps, ModelError)
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


def switching_lds(
    stay: float = 0.95, q_quiet: float = 0.01, q_manoeuvre: float = 1.0, r: float = 0.5
) -> TwoSliceDBN:
    """A switching linear dynamical system: switch ``s``, state ``x`` (position, velocity),
    observed position ``y``.

    ``s_t`` keeps its value with probability ``stay``; ``x_t = A x_{t-1} + N(0, Q[s_t])``
    with ``A = [[1, 1], [0, 0.9]]`` and ``Q[s] = diag(0.01, q_s)`` (``s = 0`` quiet,
    ``s = 1`` manoeuvring); ``y_t = x_t[0] + N(0, r)``. Slice 0: ``s_0`` uniform,
    ``x_0 ~ N(0, I)``. The CPD of ``x`` is a
    :class:`~dbn.cpds.ConditionalLinearGaussianCPD` with discrete parent ``s``.
    """
    from dbn.cpds import ConditionalLinearGaussianCPD, LinearGaussianCPD
    from dbn.variables import ContinuousVariable

    stay = _check_prob("stay", stay)
    A = np.array([[1.0, 1.0], [0.0, 0.9]])
    Q = np.array([np.diag([0.01, q_quiet]), np.diag([0.01, q_manoeuvre])])
    trans_s = np.array([[stay, 1 - stay], [1 - stay, stay]])
    s, x, y = DiscreteVariable("s", 2), ContinuousVariable("x", 2), ContinuousVariable("y", 1)
    obs = LinearGaussianCPD("y", ["x"], [[[1.0, 0.0]]], [0.0], [[r]])
    init = [
        TabularCPD("s", [], [0.5, 0.5]),
        LinearGaussianCPD("x", [], [], np.zeros(2), np.eye(2)),
        obs,
    ]
    trans = [
        TabularCPD("s", [prev("s")], trans_s),
        ConditionalLinearGaussianCPD(
            "x", ["s"], [prev("x")], [np.stack([A, A])], np.zeros((2, 2)), Q
        ),
        obs,
    ]
    return TwoSliceDBN([s, x, y], init, trans)


def sample_switching_lds(
    rng: np.random.Generator,
    num_timesteps: int,
    stay: float = 0.95,
    q_quiet: float = 0.01,
    q_manoeuvre: float = 1.0,
    r: float = 0.5,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Simulate :func:`switching_lds`: switches (T,) int, states (T, 2), observations (T, 1)."""
    switching_lds(stay, q_quiet, q_manoeuvre, r)  # validates the arguments
    A = np.array([[1.0, 1.0], [0.0, 0.9]])
    q = [q_quiet, q_manoeuvre]
    s = np.empty(num_timesteps, np.int64)
    xs = np.empty((num_timesteps, 2))
    s[0] = int(rng.random() < 0.5)
    xs[0] = rng.normal(size=2)
    for t in range(1, num_timesteps):
        s[t] = s[t - 1] if rng.random() < stay else 1 - s[t - 1]
        xs[t] = A @ xs[t - 1] + rng.normal(size=2) * np.sqrt([0.01, q[s[t]]])
    ys = xs[:, :1] + rng.normal(size=(num_timesteps, 1)) * np.sqrt(r)
    return s, xs, ys
