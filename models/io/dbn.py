"""Generic DBN files: a two-slice BIF file, an evidence CSV, a marginals CSV.

Two-slice BIF (``docs/formats.md``): an ordinary BIF Bayes net over the variables of two
consecutive slices, every name ending in ``_0`` (slice 0) or ``_1`` (slice ``t >= 1``).
The CPDs of the ``_0`` variables are the initial slice; the CPDs of the ``_1`` variables
are the transition, whose ``_0`` parents are the previous slice. This is the unrolled
2-TBN of pgmpy's ``DynamicBayesianNetwork`` (nodes ``(X, 0)``, ``(X, 1)``) written as BIF.
A variable ``X_1`` whose BIF has no ``X_0`` is an error. :func:`write_two_slice_bif`
writes a :class:`~dbn.dbn.TwoSliceDBN` (one from pgmpy through
:func:`dbn.pgmpy_adapter.dbn_from_pgmpy`, say) as such a file.

Evidence CSV: a header of observed variable names (the base names, without ``_0``/``_1``),
then one row per slice; a field holds a state name (or its index, for a variable none of
whose state names is a number), empty = unobserved. ``X_0`` and ``X_1`` declare the same
states in the same order.

Marginals CSV (output): ``slice,variable,state,probability``, one row per slice, hidden
variable and state, ``P(X_t = state | e_{0:t})``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from dbn.bayesnet import BayesNet
from dbn.cpds import TabularCPD
from dbn.dbn import TwoSliceDBN, prev
from dbn.errors import DBNError, FileFormatError
from dbn.variables import DiscreteVariable
from models.io.table import Row, fail, read_rows, require_file, write_rows

__all__ = [
    "read_two_slice_bif",
    "write_two_slice_bif",
    "two_slice_from_bn",
    "read_evidence",
    "write_evidence",
    "write_marginals",
    "read_marginals",
    "read_states",
]


def _split(name: str) -> tuple[str, int] | None:
    base, _, t = name.rpartition("_")
    return (base, int(t)) if base and t in ("0", "1") else None


def two_slice_from_bn(bn: BayesNet, source: str = "model") -> TwoSliceDBN:
    """The :class:`TwoSliceDBN` of a Bayes net over ``X_0`` / ``X_1`` variables."""
    variables: dict[str, DiscreteVariable] = {}
    initial, transition = [], []
    if not bn.nodes:
        raise FileFormatError(source, "no variable with a probability block (not a BIF network?)")
    for name in bn.nodes:
        parts = _split(name)
        if parts is None:
            raise FileFormatError(source, f"variable {name!r} does not end in _0 or _1")
        base, t = parts
        v = bn.variable(name)
        if t == 0:
            variables[base] = DiscreteVariable(base, v.cardinality, v.state_names)
    for name in bn.nodes:
        base, t = _split(name)
        if base not in variables:
            raise FileFormatError(source, f"{name!r} has no slice-0 variable {base + '_0'!r}")
        states, first = bn.variable(name).state_names, variables[base].state_names
        if states != first:
            raise FileFormatError(source, f"{name!r} has states {list(states)}, but "
                                  f"{base + '_0'!r} has {list(first)}: one variable, one "
                                  "list of states in one order")
        parents = [_split(p) for p in bn.parents(name)]
        if t == 0:
            if any(pt != 0 for _, pt in parents):
                raise FileFormatError(source, f"slice-0 variable {name!r} has a slice-1 parent")
            initial.append(TabularCPD(base, [p for p, _ in parents], bn.table(name)))
        else:
            names = [prev(p) if pt == 0 else p for p, pt in parents]
            transition.append(TabularCPD(base, names, bn.table(name)))
    missing = sorted(set(variables) - {c.variable for c in transition})
    if missing:
        raise FileFormatError(source, f"no slice-1 CPD for {[m + '_1' for m in missing]}")
    return TwoSliceDBN(list(variables.values()), initial, transition)


def read_two_slice_bif(path: str | Path) -> TwoSliceDBN:
    """Read a two-slice BIF file (see the module docstring)."""
    from dbn.pgmpy_adapter import read_bif

    path = require_file(path, "BIF file")
    try:
        bn = read_bif(path)  # its errors name the file and the line
    except DBNError:
        raise
    except Exception as exc:  # a safety net: never a raw exception from a bad file
        msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise FileFormatError(path, f"not a valid BIF file ({msg})") from None
    return two_slice_from_bn(bn, str(path))


def write_two_slice_bif(path: str | Path, dbn: TwoSliceDBN) -> Path:
    """Write a discrete two-slice DBN as a two-slice BIF file (the module docstring), which
    :func:`read_two_slice_bif` and ``dbntrack track dbn`` read back: the net of
    ``dbn.unroll(2)``, variables ``X_0`` with the initial CPDs and ``X_1`` with the
    transition ones (deterministic CPDs as 0/1 tables), every probability to the last bit
    (:func:`dbn.bif_writer.format_bif`). Read back, the variables come in sorted order.

    Raises
    ------
    ModelError
        ``dbn`` is not a :class:`TwoSliceDBN`, has a continuous variable, or a name BIF
        cannot hold (:func:`dbn.bif_writer.check_bif_name`); nothing is written.
    InputError
        ``path`` cannot be written (its folder is missing, say).
    """
    from dbn.bif_writer import format_bif
    from dbn.dbn import check_two_slice
    from dbn.errors import InputError, ModelError

    check_two_slice(dbn, "write_two_slice_bif")
    for v in dbn.variables:
        if not isinstance(v, DiscreteVariable):
            raise ModelError(f"write_two_slice_bif: variable {v.name!r} is continuous; "
                             "a BIF file holds discrete variables only")  # fmt: skip
    text = format_bif(dbn.unroll(2))
    path = Path(path)
    try:
        path.write_text(text, encoding="utf-8")
    except OSError as exc:
        raise InputError(f"{path}: cannot write the BIF file ({exc.strerror or exc})") from None
    return path


def _numbered(var: DiscreteVariable) -> bool:
    """Whether a state name of ``var`` is itself a number (then ``"0"`` could be a name or
    an index, and :func:`_state_index` reads names only). Python evidence reads ints by
    another rule (:meth:`dbn.variables.DiscreteVariable.renumbered`); ``docs/formats.md``
    ("Numbers as state names") states both."""
    return any(s.strip().lstrip("+-").replace(".", "", 1).isdigit() for s in var.state_names)


def _state_index(var: DiscreteVariable, text: str, path, line: int, where: str,
                 numbered: bool) -> int:
    """The index of state ``text`` of ``var``: its name, else its index unless
    ``numbered`` (:func:`_numbered`, computed once per column)."""
    if text in var.state_names:
        return var.state_names.index(text)
    if text.isdigit() and int(text) < var.cardinality and not numbered:
        return int(text)
    also = " (its state names are numbers: a field is a name, never an index)" if numbered else ""
    raise fail(path, line,
               f"{var.name} = {text!r} is not a state of {list(var.state_names)}{where}{also}")


SLICE_COLUMN = "slice"
"""An evidence or truth CSV's optional column of slice numbers (unless a variable is named
so): rows then need not be consecutive slices (:func:`row_slices`)."""


def row_slices(header: list[str], rows: list[Row], names) -> tuple[list[str], list[int]]:
    """The variable columns of an evidence or truth CSV and each row's slice: its position,
    or the row's :data:`SLICE_COLUMN` field (integers >= 0, increasing; a slice no row
    gives is unobserved, or not scored) where the header has one and ``names`` (the
    variables) does not."""
    if SLICE_COLUMN not in header or SLICE_COLUMN in names:
        return header, list(range(len(rows)))
    slices: list[int] = []
    for row in rows:
        t = row.int(SLICE_COLUMN)
        if t < 0 or (slices and t <= slices[-1]):
            after = f" after slice {slices[-1]}" if slices else ""
            raise row.fail(f"slice = {t}{after}: slices must be >= 0 and increasing")
        slices.append(t)
    return [c for c in header if c != SLICE_COLUMN], slices


def read_states(path: str | Path, dbn: TwoSliceDBN, model: str | Path | None = None) -> dict[str, np.ndarray]:
    """Columns of states per slice: ``name -> (T,) int``, ``-1`` where the field is empty
    (or, with a :data:`SLICE_COLUMN`, where no row gives the slice).

    Used for evidence and for truth files (same format). ``model``: the DBN's file, named
    beside the states or variables it declares when the CSV disagrees with them (either
    file may be the wrong one).
    """
    header, rows = read_rows(path, what="evidence CSV", keep_blank=True)
    variables = {v.name: v for v in dbn.variables}
    where = "" if model is None else f" (declared in {model})"
    header, slices = row_slices(header, rows, variables)
    for col in header:
        if col not in variables:
            raise fail(path, 1, f"column {col!r} is not a variable of the DBN {sorted(variables)}{where}")
    if not rows:
        raise fail(path, 0, "no slices (the file has a header only)")
    cols = {c: np.full(slices[-1] + 1, -1, dtype=np.int64) for c in header}
    numbered = {c: _numbered(variables[c]) for c in header}
    for t, row in zip(slices, rows):
        for c in header:
            if row[c] != "":
                cols[c][t] = _state_index(variables[c], row[c], path, row.line, where,
                                          numbered[c])
    return cols


read_evidence = read_states


def write_evidence(path: str | Path, dbn: TwoSliceDBN, evidence) -> Path:
    """Write columnar evidence as the evidence CSV ``dbntrack track dbn`` reads, so that
    :func:`read_evidence` gives back ``name -> (T,) int`` with ``-1`` where unobserved.

    Parameters
    ----------
    evidence : mapping name -> (T,) array
        As :func:`inference.filter` takes it (indices with ``-1``, state names with
        ``None``, floats with NaN), discrete variables only. Written with a
        :data:`SLICE_COLUMN` first and one row per slice, observed or not, so a state name
        beginning with ``#`` never begins a line (the reader skips such lines as comments).

    Raises
    ------
    DBNError
        The checks of :func:`inference.evidence_columns.check_columns` (unknown variable,
        state out of range, columns of different lengths); a continuous variable, a DBN
        variable named ``slice``, or a state name the CSV reader would change (whitespace
        at an end, a control character): nothing is written.
    InputError
        ``path`` cannot be written.
    """
    from dbn.errors import InputError, ModelError
    from inference.evidence_columns import check_columns

    cols = check_columns(dbn, evidence)
    if cols.continuous:
        raise ModelError(f"write_evidence: {sorted(cols.continuous)} continuous; the evidence "
                         "CSV holds discrete variables only")  # fmt: skip
    if SLICE_COLUMN in dbn.names:
        raise ModelError(f"write_evidence: the DBN has a variable named {SLICE_COLUMN!r}, the "
                         "CSV's slice column; rename it")  # fmt: skip
    names = list(cols.discrete)
    states = {n: dbn.initial_net.variable(n).state_names for n in names}
    for n in names:
        for s in states[n]:
            if s != s.strip() or any(ord(ch) < 32 for ch in s):
                raise ModelError(f"write_evidence: state {s!r} of {n!r} would not read back "
                                 "(whitespace at an end or a control character)")  # fmt: skip
    rows = [(t, *(states[n][k] if (k := int(cols.discrete[n][t])) >= 0 else "" for n in names))
            for t in range(cols.num_timesteps)]  # fmt: skip
    try:
        return write_rows(path, (SLICE_COLUMN, *names), rows)
    except OSError as exc:
        raise InputError(f"{path}: cannot write the evidence CSV ({exc.strerror or exc})") from None


def write_marginals(path: str | Path, dbn: TwoSliceDBN, marginals: dict[str, np.ndarray]) -> Path:
    """Write ``name -> (T, K)`` marginals as ``slice,variable,state,probability`` rows."""
    states = {v.name: v.state_names for v in dbn.variables}
    rows = []
    for name, m in marginals.items():
        for t in range(m.shape[0]):
            rows += [(t, name, s, float(m[t, k])) for k, s in enumerate(states[name])]
    rows.sort(key=lambda r: r[0])
    return write_rows(path, ("slice", "variable", "state", "probability"), rows)


MARGINAL_SUM_TOL = 1e-3
"""How far a marginal read back may sum from 1 (rounded probabilities pass, garbage not)."""


def read_marginals(path: str | Path) -> dict[str, tuple[list[str], np.ndarray]]:
    """Read a marginals CSV back: ``name -> (state names, (T, K) probabilities)``.

    Raises
    ------
    FileFormatError
        Naming the file and line: a negative slice; a probability outside [0, 1]; a
        (slice, variable, state) given twice; a state without a row for some slice
        ``0..T-1``; a (slice, variable) whose probabilities do not sum to 1 (within
        :data:`MARGINAL_SUM_TOL`). A gap would leave NaN, a huge slice number would
        allocate that many rows, and the scores would be garbage.
    """
    _, rows = read_rows(path, ("slice", "variable", "state", "probability"), "marginals CSV")
    table: dict[str, dict[str, dict[int, float]]] = {}
    lines: dict[tuple[str, int], int] = {}
    for r in rows:
        t, p = r.int("slice"), r.float("probability")
        if t < 0:
            raise r.fail(f"slice = {t} (slices count from 0)")
        if not -1e-9 <= p <= 1.0 + 1e-9:  # a float sum may end a hair above 1
            raise r.fail(f"probability = {p!r} is not in [0, 1]")
        cell = table.setdefault(r["variable"], {}).setdefault(r["state"], {})
        if t in cell:
            raise r.fail(f"slice {t}, {r['variable']} = {r['state']} is given twice")
        cell[t] = p
        lines.setdefault((r["variable"], t), r.line)
    return {name: _marginal_array(path, name, by_state, lines) for name, by_state in table.items()}


def _marginal_array(path, name: str, by_state: dict[str, dict[int, float]],
                    lines: dict[tuple[str, int], int]) -> tuple[list[str], np.ndarray]:  # fmt: skip
    """``(states, (T, K) array)`` of one variable of :func:`read_marginals`, checked whole."""
    states = list(by_state)
    T = 1 + max(max(d) for d in by_state.values())
    for s, d in by_state.items():
        if len(d) != T:  # the first gap, found in at most len(d) + 1 steps
            gap = next(t for t in range(T) if t not in d)
            raise fail(path, 0, f"{name} = {s} has no row for slice {gap} (every state of "
                                f"{name} needs one for each slice 0..{T - 1})")  # fmt: skip
    m = np.array([[by_state[s][t] for s in states] for t in range(T)])
    off = np.flatnonzero(np.abs(m.sum(axis=1) - 1.0) > MARGINAL_SUM_TOL)
    if off.size:
        t = int(off[0])
        raise fail(path, lines[(name, t)], f"the probabilities of {name} at slice {t} sum to "
                                           f"{m[t].sum():.6g}, not 1")  # fmt: skip
    return states, m
