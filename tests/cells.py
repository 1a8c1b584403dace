"""Example files with one cell changed: the tests that feed the readers a bad number (a unit
mistake, a corrupt export) edit their copies through these three functions, one way.

Files: ``#`` lines and blank lines are comments; a ``.csv`` has a header line of column
names; fields are split by commas, by whitespace in a ``.dat`` (MRCLAM), rejoined by one
space there.
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["columns", "data_line", "set_cell"]


def _sep(path: Path) -> str | None:
    return None if path.suffix == ".dat" else ","


def _first_line(lines: list[str]) -> int:
    """0-based index of the first line that is neither blank nor a ``#`` comment."""
    return next(i for i, ln in enumerate(lines) if ln and not ln.startswith("#"))


def data_line(path: Path) -> int:
    """1-based number of the first data line of ``path`` (after comments and a header)."""
    return _first_line(Path(path).read_text().splitlines()) + 1 + (Path(path).suffix == ".csv")


def columns(path: Path) -> list[str] | list[int]:
    """A ``.csv``'s header names, else the indices of the first data line's fields."""
    path = Path(path)
    lines = path.read_text().splitlines()
    first = lines[_first_line(lines)].split(_sep(path))
    return first if path.suffix == ".csv" else list(range(len(first)))


def set_cell(path: Path, line: int, column: str | int, value: str, out: Path | None = None
             ) -> Path:  # fmt: skip
    """Write ``path`` (or a copy of it at ``out``) with ``column`` (a header name or an
    index) of 1-based ``line`` set to ``value``; the path written."""
    path = Path(path)
    lines = path.read_text().splitlines()
    col = columns(path).index(column) if isinstance(column, str) else column
    fields = lines[line - 1].split(_sep(path))
    fields[col] = value
    lines[line - 1] = (_sep(path) or " ").join(fields)
    out = path if out is None else Path(out)
    out.write_text("\n".join(lines) + "\n")
    return out
