"""Every exception the library raises on bad input, in one place.

All are :class:`ValueError` subclasses, so ``except ValueError`` keeps working for
callers who do not care which check failed. Each message names the offending field
(node, variable, observation index, ...) and the offending value. Every check runs
*before* any state is changed: a rejected input leaves a model, a filter or a tracker
exactly as it was.
"""

from __future__ import annotations

__all__ = [
    "DBNError",
    "ModelError",
    "CycleError",
    "UnknownVariableError",
    "DuplicateNameError",
    "CPDShapeError",
    "NotNormalizedError",
    "NegativeProbabilityError",
    "FrontierTooLargeError",
    "EvidenceError",
    "InputError",
    "ConfigError",
    "ShapeError",
    "NonFiniteError",
    "TimeOrderError",
    "FileFormatError",
    "CheckpointError",
    "in_file",
    "MemoryLimitError",
    "as_memory_limit",
]


class DBNError(ValueError):
    """Base class of every error raised by this library on bad input."""


# --- model declaration -----------------------------------------------------------------
class ModelError(DBNError):
    """A model declaration (variables, CPDs, graph) is invalid."""


class CycleError(ModelError):
    """The parent relation of a Bayes net (or of one DBN slice) has a directed cycle."""


class UnknownVariableError(ModelError):
    """A CPD, an edge, a query or evidence names a variable the model does not have."""


class DuplicateNameError(ModelError):
    """Two variables (or two CPDs) share one name."""


class CPDShapeError(ModelError):
    """A CPD's table, weights or covariance does not have the shape its variables imply."""


class NotNormalizedError(ModelError):
    """A row of a conditional probability table does not sum to 1 (tolerance 1e-9)."""


class NegativeProbabilityError(ModelError):
    """A probability table holds a negative (or NaN) entry."""


class FrontierTooLargeError(ModelError):
    """Exact inference would build a table larger than its memory limit; the message
    quotes the size and names the approximate methods (Boyen-Koller, particle, RBPF)."""


# --- evidence and data -----------------------------------------------------------------
class EvidenceError(DBNError):
    """Evidence (hard or soft) is invalid: unknown variable, state out of range, a
    likelihood vector of the wrong length, negative or all zero."""


class UnknownEvidenceError(UnknownVariableError, EvidenceError):
    """Evidence (hard or soft) names a variable the model does not have: both an unknown
    variable and invalid evidence, so ``except`` of either class catches it."""


class InputError(DBNError):
    """Data handed to a filter or a tracker is invalid."""


class ShapeError(InputError):
    """An array has the wrong shape or dimension."""


class NonFiniteError(InputError):
    """An array holds NaN or infinity where finite numbers are required."""


class TimeOrderError(InputError):
    """Observations or log timestamps go backwards in time (or quit before enter)."""


class ConfigError(InputError):
    """A tracker option (a ``--config`` key or value) is unknown or invalid; the message
    names the key, and ``dbntrack track`` puts the config file before it."""


class FileFormatError(InputError):
    """A file is empty, truncated, malformed, of the wrong type or inconsistent.

    The message starts with ``FILE:LINE:`` (or ``FILE:`` when no line applies) and names
    the element; ``file`` and ``line`` (``None`` where it does not apply) are attributes.
    """

    def __init__(self, file, message: str, line: int | None = None) -> None:
        self.file = str(file)
        self.line = line
        self.message = message
        where = f"{self.file}:{line}" if line else self.file
        super().__init__(f"{where}: {message}")

    def __reduce__(self):  # picklable across processes (dask workers)
        return (self.__class__, (self.file, self.message, self.line))


class CheckpointError(FileFormatError):
    """A saved state (checkpoint) is unreadable, of another format version, saved under
    another configuration, fails its checksum or holds NaN/inf."""


def in_file(exc: DBNError, file) -> DBNError:
    """``exc`` (a library error) as the same class with ``FILE: `` before its message;
    a :class:`FileFormatError` already names its file and is returned unchanged."""
    if isinstance(exc, FileFormatError):
        return exc
    return type(exc)(f"{file}: {exc}")


# --- resources -------------------------------------------------------------------------
class MemoryLimitError(DBNError):
    """An exact engine would allocate a table larger than its limit (the message names
    the clique and its size); raised before anything is allocated. Also what a run that
    did run out of memory raises in its place (:func:`as_memory_limit`)."""


def as_memory_limit(exc: BaseException, what: str, advice: str) -> MemoryLimitError | None:
    """``MemoryLimitError("{what} ran out of memory (...): {advice}")`` for numpy's
    ``MemoryError`` or jax's ``RESOURCE_EXHAUSTED`` (a ``RuntimeError``: raw and naming
    no setting before); None for any other exception, which the caller re-raises."""
    if not isinstance(exc, MemoryError) and not (
        isinstance(exc, RuntimeError) and "RESOURCE_EXHAUSTED" in str(exc)
    ):
        return None
    detail = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
    return MemoryLimitError(f"{what} ran out of memory ({detail}): {advice}")
