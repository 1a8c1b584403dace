"""``models.track.sweep_task.track_task``: a sweep of ``dbntrack track`` runs on files."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from dbn.errors import ConfigError, FileFormatError, InputError
from models.cli import main
from models.experiments import GridPoint, load_sweep, run_grid
from models.track.sweep_task import (
    data_arguments,
    fit_arguments,
    fit_task,
    nest_params,
    track_task,
)

DATA = Path(__file__).resolve().parent.parent / "data"


def test_nest_params_sets_fields_of_objects_and_copies_values():
    shared = [1, 2]
    got = nest_params([("fps", 7), ("network.max_gap_frames", 45), ("network.radius", 20.0),
                       ("view.a.b", shared)])  # fmt: skip
    assert got == {"fps": 7, "network": {"max_gap_frames": 45, "radius": 20.0},
                   "view": {"a": {"b": [1, 2]}}}  # fmt: skip
    got["view"]["a"]["b"].append(3)
    assert shared == [1, 2]  # a grid's value is shared by its points: never changed
    assert nest_params([]) == {}
    clash = [("network", {}), ("network.radius", 1)]
    for params, needle in ((clash, "'network' is also given a value"),
                           ([("network..radius", 1)], "an empty part"),
                           ([(".fps", 1)], "an empty part")):
        with pytest.raises(ConfigError, match=needle):
            nest_params(params)


def test_data_arguments_are_a_track_command_line():
    assert data_arguments("a.xml") == (["a.xml"], None, None)
    quoted = "'my video.xml' --truth 'my video.xml'"
    assert data_arguments(quoted) == (["my video.xml"], "my video.xml", None)
    assert data_arguments("e.bif ev.csv --keep out") == (["e.bif", "ev.csv"], None, "out")
    for data, needle in (("a.xml -o out", "option '-o'"), ("a.xml --seed 3", "option '--seed'"),
                         ("a.xml --truth", "--truth needs a file"),
                         ("a.xml --keep", "--keep needs a folder"),
                         ("a.xml --truth b --truth c", "--truth given twice"),
                         ("--truth a.xml", "no input file"), ("'a.xml", "closing quotation")):
        with pytest.raises(InputError, match=needle):
            data_arguments(data)


def _run(tmp_path: Path, xml: Path, config: dict) -> dict:
    """``dbntrack track jorge`` with ``--seed 3``, ``--truth`` the box file: its metrics."""
    cfg = tmp_path / "cfg.json"
    cfg.write_text(json.dumps(config))
    out = tmp_path / "direct"
    shutil.rmtree(out, ignore_errors=True)
    assert main(["track", "jorge", str(xml), "-o", str(out), "--seed", "3", "--config", str(cfg),
                 "--truth", str(xml), "--quiet"]) == 0  # fmt: skip
    return json.loads((out / "summary.json").read_text())


def test_a_sweep_of_track_runs_equals_the_runs_themselves(tmp_path, capsys):
    """Each point is the ``dbntrack track`` run its data, seed and parameters spell; a key
    the runner does not read fails that point alone, naming the key."""
    xml = tmp_path / "my video.xml"  # a path that needs quoting
    shutil.copy(DATA / "jorge" / "caviar.xml", xml)
    sweep = tmp_path / "sweep.toml"
    sweep.write_text('task = "models.track.sweep_task:track_task"\ntrackers = ["jorge"]\n'
                     f'data = ["\'{xml}\' --truth \'{xml}\'"]\nseeds = [3]\n[params]\n'
                     '"network.max_gap_frames" = [10, 30]\ngaps_per_100 = [8]\n'
                     'gap_min = [20]\ngap_max = [30]\n')  # fmt: skip
    task, grid = load_sweep(sweep)
    assert task is track_task and len(grid) == 2
    records = run_grid(task, grid, serial=True, progress=False)
    assert [r["status"] for r in records] == ["ok", "ok"], records
    for rec in records:
        gap = rec["point"]["params"]["network.max_gap_frames"]
        want = _run(tmp_path, xml, {"gaps_per_100": 8, "gap_min": 20, "gap_max": 30,
                                    "network": {"max_gap_frames": gap}})  # fmt: skip
        assert rec["result"]["metrics"] == want["metrics"]
        assert rec["result"]["parameters"] == want["parameters"]
        assert rec["result"]["parameters"]["network"] == {"max_gap_frames": gap}
    short, default = (r["result"]["metrics"]["missed_links"]["gap"] for r in records)
    assert short > default  # the setting reached the link rule
    capsys.readouterr()
    bad = GridPoint("jorge", f"'{xml}'", 3, (("netwrk.max_gap_frames", 10),))
    (rec,) = run_grid(track_task, [bad], serial=True, progress=False)
    assert rec["status"] == "error" and "ConfigError" in rec["error"] and "netwrk" in rec["error"]
    with pytest.raises(InputError, match="seed"):
        track_task(GridPoint("jorge", f"'{xml}'", 2**32))


def test_an_unquoted_dotted_name_is_refused_naming_the_file(tmp_path):
    sweep = tmp_path / "sweep.toml"
    sweep.write_text('task = "models.track.sweep_task:track_task"\ntrackers = ["jorge"]\n'
                     'data = ["a.xml"]\n[params]\nnetwork.max_gap_frames = [10, 30]\n')  # fmt: skip
    with pytest.raises(FileFormatError, match=r"sweep.toml.*'network' is a table.*quoted"):
        load_sweep(sweep)


def test_the_example_sweep_runs_from_the_repository_root(monkeypatch):
    monkeypatch.chdir(DATA.parent.parent)
    task, grid = load_sweep(DATA / "sweep_files.toml")
    assert task is track_task and len(grid) == 4
    (rec,) = run_grid(task, grid[:1], serial=True, progress=False)
    assert rec["status"] == "ok", rec["error"]
    gap = rec["point"]["params"]["network.max_gap_frames"]
    assert rec["result"]["parameters"]["network"] == {"max_gap_frames": gap}
    assert 0.0 <= rec["result"]["metrics"]["error_rate"] <= 1.0


def test_keep_writes_each_points_outputs_under_its_id(tmp_path):
    xml = DATA / "jorge" / "caviar.xml"
    point = GridPoint("jorge", f"'{xml}' --keep '{tmp_path / 'runs'}'", 3)
    got = track_task(point)
    out = tmp_path / "runs" / point.id
    assert got["outdir"] == str(out.resolve()) and "metrics" not in got
    assert sorted(got["outputs"]) == sorted(p.name for p in out.iterdir() if p.name != "summary.json")
    assert json.loads((out / "summary.json").read_text())["parameters"] == got["parameters"]


def test_fit_arguments_are_a_fit_command_line():
    got = fit_arguments("'my a.jsonl' b.xml --validate c.jsonl --seeds 2 --keep k "
                        "--prior-strength 50")  # fmt: skip
    assert got == (["my a.jsonl", "b.xml"], ["c.jsonl"], 2, (50.0,), 0, None, "k")
    assert fit_arguments("a.jsonl") == (["a.jsonl"], [], 1, (0.0,), 0, None, None)
    got = fit_arguments(r"a b c --prior-strength 0,30,1e3,inf --folds 3 --fold-by '(\w)_\d'")
    assert (got.prior_strength, got.folds) == ((0.0, 30.0, 1000.0, float("inf")), 3)
    assert got.fold_by == r"(\w)_\d"
    for data, needle in (("a --seed 3", "option '--seed'"), ("a --seed=3", "option '--seed=3'"),
                         ("a -o out", "option '-o'"), ("--validate c", "required: train"),
                         ("a --seeds x", "invalid int value: 'x'"), ("a --seeds 0", "at least 1"),
                         ("a --val c", "unrecognized arguments: --val"),
                         ("a --validate", "expected at least one"), ("'a", "closing quotation"),
                         ("a --prior-strength -1", "-1 is not a number >= 0"),
                         ("a --prior-strength nan", "nan is not a number >= 0"),
                         ("a --prior-strength 1,x", "not a number: 'x'"),
                         ("a --folds 1", "at least 2"), ("a --folds -2", "at least 2"),
                         ("a --folds two", "invalid int value: 'two'")):
        with pytest.raises(InputError, match=needle):
            fit_arguments(data)


def test_a_sweep_of_fits_equals_the_fits_themselves(tmp_path):
    """Each point is the ``dbntrack fit`` its data, seed and parameters spell."""
    xml = DATA / "jorge" / "caviar.xml"
    held = tmp_path / "held.jsonl"
    shutil.copy(DATA / "jorge" / "regions.jsonl", held)
    grid = [GridPoint("jorge", f"'{xml}' --validate '{held}' --seeds 2 --keep '{tmp_path}/k'",
                      5, (("labels.max_group_size", g),)) for g in (3, 5)]
    records = run_grid(fit_task, grid, serial=True, progress=False)
    assert [r["status"] for r in records] == ["ok", "ok"], records
    for rec, point, g in zip(records, grid, (3, 5)):
        cfg = tmp_path / "cfg.json"
        cfg.write_text(json.dumps({"labels": {"max_group_size": g}}))
        out = tmp_path / f"direct{g}"
        assert main(["fit", "jorge", str(xml), "--validate", str(held), "--seeds", "2",
                     "--seed", "5", "--config", str(cfg), "-o", str(out), "--quiet"]) == 0
        want = json.loads((out / "summary.json").read_text())
        for key in ("metrics", "files", "parameters"):
            assert rec["result"][key] == want[key], key
        kept = json.loads((Path(rec["result"]["outdir"]) / "config.json").read_text())
        assert Path(rec["result"]["outdir"]) == (tmp_path / "k" / point.id).resolve()
        assert kept == json.loads((out / "config.json").read_text())
        assert kept["labels"]["max_group_size"] == g
