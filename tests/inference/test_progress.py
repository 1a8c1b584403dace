"""``inference.progress.progress_bar`` asks for tqdm's notebook widget only where
``ipywidgets`` can be imported (else ``tqdm.auto`` warns "IProgress not found" in a
notebook)."""

from __future__ import annotations

import importlib.util
import warnings

import pytest
import tqdm.auto
import tqdm.std

from inference import progress


def _find_spec_without(name: str):
    real = importlib.util.find_spec

    def find_spec(module: str, *args):
        return None if module == name else real(module, *args)

    return find_spec


def test_text_bar_without_ipywidgets(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(progress.importlib.util, "find_spec", _find_spec_without("ipywidgets"))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        bar = progress.progress_bar(range(3), desc="x", disable=True)
    assert type(bar) is tqdm.std.tqdm
    assert list(bar) == [0, 1, 2]


def test_auto_bar_with_ipywidgets(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(progress.importlib.util, "find_spec",
                        lambda module, *args: object() if module == "ipywidgets" else None)
    bar = progress.progress_bar(total=2, disable=True)
    assert type(bar) is tqdm.auto.tqdm
    assert bar.total == 2
