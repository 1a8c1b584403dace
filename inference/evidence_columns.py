"""Validation of columnar DBN evidence, shared by the approximate DBN filters.

Columnar evidence maps a variable name to one array over the slices:

- a discrete variable: shape ``(num_timesteps,)``, its states by index (integers, ``-1`` =
  unobserved; floats that are whole numbers, NaN = unobserved, as pandas writes an integer
  column with a gap) or by name (the variable's ``state_names``, as pgmpy gives them;
  ``None`` = unobserved), not both in one column;
- a continuous variable of dimension ``d``: floats, shape ``(num_timesteps, d)`` (a 1-D
  column is read as ``d = 1``), a row of NaN = unobserved;
- soft evidence on a discrete variable: nonnegative likelihoods, shape
  ``(num_timesteps, cardinality)``, each row finite and not all zero, or all NaN for no
  soft evidence at that slice.

Every check runs before any filtering, and each error names the column and the value.
pgmpy's evidence ``{(name, t): state}`` becomes columns with :func:`columns_from_slices`,
a pandas ``DataFrame`` (a column per variable, a row per slice) with
:func:`columns_from_frame`.
One slice's evidence (the on-line ``init`` / ``step`` of every engine) is ``name -> state``
(or a pandas ``Series``, a ``DataFrame``'s row), by index or by name, ``-1``, ``None`` or NaN
= unobserved, whole-number floats read as indices as in a column: :func:`slice_states`.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from dbn.checks import (
    check_count,
    check_mapping,
    evidence_mapping,
    evidence_state,
    instance_of,
    is_real_number,
    is_whole,
    refuse_complex,
)
from dbn.dbn import TwoSliceDBN
from dbn.errors import (
    EvidenceError,
    InputError,
    NonFiniteError,
    ShapeError,
    UnknownEvidenceError,
    UnknownVariableError,
)
from dbn.variables import ContinuousVariable, DiscreteVariable

__all__ = ["Columns", "as_column", "check_columns", "check_query", "columns_from_frame",
           "columns_from_slices", "first_bad_row", "slice_states", "soft_column",
           "state_column"]


class Columns(NamedTuple):
    """Validated evidence.

    Attributes
    ----------
    num_timesteps : int
    discrete : dict name -> int64 array (num_timesteps,), -1 = unobserved
    continuous : dict name -> float64 array (num_timesteps, dim), NaN rows = unobserved
    soft : dict name -> float64 array (num_timesteps, cardinality)
    """

    num_timesteps: int
    discrete: dict[str, np.ndarray]
    continuous: dict[str, np.ndarray]
    soft: dict[str, np.ndarray]


def as_column(name: str, col: ArrayLike, what: str = "evidence column", dtype=None) -> np.ndarray:
    """``col`` as an array (of ``dtype``): a ragged or non-numeric one is an
    :class:`EvidenceError` naming ``what`` and ``name``, not numpy's error; so is a
    complex one (its imaginary parts were dropped with a warning)."""
    refuse_complex(f"{what} {name!r}", col, EvidenceError)
    try:
        return np.asarray(col, dtype=dtype)
    except (TypeError, ValueError) as exc:
        raise EvidenceError(f"{what} {name!r} is not an array of numbers ({exc})") from None


def _length(name: str, n: int, T: int | None) -> int:
    if T is not None and n != T:
        raise ShapeError(f"evidence column {name!r} has length {n}, expected {T}")
    return n


def first_bad_row(arr: np.ndarray) -> int | None:
    """The first row of a (T, d) float array that holds an infinity or is partly NaN (a
    row is all finite, or all NaN for unobserved); None when every row is good."""
    nan = np.isnan(arr)
    bad = (nan.any(axis=1) & ~nan.all(axis=1)) | np.isinf(arr).any(axis=1)
    return int(np.argmax(bad)) if bad.any() else None


def state_column(
    name: str, v: DiscreteVariable, col: ArrayLike, T: int | None = None
) -> tuple[np.ndarray, int]:
    """A hard evidence column of discrete variable ``v``, its states given by index or by
    name (module docstring), as (T,) int64 states, -1 unobserved; and its length, which
    must equal ``T`` unless ``T`` is None.

    Raises
    ------
    ShapeError
        Not 1-D, or not of length ``T``.
    EvidenceError
        Not integers or names, an index out of range, or an unknown name (each naming the
        column and the slice).
    """
    arr = as_column(name, col)
    if arr.dtype.kind == "U" and not isinstance(col, np.ndarray):
        arr = as_column(name, col, dtype=object)  # numpy writes a mixed list's ints as names
    if arr.ndim != 1:
        raise ShapeError(
            f"evidence column {name!r} must be 1-D (num_timesteps,), got shape {arr.shape}"
        )
    named = arr.dtype.kind in "UO"
    if not (named or arr.dtype.kind in "iuf"):
        raise EvidenceError(
            f"evidence column {name!r} must hold integer states (-1 = unobserved) or state "
            f"names, got dtype {arr.dtype}"
        )
    T = _length(name, arr.shape[0], T)
    if named:
        return _state_indices(name, v, arr), T
    if arr.dtype.kind == "f":  # pandas' integer column with a gap: whole numbers, NaN
        arr = _whole_states(name, arr)
    bad = (arr < -1) | (arr >= v.cardinality)
    if bad.any():
        t = int(np.argmax(bad))
        raise EvidenceError(
            f"evidence column {name!r}: state {int(arr[t])} at slice {t} out of range "
            f"-1..{v.cardinality - 1}"
        )
    return arr.astype(np.int64), T


def _whole_states(name: str, arr: np.ndarray) -> np.ndarray:
    """A float column of whole numbers, NaN = unobserved (pandas writes an integer column
    with a missing value so), as int64 with -1 for NaN; any other float is refused."""
    whole = is_whole(arr)
    bad = ~np.isnan(arr) & ~whole
    if bad.any():
        t = int(np.argmax(bad))
        raise EvidenceError(
            f"evidence column {name!r} at slice {t}: {float(arr[t])!r} is not a state "
            "(integers, -1 or NaN = unobserved; or state names)"
        )
    return np.where(np.isnan(arr), -1, arr).astype(np.int64)


def _state_indices(name: str, v: DiscreteVariable, arr: np.ndarray) -> np.ndarray:
    """A column of state names (None = unobserved) as (T,) int64 indices, -1 unobserved."""
    index = {s: i for i, s in enumerate(v.state_names)}  # type: ignore[arg-type]
    out = np.empty(arr.shape[0], np.int64)
    for t, s in enumerate(arr.tolist()):
        if s is None:
            out[t] = -1
        elif isinstance(s, str) and s in index:
            out[t] = index[s]
        else:
            why = ("is not a state name: a column gives states by index or by name, not both"
                   if not isinstance(s, str) else f"is not a state of {v.name!r}")
            raise EvidenceError(
                f"evidence column {name!r} at slice {t}: {s!r} {why} "
                f"(states: {v.state_names}; None = unobserved)"
            )
    return out


def slice_states(
    variables: Mapping[str, DiscreteVariable], evidence: Mapping | None
) -> dict[str, int]:
    """One slice's hard evidence, ``name -> state`` by index or by name (``-1``, ``None``
    or NaN = unobserved, a whole-number float an index, as in a column; or a pandas
    ``Series``), as ``name -> index`` of the observed ones.

    Raises
    ------
    UnknownEvidenceError, EvidenceError
        Not a mapping, an unknown variable, a state out of range or not a state name.
    """
    evidence = evidence_mapping(evidence)
    check_mapping("evidence", evidence)
    out: dict[str, int] = {}
    for name, state in (evidence or {}).items():
        v = variables.get(name)
        if v is None:
            raise UnknownEvidenceError(
                f"evidence on unknown variable {name!r} (known: {sorted(variables)})"
            )
        state = evidence_state(state)
        if state is not None:
            out[name] = v.index(state)
    return out


def columns_from_slices(
    dbn: TwoSliceDBN, evidence: Mapping, num_timesteps: int | None = None
) -> dict[str, np.ndarray]:
    """pgmpy's DBN evidence, ``{(name, t): state}`` (``DBNInference``), as discrete columns.

    Parameters
    ----------
    dbn : TwoSliceDBN
    evidence : mapping (str, int) -> int or str
        The state of discrete variable ``name`` at slice ``t >= 0``: its name, or an int
        read as pgmpy reads it: the state of that name where the state names are integers
        other than the indices (``DiscreteVariable.renumbered``), else the state's index.
        (In a column, an int is always an index.)
    num_timesteps : int, optional
        ``T``; default: the last slice with evidence, plus one.

    Returns
    -------
    dict name -> ndarray, shape (T,)
        int64 indices with -1 where unobserved, or (a variable given by names) object
        names with None where unobserved; :func:`state_column` reads both.

    Raises
    ------
    EvidenceError
        A key that is not ``(name, slice)`` of a discrete variable, a slice beyond
        ``num_timesteps``, a state that is neither an integer nor a name, an integer that
        names no state (each naming the key).
    """
    check_mapping("evidence", evidence)
    variables = {v.name: v for v in dbn.variables if isinstance(v, DiscreteVariable)}
    slices: dict[str, dict[int, int | str]] = {}
    for key, state in evidence.items():
        name, t = _slice_key(key, variables)
        slices.setdefault(name, {})[t] = _pgmpy_state(key, variables[name], state)
    last = max((t for col in slices.values() for t in col), default=-1)
    T = last + 1
    if num_timesteps is not None:
        T = check_count("num_timesteps", num_timesteps, ShapeError)
    if last >= T:
        raise EvidenceError(f"evidence at slice {last} is beyond num_timesteps = {T}")
    out = {}
    for name, col in slices.items():
        named = any(isinstance(x, str) for x in col.values())
        arr = np.full(T, None, object) if named else np.full(T, -1, np.int64)
        for t, x in col.items():
            arr[t] = x
        out[name] = arr
    return out


def columns_from_frame(frame) -> dict[str, np.ndarray]:
    """A pandas ``DataFrame`` as evidence columns: one column per variable (named by its
    column label), one row per slice, in the frame's row order (the index is not read).

    A missing value (NaN, None, ``pd.NA``, ``NaT``) is unobserved: a column of numbers
    becomes floats with NaN (whole numbers read as state indices, as a nullable ``Int64``
    column with a gap gives them), any other column (state names, a ``category``) objects
    with None. Two-level column labels ``(name, component)`` (``pd.concat({"y": ys},
    axis=1)`` makes them) give a variable several columns, read in the frame's order as
    one ``(num_timesteps, num_components)`` float column: a continuous variable's
    dimensions, or soft evidence's states; a name with one component is a plain column.
    Anything that is not a ``DataFrame`` is returned as is.

    Raises
    ------
    EvidenceError
        A column label that is neither a string nor a ``(name, component)`` pair with a
        string name (an int, a three-level label), one label given twice, or a component
        that is not numbers.
    """
    if not instance_of(frame, "pandas", "DataFrame"):
        return frame
    labels = list(frame.columns)
    pairs = frame.columns.nlevels == 2
    bad = [c for c in labels if not isinstance(c[0] if pairs else c, str)]
    if bad or frame.columns.nlevels > 2:
        raise EvidenceError(f"evidence DataFrame: column labels must be variable names "
                            f"(str) or (name, component) pairs, got "
                            f"{(bad or labels)[0]!r}")  # fmt: skip
    twice = sorted({c for c in labels if labels.count(c) > 1})
    if twice:
        raise EvidenceError(f"evidence DataFrame: columns {twice} given more than once")
    if not pairs:
        return {c: _frame_column(frame[c]) for c in labels}
    groups: dict[str, list] = {}
    for label in labels:
        groups.setdefault(label[0], []).append(label)
    return {name: _components(name, [_frame_column(frame[c]) for c in group])
            for name, group in groups.items()}  # fmt: skip


def _components(name: str, parts: list[np.ndarray]) -> np.ndarray:
    """The columns of one variable's ``(name, component)`` labels: a plain column for one,
    else stacked as ``(num_timesteps, num_components)`` floats."""
    if len(parts) == 1:
        return parts[0]
    if any(p.dtype == object for p in parts):
        raise EvidenceError(f"evidence DataFrame: {name!r} has {len(parts)} component "
                            f"columns, and they must hold numbers")  # fmt: skip
    return np.column_stack(parts).astype(np.float64)


def _frame_column(series) -> np.ndarray:
    """One ``DataFrame`` column as a numpy column, missing values as NaN or None."""
    missing = np.asarray(series.isna(), bool)
    if series.dtype.kind in "iuf" and not missing.any():
        return series.to_numpy()
    values = series.to_numpy(dtype=object)
    numbers = all(is_real_number(x) for x in values[~missing])
    if numbers:
        return np.where(missing, np.nan, values).astype(np.float64)
    values[missing] = None
    return values


def _slice_key(key: object, variables: Mapping[str, DiscreteVariable]) -> tuple[str, int]:
    """``(name, t)`` of a pgmpy evidence key, a discrete variable's name and a slice >= 0."""
    if not (isinstance(key, tuple) and len(key) == 2 and isinstance(key[0], str)
            and isinstance(key[1], int | np.integer) and not isinstance(key[1], bool)
            and key[1] >= 0):
        raise EvidenceError(f"evidence key {key!r} is not (variable name, slice >= 0)")
    if key[0] not in variables:
        raise UnknownEvidenceError(f"evidence {key!r}: no discrete variable {key[0]!r} "
                                   f"(discrete: {sorted(variables)})")
    return key[0], int(key[1])


def _pgmpy_state(key: object, v: DiscreteVariable, state: object) -> int | str:
    """A pgmpy evidence value as :func:`state_column` reads it: an index or a name (an
    int of a :attr:`~dbn.variables.DiscreteVariable.renumbered` variable: its name)."""
    if isinstance(state, bool) or not isinstance(state, int | np.integer | str):
        raise EvidenceError(f"evidence {key!r}: state {state!r} is not an index or a name")
    if isinstance(state, str) or not v.renumbered:
        return state if isinstance(state, str) else int(state)
    if str(int(state)) not in v.state_names:  # type: ignore[operator]
        raise EvidenceError(f"evidence {key!r}: {state!r} is not a state of {v.name!r} "
                            f"(states: {v.state_names})")
    return str(int(state))  # pgmpy's names were integers


def _continuous_column(
    name: str, v: ContinuousVariable, col: ArrayLike, T: int | None
) -> tuple[np.ndarray, int]:
    """An evidence column of a continuous variable: (T, dim) float64, NaN rows unobserved;
    and its length."""
    arr = as_column(name, col, dtype=np.float64)
    if arr.ndim == 1 and v.dim == 1:
        arr = arr[:, None]
    if arr.ndim != 2 or arr.shape[1] != v.dim:
        raise ShapeError(
            f"evidence column {name!r} must have shape (num_timesteps, {v.dim}), got {arr.shape}"
        )
    T = _length(name, arr.shape[0], T)
    t = first_bad_row(arr)
    if t is not None:
        raise NonFiniteError(
            f"evidence column {name!r} at slice {t}: {arr[t]} (a row is all finite, "
            "or all NaN for unobserved)"
        )
    return arr, T


def soft_column(
    name: str, v: DiscreteVariable | ContinuousVariable, col: ArrayLike, T: int | None = None
) -> tuple[np.ndarray, int]:
    """A soft evidence column of a discrete variable: (T, cardinality) float64 likelihoods,
    all-NaN rows (no soft evidence) read as ones; and its length, which must equal ``T``
    unless ``T`` is None."""
    if not isinstance(v, DiscreteVariable):
        raise EvidenceError(f"soft evidence on continuous variable {name!r}")
    arr = as_column(name, col, "soft evidence", np.float64)
    if arr.ndim != 2 or arr.shape[1] != v.cardinality:
        raise ShapeError(
            f"soft evidence {name!r} must have shape (num_timesteps, {v.cardinality}), "
            f"got {arr.shape}"
        )
    T = _length(name, arr.shape[0], T)
    none = np.isnan(arr).all(axis=1)  # an all-NaN row: no soft evidence at that slice
    rows = np.where(none[:, None], 1.0, arr)
    ok = np.all(np.isfinite(rows) & (rows >= 0), axis=1) & np.any(rows > 0, axis=1)
    if not ok.all():
        t = int(np.argmin(ok))
        raise EvidenceError(
            f"soft evidence {name!r} at slice {t}: {arr[t]} is not a likelihood "
            "(finite, nonnegative, not all zero; all-NaN = none)"
        )
    return rows, T


def check_columns(
    dbn: TwoSliceDBN,
    evidence: Mapping[str, ArrayLike] | None,
    soft_evidence: Mapping[str, ArrayLike] | None = None,
    num_timesteps: int | None = None,
) -> Columns:
    """Validate columnar evidence against ``dbn``; see the module docstring.

    Raises
    ------
    UnknownVariableError, EvidenceError, ShapeError, NonFiniteError
    """
    check_mapping("evidence", evidence)
    variables = {v.name: v for v in dbn.variables}
    T = num_timesteps
    disc: dict[str, np.ndarray] = {}
    cont: dict[str, np.ndarray] = {}
    for name, col in (evidence or {}).items():
        if name not in variables:
            raise UnknownEvidenceError(
                f"evidence on unknown variable {name!r} (known: {sorted(variables)})"
            )
        v = variables[name]
        if isinstance(v, DiscreteVariable):
            disc[name], T = state_column(name, v, col, T)
        else:
            cont[name], T = _continuous_column(name, v, col, T)
    soft: dict[str, np.ndarray] = {}
    for name, col in (soft_evidence or {}).items():
        v = variables.get(name)
        if v is None:
            raise UnknownEvidenceError(
                f"soft evidence on unknown variable {name!r} (known: {sorted(variables)})"
            )
        soft[name], T = soft_column(name, v, col, T)
    if T is None or T < 1:
        raise ShapeError("filtering needs num_timesteps >= 1 (give an evidence column)")
    return Columns(int(T), disc, cont, soft)


def check_query(dbn: TwoSliceDBN, query, default: tuple[str, ...]) -> tuple[str, ...]:
    """The query as a tuple of known variable names: a name, a sequence of names, or
    ``None`` for ``default``.

    Raises
    ------
    InputError
        Neither a name nor an iterable (an int raised Python's ``TypeError``).
    UnknownVariableError
        A name the DBN does not declare.
    """
    if query is None:
        return tuple(default)
    if isinstance(query, str):
        query = (query,)
    names = set(dbn.names)
    try:
        out = tuple(query)
    except TypeError:
        raise InputError(f"query must be a variable name or a sequence of names, got "
                         f"{type(query).__name__} {query!r}") from None  # fmt: skip
    for q in out:
        if q not in names:
            raise UnknownVariableError(f"query names unknown variable {q!r}")
    return out
