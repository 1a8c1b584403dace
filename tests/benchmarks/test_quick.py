"""CI smoke test of every benchmark: ``python -m benchmarks NAME --quick`` finishes, its
last stdout line is one JSON object with the contract's keys, and its ``ok`` is true.

Marked ``bench`` (about three minutes in all on two cores): not in the default ``pytest``;
``.ci/run`` runs them one at a time, ``pytest -m bench -n 0``."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from benchmarks import available

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.bench
@pytest.mark.parametrize("name", available())
def test_quick_benchmark_contract(name: str) -> None:
    proc = subprocess.run(
        [sys.executable, "-m", "benchmarks", name, "--quick"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    last = proc.stdout.strip().splitlines()[-1]
    result = json.loads(last)
    for key in ("name", "quick", "seed", "ok"):
        assert key in result, f"{name}: key {key!r} missing from {last}"
    assert result["name"] == name and result["quick"] is True and result["ok"] is True


@pytest.mark.slow
@pytest.mark.parametrize("name", available())
def test_full_benchmark_contract(name: str) -> None:
    """The full-size run (``pytest -m slow``): same contract, no time limit here."""
    proc = subprocess.run(
        [sys.executable, "-m", "benchmarks", name], cwd=ROOT, capture_output=True, text=True
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    result = json.loads(proc.stdout.strip().splitlines()[-1])
    assert result["name"] == name and result["quick"] is False and result["ok"] is True
