"""``dbntrack fit jorge``: the label network's parameters fitted on your files
(``models.track.jorge_fit``), written as a config ``dbntrack track jorge`` runs."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from dbn.errors import InputError
from models.cli import main
from models.io.jorge import read_strokes
from models.io.jorge_regions import write_regions
from models.jorge.fit import EventCounts, count_events, fit_counts, fit_parameters, fitted_like
from models.jorge.network import NetworkConfig
from models.jorge.online import OnlineConfig, label_online
from models.jorge.scoring import score, true_links
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
    _bad(capsys, ["fit", "localization", str(plain), "-o", str(out)],
         "'localization' has no fit; trackers with one: jorge")  # fmt: skip
    from models.track.context import RunContext
    from models.track.jorge_fit import fit

    with pytest.raises(InputError, match=r"prior strength -1.0: expected a finite number >= 0"):
        fit(RunContext("jorge", out, 0, quiet=True), [str(XML)], [], {}, 1, -1.0)
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
    for bad in ("-1", "inf", "x"):
        with pytest.raises(SystemExit):
            main(["fit", "jorge", str(XML), "-o", str(tmp_path / "b"), "--prior-strength", bad])
        assert "--prior-strength" in capsys.readouterr().err
