"""Every tutorial runs end to end (small sizes: ``DBNTRACK_QUICK=1``) and its notebook
is the jupytext pair of its ``.py`` source."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

TUTORIALS = sorted((Path(__file__).resolve().parent.parent / "tutorials").glob("[0-9]*.py"))


@pytest.mark.parametrize("path", TUTORIALS, ids=[p.stem for p in TUTORIALS])
def test_notebook_is_paired(path: Path) -> None:
    jupytext = pytest.importorskip("jupytext")
    ipynb = path.with_suffix(".ipynb")
    assert ipynb.exists(), f"{ipynb.name} missing: run `jupytext --sync {path.name}`"
    source = [c.source for c in jupytext.read(path).cells]
    paired = [c.source for c in jupytext.read(ipynb).cells]
    assert source == paired, f"{ipynb.name} is out of sync with {path.name}: run jupytext --sync"


@pytest.mark.heavy  # 10-25 s each: CI runs them (pytest -m heavy)
@pytest.mark.parametrize("path", TUTORIALS, ids=[p.stem for p in TUTORIALS])
def test_tutorial_executes(path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    jupytext = pytest.importorskip("jupytext")
    nbclient = pytest.importorskip("nbclient")
    monkeypatch.setenv("DBNTRACK_QUICK", "1")
    monkeypatch.setenv("MPLBACKEND", "Agg")
    nb = jupytext.read(path)
    client = nbclient.NotebookClient(
        nb, timeout=900, kernel_name="python3", resources={"metadata": {"path": str(path.parent)}}
    )
    client.execute(env=dict(os.environ))
    warned = [o["text"] for c in nb.cells for o in c.get("outputs", [])
              if o.get("name") == "stderr" and "IProgress not found" in o.get("text", "")]
    assert not warned, f"{path.name}: a progress bar wants ipywidgets: {warned[0]}"
