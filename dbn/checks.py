"""Argument checks shared by the declarations, the engines and the runners. Each raises
the library's error (the class the caller names) with the argument's name, never
numpy's or Python's own."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any

import numpy as np

from dbn.errors import (
    DBNError,
    EvidenceError,
    InputError,
    ModelError,
    NonFiniteError,
    ShapeError,
)

__all__ = ["MAX_SCALE", "MIN_SCALE", "check_count", "check_mapping", "check_nonnegative",
           "check_number_fields", "check_numbers", "check_size", "check_type",
           "evidence_mapping", "evidence_state", "from_package", "instance_of", "is_whole",
           "is_real_number", "make_rng", "real_array", "refuse_complex", "whole_array"]

MAX_SCALE = 1e100
"""Largest ``|value|`` a tracker takes as a time (s), a spread or a model parameter: its
square, 1e200, is still finite in float64 (1e155 squared overflows). A value beyond it is a
unit mistake or a corrupt export (a Zajdel ``t_enter`` of -1e300 ran both trackers to rc 0),
so readers and configs refuse it, naming the field."""

MIN_SCALE = 1e-100
"""Smallest spread a tracker takes: its square, 1e-200, is still a normal float64 (a
``within_std`` of 1e-300 made the ADF prior's ``kappa`` 0.0)."""


def check_count(name: str, value: Any, error: type[DBNError] = InputError) -> int:
    """``value`` as an int >= 1: a Python or numpy integer, not a bool or a float (2.5 would
    be truncated, True read as 1); else ``error`` naming ``name``."""
    ok = isinstance(value, int | np.integer) and not isinstance(value, bool)
    if not ok or value < 1:
        raise error(f"{name} must be an integer >= 1, got {value!r}")
    return int(value)


def check_size(name: str, value: Any, error: type[DBNError] = InputError) -> int:
    """``value`` as an int >= 0 (a count that may be zero: samples, steps, restarts): a
    Python or numpy integer, not a bool or a float; else ``error`` naming ``name``."""
    ok = isinstance(value, int | np.integer) and not isinstance(value, bool)
    if not ok or value < 0:
        raise error(f"{name} must be an integer >= 0, got {value!r}")
    return int(value)


def is_real_number(value: Any) -> bool:
    """Whether ``value`` is one real number: a Python or numpy int or float, not a bool
    (True read as 1) and not complex (``np.number`` takes complex scalars, which numpy
    orders by their real parts and ``float()`` casts with only a warning)."""
    return (isinstance(value, int | float | np.integer | np.floating)
            and not isinstance(value, bool | np.bool_))  # fmt: skip


def check_nonnegative(name: str, value: Any, error: type[DBNError] = InputError) -> float:
    """``value`` as a float >= 0: a real number, not a bool (True read as 1) or a string
    (raised ``TypeError`` on comparison); NaN is refused; else ``error`` naming ``name``."""
    if not is_real_number(value) or not value >= 0:
        raise error(f"{name} must be a number >= 0, got {value!r}")
    return float(value)


def check_number_fields(obj: Any, error: type[DBNError] = InputError) -> None:
    """Check the numeric fields of a config (a dataclass or a ``NamedTuple``) by their
    defaults' types, before its own range checks compare them: a field whose default is
    an int holds an int (a Python or numpy integer: not a float, a bool or NaN), one whose
    default is a float a real number (an int too), finite with ``|x| <=``
    :data:`MAX_SCALE`, one whose default is a flat tuple of numbers a sequence (tuple, list,
    1-D array) of such numbers; else ``error`` naming ``Class.field``. (NaN passed range checks
    written as ``x < 1``, 2.5 was truncated or compared as it was, a string raised
    Python's ``TypeError`` on comparison, and 1e300 overflowed once squared.)"""
    if dataclasses.is_dataclass(obj):
        defaults = {f.name: f.default for f in dataclasses.fields(obj)}
    else:
        defaults = dict(getattr(type(obj), "_field_defaults", {}))
    cls = type(obj).__name__
    for name, default in defaults.items():
        value = getattr(obj, name)
        if type(default) is int:
            if isinstance(value, bool) or not isinstance(value, int | np.integer):
                raise error(f"{cls}.{name} must be an integer, got {value!r}")
        elif type(default) is float:
            if not _finite_number(value):
                raise error(f"{cls}.{name} must be a finite number, |x| <= {MAX_SCALE:g}, "
                            f"got {value!r}")  # fmt: skip
        elif _numbers_default(default):
            flat = isinstance(value, tuple | list) or (isinstance(value, np.ndarray)
                                                       and value.ndim == 1)  # fmt: skip
            if not flat or not all(_finite_number(v) for v in value):
                raise error(f"{cls}.{name} must be a sequence of finite numbers, |x| <= "
                            f"{MAX_SCALE:g}, got {value!r}")  # fmt: skip


def _finite_number(value: Any) -> bool:
    """A real number (a Python or numpy int or float, not a bool), finite, ``|x| <=``
    :data:`MAX_SCALE`."""
    if isinstance(value, np.floating):  # float32 compared with 1e100 overflows
        value = float(value)
    return is_real_number(value) and abs(value) <= MAX_SCALE


def _numbers_default(default: Any) -> bool:
    """A config default that is a non-empty flat tuple of numbers (move probabilities, a
    range): its field holds a sequence of real numbers."""
    return (type(default) is tuple and bool(default)
            and all(type(v) in (int, float) for v in default))  # fmt: skip


def check_numbers(name: str, value: Any, size: int, low: float | None = None,
                  error: type[DBNError] = ModelError) -> np.ndarray:
    """``value`` as ``size`` float64 numbers (any shape of that size, returned flat),
    finite, ``|x| <=`` :data:`MAX_SCALE` and ``>= low`` where given; else a
    :mod:`dbn.errors` class naming ``name``: ``error`` for what is not numbers or is below
    ``low``, :class:`ShapeError` for another count, :class:`NonFiniteError` for NaN,
    infinity or a number beyond the bound (numpy's reshape or float errors before)."""
    refuse_complex(name, value, error)
    try:
        v = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise error(f"{name} must be numbers, got {value!r}") from None
    if v.size != size:
        raise ShapeError(f"{name} has {v.size} numbers (shape {v.shape}), expected {size}")
    v = v.reshape(size)
    if not np.all(np.isfinite(v)) or np.any(np.abs(v) > MAX_SCALE):
        raise NonFiniteError(f"{name} = {v.tolist()}: every number finite, |x| <= {MAX_SCALE:g}")
    if low is not None and np.any(v < low):
        raise error(f"{name} = {v.tolist()}: every number must be >= {low:g}")
    return v


def check_type(name: str, value: Any, kind: type | tuple[type, ...],
               error: type[DBNError] = ModelError) -> Any:
    """``value`` if it is an instance of ``kind`` (a class or a tuple of them), else
    ``error`` naming ``name``, the class(es) it needs and the one it got (a constructor
    given the wrong object raised ``AttributeError`` deep inside, or later, at a step)."""
    if not isinstance(value, kind):
        kinds = kind if isinstance(kind, tuple) else (kind,)
        raise error(f"{name} must be an instance of {' or '.join(k.__name__ for k in kinds)}, "
                    f"got {type(value).__name__}")  # fmt: skip
    return value


def refuse_complex(what: str, value: Any, error: type[DBNError] = InputError) -> None:
    """Raise ``error`` naming ``what`` if ``value`` holds complex numbers: numpy's float
    conversion drops their imaginary parts with only a ``ComplexWarning``. (What numpy
    cannot read as one array passes, for the caller's conversion to name.)"""
    try:
        complex_ = np.iscomplexobj(value)
    except (TypeError, ValueError):
        return
    if complex_:
        raise error(f"{what} holds complex numbers: expected real ones (numpy would drop "
                    "the imaginary parts)")  # fmt: skip


def real_array(what: str, value: Any, error: type[DBNError] = InputError) -> np.ndarray:
    """``value`` as a float64 array (any shape; finiteness is the caller's check); else
    ``error`` naming ``what``: complex numbers (:func:`refuse_complex`), strings, ragged
    lists and other objects that are not numbers (numpy's own ValueError or TypeError named
    no argument)."""
    refuse_complex(what, value, error)
    try:
        return np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise error(f"{what} is not an array of numbers ({exc})") from None


def whole_array(what: str, value: Any, error: type[DBNError] = InputError) -> np.ndarray:
    """``value`` as an int64 array of its own (a copy); else ``error`` naming ``what``:
    what :func:`real_array` refuses, and a float that is not a whole number an int64 holds
    (:func:`is_whole`: an index of 1.7 was truncated to 1, NaN cast to garbage)."""
    arr = real_array(what, value, error) if not _is_int_array(value) else np.asarray(value)
    if arr.dtype.kind == "f" and not np.all(is_whole(arr)):
        raise error(f"{what} must be whole numbers, got {arr[~is_whole(arr)][:3].tolist()}")
    return arr.astype(np.int64)


def _is_int_array(value: Any) -> bool:
    """An integer numpy array (its int64 values are taken as they are, not via float)."""
    return isinstance(value, np.ndarray) and value.dtype.kind in "iu"


def check_mapping(what: str, value: Any, error: type[DBNError] = EvidenceError) -> None:
    """Raise ``error`` unless ``value`` is None or a mapping (evidence ``name -> value``:
    a list of pairs raised ``AttributeError`` deep inside)."""
    if value is not None and not isinstance(value, Mapping):
        raise error(f"{what} must be a mapping name -> value, got {type(value).__name__}")


def make_rng(seed: Any, name: str = "seed") -> np.random.Generator:
    """``np.random.default_rng(seed)`` for what numpy takes as a seed (an int >= 0, a
    sequence of them, a ``SeedSequence``, a ``Generator`` returned as is), not a bool
    (True seeded as 1); else :class:`InputError` naming ``name`` (numpy's own ValueError
    "expected non-negative integer" or TypeError named no argument)."""
    if isinstance(seed, bool | np.bool_):
        raise InputError(f"{name} must be an integer >= 0, got {seed!r}")
    try:
        return np.random.default_rng(seed)
    except (TypeError, ValueError):
        raise InputError(f"{name} must be an integer >= 0 (or a numpy Generator), got "
                         f"{seed!r}") from None


def instance_of(obj: Any, package: str, kind: str) -> bool:
    """Whether ``obj`` is an instance of ``package``'s class ``kind`` or of a subclass
    (yours included), told by the classes' names and modules so that ``package`` (pgmpy,
    pandas) is not imported to ask."""
    return any(c.__name__ == kind and c.__module__.split(".")[0] == package
               for c in type(obj).__mro__)  # fmt: skip


def from_package(obj: Any, package: str) -> bool:
    """Whether ``obj``'s class is defined in ``package`` (``"pgmpy"``), told by its
    module's name so that ``package`` is not imported to ask."""
    return type(obj).__module__.split(".")[0] == package


def evidence_mapping(evidence: Any) -> Any:
    """One case's evidence as a mapping: a pandas ``Series`` (a ``DataFrame``'s row, its
    index the variable names) as a dict; anything else as is (then checked as a mapping).
    A two-level index ``(name, component)`` (a row of a frame with column pairs, read as
    :func:`inference.evidence_columns.columns_from_frame` reads the frame) maps each name
    to its one value, or to the list of its components' values in the row's order."""
    if not instance_of(evidence, "pandas", "Series"):
        return evidence
    if evidence.index.nlevels != 2:
        return evidence.to_dict()
    parts: dict[Any, list] = {}
    for (name, _), value in evidence.items():
        parts.setdefault(name, []).append(value)
    return {name: values[0] if len(values) == 1 else values for name, values in parts.items()}


def evidence_state(state: Any) -> Any:
    """One observed state as a column of evidence reads it: ``None``, ``-1``, NaN and
    pandas' ``NA`` / ``NaT`` are unobserved (``None``); a float of a whole number is its
    index (a ``DataFrame`` row with a gap holds floats); anything else as is (the
    variable then checks it)."""
    if type(state).__name__ in ("NAType", "NaTType"):
        return None
    if isinstance(state, float | np.floating):
        if np.isnan(state):
            return None
        if is_whole(state):
            state = int(state)
    if isinstance(state, int | np.integer) and not isinstance(state, bool) and state == -1:
        return None
    return state


def is_whole(value: Any) -> Any:
    """Where a float (scalar or array) is a whole number an int64 holds exactly: finite,
    equal to its rounding, below 2**53 in size (a state index written as a float)."""
    return np.isfinite(value) & (value == np.round(value)) & (np.abs(value) < 2.0**53)
