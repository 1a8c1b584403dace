"""The jorge benchmark scores ground truths added to the data folder that none of its lists
names (``models.jorge.fit.unlisted_sequences``), as the split ``unlisted``, on their own."""

from __future__ import annotations

import gzip
import shutil
import warnings
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from benchmarks.jorge import _error_keys, _issue4_mean, _label_sequences, _unlisted_keys
from models.io.jorge import read_mot
from models.jorge.fit import (
    extra_ground_truths,
    frame_rate_note,
    listed_copies,
    load_sequence,
    same_name,
    sequence_key,
    unlisted_sequences,
)
from models.jorge.online import OnlineConfig, label_online
from models.jorge.scoring import score
from models.jorge.strokes import build_strokes

EXAMPLES = Path(__file__).resolve().parent.parent / "data" / "jorge"


def _moved_xml(src: Path, dx: float) -> bytes:
    """The example XML ``src`` with every box ``dx`` pixels to the right: the examples are
    one recording, and each of these another (:mod:`models.jorge.recordings`)."""
    root = ET.parse(src).getroot()
    for box in root.iter("box"):
        box.set("xc", str(float(box.get("xc")) + dx))
    return ET.tostring(root)


def _moved_gt(dx: float) -> str:
    """The example ``gt.txt`` with every box ``dx`` pixels to the right."""
    rows = [line.split(",") for line in (EXAMPLES / "gt.txt").read_text().splitlines()]
    return "".join(",".join(r[:2] + [f"{float(r[2]) + dx:g}"] + r[3:]) + "\n" for r in rows)


def _data(tmp_path: Path, monkeypatch) -> Path:
    """A data folder holding a CAVIAR and a PETS2009 example (SIMULATED, tests/data) under
    names no list has, a camera file that is not a ground truth, and one listed name."""
    for folder in ("caviar", "pets2009"):
        (tmp_path / folder).mkdir()
    shutil.copy(EXAMPLES / "caviar.xml", tmp_path / "caviar" / "mine.xml")
    (tmp_path / "pets2009" / "PETS2009-S9L9.xml").write_bytes(_moved_xml(EXAMPLES / "pets2009.xml",
                                                                         10.0))
    (tmp_path / "pets2009" / "View_001.xml").write_text("<Camera><Geometry/></Camera>\n")
    (tmp_path / "pets2009" / "notes.txt").write_text("not a sequence\n")
    monkeypatch.setenv("DBNTRACK_DATA", str(tmp_path))
    return tmp_path


def test_unlisted_sequences_lists_the_xml_files_no_list_names(tmp_path, monkeypatch):
    data = _data(tmp_path, monkeypatch)
    assert unlisted_sequences() == [("caviar", "mine.xml"), ("pets2009", "PETS2009-S9L9.xml"),
                                    ("pets2009", "View_001.xml")]
    shutil.copy(EXAMPLES / "caviar.xml", data / "caviar" / "ms3ggt.xml.gz")  # a listed name
    assert ("caviar", "ms3ggt.xml.gz") not in unlisted_sequences()
    assert listed_copies() == []  # the listed file itself
    monkeypatch.setenv("DBNTRACK_DATA", str(tmp_path / "absent"))
    assert unlisted_sequences() == []


def test_benchmark_scores_unlisted_sequences_on_their_own(tmp_path, monkeypatch):
    _data(tmp_path, monkeypatch)
    per, rows_by, _, ok = _label_sequences([0], OnlineConfig())
    assert ok and set(per) == {"mine", "PETS2009-S9L9"}  # the camera file is skipped
    assert {p["split"] for p in per.values()} == {"unlisted"}
    assert per["mine"]["fps"] == 25.0 and per["PETS2009-S9L9"]["fps"] == 7.0
    keys = _unlisted_keys(rows_by)
    assert keys["unlisted_sequences"] == ["mine", "PETS2009-S9L9"]
    rows = [r for _, rs in rows_by.values() for r in rs]
    wrong = sum(int(r["wrong"].sum()) for r in rows)
    assert keys["error_rate_unlisted"] == wrong / sum(r["strokes"] for r in rows)
    assert 0.0 <= keys["error_rate_unlisted_colour_only"] <= 1.0
    assert keys["first_mistakes_unlisted"] == sum(r["first"] for r in rows)
    assert 0.0 <= keys["true_label_kept_unlisted"] <= 1.0
    # never pooled with the training and validation keys
    assert np.isnan(_error_keys(rows_by, 5)["error_rate_validation"])
    assert _unlisted_keys({}) == {"unlisted_sequences": []}


def _nested(tmp_path: Path, monkeypatch) -> Path:
    """A data folder laid out as the sequences' own archives are: a gzipped CAVIAR file two
    folders down, MOTChallenge ``gt.txt`` files with and without a ``seqinfo.ini`` (one
    with a static person, class 7, who is not scored), a tracker's ``det.txt``, an XML in
    ``mot``, a file under a training sequence's name, a cut of it under another name and a
    hidden copy (all SIMULATED, tests/data; each its own recording, its boxes moved)."""
    caviar = tmp_path / "caviar" / "Meeting" / "Meet_Two"
    caviar.mkdir(parents=True)
    with gzip.open(caviar / "m2gt.xml.gz", "wb") as f:
        f.write((EXAMPLES / "caviar.xml").read_bytes())
    static = "".join(f"{fr},9,300,100,20,40,1,7,1\n" for fr in range(70, 90))
    for seq, text, ini in (("pets2009/PETS09-S9L8", _moved_gt(10), "[Sequence]\nframeRate=10\n"),
                           ("pets2009/PETS09-S9L7", _moved_gt(20) + static, None),
                           ("mot/MOT-X", _moved_gt(30), None)):
        (tmp_path / seq / "gt").mkdir(parents=True)
        (tmp_path / seq / "gt" / "gt.txt").write_text(text)
        if ini:
            (tmp_path / seq / "seqinfo.ini").write_text(ini)
    (tmp_path / "pets2009" / "PETS09-S9L7" / "det").mkdir()
    (tmp_path / "pets2009" / "PETS09-S9L7" / "det" / "det.txt").write_text(_moved_gt(20))
    (tmp_path / "mot" / "Walk").mkdir()
    (tmp_path / "mot" / "Walk" / "walkgt.xml").write_bytes(_moved_xml(EXAMPLES / "caviar.xml", 40))
    copy = tmp_path / "caviar" / "Meeting" / "Meet_Split_3rdGuy"  # a training sequence's name
    copy.mkdir()
    root = ET.parse(EXAMPLES / "pets2009.xml").getroot()  # the examples are one recording:
    for box in root.iter("box"):  # this one is another, its boxes 5 pixels to the right
        box.set("xc", str(float(box.get("xc")) + 5.0))
    ET.ElementTree(root).write(copy / "MS3GGT.xml")
    for frame in [f for f in root.findall("frame") if int(f.get("number")) < 100]:
        root.remove(frame)
    ET.ElementTree(root).write(copy / "ms3ggt1.xml")  # and a cut of it, from frame 100 on
    (tmp_path / "caviar" / ".cache").mkdir()
    shutil.copy(EXAMPLES / "caviar.xml", tmp_path / "caviar" / ".cache" / "copy.xml")
    monkeypatch.setenv("DBNTRACK_DATA", str(tmp_path))
    return tmp_path


NESTED = [("caviar", "Meeting/Meet_Split_3rdGuy/ms3ggt1.xml"),
          ("caviar", "Meeting/Meet_Two/m2gt.xml.gz"), ("pets2009", "PETS09-S9L7/gt/gt.txt"),
          ("pets2009", "PETS09-S9L8/gt/gt.txt"), ("mot", "MOT-X/gt/gt.txt"),
          ("mot", "Walk/walkgt.xml")]


def test_unlisted_sequences_at_any_depth_and_in_motchallenge_layout(tmp_path, monkeypatch):
    data = _nested(tmp_path, monkeypatch)
    assert unlisted_sequences() == NESTED
    assert listed_copies() == [("caviar", "Meeting/Meet_Split_3rdGuy/MS3GGT.xml", "ms3ggt")]
    assert extra_ground_truths() == (unlisted_sequences(), listed_copies())
    assert [sequence_key(*s) for s in NESTED] == ["ms3ggt1", "m2gt", "PETS09-S9L7", "PETS09-S9L8",
                                                  "MOT-X", "walkgt"]
    truths = [load_sequence(*s) for s in NESTED[1:]]
    assert [t.fps for t in truths] == [25.0, 7.0, 10.0, 25.0, 25.0]
    assert frame_rate_note(*NESTED[3]) == str(data / "pets2009" / "PETS09-S9L8" / "seqinfo.ini")
    assert "7 fps, PETS2009's cameras' rate" in frame_rate_note(*NESTED[2])
    assert "25 fps, assumed" in frame_rate_note(*NESTED[4])
    assert frame_rate_note(*NESTED[1]) == "CAVIAR XML: 25 fps"
    assert "with grouplists" in frame_rate_note(*NESTED[5])
    # the static person (class 7) is not a person of the ground truth; the rest is the file's
    assert 9 in read_mot(data / "pets2009" / "PETS09-S9L7" / "gt" / "gt.txt").ids
    assert 9 not in truths[1].ids
    np.testing.assert_allclose(truths[1].boxes, truths[2].boxes + [10.0, 0, 0, 0])  # 20 px, 10 px
    assert len(truths[4].groups) > 0 and truths[4].fps == 25.0  # CAVIAR's, by its grouplists


def test_benchmark_scores_nested_and_motchallenge_sequences(tmp_path, monkeypatch, capsys):
    _nested(tmp_path, monkeypatch)
    per, rows_by, _, ok = _label_sequences([0], OnlineConfig())
    unlisted = ["m2gt", "PETS09-S9L7", "PETS09-S9L8", "MOT-X", "walkgt"]
    assert ok and list(per) == ["ms3ggt"] + unlisted  # ms3ggt: absent from its listed path
    assert [per[k]["split"] for k in per] == ["train"] + ["unlisted"] * 5
    assert [per[k]["fps"] for k in per] == [25.0, 25.0, 7.0, 10.0, 25.0, 25.0]
    copy = ("caviar", "Meeting/Meet_Split_3rdGuy/MS3GGT.xml")
    for key, seq in zip(per, [copy] + NESTED[1:]):  # NESTED[0], a cut of ms3ggt, is not scored
        strokes = build_strokes(0, load_sequence(*seq))
        assert per[key]["strokes"] == len(strokes)
        labels = label_online(strokes, OnlineConfig()).labels
        assert per[key]["error_rate"] == score(strokes, labels).error_rate
    err = capsys.readouterr().err
    assert "jorge: pets2009/PETS09-S9L7/gt/gt.txt: 7 fps (no seqinfo.ini" in err
    assert "jorge: pets2009/PETS09-S9L8/gt/gt.txt: 10 fps (" in err
    assert "jorge: caviar/Meeting/Meet_Split_3rdGuy/MS3GGT.xml: the listed sequence ms3ggt" in err
    assert ("jorge: caviar/Meeting/Meet_Split_3rdGuy/ms3ggt1.xml: the recording of the listed "
            "sequence ms3ggt (the same boxes)") in err
    assert ("jorge: ms3ggt is not at its listed path: its copy caviar/Meeting/Meet_Split_3rdGuy/"
            "MS3GGT.xml is scored as train") in err
    assert _unlisted_keys(rows_by)["unlisted_sequences"] == unlisted


def test_issue4_figure_takes_only_the_listed_ms3ggt_and_mws1gt():
    per = {"ms3ggt": {"split": "unlisted", "error_rate": 0.5},  # a file of yours of that name
           "mws1gt": {"split": "train", "error_rate": 0.1}}
    assert _issue4_mean(per, "error_rate") == 0.1
    per["mws1gt"]["split"] = "unlisted"
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no mean of an empty list: a data folder of yours only
        assert np.isnan(_issue4_mean(per, "error_rate"))


def test_a_cut_of_a_training_recording_at_its_listed_path_is_not_scored_as_unlisted(
        tmp_path, monkeypatch, capsys):
    (tmp_path / "caviar").mkdir()
    with gzip.open(tmp_path / "caviar" / "ms3ggt.xml.gz", "wb") as f:  # at the listed path
        f.write((EXAMPLES / "caviar.xml").read_bytes())
    root = ET.parse(EXAMPLES / "caviar.xml").getroot()
    for frame in [f for f in root.findall("frame") if int(f.get("number")) >= 120]:
        root.remove(frame)
    ET.ElementTree(root).write(tmp_path / "caviar" / "first_half.xml")
    monkeypatch.setenv("DBNTRACK_DATA", str(tmp_path))
    assert unlisted_sequences() == [("caviar", "first_half.xml")] and listed_copies() == []
    per, rows_by, _, ok = _label_sequences([0], OnlineConfig())
    assert ok and list(per) == ["ms3ggt"] and per["ms3ggt"]["split"] == "train"
    err = capsys.readouterr().err
    assert "caviar/first_half.xml: the recording of the listed sequence ms3ggt" in err
    assert _unlisted_keys(rows_by) == {"unlisted_sequences": []}


def _mot_copy(truth) -> str:
    """``truth`` as MOTChallenge writes a ground truth: frames from one more, its own ids,
    the corners rounded to whole pixels (as MOTChallenge's PETS09-S2L1 is PETS2009 S2L1)."""
    rows = []
    for i, frame in enumerate(truth.frames):
        for j in np.flatnonzero(np.isfinite(truth.boxes[i, :, 0])):
            xc, yc, w, h = truth.boxes[i, j]
            rows.append(f"{frame + 1},{100 + j},{round(xc - w / 2)},{round(yc - h / 2)},"
                        f"{w:g},{h:g},1,1,1\n")
    return "".join(rows)


def test_one_recording_is_scored_once_and_a_converted_listed_one_not_at_all(
        tmp_path, monkeypatch, capsys):
    caviar, new = tmp_path / "caviar", tmp_path / "caviar" / "Meet_New"
    new.mkdir(parents=True)
    with gzip.open(caviar / "ms3ggt.xml.gz", "wb") as f:  # the training recording
        f.write(_moved_xml(EXAMPLES / "caviar.xml", 50.0))
    shutil.copy(EXAMPLES / "caviar.xml", new / "mngt.xml")  # a new recording, whole
    root = ET.parse(EXAMPLES / "caviar.xml").getroot()
    for frame in [f for f in root.findall("frame") if int(f.get("number")) < 100]:
        root.remove(frame)
    ET.ElementTree(root).write(new / "mngt1.xml")  # and cut, from frame 100 on
    monkeypatch.setenv("DBNTRACK_DATA", str(tmp_path))
    for seq, truth in (("MOT-NEW", load_sequence("caviar", "Meet_New/mngt.xml")),
                       ("MOT-TRAIN", load_sequence("caviar", "ms3ggt.xml.gz"))):
        (tmp_path / "mot" / seq / "gt").mkdir(parents=True)
        (tmp_path / "mot" / seq / "gt" / "gt.txt").write_text(_mot_copy(truth))
    assert len(unlisted_sequences()) == 4
    per, rows_by, _, ok = _label_sequences([0], OnlineConfig())
    assert ok and list(per) == ["ms3ggt", "mngt"]
    assert _unlisted_keys(rows_by)["unlisted_sequences"] == ["mngt"]
    err = capsys.readouterr().err
    for cut in ("caviar/Meet_New/mngt1.xml", "mot/MOT-NEW/gt/gt.txt"):
        assert (f"jorge: {cut}: the recording of the unlisted caviar/Meet_New/mngt.xml (the "
                "same boxes), scored once") in err
    assert "jorge: mot/MOT-TRAIN/gt/gt.txt: the recording of the listed sequence ms3ggt" in err


def test_motchallenge_pets09_is_our_pets2009_sequence_by_name(tmp_path, monkeypatch, capsys):
    """MOTChallenge's PETS09-S2L1 is our validation PETS2009-S2L1: never unlisted, and
    scored as validation where our file is absent (the example boxes, SIMULATED)."""
    seq = tmp_path / "mot" / "PETS09-S2L1"
    (seq / "gt").mkdir(parents=True)
    (seq / "gt" / "gt.txt").write_text((EXAMPLES / "gt.txt").read_text())
    (seq / "seqinfo.ini").write_text("[Sequence]\nframeRate=7\n")
    monkeypatch.setenv("DBNTRACK_DATA", str(tmp_path))
    assert same_name("PETS09-S2L1") == same_name("pets2009-s2l1") == "pets2009-s2l1"
    assert same_name("PETS09S2L1") == "pets09s2l1"
    assert unlisted_sequences() == []
    assert listed_copies() == [("mot", "PETS09-S2L1/gt/gt.txt", "PETS2009-S2L1")]
    per, rows_by, _, ok = _label_sequences([0], OnlineConfig())
    assert ok and list(per) == ["PETS2009-S2L1"] and per["PETS2009-S2L1"]["split"] == "validation"
    assert per["PETS2009-S2L1"]["fps"] == 7.0
    assert ("jorge: PETS2009-S2L1 is not at its listed path: its copy mot/PETS09-S2L1/gt/gt.txt "
            "is scored as validation") in capsys.readouterr().err
