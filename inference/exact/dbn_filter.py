"""Exact inference in discrete two-slice DBNs: forward filter, smoother, Viterbi.

The belief carried from slice to slice is the joint distribution of the *interface*
variables (those with a child in the next slice; ``dbn.interface``), of size
``S = prod(cardinalities of the interface)``. One slice is compiled once into a dense
local table

.. math:: L(i_{t-1}, i_t, r_t) = \\prod_{v \\in \\text{slice } t} P(x_v \\mid \\mathrm{pa}(x_v)),

with ``r_t`` the other (non-interface) variables of the slice. Evidence on slice ``t``
(hard or soft, on any variable) turns it into an ``S x S`` matrix

.. math:: M_t(i, j) = \\sum_{r} L(i, j, r) \\prod_v \\lambda_{v,t}(x_v)

and the forward recursion is ``alpha_t \\propto alpha_{t-1} M_t``, normalised at every
slice with the log normaliser added to the log-likelihood, so it stays finite for any
number of slices. Matrices for the same hard evidence are built once and cached, so a
slice costs one ``S x S`` matrix-vector product.

API
---
- :class:`DBNFilter` (compile once): ``init`` / ``step`` for on-line use (pure: they return
  a new :class:`FilterState`), ``filter`` (a whole sequence, columnar evidence),
  ``smooth`` (forward-backward), ``viterbi`` (most probable explanation of every hidden
  variable of every slice), ``slice_marginals`` (every variable of the current slice).

Cost: the local table has ``S * prod(all slice cardinalities)`` entries; compiling
refuses more than :data:`MAX_LOCAL_SIZE`.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import NamedTuple

import jax
import numpy as np
from numpy.typing import ArrayLike

from dbn.bayesnet import check_likelihood
from dbn.dbn import TwoSliceDBN, check_two_slice, prev
from dbn.errors import EvidenceError, ModelError, UnknownEvidenceError
from dbn.variables import DiscreteVariable
from inference.evidence_columns import check_columns, slice_states
from inference.exact.factor import Factor, product


@jax.jit
def _forward_scan(a0: jax.Array, mats: jax.Array, steps: jax.Array) -> tuple[jax.Array, jax.Array]:
    """Normalised forward recursion ``a_t = a_{t-1} M_{steps[t]} / z_t`` (float64 scan).

    Returns the beliefs (num_steps, S) and ``z_t`` (num_steps,); a zero ``z_t`` gives NaN
    beliefs, which the caller turns into an :class:`EvidenceError`. The logarithm is
    taken by the caller in numpy: XLA's CPU ``log`` is not correctly rounded (errors of
    ~1e-8 relative were measured inside a scan).
    """

    def body(a, i):
        b = a @ mats[i]
        z = b.sum()
        b = b / z
        return b, (b, z)

    _, (beliefs, norms) = jax.lax.scan(body, a0, steps)
    return beliefs, norms


__all__ = ["DBNFilter", "FilterState", "FilterResult", "SmootherResult", "MAX_LOCAL_SIZE"]

MAX_LOCAL_SIZE = 2**24
"""Largest local table (entries) the compiler accepts."""


class FilterState(NamedTuple):
    """The on-line filter's state after slice ``t``.

    Attributes
    ----------
    t : int
        Index of the last slice absorbed (0 after ``init``).
    belief : ndarray, shape (num_interface_states,)
        ``P(interface_t | e_{0:t})``, sums to 1.
    log_likelihood : float
        ``log P(e_{0:t})``.
    """

    t: int
    belief: np.ndarray
    log_likelihood: float


class FilterResult(NamedTuple):
    """Output of :meth:`DBNFilter.filter` for ``T`` slices.

    Attributes
    ----------
    beliefs : ndarray, shape (num_timesteps, num_interface_states)
        Filtered joint of the interface at every slice.
    log_likelihood : float
        ``log P(e_{0:T-1})``.
    log_normalizers : ndarray, shape (num_timesteps,)
        ``log P(e_t | e_{0:t-1})``.
    """

    beliefs: np.ndarray
    log_likelihood: float
    log_normalizers: np.ndarray


class SmootherResult(NamedTuple):
    """Output of :meth:`DBNFilter.smooth`: ``posteriors[t] = P(interface_t | e_{0:T-1})``."""

    posteriors: np.ndarray
    log_likelihood: float


Evidence = Mapping[str, int | str]
SoftEvidence = Mapping[str, ArrayLike]


class DBNFilter:
    """Exact inference engine for a discrete :class:`~dbn.dbn.TwoSliceDBN`.

    Parameters
    ----------
    dbn : TwoSliceDBN
        All variables discrete.

    Attributes
    ----------
    interface : tuple of str
        The variables the belief is over (their joint, C order: the last varies fastest).
    num_states : int
        ``S``, the number of joint interface states.
    """

    def __init__(self, dbn: TwoSliceDBN) -> None:
        check_two_slice(dbn, "DBNFilter")
        for v in dbn.variables:
            if not isinstance(v, DiscreteVariable):
                raise ModelError(
                    f"variable {v.name!r} is continuous: DBNFilter needs discrete DBNs"
                )
        self.dbn = dbn
        self.names = dbn.names
        self._vars = {v.name: v for v in dbn.variables}
        self.cards = {v.name: v.cardinality for v in dbn.variables}
        self.interface = dbn.interface if dbn.interface else ()
        self.others = tuple(n for n in self.names if n not in self.interface)
        self.iface_cards = tuple(self.cards[n] for n in self.interface)
        self.num_states = int(np.prod(self.iface_cards)) if self.interface else 1
        other_cards = tuple(self.cards[n] for n in self.others)
        size = self.num_states * self.num_states * int(np.prod(other_cards))
        if size > MAX_LOCAL_SIZE:
            raise ModelError(
                f"the local table of one slice would have {size} entries (> {MAX_LOCAL_SIZE}): "
                "the interface or the slice is too large for this dense engine; the "
                "structured one (inference.exact.structured_filter.StructuredFilter, or "
                "inference.filter(model, evidence, method='exact')) never builds it"
            )
        # the state of each interface variable in every joint interface state
        grids = (
            np.indices(self.iface_cards).reshape(len(self.interface), -1)
            if self.interface
            else np.zeros((0, 1), int)
        )
        self._iface_state = {n: grids[k] for k, n in enumerate(self.interface)}

        order = (*self.interface, *self.others)
        init = product(
            Factor.from_table((*dbn.initial_net.parents(n), n), dbn.initial_net.table(n))
            for n in self.names
        ).transpose(order)
        self._L0 = np.exp(init.log_values).reshape(1, self.num_states, *other_cards)
        prev_iface = tuple(prev(n) for n in self.interface)
        trans = product(
            Factor.from_table((*dbn.transition_net.parents(n), n), dbn.transition_net.table(n))
            for n in self.names
        )
        # interface variables of slice t-1 that slice t does not use still index the belief
        for p, n in zip(prev_iface, self.interface):
            if p not in trans.variables:
                trans = trans.product(Factor((p,), np.zeros(self.cards[n])))
        trans = trans.transpose((*prev_iface, *order))
        self._L = np.exp(trans.log_values).reshape(self.num_states, self.num_states, *other_cards)
        self._cache: dict[tuple[bool, tuple[tuple[str, int], ...]], np.ndarray] = {}

    def __repr__(self) -> str:
        return f"DBNFilter(interface={list(self.interface)}, num_states={self.num_states})"

    # --- evidence -----------------------------------------------------------------------
    def _check(
        self, evidence: Evidence | None, soft: SoftEvidence | None
    ) -> tuple[dict[str, int], dict[str, np.ndarray]]:
        hard = slice_states(self._vars, evidence)
        lik: dict[str, np.ndarray] = {}
        for name, vec in (soft or {}).items():
            if name not in self._vars:
                raise UnknownEvidenceError(f"soft evidence on unknown variable {name!r}")
            lik[name] = check_likelihood(name, self.cards[name], vec)
        return hard, lik

    def _local(
        self, first: bool, hard: dict[str, int], soft: dict[str, np.ndarray], mode: str = "sum"
    ):
        """``M`` (S_prev x S) for one slice's evidence; with ``mode="max"`` also the argmax
        over the non-interface variables (flat index into their joint)."""
        key = (first, tuple(sorted(hard.items())))
        if mode == "sum" and not soft and key in self._cache:
            return self._cache[key]
        A = self._L0 if first else self._L
        scale = 1.0
        row = np.ones(self.num_states)
        for name, state in hard.items():
            if name in self._iface_state:
                row = row * (self._iface_state[name] == state)
        for name, vec in soft.items():
            if name in self._iface_state:
                row = row * vec[self._iface_state[name]]
        index: list[object] = [slice(None), slice(None)]
        for n in self.others:
            index.append(hard.get(n, slice(None)))
        A = A[tuple(index)]
        kept = [n for n in self.others if n not in hard]
        for k, n in enumerate(kept):
            if n in soft:
                shape = [1] * A.ndim
                shape[2 + k] = self.cards[n]
                A = A * soft[n].reshape(shape)
        for name, vec in soft.items():
            if name in hard:  # soft on an observed variable: a constant factor
                scale *= float(vec[hard[name]])
        A = A.reshape(A.shape[0], A.shape[1], -1)
        if mode == "sum":
            M = A.sum(axis=2) * row[None, :] * scale
            if not soft:
                M.setflags(write=False)
                self._cache[key] = M
            return M
        arg = A.argmax(axis=2)
        M = np.take_along_axis(A, arg[..., None], axis=2)[..., 0] * row[None, :] * scale
        return M, arg, kept

    # --- on-line filtering --------------------------------------------------------------
    def init(
        self, evidence: Evidence | None = None, soft_evidence: SoftEvidence | None = None
    ) -> FilterState:
        """Absorb slice 0 (evidence: name -> state, ``-1`` or None = unobserved). Raises
        :class:`EvidenceError` (bad or impossible evidence)."""
        hard, soft = self._check(evidence, soft_evidence)
        M = self._local(True, hard, soft)
        return self._absorb(FilterState(-1, np.ones(1), 0.0), M)

    def step(
        self,
        state: FilterState,
        evidence: Evidence | None = None,
        soft_evidence: SoftEvidence | None = None,
    ) -> FilterState:
        """Absorb the next slice; returns a new state (``state`` is not modified).

        Raises
        ------
        EvidenceError
            Bad evidence, or evidence impossible given the past (``state`` stays valid).
        """
        hard, soft = self._check(evidence, soft_evidence)
        return self._absorb(state, self._local(False, hard, soft))

    def _absorb(self, state: FilterState, M: np.ndarray) -> FilterState:
        a = state.belief @ M
        z = a.sum()
        if not z > 0.0:
            raise EvidenceError(
                f"the evidence of slice {state.t + 1} has probability zero given the past"
            )
        return FilterState(state.t + 1, a / z, state.log_likelihood + float(np.log(z)))

    def marginal(self, state: FilterState, name: str) -> np.ndarray:
        """Filtered marginal of interface variable ``name`` from a state."""
        if name not in self._iface_state:
            raise EvidenceError(
                f"{name!r} is not an interface variable {self.interface}: use slice_marginals"
            )
        return np.bincount(
            self._iface_state[name], weights=state.belief, minlength=self.cards[name]
        )

    def slice_marginals(
        self,
        state: FilterState | None,
        evidence: Evidence | None = None,
        soft_evidence: SoftEvidence | None = None,
    ) -> dict[str, np.ndarray]:
        """``P(x_v,t | e_{0:t})`` for every variable of the slice after ``state``
        (``state=None``: slice 0), given that slice's evidence."""
        hard, soft = self._check(evidence, soft_evidence)
        A = self._L0[0] if state is None else np.tensordot(state.belief, self._L, axes=(0, 0))
        row = np.ones(self.num_states)
        for name, states in self._iface_state.items():
            if name in hard:
                row = row * (states == hard[name])
            if name in soft:
                row = row * soft[name][states]
        A = A * row.reshape(-1, *([1] * len(self.others)))
        for n in self.others:
            vec = np.ones(self.cards[n])
            if n in hard:
                vec = np.eye(self.cards[n])[hard[n]]
            if n in soft:
                vec = vec * soft[n]
            shape = [1] * A.ndim
            shape[1 + self.others.index(n)] = self.cards[n]
            A = A * vec.reshape(shape)
        z = A.sum()
        if not z > 0.0:
            raise EvidenceError("the evidence has probability zero")
        A = A / z
        out = {}
        joint = A.reshape(self.num_states, -1).sum(axis=1)
        for n in self.interface:
            out[n] = np.bincount(self._iface_state[n], weights=joint, minlength=self.cards[n])
        for k, n in enumerate(self.others):
            out[n] = A.sum(axis=tuple(a for a in range(A.ndim) if a != k + 1))
        return out

    # --- whole sequences ----------------------------------------------------------------
    def _columns(
        self, evidence: Mapping[str, ArrayLike], num_timesteps: int | None
    ) -> tuple[int, dict[str, np.ndarray]]:
        """Validated columnar hard evidence (:func:`inference.evidence_columns.check_columns`)."""
        cols = check_columns(self.dbn, evidence, None, num_timesteps)
        return cols.num_timesteps, cols.discrete

    def _matrices(self, T: int, cols: dict[str, np.ndarray], mode: str = "sum"):
        """Per-slice matrices: (unique matrices, index of each slice's matrix)."""
        names = sorted(cols)
        table = np.stack([cols[n] for n in names], axis=1) if names else np.zeros((T, 0), np.int64)
        if T > 1 and names:
            # one integer code per slice's evidence row (-1 = unobserved becomes 0)
            codes = np.ravel_multi_index((table[1:] + 1).T, [self.cards[n] + 1 for n in names])
            uniq, inverse = np.unique(codes, return_inverse=True)
            keys = np.stack(np.unravel_index(uniq, [self.cards[n] + 1 for n in names]), axis=1) - 1
        else:
            keys = np.zeros((1 if T > 1 else 0, 0), np.int64)
            inverse = np.zeros(max(T - 1, 0), np.int64)

        def hard_of(row) -> dict[str, int]:
            return {n: int(s) for n, s in zip(names, row) if s >= 0}

        first = self._local(True, hard_of(table[0]), {}, mode)
        rest = [self._local(False, hard_of(k), {}, mode) for k in keys]
        return first, rest, np.asarray(inverse).reshape(-1), names

    def filter(
        self, evidence: Mapping[str, ArrayLike], num_timesteps: int | None = None
    ) -> FilterResult:
        """Filter a whole sequence.

        Parameters
        ----------
        evidence : mapping name -> array, shape (num_timesteps,)
            Columnar hard evidence: the observed state of each variable at every slice,
            ``-1`` where unobserved (or state names, None where unobserved).
        num_timesteps : int, optional
            Needed only without evidence columns.

        Returns
        -------
        FilterResult
        """
        T, cols = self._columns(evidence, num_timesteps)
        first, rest, idx, _ = self._matrices(T, cols)
        return self._forward(T, first, rest, idx)

    def _forward(
        self, T: int, first: np.ndarray, rest: list[np.ndarray], idx: np.ndarray
    ) -> FilterResult:
        """The normalised forward pass over prepared per-slice matrices."""
        # pad the slice count and the matrix stack to powers of two (identity matrices),
        # so that sequences of different lengths share a handful of compiled scans
        num = 1 << max(0, (T - 1)).bit_length()
        stack = [*rest, np.eye(self.num_states)]
        stack += [np.eye(self.num_states)] * ((1 << (len(stack) - 1).bit_length()) - len(stack))
        steps = np.full(num, len(rest), dtype=np.int32)
        steps[: T - 1] = idx
        a0 = first[0]
        z0 = a0.sum()
        if not z0 > 0.0:
            raise EvidenceError("the evidence of slice 0 has probability zero")
        with jax.enable_x64(True):  # float64 scan without touching jax's global config
            beliefs, norms = _forward_scan(a0 / z0, np.stack(stack), steps)
        beliefs = np.concatenate([(a0 / z0)[None], np.asarray(beliefs)[: T - 1]])
        norms = np.concatenate([[z0], np.asarray(norms)[: T - 1]])
        with np.errstate(divide="ignore", invalid="ignore"):
            lognorm = np.log(norms)
        if not np.all(np.isfinite(lognorm)):
            t = int(np.argmin(np.isfinite(lognorm)))
            raise EvidenceError(f"the evidence of slice {t} has probability zero given the past")
        return FilterResult(beliefs, float(lognorm.sum()), lognorm)

    def smooth(
        self, evidence: Mapping[str, ArrayLike], num_timesteps: int | None = None
    ) -> SmootherResult:
        """Forward-backward: ``P(interface_t | e_{0:T-1})`` for every slice, shape (T, S)."""
        T, cols = self._columns(evidence, num_timesteps)
        first, rest, idx, _ = self._matrices(T, cols)
        fwd = self._forward(T, first, rest, idx)
        post = np.empty_like(fwd.beliefs)
        beta = np.ones(self.num_states)
        post[T - 1] = fwd.beliefs[T - 1]
        for t in range(T - 2, -1, -1):
            beta = rest[idx[t]] @ beta
            beta = beta / beta.sum()
            p = fwd.beliefs[t] * beta
            post[t] = p / p.sum()
        return SmootherResult(post, fwd.log_likelihood)

    def marginals_of(self, beliefs: np.ndarray, name: str) -> np.ndarray:
        """Per-slice marginals ``(T, cardinality)`` of interface variable ``name`` from
        filtered or smoothed joint beliefs ``(T, S)``."""
        if name not in self._iface_state:
            raise EvidenceError(f"{name!r} is not an interface variable {self.interface}")
        onehot = np.eye(self.cards[name])[self._iface_state[name]]  # (S, K)
        return np.asarray(beliefs) @ onehot

    def viterbi(
        self, evidence: Mapping[str, ArrayLike], num_timesteps: int | None = None
    ) -> tuple[dict[str, np.ndarray], float]:
        """Most probable explanation of every unobserved variable of every slice.

        Max-product over the interface, with the non-interface variables maximised inside
        each slice's matrix, then a traceback.

        Returns
        -------
        path : dict name -> int array (num_timesteps,)
            The MPE state of every variable (observed ones repeat their evidence).
        log_prob : float
            ``log P(x*, e)``.
        """
        T, cols = self._columns(evidence, num_timesteps)
        first, rest, idx, _ = self._matrices(T, cols, mode="max")
        with np.errstate(divide="ignore"):
            logs = [np.log(m) for m, _, _ in rest]
            delta = np.log(first[0][0])
        back = np.empty((T, self.num_states), dtype=np.int64)
        for t in range(1, T):
            scores = delta[:, None] + logs[idx[t - 1]]
            back[t] = scores.argmax(axis=0)
            delta = scores[back[t], np.arange(self.num_states)]
        best = float(delta.max())
        if not np.isfinite(best):
            raise EvidenceError("the evidence has probability zero")
        states = np.empty(T, dtype=np.int64)
        states[T - 1] = int(delta.argmax())
        for t in range(T - 1, 0, -1):
            states[t - 1] = back[t, states[t]]
        path = {n: np.empty(T, dtype=np.int64) for n in self.names}
        for n in self.interface:
            path[n][:] = self._iface_state[n][states]
        for t in range(T):
            if t == 0:
                _, arg, kept = first
                flat = arg[0, states[0]]
            else:
                _, arg, kept = rest[idx[t - 1]]
                flat = arg[states[t - 1], states[t]]
            kcards = [self.cards[n] for n in kept]
            unr = np.unravel_index(int(flat), kcards) if kept else ()
            for n in self.others:
                if n in kept:
                    path[n][t] = int(unr[kept.index(n)])
                else:
                    path[n][t] = int(cols[n][t])
        return path, best
