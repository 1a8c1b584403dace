"""``dbntrack fit pathrecovery``: the default weighting's ``sharpness`` and
``hidden_likelihood`` searched by the path score on runs whose true path is known
(``models.track.pathrecovery_fit``), written as a config ``dbntrack track pathrecovery``
runs. The runs are SIMULATED scenes (``models.pathrecovery.simulate``) written by
``models.io.pathrecovery.write_scene``."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from models.cli import main
from models.io.pathrecovery import read_network, read_observations, read_path, write_scene
from models.pathrecovery.fit import count_moves, fitted_network, pool_moves
from models.pathrecovery.simulate import manhattan_grid, simulate_scene
from tests.cli.test_cli_track import _bad, _fitted

DATA = Path(__file__).resolve().parents[1] / "data" / "pathrecovery"
GRID = {"search_sharpness": [1, 3], "search_hidden_likelihood": [0.1, 0.3]}  # not the default
CONFIG = {"num_particles": 100, **GRID}


@pytest.fixture(scope="module")
def runs(tmp_path_factory) -> dict[int, Path]:
    """Four SIMULATED scenes on one 2 x 2 grid of street blocks (seeds 3-6): 60 walkers,
    20 steps, confusion measure 0.4, each written as a run folder."""
    root = tmp_path_factory.mktemp("runs")
    net = manhattan_grid(5, 2, 2, block=(2, 2))
    return {s: write_scene(root / f"scene{s}", simulate_scene(s, net, num_objects=60,
                                                              num_timesteps=20, cm=0.4))
            for s in (3, 4, 5, 6)}  # fmt: skip


def _fit(tmp_path: Path, out: str, config: dict, *argv) -> tuple[dict, dict]:
    """``dbntrack fit pathrecovery ARGV --config CONFIG -o tmp/OUT``: (summary,
    config.json)."""
    path = tmp_path / f"{out}.json"
    path.write_text(json.dumps(config))
    return _fitted(tmp_path, "pathrecovery", out, *argv, "--config", path)


def _track_error(tmp_path: Path, run: Path, config: dict, out: str, seed: int = 0,
                 edges: Path | None = None) -> float:
    """1 - the path score ``dbntrack track pathrecovery --config --truth`` gives (with the
    run's ``edges.csv`` or ``edges``), the target started at its true observation at
    t = 0."""
    start = read_path(run / "truth_path.csv")[0][3]
    path = tmp_path / f"{out}.json"
    path.write_text(json.dumps({**config, "target_obs": start}))
    assert main(["track", "pathrecovery", str(edges or run / "edges.csv"),
                 str(run / "observations.csv"),
                 "--config", str(path), "--truth", str(run / "truth_path.csv"),
                 "-o", str(tmp_path / out), "--seed", str(seed), "--quiet"]) == 0  # fmt: skip
    return 1.0 - json.loads((tmp_path / out / "summary.json").read_text())["metrics"]["path_score"]


def _moves(net, run: Path):
    """The moves of a run folder's objects (``models.pathrecovery.fit.count_moves``)."""
    odb = read_observations(run / "observations.csv")
    steps = np.repeat(np.arange(odb.time_ptr.size - 1), np.diff(odb.time_ptr))
    return count_moves(net, steps, odb.cam, odb.obj)


def test_write_scene_reads_back(runs):
    """A written scene is the scene: its network, observations and true path."""
    net = manhattan_grid(5, 2, 2, block=(2, 2))
    scene = simulate_scene(3, net, num_objects=60, num_timesteps=20, cm=0.4)
    back = read_network(runs[3] / "edges.csv", runs[3] / "cameras.csv")
    for name in ("indptr", "indices", "probs", "gap_mean", "coords"):
        np.testing.assert_array_equal(getattr(back, name), getattr(net, name), err_msg=name)
    odb = read_observations(runs[3] / "observations.csv")
    np.testing.assert_array_equal(odb.time_ptr, scene.odb.time_ptr)
    np.testing.assert_array_equal(odb.cam, scene.odb.cam)
    np.testing.assert_array_equal(odb.feat, scene.odb.feat)
    truth = read_path(runs[3] / "truth_path.csv")
    assert sorted(truth) == list(range(20))
    got = np.array([truth[t] for t in range(20)])
    np.testing.assert_array_equal(got[:, 0], scene.true_ta > 0)
    np.testing.assert_array_equal(got[:, 1:], np.column_stack(
        [scene.true_cam, scene.true_ta, scene.true_obs]))


# ~9 s (the fit's ties, refusals and network stay in the default run): CI runs it
@pytest.mark.heavy
def test_fit_keeps_the_least_training_error_and_scores_as_track_and_eval(runs, tmp_path, capsys):
    """``edges.csv`` is the network counted from the training runs' objects, ``config.json``
    the config with the pair of the least mean training error; each run's errors are those
    ``dbntrack track --config --truth`` gives with its own network and the config's
    settings and with the fitted (mean over the seeds); a held-out copy of a training run
    is named as not held out, whatever its observations' ids."""
    copy = _renumbered_copy(runs[3], tmp_path / "copy")
    summary, fitted = _fit(tmp_path, "fit", {**CONFIG, "fit_network": True}, runs[3], runs[4],
                           "--validate", runs[5], copy, "--seeds", "2")  # fmt: skip
    net = read_network(runs[3] / "edges.csv")
    want = fitted_network(net, pool_moves([_moves(net, runs[3]), _moves(net, runs[4])]))
    got = read_network(tmp_path / "fit" / "edges.csv")
    np.testing.assert_array_equal(got.indices, net.indices)
    np.testing.assert_allclose(got.probs, want.probs, rtol=1e-12)
    np.testing.assert_allclose(got.gap_mean, want.gap_mean, rtol=1e-12)
    assert np.abs(got.probs - net.probs).max() > 0.01  # counted, not the runs' own
    p = summary["parameters"]
    search = {(r["sharpness"], r["hidden_likelihood"]): r["error"] for r in p["search"]}
    assert sorted(search) == [(1, 0.1), (1, 0.3), (3, 0.1), (3, 0.3)]
    chosen = (p["sharpness"], p["hidden_likelihood"])
    assert search[chosen] == min(search.values()) and len(set(search.values())) > 1
    assert fitted == {"num_particles": 100, "sharpness": chosen[0],
                      "hidden_likelihood": chosen[1]}  # fmt: skip
    rows = {Path(r["file"]).name: r for r in summary["files"]}
    assert [r["split"] for r in summary["files"]] == ["train", "train", "validation",
                                                      "validation"]  # fmt: skip
    plain = {"num_particles": 100}
    for name, run in (("scene3", runs[3]), ("scene4", runs[4]), ("scene5", runs[5])):
        for which, config, edges in (("config", plain, None),
                                     ("fitted", fitted, tmp_path / "fit" / "edges.csv")):
            want = np.mean([_track_error(tmp_path, run, config, f"{name}{which}{s}", s, edges)
                            for s in (0, 1)])  # fmt: skip
            assert rows[name][f"error_{which}"] == pytest.approx(want, abs=1e-12), (name, which)
    assert np.mean([rows["scene3"]["error_fitted"], rows["scene4"]["error_fitted"]]) == \
        pytest.approx(search[chosen])
    assert rows["scene5"]["hidden_steps"] == sum(
        v[0] == 1 for v in read_path(runs[5] / "truth_path.csv").values())
    assert p["validation_same_recording"] == {str(copy.resolve()): rows["scene3"]["file"]}
    assert "copy (scene3)" in capsys.readouterr().out


def test_ties_keep_the_config_pair_else_the_smallest(tmp_path, capsys):
    """On the tiny example every pair recovers the whole path: the config's pair is kept
    where the grid holds it, else the least sharpness and hidden likelihood; a choice at
    the grid's edge is reported."""
    config = {"sharpness": 4, "hidden_likelihood": 0.3, "sigma": np.eye(4).tolist(),
              "search_sharpness": [3, 4, 5], "search_hidden_likelihood": [0.3, 0.4]}
    summary, fitted = _fit(tmp_path, "own", config, DATA)
    assert not summary["parameters"]["network"]["fitted"]  # by default
    kept, given = (read_network(f) for f in (tmp_path / "own" / "edges.csv", DATA / "edges.csv"))
    for name in ("indptr", "indices", "probs", "gap_mean"):
        np.testing.assert_array_equal(getattr(kept, name), getattr(given, name))
    assert {r["error"] for r in summary["parameters"]["search"]} == {0.0}  # all tie
    assert (fitted["sharpness"], fitted["hidden_likelihood"]) == (4, 0.3)
    assert fitted["sigma"] == config["sigma"]
    assert summary["parameters"]["on_edge"] == ["search_hidden_likelihood"]
    assert "edge of config search_hidden_likelihood" in capsys.readouterr().out
    summary, fitted = _fit(tmp_path, "other", {**config, "search_sharpness": [6, 5]}, DATA)
    assert (fitted["sharpness"], fitted["hidden_likelihood"]) == (5, 0.3)
    assert summary["parameters"]["on_edge"] == ["search_sharpness", "search_hidden_likelihood"]


def test_the_network_is_kept_without_objects_or_refused_when_runs_differ(runs, tmp_path, capsys):
    """``fit_network`` asks for the objects of every training run (else the runs' network is
    kept and the summary says why); runs of different networks are refused."""
    bare = shutil.copytree(runs[4], tmp_path / "bare")
    lines = (bare / "observations.csv").read_text().splitlines()
    (bare / "observations.csv").write_text("\n".join(line.rsplit(",", 1)[0] for line in lines)
                                           + "\n")  # fmt: skip
    config = {**CONFIG, "fit_network": True, "search_sharpness": [6],
              "search_hidden_likelihood": [0.5]}  # fmt: skip
    summary, _ = _fit(tmp_path, "kept", config, runs[3], bare)
    network = summary["parameters"]["network"]
    assert not network["fitted"] and str(bare / "observations.csv") in network["why_not"]
    assert "no object column" in capsys.readouterr().out
    other = shutil.copytree(runs[5], tmp_path / "other")
    edges = (other / "edges.csv").read_text().splitlines()
    a, b, prob, gap = edges[1].split(",")
    c, d, prob2, gap2 = edges[2].split(",")
    edges[1:3] = [f"{a},{b},{prob2},{gap}", f"{c},{d},{prob},{gap2}"]  # still sums to 1
    (other / "edges.csv").write_text("\n".join(edges) + "\n")
    cfg = tmp_path / "c.json"
    cfg.write_text(json.dumps(config))
    _bad(capsys, ["fit", "pathrecovery", str(runs[3]), "--validate", str(other), "--config",
                  str(cfg), "-o", str(tmp_path / "o")], "other/edges.csv",
         "not the network of", "share one camera network")  # fmt: skip
    twice = shutil.copytree(runs[4], tmp_path / "twice")
    lines = (twice / "observations.csv").read_text().splitlines()
    first = lines[1].split(",")  # obs 0 at t = 0; its object seen once more at t = 0
    again = ",".join(["99999", *first[1:]])
    (twice / "observations.csv").write_text("\n".join([*lines, again]) + "\n")
    _bad(capsys, ["fit", "pathrecovery", str(runs[3]), str(twice), "--config", str(cfg),
                  "-o", str(tmp_path / "o")], "twice/observations.csv",
         f"object {first[-1]} is observed twice at t = 0")  # fmt: skip


def _renumbered_copy(run: Path, folder: Path) -> Path:
    """A copy of ``run`` whose observation ids are 1000 more (in its true path too)."""
    shutil.copytree(run, folder)
    for name, column in (("observations.csv", 0), ("truth_path.csv", 4)):
        lines = (folder / name).read_text().splitlines()
        rows = [line.split(",") for line in lines[1:]]
        for r in rows:
            r[column] = str(int(r[column]) + 1000 if int(r[column]) >= 0 else -1)
        (folder / name).write_text("\n".join([lines[0], *map(",".join, rows)]) + "\n")
    return folder


def _edited_run(runs: dict, tmp_path: Path, name: str, rows) -> Path:
    """A copy of scene 3 whose true path keeps the data rows ``rows`` selects."""
    run = shutil.copytree(runs[3], tmp_path / name)
    lines = (run / "truth_path.csv").read_text().splitlines()
    (run / "truth_path.csv").write_text("\n".join([lines[0], *rows(lines[1:])]) + "\n")
    return run


def test_refusals_name_the_run_or_option(runs, tmp_path, capsys):
    cfg = tmp_path / "c.json"
    cfg.write_text(json.dumps(CONFIG))
    base = ["fit", "pathrecovery", str(runs[3]), "--config", str(cfg), "-o", str(tmp_path / "o")]
    bare = shutil.copytree(runs[4], tmp_path / "bare")
    (bare / "truth_path.csv").unlink()
    _bad(capsys, [*base, "--validate", str(bare)], "bare", "no truth_path.csv")
    _bad(capsys, [*base, "--validate", str(runs[4] / "edges.csv")], "expected a run folder")
    short = _edited_run(runs, tmp_path, "short", lambda r: r[:-1])
    _bad(capsys, [*base, "--validate", str(short)], "truth_path.csv", "t = 0 .. 18",
         "every step")  # fmt: skip
    unseen = _edited_run(runs, tmp_path, "unseen",
                         lambda r: ["0,hidden,1,1,-1", *r[1:]])  # fmt: skip
    _bad(capsys, [*base, "--validate", str(unseen)], "unseen", "not seen at t = 0")
    late = _edited_run(runs, tmp_path, "late",
                       lambda r: [r[0].rsplit(",", 1)[0] + ",99999", *r[1:]])  # fmt: skip
    _bad(capsys, [*base, "--validate", str(late)], "late", "truth_path.csv", "no such obs")
    _bad(capsys, [*base, "--prior-strength", "1"], "no prior strength")
    _bad(capsys, ["fit", "pathrecovery", str(runs[3]), str(runs[4]), *base[3:], "--folds", "2"],
         "--folds")  # fmt: skip
    _bad(capsys, [*base, "--validate", str(runs[3])], "given twice")
    for bad, key in (({"search_sharpness": [1, 1]}, "search_sharpness"),
                     ({"search_sharpness": [0, 2]}, "search_sharpness"),
                     ({"search_sharpness": []}, "search_sharpness"),
                     ({"search_hidden_likelihood": [0.5, 1.5]}, "search_hidden_likelihood"),
                     ({"target_obs": 3}, "target_obs"),
                     ({"c0": 1, "f0": [0, 0, 0, 0]}, "c0"),
                     ({"faithful": True}, "faithful"),
                     ({"sharpness": -1}, "sharpness"),
                     ({"search_alpha": [1]}, "search_alpha"),
                     ({"fit_network": "yes"}, "fit_network")):  # fmt: skip
        cfg.write_text(json.dumps({**CONFIG, **bad}))
        _bad(capsys, base, key)
