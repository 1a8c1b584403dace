"""Observation values the Zajdel trackers cannot use are refused by the reader, naming the
file, the line and the column: an appearance of 1e200 reached the ADF's data-driven prior
(``dbntrack track zajdel_adf`` said "prior.kappa = nan" after a RuntimeWarning), a time of
-1e300 ran both trackers to rc 0 on overflowing travel times."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from dbn.errors import FileFormatError, InputError
from models.cli import main
from models.io.zajdel import read_observations
from models.zajdel.data import MAX_APPEARANCE, MAX_TIME, validate_observations
from tests.cells import set_cell

DATA = Path(__file__).resolve().parents[1] / "data" / "zajdel"


def _with(tmp_path: Path, name: str, line: int, column: str, value: str) -> Path:
    """A copy of ``DATA/name`` with ``column`` of 1-based ``line`` set to ``value``."""
    return set_cell(DATA / name, line, column, value, out=tmp_path / name)


_CASES = [  # (file, line, column, value, needle)
    ("observations.csv", 6, "a3", "1e200", "a3 = 1e+200: |appearance| must be <= 1e+06"),
    ("observations.csv", 6, "a0", "-2e6", "a0 = -2e+06: |appearance| must be <= 1e+06"),
    ("observations.csv", 6, "t_enter", "-1e300", "t_enter = -1e+300: |time| must be <= 1e+100"),
    ("observations.csv", 6, "t_quit", "1e101", "t_quit = 1e+101: |time|"),
    ("events.csv", 3, "a8", "-1e308", "a8 = -1e+308: |appearance|"),
    ("events.csv", 4, "time", "-1e300", "time = -1e+300: |time|"),
]


@pytest.mark.parametrize(("name", "line", "column", "value", "needle"), _CASES)
def test_the_reader_names_file_line_and_column(tmp_path, name, line, column, value, needle) -> None:
    path = _with(tmp_path, name, line, column, value)
    with pytest.raises(FileFormatError) as exc:
        read_observations(path)
    assert f"{path}:{line}: {needle}" in str(exc.value)


def test_the_bounds_themselves_are_read() -> None:
    """Values at the bounds are data, not mistakes (the reader and the trackers agree)."""
    table = read_observations(DATA / "observations.csv")
    obs = table.obs
    app = obs.appearance.copy()
    app[0, 0], app[1, 1] = MAX_APPEARANCE, -MAX_APPEARANCE
    te, tq = obs.t_enter - MAX_TIME, obs.t_quit.copy()
    tq[-1] = MAX_TIME
    big = obs._replace(appearance=app, t_enter=te, t_quit=tq)
    ncam = int(obs.camera.max()) + 1
    nb = int(max(obs.border_enter.max(), obs.border_quit.max())) + 1
    validate_observations(big, app.shape[1], ncam, nb)
    with pytest.raises(InputError, match=r"t_quit\[.*\] = 1e\+101: \|time\| must be <= 1e\+100"):
        validate_observations(big._replace(t_quit=np.where(tq == MAX_TIME, 1e101, tq)),
                              app.shape[1], ncam, nb)  # fmt: skip


@pytest.mark.parametrize("tracker", ["zajdel_adf", "zajdel_learnsearch"])
def test_dbntrack_track_says_it_in_one_line(capsys, tmp_path, tracker) -> None:
    path = _with(tmp_path, "observations.csv", 6, "a3", "1e200")
    rc = main(["track", tracker, str(path), "-o", str(tmp_path / "out"), "--quiet"])
    err = capsys.readouterr().err.strip()
    assert rc == 2 and len(err.splitlines()) == 1, err
    assert f"{path}:6: a3 = 1e+200" in err and "nan" not in err, err


def test_an_event_row_with_part_of_an_appearance_is_refused(tmp_path) -> None:
    """An enter row with a0 given and a1..a8 empty was read as a row without appearance:
    its a0 was dropped without a word."""
    path = _with(tmp_path, "events.csv", 2, "a0", "0.5")
    with pytest.raises(FileFormatError) as exc:
        read_observations(path)
    assert f"{path}:2: appearance columns ['a1'," in str(exc.value)
    assert "are empty where ['a0'] are not" in str(exc.value)
