"""Conditional probability distributions (CPDs).

Kinds
-----
- :class:`TabularCPD`: a discrete child with discrete parents, one probability row per
  parent configuration.
- :class:`DeterministicCPD`: a discrete child that is a function of its discrete parents
  (e.g. a counter ``c_k = c_{k-1} + [l_k = new]``); exact inference sees a 0/1 table.
- :class:`LinearGaussianCPD`: a continuous child ``x ~ N(b + sum_p W_p u_p, S)``.
- :class:`ConditionalLinearGaussianCPD`: a continuous child whose linear-Gaussian
  parameters are selected by discrete parents,
  ``x ~ N(b[k] + sum_p W_p[k] u_p, S[k])`` with ``k`` the discrete parents' states
  (the switching linear dynamical system's CPD).
- :class:`ContinuousCPD`: the protocol any continuous CPD implements
  (``sample(key, parent_values)``, ``log_prob(value, parent_values)``).

Table layout
------------
A tabular CPD of a child with cardinality ``K`` and parents with cardinalities
``(K_1, ..., K_m)`` holds an array of shape ``(K_1, ..., K_m, K)``: the **last** axis is
the child, so ``table[u_1, ..., u_m]`` is the row ``P(child | parents = u)`` and sums to 1.
(pgmpy stores the transpose, ``(K, K_1 * ... * K_m)``; :mod:`dbn.pgmpy_adapter` converts.)
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike

from dbn.checks import real_array
from dbn.errors import CPDShapeError, ModelError, NegativeProbabilityError, NotNormalizedError

__all__ = [
    "ROW_TOLERANCE",
    "TabularCPD",
    "DeterministicCPD",
    "LinearGaussianCPD",
    "ContinuousCPD",
    "ConditionalLinearGaussianCPD",
    "DiscreteCPD",
]

ROW_TOLERANCE = 1e-9
"""Rows of a probability table must sum to 1 within this absolute tolerance."""


def _name_hint(value: object) -> str:
    """For a :class:`~dbn.variables.Variable` given where its name is wanted: how to fix it."""
    name = getattr(value, "name", None)
    return f" (a CPD names its variables: give {name!r})" if isinstance(name, str) else ""


def _parents_tuple(variable: str, parents: Sequence[str]) -> tuple[str, ...]:
    """The parents as a tuple of names (checked, with the CPD's own name)."""
    if not isinstance(variable, str) or not variable:
        raise ModelError(f"a CPD's variable must be a non-empty name, got {variable!r}"
                         f"{_name_hint(variable)}")  # fmt: skip
    if isinstance(parents, str) or not isinstance(parents, Iterable):
        raise ModelError(
            f"CPD of {variable!r}: parents must be a sequence of names, got {parents!r}"
        )
    out = tuple(parents)
    for p in out:
        if not isinstance(p, str) or not p:
            raise ModelError(f"CPD of {variable!r}: parent names must be non-empty strings, "
                             f"got {p!r}{_name_hint(p)}")  # fmt: skip
    if len(set(out)) != len(out):
        raise ModelError(f"CPD of {variable!r}: a parent is listed twice in {out}")
    if variable in out:
        raise ModelError(f"CPD of {variable!r}: the variable is its own parent")
    return out


def _real_array(variable: str, what: str, value: ArrayLike) -> np.ndarray:
    """``value`` as a finite float64 array of the CPD's own (a copy: the CPD freezes it,
    and the caller's array stays writable); else :class:`ModelError` naming the CPD."""
    arr = real_array(f"CPD of {variable!r}: {what}", value, ModelError).copy()
    if not np.all(np.isfinite(arr)):
        raise ModelError(f"CPD of {variable!r}: {what} must be finite")
    return arr


def _weight_list(variable: str, weights: Any, num_parents: int) -> list:
    """One weight array per continuous parent; else :class:`CPDShapeError`."""
    if isinstance(weights, str) or not isinstance(weights, Iterable):
        raise CPDShapeError(f"CPD of {variable!r}: weights must be a sequence of arrays, "
                            f"got {weights!r}")  # fmt: skip
    weights = list(weights)
    if len(weights) != num_parents:
        raise CPDShapeError(
            f"CPD of {variable!r}: {len(weights)} weight arrays for {num_parents} "
            "continuous parents"
        )
    return weights


def check_probability_table(variable: str, parents: tuple[str, ...], table: np.ndarray) -> None:
    """Raise unless ``table`` (shape ``(*parent_cards, K)``) holds probability rows.

    Raises
    ------
    NegativeProbabilityError
        An entry is negative or NaN (the message gives the first one and where).
    NotNormalizedError
        A row does not sum to 1 within :data:`ROW_TOLERANCE` (the message gives the row).
    """
    bad = ~(table >= 0)
    if bad.any():
        where = tuple(int(i) for i in np.argwhere(bad)[0])
        raise NegativeProbabilityError(
            f"CPD of {variable!r}: entry {float(table[where])!r} at {_describe(parents, where[:-1])}, "
            f"state {where[-1]} is negative or NaN"
        )
    sums = table.sum(axis=-1)
    off = np.abs(sums - 1.0) > ROW_TOLERANCE
    if off.any():
        where = tuple(int(i) for i in np.argwhere(off)[0])
        raise NotNormalizedError(
            f"CPD of {variable!r}: the row for {_describe(parents, where)} sums to "
            f"{float(sums[where])!r}, not 1 (tolerance {ROW_TOLERANCE})"
        )


def _describe(parents: tuple[str, ...], index: tuple[int, ...]) -> str:
    if not parents:
        return "the prior (no parents)"
    return "parents " + ", ".join(f"{p}={i}" for p, i in zip(parents, index))


@dataclass(frozen=True, eq=False)
class TabularCPD:
    """``P(variable | parents)`` as a table of shape ``(*parent_cardinalities, cardinality)``.

    Parameters
    ----------
    variable : str
        The child.
    parents : sequence of str
        The parents, in the order of the table's leading axes.
    table : array_like, shape ``(K_1, ..., K_m, K)``
        ``table[u] = P(variable = . | parents = u)``; every row sums to 1 within 1e-9 and
        holds no negative entry. For a root node the shape is ``(K,)``.

    The table is copied and made read-only (value semantics).
    """

    variable: str
    parents: tuple[str, ...]
    table: np.ndarray = field(repr=False)

    def __init__(self, variable: str, parents: Sequence[str], table: ArrayLike) -> None:
        parents_t = _parents_tuple(variable, parents)
        arr = real_array(f"CPD of {variable!r}: table", table, CPDShapeError).copy()
        if arr.ndim != len(parents_t) + 1:
            raise CPDShapeError(
                f"CPD of {variable!r}: table has {arr.ndim} axes, expected {len(parents_t) + 1} "
                f"(one per parent {parents_t} and one for the child, last)"
            )
        check_probability_table(variable, parents_t, arr)
        arr.setflags(write=False)
        object.__setattr__(self, "variable", variable)
        object.__setattr__(self, "parents", parents_t)
        object.__setattr__(self, "table", arr)

    @property
    def cardinality(self) -> int:
        """Number of states of the child."""
        return int(self.table.shape[-1])

    @property
    def parent_cardinalities(self) -> tuple[int, ...]:
        """Cardinalities of the parents, in order."""
        return tuple(int(k) for k in self.table.shape[:-1])

    @property
    def log_table(self) -> np.ndarray:
        """``log(table)`` (zeros become ``-inf``)."""
        with np.errstate(divide="ignore"):
            return np.log(self.table)

    def to_table(self, parent_cardinalities: Sequence[int], cardinality: int) -> np.ndarray:
        """The table, after checking it has the shape the model's cardinalities imply."""
        expected = (*tuple(int(k) for k in parent_cardinalities), int(cardinality))
        if self.table.shape != expected:
            raise CPDShapeError(
                f"CPD of {self.variable!r}: table shape {self.table.shape} does not match "
                f"{expected} (parents {self.parents} then the child)"
            )
        return self.table


@dataclass(frozen=True, eq=False)
class DeterministicCPD:
    """A discrete child that is a deterministic function of its discrete parents.

    Parameters
    ----------
    variable : str
        The child.
    parents : sequence of str
        The parents, in the order of ``fn``'s arguments.
    fn : callable
        ``fn(*parent_states) -> child_state``. It is called once with integer numpy arrays
        (all parent configurations, broadcast) and must return integer states of the same
        shape, each in ``0..cardinality-1``. Example, a counter:
        ``DeterministicCPD("c", [prev("c"), "new"], lambda c, new: np.minimum(c + new, C - 1))``.
    """

    variable: str
    parents: tuple[str, ...]
    fn: Callable[..., Any] = field(repr=False)

    def __init__(self, variable: str, parents: Sequence[str], fn: Callable[..., Any]) -> None:
        parents_t = _parents_tuple(variable, parents)
        if not callable(fn):
            raise ModelError(f"CPD of {variable!r}: fn must be callable, got {fn!r}")
        object.__setattr__(self, "variable", variable)
        object.__setattr__(self, "parents", parents_t)
        object.__setattr__(self, "fn", fn)

    def to_table(self, parent_cardinalities: Sequence[int], cardinality: int) -> np.ndarray:
        """The 0/1 table of shape ``(*parent_cardinalities, cardinality)``."""
        cards = tuple(int(k) for k in parent_cardinalities)
        if len(cards) != len(self.parents):
            raise CPDShapeError(
                f"CPD of {self.variable!r}: {len(cards)} parent cardinalities for parents {self.parents}"
            )
        grids = np.indices(cards, dtype=np.int64) if cards else np.zeros((0,), dtype=np.int64)
        try:
            out = np.asarray(self.fn(*grids) if cards else self.fn())
        except Exception as exc:  # the user's function failed: say which CPD
            raise ModelError(
                f"CPD of {self.variable!r}: fn raised {type(exc).__name__}: {exc}"
            ) from exc
        out = np.broadcast_to(out, cards)
        if not np.issubdtype(out.dtype, np.integer):
            if not np.all(np.equal(np.mod(out, 1), 0)):
                raise CPDShapeError(f"CPD of {self.variable!r}: fn returned non-integer states")
            out = out.astype(np.int64)
        bad = (out < 0) | (out >= cardinality)
        if bad.any():
            where = tuple(int(i) for i in np.argwhere(bad)[0]) if cards else ()
            raise CPDShapeError(
                f"CPD of {self.variable!r}: fn gives state {int(out[where])} for "
                f"{_describe(self.parents, where)}, outside 0..{cardinality - 1}"
            )
        table = np.zeros((*cards, int(cardinality)))
        np.put_along_axis(table, out[..., None], 1.0, axis=-1)
        return table


@runtime_checkable
class ContinuousCPD(Protocol):
    """What any continuous CPD implements (NIW, truncated normal, mixtures, ...).

    ``parent_values`` is a mapping from parent name to its value (an array).
    """

    variable: str
    parents: tuple[str, ...]

    def sample(self, key: Any, parent_values: dict[str, Any]) -> Any:
        """One draw of the child given its parents' values (``key``: a jax PRNG key)."""
        ...

    def log_prob(self, value: Any, parent_values: dict[str, Any]) -> Any:
        """``log p(value | parents)``."""
        ...


def _cov_cholesky(variable: str, S: np.ndarray) -> np.ndarray:
    """The Cholesky factor of the CPD's covariance ``S`` (d, d), or of each of a stack
    (..., d, d); a :class:`ModelError` naming the CPD unless finite, symmetric and
    positive definite."""
    if not np.all(np.isfinite(S)) or not np.allclose(S, np.swapaxes(S, -1, -2), atol=1e-12):
        raise ModelError(f"CPD of {variable!r}: cov must be finite and symmetric")
    try:
        return np.linalg.cholesky(S)
    except np.linalg.LinAlgError:
        which = "a cov[k]" if S.ndim > 2 else "cov"
        raise ModelError(f"CPD of {variable!r}: {which} is not positive definite") from None


@dataclass(frozen=True, eq=False)
class LinearGaussianCPD:
    """``x ~ N(bias + sum_p W_p u_p, cov)`` for a continuous child of dimension ``d``.

    Parameters
    ----------
    variable : str
    parents : sequence of str
        Continuous parents ``u_p``.
    weights : sequence of arrays, shapes ``(d, dim(u_p))``
        One matrix per parent, in the order of ``parents``.
    bias : array_like, shape ``(d,)``
    cov : array_like, shape ``(d, d)``
        Symmetric positive definite (checked by a Cholesky factorisation).
    """

    variable: str
    parents: tuple[str, ...]
    weights: tuple[np.ndarray, ...] = field(repr=False)
    bias: np.ndarray = field(repr=False)
    cov: np.ndarray = field(repr=False)
    chol: np.ndarray = field(repr=False)

    def __init__(
        self,
        variable: str,
        parents: Sequence[str],
        weights: Sequence[ArrayLike],
        bias: ArrayLike,
        cov: ArrayLike,
    ) -> None:
        parents_t = _parents_tuple(variable, parents)
        b = np.atleast_1d(_real_array(variable, "bias", bias))
        d = b.shape[0]
        if b.ndim != 1:
            raise CPDShapeError(f"CPD of {variable!r}: bias must be a vector, got shape {b.shape}")
        S = np.atleast_2d(_real_array(variable, "cov", cov))
        if S.shape != (d, d):
            raise CPDShapeError(f"CPD of {variable!r}: cov shape {S.shape}, expected {(d, d)}")
        L = _cov_cholesky(variable, S)
        weights = _weight_list(variable, weights, len(parents_t))
        W = []
        for p, w in zip(parents_t, weights):
            w = np.atleast_2d(_real_array(variable, f"weight of parent {p!r}", w))
            if w.shape[0] != d:
                raise CPDShapeError(
                    f"CPD of {variable!r}: weight of parent {p!r} has shape {w.shape}, needs {d} rows"
                )
            w.setflags(write=False)
            W.append(w)
        for a in (b, S, L):
            a.setflags(write=False)
        object.__setattr__(self, "variable", variable)
        object.__setattr__(self, "parents", parents_t)
        object.__setattr__(self, "weights", tuple(W))
        object.__setattr__(self, "bias", b)
        object.__setattr__(self, "cov", S)
        object.__setattr__(self, "chol", L)

    @property
    def dim(self) -> int:
        return int(self.bias.shape[0])

    def mean(self, parent_values: dict[str, Any]) -> np.ndarray:
        """``bias + sum_p W_p u_p``; shape ``(..., d)`` (parents may carry batch axes)."""
        m = self.bias
        for p, w in zip(self.parents, self.weights):
            m = m + np.asarray(parent_values[p]) @ w.T
        return m

    def sample(self, key: Any, parent_values: dict[str, Any]) -> np.ndarray:
        """One draw, ``mean + L eps`` with ``eps ~ N(0, I)`` from the jax key ``key``."""
        import jax

        m = self.mean(parent_values)
        eps = np.asarray(jax.random.normal(key, np.shape(m), dtype=np.float64))
        return m + eps @ self.chol.T

    def log_prob(self, value: ArrayLike, parent_values: dict[str, Any]) -> np.ndarray:
        """Gaussian log density by a Cholesky solve; shape ``value.shape[:-1]``."""
        from scipy.linalg import solve_triangular

        r = np.asarray(value, dtype=np.float64) - self.mean(parent_values)
        z = solve_triangular(self.chol, np.moveaxis(np.atleast_2d(r), -1, 0), lower=True)
        maha = np.sum(z**2, axis=0).reshape(np.shape(r)[:-1])
        logdet = 2.0 * np.sum(np.log(np.diag(self.chol)))
        return -0.5 * (maha + logdet + self.dim * np.log(2.0 * np.pi))


@dataclass(frozen=True, eq=False)
class ConditionalLinearGaussianCPD:
    """``x ~ N(bias[k] + sum_p W_p[k] u_p, cov[k])``: linear-Gaussian given discrete parents.

    ``k = (k_1, ..., k_m)`` are the states of the discrete parents; ``u_p`` the values of
    the continuous parents. With no discrete parent it is a :class:`LinearGaussianCPD`.

    Parameters
    ----------
    variable : str
    discrete_parents : sequence of str
        Discrete parents, in the order of the leading axes of ``bias``, ``cov`` and each
        weight array.
    continuous_parents : sequence of str
        Continuous parents ``u_p``.
    weights : sequence of arrays, shapes ``(K_1, ..., K_m, d, dim(u_p))``
        One per continuous parent.
    bias : array_like, shape ``(K_1, ..., K_m, d)``
    cov : array_like, shape ``(K_1, ..., K_m, d, d)``
        Each ``cov[k]`` symmetric positive definite (checked by Cholesky).

    Attributes
    ----------
    parents : tuple of str
        ``(*discrete_parents, *continuous_parents)``.
    chol : ndarray, shape ``(K_1, ..., K_m, d, d)``
        Lower Cholesky factors of ``cov``.
    """

    variable: str
    discrete_parents: tuple[str, ...]
    continuous_parents: tuple[str, ...]
    weights: tuple[np.ndarray, ...] = field(repr=False)
    bias: np.ndarray = field(repr=False)
    cov: np.ndarray = field(repr=False)
    chol: np.ndarray = field(repr=False)

    def __init__(
        self,
        variable: str,
        discrete_parents: Sequence[str],
        continuous_parents: Sequence[str],
        weights: Sequence[ArrayLike],
        bias: ArrayLike,
        cov: ArrayLike,
    ) -> None:
        dpa = _parents_tuple(variable, discrete_parents)
        cpa = _parents_tuple(variable, continuous_parents)
        if set(dpa) & set(cpa):
            raise ModelError(f"CPD of {variable!r}: {set(dpa) & set(cpa)} listed twice")
        m = len(dpa)
        b = _real_array(variable, "bias", bias)
        if b.ndim != m + 1:
            raise CPDShapeError(
                f"CPD of {variable!r}: bias has shape {b.shape}, expected one axis per discrete "
                f"parent {dpa} and one of size d"
            )
        kshape, d = b.shape[:-1], b.shape[-1]
        S = _real_array(variable, "cov", cov)
        if S.shape != (*kshape, d, d):
            raise CPDShapeError(
                f"CPD of {variable!r}: cov shape {S.shape}, expected {(*kshape, d, d)}"
            )
        L = _cov_cholesky(variable, S)
        weights = _weight_list(variable, weights, len(cpa))
        W = []
        for p, w in zip(cpa, weights):
            w = _real_array(variable, f"weight of parent {p!r}", w)
            if w.ndim != m + 2 or w.shape[: m + 1] != (*kshape, d) or not np.all(np.isfinite(w)):
                raise CPDShapeError(
                    f"CPD of {variable!r}: weight of parent {p!r} has shape {w.shape}, "
                    f"expected {(*kshape, d)} + (dim of {p!r},), finite"
                )
            w.setflags(write=False)
            W.append(w)
        for a in (b, S, L):
            a.setflags(write=False)
        object.__setattr__(self, "variable", variable)
        object.__setattr__(self, "discrete_parents", dpa)
        object.__setattr__(self, "continuous_parents", cpa)
        object.__setattr__(self, "weights", tuple(W))
        object.__setattr__(self, "bias", b)
        object.__setattr__(self, "cov", S)
        object.__setattr__(self, "chol", L)

    @property
    def parents(self) -> tuple[str, ...]:
        return (*self.discrete_parents, *self.continuous_parents)

    @property
    def dim(self) -> int:
        return int(self.bias.shape[-1])

    @property
    def discrete_cardinalities(self) -> tuple[int, ...]:
        return tuple(int(k) for k in self.bias.shape[:-1])

    def renamed(self, variable: str, parents: Sequence[str]) -> ConditionalLinearGaussianCPD:
        """The same CPD with the child and parents renamed (for unrolling)."""
        m = len(self.discrete_parents)
        return ConditionalLinearGaussianCPD(
            variable, parents[:m], parents[m:], self.weights, self.bias, self.cov
        )

    def _index(self, parent_values: dict[str, Any]) -> tuple[np.ndarray, ...]:
        out = []
        for p, k in zip(self.discrete_parents, self.discrete_cardinalities):
            s = np.asarray(parent_values[p])
            if not np.issubdtype(s.dtype, np.integer) or np.any((s < 0) | (s >= k)):
                raise ModelError(
                    f"CPD of {self.variable!r}: discrete parent {p!r} needs integer states "
                    f"0..{k - 1}"
                )
            out.append(s)
        return tuple(out)

    def mean(self, parent_values: dict[str, Any]) -> np.ndarray:
        """``bias[k] + sum_p W_p[k] u_p``; shape ``(..., d)`` (parents may carry batch axes)."""
        k = self._index(parent_values)
        m = self.bias[k]
        for p, w in zip(self.continuous_parents, self.weights):
            m = m + np.einsum("...ij,...j->...i", w[k], np.asarray(parent_values[p]))
        return m

    def sample(self, key: Any, parent_values: dict[str, Any]) -> np.ndarray:
        """One draw, ``mean + L[k] eps`` with ``eps ~ N(0, I)`` from the jax key ``key``."""
        import jax

        m = self.mean(parent_values)
        L = self.chol[self._index(parent_values)]
        eps = np.asarray(jax.random.normal(key, np.shape(m), dtype=np.float64))
        return m + np.einsum("...ij,...j->...i", L, eps)

    def log_prob(self, value: ArrayLike, parent_values: dict[str, Any]) -> np.ndarray:
        """Gaussian log density by a Cholesky solve; shape ``value.shape[:-1]``."""
        r = np.asarray(value, dtype=np.float64) - self.mean(parent_values)
        L = np.broadcast_to(self.chol[self._index(parent_values)], (*r.shape, r.shape[-1]))
        z = np.linalg.solve(L, r[..., None])[..., 0]  # triangular L: exact solve
        logdet = 2.0 * np.sum(np.log(np.diagonal(L, axis1=-2, axis2=-1)), axis=-1)
        return -0.5 * (np.sum(z**2, axis=-1) + logdet + self.dim * np.log(2.0 * np.pi))


DiscreteCPD = TabularCPD | DeterministicCPD
