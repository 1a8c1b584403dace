"""``dbntrack fit jorge``: the label network's parameters fitted on your files
(``models.track.jorge_fit``), written as a config ``dbntrack track jorge`` runs."""

from __future__ import annotations

import json
import xml.etree.ElementTree as ET
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from dbn.errors import InputError
from models.cli import main
from models.io.jorge import read_strokes
from models.io.jorge_regions import write_regions
from models.jorge.fit import EventCounts, count_events, fit_counts, fit_parameters, fitted_like
from models.jorge.fit_prior import shrink
from models.jorge.network import NetworkConfig
from models.jorge.online import OnlineConfig, label_online
from models.jorge.scoring import group_errors, score, true_links
from models.jorge.strokes import build_strokes, load_caviar
from models.track.jorge import LABELLER_KEYS, labeller_config
from tests.cli.test_cli_track import _bad

DATA = Path(__file__).resolve().parent.parent / "data"
XML = DATA / "jorge" / "caviar.xml"


def _fit(tmp_path: Path, name: str, *argv: str) -> tuple[dict, dict]:
    """``dbntrack fit jorge ARGV -o tmp/NAME``: (summary, config.json)."""
    out = tmp_path / name
    assert main(["fit", "jorge", *argv, "-o", str(out), "--quiet"]) == 0
    assert (out / "fit.png").is_file()
    return (json.loads((out / "summary.json").read_text()),
            json.loads((out / "config.json").read_text()))


def _network(config: dict) -> NetworkConfig:
    """The labeller's network a config sets (as ``dbntrack track jorge`` builds it)."""
    over = {k: config[k] for k in LABELLER_KEYS if k in config}
    return labeller_config(config.get("split_cover", True), over).network


def test_fit_writes_the_fitted_network_and_track_runs_it(tmp_path, capsys):
    """The config written holds exactly the network the API fits on the same SIMULATED
    strokes (seeds 5 and 6), its other keys kept; `dbntrack track --config` labels with
    it; the summary's errors are those of label_online with each network."""
    cfg = tmp_path / "cfg.json"
    cfg.write_text('{"gaps_per_100": 20.0, "network": {"max_gap_frames": 40}}')
    held = write_regions(tmp_path / "held.jsonl", build_strokes(9, load_caviar(XML)), fps=25.0)
    summary, written = _fit(tmp_path, "fit", str(XML), "--validate", str(held), "--seed", "5",
                            "--seeds", "2", "--config", str(cfg))  # fmt: skip
    base = labeller_config(overrides={"network": {"max_gap_frames": 40}}).network
    from models.jorge.strokes import StrokeConfig

    sets = [build_strokes(s, load_caviar(XML), StrokeConfig(gaps_per_100=20.0)) for s in (5, 6)]
    want = fitted_like(base, fit_parameters(sets, base))
    assert _network(written) == want != base
    assert written["gaps_per_100"] == 20.0 and written["network"]["max_gap_frames"] == 40
    assert written["labels"]["p_new"] == want.labels.p_new
    assert summary["parameters"]["training_strokes"] == sum(len(s) for s in sets)
    rows = {Path(r["file"]).name: r for r in summary["files"]}
    assert rows["caviar.xml"]["split"] == "train" and rows["held.jsonl"]["split"] == "validation"
    strokes = build_strokes(9, load_caviar(XML))
    for name, net in (("config", base), ("fitted", want)):
        err = score(strokes, label_online(strokes, OnlineConfig(network=net)).labels).error_rate
        assert rows["held.jsonl"][f"error_{name}"] == err
        assert summary["metrics"][f"error_validation_{name}"] == err
    assert "held.jsonl: " in capsys.readouterr().out
    out = tmp_path / "run"
    conf = tmp_path / "fitted.json"
    conf.write_text(json.dumps({k: v for k, v in written.items() if k != "gaps_per_100"}))
    argv = ["track", "jorge", str(held), "-o", str(out), "--config", str(conf), "--quiet"]
    assert main(argv) == 0
    _, got = read_strokes(out / "strokes.csv")
    want_labels = label_online(strokes, OnlineConfig(network=want)).labels
    assert [r["label"] for r in got] == list(want_labels)


def test_fit_counts_a_regions_files_own_links(tmp_path):
    """A regions file's links, not the rule's, are the ones fitted on."""
    strokes = build_strokes(3, load_caviar(XML))
    links = [tuple(p) for p in true_links(strokes)]
    links[next(k for k, p in enumerate(links) if p)] = ()  # one link dropped
    path = write_regions(tmp_path / "linked.jsonl", strokes, links, fps=25.0)
    _, written = _fit(tmp_path, "fit", str(path))
    base = labeller_config().network
    by_file = fit_counts(count_events(strokes, base, EventCounts(), links=links, fps=25.0), base)
    by_rule = fit_parameters([strokes], base)
    assert _network(written) == fitted_like(base, by_file) != fitted_like(base, by_rule)


def test_fit_keeps_what_the_config_switched_off(tmp_path):
    cfg = tmp_path / "cfg.json"
    cfg.write_text('{"labels": {"max_group_size": 4, "p_join": 0.0}, "split_cover": false,'
                   ' "network": {"palette_missing_table": []}}')
    _, written = _fit(tmp_path, "fit", str(XML), "--config", str(cfg))
    net = _network(written)
    assert net.palette_missing_table == () and net.palette_count_table == ()
    assert net.palette_gain_table != NetworkConfig().palette_gain_table  # refitted
    assert net.labels.max_group_size == 4 and len(net.labels.new_group_probs) == 4
    assert net.labels.p_join == 0.0 and net.labels.split_cover == ()
    assert written["split_cover"] is False


def test_fit_refusals(tmp_path, capsys):
    strokes = build_strokes(3, load_caviar(XML))
    plain = write_regions(tmp_path / "plain.jsonl", strokes, fps=25.0)
    lines = plain.read_text().splitlines()
    obj = json.loads(lines[3])
    del obj["truth"]
    nameless = tmp_path / "nameless.jsonl"
    nameless.write_text("\n".join([*lines[:3], json.dumps(obj), *lines[4:]]) + "\n")
    out = tmp_path / "out"
    _bad(capsys, ["fit", "jorge", str(nameless), "-o", str(out)],
         "nameless.jsonl:4: stroke 2 has no truth: fitting needs")  # fmt: skip
    _bad(capsys, ["fit", "jorge", str(plain), "--validate", str(tmp_path / "." / "plain.jsonl"),
                  "-o", str(out)], "given twice", "must not be a training file")  # fmt: skip
    lonely = tmp_path / "lonely.jsonl"
    lonely.write_text(lines[0] + "\n" + lines[1] + "\n")
    _bad(capsys, ["fit", "jorge", str(lonely), "-o", str(out)], "has a parent", "nothing to fit")
    cfg = tmp_path / "cfg.json"
    for text, needles in (
            ('{"gap_min": 3}', ("cfg.json", "['gap_min']", "every file is a regions")),
            ('{"network": {"size_sigma": -1.0}}', ("cfg.json", "size_sigma")),
            ('{"nope": 1}', ("cfg.json", "unknown config key(s) ['nope']"))):
        cfg.write_text(text)
        _bad(capsys, ["fit", "jorge", str(plain), "-o", str(out), "--config", str(cfg)], *needles)
    _bad(capsys, ["fit", "rjmcmc3d", str(plain), "-o", str(out)],
         "'rjmcmc3d' has no fit; trackers with one: localization, zajdel_adf, "
         "zajdel_learnsearch, pathrecovery, jorge")  # fmt: skip
    from models.track.context import RunContext
    from models.track.jorge_fit import fit

    with pytest.raises(InputError, match=r"prior strength -1.0: expected a number >= 0 \(or inf"):
        fit(RunContext("jorge", out, 0, quiet=True), [str(XML)], [], {}, 1, -1.0)
    with pytest.raises(InputError, match=r"prior strength np.complex128\(2\+1j\): expected a number"):
        fit(RunContext("jorge", out, 0, quiet=True), [str(XML)], [], {}, 1, np.complex128(2 + 1j))
    assert not (out / "config.json").exists() and not (out / "summary.json").exists()
    with pytest.raises(SystemExit):  # argparse: usage and exit status 2
        main(["fit", "jorge", str(XML), "-o", str(out), "--seeds", "0"])
    assert "--seeds: 0 is not >= 1" in capsys.readouterr().err



def test_a_prior_strength_shrinks_the_fit_towards_the_configs_network(tmp_path, capsys):
    plain_summary, plain = _fit(tmp_path, "plain", str(XML))
    summary, strong = _fit(tmp_path, "strong", str(XML), "--prior-strength", "1e12")
    base = labeller_config().network
    assert plain_summary["prior_strength"] == 0.0 and summary["prior_strength"] == 1e12
    assert summary["parameters"]["prior_strength"] == 1e12
    for name in ("p_new", "p_join", "p_part"):
        assert getattr(_network(strong).labels, name) == pytest.approx(getattr(base.labels, name))
        assert getattr(_network(plain).labels, name) != pytest.approx(getattr(base.labels, name))
    for bad in ("-1", "nan", "x", "1,,2"):
        with pytest.raises(SystemExit):
            main(["fit", "jorge", str(XML), "-o", str(tmp_path / "b"), "--prior-strength", bad])
        assert "--prior-strength" in capsys.readouterr().err
    summary, limit = _fit(tmp_path, "limit", str(XML), "--prior-strength", "inf")
    assert _network(limit) == base  # the prior itself: the size likelihood too
    assert summary["prior_strength"] == summary["parameters"]["prior_strength"] == "inf"
    assert summary["metrics"]["error_train_fitted"] == summary["metrics"]["error_train_config"]


def _noisy(seed: int) -> list:
    """The SIMULATED strokes of the tiny CAVIAR file, each with its noisy colours as its
    palette (where the default palette tables, fitted on clean palettes, mislead)."""
    return [replace(s, palette=s.colours) for s in build_strokes(seed, load_caviar(XML))]


def _cv_files(tmp_path: Path, seeds) -> list[Path]:
    """Regions files of :func:`_noisy` strokes, one per seed."""
    return [write_regions(tmp_path / f"s{s}.jsonl", _noisy(s), fps=25.0) for s in seeds]


def _fitted_on(stroke_sets: list, lam: float) -> NetworkConfig:
    """The default network fitted on ``stroke_sets`` (25 fps) with prior strength ``lam``,
    with the API (inf: the default network)."""
    base = labeller_config().network
    c = EventCounts()
    for strokes in stroke_sets:
        count_events(strokes, base, c, fps=25.0)
    return base if lam == np.inf else fitted_like(base, shrink(fit_counts(c, base), base, c, lam))


def _error_of(network: NetworkConfig, strokes: list) -> float:
    """The error rate of the on-line labeller with ``network`` on ``strokes`` (25 fps)."""
    labels = label_online(strokes, OnlineConfig(network=network), fps=25.0).labels
    return score(strokes, labels).error_rate


def test_cross_validation_chooses_the_prior_strength(tmp_path, capsys):
    """Each training file's error is that of the fit on the other folds (recomputed with
    the API); the strength with the lowest mean (here the third given) is chosen and
    fitted on every file; the prior itself (inf) errs as the config's network."""
    seeds = (3, 4, 5, 6)
    files = _cv_files(tmp_path, seeds)
    held = write_regions(tmp_path / "held.jsonl", _noisy(9), fps=25.0)
    summary, written = _fit(tmp_path, "cv", *map(str, files), "--validate", str(held),
                            "--folds", "2", "--prior-strength", "inf,1e12,0")  # fmt: skip
    sets = {f.name: _noisy(s) for f, s in zip(files, seeds)}

    def fitted(names, lam):
        return _fitted_on([sets[n] for n in names], lam)

    def error(net, name):
        return _error_of(net, sets[name])

    cv = summary["parameters"]["cross_validation"]
    assert cv["folds"] == [[str(f.resolve()) for f in fold] for fold in (files[:2], files[2:])]
    cv["folds"] = [[Path(f).name for f in fold] for fold in cv["folds"]]
    rows = {Path(r["file"]).name: r for r in summary["files"]}
    want = {}
    for lam in (np.inf, 1e12, 0.0):
        per = {n: error(fitted([m for f in cv["folds"] if n not in f for m in f], lam), n)
               for n in sets}  # fmt: skip
        want[lam] = per
    for lam, per in want.items():  # each strength's mean, and its difference from the choice
        diff = [per[n] - want[0.0][n] for n in sets]
        row = next(r for r in cv["errors"] if r["prior_strength"] == ("inf" if lam == np.inf
                                                                       else lam))  # fmt: skip
        assert row == {"prior_strength": row["prior_strength"],
                       "error": pytest.approx(np.mean(list(per.values()))),
                       "versus_chosen": pytest.approx(np.mean(diff)),
                       "versus_chosen_se": pytest.approx(np.std(diff, ddof=1) / 2)}
    assert want[np.inf] == {n: rows[n]["error_config"] for n in sets}
    means = {lam: np.mean(list(per.values())) for lam, per in want.items()}
    assert means[0.0] < min(means[1e12], means[np.inf])  # the noisy palettes: the fit helps
    assert cv["chosen"] == summary["parameters"]["prior_strength"] == 0.0
    assert {n: rows[n]["error_cv"] for n in sets} == want[0.0]
    assert "error_cv" not in rows["held.jsonl"]
    assert summary["metrics"]["error_cv_fitted"] == pytest.approx(means[0.0])
    assert _network(written) == fitted(list(sets), 0.0)
    assert summary["prior_strength"] == ["inf", 1e12, 0.0] and summary["folds"] == 2
    assert "2-fold cross-validation error by prior strength: inf: " in capsys.readouterr().out


def test_fold_by_keeps_a_recordings_files_in_one_fold(tmp_path, capsys):
    """Files given out of order: ``--fold-by`` puts each recording's files in one fold,
    and each file is scored by the fit on the other recording's files alone; a held-out
    file of a training recording is named."""
    named = {"recA_3.jsonl": 3, "recB_4.jsonl": 4, "recA_5.jsonl": 5, "recB_6.jsonl": 6}
    files = [write_regions(tmp_path / n, _noisy(s), fps=25.0) for n, s in named.items()]
    held = [write_regions(tmp_path / n, _noisy(s), fps=25.0)
            for n, s in (("recA_9.jsonl", 9), ("recC_7.jsonl", 7), ("other.jsonl", 8))]
    summary, _ = _fit(tmp_path, "grouped", *map(str, files), "--folds", "2",
                      "--fold-by", r"rec(\w)_", "--validate", *map(str, held))  # fmt: skip
    assert summary["parameters"]["validation_of_training_recordings"] == [str(held[0].resolve())]
    assert "training files hold too (--fold-by): recA_9.jsonl: their errors" in \
        capsys.readouterr().out
    cv = summary["parameters"]["cross_validation"]
    assert [[Path(f).name for f in fold] for fold in cv["folds"]] == [
        ["recA_3.jsonl", "recA_5.jsonl"], ["recB_4.jsonl", "recB_6.jsonl"]]
    assert summary["fold_by"] == summary["parameters"]["fold_by"] == r"rec(\w)_"
    rows = {Path(r["file"]).name: r for r in summary["files"]}
    for name, other in (("recA_3.jsonl", "B"), ("recB_6.jsonl", "A")):
        net = _fitted_on([_noisy(s) for n, s in named.items() if n.startswith(f"rec{other}")],
                         0.0)  # fmt: skip
        assert rows[name]["error_cv"] == _error_of(net, _noisy(named[name]))


def test_files_of_one_name_are_shown_by_their_folders(tmp_path, capsys):
    (tmp_path / "r1").mkdir(), (tmp_path / "r2").mkdir()
    files = [str(write_regions(tmp_path / r / "gt.jsonl", _noisy(s), fps=25.0))
             for r, s in (("r1", 3), ("r2", 4))]
    _fit(tmp_path, "names", *files)
    out = capsys.readouterr().out
    assert "train  r1/gt.jsonl: " in out and "train  r2/gt.jsonl: " in out


@pytest.mark.heavy  # ~12-16 s: 3 files labelled 9 times over; CI runs it (pytest -m heavy)
def test_fit_scores_the_strokes_of_three_and_more_people(tmp_path, capsys):
    """SIMULATED meetings of five: each file's error over its strokes of 3+ people, with
    the config's and the fitted network and (training files, 2 folds) with the fit on the
    other fold, is a recomputation with the API; the means pool those strokes."""
    from models.jorge.fit import meeting_strokes

    sets = {f"meet{s}.jsonl": meeting_strokes((s,), (5,))[0] for s in (701, 704, 705)}
    paths = [str(write_regions(tmp_path / n, ss.strokes, fps=ss.fps)) for n, ss in sets.items()]
    summary, written = _fit(tmp_path, "big", *paths[1:], "--validate", paths[0], "--folds", "2")
    rows = {Path(r["file"]).name: r for r in summary["files"]}
    metrics = summary["metrics"]

    def errors(name, net):
        labels = label_online(sets[name], OnlineConfig(network=net)).labels
        return group_errors(sets[name].strokes, score(sets[name].strokes, labels).errors)

    def pooled(counts):
        return sum(w for w, _ in counts) / sum(n for _, n in counts)

    train, held = ["meet704.jsonl", "meet705.jsonl"], "meet701.jsonl"  # 37 and 28 such strokes
    for which, net in (("config", labeller_config().network), ("fitted", _network(written))):
        counts = {name: errors(name, net) for name in sets}
        for name, (wrong, n) in counts.items():
            assert n > 0 and rows[name]["strokes_group_3plus"] == n
            assert rows[name][f"error_group_3plus_{which}"] == pytest.approx(wrong / n)
        want = pooled([counts[t] for t in train])
        assert metrics[f"error_train_group_3plus_{which}"] == pytest.approx(want)
        want = pooled([counts[held]])
        assert metrics[f"error_validation_group_3plus_{which}"] == pytest.approx(want)
    cv = {a: errors(a, _fitted_on([sets[b].strokes], 0.0)) for a, b in zip(train, train[::-1])}
    for name, (wrong, n) in cv.items():
        assert rows[name]["error_cv_group_3plus"] == pytest.approx(wrong / n)
    assert "error_cv_group_3plus" not in rows[held]
    assert metrics["error_cv_group_3plus_fitted"] == pytest.approx(pooled(list(cv.values())))
    assert "strokes of 3+ people: " in capsys.readouterr().out


def test_cross_validation_refusals(tmp_path, capsys):
    files = [str(f) for f in _cv_files(tmp_path, (3, 4))]
    out = tmp_path / "out"
    _bad(capsys, ["fit", "jorge", *files, "-o", str(out), "--prior-strength", "0,30"],
         "choosing among several needs cross-validation")  # fmt: skip
    _bad(capsys, ["fit", "jorge", *files, "-o", str(out), "--folds", "3"],
         "folds 3: expected an integer from 2 to the number of training files (2)")  # fmt: skip
    _bad(capsys, ["fit", "jorge", *files, "-o", str(out), "--folds", "2", "--prior-strength",
                  "30,30"], "none twice")  # fmt: skip
    lonely = tmp_path / "lonely.jsonl"
    lonely.write_text("\n".join(Path(files[0]).read_text().splitlines()[:2]) + "\n")
    _bad(capsys, ["fit", "jorge", files[0], str(lonely), "-o", str(out), "--folds", "2"],
         f"cross-validation, the fit for the fold of ['{files[0]}']: no stroke of the "
         f"training files ['{lonely}'] has a parent")  # fmt: skip
    for argv, needle in ((["--fold-by", "s"], "they group the folds of a cross-validation"),
                         (["--folds", "2", "--fold-by", "zz"], "fold groups 'zz': no match in"),
                         (["--folds", "2", "--fold-by", "("], "not a regular expression"),
                         (["--folds", "2", "--fold-by", "jsonl"],
                          "number of groups of training files (1)")):
        _bad(capsys, ["fit", "jorge", *files, "-o", str(out), *argv], needle)
    assert not out.exists() or not any(out.iterdir())
    for bad in ("1", "x"):
        with pytest.raises(SystemExit):
            main(["fit", "jorge", *files, "-o", str(out), "--folds", bad])
        assert "--folds" in capsys.readouterr().err


def test_held_out_box_files_of_a_training_recording_are_named(tmp_path, capsys):
    """A held-out cut of a training box file (its first 120 frames) is named as that
    recording; another recording (the same boxes 5 pixels to the right) and a regions
    file are not."""
    root = ET.parse(XML).getroot()
    for box in root.iter("box"):
        box.set("xc", str(float(box.get("xc")) + 5.0))
    ET.ElementTree(root).write(tmp_path / "other.xml")
    root = ET.parse(XML).getroot()
    for frame in [f for f in root.findall("frame") if int(f.get("number")) >= 120]:
        root.remove(frame)
    ET.ElementTree(root).write(tmp_path / "cut.xml")
    held = write_regions(tmp_path / "held.jsonl", build_strokes(9, load_caviar(XML)), fps=25.0)
    summary, _ = _fit(tmp_path, "same", str(XML), "--validate", str(tmp_path / "cut.xml"),
                      str(tmp_path / "other.xml"), str(held))  # fmt: skip
    same = summary["parameters"]["validation_same_recording"]
    assert same == {str((tmp_path / "cut.xml").resolve()): str(XML.resolve())}
    assert "(the same recording, or a cut of it): cut.xml (caviar.xml): their errors" in \
        capsys.readouterr().out
    summary, _ = _fit(tmp_path, "apart", str(XML), "--validate", str(tmp_path / "other.xml"))
    assert summary["parameters"]["validation_same_recording"] == {}


def test_search_grid_runs_every_pair_on_every_training_run(tmp_path):
    """``search_grid``: one call per pair of the two axes and training run, pair by pair in
    the axes' order, each result under its pair and run."""
    from models.track.context import RunContext
    from models.track.fitting import search_grid

    calls = []

    def error(a: float, b: float, run: str) -> float:
        calls.append((a, b, run))
        return 10 * a + b + (0.5 if run == "y" else 0.0)

    ctx = RunContext("localization", tmp_path, 0, quiet=True)
    out = search_grid(ctx, ((1.0, 2.0), (3.0, 4.0, 5.0)), ["x", "y"], error)
    pairs = [(a, b) for a in (1.0, 2.0) for b in (3.0, 4.0, 5.0)]
    assert calls == [(a, b, r) for a, b in pairs for r in ("x", "y")]
    assert list(out) == pairs
    assert out[(2.0, 4.0)] == {"x": 24.0, "y": 24.5}
