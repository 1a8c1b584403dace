"""Fuzzing every reader (issue 14): valid example files, randomly damaged.

Each reader is given a valid file (``tests/data/*`` or a small generated one) after one
random mutation: truncation, a flipped byte, a deleted line or XML element, inserted
garbage. It must either raise a :mod:`dbn.errors` class whose message names the file, or
return a sane result (the mutation left the file valid: no NaN or inf, ranges kept).
Any other exception fails the test. The default run draws a few examples per reader;
``-m slow`` draws many more.
"""

from __future__ import annotations

import functools
import re
import shutil
import tempfile
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from dbn.errors import CheckpointError, DBNError, FileFormatError

DATA = Path(__file__).resolve().parents[1] / "data"
SHARED = Path(__file__).resolve().parents[2].parent / "shared" / "data"

FAST = settings(max_examples=8, deadline=None, suppress_health_check=list(HealthCheck))
SLOW = settings(max_examples=150, deadline=None, suppress_health_check=list(HealthCheck))


# --- mutations ---------------------------------------------------------------------------
@st.composite
def mutations(draw, data: bytes, xml: bool = False) -> bytes:
    """One random damage to ``data`` (never the identity for truncation and deletion)."""
    kinds = ["truncate", "flip", "delete_line", "insert", "empty"] + (["delete_element"] * xml)
    kind = draw(st.sampled_from(kinds))
    if kind == "empty":
        return b""
    if kind == "truncate":
        return data[: draw(st.integers(0, len(data) - 1))]
    if kind == "flip":
        i = draw(st.integers(0, len(data) - 1))
        b = draw(st.integers(0, 255).filter(lambda v: v != data[i]))
        return data[:i] + bytes([b]) + data[i + 1 :]
    if kind == "insert":
        i = draw(st.integers(0, len(data)))
        junk = draw(st.sampled_from([b"\x00", b"nan", b"-inf", b",", b"\n", b"}", b"<", b"1e999"]))
        return data[:i] + junk + data[i:]
    lines = data.splitlines(keepends=True)
    if kind == "delete_line":
        i = draw(st.integers(0, len(lines) - 1))
        return b"".join(lines[:i] + lines[i + 1 :])
    # delete one XML element: a whole <tag .../> line or an open/close tag line
    tagged = [i for i, ln in enumerate(lines) if re.match(rb"\s*</?\w", ln)]
    i = draw(st.sampled_from(tagged))
    return b"".join(lines[:i] + lines[i + 1 :])


def check_reader(
    read: Callable[[Path], object],
    sane: Callable[[object], None],
    mutated: bytes,
    name: str,
    names_file: bool = True,
) -> None:
    """Write ``mutated`` to a fresh file ``name``, read it: a library error naming the
    file, or a result that passes ``sane``."""
    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / name
        path.write_bytes(mutated)
        try:
            result = read(path)
        except DBNError as exc:
            if names_file:
                assert path.name in str(exc), f"error does not name the file: {exc}"
            return
        sane(result)


def finite(*arrays) -> None:
    for a in arrays:
        assert np.all(np.isfinite(np.asarray(a, dtype=np.float64)))


def finite_leaves(result) -> None:
    """Every float array inside a (nested) result is finite."""
    import jax

    for leaf in jax.tree_util.tree_leaves(result):
        a = np.asarray(leaf)
        if a.dtype.kind == "f":
            finite(a)


# --- BIF -------------------------------------------------------------------------------
def _sane_bn(bn) -> None:
    for n in bn.nodes:
        t = np.asarray(bn.table(n))
        finite(t)
        assert np.all(t >= 0) and np.allclose(t.sum(-1), 1.0)


def _sane_dbn(d) -> None:
    _sane_bn(d.initial_net)
    _sane_bn(d.transition_net)


BIF = (DATA / "dbn" / "umbrella.bif").read_bytes()


def _parse_bif_text(path: Path):
    from dbn.pgmpy_adapter import parse_bif

    try:
        text = path.read_bytes().decode("utf-8")
    except UnicodeDecodeError:
        return None
    return parse_bif(text, source=path.name)


def _read_bif(path: Path):
    from dbn.pgmpy_adapter import read_bif

    return read_bif(path)


def _read_two_slice(path: Path):
    from models.io.dbn import read_two_slice_bif

    return read_two_slice_bif(path)


@pytest.mark.parametrize(
    "read,sane",
    [
        (_parse_bif_text, lambda r: r is None or _sane_bn(r)),
        (_read_bif, _sane_bn),
        (_read_two_slice, _sane_dbn),
    ],
    ids=["parse_bif", "read_bif", "read_two_slice_bif"],
)
@FAST
@given(data=st.data())
def test_bif_readers(read, sane, data) -> None:
    check_reader(read, sane, data.draw(mutations(BIF)), "model.bif")


def test_known_bif_failures_are_library_errors(tmp_path) -> None:
    """The failures listed in issue 14, one by one, through every BIF path."""
    from dbn.errors import CycleError
    from dbn.pgmpy_adapter import read_bif

    text = BIF.decode()
    cyclic = (
        "variable A { type discrete [ 2 ] { a, b }; }\n"
        "variable B { type discrete [ 2 ] { a, b }; }\n"
        "probability ( A | B ) { (a) 0.5, 0.5; (b) 0.5, 0.5; }\n"
        "probability ( B | A ) { (a) 0.5, 0.5; (b) 0.5, 0.5; }\n"
    )
    cases = {
        "empty": ("", FileFormatError, None),
        "truncated": (text[: len(text) // 3], FileFormatError, ":9:"),
        "unknown_parent": (
            text.replace("Rain_1 | Rain_0", "Rain_1 | Foo_0"),
            FileFormatError,
            ":22:",
        ),
        "short_table": (text.replace("(yes) 0.7, 0.3;", "(yes) 0.7;"), FileFormatError, ":22:"),
        "cyclic": (cyclic, CycleError, None),
    }
    for name, (body, cls, line) in cases.items():
        path = tmp_path / f"{name}.bif"
        path.write_text(body)
        for read in (read_bif, _read_two_slice):
            with pytest.raises(cls) as info:
                read(path)
            assert path.name in str(info.value)
            if line:
                assert line in str(info.value)


# --- evidence / marginals CSV ------------------------------------------------------------
@functools.cache
def _umbrella():
    """The evidence's DBN, read once (pgmpy's BIF parser builds its grammar anew on each
    read: about 1 s)."""
    from models.io.dbn import read_two_slice_bif

    return read_two_slice_bif(DATA / "dbn" / "umbrella.bif")


def _evidence(path: Path):
    from models.io.dbn import read_evidence

    cols = read_evidence(path, _umbrella())
    for arr in cols.values():
        assert arr.dtype.kind == "i" and np.all((arr >= -1) & (arr < 2))
    return cols


@FAST
@given(data=st.data())
def test_evidence_csv(data) -> None:
    raw = (DATA / "dbn" / "evidence.csv").read_bytes()
    check_reader(_evidence, lambda r: None, data.draw(mutations(raw)), "ev.csv")


# --- CAVIAR / PETS2009 XML, MOTChallenge --------------------------------------------------
def _sane_truth(gt) -> None:
    assert np.all(np.diff(gt.frames) > 0)
    b = gt.boxes[~np.isnan(gt.boxes).any(-1)]
    finite(b)
    assert np.all(b[:, 2:] > 0)


def _small_xml(name: str) -> bytes:
    """The first ~60 lines of an example XML, closed (the full file is ~60 KB)."""
    lines = (DATA / "jorge" / name).read_bytes().splitlines(keepends=True)
    starts = [i for i, ln in enumerate(lines) if b"<frame " in ln and i > 40]
    return b"".join(lines[: starts[0]]) + b"</dataset>\n"


@pytest.mark.parametrize("name", ["caviar.xml", "pets2009.xml"])
@FAST
@given(data=st.data())
def test_box_xml(name, data) -> None:
    from models.io.jorge import read_boxes
    from models.jorge.strokes import load_caviar, load_pets2009

    raw = _small_xml(name)
    load = load_caviar if name == "caviar.xml" else load_pets2009
    mutated = data.draw(mutations(raw, xml=True))
    check_reader(load, _sane_truth, mutated, name)
    check_reader(read_boxes, _sane_truth, mutated, name)


def test_truncated_caviar_names_file_and_line(tmp_path) -> None:
    from models.jorge.strokes import load_caviar

    path = tmp_path / "cut.xml"
    path.write_bytes(_small_xml("caviar.xml")[:300])
    with pytest.raises(FileFormatError, match=r"cut\.xml:\d+: not well-formed XML"):
        load_caviar(path)


@FAST
@given(data=st.data())
def test_mot_text(data) -> None:
    from models.io.jorge import read_boxes

    raw = b"".join((DATA / "jorge" / "gt.txt").read_bytes().splitlines(keepends=True)[:40])
    check_reader(read_boxes, _sane_truth, data.draw(mutations(raw)), "gt.txt")


def _sane_regions(regions) -> None:
    assert regions.strokes and len(regions.lines) == len(regions.strokes)
    for s in regions.strokes:
        finite(s.positions, s.extent)
        assert np.all(s.extent > 0) and np.all(np.diff(s.frames) > 0) and s.colours.size > 0
    if regions.parents is not None:
        assert all(p < k for k, par in enumerate(regions.parents) for p in par)


@FAST
@given(data=st.data())
def test_regions_jsonl(data) -> None:
    """A regions file (your tracker's strokes), damaged: an error naming the file, or
    strokes the label network's own checks then take or refuse naming the line."""
    from models.io.jorge_regions import check_regions, read_regions
    from models.jorge.network import NetworkConfig

    def read(path):
        regions = read_regions(path)
        check_regions(regions, NetworkConfig(), 25.0)
        return regions

    raw = b"".join((DATA / "jorge" / "regions.jsonl").read_bytes().splitlines(keepends=True)[:5])
    check_reader(read, _sane_regions, data.draw(mutations(raw)), "regions.jsonl")


# --- MRCLAM and the localisation CSVs -----------------------------------------------------
@pytest.mark.parametrize(
    "name,cols",
    [("Robot1_Odometry.dat", 3), ("Robot1_Measurement.dat", 4), ("Landmark_Groundtruth.dat", 3)],
)
@FAST
@given(data=st.data())
def test_mrclam_dat(name, cols, data) -> None:
    from models.io.localization import read_dat

    raw = (DATA / "localization" / "mrclam" / name).read_bytes()
    mutated = data.draw(mutations(raw))
    check_reader(lambda p: read_dat(p, cols), finite, mutated, name)


@FAST
@given(data=st.data(), which=st.sampled_from(["Robot1_Odometry.dat", "Barcodes.dat"]))
def test_mrclam_folder(data, which) -> None:
    from models.io.localization import read_mrclam_folder

    src = DATA / "localization" / "mrclam"
    mutated = data.draw(mutations((src / which).read_bytes()))
    with tempfile.TemporaryDirectory() as d:
        folder = Path(d) / "mrclam"
        shutil.copytree(src, folder)
        (folder / which).write_bytes(mutated)
        try:
            robot = read_mrclam_folder(folder)
        except DBNError as exc:
            assert "mrclam" in str(exc)
            return
        finite(robot.odometry, robot.measurements, robot.landmarks)


@pytest.mark.parametrize("value", ["1e300", "12.5"])
@pytest.mark.parametrize(
    "name,line,column,what",
    [("Landmark_Groundtruth.dat", 2, 0, "landmark subject"), ("Barcodes.dat", 3, 0, "barcode subject"),
     ("Barcodes.dat", 3, 1, "barcode"), ("Robot1_Measurement.dat", 2, 1, "measured barcode")],
)
def test_mrclam_ids_are_integers_in_range_at_their_line(tmp_path, name, line, column, what, value) -> None:
    """An id column holding a fraction or a float too large for an integer is refused at
    its line: ``int()`` had truncated 12.5 to the id 12, and 1e300 wrapped in the cast
    (numpy's "invalid value encountered in cast") to a garbage landmark id."""
    import warnings

    from models.io.localization import read_mrclam_folder

    folder = tmp_path / "mrclam"
    shutil.copytree(DATA / "localization" / "mrclam", folder)
    rows = (folder / name).read_text().splitlines()
    fields = rows[line - 1].split()
    fields[column] = value
    rows[line - 1] = "\t".join(fields)
    (folder / name).write_text("\n".join(rows) + "\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(FileFormatError, match=rf"{re.escape(name)}:{line}: {what} {re.escape(f'{float(value):g}')} is (not an integer|out of range)"):
            read_mrclam_folder(folder)


@pytest.mark.parametrize("name,column,what", [("landmarks.csv", 0, "landmark id"), ("measurements.csv", 1, "measured landmark")])
def test_localization_csv_ids_are_integers_in_range(tmp_path, name, column, what) -> None:
    from models.io.localization import read_generic

    src = DATA / "localization"
    for f in ("odometry.csv", "measurements.csv", "landmarks.csv"):
        shutil.copy(src / f, tmp_path / f)
    rows = (tmp_path / name).read_text().splitlines()
    fields = rows[2].split(",")
    fields[column] = "1e300"
    rows[2] = ",".join(fields)
    (tmp_path / name).write_text("\n".join(rows) + "\n")
    with pytest.raises(FileFormatError, match=rf"{re.escape(name)}:3: {what} 1e\+300 is out of range"):
        read_generic(tmp_path / "odometry.csv", tmp_path / "measurements.csv", tmp_path / "landmarks.csv")


@pytest.mark.parametrize("name", ["odometry.csv", "measurements.csv", "landmarks.csv"])
@FAST
@given(data=st.data())
def test_localization_csv(name, data) -> None:
    from models.io.localization import read_generic

    src = DATA / "localization"
    mutated = data.draw(mutations((src / name).read_bytes()))
    with tempfile.TemporaryDirectory() as d:
        for f in ("odometry.csv", "measurements.csv", "landmarks.csv"):
            shutil.copy(src / f, Path(d) / f)
        (Path(d) / name).write_bytes(mutated)
        try:
            robot = read_generic(
                *(Path(d) / f for f in ("odometry.csv", "measurements.csv", "landmarks.csv"))
            )
        except DBNError as exc:
            assert name in str(exc)
            return
        finite(robot.odometry, robot.measurements, robot.landmarks)
        assert np.all(np.diff(robot.odometry[:, 0]) >= 0)


# --- Tsai calibration, masks, 3-D tracks --------------------------------------------------
def _sane_camera(result) -> None:
    cam, kappa = result
    finite(cam.K, cam.R, cam.t, kappa)
    assert cam.width > 0 and cam.height > 0


@FAST
@given(data=st.data())
def test_tsai_calibration(data) -> None:
    from models.rjmcmc3d.calibration import load_tsai_xml

    raw = (DATA / "rjmcmc3d" / "view0" / "calibration.xml").read_bytes()
    check_reader(load_tsai_xml, _sane_camera, data.draw(mutations(raw, xml=True)), "cal.xml")


@FAST
@given(data=st.data())
def test_mask_png(data) -> None:
    from models.io.rjmcmc3d import read_png

    raw = (DATA / "rjmcmc3d" / "view0" / "mask_0000.png").read_bytes()

    def sane(img) -> None:
        finite(img)
        assert img.min() >= 0.0 and img.max() <= 1.0

    check_reader(lambda p: read_png(p, (288, 384)), sane, data.draw(mutations(raw)), "m.png")


@FAST
@given(data=st.data())
def test_tracks3d(data) -> None:
    from models.io.rjmcmc3d import read_tracks3d

    def sane(out) -> None:
        for ids, pos in out.values():
            finite(pos)
            assert len(set(ids.tolist())) == len(ids)

    raw = b"".join((DATA / "rjmcmc3d" / "truth3d.txt").read_bytes().splitlines(keepends=True)[:30])
    check_reader(read_tracks3d, sane, data.draw(mutations(raw)), "t3d.txt")


# --- Zajdel passes, path recovery ---------------------------------------------------------
@pytest.mark.parametrize("name", ["observations.csv", "events.csv"])
@FAST
@given(data=st.data())
def test_zajdel_observations(name, data) -> None:
    from models.io.zajdel import read_observations

    raw = (DATA / "zajdel" / name).read_bytes()
    check_reader(read_observations, finite_leaves, data.draw(mutations(raw)), name)


@pytest.mark.parametrize("name", ["edges.csv", "observations.csv", "truth_path.csv"])
@FAST
@given(data=st.data())
def test_pathrecovery_files(name, data) -> None:
    from models.io import pathrecovery as io

    read = {
        "edges.csv": io.read_network,
        "observations.csv": io.read_observations,
        "truth_path.csv": io.read_path,
    }[name]
    raw = (DATA / "pathrecovery" / name).read_bytes()
    if name == "observations.csv":
        raw = b"".join(raw.splitlines(keepends=True)[:30])
    check_reader(read, finite_leaves, data.draw(mutations(raw)), name)


# --- sweep configuration and results ------------------------------------------------------
@FAST
@given(data=st.data())
def test_sweep_config(data) -> None:
    from models.experiments import load_sweep

    def sane(result) -> None:
        task, grid = result
        assert callable(task) and all(isinstance(p.seed, int) for p in grid)

    raw = (DATA / "sweep_example.toml").read_bytes()
    check_reader(load_sweep, sane, data.draw(mutations(raw)), "sweep.toml")


@FAST
@given(data=st.data())
def test_sweep_results(data) -> None:
    import json

    from models.experiments import read_results

    recs = [
        {"id": f"{k:016x}", "status": "ok", "point": {"seed": k}, "result": {"x": k}}
        for k in range(5)
    ]
    raw = "".join(json.dumps(r) + "\n" for r in recs).encode()

    def sane(out) -> None:
        assert all(isinstance(r, dict) and r["status"] in ("ok", "error") for r in out)

    check_reader(read_results, sane, data.draw(mutations(raw)), "r.jsonl")


# --- checkpoints ---------------------------------------------------------------------------
def _checkpoint_bytes(config=None) -> bytes:
    from inference.checkpoint import save_arrays

    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "c.npz"
        arrays = {"w": np.linspace(-1.0, 1.0, 7), "k": np.arange(5, dtype=np.int32)}
        save_arrays(path, arrays, "test-state", config=config or {"n": 7}, extra={"t": 3})
        return path.read_bytes()


@FAST
@given(data=st.data())
def test_checkpoint_arrays(data) -> None:
    from inference.checkpoint import load_arrays

    raw = _checkpoint_bytes()

    def sane(result) -> None:
        arrays, header = result
        finite(arrays["w"])
        assert header["t"] == 3

    read = lambda p: load_arrays(p, "test-state", ("w", "k"), {"n": 7})  # noqa: E731
    try:
        check_reader(read, sane, data.draw(mutations(raw)), "c.npz")
    except CheckpointError:  # pragma: no cover - CheckpointError is a DBNError
        raise


def test_checkpoint_rejects_config_version_nan_and_foreign(tmp_path) -> None:
    from inference.checkpoint import load_arrays, save_arrays

    path = tmp_path / "c.npz"
    path.write_bytes(_checkpoint_bytes())
    load_arrays(path, "test-state", ("w", "k"), {"n": 7})  # the valid file loads
    with pytest.raises(CheckpointError, match="configuration"):
        load_arrays(path, "test-state", ("w", "k"), {"n": 8})
    with pytest.raises(CheckpointError, match="format"):
        load_arrays(path, "other-state", ("w", "k"), {"n": 7})
    with pytest.raises(CheckpointError, match="NaN or inf"):
        save_arrays(path, {"w": np.array([np.nan])}, "test-state")
    # NaN written behind the library's back (an old or hand-made file)
    np.savez(path, w=np.array([np.inf]))
    with pytest.raises(CheckpointError, match="no header"):
        load_arrays(path, "test-state", ("w",))
    for blob in (b"", b"PK\x03\x04garbage", _checkpoint_bytes()[:200]):
        path.write_bytes(blob)
        with pytest.raises(CheckpointError, match="c.npz"):
            load_arrays(path, "test-state", ("w", "k"), {"n": 7})


def test_checkpoint_checksum_catches_a_changed_value(tmp_path) -> None:
    import json
    import zipfile

    from inference.checkpoint import load_arrays

    src, dst = tmp_path / "a.npz", tmp_path / "b.npz"
    src.write_bytes(_checkpoint_bytes())
    with zipfile.ZipFile(src) as zin, zipfile.ZipFile(dst, "w") as zout:
        for item in zin.infolist():
            blob = zin.read(item)
            if item.filename == "w.npy":
                blob = blob[:-8] + np.float64(0.5).tobytes()  # last value 1.0 -> 0.5
            zout.writestr(item, blob)
        header = json.loads(bytes(np.load(src)["__header__"]).decode())
    assert header["version"] >= 2 and len(header["checksum"]) == 64
    with pytest.raises(CheckpointError, match="checksum"):
        load_arrays(dst, "test-state", ("w", "k"), {"n": 7})


# --- the slow, many-example run -----------------------------------------------------------
@pytest.mark.slow
@SLOW
@given(data=st.data())
def test_many_mutations_all_readers(data) -> None:
    """Every reader above with many more examples (run with ``-m slow``)."""
    test_bif_readers.hypothesis.inner_test(_read_two_slice, _sane_dbn, data)
    test_box_xml.hypothesis.inner_test("caviar.xml", data)
    test_regions_jsonl.hypothesis.inner_test(data)
    test_mrclam_dat.hypothesis.inner_test("Robot1_Measurement.dat", 4, data)
    test_tsai_calibration.hypothesis.inner_test(data)
    test_evidence_csv.hypothesis.inner_test(data)
    test_zajdel_observations.hypothesis.inner_test("events.csv", data)
    test_pathrecovery_files.hypothesis.inner_test("edges.csv", data)
    test_sweep_config.hypothesis.inner_test(data)
    test_checkpoint_arrays.hypothesis.inner_test(data)


@pytest.mark.skipif(not (SHARED / "caviar").is_dir(), reason="shared CAVIAR data absent")
@pytest.mark.slow
@SLOW
@given(data=st.data())
def test_real_caviar_file(data) -> None:
    from models.jorge.strokes import load_caviar

    files = sorted((SHARED / "caviar").rglob("*.xml*"))
    if not files:
        pytest.skip("no CAVIAR XML under shared data")
    raw = files[0].read_bytes()
    if files[0].suffix == ".gz":
        import gzip

        raw = gzip.decompress(raw)
    check_reader(load_caviar, _sane_truth, data.draw(mutations(raw, xml=True)), "real.xml")


# --- every tracker's save/load -------------------------------------------------------------
def _rewrite(src: Path, dst: Path, header_fn=None, arrays_fn=None) -> None:
    """Copy a checkpoint with its header and/or arrays changed, checksum recomputed (a
    well-formed file saved under another configuration, or holding NaN)."""
    import json

    from inference.checkpoint import _checksum

    with np.load(src) as f:
        header = json.loads(bytes(f["__header__"]).decode())
        arrays = {n: np.array(f[n]) for n in f.files if n != "__header__"}
    if header_fn:
        header_fn(header)
    if arrays_fn:
        arrays_fn(arrays)
    header["checksum"] = _checksum(header, arrays)
    blob = np.frombuffer(json.dumps(header).encode(), np.uint8)
    np.savez(dst, __header__=blob, **arrays)


@pytest.mark.parametrize("name", ["jorge", "localization", "pathrecovery", "rjmcmc3d",
                                  "zajdel_adf", "zajdel_learnsearch"])
def test_tracker_checkpoints_reject_bad_files(name, tmp_path) -> None:
    import jax

    import models

    ex = models.get(name).example(jax.random.key(0))
    tr = ex.tracker
    state, _ = tr.step(jax.random.key(2), tr.init(jax.random.key(1)), ex.observations[0])
    good = tmp_path / "good.npz"
    tr.save(state, good)
    tr.load(good)  # the valid file loads
    raw = good.read_bytes()
    bad = tmp_path / "bad.npz"
    for blob in (b"", raw[: len(raw) // 2], raw[:-30], b"PK\x03\x04" + raw[4:100]):
        bad.write_bytes(blob)
        with pytest.raises(CheckpointError, match="bad.npz"):
            tr.load(bad)
    np.savez(bad, x=np.zeros(3))  # a foreign .npz
    with pytest.raises(CheckpointError, match="no header"):
        tr.load(bad)

    def other_config(h):
        h["config"] = {"saved": "elsewhere"}

    _rewrite(good, bad, header_fn=other_config)
    with pytest.raises(CheckpointError, match="configuration"):
        tr.load(bad)

    def old_version(h):
        h["version"] = 1

    _rewrite(good, bad, header_fn=old_version)
    with pytest.raises(CheckpointError, match="version"):
        tr.load(bad)

    def nan_inside(a):
        k = next(n for n, v in a.items() if v.dtype.kind == "f" and v.size)
        a[k] = a[k].copy()
        a[k].flat[0] = np.nan

    _rewrite(good, bad, arrays_fn=nan_inside)
    with pytest.raises(CheckpointError, match="NaN"):
        tr.load(bad)


@FAST
@given(data=st.data())
def test_json_config(data) -> None:
    from models.io.table import read_json_config

    raw = (DATA / "rjmcmc3d" / "config.json").read_bytes()
    check_reader(
        read_json_config, lambda c: isinstance(c, dict), data.draw(mutations(raw)), "c.json"
    )


def test_checkpoint_allows_minus_inf_only_where_declared(tmp_path) -> None:
    from inference.checkpoint import load_arrays, save_arrays

    path = tmp_path / "c.npz"
    lw = np.array([0.0, -np.inf, -1.0])
    save_arrays(path, {"log_weights": lw}, "t", neg_inf=["log_weights"])
    arrays, _ = load_arrays(path, "t", ["log_weights"], neg_inf=["log_weights"])
    np.testing.assert_array_equal(arrays["log_weights"], lw)
    with pytest.raises(CheckpointError, match="log_weights"):
        load_arrays(path, "t", ["log_weights"])  # not declared by this loader
    for bad in (np.inf, np.nan):
        with pytest.raises(CheckpointError, match="NaN or inf"):
            save_arrays(path, {"log_weights": np.array([bad])}, "t", neg_inf=["log_weights"])
