"""Random variables: discrete (cardinality, state names) and continuous (dimension)."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from dbn.checks import check_count
from dbn.errors import EvidenceError, ModelError

__all__ = ["DiscreteVariable", "ContinuousVariable", "Variable", "MAX_CARDINALITY"]


def _check_name(name: object) -> str:
    if not isinstance(name, str) or not name:
        raise ModelError(f"variable name must be a non-empty string, got {name!r}")
    return name


MAX_CARDINALITY = 2**24
"""The most states a discrete variable may have: one table row over them is 128 MiB."""


@dataclass(frozen=True)
class DiscreteVariable:
    """A discrete random variable with ``cardinality`` states.

    Parameters
    ----------
    name : str
        Unique name in its model.
    cardinality : int
        Number of states, 1 to :data:`MAX_CARDINALITY`.
    state_names : tuple of str, optional
        One name per state; defaults to ``("0", "1", ...)``.
    """

    name: str
    cardinality: int
    state_names: tuple[str, ...] | None = None

    def __post_init__(self) -> None:
        _check_name(self.name)
        card = check_count(f"variable {self.name!r}: cardinality", self.cardinality, ModelError)
        if card > MAX_CARDINALITY:  # its default state names alone would not fit in memory
            raise ModelError(
                f"variable {self.name!r}: cardinality {card} is over {MAX_CARDINALITY:,} (2**24)"
            )
        object.__setattr__(self, "cardinality", int(card))
        if self.state_names is None:
            object.__setattr__(self, "state_names", tuple(str(i) for i in range(card)))
        else:
            given = self.state_names
            if isinstance(given, str) or not isinstance(given, Iterable):
                raise ModelError(f"variable {self.name!r}: state_names must be a sequence of "
                                 f"names, got {given!r}")  # fmt: skip
            names = tuple(str(s) for s in given)
            if len(names) != card:
                raise ModelError(
                    f"variable {self.name!r}: {len(names)} state names for cardinality {card}"
                )
            if len(set(names)) != len(names):
                raise ModelError(f"variable {self.name!r}: duplicate state names {names}")
            object.__setattr__(self, "state_names", names)

    @property
    def renumbered(self) -> bool:
        """Whether the state names are integers other than the indices (pgmpy's states
        ``[1, 2, 3]`` become ``("1", "2", "3")``): an int there means a name to pgmpy and
        an index to :meth:`index` (pgmpy's own evidence is read as pgmpy reads it:
        :func:`inference.evidence_columns.columns_from_slices`). A CSV's fields are read by
        another rule (``models.io.dbn``); ``docs/formats.md`` ("Numbers as state names")
        states both."""
        names = self.state_names
        return (all(s.removeprefix("-").isdigit() for s in names)  # type: ignore[union-attr]
                and names != tuple(str(i) for i in range(self.cardinality)))

    def index(self, state: int | str) -> int:
        """Index of a state given by its index or its name."""
        if isinstance(state, str):
            try:
                return self.state_names.index(state)  # type: ignore[union-attr]
            except ValueError:
                raise EvidenceError(
                    f"variable {self.name!r} has no state named {state!r} "
                    f"(states: {self.state_names})"
                ) from None
        if isinstance(state, bool) or not isinstance(state, int | np.integer):
            raise EvidenceError(
                f"variable {self.name!r}: state must be an int or a name, got {state!r}"
            )
        if not 0 <= int(state) < self.cardinality:
            raise EvidenceError(
                f"variable {self.name!r}: state {state} out of range 0..{self.cardinality - 1}"
            )
        return int(state)


@dataclass(frozen=True)
class ContinuousVariable:
    """A real vector-valued random variable of dimension ``dim``."""

    name: str
    dim: int = 1

    def __post_init__(self) -> None:
        _check_name(self.name)
        dim = check_count(f"variable {self.name!r}: dim", self.dim, ModelError)
        object.__setattr__(self, "dim", dim)  # a numpy integer too, stored as an int


Variable = DiscreteVariable | ContinuousVariable
