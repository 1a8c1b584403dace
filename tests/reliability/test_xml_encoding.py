"""An XML declaration naming an unknown encoding (a byte flip the fuzzer found:
``utf-8`` -> ``u-f-8``) is a FileFormatError naming the file, for every XML reader."""

from __future__ import annotations

from pathlib import Path

import pytest

from dbn.errors import FileFormatError

DATA = Path(__file__).resolve().parent.parent / "data"


def _flip_encoding(src: Path, dst: Path, encoding: str = "u-f-8") -> Path:
    """``src`` with its declaration's encoding replaced by ``encoding``."""
    raw = src.read_bytes()
    assert raw.startswith(b"<?xml"), src
    end = raw.index(b"?>")
    dst.write_bytes(f'<?xml version="1.0" encoding="{encoding}"'.encode() + raw[end:])
    return dst


# u-f-8: LookupError; UTF-7 (hypothesis drew it), UTF-32, Shift-JIS: expat's ValueError
# "multi-byte encodings are not supported", which escaped as itself
@pytest.mark.parametrize("encoding", ["u-f-8", "UTF-7", "UTF-32", "shift_jis"])
@pytest.mark.parametrize("name", ["caviar.xml", "pets2009.xml"])
def test_box_xml_with_unknown_encoding(tmp_path: Path, name: str, encoding: str) -> None:
    from models.io.jorge import read_boxes
    from models.jorge.strokes import load_caviar, load_pets2009

    bad = _flip_encoding(DATA / "jorge" / name, tmp_path / name, encoding)
    for read in (load_caviar if name == "caviar.xml" else load_pets2009, read_boxes):
        with pytest.raises(FileFormatError, match=f"{name}:1:.*encoding"):
            read(bad)


def test_tsai_calibration_with_unknown_encoding(tmp_path: Path) -> None:
    from models.rjmcmc3d.calibration import load_tsai_xml

    src = sorted((DATA / "rjmcmc3d").rglob("*.xml"))
    if not src:
        pytest.skip("no Tsai calibration example under tests/data/rjmcmc3d")
    bad = _flip_encoding(src[0], tmp_path / src[0].name)
    with pytest.raises(FileFormatError, match=f"{src[0].name}:1:.*encoding"):
        load_tsai_xml(bad)
