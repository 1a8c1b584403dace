"""One number of a valid example file set to +-1e200 (a unit mistake, or a corrupted
export) is refused with exit status 2 and one line naming the file and its line.

A probe of every numeric column of the example files found readers that took such a
value: runs that ended with rc 0 on absurd results (a robot at 4e198 m, a pathrecovery
gap wrapped to one step), numpy tracebacks ("Singular matrix", "Maximum allowed size
exceeded"), a 12.9 GiB allocation, or NaN priors naming no file. Columns a tracker does
not read, or only plots, are listed in ``UNREAD`` with the reason.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from models.cli import main
from tests.cells import columns, data_line, set_cell

DATA = Path(__file__).resolve().parents[1] / "data"
LOC = ("localization/odometry.csv", "localization/measurements.csv",
       "localization/landmarks.csv", "localization/groundtruth.csv")  # fmt: skip
PATH = ("pathrecovery/edges.csv", "pathrecovery/observations.csv", "pathrecovery/cameras.csv")
CASES = {  # (command, tracker, inputs; the file whose number is set is one of them)
    "zajdel observations": ("track", "zajdel_adf", ("zajdel/observations.csv",)),
    "zajdel events": ("track", "zajdel_learnsearch", ("zajdel/events.csv",)),
    "localization": ("track", "localization", LOC),
    "pathrecovery": ("track", "pathrecovery", PATH),
    "MOT boxes": ("track", "jorge", ("jorge/gt.txt",)),
    "3-D truth": ("eval", "rjmcmc3d", ("rjmcmc3d/truth3d.txt", "rjmcmc3d/truth3d.txt")),
}
UNREAD = {  # (file, column) -> why a huge value there is not refused
    ("pathrecovery/cameras.csv", "x"): "camera positions only place the figure's nodes",
    ("pathrecovery/cameras.csv", "y"): "camera positions only place the figure's nodes",
    ("jorge/gt.txt", 6): "conf: a detector's score (0 = not a person), any size",
    ("jorge/gt.txt", 7): "class: read only from a MOT16/17/20 truth being scored",
    ("jorge/gt.txt", 8): "visibility: not read",
    **{("rjmcmc3d/truth3d.txt", c): "not read (-1 fields, conf, z)" for c in (2, 3, 4, 5, 6, 9)},
}


def _cells() -> list:
    out = []
    for case, (_, _, inputs) in CASES.items():
        for rel in dict.fromkeys(inputs):
            out += [pytest.param(case, rel, c, id=f"{case}-{Path(rel).name}-{c}")
                    for c in columns(DATA / rel) if (rel, c) not in UNREAD]  # fmt: skip
    return out


@pytest.mark.parametrize(("case", "rel", "column"), _cells())
def test_a_huge_number_in_any_read_column_is_refused_at_its_line(capsys, tmp_path, case, rel,
                                                                 column) -> None:
    command, tracker, inputs = CASES[case]
    for src in dict.fromkeys(inputs):
        (tmp_path / src).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(DATA / src, tmp_path / src)
    path, line = tmp_path / rel, data_line(tmp_path / rel)
    line += rel == "zajdel/events.csv"  # the first pass's leave row (enter: no appearance)
    for value in ("1e200", "-1e200"):
        set_cell(path, line, column, value)
        argv = [command, tracker, *(str(tmp_path / p) for p in inputs)]
        argv += ["-o", str(tmp_path / "out"), "--quiet"] if command == "track" else []
        rc = main(argv)
        err = capsys.readouterr().err.strip()
        assert rc == 2 and len(err.splitlines()) == 1, (value, err)
        assert str(path) in err and "Traceback" not in err, (value, err)
