"""Log-space discrete factors with value semantics.

A :class:`Factor` is a nonnegative function of a few discrete variables stored as
``log_values`` of shape ``cards`` (one axis per variable, in ``variables`` order).
Every operation returns a new factor; none mutates its operands.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from dbn.checks import real_array
from dbn.errors import (
    EvidenceError,
    ModelError,
    NegativeProbabilityError,
    ShapeError,
    UnknownVariableError,
)

__all__ = ["Factor", "logsumexp", "product"]


def logsumexp(a: np.ndarray, axis: int | tuple[int, ...] | None = None) -> np.ndarray:
    """``log(sum(exp(a)))`` over ``axis``, exact for all ``-inf`` slices (gives ``-inf``)."""
    a = np.asarray(a, dtype=np.float64)
    if a.size == 0:
        return np.log(np.sum(np.exp(a), axis=axis))
    m = np.max(a, axis=axis, keepdims=True)
    m = np.where(np.isfinite(m), m, 0.0)
    with np.errstate(divide="ignore"):
        out = np.log(np.sum(np.exp(a - m), axis=axis, keepdims=True)) + m
    return np.squeeze(out, axis=axis) if axis is not None else out.reshape(())


@dataclass(frozen=True, eq=False)
class Factor:
    """``phi(variables) = exp(log_values)``.

    Parameters
    ----------
    variables : tuple of str
        Distinct variable names, one per axis.
    log_values : ndarray, shape ``(card_1, ..., card_n)``
        Log of the factor's values (``-inf`` for zeros). Stored read-only.
    """

    variables: tuple[str, ...]
    log_values: np.ndarray

    def __post_init__(self) -> None:
        if isinstance(self.variables, str):  # 'ab' was read as the variables 'a', 'b'
            raise ModelError(f"factor variables must be a tuple of names, got "
                             f"{self.variables!r}")  # fmt: skip
        variables = tuple(self.variables)
        values = np.array(real_array(f"factor over {variables}: log_values", self.log_values))
        if values.ndim != len(variables):
            raise ShapeError(
                f"factor over {variables} needs {len(variables)} axes, got shape {values.shape}"
            )
        if len(set(variables)) != len(variables):
            raise ModelError(f"factor variables must be distinct, got {variables}")
        values.setflags(write=False)
        object.__setattr__(self, "variables", variables)
        object.__setattr__(self, "log_values", values)

    # --- constructors ---------------------------------------------------------------------
    @classmethod
    def from_table(cls, variables: Sequence[str], table: np.ndarray) -> Factor:
        """A factor from nonnegative values (not logs)."""
        if not isinstance(variables, str):  # a string is refused by the constructor
            variables = tuple(variables)
        table = real_array(f"factor over {variables}: table", table)
        if not np.all(table >= 0):  # log gave NaN with only a RuntimeWarning
            raise NegativeProbabilityError(f"factor over {variables}: table holds a "
                                           "negative value or NaN")  # fmt: skip
        with np.errstate(divide="ignore"):
            return cls(variables, np.log(table))

    @classmethod
    def unit(cls) -> Factor:
        """The factor over no variables with value 1."""
        return cls((), np.zeros(()))

    # --- views ----------------------------------------------------------------------------
    @property
    def cards(self) -> tuple[int, ...]:
        return tuple(int(k) for k in self.log_values.shape)

    @property
    def values(self) -> np.ndarray:
        """``exp(log_values)``."""
        return np.exp(self.log_values)

    def card(self, name: str) -> int:
        return self.cards[self._axis(name)]

    def _axis(self, name: str) -> int:
        try:
            return self.variables.index(name)
        except ValueError:
            raise UnknownVariableError(
                f"factor over {self.variables} has no variable {name!r}"
            ) from None

    def __repr__(self) -> str:
        return f"Factor({self.variables}, cards={self.cards})"

    # --- algebra --------------------------------------------------------------------------
    def aligned(self, variables: Sequence[str]) -> np.ndarray:
        """``log_values`` transposed and expanded to broadcast against ``variables``
        (which must include all of this factor's variables)."""
        variables = tuple(variables)
        perm = sorted(range(len(self.variables)), key=lambda i: variables.index(self.variables[i]))
        arr = np.transpose(self.log_values, perm)
        present = sorted(variables.index(v) for v in self.variables)
        shape = [1] * len(variables)
        for ax, pos in enumerate(present):
            shape[pos] = arr.shape[ax]
        return arr.reshape(shape)

    def product(self, other: Factor) -> Factor:
        """Pointwise product (sum of logs) over the union of the variables."""
        variables = self.variables + tuple(v for v in other.variables if v not in self.variables)
        return Factor(variables, self.aligned(variables) + other.aligned(variables))

    __mul__ = product

    def marginalize(self, names: Iterable[str]) -> Factor:
        """Sum out ``names`` (logsumexp)."""
        axes = tuple(sorted({self._axis(n) for n in names}))
        if not axes:
            return self
        keep = tuple(v for i, v in enumerate(self.variables) if i not in axes)
        return Factor(keep, logsumexp(self.log_values, axis=axes))

    def maximize(self, names: Iterable[str]) -> Factor:
        """Max out ``names``."""
        axes = tuple(sorted({self._axis(n) for n in names}))
        if not axes:
            return self
        keep = tuple(v for i, v in enumerate(self.variables) if i not in axes)
        return Factor(keep, np.max(self.log_values, axis=axes))

    def keep(self, names: Iterable[str]) -> Factor:
        """Sum out every variable not in ``names``."""
        names = set(names)
        return self.marginalize([v for v in self.variables if v not in names])

    def reduce(self, evidence: Mapping[str, int]) -> Factor:
        """Condition on hard evidence: index the observed axes (they disappear)."""
        index: list[object] = []
        keep: list[str] = []
        for v, k in zip(self.variables, self.cards):
            if v in evidence:
                s = int(evidence[v])
                if not 0 <= s < k:
                    raise EvidenceError(f"state {s} of {v!r} out of range 0..{k - 1}")
                index.append(s)
            else:
                index.append(slice(None))
                keep.append(v)
        return Factor(tuple(keep), self.log_values[tuple(index)])

    def log_normalizer(self) -> float:
        """``log sum_x phi(x)``."""
        return float(logsumexp(self.log_values))

    def normalize(self) -> Factor:
        """The factor divided by its sum (a distribution); an all-zero factor is an error."""
        z = self.log_normalizer()
        if not np.isfinite(z):
            raise EvidenceError(f"factor over {self.variables} has zero mass (impossible evidence)")
        return Factor(self.variables, self.log_values - z)

    def transpose(self, variables: Sequence[str]) -> Factor:
        """The same factor with its axes in the order ``variables``."""
        variables = tuple(variables)
        if set(variables) != set(self.variables) or len(variables) != len(self.variables):
            raise UnknownVariableError(f"{variables} is not a permutation of {self.variables}")
        return Factor(variables, np.transpose(self.log_values, [self._axis(v) for v in variables]))

    def probabilities(self, variables: Sequence[str] | None = None) -> np.ndarray:
        """Normalised probabilities, axes in ``variables`` order (default: own order)."""
        f = self.normalize()
        if variables is not None:
            f = f.transpose(variables)
        return np.exp(f.log_values)


def product(factors: Iterable[Factor]) -> Factor:
    """Product of several factors (the unit factor for none), in one broadcast sum."""
    factors = list(factors)
    if not factors:
        return Factor.unit()
    variables: list[str] = []
    for f in factors:
        variables.extend(v for v in f.variables if v not in variables)
    # every variable appears in some factor, so the broadcast sum has the full shape
    return Factor(tuple(variables), sum(f.aligned(variables) for f in factors))
