"""The progress bar of every long loop: tqdm's notebook widget where Jupyter can draw it,
its text bar elsewhere.

``tqdm.auto`` picks the widget in any notebook and, where ``ipywidgets`` is not installed
(our ``test`` and ``notebooks`` extras do not install it), warns "IProgress not found" in
every cell that shows a bar before falling back to the text bar; :func:`progress_bar`
asks for the widget only where ``ipywidgets`` can be imported.
"""

from __future__ import annotations

import importlib.util
from collections.abc import Iterable
from typing import Any

__all__ = ["progress_bar"]


def progress_bar(iterable: Iterable | None = None, **kwargs: Any):
    """``tqdm(iterable, **kwargs)``: ``tqdm.auto``'s bar with ``ipywidgets`` installed,
    ``tqdm.std``'s without (the same arguments; ``disable=True`` shows nothing)."""
    if importlib.util.find_spec("ipywidgets") is not None:
        from tqdm.auto import tqdm
    else:
        from tqdm.std import tqdm
    return tqdm(iterable, **kwargs)
