"""Where the real ground truth lives (``../shared/data`` beside the repository).

The data are never copied into the project. Code finds them through the
``DBNTRACK_DATA`` environment variable, defaulting to ``shared/data`` next to the
repository checkout. Callers that need a file and cannot fall back to simulated data
call :func:`require`, which raises :class:`FileNotFoundError` with the path it looked at;
tests turn that into a skip with a reason.
"""

from __future__ import annotations

import os
from pathlib import Path

__all__ = ["data_dir", "find", "require"]

_REPO_ROOT = Path(__file__).resolve().parent.parent


def data_dir() -> Path:
    """The data folder: ``$DBNTRACK_DATA`` if set, else ``<repo>/../shared/data``.

    The folder may not exist; use :func:`find` or :func:`require` to get a file.
    """
    env = os.environ.get("DBNTRACK_DATA")
    if env:
        return Path(env).expanduser()
    return _REPO_ROOT.parent / "shared" / "data"


def find(*parts: str) -> Path | None:
    """Path of ``data_dir()/parts...`` if that file or folder exists, else ``None``."""
    path = data_dir().joinpath(*parts)
    return path if path.exists() else None


def require(*parts: str) -> Path:
    """Path of ``data_dir()/parts...``; raise :class:`FileNotFoundError` if absent."""
    path = data_dir().joinpath(*parts)
    if not path.exists():
        raise FileNotFoundError(
            f"real data file {path} not found: set DBNTRACK_DATA to the folder holding "
            "the shared data (see ../shared/data/README.md)"
        )
    return path
