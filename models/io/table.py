"""CSV plumbing shared by the readers: rows with their line numbers, typed fields, and
errors that name the file and the line (``FILE:LINE: message``)."""

from __future__ import annotations

import codecs
import csv
import gzip
import json
import math
import zlib
from collections.abc import Iterable, Sequence
from pathlib import Path

from dbn.errors import FileFormatError, InputError

__all__ = [
    "Row",
    "read_rows",
    "read_lines",
    "fail",
    "as_float",
    "as_int",
    "write_rows",
    "require_file",
    "read_json_config",
]


class Row(dict):
    """One CSV row (column name -> raw text) that remembers its file and line."""

    path: str = ""
    line: int = 0

    def fail(self, message: str) -> InputError:
        """An :class:`InputError` ``FILE:LINE: message`` for this row."""
        return fail(self.path, self.line, message)

    def float(self, name: str, *, allow_empty: bool = False) -> float:
        """Field ``name`` as a finite float (``nan`` for an empty field if allowed)."""
        return as_float(self.get(name, ""), self.path, self.line, name, allow_empty)

    def int(self, name: str) -> int:
        """Field ``name`` as an int."""
        return as_int(self.get(name, ""), self.path, self.line, name)


def fail(path: str | Path, line: int, message: str) -> FileFormatError:
    """``FileFormatError("FILE:LINE: message")`` (line 0: the file as a whole); an
    :class:`~dbn.errors.InputError`, with ``file`` and ``line`` attributes."""
    return FileFormatError(path, message, line or None)


def read_lines(path: str | Path, what: str = "file") -> list[str]:
    """The lines of a UTF-8 text file (``.gz`` decompressed), newlines kept; a leading
    byte-order mark (a spreadsheet's "CSV UTF-8" export writes one) is dropped.

    Raises :class:`~dbn.errors.FileFormatError` naming the file for a missing,
    unreadable, truncated (gzip), binary (NUL byte) or non-UTF-8 file, with the line
    where it applies.
    """
    path = require_file(path, what)
    opener = gzip.open if path.name.endswith(".gz") else open
    try:
        with opener(path, "rb") as f:
            data = f.read()
    except (OSError, EOFError, zlib.error) as exc:
        raise fail(path, 0, f"unreadable {what} ({exc})") from None
    data = data.removeprefix(codecs.BOM_UTF8)
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = data.count(b"\n", 0, exc.start) + 1
        raise fail(path, line, f"not UTF-8 text ({exc.reason})") from None
    if "\x00" in text:
        raise fail(path, text.count("\n", 0, text.index("\x00")) + 1, "binary data (NUL byte)")
    return text.splitlines(keepends=True)


def require_file(path: str | Path, what: str) -> Path:
    """``path`` as a Path; :class:`InputError` naming ``what`` when it is not a file."""
    p = Path(path)
    if not p.is_file():
        raise InputError(f"{p}: {what} not found (no such file)")
    return p


def as_float(text: str, path, line: int, name: str, allow_empty: bool = False) -> float:
    """``text`` as a finite float, else ``InputError`` naming file, line and column."""
    text = (text or "").strip()
    if text == "" and allow_empty:
        return math.nan
    try:
        value = float(text)
    except ValueError:
        raise fail(path, line, f"{name} = {text!r} is not a number") from None
    if not math.isfinite(value):
        raise fail(path, line, f"{name} = {text!r} is not finite")
    return value


_INT_LIMIT = 2**63  # the int64 arrays the readers fill


def as_int(text: str, path, line: int, name: str) -> int:
    """``text`` as an int (``"3"``, ``"3.0"``, ``"3e2"``) that fits in int64, else
    ``InputError`` naming file, line and column (a larger one overflowed the reader's
    int64 array with a raw ``OverflowError``)."""
    text = (text or "").strip()
    try:
        value = int(text)
    except ValueError:
        try:
            number = float(text)
        except ValueError:
            number = math.nan
        if not number.is_integer():
            raise fail(path, line, f"{name} = {text!r} is not an integer") from None
        value = int(number)
    if not -_INT_LIMIT <= value < _INT_LIMIT:
        raise fail(path, line, f"{name} = {text!r} is out of range (|{name}| < 2^63)")
    return value


def read_rows(
    path: str | Path,
    required: Sequence[str] = (),
    what: str = "CSV file",
    keep_blank: bool = False,
) -> tuple[list[str], list[Row]]:
    """The header and the rows of a CSV file with a header line.

    Lines starting with ``#`` are skipped, and so are blank lines unless ``keep_blank``
    (then a blank line after the header is a row of empty fields: a slice with no
    evidence in a one-column file). Raises :class:`InputError`
    (``FILE:LINE: ...``) for a missing file, a missing required column, a header name
    holding a control character or a row with more fields than the header.
    """
    lines = read_lines(path, what)
    path = Path(path)
    rows: list[Row] = []
    header: list[str] | None = None
    try:
        records = list(csv.reader(lines))
    except csv.Error as exc:
        raise fail(path, 0, f"not a CSV file ({exc})") from None
    if len(records) != len(lines):  # a quoted field spans lines: line numbers would shift
        raise fail(path, 0, "a quoted field spans several lines (unbalanced quote?)")
    for line_no, fields in enumerate(records, start=1):
        blank = not fields or all(not x.strip() for x in fields)
        if (blank and not (keep_blank and header)) or (fields and fields[0].startswith("#")):
            continue
        fields = [x.strip() for x in fields]
        if header is None:
            header = fields
            odd = [c for c in header if any(ord(ch) < 32 and ch != "\t" for ch in c)]
            if odd:  # a damaged header (a byte flip merged it with the next line, say)
                raise fail(path, line_no, f"header column {odd[0]!r} holds a control character")
            missing = [c for c in required if c not in header]
            if missing:
                raise fail(path, line_no, f"missing column(s) {missing}; header is {header}")
            continue
        if len(fields) > len(header):
            raise fail(path, line_no, f"{len(fields)} fields, header has {len(header)}")
        row = Row(zip(header, fields + [""] * (len(header) - len(fields))))
        row.path, row.line = str(path), line_no
        rows.append(row)
    if header is None:
        raise fail(path, 0, "empty file (no header line)")
    return header, rows


def write_rows(path: str | Path, header: Sequence[str], rows: Iterable[Sequence],
               comments: Sequence[str] = ()) -> Path:
    """Write a CSV file with a header line; floats with full precision (``repr``).
    ``comments`` go first, one ``# `` line each (:func:`read_rows` skips them)."""
    path = Path(path)
    with open(path, "w", newline="", encoding="utf-8") as f:
        w = csv.writer(f)
        f.writelines(f"# {c}{w.dialect.lineterminator}" for c in comments)
        w.writerow(header)
        for r in rows:
            w.writerow([repr(float(x)) if isinstance(x, float) else x for x in r])
    return path


def read_json_config(path: str | Path) -> dict:
    """A ``--config`` file: a JSON object; anything else is a
    :class:`~dbn.errors.FileFormatError` naming the file (and the line)."""
    text = "".join(read_lines(path, "config file"))
    try:
        config = json.loads(text)
    except json.JSONDecodeError as exc:
        raise fail(path, exc.lineno, f"not valid JSON ({exc.msg})") from None
    except RecursionError:
        raise fail(path, 0, "JSON nested too deeply") from None
    if not isinstance(config, dict):
        raise fail(path, 1, "the config must be a JSON object")
    return config
