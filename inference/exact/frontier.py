"""Elimination plans over one slice of a two-slice DBN (the interface / frontier algorithm).

One slice of a discrete DBN is a product of factors: the message carried in from the
neighbouring slice (the forward belief over the previous interface, or the backward
message over this slice's interface) and one factor per CPD of the slice, each already
multiplied by its variable's evidence likelihood :math:`\\lambda_v(x_v)` (all ones where
unobserved, one-hot for hard evidence, any nonnegative vector for soft evidence):

.. math:: \\phi_t(\\cdot) = m(\\cdot) \\prod_{v} P(x_v \\mid \\mathrm{pa}(x_v))\\,\\lambda_{v,t}(x_v).

A :class:`SlicePlan` sums (or maximises) every variable that is not *kept* out of that
product, one variable at a time, in an order chosen greedily over the template (smallest
resulting table first), each step one ``numpy.einsum`` over the factors that hold the
variable, or, for a step that multiplies the message by one static factor, one batched
``numpy.matmul`` (message axes permuted to (batch, free, contracted)) whose output axes
are (batch, free, new). Observed leaves are thereby reduced to likelihood vectors over their parents
before anything meets the message, no table over (interface, next interface,
observations) is ever built, and the largest table a slice allocates is known before any
allocation (:attr:`SlicePlan.max_size`); a plan above the limit raises
:class:`~dbn.errors.FrontierTooLargeError`.

Ops whose inputs are all CPD factors are *static*: they depend on the slice's evidence
only, so the executor evaluates them once per distinct evidence row (batched over rows);
the other (*dynamic*) ops run once per slice.
"""

from __future__ import annotations

import string
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from dbn.checks import check_count
from dbn.errors import FrontierTooLargeError

__all__ = ["MAX_FRONTIER_SIZE", "check_max_size", "Op", "SlicePlan", "compile_slice_plan", "barren"]

MAX_FRONTIER_SIZE = 2**25
"""Default limit (entries, float64) of the largest table one slice may allocate (256 MiB)."""


def check_max_size(max_size: Any) -> int:
    """``max_size`` as an int >= 1 (not a bool or a fraction); else :class:`InputError`."""
    return check_count("max_size (table entries)", max_size)

_APPROX = (
    "use an approximate method: inference.filter(model, evidence, method='bk' "
    "(Boyen-Koller), 'particle' or 'rbpf')"
)
_LETTERS = string.ascii_letters[:-1]  # 51 labels per einsum; "Z" is the batch label
_BATCH = "Z"


@dataclass(frozen=True)
class Op:
    """One einsum of a plan: multiply ``inputs`` and sum (or max) out ``eliminated``.

    Attributes
    ----------
    inputs : tuple of int
        Slot ids of the operands.
    output : int
        Slot id of the result.
    scope : tuple of str
        Variables of the result, in axis order.
    eliminated : str or None
        The variable summed out (None: a plain product).
    subscripts : str
        The sum-product einsum (``"ab,bc->ac"``).
    batched : str
        The same with a leading batch label on every operand (static ops).
    keep_subscripts : str
        The product with ``eliminated`` kept as the last output axis (max-product).
    static : bool
        True when every input is derived from CPD factors only.
    matmul : tuple or None
        For a dynamic op of one message-like table ``B`` and one static factor ``f``:
        ``(position of B in inputs, axes of f summed first, B's axis permutation, its 3-D
        shape (batch, free, contracted), f's permutation, its 3-D shape (batch,
        contracted, new), the result's shape)``; the op is then one batched ``matmul``
        and its output axes are (batch, free, new). None: run ``subscripts``.
    """

    inputs: tuple[int, ...]
    output: int
    scope: tuple[str, ...]
    eliminated: str | None
    subscripts: str
    batched: str
    keep_subscripts: str
    static: bool
    matmul: tuple | None = None


@dataclass(frozen=True)
class SlicePlan:
    """A compiled elimination plan for one slice.

    Attributes
    ----------
    scopes : tuple of tuple of str
        Scope (axis order) of every slot.
    static : tuple of bool
        Whether each slot depends on the evidence only.
    base : tuple of (str, int)
        ``(variable, slot)``: the slot holding ``P(v | pa(v)) lambda_v`` (axes: the CPD's
        parents, then ``v``). A static slot that is neither a base factor nor an op's
        output (nor a static input) is the constant 1 over its scope.
    input_slot : int or None
        Slot of the incoming message (None: none, the first slice).
    ops : tuple of Op
        In execution order.
    output_slot : int
        Slot of the result, over :attr:`output_scope`.
    output_scope : tuple of str
        The kept variables, in the requested order.
    order : tuple of str
        The elimination order.
    max_size : int
        Entries of the largest table the plan holds per slice (message included).
    """

    scopes: tuple[tuple[str, ...], ...]
    static: tuple[bool, ...]
    base: tuple[tuple[str, int], ...]
    input_slot: int | None
    ops: tuple[Op, ...]
    output_slot: int
    output_scope: tuple[str, ...]
    order: tuple[str, ...]
    max_size: int


def barren(parents: Mapping[str, Sequence[str]], needed: set[str]) -> set[str]:
    """Variables that can be dropped from a sum-product: neither needed nor the ancestor
    of a needed one (summing an unobserved leaf's CPD over its child gives 1)."""
    keep: set[str] = set()
    stack = [v for v in needed if v in parents]
    while stack:
        v = stack.pop()
        if v in keep:
            continue
        keep.add(v)
        stack.extend(p for p in parents[v] if p in parents and p not in keep)
    return set(parents) - keep


def _size(scope: Sequence[str], cards: Mapping[str, int]) -> int:
    return int(np.prod([cards[v] for v in scope], dtype=np.float64)) if scope else 1


def _einsum(in_scopes: Sequence[tuple[str, ...]], out: Sequence[str]) -> tuple[str, str]:
    """(plain, batched) einsum subscripts, labels local to this one einsum."""
    labels: dict[str, str] = {}
    for s in (*in_scopes, tuple(out)):
        for v in s:
            if v not in labels:
                if len(labels) == len(_LETTERS):
                    raise FrontierTooLargeError(
                        f"exact filtering would need one step over more than {len(_LETTERS)} "
                        f"variables {sorted(labels)[:8]} ...; {_APPROX}"
                    )
                labels[v] = _LETTERS[len(labels)]
    ins = ["".join(labels[v] for v in s) for s in in_scopes]
    res = "".join(labels[v] for v in out)
    plain = ",".join(ins) + "->" + res
    batched = ",".join(_BATCH + i for i in ins) + "->" + _BATCH + res
    return plain, batched


def _out_scope(scopes: Sequence[tuple[str, ...]], sizes: Sequence[int], drop: str | None):
    """Result axes: the largest operand's axes, ``drop`` replaced in place by the new
    variables (so a chain's new state takes its old state's axis), the rest appended."""
    big = scopes[int(np.argmax(sizes))]
    new = [v for s in scopes for v in s if v not in big]
    new = list(dict.fromkeys(new))
    if drop is not None and drop in big:
        i = big.index(drop)
        return (*big[:i], *new, *big[i + 1 :])
    return (*big, *new) if drop is None else tuple(v for v in (*big, *new) if v != drop)


class _Builder:
    def __init__(self, cards: Mapping[str, int]) -> None:
        self.cards = cards
        self.scopes: list[tuple[str, ...]] = []
        self.static: list[bool] = []
        self.ops: list[Op] = []
        self.max_size = 0

    def slot(self, scope: tuple[str, ...], static: bool) -> int:
        self.scopes.append(scope)
        self.static.append(static)
        self.max_size = max(self.max_size, _size(scope, self.cards))
        return len(self.scopes) - 1

    def op(self, inputs: Sequence[int], drop: str | None, out: tuple[str, ...] | None = None):
        scopes = [self.scopes[i] for i in inputs]
        static = all(self.static[i] for i in inputs)
        mm = None
        if out is None and len(inputs) == 2 and not static and any(self.static[i] for i in inputs):
            mm, out = self._matmul(inputs, drop)
        elif out is None:
            out = _out_scope(scopes, [_size(s, self.cards) for s in scopes], drop)
        slot = self.slot(tuple(out), static)
        plain, batched = _einsum(scopes, out)
        keep, _ = _einsum(scopes, (*out, drop) if drop is not None else out)
        op = Op(tuple(inputs), slot, tuple(out), drop, plain, batched, keep, static, mm)
        self.ops.append(op)
        return slot

    def _matmul(self, inputs: Sequence[int], drop: str | None):
        """The batched-matmul form of (dynamic table B) x (static factor f), summing
        ``drop``: ``out[b, F, N] = sum_C B[b, F, C] f[b, C, N]``."""
        pos = 0 if not self.static[inputs[0]] else 1
        sb, sf = self.scopes[inputs[pos]], self.scopes[inputs[1 - pos]]
        summed = tuple(k for k, u in enumerate(sf) if u == drop and u not in sb)
        sf = tuple(u for u in sf if not (u == drop and u not in sb))
        batch = [u for u in sb if u in sf and u != drop]
        contracted = [u for u in sb if u == drop and u in sf]
        free = [u for u in sb if u not in sf]
        new = [u for u in sf if u not in sb]
        card = self.cards

        def n(vs):
            return _size(tuple(vs), card)

        perm_b = tuple(sb.index(u) for u in (*batch, *free, *contracted))
        perm_f = tuple(sf.index(u) for u in (*batch, *contracted, *new))
        out = (*batch, *free, *new)
        shape = tuple(card[u] for u in out)
        spec = (
            pos,
            summed,
            perm_b,
            (n(batch), n(free), n(contracted)),
            perm_f,
            (n(batch), n(contracted), n(new)),
            shape,
        )
        return spec, out

    def product(self, slots: list[int], drop: str | None, out: tuple[str, ...] | None = None):
        """Multiply ``slots`` pairwise (static and small ones first), then drop ``drop``."""
        slots = sorted(slots, key=lambda s: (not self.static[s], _size(self.scopes[s], self.cards)))
        acc = slots[0]
        if len(slots) == 1:
            return self.op([acc], drop, out)
        for k, s in enumerate(slots[1:], start=2):
            last = k == len(slots)
            acc = self.op([acc, s], drop if last else None, out if last else None)
        return acc


def _absorb(factors: dict[int, tuple[str, ...]], b: _Builder) -> None:
    """Multiply every static factor whose scope lies inside another static factor's scope
    into that one (once per evidence row, instead of into the message at every slice)."""
    changed = True
    while changed:
        changed = False
        static = sorted((s for s in factors if b.static[s]), key=lambda s: len(factors[s]))
        for i, f in enumerate(static):
            host = next((g for g in static[i + 1 :] if set(factors[f]) <= set(factors[g])), None)
            if host is not None:
                out = b.op([host, f], None, factors[host])
                del factors[f], factors[host]
                factors[out] = b.scopes[out]
                changed = True
                break


def _choose(factors: dict[int, tuple[str, ...]], todo: set[str], b: _Builder) -> str:
    """Greedy step: the variable whose elimination builds the smallest table; ties go to
    variables touching static factors only, then to the name."""
    best = None
    for v in todo:
        holders = [s for s, sc in factors.items() if v in sc]
        union = {u for s in holders for u in factors[s]} - {v}
        dyn = any(not b.static[s] for s in holders)
        key = (_size(tuple(union), b.cards), dyn, v)
        if best is None or key < best:
            best = key
    assert best is not None
    return best[2]


def compile_slice_plan(
    cpds: Mapping[str, tuple[Sequence[str], ...]],
    cards: Mapping[str, int],
    input_scope: tuple[str, ...] | None,
    keep: tuple[str, ...],
    *,
    limit: int = MAX_FRONTIER_SIZE,
    input_static: bool = False,
) -> SlicePlan:
    """Compile the elimination plan of one slice.

    Parameters
    ----------
    cpds : mapping variable -> parents
        The CPDs taking part (already pruned of barren variables by the caller).
    cards : mapping name -> cardinality
        For every variable and previous-slice reference that occurs.
    input_scope : tuple of str or None
        Scope of the incoming message (None: no message).
    keep : tuple of str
        Variables left in the result, in this axis order.
    limit : int
        Largest table (entries) allowed.
    input_static : bool
        The message is a constant (e.g. an identity that turns the plan into the dense
        per-slice matrix), so every op is static.

    Raises
    ------
    FrontierTooLargeError
        Some table of the plan (message or intermediate) would exceed ``limit`` entries;
        raised before anything is allocated.
    """
    b = _Builder(cards)
    factors: dict[int, tuple[str, ...]] = {}
    base = []
    for v, parents in cpds.items():
        s = b.slot((*parents, v), True)
        base.append((v, s))
        factors[s] = b.scopes[s]
    input_slot = None
    if input_scope is not None:
        input_slot = b.slot(tuple(input_scope), input_static)
        factors[input_slot] = tuple(input_scope)
    todo = {v for sc in factors.values() for v in sc} - set(keep)
    order: list[str] = []
    _absorb(factors, b)
    while todo:
        v = _choose(factors, todo, b)
        holders = [s for s, sc in factors.items() if v in sc]
        union = {u for s in holders for u in factors[s]} - {v}
        _guard(_size(tuple(union), cards), limit, union)
        out = b.product(holders, v)
        for s in holders:
            del factors[s]
        factors[out] = b.scopes[out]
        todo.discard(v)
        order.append(v)
        _absorb(factors, b)
    rest = list(factors)
    loose = tuple(v for v in keep if not any(v in sc for sc in factors.values()))
    if loose or not rest:  # kept variables no factor mentions: a constant 1 over them
        rest.append(b.slot(loose, True))
    if len(rest) == 1 and b.scopes[rest[0]] == tuple(keep):
        output = rest[0]
    else:
        output = b.product(rest, None, tuple(keep))
    _guard(b.max_size, limit, set(keep))
    return SlicePlan(
        tuple(b.scopes),
        tuple(b.static),
        tuple(base),
        input_slot,
        tuple(b.ops),
        output,
        tuple(keep),
        tuple(order),
        b.max_size,
    )


def _guard(size: int, limit: int, scope: set[str]) -> None:
    if size > limit:
        raise FrontierTooLargeError(
            f"exact filtering needs a table of {size:,} entries ({size * 8 / 2**20:,.0f} MiB "
            f"of float64) over {len(scope)} variables {sorted(scope)[:8]}"
            f"{' ...' if len(scope) > 8 else ''}, above the limit of {limit:,} entries; {_APPROX}"
            ", or raise max_size if the memory is there"
        )
