"""Issue 14 edges: frame indices that do not advance, explicit pixel conversion, time
order in files named by file and line."""

from __future__ import annotations

import functools
import shutil
from pathlib import Path

import jax
import numpy as np
import pytest

import models
from dbn.errors import DBNError, FileFormatError, InputError, TimeOrderError
from models.protocol import next_frame_index

DATA = Path(__file__).resolve().parents[1] / "data"


# --- frame indices ----------------------------------------------------------------------
def test_next_frame_index_rules() -> None:
    assert next_frame_index(-1, None, "t") == 0 and next_frame_index(4, None, "t") == 5
    assert next_frame_index(-1, 7, "t") == 7  # the first frame may start anywhere
    assert next_frame_index(4, np.int64(5), "t") == 5
    for bad in (4, 3, 6, 10**6):  # repeated, replayed, skipped
        with pytest.raises(TimeOrderError, match=rf"frame.t = {bad} "):
            next_frame_index(4, bad, "frame.t")
    with pytest.raises(TimeOrderError, match="negative"):
        next_frame_index(-1, -1, "frame.t")
    for bad in (1.5, "5", True):
        with pytest.raises(InputError, match="frame.t"):
            next_frame_index(4, bad, "frame.t")


@functools.cache
def _two_steps(name: str):
    ex = models.get(name).example(jax.random.key(0))
    tr, obs = ex.tracker, ex.observations
    s = tr.init(jax.random.key(1))
    for i in range(2):
        s, _ = tr.step(jax.random.key(2 + i), s, obs[i])
    return tr, obs, s


@pytest.mark.parametrize("name,field", [("pathrecovery", "obs.t"), ("rjmcmc3d", "frame.t")])
def test_replayed_or_skipped_frame_rejected_before_any_change(name, field) -> None:
    tr, obs, state = _two_steps(name)
    before = jax.tree.map(np.copy, state)
    nxt = obs[2].t
    for t in (obs[0].t, obs[1].t, nxt + 1):
        with pytest.raises(TimeOrderError, match=field):
            tr.step(jax.random.key(9), state, obs[2]._replace(t=t))
    assert all(
        np.array_equal(a, b) for a, b in zip(jax.tree.leaves(before), jax.tree.leaves(state))
    )
    new, _ = tr.step(jax.random.key(9), state, obs[2])  # the right index is accepted
    same, _ = tr.step(jax.random.key(9), state, obs[2]._replace(t=None))  # None: the next
    assert jax.tree.leaves(new)[-1] == jax.tree.leaves(same)[-1] == nxt


def test_rjmcmc3d_checkpoint_keeps_the_frame_index(tmp_path) -> None:
    tr, _, state = _two_steps("rjmcmc3d")
    tr.save(state, tmp_path / "s.npz")
    assert tr.load(tmp_path / "s.npz").frame == state.frame == 1


# --- pixels ------------------------------------------------------------------------------
def test_read_png_8bit_divided_by_255(tmp_path) -> None:
    import matplotlib.image as mpimg

    from models.io.rjmcmc3d import read_png

    grey = (np.arange(288 * 384) % 256).astype(np.uint8).reshape(288, 384)
    mpimg.imsave(tmp_path / "g.png", np.repeat(grey[..., None], 3, axis=2))  # 8-bit RGB
    np.testing.assert_allclose(read_png(tmp_path / "g.png", (288, 384)), grey / 255.0, atol=1e-6)


def test_unit_float_conversion_is_explicit() -> None:
    from models.io.rjmcmc3d import _unit_float

    u8 = np.array([[0, 128, 255]], np.uint8)
    np.testing.assert_allclose(_unit_float(u8, "f.png"), u8 / 255.0, atol=1e-7)
    u16 = np.array([[0, 65535]], np.uint16)
    np.testing.assert_array_equal(_unit_float(u16, "f.png"), [[0.0, 1.0]])
    for value in (255.0, 1.0001, -0.5, np.nan, np.inf):
        a = np.full((2, 3), 0.5, np.float32)
        a[1, 2] = value
        with pytest.raises(FileFormatError, match=r"f\.png: pixel \(1, 2\)"):
            _unit_float(a, "f.png")
    with pytest.raises(FileFormatError, match="pixel type"):
        _unit_float(np.zeros((2, 2), np.int32), "f.png")


def test_read_png_valid_mask_in_unit_range() -> None:
    from models.io.rjmcmc3d import read_png

    img = read_png(DATA / "rjmcmc3d" / "view0" / "mask_0000.png", (288, 384))
    assert img.dtype == np.float32 and 0.0 <= img.min() and img.max() <= 1.0 and img.max() > 0.5


# --- time order in files: file and line ---------------------------------------------------
def _backwards(src: Path, dst: Path) -> int:
    """``src`` with its last data row swapped with its second; the line number of the
    first row that then goes back in time (the third data row)."""
    lines = src.read_text().splitlines(keepends=True)
    data = [i for i, ln in enumerate(lines) if ln.split("#", 1)[0].strip()]
    lines[data[1]], lines[data[-1]] = lines[data[-1]], lines[data[1]]
    dst.write_text("".join(lines))
    return data[2] + 1


def test_mrclam_loader_names_file_and_line(tmp_path, monkeypatch) -> None:
    """``load_robot`` reads the shared folder with the checks of any MRCLAM folder."""
    from models.localization.mrclam import load_robot

    folder = tmp_path / "mrclam6"  # a stand-in for the shared data (the test files)
    shutil.copytree(DATA / "localization" / "mrclam", folder)
    monkeypatch.setenv("DBNTRACK_DATA", str(tmp_path))
    robot = load_robot(1)
    assert robot.odometry.shape[1] == 3 and robot.barcode_to_subject
    odo = folder / "Robot1_Odometry.dat"
    good = odo.read_text()
    line = _backwards(odo, odo)
    with pytest.raises(TimeOrderError, match=rf"Robot1_Odometry\.dat:{line}: time goes back"):
        load_robot(1)
    odo.write_text(good)
    codes = folder / "Barcodes.dat"
    rows = codes.read_text().splitlines(keepends=True)
    k = [i for i, ln in enumerate(rows) if ln.split("#", 1)[0].strip()][0]
    rows[k] = rows[k].split()[0] + " 5.5\n"  # a barcode that is not an integer
    codes.write_text("".join(rows))
    with pytest.raises(FileFormatError, match=rf"Barcodes\.dat:{k + 1}: barcode 5.5 is not an integer"):
        load_robot(1)


def test_mrclam_numeric_error_names_the_file_line(tmp_path) -> None:
    from models.io.localization import read_dat

    src = DATA / "localization" / "mrclam" / "Robot1_Odometry.dat"
    lines = src.read_text().splitlines(keepends=True)
    k = [i for i, ln in enumerate(lines) if ln.split("#", 1)[0].strip()][3]
    lines[k] = "1.0 x 2.0\n"
    (tmp_path / "o.dat").write_text("".join(lines))
    with pytest.raises(FileFormatError, match=rf"o\.dat:{k + 1}: column 2 = 'x' is not a number"):
        read_dat(tmp_path / "o.dat", 3)
    lines[k] = "1.0 inf 2.0\n"  # parsed, but not finite
    (tmp_path / "o.dat").write_text("".join(lines))
    with pytest.raises(FileFormatError, match=rf"o\.dat:{k + 1}: column 2 = 'inf' is not finite"):
        read_dat(tmp_path / "o.dat", 3)


def test_mrclam_folder_and_csv_name_file_and_line(tmp_path) -> None:
    from models.io.localization import read_mrclam_folder, read_poses

    folder = tmp_path / "mrclam"
    shutil.copytree(DATA / "localization" / "mrclam", folder)
    src = folder / "Robot1_Measurement.dat"
    line = _backwards(src, src)
    with pytest.raises(TimeOrderError, match=rf"Robot1_Measurement\.dat:{line}: time goes back"):
        read_mrclam_folder(folder)
    csv = tmp_path / "poses.csv"
    csv.write_text("t,x,y,theta\n# c\n1,0,0,0\n2,0,0,0\n1.5,0,0,0\n")
    with pytest.raises(TimeOrderError, match=r"poses\.csv:5: time goes back"):
        read_poses(csv)
    assert issubclass(TimeOrderError, DBNError)
