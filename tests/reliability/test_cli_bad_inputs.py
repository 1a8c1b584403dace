"""Bad files through the command line (issue 14): every input and truth format that
``dbntrack track`` / ``dbntrack eval`` reads (docs/formats.md), each damaged in the ways
of the issue -- empty, truncated, byte flips, NaN, wrong columns, time going backwards.

A deterministic damage (empty, NaN, a missing column, time backwards) must end with exit
status 2 and one line on stderr naming the file, and the line where one applies; a
random one (truncation, byte flips: hypothesis) either still parses or does the same.
Never a traceback. The deterministic cases fail while reading, before any tracking, so
they are fast; the random ones are drawn for the cheap ``eval`` formats by default and
for every format under ``-m slow``.
"""

from __future__ import annotations

import re
import shutil
import tempfile
from collections.abc import Callable
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from models.cli import main

DATA = Path(__file__).resolve().parents[1] / "data"
FAST = settings(max_examples=6, deadline=None, suppress_health_check=list(HealthCheck))
SLOW = settings(max_examples=25, deadline=None, suppress_health_check=list(HealthCheck))


class Case:
    """One file format as the CLI reads it.

    ``src``: a valid example (relative to tests/data); ``argv(tmp, path)``: the command
    line with the damaged copy at ``path``; ``numeric``: the header-less column index of
    a numeric field to put NaN in (None: no numeric field); ``header``: a CSV header line
    comes first; ``timed``: rows must come in time order (the column of the time);
    ``cheap``: a valid file runs in well under a second (random damage by default).
    """

    def __init__(self, name, src, argv, numeric=None, header=False, timed=None, cheap=False):
        self.name, self.src, self.argv = name, src, argv
        self.numeric, self.header, self.timed, self.cheap = numeric, header, timed, cheap

    def __repr__(self) -> str:
        return self.name


def _track(name: str, *before: str, after: tuple[str, ...] = ()) -> Callable:
    def argv(tmp: Path, path: Path) -> list[str]:
        ins = [str(DATA / b) if b != "{}" else str(path) for b in before]
        return ["track", name, *ins, *after, "-o", str(tmp / "out")]

    return argv


def _eval(name: str, result: str | None) -> Callable:
    def argv(tmp: Path, path: Path) -> list[str]:
        return ["eval", name, str(DATA / result) if result else str(path), str(path)]

    return argv


def _in_folder(folder: str, name: str, track_name: str) -> Callable:
    def argv(tmp: Path, path: Path) -> list[str]:
        dst = tmp / "folder"
        if not dst.exists():
            shutil.copytree(DATA / folder, dst)
        shutil.copy(path, dst / name)
        return ["track", track_name, str(dst), "-o", str(tmp / "out")]

    return argv


LOC = "localization"
GT = f"{LOC}/groundtruth.csv"
CASES = [
    Case("bif", "dbn/umbrella.bif", _track("dbn", "{}", "dbn/evidence.csv")),
    Case("dbn evidence", "dbn/evidence.csv", _track("dbn", "dbn/umbrella.bif", "{}"),
         header=True),
    Case("odometry.csv", f"{LOC}/odometry.csv", _track(LOC, "{}", f"{LOC}/measurements.csv",
         f"{LOC}/landmarks.csv", GT), numeric=1, header=True, timed=0),
    Case("measurements.csv", f"{LOC}/measurements.csv", _track(LOC, f"{LOC}/odometry.csv",
         "{}", f"{LOC}/landmarks.csv", GT), numeric=2, header=True, timed=0),
    Case("landmarks.csv", f"{LOC}/landmarks.csv", _track(LOC, f"{LOC}/odometry.csv",
         f"{LOC}/measurements.csv", "{}", GT), numeric=1, header=True),
    Case("groundtruth.csv", f"{LOC}/groundtruth.csv", _track(LOC, f"{LOC}/odometry.csv",
         f"{LOC}/measurements.csv", f"{LOC}/landmarks.csv", "{}"), numeric=1, header=True,
         timed=0),
    Case("pose truth csv", f"{LOC}/groundtruth.csv", _eval(LOC, f"{LOC}/groundtruth.csv"),
         numeric=1, header=True, timed=0, cheap=True),
    Case("mrclam odometry.dat", f"{LOC}/mrclam/Robot1_Odometry.dat",
         _in_folder(f"{LOC}/mrclam", "Robot1_Odometry.dat", LOC), numeric=1, timed=0),
    Case("mrclam measurement.dat", f"{LOC}/mrclam/Robot1_Measurement.dat",
         _in_folder(f"{LOC}/mrclam", "Robot1_Measurement.dat", LOC), numeric=2, timed=0),
    Case("mrclam barcodes.dat", f"{LOC}/mrclam/Barcodes.dat",
         _in_folder(f"{LOC}/mrclam", "Barcodes.dat", LOC), numeric=1),
    Case("mrclam groundtruth.dat", f"{LOC}/mrclam/Robot1_Groundtruth.dat",
         _eval(LOC, f"{LOC}/groundtruth.csv"), numeric=1, timed=0, cheap=True),
    # passes and events may come in any row order (the reader orders passes by quit time)
    Case("zajdel passes", "zajdel/observations.csv", _track("zajdel_adf", "{}"), numeric=6,
         header=True),
    Case("zajdel events", "zajdel/events.csv", _track("zajdel_adf", "{}"), numeric=1,
         header=True),
    Case("edges.csv", "pathrecovery/edges.csv", _track("pathrecovery", "{}",
         "pathrecovery/observations.csv"), numeric=2, header=True),
    # rows in any order (the reader sorts them by step); a negative step is refused
    Case("path observations", "pathrecovery/observations.csv", _track("pathrecovery",
         "pathrecovery/edges.csv", "{}"), numeric=3, header=True),
    Case("cameras.csv", "pathrecovery/cameras.csv", _track("pathrecovery",
         "pathrecovery/edges.csv", "pathrecovery/observations.csv", "{}"), numeric=1,
         header=True),
    Case("truth path", "pathrecovery/truth_path.csv",
         _eval("pathrecovery", "pathrecovery/truth_path.csv"), header=True, timed=0, cheap=True),
    Case("MOT boxes", "jorge/gt.txt", _track("jorge", "{}"), numeric=2),
    Case("MOT truth", "jorge/gt.txt", _eval("jorge", "jorge/gt.txt"), numeric=2, cheap=True),
    Case("CAVIAR xml", "jorge/caviar.xml", _track("jorge", "{}")),
    Case("PETS2009 xml", "jorge/pets2009.xml", _track("jorge", "{}")),
    Case("tracks3d truth", "rjmcmc3d/truth3d.txt", _eval("rjmcmc3d", "rjmcmc3d/truth3d.txt"),
         numeric=7, cheap=True),
    Case("Tsai calibration", "rjmcmc3d/view0/calibration.xml",
         _in_folder("rjmcmc3d/view0", "calibration.xml", "rjmcmc3d")),
    Case("config json", "rjmcmc3d/config.json", _track("rjmcmc3d", "rjmcmc3d/view0",
         after=("--config", "{}"))),
]  # fmt: skip


def _run(capsys, case: Case, tmp: Path, data: bytes) -> tuple[int, str, Path]:
    """Write ``data`` as the case's file, run the CLI: (exit status, stderr, the path)."""
    path = tmp / Path(case.src).name
    path.write_bytes(data)
    argv = case.argv(tmp, path)
    if "--config" in argv:  # the config file is the damaged one, after --config
        argv[argv.index("--config") + 1] = str(path)
    capsys.readouterr()
    try:
        rc = main(argv)
    except Exception as exc:  # noqa: BLE001 - the point: a traceback is a failure
        pytest.fail(f"{case.name}: {type(exc).__name__} escaped the CLI: {exc}")
    err = capsys.readouterr().err.strip()
    return rc, err, path


def _rejected(case: Case, rc: int, err: str, path: Path, line: int | None) -> None:
    assert rc == 2, f"{case.name}: exit {rc}, expected 2 (stderr: {err!r})"
    assert len(err.splitlines()) == 1, err
    assert path.name in err, f"{case.name}: error does not name the file: {err}"
    if line is not None:
        assert re.search(rf"{re.escape(path.name)}:{line}\b", err), f"no :{line}: in {err}"


def _data_lines(case: Case, lines: list[str]) -> list[int]:
    """Indices of the data rows (not blank, not comments, not the header)."""
    rows = [i for i, ln in enumerate(lines) if ln.split("#", 1)[0].strip()]
    return rows[1:] if case.header else rows


def _fields(line: str) -> tuple[list[str], str]:
    sep = "," if "," in line else None
    return line.rstrip("\n").split(sep), sep or "\t"


def _with_field(case: Case, line_index: int, column: int, value: str) -> tuple[bytes, int]:
    lines = (DATA / case.src).read_text().splitlines(keepends=True)
    fields, sep = _fields(lines[line_index])
    fields[column] = value
    lines[line_index] = sep.join(fields) + "\n"
    return "".join(lines).encode(), line_index + 1


@pytest.mark.parametrize("case", CASES, ids=repr)
def test_empty_file(capsys, tmp_path, case):
    rc, err, path = _run(capsys, case, tmp_path, b"")
    _rejected(case, rc, err, path, None)


@pytest.mark.parametrize("case", [c for c in CASES if c.numeric is not None], ids=repr)
def test_nan_field(capsys, tmp_path, case):
    lines = (DATA / case.src).read_text().splitlines(keepends=True)
    row = _data_lines(case, lines)[1]
    data, line = _with_field(case, row, case.numeric, "nan")
    rc, err, path = _run(capsys, case, tmp_path, data)
    _rejected(case, rc, err, path, line)


@pytest.mark.parametrize("case", [c for c in CASES if c.numeric is not None], ids=repr)
def test_missing_column(capsys, tmp_path, case):
    """The header loses its last column (the error: at the header, or at the first row,
    which then has more fields than the header), or, without a header, a data row loses
    its fields from the numeric one on (the error: at that row)."""
    lines = (DATA / case.src).read_text().splitlines(keepends=True)
    rows = [i for i, ln in enumerate(lines) if ln.split("#", 1)[0].strip()]
    i = rows[0] if case.header else rows[1]
    fields, sep = _fields(lines[i])
    lines[i] = sep.join(fields[:-1] if case.header else fields[: case.numeric]) + "\n"
    rc, err, path = _run(capsys, case, tmp_path, "".join(lines).encode())
    _rejected(case, rc, err, path, None)
    where = {i + 1, rows[1] + 1} if case.header else {i + 1}
    assert any(f"{path.name}:{n}:" in err for n in where), f"not at line {where}: {err}"


@pytest.mark.parametrize("case", [c for c in CASES if c.timed is not None], ids=repr)
def test_time_backwards(capsys, tmp_path, case):
    """A data row's time set before the previous row's: rejected at that row's line."""
    lines = (DATA / case.src).read_text().splitlines(keepends=True)
    rows = _data_lines(case, lines)
    times = [float(_fields(lines[i])[0][case.timed]) for i in rows]
    k = next(k for k in range(2, len(rows)) if times[k] > times[0])
    data, line = _with_field(case, rows[k], case.timed, repr(times[0] - 1.0))
    rc, err, path = _run(capsys, case, tmp_path, data)
    _rejected(case, rc, err, path, line)


def _random_damage(capsys, tmp_path, case, data) -> None:
    raw = (DATA / case.src).read_bytes()
    kind = data.draw(st.sampled_from(["truncate", "flip"]))
    if kind == "truncate":
        bad = raw[: data.draw(st.integers(1, len(raw) - 1))]
    else:
        i = data.draw(st.integers(0, len(raw) - 1))
        bad = raw[:i] + bytes([data.draw(st.integers(0, 255))]) + raw[i + 1 :]
    d = Path(tempfile.mkdtemp(dir=tmp_path))
    rc, err, path = _run(capsys, case, d, bad)
    if rc != 0:
        _rejected(case, rc, err, path, None)


@pytest.mark.parametrize("case", [c for c in CASES if c.cheap], ids=repr)
@FAST
@given(data=st.data())
def test_random_damage_cheap_formats(capsys, tmp_path, case, data):
    _random_damage(capsys, tmp_path, case, data)


@pytest.mark.slow
@pytest.mark.parametrize("case", CASES, ids=repr)
@SLOW
@given(data=st.data())
def test_random_damage_every_format(capsys, tmp_path, case, data):
    _random_damage(capsys, tmp_path, case, data)


#: formats whose rows are keyed by an id (the column): a repeated key would silently
#: shadow the other row
KEYED = {
    "landmarks.csv": (0,),
    "mrclam barcodes.dat": (1,),
    "edges.csv": (0, 1),
    "MOT boxes": (0, 1),
    "tracks3d truth": (0, 1),
}


@pytest.mark.parametrize("case", [c for c in CASES if c.name in KEYED], ids=repr)
def test_repeated_key(capsys, tmp_path, case):
    """A data row repeated with its other fields changed: rejected at the second one."""
    lines = (DATA / case.src).read_text().splitlines(keepends=True)
    row = _data_lines(case, lines)[0]
    fields, sep = _fields(lines[row])
    key = KEYED[case.name]
    other = next(i for i in range(len(fields)) if i not in key and fields[i] != "-1")
    fields[other] = "0.25" if fields[other] != "0.25" else "0.5"
    lines.append(sep.join(fields) + "\n")
    rc, err, path = _run(capsys, case, tmp_path, "".join(lines).encode())
    _rejected(case, rc, err, path, len(lines))
