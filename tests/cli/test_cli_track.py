"""End-to-end ``dbntrack`` tests on the shipped example files (tests/data): every runner
``track`` then ``eval``, the outputs parse back, bad input exits 2 with one line."""

from __future__ import annotations

import dataclasses
import json
import math
import shutil
import warnings
from pathlib import Path

import numpy as np
import pytest

from models.cli import main
from tests.cells import data_line, set_cell

DATA = Path(__file__).resolve().parent.parent / "data"


def _track(tmp_path: Path, name: str, inputs: list[Path], *extra: str) -> Path:
    out = tmp_path / name
    assert main(["track", name, *map(str, inputs), "-o", str(out), "--seed", "3", *extra]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["tracker"] == name and summary["seed"] == 3
    assert summary["versions"]["numpy"] == np.__version__
    assert list(out.glob("*.png")), "no figure written"
    for f in summary["outputs"]:
        assert (out / f).is_file()
    return out


def _bad(capsys, argv: list[str], *needles: str) -> None:
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    for n in needles:
        assert n in err, err


def _fitted(tmp_path: Path, name: str, out: str, *argv) -> tuple[dict, dict]:
    """``dbntrack fit NAME ARGV -o tmp/OUT``: (summary, config.json), ``fit.png`` written."""
    assert main(["fit", name, *map(str, argv), "-o", str(tmp_path / out), "--quiet"]) == 0
    assert (tmp_path / out / "fit.png").is_file()
    return (json.loads((tmp_path / out / "summary.json").read_text()),
            json.loads((tmp_path / out / "config.json").read_text()))


def test_list_names_every_runner(capsys):
    assert main(["list", "--json"]) == 0
    rows = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert {"dbn", "localization"} <= {r["name"] for r in rows}
    with_fit = ["zajdel_adf", "zajdel_learnsearch", "jorge", "localization",
                "pathrecovery"]  # dbntrack fit
    assert [r["name"] for r in rows if r["fit"]] == with_fit
    assert main(["list"]) == 0
    assert "dbntrack fit: yes" in capsys.readouterr().out.split("\njorge\n")[1]


def test_unknown_tracker_and_demo_part_exit_2(capsys, tmp_path):
    _bad(capsys, ["track", "nosuch", "x", "-o", str(tmp_path)], "nosuch", "localization")
    with pytest.raises(SystemExit) as exc:
        main(["demo", "--only", "nosuch"])
    assert exc.value.code == 2
    assert "nosuch" in capsys.readouterr().err


def test_dbn_track_eval_matches_forward_algorithm(tmp_path, capsys):
    d = DATA / "dbn"
    out = _track(tmp_path, "dbn", [d / "umbrella.bif", d / "evidence.csv"],
                 "--truth", str(d / "truth.csv"))  # fmt: skip
    from models.io.dbn import read_marginals

    states, rain = read_marginals(out / "marginals.csv")["Rain"]
    # oracle: the forward algorithm by hand on the umbrella HMM (slice 3 unobserved)
    T, O = np.array([[0.7, 0.3], [0.3, 0.7]]), np.array([[0.9, 0.1], [0.2, 0.8]])
    a, ref = np.array([0.5, 0.5]), []
    for t, u in enumerate([0, 0, 1, None, 0]):
        a = a if t == 0 else a @ T
        a = a * (O[:, u] if u is not None else 1.0)
        a = a / a.sum()
        ref.append(a)
    assert states == ["yes", "no"]
    np.testing.assert_allclose(rain, np.array(ref), atol=1e-12)
    summary = json.loads((out / "summary.json").read_text())
    capsys.readouterr()
    assert main(["eval", "dbn", str(out / "marginals.csv"), str(d / "truth.csv"), "--json"]) == 0
    metrics = json.loads(capsys.readouterr().out)
    assert metrics == summary["metrics"]
    truth = np.array([0, 0, 1, 1, 0])
    assert metrics["label_error_rate"] == pytest.approx(np.mean(np.argmax(ref, 1) != truth))
    # a truth longer than the run is another recording's: refused at its first extra line
    long_truth = tmp_path / "long.csv"
    long_truth.write_text((d / "truth.csv").read_text() + "no\n")
    _bad(capsys, ["eval", "dbn", str(out / "marginals.csv"), str(long_truth)], "long.csv:7:", "6 slices")


def test_dbn_fully_observed_gives_the_log_likelihood_and_no_heat_map(tmp_path, capsys):
    """Every variable observed at every slice: nothing to plot (matplotlib raised on zero
    rows, a traceback), the log-likelihood by hand, an empty marginals file eval refuses."""
    ev = tmp_path / "full.csv"
    ev.write_text("Rain,Umbrella\nyes,yes\nno,no\n")
    out = tmp_path / "out"
    assert main(["track", "dbn", str(DATA / "dbn" / "umbrella.bif"), str(ev), "-o", str(out),
                 "--quiet"]) == 0  # fmt: skip
    summary = json.loads((out / "summary.json").read_text())
    # P(R0 = yes) P(U0 = yes | yes) * P(R1 = no | yes) P(U1 = no | no) = 0.5 0.9 * 0.3 0.8
    assert summary["log_likelihood"] == pytest.approx(math.log(0.45 * 0.24), abs=1e-12)
    assert summary["outputs"] == ["marginals.csv"] and not list(out.glob("*.png"))
    truth = tmp_path / "truth.csv"
    truth.write_text("Rain\nyes\nno\n")
    _bad(capsys, ["eval", "dbn", str(out / "marginals.csv"), str(truth)], "no marginals to score")


def test_dbn_bad_evidence_names_file_and_line(tmp_path, capsys):
    d = DATA / "dbn"
    _bad(capsys, ["track", "dbn", str(d / "umbrella.bif"), str(d / "bad_evidence.csv"),
                  "-o", str(tmp_path)], "bad_evidence.csv:3:", "maybe")  # fmt: skip
    bif = tmp_path / "broken.bif"
    bif.write_text("variable Rain_0 { type discrete [ 2 ] { yes, no }; }\n")
    _bad(capsys, ["track", "dbn", str(bif), str(d / "evidence.csv"), "-o", str(tmp_path)],
         "broken.bif")  # fmt: skip


def test_localization_track_eval(tmp_path, capsys):
    d = DATA / "localization"
    cfg = tmp_path / "cfg.json"
    cfg.write_text(json.dumps({"num_particles": 200, "duration": 3.0}))
    out = _track(tmp_path, "localization", [d / "mrclam"], "--config", str(cfg),
                 "--truth", str(d / "groundtruth.csv"))  # fmt: skip
    from models.io.localization import read_poses

    t, poses = read_poses(out / "poses.csv")
    assert poses.shape == (30, 3) and np.all(np.diff(t) > 0)
    capsys.readouterr()
    assert main(["eval", "localization", str(out / "poses.csv"), str(d / "mrclam"), "--json"]) == 0
    metrics = json.loads(capsys.readouterr().out)
    summary = json.loads((out / "summary.json").read_text())
    assert metrics["rmse_m"] == pytest.approx(summary["metrics"]["rmse_m"], abs=1e-3)
    assert metrics["rmse_m"] < 0.2  # odometry noise alone drifts; landmarks every 0.2 s


def test_localization_start_without_duration_ends_with_the_odometry(tmp_path):
    """``start`` alone runs to the odometry's end (it ran as far past it as the start was
    late, the robot held still on no data)."""
    d = DATA / "localization"
    cfg = tmp_path / "cfg.json"
    cfg.write_text(json.dumps({"num_particles": 50, "start": 104.0}))
    out = _track(tmp_path, "localization", [d / "mrclam"], "--config", str(cfg))
    from models.io.localization import read_dat, read_poses

    t, _ = read_poses(out / "poses.csv")
    end = read_dat(d / "mrclam" / "Robot1_Odometry.dat", 3)[-1, 0]
    assert t[0] == pytest.approx(104.1) and end - 0.1 < t[-1] <= end


def test_localization_noise_keys_reach_the_model(tmp_path, monkeypatch):
    """The config's noise keys are the model's (the MRCLAM defaults where absent), and
    ``summary.json`` records the noise the run used."""
    import models.localization.mrclam as mrclam

    seen = []
    real = mrclam.mrclam_model
    monkeypatch.setattr(mrclam, "mrclam_model", lambda seq, s=None: seen.append(real(seq, s))
                        or seen[-1])  # fmt: skip
    d = DATA / "localization"
    noise = {"motion": [0.03, 0.2, 0.04, 0.3], "sigma_range": 0.25, "sigma_bearing": 0.07,
             "outlier_prob": 0.1, "initial_std": [0.1, 0.2, 0.3], "range_bias": 0.02,
             "max_range": 7.0}  # fmt: skip
    for i, extra in enumerate(({}, noise)):
        cfg = tmp_path / f"cfg{i}.json"
        cfg.write_text(json.dumps({"num_particles": 50, "duration": 1.0, **extra}))
        out = _track(tmp_path / str(i), "localization", [d / "mrclam"], "--config", str(cfg))
        used = json.loads((out / "summary.json").read_text())["parameters"]["noise"]
        m = seen[-1]
        got = {"motion": list(m.noise), "sigma_range": m.sigma_range,
               "sigma_bearing": m.sigma_bearing, "outlier_prob": m.outlier_prob,
               "initial_std": list(m.initial_std), "range_bias": m.range_bias,
               "max_range": m.max_range}  # fmt: skip
        want = noise if extra else {**mrclam.MRCLAM_NOISE, "range_bias": 0.0, "max_range": 10.0}
        assert set(got) == set(want) == set(used)
        for k, v in want.items():  # lists inside: approx compares flat mappings only
            np.testing.assert_allclose(got[k], v, rtol=1e-12, err_msg=k)
            np.testing.assert_allclose(used[k], v, rtol=1e-12, err_msg=k)


def test_localization_csv_layout_equals_mrclam_folder():
    from models.io.localization import read_generic, read_mrclam_folder

    d = DATA / "localization"
    a = read_mrclam_folder(d / "mrclam", robot=1)
    b = read_generic(*(d / f"{n}.csv" for n in ("odometry", "measurements", "landmarks",
                                                 "groundtruth")))  # fmt: skip
    for name in ("odometry", "measurements", "groundtruth", "landmarks", "landmark_subjects"):
        np.testing.assert_allclose(getattr(a, name), getattr(b, name), err_msg=name)
    ids = a.landmark_subjects
    assert [a.barcode_to_subject[i] for i in ids] == [b.barcode_to_subject[i] for i in ids]


def test_localization_bad_file(tmp_path, capsys):
    d = DATA / "localization"
    argv = ["track", "localization", str(d / "bad_odometry.csv"), str(d / "measurements.csv"),
            str(d / "landmarks.csv"), "-o", str(tmp_path)]  # fmt: skip
    _bad(capsys, argv, "bad_odometry.csv:3:", "oops")


@pytest.mark.parametrize(("column", "value", "needle"), [
    ("bearing", lambda b: b * 180 / math.pi, "beyond one turn: bearings are radians"),
    ("range", lambda r: -r, "is negative"),
])
def test_localization_refuses_degrees_and_negative_ranges(tmp_path, capsys, column, value,
                                                            needle):
    """Bearings in degrees and negative ranges were taken, in both layouts."""
    d = DATA / "localization"
    lines = (d / "measurements.csv").read_text().splitlines()
    col = lines[0].split(",").index(column)
    rows = [r.split(",") for r in lines[1:]]
    for r in rows:
        r[col] = f"{value(float(r[col])):.6g}"
    meas = tmp_path / "measurements.csv"
    meas.write_text("\n".join([lines[0], *(",".join(r) for r in rows)]) + "\n")
    argv = ["track", "localization", str(d / "odometry.csv"), str(meas),
            str(d / "landmarks.csv"), "-o", str(tmp_path / "out")]  # fmt: skip
    _bad(capsys, argv, "measurements.csv:2:", needle)
    folder = tmp_path / "mrclam"
    shutil.copytree(d / "mrclam", folder)
    dat = folder / "Robot1_Measurement.dat"  # time barcode range bearing
    out, i = [], 2 if column == "range" else 3
    for ln in dat.read_text().splitlines():
        f = ln.split()
        if f and not ln.startswith("#"):
            f[i] = f"{value(float(f[i])):.6g}"
            ln = " ".join(f)
        out.append(ln)
    dat.write_text("\n".join(out) + "\n")
    argv = ["track", "localization", str(folder), "-o", str(tmp_path / "out2")]
    _bad(capsys, argv, "Robot1_Measurement.dat:", needle)


def _set_first_row(path: Path, column: int | str, value: str) -> int:
    """Set ``column`` of the first data row of ``path`` to ``value``; its 1-based line."""
    set_cell(path, line := data_line(path), column, value)
    return line


@pytest.mark.parametrize(("csv", "column", "dat", "unit"), [
    ("odometry", "v", ("Robot1_Odometry", 1), "m/s"),
    ("odometry", "w", ("Robot1_Odometry", 2), "rad/s"),
    ("measurements", "range", ("Robot1_Measurement", 2), "m"),
    ("landmarks", "y", ("Landmark_Groundtruth", 2), "m"),
    ("groundtruth", "theta", ("Robot1_Groundtruth", 3), "rad"),
])
def test_localization_refuses_values_beyond_ten_thousand_km(tmp_path, capsys, csv, column, dat,
                                                             unit):
    """A velocity of 1e200 sent the robot to 4e198 m with rc 0 (a position or heading of
    1e200 likewise): beyond :data:`models.io.localization.MAX_MAGNITUDE` (1e7) a value is
    refused at its line in both layouts; at it, it is read."""
    from models.io.localization import MAX_MAGNITUDE, read_generic

    d = DATA / "localization"
    names = ("odometry", "measurements", "landmarks", "groundtruth")
    for value, ok in ((f"{MAX_MAGNITUDE:g}", True), ("-1e200", False)):
        folder = tmp_path / value
        shutil.copytree(d, folder)
        path = folder / f"{csv}.csv"
        line = _set_first_row(path, column, value)
        if ok:
            read_generic(*(folder / f"{n}.csv" for n in names))
            continue
        argv = ["track", "localization", *(str(folder / f"{n}.csv") for n in names),
                "-o", str(folder / "out")]  # fmt: skip
        _bad(capsys, argv, f"{csv}.csv:{line}: {column} = -1e+200 {unit} is beyond 1e+07 {unit}")
        line = _set_first_row(folder / "mrclam" / f"{dat[0]}.dat", dat[1], value)
        argv = ["track", "localization", str(folder / "mrclam"), "-o", str(folder / "out2")]
        _bad(capsys, argv, f"{dat[0]}.dat:{line}: {column} = -1e+200 {unit}")


def test_localization_eval_refuses_a_pose_beyond_ten_thousand_km(tmp_path, capsys):
    """A pose of 1e200 m in the truth or the result made ``dbntrack eval`` print
    ``rmse_m: None`` (its square overflowed) with rc 0."""
    gt = DATA / "localization" / "groundtruth.csv"
    for name in ("truth.csv", "result.csv"):
        bad = tmp_path / name
        shutil.copy(gt, bad)
        line = _set_first_row(bad, 1, "1e200")
        pair = (bad, gt) if name == "result.csv" else (gt, bad)
        _bad(capsys, ["eval", "localization", *map(str, pair)],
             f"{name}:{line}: x = 1e+200 m is beyond 1e+07 m")  # fmt: skip


def test_localization_refuses_a_measurement_read_twice(tmp_path, capsys):
    """A repeated measurement row (one landmark, one time) counted its evidence twice; it
    is refused at its line in both layouts (a second landmark at that time is not)."""
    d = DATA / "localization"
    lines = (d / "measurements.csv").read_text().splitlines()
    meas = tmp_path / "measurements.csv"
    meas.write_text("\n".join([*lines[:6], lines[5], *lines[6:]]) + "\n")
    argv = ["track", "localization", str(d / "odometry.csv"), str(meas),
            str(d / "landmarks.csv"), "-o", str(tmp_path / "out")]  # fmt: skip
    t, lm = lines[5].split(",")[:2]
    _bad(capsys, argv, "measurements.csv:7:", f"measurement of id {lm} at t = {float(t):g}",
         "the first at line 6")  # fmt: skip
    folder = tmp_path / "mrclam"
    shutil.copytree(d / "mrclam", folder)
    dat = folder / "Robot1_Measurement.dat"
    rows = dat.read_text().splitlines()
    dat.write_text("\n".join([*rows, rows[-1]]) + "\n")
    argv = ["track", "localization", str(folder), "-o", str(tmp_path / "out2")]
    _bad(capsys, argv, f"Robot1_Measurement.dat:{len(rows) + 1}:", "a second measurement")


@pytest.mark.parametrize("name", ["zajdel_adf", "zajdel_learnsearch"])
def test_zajdel_track_eval(tmp_path, capsys, name):
    d = DATA / "zajdel"
    cfg = tmp_path / "cfg.json"  # small ADF tables (short compile), a narrower beam
    small = {"max_open": 8, "persons_per_slot": 4, "init_persons": 16, "chunk": 4, "mix_top": 8}
    cfg.write_text(json.dumps(small if name == "zajdel_adf" else {"num_hypotheses": 5}))
    out = _track(tmp_path, name, [d / "observations.csv"], "--config", str(cfg),
                 "--truth", str(d / "observations.csv"))  # fmt: skip
    from models.io.zajdel import read_labels, read_observations
    from models.zajdel.metrics import pairwise_prf

    labels = read_labels(out / "labels.csv")
    table = read_observations(d / "observations.csv")
    assert sorted(labels) == sorted(table.ids.tolist())
    capsys.readouterr()
    assert main(["eval", name, str(out / "labels.csv"), str(d / "observations.csv"), "--json"]) == 0
    metrics = json.loads(capsys.readouterr().out)
    assert metrics == json.loads((out / "summary.json").read_text())["metrics"]
    pred = np.array([labels[i] for i in table.ids])
    assert metrics["pairwise_f1"] == pytest.approx(pairwise_prf(pred, table.person)[2])
    partition = (out / "partition.csv").read_text().splitlines()[1:]
    assert sum(int(row.split(",")[1]) for row in partition) == len(labels)


def test_zajdel_learnsearch_streaming_window(tmp_path, capsys):
    """``stream_window``: one step per pass of the fixed-lag search; equal to the batch
    stream search on the same passes and starting point (no learning: no final EM)."""
    from models.io.zajdel import read_labels, read_observations
    from models.track.zajdel import _path_and_start
    from models.zajdel.learnsearch import LearnSearchConfig
    from models.zajdel.learnsearch_stream import stream_learn_search

    d = DATA / "zajdel"
    conf = {"num_hypotheses": 5, "learn": False, "stream_window": 6, "close_z": 3.0}
    cfg = tmp_path / "cfg.json"
    cfg.write_text(json.dumps(conf))
    out = _track(tmp_path, "zajdel_learnsearch", [d / "observations.csv"], "--config", str(cfg))
    summary = json.loads((out / "summary.json").read_text())
    assert summary["parameters"]["stream_window"] == 6
    table = read_observations(d / "observations.csv")
    labels = read_labels(out / "labels.csv")
    ref = stream_learn_search(table.obs, _path_and_start(table, conf, str(d / "observations.csv")),
                              LearnSearchConfig(num_hypotheses=5, learn=False), 6, 3.0)  # fmt: skip
    np.testing.assert_array_equal([labels[i] for i in table.ids], ref.labels)
    cfg.write_text(json.dumps({**conf, "stream_window": 0}))
    argv = ["track", "zajdel_learnsearch", str(d / "observations.csv"), "-o", str(tmp_path / "x"),
            "--config", str(cfg)]  # fmt: skip
    _bad(capsys, argv, "window")


def test_zajdel_events_layout_equals_passes(tmp_path):
    from models.io.zajdel import read_observations

    a = read_observations(DATA / "zajdel" / "observations.csv")
    b = read_observations(DATA / "zajdel" / "events.csv")
    np.testing.assert_array_equal(a.ids, b.ids)
    for x, y in zip(a.obs, b.obs):
        np.testing.assert_allclose(x, y)


def test_zajdel_rows_in_any_order_label_the_same_passes(tmp_path, capsys):
    """Rows not in quit-time order (shuffled; an events file lists its passes in order of
    entry): the passes are read in quit-time order with their own ids and people, so
    labels.csv gives each pass id the same label and eval the same metrics. The reader
    took the ids in the file's order and the passes in quit-time order: the shuffled copy of
    the example got other passes' labels (pairwise F1 0.33 against 1.0)."""
    from models.io.zajdel import read_labels, read_observations

    rows = (DATA / "zajdel" / "observations.csv").read_text().splitlines()
    head, body = rows[:2], rows[2:]
    shuffled = tmp_path / "shuffled.csv"
    shuffled.write_text("\n".join(head + [body[i] for i in np.random.default_rng(0).permutation(
        len(body))]) + "\n")  # fmt: skip
    a, b = read_observations(DATA / "zajdel" / "observations.csv"), read_observations(shuffled)
    for x, y in zip([a.ids, a.person, *a.obs], [b.ids, b.person, *b.obs]):
        np.testing.assert_array_equal(x, y)
    results = []
    for path in (DATA / "zajdel" / "observations.csv", shuffled):
        out = _track(tmp_path, "zajdel_learnsearch", [path], "--config", str(_beam(tmp_path)))
        capsys.readouterr()
        assert main(["eval", "zajdel_learnsearch", str(out / "labels.csv"), str(path),
                     "--json"]) == 0  # fmt: skip
        results.append((read_labels(out / "labels.csv"), json.loads(capsys.readouterr().out)))
    assert results[0] == results[1] and results[0][1]["pairwise_f1"] == 1.0


def _beam(tmp_path: Path) -> Path:
    """A config of a narrower learn-search beam (faster)."""
    cfg = tmp_path / "beam.json"
    cfg.write_text('{"num_hypotheses": 5}')
    return cfg


def test_zajdel_bad_file(tmp_path, capsys):
    argv = ["track", "zajdel_adf", str(DATA / "zajdel" / "bad_observations.csv"), "-o",
            str(tmp_path)]  # fmt: skip
    _bad(capsys, argv, "bad_observations.csv:2:", "t_quit")


def test_pathrecovery_track_eval(tmp_path, capsys):
    d = DATA / "pathrecovery"
    out = _track(tmp_path, "pathrecovery", [d / "edges.csv", d / "observations.csv",
                 d / "cameras.csv"], "--truth", str(d / "truth_path.csv"))  # fmt: skip
    from models.io.pathrecovery import read_path

    path, truth = read_path(out / "path.csv"), read_path(d / "truth_path.csv")
    assert sorted(path) == sorted(t for t in truth if t >= 1)
    capsys.readouterr()
    argv = ["eval", "pathrecovery", str(out / "path.csv"), str(d / "truth_path.csv"), "--json"]
    assert main(argv) == 0
    metrics = json.loads(capsys.readouterr().out)
    assert metrics == json.loads((out / "summary.json").read_text())["metrics"]
    ok = [path[t][3] == truth[t][3] if truth[t][0] == 0 else path[t][0] == 1 for t in path]
    assert metrics["path_score"] == pytest.approx(np.mean(ok))


def test_pathrecovery_bad_network(tmp_path, capsys):
    d = DATA / "pathrecovery"
    argv = ["track", "pathrecovery", str(d / "bad_edges.csv"), str(d / "observations.csv"),
            "-o", str(tmp_path)]  # fmt: skip
    _bad(capsys, argv, "bad_edges.csv", "probs of camera 0 sum to 1.2, not 1")


@pytest.mark.parametrize(("edit", "needle"), [
    (lambda rows: rows + [rows[1]], "cameras.csv:26: camera 0 is listed twice"),
    (lambda rows: [rows[0], *rows[2:]], "no position for camera(s) [0]"),
])
def test_pathrecovery_cameras_csv_places_every_camera_once(tmp_path, capsys, edit, needle):
    """A camera listed twice took its last row; one left out was drawn on the default
    circle among the real positions."""
    d = DATA / "pathrecovery"
    cams = tmp_path / "cameras.csv"
    cams.write_text("\n".join(edit((d / "cameras.csv").read_text().splitlines())) + "\n")
    argv = ["track", "pathrecovery", str(d / "edges.csv"), str(d / "observations.csv"),
            str(cams), "-o", str(tmp_path / "out")]  # fmt: skip
    _bad(capsys, argv, needle)


def test_pathrecovery_eval_truth_without_steps(tmp_path, capsys):
    """A truth path that holds only the start (t = 0) leaves nothing to score: a clear
    error naming the file, not a metric of an empty mean (NaN and a numpy warning)."""
    lines = (DATA / "pathrecovery" / "truth_path.csv").read_text().splitlines()
    truth = tmp_path / "start_only.csv"
    truth.write_text("\n".join(lines[:2]) + "\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        _bad(capsys, ["eval", "pathrecovery", str(truth), str(truth)], "start_only.csv",
             "no step t >= 1")


def test_jorge_track_eval(tmp_path, capsys):
    d = DATA / "jorge"
    out = _track(tmp_path, "jorge", [d / "caviar.xml"], "--truth", str(d / "caviar.xml"))
    from models.io.jorge import read_mot, read_strokes
    from models.jorge.online import label_online
    from models.jorge.scoring import first_errors, score
    from models.jorge.strokes import build_strokes, load_caviar

    seed, rows = read_strokes(out / "strokes.csv")
    strokes = build_strokes(3, load_caviar(d / "caviar.xml"))  # the batch labeller, same seed
    ref = score(strokes, label_online(strokes).labels)
    assert seed == 3 and len(rows) == len(strokes)
    capsys.readouterr()
    assert main(["eval", "jorge", str(out / "strokes.csv"), str(d / "caviar.xml"), "--json"]) == 0
    metrics = json.loads(capsys.readouterr().out)
    assert metrics == json.loads((out / "summary.json").read_text())["metrics"]
    assert metrics["error_rate"] == pytest.approx(ref.error_rate)
    assert metrics["first_mistakes"] == len(first_errors(list(strokes), ref.errors)) > 0
    assert metrics["strokes_group_3plus"] == 0 and metrics["error_rate_group_3plus"] is None
    tracks = read_mot(out / "tracks.txt")
    assert tracks.frames.size > 0
    assert main(["eval", "jorge", str(out / "tracks.txt"), str(d / "gt.txt"), "--json"]) == 0
    mot = json.loads(capsys.readouterr().out)
    assert -1.0 <= mot["mota"] <= 1.0 and 0.0 <= mot["idf1"] <= 1.0


def test_jorge_split_cover_option(tmp_path, capsys):
    from dataclasses import replace

    from models.io.jorge import read_strokes
    from models.jorge.network import FITTED_LABELS, FITTED_SPLIT_COVER, NetworkConfig
    from models.jorge.online import OnlineConfig, label_online
    from models.jorge.strokes import build_strokes, load_caviar

    d = DATA / "jorge"
    cfg = tmp_path / "cfg.json"
    cfg.write_text('{"split_cover": false}')
    out = _track(tmp_path, "jorge", [d / "caviar.xml"], "--config", str(cfg))
    assert json.loads((out / "summary.json").read_text())["parameters"]["split_cover"] is False
    _, rows = read_strokes(out / "strokes.csv")
    strokes = build_strokes(3, load_caviar(d / "caviar.xml"))  # the batch labeller, option off
    off = OnlineConfig(network=NetworkConfig(labels=replace(FITTED_LABELS, split_cover=())))
    want = label_online(strokes, off).labels
    assert [r["label"] for r in rows] == list(want)
    from models.track.jorge import labeller_config  # (this small file labels the same either way)

    assert labeller_config(False) == off and labeller_config(True) == OnlineConfig()
    assert OnlineConfig().network.labels.split_cover == FITTED_SPLIT_COVER  # on by default
    cfg.write_text('{"split_cover": "yes"}')
    _bad(capsys, ["track", "jorge", str(d / "caviar.xml"), "-o", str(tmp_path / "bad"), "--config", str(cfg)],
         "split_cover")  # fmt: skip


def test_jorge_labeller_settings_reach_the_run_and_eval(tmp_path, capsys):
    """The config's ``network``, ``labels`` and ``online`` objects set the labeller's fields
    over the fitted defaults; the run records them, labels and links as the batch labeller
    with the same settings, and ``eval`` replays the link rule of the network the header
    records (without it, the default network's); bad settings are refused naming the
    field, before anything is written."""
    from dataclasses import replace

    from models.io.jorge import read_strokes, read_strokes_header
    from models.jorge.network import FITTED_LABELS, LabelGraph, NetworkConfig
    from models.jorge.online import OnlineConfig, label_online
    from models.jorge.recall import missed_link_counts, missed_links
    from models.jorge.strokes import StrokeConfig, build_strokes, load_caviar

    xml = DATA / "jorge" / "caviar.xml"
    cfg = tmp_path / "cfg.json"
    cfg.write_text('{"gap_min": 20, "gap_max": 30, "gaps_per_100": 8, "network": '
                   '{"max_gap_frames": 10, "sibling_window": 25}, "labels": {"max_group_size": 6}, '
                   '"online": {"max_active": 20}}')  # fmt: skip
    out = _track(tmp_path, "jorge", [xml], "--config", str(cfg), "--truth", str(xml))
    summary = json.loads((out / "summary.json").read_text())
    assert summary["parameters"]["network"] == {"max_gap_frames": 10, "sibling_window": 25}
    assert summary["parameters"]["labels"] == {"max_group_size": 6}
    assert summary["parameters"]["online"] == {"max_active": 20}
    net = NetworkConfig(max_gap_frames=10, sibling_window=25,
                        labels=replace(FITTED_LABELS, max_group_size=6))  # fmt: skip
    settings = StrokeConfig(gap_min=20, gap_max=30, gaps_per_100=8.0)
    strokes = build_strokes(3, load_caviar(xml), settings)
    res = label_online(strokes, OnlineConfig(max_active=20, network=net))
    default = label_online(strokes).labeller.graph
    _, rows = read_strokes(out / "strokes.csv")
    assert [r["label"] for r in rows] == list(res.labels)
    links = [tuple(n.parents) for n in res.labeller.graph.nodes]
    assert [r["parents"] for r in rows] == links != [tuple(n.parents) for n in default.nodes]
    csv = out / "strokes.csv"
    assert read_strokes_header(csv)["network"] == {"max_gap_frames": 10, "sibling_window": 25}
    m = summary["metrics"]
    assert m["missed_links"] == missed_link_counts(missed_links(strokes, res.labeller.graph))
    # the rule replayed is the run's own: the gaps of 20-30 frames are beyond its 10
    assert m["missed_links"]["given_links"] == 0 and m["missed_links"]["gap"] > 0
    lines = csv.read_text().splitlines()
    plain = tmp_path / "plain.csv"  # the header line gone: the default network's rule
    plain.write_text("\n".join(line for line in lines if not line.startswith("# network=")) + "\n")
    capsys.readouterr()
    assert main(["eval", "jorge", str(plain), str(xml), "--json"]) == 0
    graph = LabelGraph(NetworkConfig(), with_domains=False, fps=25.0)
    for s, par in zip(strokes, links):
        graph.add_stroke(s, par)
    want = missed_link_counts(missed_links(strokes, graph))
    assert json.loads(capsys.readouterr().out)["missed_links"] == want
    assert want["given_links"] > 0  # links the default rule makes within 30 frames
    bad_head = tmp_path / "bad_head.csv"
    bad_head.write_text("\n".join(line if not line.startswith("# network=") else
                                  '# network={"max_gap_frames": "x"}' for line in lines) + "\n")
    _bad(capsys, ["eval", "jorge", str(bad_head), str(xml)], "bad_head.csv: header: config",
         "network.max_gap_frames = 'x'")  # fmt: skip
    for text, needles in (('{"network": {"max_gap_frames": 0}}',
                           ("config network", "max_gap_frames")),
                          ('{"network": {"labels": {}}}', ("non-scalar", "['labels']")),
                          ('{"labels": {"split_cover": [1.0, 0.0]}}',
                           ("config labels", "split_cover must be probabilities")),
                          ('{"online": {"max_active": 2.5}}',
                           ("online.max_active = 2.5", "integer")),
                          ('{"network": 3}', ("config network = 3", "NetworkConfig fields"))):
        cfg.write_text(text)
        bad = tmp_path / "bad"
        _bad(capsys, ["track", "jorge", str(xml), "-o", str(bad), "--config", str(cfg)], *needles)
        assert not (bad / "strokes.csv").exists()


def test_jorge_frame_rate_from_seqinfo(tmp_path, capsys):
    from models.io.jorge import read_mot, read_strokes
    from models.io.table import read_lines
    from models.jorge.online import label_online
    from models.jorge.strokes import build_strokes

    seq = tmp_path / "SEQ"
    (seq / "gt").mkdir(parents=True)
    gt = seq / "gt" / "gt.txt"  # the MOTChallenge layout: SEQ/gt/gt.txt, SEQ/seqinfo.ini
    gt.write_text("".join(read_lines(DATA / "jorge" / "gt.txt")))

    def params(out: Path) -> dict:
        return json.loads((out / "summary.json").read_text())["parameters"]

    # no seqinfo.ini: 25 fps assumed, and the run says so
    assert read_mot(gt).fps == 25.0
    capsys.readouterr()
    got = params(_track(tmp_path / "a", "jorge", [gt]))
    assert got["fps"] == 25.0 and got["fps_source"].startswith("assumed 25 fps")
    assert "assumed 25 fps" in capsys.readouterr().err
    # the challenge's seqinfo.ini gives the rate; the labels are the batch labeller's at that rate
    (seq / "seqinfo.ini").write_text("[Sequence]\nname=SEQ\nframeRate=7\nseqLength=100\n")
    assert read_mot(gt).fps == 7.0
    out = _track(tmp_path / "b", "jorge", [gt])
    got = params(out)
    assert got["fps"] == 7.0 and got["fps_source"] == str(seq / "seqinfo.ini")
    assert got["sequence"] == "SEQ"  # a gt.txt is its sequence folder's
    assert "assumed" not in capsys.readouterr().err
    strokes = build_strokes(3, read_mot(gt))
    assert [r["label"] for r in read_strokes(out / "strokes.csv")[1]] == list(label_online(strokes).labels)
    # the config's fps wins
    cfg = tmp_path / "cfg.json"
    cfg.write_text('{"fps": 12.5}')
    got = params(_track(tmp_path / "c", "jorge", [gt], "--config", str(cfg)))
    assert got["fps"] == 12.5 and got["fps_source"] == "config"
    for text, needle in (("[Sequence]\nframeRate=fast\n", "frameRate = 'fast'"),
                         ("[Sequence]\nframeRate=0\n", "frameRate = '0'"),
                         ("garbage\n", "seqinfo.ini:1: not an INI file")):
        (seq / "seqinfo.ini").write_text(text)
        _bad(capsys, ["track", "jorge", str(gt), "-o", str(tmp_path / "bad")], "seqinfo.ini", needle)


def _obsmat(tmp_path: Path) -> Path:
    """Two people meet, walk together 1 m apart in depth, part; a third stands apart."""
    rows = []
    for k in range(40):
        gap = 1.0 if 10 <= k < 30 else 4.0
        rows += [f"{780 + 6 * k} 1 {0.5 * k} 0 0 0.5 0 0", f"{780 + 6 * k} 2 {0.5 * k} 0 {gap} 0.5 0 0"]
    rows.append(f"{780 + 6 * 40} 3 1 0 8 0 0 0")
    obs = tmp_path / "obsmat.txt"
    obs.write_text("\n".join(rows) + "\n")
    return obs


def test_jorge_tracks_in_metres(tmp_path, capsys):
    """An ETH / UCY obsmat file runs through the SIMULATED camera, says so, and evaluates."""
    from models.io.jorge import read_strokes
    from models.jorge.eth import load_eth
    from models.jorge.online import label_online
    from models.jorge.strokes import build_strokes

    obs = _obsmat(tmp_path)
    capsys.readouterr()
    out = _track(tmp_path, "jorge", [obs])
    got = json.loads((out / "summary.json").read_text())["parameters"]
    assert got["fps"] == 2.5 and got["fps_source"].startswith("file format (ETH")
    assert got["simulated_view"].startswith("ObliqueView(") and "SIMULATED camera" in capsys.readouterr().err
    strokes = build_strokes(3, load_eth(obs))
    assert {len(s.truth) for s in strokes} == {1, 2}  # the pair 1 m apart in depth overlaps
    assert [r["label"] for r in read_strokes(out / "strokes.csv")[1]] == list(label_online(strokes).labels)
    assert main(["eval", "jorge", str(out / "strokes.csv"), str(obs)]) == 0
    bad = tmp_path / "bad" / "obsmat.txt"
    bad.parent.mkdir()
    bad.write_text("780 1 0 0 0\n786 1 0 0\n")
    _bad(capsys, ["track", "jorge", str(bad), "-o", str(tmp_path / "b")], "obsmat.txt:2:", "4 columns")


def test_jorge_eval_scores_groups_of_three_and_more(tmp_path, capsys):
    """``dbntrack eval jorge`` on a SIMULATED meeting of five written as a MOTChallenge
    ground truth: the 3+ error rate, the first mistakes and the missed links, as computed
    from the rebuilt strokes, the written labels and the labeller's graph."""
    from models.io.jorge import read_boxes, read_strokes
    from models.jorge.meeting import simulate_meeting
    from models.jorge.online import OnlineConfig, label_online
    from models.jorge.recall import missed_link_counts, missed_links
    from models.jorge.scoring import first_errors, score
    from models.jorge.strokes import build_strokes

    truth = simulate_meeting(3, 5)
    gt = tmp_path / "gt.txt"
    lines = [f"{fr + 1},{pid + 1},{xc - w / 2:.2f},{yc - h / 2:.2f},{w:.2f},{h:.2f},1,1,1"
             for fr, row in zip(truth.frames, truth.boxes) for pid, (xc, yc, w, h) in zip(truth.ids, row)
             if np.isfinite(w)]
    gt.write_text("\n".join(lines) + "\n")
    out = _track(tmp_path, "jorge", [gt])
    seed, rows = read_strokes(out / "strokes.csv")
    strokes = build_strokes(seed, read_boxes(gt))
    labels = [r["label"] for r in rows]
    sc = score(strokes, labels)
    big = [s.index for s in strokes if len(s.truth) >= 3]
    capsys.readouterr()
    assert main(["eval", "jorge", str(out / "strokes.csv"), str(gt), "--json"]) == 0
    m = json.loads(capsys.readouterr().out)
    assert m["strokes_group_3plus"] == len(big) > 0
    assert m["error_rate_group_3plus"] == pytest.approx(len(set(big) & set(sc.errors)) / len(big))
    assert 0.0 < m["error_rate_group_3plus"] < 1.0 and m["error_rate_group_3plus"] != m["error_rate"]
    assert m["first_mistakes"] == len(first_errors(list(strokes), sc.errors)) > 0
    assert m["error_rate"] == pytest.approx(sc.error_rate)
    # the links written are the labeller's, and eval's replay of the rule on them finds
    # the labeller's own missed links (none the rule would have made: given_links 0)
    graph = label_online(strokes, OnlineConfig()).labeller.graph
    assert [r["parents"] for r in rows] == [tuple(n.parents) for n in graph.nodes]
    missed = missed_links(strokes, graph)
    assert m["missed_links"] == missed_link_counts(missed) and m["missed_links"]["given_links"] == 0
    mask = np.isin(np.arange(len(strokes)), list(first_errors(list(strokes), sc.errors)))
    assert m["first_mistake_missed_links"] == missed_link_counts(missed, mask)


def test_jorge_eval_rebuilds_the_strokes_of_the_runs_settings(tmp_path, capsys):
    """Stroke settings from the config reach ``--truth`` and ``eval`` through the strokes
    CSV's header; strokes that are not the file's are refused, not scored."""
    import dataclasses

    from models.io.jorge import read_strokes_header
    from models.jorge.online import label_online
    from models.jorge.scoring import score
    from models.jorge.strokes import StrokeConfig, build_strokes, load_caviar

    xml = DATA / "jorge" / "caviar.xml"
    cfg = tmp_path / "cfg.json"
    cfg.write_text('{"gap_min": 20, "gap_max": 30, "gaps_per_100": 8}')
    out = _track(tmp_path, "jorge", [xml], "--config", str(cfg), "--truth", str(xml))
    settings = StrokeConfig(gap_min=20, gap_max=30, gaps_per_100=8.0)
    strokes = build_strokes(3, load_caviar(xml), settings)
    default = build_strokes(3, load_caviar(xml))
    # as many strokes as the default settings give, on other frames: a count check alone
    # would have scored these labels against the wrong strokes
    assert len(strokes) == len(default) and [s.start for s in strokes] != [s.start for s in default]
    csv = out / "strokes.csv"
    want_head = {"seed": 3, "strokes": dataclasses.asdict(settings), "fps": 25.0}
    assert read_strokes_header(csv) == want_head
    want = score(strokes, label_online(strokes).labels).error_rate
    assert json.loads((out / "summary.json").read_text())["metrics"]["error_rate"] == pytest.approx(want)
    capsys.readouterr()
    assert main(["eval", "jorge", str(csv), str(xml), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["error_rate"] == pytest.approx(want)
    lines = [line for line in csv.read_text().splitlines() if not line.startswith("# fps=")]
    old = tmp_path / "old.csv"  # an earlier version's file (seed only): default settings
    old.write_text("\n".join([lines[0], *lines[2:]]) + "\n")
    _bad(capsys, ["eval", "jorge", str(old), str(xml)], "old.csv: stroke 0 spans frames 62-87", "gives 62-89",
         "not the boxes (or settings) this result was made from")  # fmt: skip
    for line, needle in (("# strokes=[20]", "old.csv:2: strokes = '[20]': expected a JSON object"),
                         ('# strokes={"gap_min": 0}', "old.csv: header: config"),
                         ("# seed=three", "old.csv:1: seed = 'three': expected an integer")):
        head = [line, lines[1]] if line.startswith("# seed") else [lines[0], line]
        old.write_text("\n".join([*head, *lines[2:]]) + "\n")
        _bad(capsys, ["eval", "jorge", str(old), str(xml)], needle)
    first = lines[3].split(",")  # the first row, after the two header lines and the columns
    for label, needle in (("1 x", "label '1 x' / truth"), ("", "empty label")):
        old.write_text("\n".join([*lines[:3], ",".join([*first[:3], label, *first[4:]]), *lines[4:]]) + "\n")
        _bad(capsys, ["eval", "jorge", str(old), str(xml)], "old.csv:4:", needle)


def test_jorge_view_option(tmp_path, capsys):
    """The config's ``view`` sets an obsmat file's SIMULATED camera; eval sees the same."""
    from models.io.jorge import read_strokes, read_strokes_header
    from models.jorge.eth import ObliqueView, load_eth
    from models.jorge.online import label_online
    from models.jorge.strokes import build_strokes

    obs = _obsmat(tmp_path)
    cfg = tmp_path / "cfg.json"
    cfg.write_text('{"view": {"tilt_deg": 90}}')  # straight down: people are discs
    capsys.readouterr()
    out = _track(tmp_path, "jorge", [obs], "--config", str(cfg), "--truth", str(obs))
    view = ObliqueView(tilt_deg=90.0)
    assert repr(view) in capsys.readouterr().err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["parameters"]["simulated_view"] == repr(view)
    assert read_strokes_header(out / "strokes.csv")["view"]["tilt_deg"] == 90.0
    strokes = build_strokes(3, load_eth(obs, view))
    assert {len(s.truth) for s in strokes} == {1}  # seen from above, the pair 1 m apart never overlaps
    assert [r["label"] for r in read_strokes(out / "strokes.csv")[1]] == list(label_online(strokes).labels)
    assert summary["metrics"]["error_rate"] == 0.0
    assert main(["eval", "jorge", str(out / "tracks.txt"), str(obs), "--json"]) == 0
    mota = json.loads(capsys.readouterr().out)["mota"]  # below 1: the simulated occlusion gaps
    alone = tmp_path / "alone"  # without the run's strokes.csv beside it: the default view
    alone.mkdir()
    (alone / "tracks.txt").write_text((out / "tracks.txt").read_text())
    assert main(["eval", "jorge", str(alone / "tracks.txt"), str(obs), "--json"]) == 0
    assert mota > 0.8 and json.loads(capsys.readouterr().out)["mota"] < 0.0  # boxes of another view
    _bad(capsys, ["eval", "jorge", str(out / "strokes.csv"), str(DATA / "jorge" / "caviar.xml")],
         "caviar.xml: a camera view applies only to an ETH / UCY obsmat file")  # fmt: skip
    for text, needles in (('{"view": {"tilt_deg": 120}}', ("config view", "tilt_deg")),
                          ('{"view": {"zoom": 2}}', ("config view", "zoom")),
                          ('{"view": 3}', ("config view = 3",))):
        cfg.write_text(text)
        _bad(capsys, ["track", "jorge", str(obs), "-o", str(tmp_path / "b"), "--config", str(cfg)], *needles)
    cfg.write_text('{"view": {"tilt_deg": 60}}')
    _bad(capsys, ["track", "jorge", str(DATA / "jorge" / "caviar.xml"), "-o", str(tmp_path / "c"),
                  "--config", str(cfg)], "config view", "obsmat")  # fmt: skip


def test_jorge_formats_agree():
    from models.io.jorge import read_boxes

    d = DATA / "jorge"
    a, b, c = (read_boxes(d / f) for f in ("caviar.xml", "pets2009.xml", "gt.txt"))
    np.testing.assert_array_equal(a.ids, c.ids)
    np.testing.assert_allclose(a.boxes, b.boxes)
    rows = np.searchsorted(a.frames, c.frames)  # MOT files list no empty frame
    assert np.isnan(np.delete(a.boxes, rows, axis=0)).all()
    np.testing.assert_allclose(a.boxes[rows, :, 2:], c.boxes[:, :, 2:], atol=0.051)
    np.testing.assert_allclose(a.boxes[rows, :, :2], c.boxes[:, :, :2], atol=0.11)


def test_jorge_bad_files(tmp_path, capsys):
    d = DATA / "jorge"
    _bad(capsys, ["track", "jorge", str(d / "bad_gt.txt"), "-o", str(tmp_path)],
         "bad_gt.txt:2:", "width")  # fmt: skip
    bad = tmp_path / "broken.xml"
    bad.write_text('<dataset>\n<frame number="0">\n<objectlist>\n</dataset>\n')
    _bad(capsys, ["track", "jorge", str(bad), "-o", str(tmp_path)], "broken.xml:4:")


def test_mot_reader_keeps_empty_fields_and_bounds_pixels(tmp_path, capsys):
    """An empty field is an error in its own column (it used to be dropped, shifting y, w,
    h into x, y, w: a silent wrong box); a box beyond the pixel bound names its line, as
    does the XML reader its frame and object; blank and space-separated lines still read."""
    from models.io.jorge import read_mot

    good = tmp_path / "good.txt"
    good.write_text("1,1,10,20,5,8,1,1,1\n,,,,,,,,\n2 1 11 20 5 8\n3,1,12,20,5,8,\n")
    truth = read_mot(good)
    np.testing.assert_allclose(truth.boxes[:, 0], [[12.5, 24, 5, 8], [13.5, 24, 5, 8], [14.5, 24, 5, 8]])
    gap = tmp_path / "gap.txt"
    gap.write_text("1,1,10,20,5,8,1,1,1\n2,1,,20,5,8,1,1,1\n")
    _bad(capsys, ["track", "jorge", str(gap), "-o", str(tmp_path / "a")], "gap.txt:2:", "x = ''")
    far = tmp_path / "far.txt"
    far.write_text("1,1,10,20,5,8,1,1,1\n2,1,99999999999,20,5,8,1,1,1\n")
    _bad(capsys, ["track", "jorge", str(far), "-o", str(tmp_path / "b")], "far.txt:2:", "pixels")
    xml = (DATA / "jorge" / "caviar.xml").read_text()
    big = tmp_path / "big.xml"
    big.write_text(xml.replace('w="18.0"', 'w="99999999999"', 1))
    _bad(capsys, ["track", "jorge", str(big), "-o", str(tmp_path / "c")], "big.xml", "object", "pixels")


@pytest.mark.heavy  # ~12-22 s: a whole RJ-MCMC run through the CLI; CI runs it (pytest -m heavy)
def test_rjmcmc3d_track_eval(tmp_path, capsys):
    d = DATA / "rjmcmc3d"
    views = [d / f"view{v}" for v in range(3)]
    out = _track(tmp_path, "rjmcmc3d", views, "--config", str(d / "config.json"),
                 "--truth", str(d / "truth3d.txt"))  # fmt: skip
    from models.io.rjmcmc3d import read_tracks3d

    tracks = read_tracks3d(out / "tracks3d.txt")
    assert set(tracks) <= {1, 2, 3, 4, 5, 6}
    capsys.readouterr()
    argv = ["eval", "rjmcmc3d", str(out / "tracks3d.txt"), str(d / "truth3d.txt"), "--json"]
    assert main(argv) == 0
    metrics = json.loads(capsys.readouterr().out)
    assert metrics == json.loads((out / "summary.json").read_text())["metrics"]
    # the two simulated walkers are found (at 96 x 72 px the tracker found nobody)
    assert metrics["recall"] >= 0.75 and metrics["precision"] >= 0.75
    # oracle: the truth scored against itself is perfect
    assert main(["eval", "rjmcmc3d", str(d / "truth3d.txt"), str(d / "truth3d.txt"), "--json"]) == 0
    perfect = json.loads(capsys.readouterr().out)
    assert perfect["mota"] == 1.0 and perfect["idf1"] == 1.0


def test_rjmcmc3d_calibration_round_trip():
    from models.io.rjmcmc3d import read_view
    from models.rjmcmc3d.scene import default_scene

    scene = default_scene(0)  # the cameras make_example.py wrote
    for v, cam in enumerate(scene.cameras):
        got = read_view(DATA / "rjmcmc3d" / f"view{v}").camera
        np.testing.assert_allclose(got.K, cam.K, atol=1e-9)
        np.testing.assert_allclose(got.R, cam.R, atol=1e-9)
        np.testing.assert_allclose(got.t, cam.t, atol=1e-9)


def test_rjmcmc3d_bad_files(tmp_path, capsys):
    d = DATA / "rjmcmc3d"
    argv = ["eval", "rjmcmc3d", str(d / "bad_truth3d.txt"), str(d / "truth3d.txt")]
    _bad(capsys, argv, "bad_truth3d.txt:2:", "abc")
    _bad(capsys, ["track", "rjmcmc3d", str(tmp_path), "-o", str(tmp_path / "o")], "calibration")
    short = tmp_path / "short"  # a view with one mask fewer: the message names each folder
    shutil.copytree(d / "view2", short)
    sorted(short.glob("mask_*.png"))[-1].unlink()
    views = [str(d / "view0"), str(d / "view1"), str(short)]
    _bad(capsys, ["track", "rjmcmc3d", *views, "-o", str(tmp_path / "o2")],
         "different numbers of masks", "view0: 6", f"{short}: 5")
    late = tmp_path / "late"  # the same count, exported from frame 1: matched one frame off
    shutil.copytree(d / "view2", late)
    for m in sorted(late.glob("mask_*.png"), reverse=True):
        m.rename(late / f"mask_{int(m.stem[5:]) + 1:04d}.png")
    views = [str(d / "view0"), str(d / "view1"), str(late)]
    _bad(capsys, ["track", "rjmcmc3d", *views, "-o", str(tmp_path / "o3")],
         f"{d / 'view0' / 'mask_0000.png'} and {late / 'mask_0001.png'} are mask 1",
         "of frames 0 and 1")


@pytest.mark.parametrize("command", ["track", "fit", "eval", "list", "demo", "sweep"])
def test_every_subcommand_has_help(capsys, command):
    with pytest.raises(SystemExit) as exc:
        main([command, "--help"])
    assert exc.value.code == 0
    assert "usage: dbntrack" in capsys.readouterr().out


def test_data_option_sets_the_data_folder(tmp_path, monkeypatch, capsys):
    from models import datasets

    monkeypatch.setenv("DBNTRACK_DATA", "/nonexistent")  # restored after the test
    assert main(["--data", str(tmp_path), "list", "--json"]) == 0
    assert datasets.data_dir() == tmp_path.resolve()
    with pytest.raises(FileNotFoundError, match="DBNTRACK_DATA"):
        datasets.require("mrclam6", "Barcodes.dat.gz")


def test_dbn_generic_method_matches_exact_or_says_why(tmp_path, capsys):
    d = DATA / "dbn"
    argv = ["track", "dbn", str(d / "umbrella.bif"), str(d / "evidence.csv"), "--method", "auto"]
    rc = main([*argv, "-o", str(tmp_path / "auto")])
    if rc == 2:  # inference.filter (the generic engines) not in this version
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and "inference.filter" in err
        return
    assert rc == 0
    assert main([*argv[:4], "-o", str(tmp_path / "exact")]) == 0
    from models.io.dbn import read_marginals

    a = read_marginals(tmp_path / "auto" / "marginals.csv")["Rain"][1]
    b = read_marginals(tmp_path / "exact" / "marginals.csv")["Rain"][1]
    np.testing.assert_allclose(a, b, atol=1e-10)


def _edited_observations(tmp_path: Path, column: int, value: str) -> Path:
    lines = (DATA / "pathrecovery" / "observations.csv").read_text().splitlines()
    fields = lines[5].split(",")
    fields[column] = value
    lines[5] = ",".join(fields)
    out = tmp_path / "observations.csv"
    out.write_text("\n".join(lines) + "\n")
    return out


@pytest.mark.parametrize(("column", "needle"), [(3, "observations.csv:6:"),
                                                (2, "not in the network")])  # fmt: skip
def test_pathrecovery_observation_the_filter_refuses_names_the_file(tmp_path, capsys,
                                                                    column, needle):
    """A byte flip made a feature 2e6 (the filter's limit is 1e6) or a camera the network
    lacks: the error names the observations file (the line, for the feature), not only
    the filter's array."""
    obs = _edited_observations(tmp_path, column, "2000000")
    argv = ["track", "pathrecovery", str(DATA / "pathrecovery" / "edges.csv"), str(obs),
            "-o", str(tmp_path / "out")]  # fmt: skip
    _bad(capsys, argv, needle, "observations.csv")


def test_bif_with_a_control_character_is_refused_at_its_line(tmp_path, capsys):
    """A byte flip put U+0001 into a state name: pgmpy would keep it, and the evidence
    file, naming the state, would be blamed."""
    raw = (DATA / "dbn" / "umbrella.bif").read_bytes()
    i = raw.index(b"yes")
    bif = tmp_path / "damaged.bif"
    bif.write_bytes(raw[:i] + b"\x01" + raw[i:])
    line = raw[:i].count(b"\n") + 1
    argv = ["track", "dbn", str(bif), str(DATA / "dbn" / "evidence.csv"), "-o", str(tmp_path)]
    _bad(capsys, argv, f"damaged.bif:{line}:", "control character")


def test_dbn_evidence_state_mismatch_names_both_files(tmp_path, capsys):
    """A byte flip renamed a state in the BIF (' yes' -> '!yes', in both slices; in one,
    the BIF itself is refused): both files parse, and
    the evidence's 'yes' is no longer a state; either file may be the wrong one, so the
    error names the evidence line and the BIF that declares the states."""
    raw = (DATA / "dbn" / "umbrella.bif").read_text()
    bif = tmp_path / "renamed.bif"
    for v in ("Umbrella_0", "Umbrella_1"):  # a child: no parent rows; both slices alike
        i = raw.index("{ yes, no", raw.index(f"variable {v}"))
        raw = raw[:i] + "{!yes, no" + raw[i + len("{ yes, no"):]
    bif.write_text(raw)
    argv = ["track", "dbn", str(bif), str(DATA / "dbn" / "evidence.csv"), "-o", str(tmp_path)]
    _bad(capsys, argv, "evidence.csv:2:", "'!yes'", "declared in", "renamed.bif")


def test_dbn_slice_one_states_in_another_order_are_refused(tmp_path, capsys):
    """Rain_1 declared { no, yes } while Rain_0 is { yes, no }: the transition table was
    read in Rain_0's order, so P(rain tomorrow | rain today) silently became 0.3."""
    raw = (DATA / "dbn" / "umbrella.bif").read_text()
    i = raw.index("{ yes, no", raw.index("variable Rain_1"))
    bif = tmp_path / "swapped.bif"
    bif.write_text(raw[:i] + "{ no, yes" + raw[i + len("{ yes, no"):])
    argv = ["track", "dbn", str(bif), str(DATA / "dbn" / "evidence.csv"), "-o", str(tmp_path)]
    _bad(capsys, argv, "swapped.bif", "'Rain_1' has states ['no', 'yes']",
         "'Rain_0' has ['yes', 'no']")


def test_dbn_state_names_that_are_numbers_are_never_read_as_indices(tmp_path):
    """States named 1 and 2: the field "0" was read as index 0 (the state "1"), the same
    state as the field "1"; now a field is a name, and "0" is refused at its line."""
    from dbn.errors import InputError
    from dbn.pgmpy_adapter import parse_bif
    from models.io.dbn import read_evidence, two_slice_from_bn

    raw = (DATA / "dbn" / "umbrella.bif").read_text()
    for v in ("Umbrella_0", "Umbrella_1"):
        i = raw.index("{ yes, no", raw.index(f"variable {v}"))
        raw = raw[:i] + "{ 1, 2" + raw[i + len("{ yes, no"):]

    model = two_slice_from_bn(parse_bif(raw))
    ev = tmp_path / "ev.csv"
    ev.write_text("Umbrella\n1\n2\n")
    assert read_evidence(ev, model)["Umbrella"].tolist() == [0, 1]  # names
    ev.write_text("Umbrella\n1\n0\n")
    with pytest.raises(InputError, match="ev.csv:3:.*state names are numbers"):
        read_evidence(ev, model)
    plain = tmp_path / "plain.csv"  # named states that are not numbers: an index still reads
    plain.write_text("Rain\nno\n0\n")
    assert read_evidence(plain, model)["Rain"].tolist() == [1, 0]


def _edited_csv(src: Path, dst: Path, line: int, column: str, value: str) -> Path:
    """``src`` with field ``column`` of file line ``line`` set to ``value`` (the header is
    the first line that is not a comment)."""
    lines = src.read_text().splitlines()
    header = next(ln for ln in lines if not ln.startswith("#")).split(",")
    fields = lines[line - 1].split(",")
    fields[header.index(column)] = value
    lines[line - 1] = ",".join(fields)
    dst.write_text("\n".join(lines) + "\n")
    return dst


@pytest.mark.parametrize("value", ["1e300", "99999999999999999999"])
def test_an_integer_beyond_int64_is_refused_at_its_line(tmp_path, capsys, value):
    """It was a raw ``OverflowError`` when the reader filled its int64 array."""
    obs = _edited_csv(DATA / "zajdel" / "observations.csv", tmp_path / "obs.csv", 4, "camera", value)
    _bad(capsys, ["track", "zajdel_adf", str(obs), "-o", str(tmp_path / "out")],
         "obs.csv:4:", f"camera = '{value}' is out of range")  # fmt: skip


@pytest.mark.parametrize("config", [None, {"num_cameras": 5000}])
def test_zajdel_camera_count_beyond_the_dense_path_table_is_refused(tmp_path, capsys, config):
    """Camera 100000 made the runner ask for a (C, B, C, B) table of 298 GiB (a raw numpy
    MemoryError); 3000 took 35 s and 2 GB. The count comes from the observations' largest
    id or from the config, and the error names where."""
    src = DATA / "zajdel" / "observations.csv"
    argv = ["track", "zajdel_adf", "-o", str(tmp_path / "out")]
    if config is None:
        argv.insert(2, str(_edited_csv(src, tmp_path / "obs.csv", 4, "camera", "100000")))
        _bad(capsys, argv, "obs.csv:", "camera ids up to 100000", "path table")
    else:
        (tmp_path / "cfg.json").write_text(json.dumps(config))
        argv[2:2] = [str(src), "--config", str(tmp_path / "cfg.json")]
        _bad(capsys, argv, "cfg.json:", "config num_cameras", "path table")


def test_pathrecovery_camera_id_beyond_the_edges_is_refused_at_its_line(tmp_path, capsys):
    """Camera 4611686018427387904 in edges.csv made the network ask numpy for that many
    coordinates (a raw ValueError); every camera 0..C-1 needs an outgoing edge, so no id
    can reach the number of edges listed."""
    edges = _edited_csv(DATA / "pathrecovery" / "edges.csv", tmp_path / "edges.csv", 3, "to",
                        "4611686018427387904")  # fmt: skip
    argv = ["track", "pathrecovery", str(edges), str(DATA / "pathrecovery" / "observations.csv"),
            "-o", str(tmp_path / "out")]  # fmt: skip
    _bad(capsys, argv, "edges.csv:3:", "camera 4611686018427387904", "edges are listed")


def _spreadsheet_copy(src: Path, dst: Path) -> Path:
    """``src`` as a spreadsheet's "CSV UTF-8" export writes it: a byte-order mark first
    and CRLF line ends."""
    dst.parent.mkdir(parents=True, exist_ok=True)
    dst.write_bytes(b"\xef\xbb\xbf" + src.read_bytes().replace(b"\n", b"\r\n"))
    return dst


def _plain(x):
    """``x`` with its dataclasses as dicts and named tuples as tuples, for assert_equal."""
    if dataclasses.is_dataclass(x):
        return {f.name: _plain(getattr(x, f.name)) for f in dataclasses.fields(x)}
    if isinstance(x, tuple | list):
        return [_plain(v) for v in x]
    if isinstance(x, dict):
        return {k: _plain(v) for k, v in x.items()}
    return x


def test_a_byte_order_mark_is_not_part_of_the_first_field(tmp_path):
    """A byte-order mark was read as part of the first header name or field: "column
    '\\ufeffUmbrella' is not a variable" (dbn), "missing column(s) ['t']" (localization,
    pathrecovery), a zajdel file's header misread, a ``--config`` "not valid JSON", a
    seqinfo.ini "not an INI file". Every text reader now drops it."""
    from models.io import jorge, localization, pathrecovery, rjmcmc3d, zajdel
    from models.io.dbn import read_states, read_two_slice_bif
    from models.io.table import read_json_config

    def same(read, *names: str) -> None:  # one path each: some results hold the file name
        paths = [tmp_path / n for n in names]
        for n, path in zip(names, paths):
            path.parent.mkdir(parents=True, exist_ok=True)
            shutil.copy(DATA / n, path)
        want = _plain(read(*paths))
        for n, path in zip(names, paths):
            _spreadsheet_copy(DATA / n, path)
        np.testing.assert_equal(_plain(read(*paths)), want)

    same(pathrecovery.read_network, "pathrecovery/edges.csv", "pathrecovery/cameras.csv")
    same(pathrecovery.read_observations, "pathrecovery/observations.csv")
    same(localization.read_generic, *(f"localization/{n}.csv" for n in
                                      ("odometry", "measurements", "landmarks", "groundtruth")))
    same(zajdel.read_observations, "zajdel/observations.csv")
    same(zajdel.read_observations, "zajdel/events.csv")
    same(jorge.read_mot, "jorge/gt.txt")
    same(rjmcmc3d.read_tracks3d, "rjmcmc3d/truth3d.txt")
    same(read_json_config, "rjmcmc3d/config.json")
    dbn = read_two_slice_bif(DATA / "dbn" / "umbrella.bif")
    same(lambda path: read_states(path, dbn), "dbn/evidence.csv")
    ini = tmp_path / "SEQ" / "seqinfo.ini"
    ini.parent.mkdir()
    ini.write_bytes(b"\xef\xbb\xbf[Sequence]\r\nname=SEQ\r\nframeRate=7\r\n")
    gt = _spreadsheet_copy(DATA / "jorge" / "gt.txt", ini.parent / "gt.txt")
    assert jorge.mot_frame_rate(gt)[0] == 7.0


@pytest.mark.parametrize("method", ["exact", "auto", "bk"])
def test_dbn_integer_state_names_read_as_names_by_every_method(tmp_path, method):
    """States named 1, 2, 3: the evidence field 2 is the state '2' (index 1) under every
    method (the CLI hands the engines indices); P(X_0 | Y_0 = '2') = [0.4, 0.6] by hand."""
    bif = tmp_path / "numbers.bif"
    bif.write_text(
        "network n {\n}\n"
        "variable X_0 { type discrete [ 2 ] { 1, 2 }; }\n"
        "variable X_1 { type discrete [ 2 ] { 1, 2 }; }\n"
        "variable Y_0 { type discrete [ 3 ] { 1, 2, 3 }; }\n"
        "variable Y_1 { type discrete [ 3 ] { 1, 2, 3 }; }\n"
        "probability ( X_0 ) { table 0.5, 0.5; }\n"
        "probability ( Y_0 | X_0 ) { (1) 0.7, 0.2, 0.1; (2) 0.1, 0.3, 0.6; }\n"
        "probability ( X_1 | X_0 ) { (1) 0.9, 0.1; (2) 0.2, 0.8; }\n"
        "probability ( Y_1 | X_1 ) { (1) 0.7, 0.2, 0.1; (2) 0.1, 0.3, 0.6; }\n"
    )
    ev = tmp_path / "ev.csv"
    ev.write_text("Y\n2\n3\n\n1\n")
    out = _track(tmp_path, "dbn", [bif, ev], "--method", method)
    from models.io.dbn import read_marginals

    states, x = read_marginals(out / "marginals.csv")["X"]
    assert states == ["1", "2"]
    np.testing.assert_allclose(x[0], [0.4, 0.6], atol=1e-12)


def test_dbn_slice_column_places_rows_at_their_slices(tmp_path, capsys):
    """Without slice numbers, a row left out of an evidence or truth CSV shifted every
    later row to the slice before (silently); a ``slice`` column now places each row,
    and a slice no row gives is unobserved (evidence) or not scored (truth)."""
    d = DATA / "dbn"
    sparse = tmp_path / "sparse.csv"
    sparse.write_text("slice,Umbrella\n0,yes\n1,yes\n2,no\n4,yes\n")  # slice 3 unobserved
    a = _track(tmp_path / "a", "dbn", [d / "umbrella.bif", d / "evidence.csv"])
    b = _track(tmp_path / "b", "dbn", [d / "umbrella.bif", sparse])
    assert (a / "marginals.csv").read_text() == (b / "marginals.csv").read_text()
    truth = tmp_path / "truth.csv"
    truth.write_text("slice,Rain\n1,yes\n4,yes\n")  # the same states as truth.csv's rows 1, 4
    full = tmp_path / "full.csv"
    full.write_text("Rain\n\nyes\n\n\nyes\n")
    capsys.readouterr()

    def scored(path):
        assert main(["eval", "dbn", str(a / "marginals.csv"), str(path), "--json"]) == 0
        return json.loads(capsys.readouterr().out.strip().splitlines()[-1])

    assert scored(truth) == scored(full) and scored(truth)["num_compared"] == 2
    for text, needle in [("slice,Rain\n2,yes\n2,no\n", "bad.csv:3: slice = 2 after slice 2"),
                         ("slice,Rain\n-1,yes\n", "bad.csv:2: slice = -1"),
                         ("slice,Rain\n0,yes\nx,no\n", "bad.csv:3: slice = 'x'"),
                         ("slice,Rain\n0,yes\n7,no\n", "bad.csv:3: truth has 8 slices")]:
        (tmp_path / "bad.csv").write_text(text)
        _bad(capsys, ["eval", "dbn", str(a / "marginals.csv"), str(tmp_path / "bad.csv")], needle)


def test_a_header_merged_with_its_first_row_names_the_file(tmp_path, capsys):
    """A byte flip of the header's newline (found by the slow random-damage test) merged
    the header with the first row: its column names held a control character, the
    reader took them, and the run failed with "t = 0 has 0 observations" naming no file."""
    d = DATA / "pathrecovery"
    raw = (d / "observations.csv").read_bytes()
    i = raw.index(b"\n")
    bad = tmp_path / "observations.csv"
    bad.write_bytes(raw[:i] + b"\x01" + raw[i + 1:])
    _bad(capsys, ["track", "pathrecovery", str(d / "edges.csv"), str(bad), "-o", str(tmp_path)],
         "observations.csv:1: header column", "control character")  # fmt: skip
    two = tmp_path / "two.csv"  # two observations at t = 0 and no target in --config
    lines = raw.decode().splitlines(keepends=True)
    two.write_text(lines[0] + lines[1] + lines[1].replace("12,", "987654,", 1) + "".join(lines[2:]))
    _bad(capsys, ["track", "pathrecovery", str(d / "edges.csv"), str(two), "-o", str(tmp_path)],
         "two.csv: t = 0 has 2 observations")  # fmt: skip


def test_pathrecovery_too_few_observations_for_sigma_names_the_file(tmp_path, capsys):
    """Found by the slow random-damage test (a truncated file): the features' covariance,
    the default sigma, was not positive definite and the run said only "sigma is not
    symmetric positive definite"."""
    d = DATA / "pathrecovery"
    lines = (d / "observations.csv").read_text().splitlines(keepends=True)
    few = tmp_path / "few.csv"
    few.write_text("".join(lines[:3]))  # two observations, four features
    _bad(capsys, ["track", "pathrecovery", str(d / "edges.csv"), str(few), "-o", str(tmp_path)],
         "few.csv: the covariance of the features of its 2 observations")  # fmt: skip
    one = tmp_path / "one.csv"
    one.write_text("".join(lines[:2]))  # a single observation: no covariance at all
    _bad(capsys, ["track", "pathrecovery", str(d / "edges.csv"), str(one), "-o", str(tmp_path)],
         "one.csv: the covariance of the features of its 1 observation is")  # fmt: skip
