"""Viterbi (most probable explanation) over the structured filter's elimination plans.

Max-product on the same per-slice plans as the forward filter, with no barren variable
dropped (every variable gets a state): each elimination step keeps its argmax table, and
a traceback from the last slice reads every eliminated variable's state off its table,
slice by slice, in reverse elimination order,

.. math:: \\delta_t(i_t) = \\max_{i_{t-1}, r_t} \\delta_{t-1}(i_{t-1})
          \\prod_{v} P(x_v \\mid \\mathrm{pa}(x_v))\\,\\lambda_{v,t}(x_v),

with ``delta`` rescaled by its maximum at every slice (log scale accumulated).
"""

from __future__ import annotations

import numpy as np

from dbn.dbn import prev
from dbn.errors import EvidenceError, FrontierTooLargeError

__all__ = ["viterbi"]


def _max_slice(flt, plan, first: bool, lam_t: dict[str, np.ndarray], delta):
    """One slice of max-product: (output table, argmax table per op index)."""
    vals: list = [None] * len(plan.scopes)
    tables = flt._tables[0 if first else 1]
    for v, s in plan.base:
        t = tables[v]
        vals[s] = t * lam_t[v].reshape(*([1] * (t.ndim - 1)), -1) if v in lam_t else t
    if plan.input_slot is not None:
        vals[plan.input_slot] = delta
    for s, st in enumerate(plan.static):
        if st and vals[s] is None and not any(op.output == s for op in plan.ops):
            vals[s] = np.ones([flt.cards[v] for v in plan.scopes[s]])
    args: dict[int, np.ndarray] = {}
    for k, op in enumerate(plan.ops):
        operands = [vals[i] for i in op.inputs]
        if op.eliminated is None:
            vals[op.output] = np.einsum(op.subscripts, *operands)
        else:
            prod = np.einsum(op.keep_subscripts, *operands)
            args[k] = prod.argmax(axis=-1)
            vals[op.output] = np.take_along_axis(prod, args[k][..., None], axis=-1)[..., 0]
    return vals[plan.output_slot], args


def viterbi(flt, T: int, lam: dict[str, np.ndarray]) -> tuple[dict[str, np.ndarray], float]:
    """MPE of every variable of ``T`` slices of ``flt``'s DBN given likelihoods ``lam``
    (see :meth:`~inference.exact.structured_filter.StructuredFilter.viterbi`)."""
    evars = frozenset(lam)
    plans = (flt._plan("max0", evars), flt._plan("max", evars))
    per_slice = sum(int(np.prod([flt.cards[u] for u in op.scope])) for op in plans[1].ops)
    if T * per_slice > flt.max_size:
        raise FrontierTooLargeError(
            f"Viterbi keeps {T} x {per_slice:,} argmax entries, above the limit of "
            f"{flt.max_size:,}; decode shorter windows or raise max_size"
        )
    delta, log_scale, history = None, 0.0, []
    for t in range(T):
        lam_t = {v: lam[v][t] for v in evars}
        delta, args = _max_slice(flt, plans[0 if t == 0 else 1], t == 0, lam_t, delta)
        m = float(delta.max())
        if not m > 0.0:
            raise EvidenceError(f"the evidence up to slice {t} has probability zero")
        delta = delta / m
        log_scale += np.log(m)
        history.append(args)
    known = dict(zip(flt.interface, np.unravel_index(int(delta.argmax()), flt.iface_shape)))
    path = {n: np.empty(T, dtype=np.int64) for n in flt.dbn.names}
    for t in range(T - 1, -1, -1):
        plan = plans[0 if t == 0 else 1]
        assign = {n: int(s) for n, s in known.items()}
        for k in range(len(plan.ops) - 1, -1, -1):
            op = plan.ops[k]
            if op.eliminated is not None:
                idx = tuple(assign[u] for u in op.scope)
                assign[op.eliminated] = int(history[t][k][idx])
        for n in flt.dbn.names:
            path[n][t] = assign[n]
        known = {n: assign[prev(n)] for n in flt.interface} if t > 0 else {}
    return path, float(log_scale)
