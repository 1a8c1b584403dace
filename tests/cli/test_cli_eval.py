"""``dbntrack eval`` on hand-made result files: what each runner scores, and the damaged
results it refuses with one line naming the file (and line) instead of scoring garbage
(found by damaging every runner's example result and truth in about 40 ways)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from models.cli import main
from tests.cli.test_cli_track import _bad

DATA = Path(__file__).resolve().parent.parent / "data"


def _metrics(capsys, argv: list[str]) -> dict:
    assert main([*argv, "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def _write(path: Path, lines: list[str]) -> Path:
    path.write_text("\n".join(lines) + "\n")
    return path


# -- dbn: marginals.csv ---------------------------------------------------------------------

RAIN = [0.8, 0.3, 0.6]  # P(Rain_t = yes); the truth below is yes, yes, no


def _marginals(tmp_path: Path, edit=None) -> Path:
    rows = ["slice,variable,state,probability"]
    for t, p in enumerate(RAIN):
        rows += [f"{t},Rain,yes,{p}", f"{t},Rain,no,{1 - p:.15g}"]
    return _write(tmp_path / "marginals.csv", edit(rows) if edit else rows)


def test_dbn_eval_scores_a_hand_made_file(tmp_path, capsys):
    truth = _write(tmp_path / "truth.csv", ["Rain", "yes", "yes", "no"])
    m = _metrics(capsys, ["eval", "dbn", str(_marginals(tmp_path)), str(truth)])
    assert m["num_compared"] == 3
    assert m["label_error_rate"] == pytest.approx(2 / 3)  # argmax: yes, no, yes
    loss = -(math.log(0.8) + math.log(0.3) + math.log(0.4)) / 3
    assert m["mean_log_loss"] == pytest.approx(loss)


@pytest.mark.parametrize(
    ("row", "needles"),
    [
        ("99999999999,Rain,yes,0.5", ["marginals.csv", "Rain = yes has no row for slice 3"]),
        ("-1,Rain,yes,0.5", ["marginals.csv:8:", "slice = -1"]),
        ("2,Rain,yes,1.5", ["marginals.csv:8:", "probability = 1.5 is not in [0, 1]"]),
        ("1,Rain,no,0.7", ["marginals.csv:8:", "slice 1, Rain = no is given twice"]),
    ],
)
def test_dbn_eval_refuses_a_damaged_marginal(tmp_path, capsys, row, needles):
    """A huge slice number used to allocate that many rows (numpy MemoryError); a negative
    one wrote into the last slice; a probability of 1.5 or a repeated row was scored."""
    truth = _write(tmp_path / "truth.csv", ["Rain", "yes", "yes", "no"])
    bad = _marginals(tmp_path, lambda rows: [*rows, row])
    _bad(capsys, ["eval", "dbn", str(bad), str(truth)], *needles)


def test_dbn_eval_refuses_a_gap_and_a_bad_sum(tmp_path, capsys):
    truth = _write(tmp_path / "truth.csv", ["Rain", "yes", "yes", "no"])
    gap = _marginals(tmp_path, lambda rows: rows[:3] + rows[4:])  # slice 1's "yes" row dropped
    _bad(capsys, ["eval", "dbn", str(gap), str(truth)], "Rain = yes has no row for slice 1")
    off = _marginals(tmp_path, lambda rows: [r.replace("1,Rain,no,0.7", "1,Rain,no,0.07")
                                             for r in rows])  # fmt: skip
    _bad(capsys, ["eval", "dbn", str(off), str(truth)], "marginals.csv:4:",
         "Rain at slice 1 sum to 0.37")  # fmt: skip


# -- zajdel: labels.csv ----------------------------------------------------------------------


def test_zajdel_eval_needs_every_pass_the_truth_labels(tmp_path, capsys):
    """A result without some of the truth's passes used to be scored on the rest (a run
    cut in half scored q = 1). A pass the truth leaves unlabelled is not needed."""
    truth = _write(tmp_path / "truth.csv", ["pass,person", "0,0", "1,0", "2,1", "3,1"])
    full = _write(tmp_path / "full.csv", ["pass,label", "0,5", "1,5", "2,6", "3,5"])
    m = _metrics(capsys, ["eval", "zajdel_adf", str(full), str(truth)])
    assert (m["num_compared"], m["num_tracks"], m["num_people"]) == (4, 2, 2)
    assert m["pairwise_precision"] == pytest.approx(1 / 3)  # pairs 01 right; 03, 13 wrong
    assert m["pairwise_recall"] == pytest.approx(1 / 2)  # pairs 01 found, 23 missed
    half = _write(tmp_path / "half.csv", ["pass,label", "0,5", "1,5"])
    _bad(capsys, ["eval", "zajdel_adf", str(half), str(truth)], "half.csv",
         "no label for 2 pass(es)", "[2, 3]")  # fmt: skip
    partial = _write(tmp_path / "partial.csv", ["pass,person", "0,0", "1,0", "2,", "3,"])
    assert _metrics(capsys, ["eval", "zajdel_adf", str(half), str(partial)])["q"] == 1.0


# -- jorge: tracks.txt (MOTChallenge) and strokes.csv -----------------------------------------


def _mot_rows(frames, ids=(1, 2)) -> list[str]:
    return [f"{f},{i},{10 + 40 * i},{20 + f},20,40,1,-1,-1,-1" for f in frames for i in ids]


def test_jorge_mot_eval_counts_a_box_in_an_empty_frame(tmp_path, capsys):
    """MOTChallenge truth has no row for a frame where nobody is; a box the result puts
    there matched nothing and was ignored (precision 1). Frames past the truth's span are
    not annotated, and stay unscored."""
    truth = _write(tmp_path / "gt.txt", _mot_rows([1, 2, 4, 5]))  # frame 3: nobody
    result = _write(tmp_path / "tracks.txt", _mot_rows([1, 2, 4, 5]) + _mot_rows([3, 9], ids=(1,)))
    m = _metrics(capsys, ["eval", "jorge", str(result), str(truth)])
    assert m["recall"] == 1.0
    assert m["precision"] == pytest.approx(8 / 9)  # frame 3's box; frame 9 is not scored
    assert m["mota"] == pytest.approx(1 - 1 / 8)


def test_jorge_mot_eval_refuses_a_negative_frame(tmp_path, capsys):
    truth = _write(tmp_path / "gt.txt", _mot_rows([1, 2]))
    result = _write(tmp_path / "tracks.txt", _mot_rows([1, -2]))
    _bad(capsys, ["eval", "jorge", str(result), str(truth)], "tracks.txt:3:", "frame = -2")


def _gt_rows(frames, people=(1, 2), others=()) -> list[str]:
    """MOT16/17/20 ``gt.txt`` rows (9 fields: ..., flag, class, visibility): ``people``
    are pedestrians (class 1, flag 1); ``others`` are ``(id, flag, class)``."""
    rows = [f"{f},{i},{10 + 40 * i},{20 + f},20,40,1,1,1" for f in frames for i in people]
    rows += [f"{f},{i},{10 + 40 * i},{20 + f},20,40,{flag},{c},1"
             for f in frames for i, flag, c in others]
    return rows


def _on(frames, i: int, dx: int = 0) -> list[str]:
    """A result's track of id ``i`` on the box of truth id ``i`` (moved ``dx`` pixels)."""
    return [f"{f},{i},{10 + 40 * i + dx},{20 + f},20,40,1,-1,-1,-1" for f in frames]


@pytest.mark.parametrize("cls", [2, 7, 8, 12])
def test_jorge_mot_eval_drops_a_box_on_a_distractor(tmp_path, capsys, cls):
    """A box on a static person, a reflection, ... (flag 0 in gt.txt) was a false
    positive; the challenge's evaluation drops it. A box on a car stays one."""
    frames = [1, 2, 3, 4]
    truth = _write(tmp_path / "gt.txt", _gt_rows(frames, others=[(3, 0, cls), (4, 0, 3)]))
    result = _write(tmp_path / "tracks.txt", _mot_rows(frames) + _on(frames, 3, dx=2))
    m = _metrics(capsys, ["eval", "jorge", str(result), str(truth)])
    assert m["precision"] == 1.0 and m["mota"] == 1.0
    result = _write(tmp_path / "tracks.txt", _mot_rows(frames) + _on(frames, 4))  # the car
    m = _metrics(capsys, ["eval", "jorge", str(result), str(truth)])
    assert m["precision"] == pytest.approx(8 / 12)
    assert m["mota"] == pytest.approx(1 - 4 / 8)


def test_jorge_mot_eval_reads_classes_of_a_nine_field_truth_only(tmp_path, capsys):
    """A flagged row of another class (a car) is not a person to find; class 6 is a
    distractor in MOT20 only (seqinfo.ini's name); a 10-field truth (MOT15) has no class."""
    frames = [1, 2]
    seq = tmp_path / "SEQ"
    (seq / "gt").mkdir(parents=True)
    truth = _write(seq / "gt" / "gt.txt", _gt_rows(frames, others=[(3, 1, 3), (4, 0, 6)]))
    result = _write(tmp_path / "tracks.txt", _mot_rows(frames) + _on(frames, 4))
    m = _metrics(capsys, ["eval", "jorge", str(result), str(truth)])
    assert m["recall"] == 1.0  # the car (id 3) is not missed
    assert m["precision"] == pytest.approx(4 / 6)  # the pram (class 6) counts in MOT17
    (seq / "seqinfo.ini").write_text("[Sequence]\nname=MOT20-01\nframeRate=25\n")
    m = _metrics(capsys, ["eval", "jorge", str(result), str(truth)])
    assert m["precision"] == 1.0
    mot15 = _write(tmp_path / "gt15.txt", [r + ",-1" for r in _gt_rows(frames, others=[(3, 1, 3)])])
    m = _metrics(capsys, ["eval", "jorge", str(result), str(mot15)])
    assert m["recall"] == pytest.approx(4 / 6)  # every flagged row is a person


def test_jorge_mot_eval_keeps_a_box_matched_to_a_person_beside_a_distractor(tmp_path, capsys):
    """One to one: a box overlapping both a pedestrian and a static person (IoU >= 0.5
    with each) is the pedestrian's when that matching has the larger IoU."""
    from models.track.jorge import on_distractors

    truth = np.array([[0.0, 0.0, 20, 40], [4.0, 0.0, 20, 40]])
    boxes = np.array([[1.0, 0.0, 20, 40], [60.0, 0.0, 20, 40]])
    assert not on_distractors(boxes, truth, np.array([False, True])).any()
    assert on_distractors(boxes, truth, np.array([True, False])).tolist() == [True, False]
    two = np.array([[1.0, 0.0, 20, 40], [4.0, 0.0, 20, 40]])
    assert on_distractors(two, truth, np.array([False, True])).tolist() == [False, True]


def test_jorge_mot_eval_refuses_a_bad_class(tmp_path, capsys):
    truth = _write(tmp_path / "gt.txt", _gt_rows([1, 2]) + ["2,5,10,10,20,40,0,13,1"])
    result = _write(tmp_path / "tracks.txt", _mot_rows([1, 2]))
    _bad(capsys, ["eval", "jorge", str(result), str(truth)], "gt.txt:5:", "class = 13")


def test_jorge_strokes_eval_refuses_rows_out_of_stroke_order(tmp_path, capsys):
    """Rows are matched to the rebuilt strokes by position: a stroke id that is not the
    one at its position, or a negative object, was accepted."""
    out = tmp_path / "run"
    assert main(["track", "jorge", str(DATA / "jorge" / "caviar.xml"), "-o", str(out),
                 "--seed", "3", "--quiet"]) == 0  # fmt: skip
    capsys.readouterr()
    lines = (out / "strokes.csv").read_text().splitlines()
    head = [i for i, line in enumerate(lines) if line.startswith("stroke,")][0]
    first, second = lines[head + 1].split(","), lines[head + 2].split(",")
    renamed = lines.copy()
    renamed[head + 2] = ",".join(["0", *second[1:]])
    bad = _write(tmp_path / "renamed.csv", renamed)
    xml = str(DATA / "jorge" / "caviar.xml")
    _bad(capsys, ["eval", "jorge", str(bad), xml], "row 2 is stroke 0", "stroke 1 belongs there")
    negative = lines.copy()
    negative[head + 1] = ",".join([*first[:3], "-1", *first[4:]])
    bad = _write(tmp_path / "negative.csv", negative)
    _bad(capsys, ["eval", "jorge", str(bad), xml], f"negative.csv:{head + 2}:", "count from 0")


def test_jorge_strokes_csv_keeps_the_links_and_eval_checks_them(tmp_path, capsys):
    """``strokes.csv`` has a ``parents`` column and the labeller's frame rate in its
    header; ``eval`` reports the missed links from them, scores a file of an earlier
    version (no such column) without them, and refuses bad links naming the line or the
    stroke."""
    from models.io.jorge import read_strokes, read_strokes_header
    from models.jorge.online import OnlineConfig, label_online
    from models.jorge.recall import missed_link_counts, missed_links
    from models.jorge.strokes import StrokeConfig, build_strokes, load_caviar

    out = tmp_path / "run"
    xml = str(DATA / "jorge" / "caviar.xml")
    cfg = _write(tmp_path / "cfg.json", ['{"gap_min": 20, "gap_max": 30, "gaps_per_100": 8}'])
    assert main(["track", "jorge", xml, "-o", str(out), "--seed", "3", "--config", str(cfg),
                 "--quiet"]) == 0  # fmt: skip
    capsys.readouterr()
    _, rows = read_strokes(out / "strokes.csv")
    assert read_strokes_header(out / "strokes.csv")["fps"] == 25.0
    settings = StrokeConfig(gap_min=20, gap_max=30, gaps_per_100=8.0)
    strokes = build_strokes(3, load_caviar(xml), settings)
    graph = label_online(strokes, OnlineConfig()).labeller.graph
    assert [r["parents"] for r in rows] == [tuple(n.parents) for n in graph.nodes]
    assert rows[0]["parents"] == () and any(r["parents"] for r in rows)
    assert main(["eval", "jorge", str(out / "strokes.csv"), xml, "--json"]) == 0
    m = json.loads(capsys.readouterr().out)
    # gaps of 20-30 frames: some beyond the rule's 30 at 25 fps, once someone is seen again
    assert m["missed_links"] == missed_link_counts(missed_links(strokes, graph))
    assert m["missed_links"]["gap"] > 0 and m["missed_links"]["given_links"] == 0
    lines = (out / "strokes.csv").read_text().splitlines()
    head = [i for i, line in enumerate(lines) if line.startswith("stroke,")][0]
    old = [line for line in lines if not line.startswith("# fps=")]
    old = old[:head - 1] + [",".join(line.split(",")[:5]) for line in old[head - 1:]]
    assert main(["eval", "jorge", str(_write(tmp_path / "old.csv", old)), xml, "--json"]) == 0
    m_old = json.loads(capsys.readouterr().out)
    assert "missed_links" not in m_old and m_old["error_rate"] == m["error_rate"]
    linked = next(i for i, r in enumerate(rows) if r["parents"])
    line = head + 1 + linked
    for parents, needle in (("x", "parents 'x'"), (f"{linked}", "distinct earlier strokes")):
        bad = lines.copy()
        bad[line] = ",".join([*lines[line].split(",")[:5], parents])
        _bad(capsys, ["eval", "jorge", str(_write(tmp_path / "bad.csv", bad)), xml],
             f"bad.csv:{line + 1}:", needle)
    late = next(k for k, r in enumerate(rows) if rows[k - 1]["end"] >= r["start"] and k > 0)
    bad = lines.copy()
    bad[head + 1 + late] = ",".join([*lines[head + 1 + late].split(",")[:5], str(late - 1)])
    _bad(capsys, ["eval", "jorge", str(_write(tmp_path / "late.csv", bad)), xml],
         "late.csv", f"stroke {late}: parent {late - 1} ends")
    fps = [line if not line.startswith("# fps=") else "# fps=-7" for line in lines]
    _bad(capsys, ["eval", "jorge", str(_write(tmp_path / "fps.csv", fps)), xml],
         "fps.csv:", "fps = '-7'", "finite number > 0")


# -- rjmcmc3d: tracks3d.txt ------------------------------------------------------------------


def _rows3d(frames, ids=(0, 1)) -> list[str]:
    """Rows of ``ids`` at x = 2 id, y = 0.1 (frame mod 1000) m (within the 1e6 m bound)."""
    return [f"{f},{i},-1,-1,-1,-1,1,{2.0 * i},{0.1 * (f % 1000)},0" for f in frames for i in ids]


def test_rjmcmc3d_eval_scores_the_truth_span_only(tmp_path, capsys):
    truth = _write(tmp_path / "truth3d.txt", _rows3d([1, 2, 4]))  # frame 3: nobody
    result = _write(tmp_path / "tracks3d.txt", _rows3d([1, 2, 3, 4, 8]))
    m = _metrics(capsys, ["eval", "rjmcmc3d", str(result), str(truth)])
    assert (m["num_objects"], m["misses"], m["false_positives"]) == (6, 0, 2)  # frame 3's


def test_rjmcmc3d_eval_of_a_far_frame_does_not_walk_every_frame(tmp_path, capsys):
    """The truth's span used to be walked frame by frame: a last frame of 10^11 hung."""
    truth = _write(tmp_path / "truth3d.txt", _rows3d([1, 2, 99_999_999_999]))
    result = _write(tmp_path / "tracks3d.txt", _rows3d([1, 2]))
    m = _metrics(capsys, ["eval", "rjmcmc3d", str(result), str(truth)])
    assert (m["num_objects"], m["misses"]) == (6, 2)
    _bad(capsys, ["eval", "rjmcmc3d", str(_write(tmp_path / "neg.txt", _rows3d([-1]))),
                  str(truth)], "neg.txt:1:", "frame = -1")  # fmt: skip


def test_rjmcmc3d_eval_refuses_a_position_beyond_a_thousand_km(tmp_path, capsys):
    """A truth at x = 1e200 m was scored (a miss) after motmetrics' squared distance
    overflowed; the tracker's own detections are bounded by 1e6 m."""
    rows = _rows3d([1, 2])
    far = [r.replace(",0.0,0.1,", ",1e200,0.1,") for r in rows]  # id 0 in frame 1
    truth = _write(tmp_path / "truth3d.txt", far)
    result = _write(tmp_path / "tracks3d.txt", rows)
    _bad(capsys, ["eval", "rjmcmc3d", str(result), str(truth)],
         "truth3d.txt:1: x, y = 1e+200, 0.1: beyond 1e+06 m")  # fmt: skip
    edge = [r.replace(",0.0,0.1,", ",-1e6,0.1,") for r in rows]  # the bound itself
    _metrics(capsys, ["eval", "rjmcmc3d", str(result), str(_write(tmp_path / "e.txt", edge))])


# -- pathrecovery: path.csv ------------------------------------------------------------------


@pytest.mark.parametrize(
    ("row", "needle"),
    [
        ("2,visible,3,0,-1", "a visible step names its observation"),
        ("2,hidden,3,2,7", "a hidden step has no observation"),
        ("2,hidden,3,-1,-1", "ta = -1"),
        ("2,visible,-2,0,7", "camera = -2"),
    ],
)
def test_pathrecovery_eval_refuses_an_inconsistent_step(tmp_path, capsys, row, needle):
    truth = _write(tmp_path / "truth.csv", ["t,state,camera,ta,obs", "0,visible,1,0,0",
                                            "1,visible,1,0,4", "2,visible,3,0,7"])  # fmt: skip
    bad = _write(tmp_path / "path.csv", ["t,state,camera,ta,obs", "0,visible,1,0,0",
                                         "1,visible,1,0,4", row])  # fmt: skip
    assert _metrics(capsys, ["eval", "pathrecovery", str(truth), str(truth)])["path_score"] == 1.0
    _bad(capsys, ["eval", "pathrecovery", str(bad), str(truth)], "path.csv:4:", needle)


def test_pathrecovery_track_refuses_a_negative_observation_id(tmp_path, capsys):
    d = DATA / "pathrecovery"
    lines = (d / "observations.csv").read_text().splitlines()
    lines[3] = ",".join(["-1", *lines[3].split(",")[1:]])
    obs = _write(tmp_path / "observations.csv", lines)
    _bad(capsys, ["track", "pathrecovery", str(d / "edges.csv"), str(obs), "-o",
                  str(tmp_path / "out")], "observations.csv:4:", "obs = -1")  # fmt: skip


# -- the command line itself ------------------------------------------------------------------


@pytest.mark.parametrize("seed", ["-1", str(2**70), "x"])
def test_track_refuses_a_seed_out_of_range(tmp_path, capsys, seed):
    """A negative seed or one of 2**70 raised numpy's ValueError or an OverflowError in
    some runners."""
    with pytest.raises(SystemExit):
        main(["track", "jorge", str(DATA / "jorge" / "caviar.xml"), "-o", str(tmp_path / "o"),
              "--seed", seed])  # fmt: skip
    assert "argument --seed" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def test_track_refuses_an_output_folder_that_is_a_file(tmp_path, capsys):
    """It raised FileExistsError."""
    (tmp_path / "afile").write_text("x")
    argv = ["track", "jorge", str(DATA / "jorge" / "caviar.xml"), "-o", str(tmp_path / "afile")]
    _bad(capsys, argv, f"output folder {tmp_path / 'afile'}: cannot create")


def test_data_and_sweep_arguments_are_checked(tmp_path, capsys):
    """--data naming no folder was taken silently; a sweep's results file that is a folder
    raised IsADirectoryError; --workers 0 ran one worker per core and -1 hung."""
    with pytest.raises(SystemExit):
        main(["--data", str(tmp_path / "nosuch"), "list"])
    assert "--data" in capsys.readouterr().err
    toml = str(DATA / "sweep_example.toml")
    _bad(capsys, ["sweep", toml, "-o", str(tmp_path)], "results file", "cannot write it")
    for workers in ("0", "-1"):
        with pytest.raises(SystemExit):
            main(["sweep", toml, "-o", str(tmp_path / "r.jsonl"), "--workers", workers])
        assert "argument --workers" in capsys.readouterr().err
    assert not (tmp_path / "r.jsonl").exists()


def test_running_out_of_memory_is_one_line(monkeypatch, capsys, tmp_path):
    """jax's RESOURCE_EXHAUSTED (e.g. num_particles = 10**9 in --config) was a traceback;
    any other RuntimeError still is one (a bug, not bad input)."""
    import jax

    import models.commands

    def oom(args):
        raise jax.errors.JaxRuntimeError("RESOURCE_EXHAUSTED: Out of memory allocating 8e9 bytes.")

    monkeypatch.setattr(models.commands, "track", oom)
    argv = ["track", "localization", "x", "-o", str(tmp_path)]
    _bad(capsys, argv, "the run ran out of memory",
         "lower the sizes in --config (num_particles, ...)")

    def bug(args):
        raise RuntimeError("a bug")

    monkeypatch.setattr(models.commands, "track", bug)
    with pytest.raises(RuntimeError, match="a bug"):
        main(argv)
