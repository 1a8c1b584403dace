"""Checkpoints: a filter's or a tracker's state saved as named arrays, without pickle.

The file is an ``.npz`` holding the arrays and a JSON header with

* ``format`` (a tag naming what was saved) and ``version`` (:data:`VERSION`),
* ``config``: the configuration the state was saved under (any JSON value); loading
  under another configuration is a :class:`~dbn.errors.CheckpointError`,
* ``checksum``: the SHA-256 of the header (without the checksum) and of every array's
  name, dtype, shape and bytes,
* whatever the caller adds (e.g. a time pointer).

:func:`load_arrays` turns every way a file can be bad (missing, empty, truncated, not a
zip, another format, version or configuration, a changed byte, a missing array, NaN or
inf in a float array) into a :class:`~dbn.errors.CheckpointError` naming the file; nothing
is returned half-read.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import zipfile
import zlib
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from dbn.errors import CheckpointError, DBNError

__all__ = ["VERSION", "jsonable", "save_arrays", "load_arrays"]

VERSION = 2
"""Format version written by :func:`save_arrays` (1: the unversioned files before it)."""

_HEADER = "__header__"


def jsonable(value: Any) -> Any:
    """``value`` as plain JSON data: NamedTuples and dataclasses become dicts, arrays and
    tuples lists, numpy scalars Python numbers (so that configurations compare equal
    after a round trip through the file)."""
    if hasattr(value, "_asdict"):
        return {k: jsonable(v) for k, v in value._asdict().items()}
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: jsonable(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if isinstance(value, Mapping):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [jsonable(v) for v in value]
    if isinstance(value, np.ndarray) or hasattr(value, "__array__"):
        return jsonable(np.asarray(value).tolist())
    if isinstance(value, np.generic):
        return value.item()
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    return repr(value)


def _canonical(header: Mapping[str, Any]) -> bytes:
    return json.dumps(header, sort_keys=True, allow_nan=True).encode()


def _checksum(header: Mapping[str, Any], arrays: Mapping[str, np.ndarray]) -> str:
    h = hashlib.sha256(_canonical({k: v for k, v in header.items() if k != "checksum"}))
    for name in sorted(arrays):
        a = np.ascontiguousarray(arrays[name])
        h.update(f"{name}|{a.dtype.str}|{a.shape}|".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def _check_finite(path, arrays: Mapping[str, np.ndarray], neg_inf: Sequence[str] = ()) -> None:
    """NaN or inf anywhere is an error, except -inf in the arrays named in ``neg_inf``
    (log-space values: log 0, or "never" times)."""
    for name, a in arrays.items():
        if not np.issubdtype(a.dtype, np.inexact):
            continue
        ok = np.isfinite(a) | ((a == -np.inf) if name in neg_inf else False)
        if not np.all(ok):
            bad = a[~ok].ravel()[0]
            raise CheckpointError(path, f"array {name!r} holds {bad} (NaN or inf is not allowed)")


def save_arrays(
    path,
    arrays: Mapping[str, Any],
    fmt: str,
    config: Any = None,
    extra: Mapping[str, Any] | None = None,
    neg_inf: Sequence[str] = (),
) -> None:
    """Write named arrays and a versioned, checksummed JSON header to ``path`` (.npz).

    Parameters
    ----------
    path : file name or binary file object
    arrays : name -> array (numeric or bool; no object arrays)
    fmt : format tag, checked by :func:`load_arrays`
    config : the configuration the state belongs to (made :func:`jsonable`)
    extra : further JSON entries (e.g. ``{"t": 5}``), returned by :func:`load_arrays`
    neg_inf : arrays where -inf is a legal value (log weights: log 0; "no time yet")

    Raises
    ------
    CheckpointError
        An array holds NaN or inf (a state that cannot be resumed; -inf is allowed in
        ``neg_inf``), or a name is reserved.
    """
    data = {str(k): np.asarray(v) for k, v in arrays.items()}
    if _HEADER in data:
        raise CheckpointError(path, f"array name {_HEADER!r} is reserved")
    _check_finite(path, data, neg_inf)
    header = {"format": fmt, "version": VERSION, "config": jsonable(config)}
    header.update(jsonable(dict(extra or {})))
    header["checksum"] = _checksum(header, data)
    np.savez(path, **{_HEADER: np.frombuffer(_canonical(header), np.uint8)}, **data)


def _read(path) -> tuple[dict, dict[str, np.ndarray]]:
    """The header and every array of an .npz file; any failure is a CheckpointError."""
    try:
        with np.load(path, allow_pickle=False) as f:
            if not isinstance(f, np.lib.npyio.NpzFile):
                raise CheckpointError(path, "not a saved state (a bare .npy array, not .npz)")
            if _HEADER not in f.files:
                raise CheckpointError(path, "not a saved state (no header)")
            header = json.loads(bytes(f[_HEADER]).decode())
            arrays = {n: np.array(f[n]) for n in f.files if n != _HEADER}
    except DBNError:
        raise
    except FileNotFoundError:
        raise CheckpointError(path, "no such checkpoint file") from None
    except (
        OSError,
        EOFError,
        ValueError,
        KeyError,
        zipfile.BadZipFile,
        zlib.error,
        UnicodeDecodeError,
        NotImplementedError,
    ) as exc:
        msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise CheckpointError(path, f"unreadable or truncated checkpoint ({msg})") from None
    if not isinstance(header, dict):
        raise CheckpointError(path, f"header is {type(header).__name__}, expected an object")
    return header, arrays


def load_arrays(
    path, fmt: str, names: Sequence[str], config: Any = None, neg_inf: Sequence[str] = ()
) -> tuple[dict[str, np.ndarray], dict]:
    """Read a file written by :func:`save_arrays`, checking everything before returning.

    Parameters
    ----------
    path : file name or binary file object
    fmt : expected format tag
    names : the arrays the caller needs (others are an error too: not this format)
    config : the configuration of the loader; must equal the saved one (as JSON)
    neg_inf : arrays where -inf is a legal value (as in :func:`save_arrays`)

    Returns
    -------
    arrays : name -> numpy array, dtypes as stored
    header : the JSON header (``format``, ``version``, ``config``, extras)

    Raises
    ------
    CheckpointError
        Naming the file: unreadable, another format, version or configuration, a checksum
        mismatch, missing or unexpected arrays, NaN or inf in a float array (-inf is
        allowed in ``neg_inf``).
    """
    header, arrays = _read(path)
    if header.get("format") != fmt:
        raise CheckpointError(path, f"format {header.get('format')!r}, expected {fmt!r}")
    if header.get("version") != VERSION:
        raise CheckpointError(
            path, f"format version {header.get('version')!r}, this library reads {VERSION}"
        )
    if header.get("checksum") != _checksum(header, arrays):
        raise CheckpointError(path, "checksum mismatch (the file was changed or damaged)")
    missing = sorted(set(names) - set(arrays))
    unexpected = sorted(set(arrays) - set(names))
    if missing or unexpected:
        raise CheckpointError(path, f"missing arrays {missing}, unexpected arrays {unexpected}")
    want = json.loads(_canonical({"c": jsonable(config)}))["c"]
    if header.get("config") != want:
        raise CheckpointError(
            path, f"saved under configuration {header.get('config')!r}, this one is {want!r}"
        )
    _check_finite(path, arrays, neg_inf)
    return arrays, header
