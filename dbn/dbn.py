"""Two-slice dynamic Bayesian network templates (2TBN) and their unrolling.

A :class:`TwoSliceDBN` declares the variables of one time slice, the CPDs of the first
slice (``t = 0``, intra-slice parents only) and the CPDs of every later slice. A
transition CPD names a parent in the previous slice with :func:`prev`::

    hmm = TwoSliceDBN(
        variables=[DiscreteVariable("x", 3), DiscreteVariable("y", 4)],
        initial_cpds=[TabularCPD("x", [], pi), TabularCPD("y", ["x"], B)],
        transition_cpds=[TabularCPD("x", [prev("x")], A), TabularCPD("y", ["x"], B)],
    )

Any cardinality, any intra- and inter-slice edges (first order: parents in slice t or
t-1). The *interface* is the set of variables with a child in the next slice; exact
filtering carries a belief over it.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from dbn.bayesnet import CPD, BayesNet, check_sequence
from dbn.checks import check_count, from_package
from dbn.cpds import DeterministicCPD, LinearGaussianCPD, TabularCPD
from dbn.errors import ModelError, UnknownVariableError
from dbn.variables import DiscreteVariable, Variable

__all__ = ["prev", "is_prev", "unprev", "TwoSliceDBN", "PreviousSliceCPD", "slice_name",
           "check_two_slice", "MAX_UNROLL_NODES"]

_PREV = "[t-1]"

MAX_UNROLL_NODES = 10**6
"""The most nodes :meth:`TwoSliceDBN.unroll` builds (one per variable and slice)."""


def prev(name: str) -> str:
    """How a transition CPD names variable ``name`` of the previous slice: ``"name[t-1]"``."""
    return f"{name}{_PREV}"


def is_prev(name: str) -> bool:
    """True for a previous-slice reference made by :func:`prev`."""
    return name.endswith(_PREV)


def unprev(name: str) -> str:
    """The variable a previous-slice reference points at."""
    return name[: -len(_PREV)] if is_prev(name) else name


def slice_name(name: str, t: int) -> str:
    """Name of variable ``name`` at slice ``t`` in an unrolled net: ``"name_t"``."""
    return f"{name}_{t}"


def _renamed(cpd: CPD, mapping: dict[str, str]) -> CPD:
    """A copy of a CPD with the child and parents renamed (tables shared, read-only)."""
    child = mapping[cpd.variable]
    parents = [mapping[p] for p in cpd.parents]
    if isinstance(cpd, TabularCPD):
        return TabularCPD(child, parents, cpd.table)
    if isinstance(cpd, DeterministicCPD):
        return DeterministicCPD(child, parents, cpd.fn)
    if isinstance(cpd, LinearGaussianCPD):
        return LinearGaussianCPD(child, parents, cpd.weights, cpd.bias, cpd.cov)
    rename = getattr(cpd, "renamed", None)
    if callable(rename):
        return rename(child, parents)
    raise ModelError(
        f"CPD of {cpd.variable!r}: cannot rename a {type(cpd).__name__}; unrolling needs a "
        "tabular, deterministic or linear-Gaussian CPD, or a method renamed(variable, parents)"
    )


class PreviousSliceCPD:
    """Placeholder prior of a continuous previous-slice variable in ``transition_net``.

    Conditional queries on the transition slice never use it; it has no density of its
    own, so :meth:`sample` and :meth:`log_prob` raise.
    """

    def __init__(self, variable: str) -> None:
        self.variable = variable
        self.parents: tuple[str, ...] = ()

    def sample(self, key, parent_values):  # noqa: D401
        raise ModelError(
            f"{self.variable!r} is the previous slice: condition on it, do not sample it"
        )

    def log_prob(self, value, parent_values):
        raise ModelError(f"{self.variable!r} is the previous slice: condition on it")


class TwoSliceDBN:
    """A first-order two-slice DBN template.

    Parameters
    ----------
    variables : sequence of Variable
        The variables of one slice (names must not contain ``"[t-1]"``).
    initial_cpds : sequence of CPD
        One CPD per variable for slice 0; parents within slice 0.
    transition_cpds : sequence of CPD
        One CPD per variable for slices ``t >= 1``; parents are names of slice ``t`` or
        ``prev(name)`` for slice ``t - 1``.

    Raises
    ------
    ModelError (and subclasses)
        As :class:`dbn.bayesnet.BayesNet`, for either slice; each message names the slice.

    Attributes
    ----------
    initial_net : BayesNet
        Slice 0 alone.
    transition_net : BayesNet
        Slice ``t`` with the interface of slice ``t - 1`` as extra root nodes named
        ``prev(name)`` (uniform priors for discrete ones, a :class:`PreviousSliceCPD`
        placeholder for continuous ones; conditional queries never use them).
    interface : tuple of str
        Variables of slice ``t - 1`` that are parents of slice ``t`` (declaration order).
    """

    def __init__(
        self,
        variables: Sequence[Variable],
        initial_cpds: Sequence[CPD],
        transition_cpds: Sequence[CPD],
    ) -> None:
        variables = check_sequence("variables", variables)
        transition_cpds = check_sequence("transition_cpds", transition_cpds)
        for c in transition_cpds:
            if not (isinstance(getattr(c, "variable", None), str) and hasattr(c, "parents")):
                raise ModelError(f"transition slice: not a CPD: {c!r}")
        for v in variables:
            if is_prev(getattr(v, "name", "")):
                raise ModelError(f"variable name {v.name!r} may not end with {_PREV!r}")
        try:
            initial_net = BayesNet(variables, initial_cpds)
        except ModelError as exc:
            raise type(exc)(f"initial slice: {exc}") from None
        names = {v.name: v for v in variables}
        interface: list[str] = []
        for c in transition_cpds:
            for p in c.parents:
                if is_prev(p):
                    base = unprev(p)
                    if base not in names:
                        raise UnknownVariableError(
                            f"transition slice: CPD of {c.variable!r} has unknown parent {p!r}"
                        )
                    if base not in interface:
                        interface.append(base)
        order = {v.name: i for i, v in enumerate(variables)}
        interface.sort(key=order.__getitem__)
        prev_vars: list[Variable] = []
        prev_cpds: list[CPD] = []
        for base in interface:
            v = names[base]
            if isinstance(v, DiscreteVariable):
                pv = DiscreteVariable(prev(base), v.cardinality, v.state_names)
                prev_vars.append(pv)
                prev_cpds.append(
                    TabularCPD(pv.name, [], np.full(v.cardinality, 1.0 / v.cardinality))
                )
            else:  # continuous: conditioned on, never given a prior of its own
                pv = type(v)(prev(base), v.dim)
                prev_vars.append(pv)
                prev_cpds.append(PreviousSliceCPD(pv.name))
        try:
            transition_net = BayesNet(prev_vars + variables, prev_cpds + list(transition_cpds))
        except ModelError as exc:
            raise type(exc)(f"transition slice: {exc}") from None
        self._variables = tuple(variables)
        self._initial_cpds = tuple(initial_cpds)
        self._transition_cpds = tuple(transition_cpds)
        self.initial_net = initial_net
        self.transition_net = transition_net
        self.interface = tuple(interface)

    @property
    def variables(self) -> tuple[Variable, ...]:
        return self._variables

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(v.name for v in self._variables)

    @property
    def initial_cpds(self) -> tuple[CPD, ...]:
        return self._initial_cpds

    @property
    def transition_cpds(self) -> tuple[CPD, ...]:
        return self._transition_cpds

    def __repr__(self) -> str:
        return f"TwoSliceDBN(variables={list(self.names)}, interface={list(self.interface)})"

    def unroll(self, num_timesteps: int) -> BayesNet:
        """The Bayes net of slices ``0..num_timesteps-1``, nodes named ``"name_t"`` (at most
        :data:`MAX_UNROLL_NODES` nodes: it is meant for checks on short sequences)."""
        num_timesteps = check_count("num_timesteps", num_timesteps, ModelError)
        if num_timesteps * len(self._variables) > MAX_UNROLL_NODES:
            raise ModelError(
                f"unrolling {num_timesteps} slices of {len(self._variables)} variables is over "
                f"{MAX_UNROLL_NODES:,} nodes; filter it with inference.filter instead"
            )
        variables: list[Variable] = []
        cpds: list[CPD] = []
        for t in range(int(num_timesteps)):
            for v in self._variables:
                name = slice_name(v.name, t)
                if isinstance(v, DiscreteVariable):
                    variables.append(DiscreteVariable(name, v.cardinality, v.state_names))
                else:
                    variables.append(type(v)(name, v.dim))
            source = self._initial_cpds if t == 0 else self._transition_cpds
            mapping = {v.name: slice_name(v.name, t) for v in self._variables}
            if t > 0:
                mapping.update({prev(b): slice_name(b, t - 1) for b in self.interface})
            cpds.extend(_renamed(c, mapping) for c in source)
        return BayesNet(variables, cpds)


def check_two_slice(dbn: object, what: str) -> None:
    """Raise :class:`ModelError` unless ``dbn`` is a :class:`TwoSliceDBN`; ``what`` (e.g.
    "Boyen-Koller") needs one. Another model raised Python's ``AttributeError`` deep
    inside; for a pgmpy model the message says how to convert it."""
    if not isinstance(dbn, TwoSliceDBN):
        how = (" (inference.filter takes a pgmpy DynamicBayesianNetwork as it is; "
               "dbn.pgmpy_adapter.dbn_from_pgmpy converts one)"
               if from_package(dbn, "pgmpy") else "")
        raise ModelError(f"{what} needs a TwoSliceDBN, got {type(dbn).__name__}{how}")
