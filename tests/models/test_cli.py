"""The ``dbntrack`` command line."""

from __future__ import annotations

import subprocess
import sys

import pytest

from models import cli


def test_help_lists_demo(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exc:
        cli.main(["--help"])
    assert exc.value.code == 0
    assert "demo" in capsys.readouterr().out


def test_unknown_command_fails() -> None:
    with pytest.raises(SystemExit) as exc:
        cli.main(["nonsense"])
    assert exc.value.code != 0


def test_demo_primer_prints_results() -> None:
    proc = subprocess.run(
        [sys.executable, "-m", "models.cli", "demo", "--only", "primer"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "DBN primer" in proc.stdout
    assert "pgmpy forward_inference at slice 19 agrees" in proc.stdout


def test_every_demo_part_names_a_run_demo() -> None:
    import importlib

    for _, module_name in cli.DEMO_PARTS:
        if cli._module_exists(module_name):
            assert callable(getattr(importlib.import_module(module_name), "run_demo", None)), module_name


def test_demo_rejects_unknown_names_listing_valid_ones(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exc:
        cli.main(["demo", "--only", "primer", "kalman"])
    assert exc.value.code != 0
    err = capsys.readouterr().err
    assert "kalman" in err and "valid: primer, zajdel_adf" in err and "rjmcmc3d" in err


def test_demo_parts_follow_the_registry(capsys: pytest.CaptureFixture[str]) -> None:
    import models

    names = [name for name, _, _ in cli.demo_parts()]
    assert names == ["primer", *models.available()]
    assert cli.main(["list"]) == 0
    out = capsys.readouterr().out
    for name in models.available():
        assert name in out
