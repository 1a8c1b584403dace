"""The jorge benchmark scores ground truths added to the data folder that none of its lists
names (``models.jorge.fit.unlisted_sequences``), as the split ``unlisted``, on their own."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np

from benchmarks.jorge import _error_keys, _label_sequences, _unlisted_keys
from models.jorge.fit import unlisted_sequences
from models.jorge.online import OnlineConfig

EXAMPLES = Path(__file__).resolve().parent.parent / "data" / "jorge"


def _data(tmp_path: Path, monkeypatch) -> Path:
    """A data folder holding a CAVIAR and a PETS2009 example (SIMULATED, tests/data) under
    names no list has, a camera file that is not a ground truth, and one listed name."""
    for folder in ("caviar", "pets2009"):
        (tmp_path / folder).mkdir()
    shutil.copy(EXAMPLES / "caviar.xml", tmp_path / "caviar" / "mine.xml")
    shutil.copy(EXAMPLES / "pets2009.xml", tmp_path / "pets2009" / "PETS2009-S9L9.xml")
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
