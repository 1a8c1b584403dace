"""``dbntrack fit localization``: the robot's noise measured on runs with ground truth and
the filter's widening of it searched (``models.track.localization_fit``), written as a
config ``dbntrack track localization`` runs. The runs are SIMULATED robots in one
MRCLAM-style folder (the same sensor, other paths)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import jax
import numpy as np
import pytest

from dbn.errors import ConfigError
from models.cli import main
from models.io.localization import read_mrclam_folder
from models.localization.fit import noise_residuals, noise_settings, pool_residuals, robust_noise
from models.localization.mrclam import MRCLAM_NOISE, build_sequence
from models.track import localization_fit
from models.track.localization import filter_means, run_options, run_sequence, scan_means
from models.track.localization_fit import keeps_bias
from tests.cli.test_cli_track import _bad, _fitted

LANDMARKS = np.array([[11, 0.0, 0.0], [12, 3.0, 0.0], [13, 0.0, 3.0], [14, 3.0, 3.0]])
CONFIG = {"duration": 4.0, "num_particles": 100, "search_scales": [1, 4]}


def _robot(folder: Path, robot: int, seconds: float = 7.0, bias: float = 0.03) -> None:
    """SIMULATED robot ``robot`` (seed ``robot``) on a circle of its own through the
    landmarks' square: odometry and truth at 20 Hz (odometry noise 0.02 m/s, 0.03 rad/s),
    every landmark measured at 5 Hz (range noise 0.05 m, bias ``bias`` m; bearing 0.02
    rad)."""
    rng = np.random.default_rng(robot)
    t = 100.0 + np.arange(0.0, seconds, 0.05)
    v, w, phase = 0.3, 0.15 + 0.05 * robot, 0.7 * robot
    theta = phase + w * (t - t[0])
    x = 1.5 + (v / w) * (np.sin(theta) - np.sin(phase))
    y = 1.0 - (v / w) * (np.cos(theta) - np.cos(phase))
    odo = np.column_stack([t, v + 0.02 * rng.standard_normal(t.size),
                           w + 0.03 * rng.standard_normal(t.size)])  # fmt: skip
    meas = [[t[k], sid, np.hypot(lx - x[k], ly - y[k]) + bias + 0.05 * rng.standard_normal(),
             np.angle(np.exp(1j * (np.arctan2(ly - y[k], lx - x[k]) - theta[k]
                                   + 0.02 * rng.standard_normal())))]
            for k in range(0, t.size, 4) for sid, lx, ly in LANDMARKS]  # fmt: skip
    np.savetxt(folder / f"Robot{robot}_Odometry.dat", odo, fmt="%.4f")
    np.savetxt(folder / f"Robot{robot}_Measurement.dat", meas, fmt=["%.4f", "%d", "%.4f", "%.4f"])
    gt = np.column_stack([t, x, y, np.angle(np.exp(1j * theta))])
    np.savetxt(folder / f"Robot{robot}_Groundtruth.dat", gt, fmt="%.5f")


def _folder(folder: Path, bias: float = 0.03) -> Path:
    """An MRCLAM-style folder of three SIMULATED robots, their range bias ``bias``."""
    for robot in (1, 2, 3):
        _robot(folder, robot, bias=bias)
    np.savetxt(folder / "Landmark_Groundtruth.dat", np.column_stack([LANDMARKS, np.zeros((4, 2))]),
               fmt=["%d", "%.3f", "%.3f", "%.1f", "%.1f"])  # fmt: skip
    np.savetxt(folder / "Barcodes.dat", np.array([[s, s] for s in LANDMARKS[:, 0]]), fmt="%d")
    return folder


@pytest.fixture(scope="module")
def runs(tmp_path_factory) -> Path:
    """An MRCLAM-style folder of three SIMULATED robots."""
    return _folder(tmp_path_factory.mktemp("mrclam"))


def _fit(tmp_path: Path, out: str, config: dict, *argv) -> tuple[dict, dict]:
    """``dbntrack fit localization ARGV --config CONFIG -o tmp/OUT``: (summary, config.json)."""
    path = tmp_path / f"{out}.json"
    path.write_text(json.dumps(config))
    return _fitted(tmp_path, "localization", out, *argv, "--config", path)


def _track_rmse(tmp_path: Path, folder: Path, robot: int, config: dict, out: str) -> float:
    """The position RMSE ``dbntrack track localization --config`` then ``--truth`` give."""
    path = tmp_path / f"{out}.json"
    path.write_text(json.dumps({**config, "robot": robot}))
    assert main(["track", "localization", str(folder), "--config", str(path), "--truth",
                 str(folder / f"Robot{robot}_Groundtruth.dat"), "-o", str(tmp_path / out),
                 "--quiet"]) == 0  # fmt: skip
    return json.loads((tmp_path / out / "summary.json").read_text())["metrics"]["rmse_m"]


def _cut_copy(runs: Path, robot: int, folder: Path) -> Path:
    """A folder of the generic CSVs holding the last two thirds of ``robot``'s odometry and
    measurements (a cut of its run), its landmarks and its truth."""
    folder.mkdir()
    data = read_mrclam_folder(runs, robot)
    cut = data.odometry[len(data.odometry) // 3:]
    meas = data.measurements[data.measurements[:, 0] >= cut[0, 0]]
    for name, header, rows in (("odometry", "t,v,w", cut),
                               ("measurements", "t,landmark,range,bearing", meas),
                               ("landmarks", "id,x,y", LANDMARKS),
                               ("groundtruth", "t,x,y,theta", data.groundtruth)):  # fmt: skip
        np.savetxt(folder / f"{name}.csv", rows, delimiter=",", header=header, comments="",
                   fmt="%.5f")  # fmt: skip
    return folder


@pytest.mark.heavy
def test_fit_writes_the_measured_noise_at_the_searched_scales(runs, tmp_path, capsys):
    """``config.json`` is the noise measured in the test on the training robot at the
    scales of the least training error, which the search's rows hold; the held-out runs'
    errors are those ``dbntrack track`` with the config's and the fitted noise gives; a
    held-out cut of the training run is named as not held out."""
    copy = _cut_copy(runs, 1, tmp_path / "copy")
    config = {**CONFIG, "robot": 3}  # the held-out MRCLAM folder's robot
    summary, fitted = _fit(tmp_path, "fit", config, runs / "Robot1_Odometry.dat", "--validate",
                           runs, copy)  # fmt: skip
    p = summary["parameters"]
    search = {(r["motion_scale"], r["sensor_scale"]): r["error"] for r in p["search"]}
    assert sorted(search) == [(1, 1), (1, 4), (4, 1), (4, 4)]
    chosen = (p["motion_scale"], p["sensor_scale"])
    assert chosen == min(search, key=search.get) and len(set(search.values())) == 4
    seq = build_sequence(read_mrclam_folder(runs, 1), duration=4.0, dt=0.1)
    measured = robust_noise(pool_residuals([noise_residuals(seq)]))
    assert p["measured"] == pytest.approx(measured)
    bias = p["range_bias_errors"]
    assert bias["measured"] == pytest.approx(search[chosen])
    assert p["range_bias_kept"] == (bias["measured"] <= bias["zero"])
    want = noise_settings({**MRCLAM_NOISE, "range_bias": 0.0, "max_range": 10.0}, measured,
                          *chosen)  # fmt: skip
    want["range_bias"] = measured["range_bias"] if p["range_bias_kept"] else 0.0
    keep = {k: v for k, v in config.items() if k != "search_scales"}
    assert set(fitted) == {*keep, *want}
    for k, v in {**keep, **want}.items():  # lists inside: approx compares flat mappings only
        np.testing.assert_allclose(fitted[k], v, rtol=1e-12, err_msg=k)
    train, held, cut = summary["files"]
    assert [r["split"] for r in summary["files"]] == ["train", "validation", "validation"]
    assert train["error_fitted"] == pytest.approx(min(bias.values()))
    assert train["error_fitted"] == pytest.approx(_track_rmse(tmp_path, runs, 1, fitted, "t"),
                                                  abs=1e-6)  # fmt: skip
    assert held["error_config"] == pytest.approx(_track_rmse(tmp_path, runs, 3, keep, "c"),
                                                 abs=1e-6)  # fmt: skip
    assert held["error_fitted"] == pytest.approx(_track_rmse(tmp_path, runs, 3, fitted, "f"),
                                                 abs=1e-6)  # fmt: skip
    assert summary["metrics"]["error_validation_fitted"] == pytest.approx(
        (held["error_fitted"] + cut["error_fitted"]) / 2)
    assert p["validation_same_recording"] == {str(copy.resolve()): train["file"]}
    assert "copy (Robot1_Odometry.dat)" in capsys.readouterr().out


@pytest.mark.heavy
def test_a_run_without_a_duration_ends_with_its_truth(runs, tmp_path):
    """Without a duration a run ends where its truth does (here 3 s of truth under 7 s of
    odometry); a duration past the truth is refused."""
    cut = tmp_path / "cut"
    shutil.copytree(runs, cut)
    gt = read_mrclam_folder(runs, 1).groundtruth
    np.savetxt(cut / "Robot1_Groundtruth.dat", gt[gt[:, 0] <= 103.0], fmt="%.5f")
    config = {"num_particles": 20, "search_scales": [1]}
    summary, _ = _fit(tmp_path, "fit", config, cut / "Robot1_Odometry.dat")
    assert [r["steps"] for r in summary["files"]] == [29]  # 100 .. 102.9 in steps of 0.1 s
    cfg = tmp_path / "c.json"
    cfg.write_text(json.dumps({**config, "duration": 4.0}))
    assert main(["fit", "localization", str(cut / "Robot1_Odometry.dat"), "--config", str(cfg),
                 "-o", str(tmp_path / "o"), "--quiet"]) == 2  # fmt: skip


@pytest.mark.heavy
def test_a_range_bias_ten_times_the_noise_is_kept(tmp_path, capsys):
    """Robots whose ranges read 0.5 m long (noise 0.05 m): the bias is measured and kept,
    the filter without it doing worse on the training runs, and the report says so."""
    (tmp_path / "biased").mkdir()
    folder = _folder(tmp_path / "biased", bias=0.5)
    config = {**CONFIG, "search_scales": [2]}
    summary, fitted = _fit(tmp_path, "fit", config, folder / "Robot1_Odometry.dat",
                           folder / "Robot2_Odometry.dat")  # fmt: skip
    p = summary["parameters"]
    assert p["range_bias_kept"] and fitted["range_bias"] == pytest.approx(0.5, abs=0.02)
    assert p["range_bias_errors"]["zero"] > p["range_bias_errors"]["measured"]
    assert "kept the range bias" in capsys.readouterr().out


def test_a_bias_the_filter_does_worse_with_is_dropped(runs, tmp_path, capsys, monkeypatch):
    """Where the training runs' error is less without the range bias (here a stand-in error:
    0.1 m without, 0.2 m with), config.json has range_bias 0, the training run's fitted
    error is the one without, and the report says the bias was dropped."""
    monkeypatch.setattr(localization_fit, "_rmse",
                        lambda seq, noise, opts, keys: 0.2 if noise["range_bias"] else 0.1)
    summary, fitted = _fit(tmp_path, "fit", CONFIG, runs / "Robot1_Odometry.dat")
    p = summary["parameters"]
    assert p["measured"]["range_bias"] > 0.01  # the SIMULATED bias, 0.03 m
    assert not p["range_bias_kept"] and fitted["range_bias"] == 0.0
    assert p["range_bias_errors"] == {"measured": 0.2, "zero": 0.1}
    assert summary["files"][0]["error_fitted"] == 0.1
    assert "dropped the range bias" in capsys.readouterr().out


def test_keeps_bias_compares_mean_training_errors():
    """The measured bias stays on a tie or a lower mean error, goes on a higher one; runs
    that differ between the two are refused."""
    assert keeps_bias({"a": 0.1, "b": 0.3}, {"a": 0.3, "b": 0.1})
    assert keeps_bias({"a": 0.1, "b": 0.3}, {"a": 0.25, "b": 0.2})
    assert not keeps_bias({"a": 0.1, "b": 0.3}, {"a": 0.3, "b": 0.05})
    for unbiased in ({"a": 0.3}, {"a": 0.3, "c": 0.1}):
        with pytest.raises(ValueError, match="same training runs"):
            keeps_bias({"a": 0.1, "b": 0.3}, unbiased)
    with pytest.raises(ValueError, match="same training runs"):
        keeps_bias({}, {})


@pytest.mark.parametrize("algorithm", ["apf", pytest.param("sir", marks=pytest.mark.heavy)])
def test_the_fit_scores_the_poses_the_protocol_run_gives(runs, algorithm):
    """The fit's one-scan filter (:func:`scan_means`) gives, from the same key, the poses of
    the registry's tracker stepped through the protocol (:func:`filter_means`, what
    ``dbntrack track`` runs); a bad filter setting is a ConfigError either way."""
    opts = run_options({"duration": 4.0, "num_particles": 100, "algorithm": algorithm})
    seq = run_sequence(read_mrclam_folder(runs, 2), runs / "Robot2_Odometry.dat", opts)[0]
    scanned = scan_means(seq, opts, jax.random.key(0))
    stepped = filter_means(seq, opts, jax.random.key(0))
    np.testing.assert_allclose(scanned, stepped, rtol=0, atol=1e-9)
    assert np.abs(scan_means(seq, opts, jax.random.key(1)) - stepped).max() > 1e-6
    for bad in ({"num_particles": 0}, {"algorithm": "ukf"}):
        for means in (filter_means, scan_means):
            with pytest.raises(ConfigError, match=next(iter(bad))):
                means(seq, {**opts, **bad}, jax.random.key(0))


def test_refusals_name_the_run_or_option(runs, tmp_path, capsys):
    plain = tmp_path / "plain"
    shutil.copytree(runs, plain)
    (plain / "Robot3_Groundtruth.dat").unlink()
    cfg = tmp_path / "c.json"
    cfg.write_text(json.dumps(CONFIG))
    train = str(runs / "Robot1_Odometry.dat")
    base = ["fit", "localization", train, "--config", str(cfg), "-o", str(tmp_path / "o")]
    _bad(capsys, [*base, "--validate", str(plain / "Robot3_Odometry.dat")],
         "Robot3_Odometry.dat", "no ground truth", "fit needs each run's truth")  # fmt: skip
    _bad(capsys, [*base, "--validate", str(runs / "Robot1_Measurement.dat")],
         "Robot1_Measurement.dat", "expected a robot's MRCLAM odometry file")  # fmt: skip
    _bad(capsys, [*base, "--prior-strength", "1"], "no prior strength")
    _bad(capsys, ["fit", "localization", train, str(runs / "Robot2_Odometry.dat"),
                  *base[3:], "--folds", "2"], "--folds")  # fmt: skip
    _bad(capsys, [*base, "--validate", train], "given twice")
    for bad, key in (({"search_scales": [1, 1]}, "search_scales"),
                     ({"search_scales": [0, 2]}, "search_scales"),
                     ({"initial_pose": [0, 0, 0]}, "initial_pose"),
                     ({"sigma_range": -1}, "sigma_range")):  # fmt: skip
        cfg.write_text(json.dumps({**CONFIG, **bad}))
        _bad(capsys, base, key)
