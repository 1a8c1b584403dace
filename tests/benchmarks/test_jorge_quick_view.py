"""The jorge benchmark's ``--quick`` run labels only the first seconds of the SIMULATED-view
sequence (``QUICK_VIEW_SECONDS``), so that it keeps the contract's 60 s; the full run
labels it whole."""

from __future__ import annotations

import gzip

import numpy as np
import pytest

from benchmarks.jorge import _label_sequences
from models.jorge.eth import ETH_FPS
from models.jorge.online import OnlineConfig


def _eth_folder(tmp_path, monkeypatch, steps: int = 200) -> None:
    """A data folder with only an ETH ``obsmat`` file: three SIMULATED people walking side
    by side for ``steps`` annotations (one every 6 video frames, as ETH's)."""
    rows = [f"{780 + 6 * i:.7e} {pid:.7e} {6.0 + 0.03 * i:.4f} 0.0 {2.5 + 0.8 * pid:.4f} 0.75 0.0 0.0"
            for i in range(steps) for pid in (1, 2, 3)]
    (tmp_path / "eth").mkdir()
    with gzip.open(tmp_path / "eth" / "obsmat.txt.gz", "wt") as fh:
        fh.write("\n".join(rows) + "\n")
    monkeypatch.setenv("DBNTRACK_DATA", str(tmp_path))


def test_the_view_is_cut_to_its_first_seconds_only_when_asked(tmp_path, monkeypatch):
    _eth_folder(tmp_path, monkeypatch)
    whole, _, _, ok = _label_sequences([0], OnlineConfig())
    cut, _, _, ok_cut = _label_sequences([0], OnlineConfig(), view_seconds=20.0)
    assert ok and ok_cut and set(whole) == set(cut) == {"ETH-seq_eth"}
    assert whole["ETH-seq_eth"]["duration_s"] == pytest.approx(200 / ETH_FPS)
    assert cut["ETH-seq_eth"]["duration_s"] == pytest.approx(20.0)
    assert cut["ETH-seq_eth"]["split"] == "simulated_view"
    assert np.isfinite(cut["ETH-seq_eth"]["error_rate"])
