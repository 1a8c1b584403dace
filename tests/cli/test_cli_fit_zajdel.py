"""``dbntrack fit zajdel_adf | zajdel_learnsearch``: the path model and appearance scales
fitted on observation files whose people are known (``models.track.zajdel_fit``), written
as a config ``dbntrack track`` runs. The files are one SIMULATED office's people split
into several files (the same building, other people)."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest

from models.cli import main
from models.io.zajdel import read_observations
from models.track.context import RunContext
from models.track.zajdel import label_passes
from models.track.zajdel_fit import fitted_config
from models.zajdel.fit import fit_passes
from models.zajdel.metrics import pairwise_prf
from models.zajdel.simulate import OfficeConfig, simulate_office
from tests.cli.test_cli_track import _bad
from tests.cli.test_cli_track import _fitted as _fit


def _office_files(tmp_path: Path, files: int = 3, people: int = 12, passes: int = 72) -> list:
    """One SIMULATED office (seed 10) whose people are dealt into ``files`` CSVs (person p
    into file p mod ``files``), pass ids from 1000, a ``person`` column."""
    cfg = OfficeConfig(num_people=people, num_obs=passes, arrival_window=300.0)
    sc = simulate_office(10, cfg)
    o = sc.obs
    head = ["pass", "t_enter", "t_quit", "camera", "border_enter", "border_quit",
            *(f"a{i}" for i in range(o.appearance.shape[1])), "person"]  # fmt: skip
    paths = []
    for f in range(files):
        path = tmp_path / f"office{f}.csv"
        with path.open("w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(head)
            for i in np.flatnonzero(sc.labels % files == f):
                w.writerow([1000 + i, o.t_enter[i], o.t_quit[i], o.camera[i], o.border_enter[i],
                            o.border_quit[i], *o.appearance[i], sc.labels[i]])  # fmt: skip
        paths.append(path)
    return paths


def _error(name: str, path: Path, config: dict) -> float:
    """1 - pairwise F1 of the tracker's labels of ``path`` with ``config`` (the API)."""
    table = read_observations(path)
    labels = label_passes(RunContext(name, path.parent / "api", 0, quiet=True), table, config,
                          str(path))[0]  # fmt: skip
    return 1.0 - pairwise_prf(labels, table.person)[2]


@pytest.mark.parametrize(("name", "own"), [("zajdel_adf", {"decode": "online"}),
                                           ("zajdel_learnsearch", {"n0": 5})])
def test_fit_writes_the_fitted_parameters_and_track_runs_them(tmp_path, capsys, name, own):
    """config.json is the API's fit of the training files' passes (one pseudo-observation
    per row, the layout of every file) over the config's keys; the summary's errors are
    those of ``dbntrack track --config`` scored by ``dbntrack eval``."""
    train, held = _office_files(tmp_path)[:2], _office_files(tmp_path)[2]
    cfg = tmp_path / "cfg.json"
    cfg.write_text(json.dumps(own))
    summary, written = _fit(tmp_path, name, "fit", *train, "--validate", held, "--config", cfg)
    sets = [(t.obs, t.person) for t in map(read_observations, train)]
    fit = fit_passes(sets, 7, 2, 1.0)._asdict()
    keys = ["trans", "entry", "travel_mean", "travel_std", "p_new"]
    keys += ["within_std", "between_std"] if name == "zajdel_adf" else []  # LS learns them
    want = {**own, "num_cameras": 7, "num_borders": 2, **{k: fit[k] for k in keys}}
    assert written == json.loads(json.dumps({k: np.asarray(v).tolist() for k, v in want.items()}))
    assert summary["prior_strength"] == 1.0 and summary["parameters"]["training_people"] == 8
    rows = {Path(r["file"]).name: r for r in summary["files"]}
    assert [r["split"] for r in rows.values()] == ["train", "train", "validation"]
    for path in [*train, held]:
        out = tmp_path / f"track_{path.stem}"
        assert main(["track", name, str(path), "-o", str(out), "--config",
                     str(tmp_path / "fit" / "config.json"), "--quiet"]) == 0  # fmt: skip
        capsys.readouterr()
        assert main(["eval", name, str(out / "labels.csv"), str(path), "--json"]) == 0
        f1 = json.loads(capsys.readouterr().out)["pairwise_f1"]
        assert rows[path.name]["error_fitted"] == pytest.approx(1.0 - f1, abs=1e-12)
        assert rows[path.name]["error_config"] == pytest.approx(_error(name, path, own))
    assert summary["metrics"]["error_validation_fitted"] == rows[held.name]["error_fitted"]


def test_cross_validation_chooses_the_strength_with_the_lowest_held_out_error(tmp_path, capsys):
    """--folds 3 over three files: each file's error_cv is that of the chosen strength's
    fit on the two others (the API), and the chosen strength has the lowest mean."""
    files = _office_files(tmp_path)
    summary, written = _fit(tmp_path, "zajdel_learnsearch", "cv", *files, "--folds", "3",
                            "--prior-strength", "0,1,30")  # fmt: skip
    cv = summary["parameters"]["cross_validation"]
    means = {r["prior_strength"]: r["error"] for r in cv["errors"]}
    assert cv["chosen"] == min(means, key=means.get) == summary["parameters"]["prior_strength"]
    tables = {p: read_observations(p) for p in files}
    for row, path in zip(summary["files"], files):
        others = [(tables[p].obs, tables[p].person) for p in files if p != path]
        config = fitted_config("zajdel_learnsearch", {}, (7, 2),
                               fit_passes(others, 7, 2, cv["chosen"]))  # fmt: skip
        assert row["error_cv"] == pytest.approx(_error("zajdel_learnsearch", path, config))
    assert "3-fold cross-validation error by prior strength" in capsys.readouterr().out


def test_fit_refusals(tmp_path, capsys):
    files = _office_files(tmp_path)
    out = str(tmp_path / "out")
    nameless = tmp_path / "nameless.csv"
    rows = files[0].read_text().splitlines()
    nameless.write_text("\n".join(r.rsplit(",", 1)[0] for r in rows) + "\n")
    _bad(capsys, ["fit", "zajdel_adf", str(nameless), "-o", out],
         "nameless.csv: no person on every pass", "person column")  # fmt: skip
    twice = tmp_path / "twice.csv"  # pass 1000's person now quits after their next enters
    head, first, *rest = rows
    cells = first.split(",")
    cells[2] = "1e6"
    twice.write_text("\n".join([head, ",".join(cells), *rest]) + "\n")
    _bad(capsys, ["fit", "zajdel_adf", str(twice), "-o", out],
         "twice.csv: person", "before pass 1000 quits at 1e+06")  # fmt: skip
    _bad(capsys, ["fit", "zajdel_adf", str(files[0]), "--validate", str(files[0]), "-o", out],
         "given twice")  # fmt: skip
    _bad(capsys, ["fit", "zajdel_adf", str(files[0]), "--seeds", "2", "-o", out],
         "--seeds 2: zajdel_adf labels its files as they are")  # fmt: skip
    _bad(capsys, ["fit", "zajdel_adf", str(files[0]), "--prior-strength", "inf", "-o", out],
         "zajdel_adf's prior is a uniform table")  # fmt: skip
    far = tmp_path / "far.csv"  # a camera id of 100000: a dense table of 4e10 entries
    cells = rows[1].split(",")
    cells[3] = "100000"  # pass,t_enter,t_quit,camera,...
    far.write_text("\n".join([rows[0], ",".join(cells), *rows[2:]]) + "\n")
    _bad(capsys, ["fit", "zajdel_adf", str(files[0]), "--validate", str(far), "-o", out],
         "far.csv: camera ids up to 100000", "dense")  # fmt: skip
    cfg = tmp_path / "cfg.json"
    cfg.write_text('{"stream_window": 5}')
    _bad(capsys, ["fit", "zajdel_adf", str(files[0]), "--config", str(cfg), "-o", out],
         "cfg.json", "stream_window")  # fmt: skip
    assert not (tmp_path / "out" / "config.json").exists()


def test_a_held_out_copy_of_a_training_file_is_named(tmp_path, capsys):
    """A held-out file holding half of a training file's passes (other ids, times shifted
    by an hour, rows in another order) is named as not held out; another day is not."""
    train, other = _office_files(tmp_path)[:2]
    head, *rows = train.read_text().splitlines()
    cut = tmp_path / "cut.csv"
    shifted = []
    for row in rows[: (len(rows) + 1) // 2][::-1]:
        cells = row.split(",")
        cells[0] = str(int(cells[0]) + 5000)
        cells[1], cells[2] = (str(float(c) + 3600.0) for c in cells[1:3])
        shifted.append(",".join(cells))
    cut.write_text("\n".join([head, *shifted]) + "\n")
    summary, _ = _fit(tmp_path, "zajdel_learnsearch", "fit", train, "--validate", cut, other)
    assert summary["parameters"]["validation_same_recording"] == {
        str(cut.resolve()): str(train.resolve())}
    out = capsys.readouterr().out
    assert "held-out files of which half the passes or more are a training file's: " \
           "cut.csv (office0.csv): their errors are not held out" in out
