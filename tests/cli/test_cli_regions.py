"""Regions files (``models.io.jorge_regions``): your own low-level tracker's strokes for
``dbntrack track jorge`` and ``eval``."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from dbn.errors import FileFormatError
from models.cli import main
from models.io.jorge import read_strokes, read_strokes_header
from models.io.jorge_regions import check_regions, is_regions, read_regions, write_regions
from models.jorge.network import NetworkConfig
from models.jorge.online import label_online
from models.jorge.scoring import score, true_links
from models.jorge.strokes import build_strokes, load_caviar
from tests.cli.test_cli_track import _bad

DATA = Path(__file__).resolve().parent.parent / "data"
XML = DATA / "jorge" / "caviar.xml"


@pytest.fixture(scope="module")
def strokes():
    """SIMULATED strokes of the tiny CAVIAR example (seed 3), at 25 fps."""
    return build_strokes(3, load_caviar(XML))


def test_a_regions_file_reads_back_what_was_written(tmp_path, strokes):
    links = true_links(strokes)
    path = write_regions(tmp_path / "r.jsonl", strokes, links, 25.0)
    assert is_regions(path) and is_regions("a.JSONL.gz") and not is_regions(XML)
    got = read_regions(path)
    assert got.fps == 25.0 and got.has_truth and got.lines == list(range(2, len(strokes) + 2))
    assert got.parents == [tuple(p) for p in links]
    for a, b in zip(got.strokes, strokes):
        assert (a.index, a.start, a.end, a.truth) == (b.index, b.start, b.end, b.truth)
        for name in ("frames", "positions", "colours", "palette", "extent"):
            np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    bare = tmp_path / "bare.jsonl"  # the optional keys left out
    first = json.loads(path.read_text().splitlines()[1])
    bare.write_text(json.dumps({k: first[k] for k in ("frames", "boxes", "colours")}) + "\n")
    (s,) = read_regions(bare).strokes
    assert s.truth == frozenset() and list(s.palette) == list(s.colours)
    assert read_regions(bare).parents is None and read_regions(bare).fps is None


_LINE = {"frames": [1, 2, 3], "boxes": [[10, 20, 8, 16]] * 3, "colours": [0, 3]}


def _with(**change) -> str:
    obj = {**_LINE, **change}
    return json.dumps({k: v for k, v in obj.items() if v is not None})


@pytest.mark.parametrize("lines, line_no, needle", [
    (["[1, 2]"], 1, "not a JSON object (got list)"),
    (['{"frames": [1]'], 1, "not a JSON object"),
    (["# fps=25", _with(frame=[1])], 2, "unknown key(s) ['frame']"),
    ([_with(boxes=None)], 1, "boxes: missing"),
    ([_with(frames=[1, 3, 2])], 1, "expected increasing frame numbers"),
    ([_with(frames=[1, 2.5, 3])], 1, "frames = [1, 2.5, 3]: expected a list of integers"),
    ([_with(frames=[-1, 2, 3])], 1, "expected integers >= 0"),
    ([_with(boxes=[[10, 20, 8, 16]] * 2)], 1, "boxes: 2 for 3 frames"),
    ([_with(boxes=[[10, 20, 0, 16]] * 3)], 1, "width and height > 0"),
    ([_with(boxes=[[10, 20, True, 16]] * 3)], 1, "expected a list of [x_centre"),
    ([_with(colours=[])], 1, "colours: empty"),
    ([_with(colours=[3, 3])], 1, "colours = [3, 3]: repeated"),
    ([_with(palette=[])], 1, "palette: empty"),  # "colour_log_likelihood: empty colour set"
    ([_with(truth=[-1])], 1, "truth = [-1]: expected integers >= 0"),
    ([_with(parents=[0])], 1, "stroke 0 links to earlier strokes only"),
    ([_with(), _with(frames=[4, 5, 6], parents=[0])], 2, "parents: on every line or on none"),
    ([_with(frames=[4, 5, 6]), _with()], 2, "strokes come in start order"),
    (["# fps=x", _with()], 1, "fps = 'x': expected a finite number > 0"),
    ([_with(), "# fps=25"], 2, "comes once, before the first stroke"),
    (["# just a comment", ""], 0, "no stroke"),
])
def test_a_bad_regions_file_names_the_line_and_field(tmp_path, lines, line_no, needle):
    path = tmp_path / "r.jsonl"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(FileFormatError) as info:
        read_regions(path)
    assert needle in str(info.value)
    assert str(info.value).startswith(f"{path}:{line_no}:" if line_no else f"{path}:")


def test_what_the_network_refuses_is_named_before_any_labelling(tmp_path):
    path = tmp_path / "r.jsonl"
    late = _with(frames=[3, 4], boxes=[[10, 20, 8, 16]] * 2, parents=[0])  # parent ends at 3
    for lines, needle in (([_with(colours=[0, 12])], "r.jsonl:1: stroke 0: colour ids must be in"),
                          ([_with(parents=[]), late], "r.jsonl:2: stroke 1: parent 0 ends")):
        path.write_text("\n".join(lines) + "\n")
        with pytest.raises(FileFormatError, match=needle):
            check_regions(read_regions(path), NetworkConfig(), 25.0)
    path.write_text(_with(colours=[0, 12]) + "\n")  # a larger pool takes colour 12
    check_regions(read_regions(path), NetworkConfig(pool_size=13), 25.0)


def test_track_labels_a_regions_file_as_it_is_and_eval_scores_it(tmp_path, capsys, strokes):
    """The run labels the file's strokes as the batch labeller does (nothing simulated,
    the seed unused), with the link rule or the file's links; eval scores them against
    the file's truth."""
    plain = write_regions(tmp_path / "plain.jsonl", strokes, fps=25.0)
    for seed in ("3", "0"):  # nothing is simulated: the seed changes nothing
        out = tmp_path / f"rule{seed}"
        assert main(["track", "jorge", str(plain), "-o", str(out), "--seed", seed, "--truth",
                     str(plain), "--quiet"]) == 0  # fmt: skip
        _, rows = read_strokes(out / "strokes.csv")
        res = label_online(list(strokes), fps=25.0)
        assert [r["label"] for r in rows] == list(res.labels)
        assert [r["parents"] for r in rows] == [tuple(n.parents) for n in res.labeller.graph.nodes]
    summary = json.loads((out / "summary.json").read_text())
    assert summary["metrics"]["error_rate"] == pytest.approx(score(strokes, res.labels).error_rate)
    assert summary["parameters"]["input"] == "regions" and summary["parameters"]["links"] == "rule"
    head = read_strokes_header(out / "strokes.csv")
    assert head["input"] == "regions" and "seed" not in head and head["fps"] == 25.0
    rule = [tuple(n.parents) for n in res.labeller.graph.nodes]
    links = [tuple(p) for p in true_links(strokes)]
    links[next(k for k, p in enumerate(links) if p)] = ()  # not the rule's: one link dropped
    assert links != rule
    linked = write_regions(tmp_path / "linked.jsonl", strokes, links)  # no fps line: 25 assumed
    capsys.readouterr()
    assert main(["track", "jorge", str(linked), "-o", str(tmp_path / "l"), "--quiet"]) == 0
    assert "assumed 25 fps" in capsys.readouterr().err
    _, rows = read_strokes(tmp_path / "l" / "strokes.csv")
    assert [r["parents"] for r in rows] == links
    want = label_online(list(strokes), fps=25.0, links=links).labels
    assert [r["label"] for r in rows] == list(want)
    assert main(["eval", "jorge", str(tmp_path / "l" / "strokes.csv"), str(plain), "--json"]) == 0
    metrics = json.loads(capsys.readouterr().out)
    # the rule would have made the link the file dropped: eval names it as a given link
    assert metrics["missed_links"]["given_links"] > 0 and metrics["num_strokes"] == len(strokes)


def test_regions_refusals_name_the_file(tmp_path, capsys, strokes):
    plain = write_regions(tmp_path / "plain.jsonl", strokes, fps=25.0)
    out = tmp_path / "run"
    assert main(["track", "jorge", str(plain), "-o", str(out), "--quiet"]) == 0
    csv = str(out / "strokes.csv")
    _bad(capsys, ["eval", "jorge", csv, str(XML)], "input=regions", "score them against that file")
    _bad(capsys, ["eval", "jorge", str(out / "tracks.txt"), str(plain)], "plain.jsonl",
         "boxes of each person")  # fmt: skip
    lines = plain.read_text().splitlines()
    nameless = tmp_path / "nameless.jsonl"
    obj = json.loads(lines[3])
    del obj["truth"]
    nameless.write_text("\n".join([*lines[:3], json.dumps(obj), *lines[4:]]) + "\n")
    _bad(capsys, ["eval", "jorge", csv, str(nameless)], "nameless.jsonl:4: stroke 2 has no truth")
    cfg = tmp_path / "cfg.json"
    cfg.write_text('{"gap_min": 3}')
    _bad(capsys, ["track", "jorge", str(plain), "-o", str(tmp_path / "b"), "--config", str(cfg)],
         "['gap_min']", "apply to box files")  # fmt: skip
    bad = tmp_path / "bad.jsonl"
    twelve = lines[2].replace('"colours": [', '"colours": [12, ')  # beyond the pool of 12
    bad.write_text("\n".join([*lines[:2], twelve, *lines[3:]]) + "\n")
    _bad(capsys, ["track", "jorge", str(bad), "-o", str(tmp_path / "c")], "bad.jsonl:3:",
         "colour ids")  # fmt: skip
    assert not (tmp_path / "c" / "strokes.csv").exists()


def test_the_example_regions_file_labels_as_its_box_file(tmp_path):
    """``tests/data/jorge/regions.jsonl`` holds the strokes the SIMULATED tracker makes of
    ``caviar.xml`` with seed 3 (``make_example.py``): the same labels, links and error."""
    runs = {}
    for name, path in (("boxes", XML), ("regions", DATA / "jorge" / "regions.jsonl")):
        out = tmp_path / name
        assert main(["track", "jorge", str(path), "-o", str(out), "--seed", "3", "--truth",
                     str(path), "--quiet"]) == 0  # fmt: skip
        _, rows = read_strokes(out / "strokes.csv")
        runs[name] = (rows, json.loads((out / "summary.json").read_text())["metrics"])
    assert runs["boxes"] == runs["regions"]
