"""Structured exact inference in discrete two-slice DBNs: filter, smoother, Viterbi.

The forward belief is the joint of the interface, held as a tensor with one axis per
interface variable, but a slice never builds the interface-by-interface matrix that
:class:`~inference.exact.dbn_filter.DBNFilter` builds. Each slice runs a compiled
:class:`~inference.exact.frontier.SlicePlan`: the CPDs of the slice, multiplied by their
evidence likelihoods, are eliminated into the belief one variable at a time,

.. math:: \\alpha_t(i_t) \\propto \\sum_{i_{t-1}, r_t} \\alpha_{t-1}(i_{t-1})
          \\prod_{v \\in \\text{slice } t} P(x_v \\mid \\mathrm{pa}(x_v))\\,\\lambda_{v,t}(x_v),

(the interface / frontier algorithm), so memory per slice is bounded by the largest
frontier table and time by the sum of the einsum sizes. The belief is normalised at
every slice and ``log z_t = log p(e_t | e_{0:t-1})`` accumulated, so the log-likelihood
stays finite over any number of slices. The per-slice factors that depend on evidence
only are computed once per distinct evidence row, batched over rows.

Small interfaces (``S * S <= DENSE_LIMIT = 4096`` joint-state pairs, so at most 32 KiB)
may instead run each slice as one ``S x S`` matrix-vector product, the matrix built by the
same plan from an identity message: one transition matrix times a likelihood over the
interface when the evidence sits on downstream leaves only, else one matrix per distinct
evidence row where that is cheaper than the plan. Larger interfaces never build it.

API
---
:class:`StructuredFilter` (compile once): ``init`` / ``step`` (on-line, pure: they return
a new :class:`FrontierState`), ``filter`` (a whole sequence, columnar evidence),
``smooth`` (forward-backward), ``viterbi`` (most probable explanation),
``predicted_size`` (the largest table a slice would allocate).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from dbn.dbn import TwoSliceDBN, check_two_slice, prev
from dbn.errors import (
    EvidenceError,
    FrontierTooLargeError,
    MemoryLimitError,
    ModelError,
)
from dbn.variables import DiscreteVariable
from inference.evidence_columns import check_query
from inference.exact.dbn_evidence import distinct_rows, sequence_likelihoods, slice_likelihoods
from inference.exact.frontier import (
    MAX_FRONTIER_SIZE,
    SlicePlan,
    barren,
    check_max_size,
    compile_slice_plan,
)

__all__ = ["StructuredFilter", "FrontierState", "StructuredResult", "SmoothedResult"]

_BLOCK_ENTRIES = 2**22  # entries of per-block buffers (32 MiB)
_SOURCE = prev("[source]")  # the extra axis of the dense plan (no variable can be named so)
_ROW_CACHE = 4096  # on-line evidence rows whose static tables are kept
_ONLINE_DENSE = 16  # on-line steps use the dense matrix (cached per row) up to this S
DENSE_LIMIT = 2**12
"""Interfaces with ``S * S <= DENSE_LIMIT`` joint states run each slice as one ``S x S``
matrix-vector product, the matrix built by the same plan once per distinct evidence row."""


class FrontierState(NamedTuple):
    """The on-line filter's state after slice ``t``.

    Attributes
    ----------
    t : int
        Index of the last slice absorbed (0 after ``init``).
    belief : ndarray, shape (cardinalities of the interface)
        ``P(interface_t | e_{0:t})``, one axis per interface variable, sums to 1.
    log_likelihood : float
        ``log p(e_{0:t})``.
    joint : ndarray
        ``P(interface_t, extra query variables_t | e_{0:t})`` (the belief when the query
        holds interface variables only).
    """

    t: int
    belief: np.ndarray
    log_likelihood: float
    joint: np.ndarray


class StructuredResult(NamedTuple):
    """Output of :meth:`StructuredFilter.filter` for ``T`` slices.

    Attributes
    ----------
    marginals : dict name -> ndarray, shape (T, cardinality)
        Filtered marginal of every query variable.
    log_normalizers : ndarray, shape (T,)
        ``log p(e_t | e_{0:t-1})``.
    last : FrontierState
        The state after the last slice (continue on-line with :meth:`~StructuredFilter.step`).
    """

    marginals: dict[str, np.ndarray]
    log_normalizers: np.ndarray
    last: FrontierState

    @property
    def log_likelihood(self) -> float:
        return float(np.sum(self.log_normalizers))


class SmoothedResult(NamedTuple):
    """Output of :meth:`StructuredFilter.smooth`: ``P(x_t | e_{0:T-1})`` per query variable."""

    marginals: dict[str, np.ndarray]
    log_likelihood: float


def _normalised_into(b: np.ndarray, out: np.ndarray, norms: np.ndarray, k: int, start: int):
    """``b / sum(b)`` written into ``out``, the sum into ``norms[k]``; a zero sum means the
    evidence of slice ``start + k`` is impossible given the past (EvidenceError)."""
    z = b.sum()
    if not z > 0.0:
        raise EvidenceError(
            f"the evidence of slice {start + k} has probability zero given the past"
        )
    norms[k] = z
    return np.multiply(b, 1.0 / z, out=out)


class StructuredFilter:
    """Exact structured (frontier) inference for a discrete :class:`~dbn.dbn.TwoSliceDBN`.

    Parameters
    ----------
    dbn : TwoSliceDBN
        All variables discrete.
    query : sequence of str, optional
        Variables whose per-slice marginals are reported (default: the interface). A
        non-interface variable adds its axis to the slice's output table.
    max_size : int
        Largest table (entries) a slice may allocate.
    dense_limit : int
        Small interfaces (``S * S <= dense_limit``, no extra query variable) run the
        forward pass as per-row ``S x S`` matrices built by the plan, in blocks of slices
        where the ``R`` distinct evidence rows satisfy ``R * S <=`` the block length (the
        matrices then cost less than the slices they serve); 0 turns it off.

    Raises
    ------
    ModelError
        A continuous variable, or a query naming an unknown variable
        (:class:`~dbn.errors.UnknownVariableError`).
    InputError
        A query that is neither a name nor a sequence of names.
    FrontierTooLargeError
        Even without evidence, a slice would allocate more than ``max_size`` entries.
    """

    def __init__(
        self,
        dbn: TwoSliceDBN,
        query: Sequence[str] | None = None,
        *,
        max_size: int = MAX_FRONTIER_SIZE,
        dense_limit: int = DENSE_LIMIT,
    ) -> None:
        check_two_slice(dbn, "exact filtering")
        for v in dbn.variables:
            if not isinstance(v, DiscreteVariable):
                raise ModelError(
                    f"variable {v.name!r} is continuous: exact filtering needs discrete DBNs"
                )
        self.dbn = dbn
        self.variables = {v.name: v for v in dbn.variables}
        self.interface = tuple(dbn.interface)
        self.query = tuple(dict.fromkeys(check_query(dbn, query, self.interface)))
        self.extras = tuple(q for q in self.query if q not in self.interface)
        self.max_size = check_max_size(max_size)
        self.cards = {n: v.cardinality for n, v in self.variables.items()}
        self.cards.update({prev(n): self.cards[n] for n in self.interface})
        self.iface_shape = tuple(self.cards[n] for n in self.interface)
        self.num_states = int(np.prod(self.iface_shape, dtype=np.int64))
        self.cards[_SOURCE] = self.num_states
        self._dense = not self.extras and self.num_states**2 <= dense_limit
        self._tables = [
            {n: dbn.initial_net.table(n) for n in dbn.names},
            {n: dbn.transition_net.table(n) for n in dbn.names},
        ]
        self._parents = [
            {n: dbn.initial_net.parents(n) for n in dbn.names},
            {n: dbn.transition_net.parents(n) for n in dbn.names},
        ]
        self._plans: dict[tuple, SlicePlan] = {}
        self._down = self._downstream()
        self._rows: dict = {}  # static tables per on-line evidence row; "trans": M
        self.predicted_size(())  # raises now if even the evidence-free plan is too large

    def _downstream(self) -> frozenset[str]:
        """Non-interface, non-query variables of the transition slice whose parents are
        this slice's interface or each other and whose children are each other: with
        evidence on these only, the dense slice matrix factors as ``M diag(L_r)`` (one
        transition matrix, one likelihood over the interface per evidence row)."""
        parents = self._parents[1]
        down = {
            n
            for n in self.dbn.names
            if n not in self.interface
            and n not in self.query
            and not any(p not in parents for p in parents[n])  # no previous-slice parent
        }
        changed = True
        while changed:
            changed = False
            for n in sorted(down):
                kids = [c for c in self.dbn.names if n in parents[c]]
                if any(p not in down and p not in self.interface for p in parents[n]) or any(
                    c not in down for c in kids
                ):
                    down.discard(n)
                    changed = True
        return frozenset(down)

    def __repr__(self) -> str:
        return f"StructuredFilter(interface={list(self.interface)}, query={list(self.query)})"

    # --- plans --------------------------------------------------------------------------
    def _plan(self, kind: str, evars: frozenset[str]) -> SlicePlan:
        """kind: "first" / "next" / "dense" (forward), "back" (backward message),
        "max0" / "max" (Viterbi)."""
        key = (kind, evars)
        if key in self._plans:
            return self._plans[key]
        first = kind in ("first", "max0")
        parents = self._parents[0 if first else 1]
        keep = (*self.interface, *self.extras)
        if kind in ("max0", "max"):
            needed, keep = set(parents), self.interface
        else:
            needed = set(evars) | set(self.interface) | set(self.extras)
        drop = barren(parents, needed)
        cpds = {n: parents[n] for n in self.dbn.names if n not in drop}
        prev_scope = tuple(prev(n) for n in self.interface)
        if kind in ("trans", "lik"):  # the two halves of a separable dense slice
            cpds = {n: p for n, p in cpds.items() if (n in self._down) == (kind == "lik")}
        if kind == "lik":
            plan = compile_slice_plan(cpds, self.cards, None, self.interface, limit=self.max_size)
        elif kind == "back":
            plan = compile_slice_plan(
                cpds, self.cards, self.interface, prev_scope, limit=self.max_size
            )
        elif kind in ("dense", "trans"):
            plan = compile_slice_plan(
                cpds,
                self.cards,
                (_SOURCE, *prev_scope),
                (_SOURCE, *self.interface),
                limit=self.max_size,
                input_static=True,
            )
        else:
            plan = compile_slice_plan(
                cpds, self.cards, None if first else prev_scope, keep, limit=self.max_size
            )
        self._plans[key] = plan
        return plan

    def predicted_size(self, evidence_variables: Sequence[str] = ()) -> int:
        """Entries of the largest table one slice allocates, with evidence on these
        variables (plans are compiled, nothing allocated). Raises
        :class:`~dbn.errors.FrontierTooLargeError` above ``max_size``."""
        evars = frozenset(evidence_variables)
        return max(self._plan("first", evars).max_size, self._plan("next", evars).max_size)

    # --- executing a plan ---------------------------------------------------------------
    def _static(self, plan: SlicePlan, first: bool, rows: Mapping[str, np.ndarray], R: int):
        """Slot values of the static part for ``R`` distinct evidence rows (leading axis)."""
        vals: list = [None] * len(plan.scopes)
        if plan.input_slot is not None and plan.static[plan.input_slot]:  # the dense plan
            eye = np.eye(self.num_states).reshape(1, self.num_states, *self.iface_shape)
            vals[plan.input_slot] = eye
        tables = self._tables[0 if first else 1]
        for v, s in plan.base:
            t = tables[v]
            vals[s] = (
                t[None] * rows[v].reshape(-1, *([1] * (t.ndim - 1)), t.shape[-1])
                if v in rows
                else t[None]
            )
        made = {op.output for op in plan.ops}
        for s, st in enumerate(plan.static):
            if st and vals[s] is None and s not in made:  # the constant 1
                vals[s] = np.ones((1, *(self.cards[v] for v in plan.scopes[s])))
        for op in plan.ops:
            if op.static:
                vals[op.output] = np.einsum(op.batched, *[vals[i] for i in op.inputs])
        for s, st in enumerate(plan.static):
            if st:
                if vals[s].shape[0] != R:
                    vals[s] = np.broadcast_to(vals[s], (R, *vals[s].shape[1:]))
        return vals

    @staticmethod
    def _dynamic(plan: SlicePlan):
        ops = [
            (op.matmul or op.subscripts, tuple((i, plan.static[i]) for i in op.inputs), op.output)
            for op in plan.ops
            if not op.static
        ]
        return ops, plan.static[plan.output_slot]

    def _run_block(self, plan, first, lam, evars, start, stop, msg, buf, norms):
        """Forward over slices ``start..stop-1``: normalised outputs into ``buf``, the
        normalisers into ``norms``; returns the last belief."""
        names = tuple(sorted(evars))
        rows, inverse = distinct_rows(lam, names, start, stop)
        R = int(inverse.max()) + 1 if len(inverse) else 1
        if self._dense and not first and evars <= self._down:
            return self._run_separable(evars, rows, inverse, R, msg, buf, norms, start)
        if self._dense and not first and R * self.num_states <= stop - start:
            # building R matrices costs about R * S structured slices: worth it only when
            # the block has at least that many slices
            plan = self._plan("dense", evars)
            return self._run_dense(plan, rows, inverse, R, msg, buf, norms, start)
        vals = self._static(plan, first, rows, R)
        ops, static_out = self._dynamic(plan)
        inp, out = plan.input_slot, plan.output_slot
        split = int(np.prod(self.iface_shape, dtype=np.int64))
        for k in range(stop - start):
            r = inverse[k]
            if inp is not None:
                vals[inp] = msg
            for subs, ins, o in ops:
                vals[o] = _apply(subs, [vals[i][r] if st else vals[i] for i, st in ins])
            res = vals[out][r] if static_out else vals[out]
            _normalised_into(res, buf[k], norms, k, start)
            msg = (
                buf[k]
                if not self.extras
                else buf[k].reshape(split, -1).sum(axis=1).reshape(self.iface_shape)
            )
        return msg

    def _static_entries(self, plan: SlicePlan) -> int:
        """Entries of the static tables of one evidence row."""
        return sum(
            int(np.prod([self.cards[v] for v in sc], dtype=np.int64))
            for sc, st in zip(plan.scopes, plan.static)
            if st
        )

    def _run_separable(self, evars, rows, inverse, R, msg, buf, norms, start):
        """``a_t = (a_{t-1} M) * L_r / z_t``: one transition matrix for the sequence, one
        likelihood over the interface per distinct evidence row."""
        S = self.num_states
        mat = self._rows.get("trans")
        if mat is None:  # evidence-free: built once per filter
            trans = self._plan("trans", frozenset())
            mat = self._static(trans, False, {}, 1)[trans.output_slot].reshape(S, S)
            self._rows["trans"] = mat
        lik = self._plan("lik", evars)
        L = self._static(lik, False, rows, R)[lik.output_slot].reshape(R, S)
        a = msg.reshape(S)
        flat = buf.reshape(buf.shape[0], S)
        for k in range(buf.shape[0]):
            b = (a @ mat) * L[inverse[k]]
            a = _normalised_into(b, flat[k], norms, k, start)
        return a.reshape(self.iface_shape)

    def _run_dense(self, plan, rows, inverse, R, msg, buf, norms, start):
        """The forward pass as ``a_t = a_{t-1} M_r / z_t`` with one matrix per row."""
        S = self.num_states
        mats = self._static(plan, False, rows, R)[plan.output_slot].reshape(R, S, S)
        a = msg.reshape(S)
        flat = buf.reshape(buf.shape[0], S)
        for k in range(buf.shape[0]):
            b = a @ mats[inverse[k]]
            a = _normalised_into(b, flat[k], norms, k, start)
        return a.reshape(self.iface_shape)

    def _forward(self, T: int, lam: dict[str, np.ndarray], store: np.ndarray | None = None):
        """Whole-sequence forward pass in blocks; marginals, normalisers, last state."""
        evars = frozenset(lam)
        plans = (self._plan("first", evars), self._plan("next", evars))
        out_shape = tuple(self.cards[n] for n in plans[1].output_scope)
        size = max(1, int(np.prod(out_shape, dtype=np.int64)))
        # a block of slices holds its outputs and its rows' static tables
        per_row = self._static_entries(self._plan("next", evars))
        if self._dense:
            per_row = max(per_row, self._static_entries(self._plan("dense", evars)))
        block = max(1, min(T, _BLOCK_ENTRIES // (size + per_row), 4096))
        try:
            marg = {q: np.empty((T, self.cards[q])) for q in self.query}
            norms = np.empty(T)
        except MemoryError:  # a huge num_timesteps without evidence columns
            raise MemoryLimitError(f"the marginals of {T:,} slices do not fit in memory; "
                                   "filter shorter sequences, or on-line") from None  # fmt: skip
        msg = None
        start = 0
        while start < T:
            stop = 1 if start == 0 else min(T, start + block)
            buf = store[start:stop] if store is not None else np.empty((stop - start, *out_shape))
            first = start == 0
            msg = self._run_block(
                plans[0 if first else 1],
                first,
                lam,
                evars,
                start,
                stop,
                msg,
                buf,
                norms[start:stop],
            )
            for q, m in _axis_marginals(buf, plans[1].output_scope, self.query).items():
                marg[q][start:stop] = m
            start = stop
        logz = np.log(norms)
        joint = buf[-1].copy()
        state = FrontierState(T - 1, np.array(msg, copy=True), float(logz.sum()), joint)
        return marg, logz, state

    # --- public API ---------------------------------------------------------------------
    def filter(
        self,
        evidence: Mapping[str, ArrayLike] | None = None,
        soft_evidence: Mapping[str, ArrayLike] | None = None,
        num_timesteps: int | None = None,
    ) -> StructuredResult:
        """Filter a whole sequence.

        Parameters
        ----------
        evidence : mapping name -> array, shape (T,)
            Observed state per slice, ``-1`` where unobserved (or state names, None where
            unobserved).
        soft_evidence : mapping name -> float array, shape (T, cardinality), optional
            Likelihood rows (all-NaN row: none on that slice).
        num_timesteps : int, optional
            Needed only without evidence columns.

        Raises
        ------
        EvidenceError, ShapeError
            Bad evidence, checked before any work; or evidence of probability zero.
        """
        T, lam = sequence_likelihoods(self.variables, evidence, soft_evidence, num_timesteps)
        marg, logz, last = self._forward(T, lam)
        return StructuredResult(marg, logz, last)

    def init(
        self,
        evidence: Mapping[str, int | str] | None = None,
        soft_evidence: Mapping[str, ArrayLike] | None = None,
    ) -> FrontierState:
        """Absorb slice 0 (evidence: name -> state, ``-1`` or None = unobserved,
        :func:`~inference.evidence_columns.slice_states`; soft: name -> likelihood vector)."""
        lam = slice_likelihoods(self.variables, evidence, soft_evidence)
        return self._absorb(None, lam)

    def step(
        self,
        state: FrontierState,
        evidence: Mapping[str, int | str] | None = None,
        soft_evidence: Mapping[str, ArrayLike] | None = None,
    ) -> FrontierState:
        """Absorb the next slice; returns a new state (``state`` is not modified).

        Raises
        ------
        EvidenceError
            Bad evidence, or evidence impossible given the past (``state`` stays valid).
        """
        if not isinstance(state, FrontierState) or np.shape(state.belief) != self.iface_shape:
            raise EvidenceError(
                f"state must be a FrontierState of this filter, got {type(state).__name__}"
            )
        lam = slice_likelihoods(self.variables, evidence, soft_evidence)
        return self._absorb(state, lam)

    def _absorb(self, state: FrontierState | None, lam: dict[str, np.ndarray]) -> FrontierState:
        """One on-line slice; the evidence-only tables are cached per distinct row."""
        first = state is None
        t = 0 if first else state.t + 1
        names = tuple(sorted(lam))
        dense = self._dense and not first and self.num_states <= _ONLINE_DENSE
        kind = "dense" if dense else ("first" if first else "next")
        plan = self._plan(kind, frozenset(names))
        key = (kind, names, b"".join(lam[v].tobytes() for v in names))
        vals = self._rows.get(key)
        if vals is None:
            vals = self._static(plan, first, lam, 1)
            if dense:
                S = self.num_states
                vals = vals[plan.output_slot].reshape(S, S)
            if len(self._rows) >= _ROW_CACHE:
                self._rows = {k: v for k, v in self._rows.items() if k == "trans"}
            self._rows[key] = vals
        if dense:
            out = state.belief.reshape(-1) @ vals
        else:
            vals = list(vals)
            if plan.input_slot is not None:
                vals[plan.input_slot] = state.belief
            ops, static_out = self._dynamic(plan)
            for subs, ins, o in ops:
                vals[o] = _apply(subs, [vals[i][0] if st else vals[i] for i, st in ins])
            out = vals[plan.output_slot][0] if static_out else vals[plan.output_slot]
        z = out.sum()
        if not z > 0.0:
            raise EvidenceError(f"the evidence of slice {t} has probability zero given the past")
        joint = (out / z).reshape(
            tuple(self.cards[n] for n in plan.output_scope[1 if dense else 0 :])
        )
        belief = joint
        if self.extras:
            belief = joint.reshape(self.num_states, -1).sum(axis=1).reshape(self.iface_shape)
        ll = (0.0 if first else state.log_likelihood) + float(np.log(z))
        return FrontierState(t, belief, ll, joint)

    def marginals(self, state: FrontierState) -> dict[str, np.ndarray]:
        """Filtered marginal of every query variable from a state."""
        scope = (*self.interface, *self.extras)
        return {q: m[0] for q, m in _axis_marginals(state.joint[None], scope, self.query).items()}

    def smooth(
        self,
        evidence: Mapping[str, ArrayLike] | None = None,
        soft_evidence: Mapping[str, ArrayLike] | None = None,
        num_timesteps: int | None = None,
    ) -> SmoothedResult:
        """Forward-backward: ``P(x_t | e_{0:T-1})`` of every query variable, (T, card).

        The forward outputs of all slices are kept (``T`` tables of the output size); the
        backward message over the interface is propagated by its own compiled plan.
        """
        T, lam = sequence_likelihoods(self.variables, evidence, soft_evidence, num_timesteps)
        scope = (*self.interface, *self.extras)
        out_shape = tuple(self.cards[n] for n in scope)
        total = T * max(1, int(np.prod(out_shape, dtype=np.int64)))
        if total > self.max_size:
            raise FrontierTooLargeError(
                f"smoothing keeps {T} forward tables, {total:,} entries in all, above the limit "
                f"of {self.max_size:,}; smooth shorter windows or raise max_size"
            )
        store = np.empty((T, *out_shape))
        _, logz, _ = self._forward(T, lam, store)
        evars = frozenset(lam)
        plan = self._plan("back", evars)
        beta = np.ones(self.iface_shape)
        ext = (Ellipsis, *([None] * len(self.extras)))
        for t in range(T - 1, 0, -1):
            post = store[t] * beta[ext]
            store[t] = post / post.sum()
            rows = {v: lam[v][t : t + 1] for v in evars}
            vals = self._static(plan, False, rows, 1)
            vals[plan.input_slot] = beta
            ops, static_out = self._dynamic(plan)
            for subs, ins, o in ops:
                vals[o] = _apply(subs, [vals[i][0] if st else vals[i] for i, st in ins])
            beta = vals[plan.output_slot][0] if static_out else vals[plan.output_slot]
            beta = beta / beta.sum()
        post = store[0] * beta[ext]
        store[0] = post / post.sum()
        return SmoothedResult(_axis_marginals(store, scope, self.query), float(logz.sum()))

    def viterbi(
        self,
        evidence: Mapping[str, ArrayLike] | None = None,
        soft_evidence: Mapping[str, ArrayLike] | None = None,
        num_timesteps: int | None = None,
    ) -> tuple[dict[str, np.ndarray], float]:
        """Most probable explanation of every variable of every slice (max-product over
        the same elimination plans, then a traceback).

        Returns
        -------
        path : dict name -> int array (T,)
            The MPE state of every variable (observed ones repeat their evidence).
        log_prob : float
            ``log max_x P(x, e)`` (soft evidence enters as likelihood factors).
        """
        from inference.exact.structured_viterbi import viterbi

        T, lam = sequence_likelihoods(self.variables, evidence, soft_evidence, num_timesteps)
        return viterbi(self, T, lam)


def _apply(op, operands: list[np.ndarray]) -> np.ndarray:
    """Run one dynamic op: an einsum string, or a matmul spec (see ``frontier.Op``)."""
    if isinstance(op, str):
        return np.einsum(op, *operands)
    pos, summed, perm_b, shape_b, perm_f, shape_f, shape = op
    b, f = operands[pos], operands[1 - pos]
    if summed:
        f = f.sum(axis=summed)
    r = np.matmul(b.transpose(perm_b).reshape(shape_b), f.transpose(perm_f).reshape(shape_f))
    return r.reshape(shape)


def _axis_marginals(
    x: np.ndarray, scope: Sequence[str], wanted: Sequence[str]
) -> dict[str, np.ndarray]:
    """Single-variable marginals of a batch of joint tables ``x`` (B, *cards of scope).

    Sums out the unwanted axes, then halves the remaining axes recursively (each level
    reads the table once), so all marginals cost about two passes over the table.
    """
    scope = list(scope)
    drop = tuple(1 + i for i, n in enumerate(scope) if n not in wanted)
    if drop:
        x = x.sum(axis=drop)
        scope = [n for n in scope if n in wanted]
    out: dict[str, np.ndarray] = {}
    _halve(np.ascontiguousarray(x), scope, out)
    return out


def _halve(x: np.ndarray, scope: list[str], out: dict[str, np.ndarray]) -> None:
    if len(scope) <= 1:
        if scope:
            out[scope[0]] = x
        return
    h = len(scope) // 2
    B, left, right = x.shape[0], x.shape[1 : 1 + h], x.shape[1 + h :]
    y = x.reshape(B, int(np.prod(left)), -1)
    _halve(y.sum(axis=2).reshape(B, *left), scope[:h], out)
    _halve(y.sum(axis=1).reshape(B, *right), scope[h:], out)
