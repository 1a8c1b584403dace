"""Robot-localisation files: an MRCLAM dataset folder, or generic CSVs; pose tracks.

MRCLAM folder (UTIAS Multi-Robot Cooperative Localization and Mapping, any dataset, any
robot ``N``): ``RobotN_Odometry.dat`` (time, v, w), ``RobotN_Measurement.dat`` (time,
barcode, range, bearing), ``Landmark_Groundtruth.dat`` (subject, x, y, ...),
``Barcodes.dat`` (subject, barcode) and, optionally, ``RobotN_Groundtruth.dat`` (time, x,
y, theta); each file may be gzipped (``.dat.gz``). Whitespace-separated, ``#`` comments.

Generic CSVs (with a header line): ``odometry.csv`` ``t,v,w``; ``measurements.csv``
``t,landmark,range,bearing``; ``landmarks.csv`` ``id,x,y``; optional ``groundtruth.csv``
``t,x,y,theta``. Measurements of an id that is not a landmark are ignored (as MRCLAM's
measurements of other robots).

Pose track (output, and truth for ``dbntrack eval``): ``t,x,y,theta``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from dbn.checks import MAX_SCALE
from dbn.errors import InputError, TimeOrderError
from models.io.table import as_float, fail, read_lines, read_rows, write_rows
from models.localization.model import TWO_PI
from models.localization.mrclam import MRCLAMRobot

__all__ = ["read_dat", "mrclam_file", "read_mrclam_folder", "read_generic", "write_poses",
           "read_poses", "MAX_MAGNITUDE", "MAX_TIME"]


def read_dat(path: str | Path, num_columns: int) -> np.ndarray:
    """A whitespace-separated numeric file (``#`` comments, optionally gzipped) as an
    array ``(rows, num_columns)`` (extra columns ignored); errors name file and line."""
    return _read_dat(Path(path), num_columns)[0]


def _read_dat(path: Path, num_columns: int) -> tuple[np.ndarray, list[int]]:
    """:func:`read_dat` and the file line number of each row."""
    texts, lines = [], []
    for line_no, line in enumerate(read_lines(path, "MRCLAM .dat file"), start=1):
        fields = line.split("#", 1)[0].split()
        if not fields:
            continue
        if len(fields) < num_columns:
            raise fail(path, line_no, f"{len(fields)} fields, expected {num_columns}")
        texts.append(fields[:num_columns])
        lines.append(line_no)
    if not texts:
        raise fail(path, 0, "no data rows")
    try:  # numpy parses numbers as float() does, at once
        data = np.array(texts, dtype=np.float64)
    except ValueError:
        data = None
    if data is None or not np.isfinite(data).all():  # field by field, naming the bad one
        data = np.array([[as_float(x, path, line_no, f"column {k + 1}") for k, x in enumerate(fields)]
                         for fields, line_no in zip(texts, lines)])  # fmt: skip
    return data, lines


def mrclam_file(folder: str | Path, stem: str) -> Path:
    """The file ``stem.dat`` (or ``stem.dat.gz``) of an MRCLAM folder, e.g.
    ``Robot1_Odometry``; an :class:`InputError` if it has neither."""
    return _find(Path(folder), stem)


def _find(folder: Path, stem: str, required: bool = True) -> Path | None:
    for name in (f"{stem}.dat", f"{stem}.dat.gz"):
        if (folder / name).is_file():
            return folder / name
    if required:
        raise InputError(f"{folder}: MRCLAM folder has no {stem}.dat (or .dat.gz)")
    return None


def _check_sorted(t: np.ndarray, path, lines: list[int]) -> None:
    back = np.flatnonzero(np.diff(t) < 0)
    if back.size:
        i = int(back[0]) + 1
        raise TimeOrderError(f"{path}:{lines[i]}: time goes back ({t[i]} after {t[i - 1]})")


def _check_range_bearing(meas: np.ndarray, path, lines: list[int]) -> None:
    """A :class:`FileFormatError` at the line of the first measurement whose range is
    negative (not a distance) or whose bearing is beyond one turn (``|bearing| > 2 pi``:
    bearings are radians, and such a value is most likely degrees, which were taken)."""
    bad = np.flatnonzero((meas[:, 2] < 0) | (np.abs(meas[:, 3]) > TWO_PI))
    if bad.size:
        i = int(bad[0])
        r, b = meas[i, 2], meas[i, 3]
        say = (f"range {r:g} is negative" if r < 0 else
               f"bearing {b:g} is beyond one turn: bearings are radians (degrees?)")
        raise fail(path, lines[i], say)
    _check_repeats(meas, path, lines)


def _check_repeats(meas: np.ndarray, path, lines: list[int]) -> None:
    """A :class:`FileFormatError` at the later line of the first two measurements of one
    id at one time: one sensor reads a landmark once per instant, and a repeated row
    would count its evidence twice."""
    order = np.lexsort((meas[:, 1], meas[:, 0]))
    key = meas[order, :2]
    same = np.flatnonzero(np.all(key[1:] == key[:-1], axis=1))
    if same.size:
        a, b = sorted((lines[order[same[0]]], lines[order[same[0] + 1]]))
        t, i = key[same[0]]
        raise fail(path, b, f"a second measurement of id {i:g} at t = {t:g} (the first at line "
                            f"{a}): a repeated row would count its evidence twice")  # fmt: skip


_MAX_ID = 2**31

MAX_MAGNITUDE = 1e7
"""Largest accepted ``|value|`` of a speed (m/s, rad/s), position or range (m) or heading
(rad): 10,000 km, a UTM northing's range. A velocity of 1e200 sent the robot to 4e198 m
and the run ended with rc 0; larger values are unit mistakes."""

MAX_TIME = MAX_SCALE
"""Largest accepted ``|t|`` (s): any clock's seconds (MRCLAM's are Unix times); a first
row at t = -1e200 was taken. The library's bound on times, :data:`dbn.checks.MAX_SCALE`."""


def _check_magnitudes(arr: np.ndarray, columns: tuple[str, ...], path, lines: list[int]) -> None:
    """A :class:`FileFormatError` at the line of the first value of ``columns`` (the
    named columns of ``arr``, None for one not checked) beyond its limit in ``_LIMITS``
    (:data:`MAX_MAGNITUDE`, :data:`MAX_TIME` for times)."""
    idx = [i for i, c in enumerate(columns) if c is not None]
    limits = np.array([_LIMITS[columns[i]][1] for i in idx])
    big = np.abs(arr[:, idx]) > limits
    if big.any():
        row, j = (int(v) for v in np.argwhere(big)[0])
        name = columns[idx[j]]
        unit, limit = _LIMITS[name]
        raise fail(path, lines[row], f"{name} = {arr[row, idx[j]]:g} {unit} is beyond "
                   f"{limit:g} {unit}: a unit mistake?")  # fmt: skip


def _check_ids(ids: np.ndarray, path, lines: list[int], what: str, unique: bool = True) -> None:
    """A :class:`FileFormatError` at the line of the first id that is not an integer, is
    out of range (``|id| >= 2^31``: a larger float would wrap when cast) or, with
    ``unique``, repeats an earlier one (a repeated landmark or barcode would silently
    shadow the other)."""
    seen: set[int] = set()
    for v, line in zip(ids, lines):
        if v != np.floor(v):
            raise fail(path, line, f"{what} {v:g} is not an integer")
        if abs(v) >= _MAX_ID:
            raise fail(path, line, f"{what} {v:g} is out of range (|id| < 2^31)")
        if unique and int(v) in seen:
            raise fail(path, line, f"{what} {v:g} is repeated")
        seen.add(int(v))


def read_mrclam_folder(folder: str | Path, robot: int = 1) -> MRCLAMRobot:
    """One robot of an MRCLAM dataset folder (see the module docstring)."""
    folder = Path(folder)
    if not folder.is_dir():
        raise InputError(f"{folder}: not a folder (expected an MRCLAM dataset folder)")
    odo_p = _find(folder, f"Robot{robot}_Odometry")
    meas_p = _find(folder, f"Robot{robot}_Measurement")
    gt_p = _find(folder, f"Robot{robot}_Groundtruth", required=False)
    timed = [(p, *_read_dat(p, n)) for p, n in ((odo_p, 3), (meas_p, 4), (gt_p, 4)) if p]
    for (p, arr, lines), cols in zip(timed, (_ODO, _MEAS, _GT)):
        _check_sorted(arr[:, 0], p, lines)
        _check_magnitudes(arr, cols, p, lines)
    odo, meas = timed[0][1], timed[1][1]
    _check_ids(meas[:, 1], meas_p, timed[1][2], "measured barcode", unique=False)
    _check_range_bearing(meas, meas_p, timed[1][2])
    gt = timed[2][1] if gt_p else None
    lm_p, codes_p = _find(folder, "Landmark_Groundtruth"), _find(folder, "Barcodes")
    lm, lm_lines = _read_dat(lm_p, 3)
    _check_magnitudes(lm, (None, "x", "y"), lm_p, lm_lines)
    codes, code_lines = _read_dat(codes_p, 2)
    _check_ids(lm[:, 0], lm_p, lm_lines, "landmark subject")
    _check_ids(codes[:, 1], codes_p, code_lines, "barcode")
    _check_ids(codes[:, 0], codes_p, code_lines, "barcode subject", unique=False)
    barcodes = {int(b): int(s) for s, b in codes}
    return MRCLAMRobot(odo, meas, gt, lm[:, 1:3].copy(), lm[:, 0].astype(int), barcodes)


_LIMITS = {"v": ("m/s", MAX_MAGNITUDE), "w": ("rad/s", MAX_MAGNITUDE),
           "range": ("m", MAX_MAGNITUDE), "x": ("m", MAX_MAGNITUDE), "y": ("m", MAX_MAGNITUDE),
           "theta": ("rad", MAX_MAGNITUDE), "t": ("s", MAX_TIME)}  # fmt: skip
_ODO, _MEAS, _GT = ("t", "v", "w"), ("t", None, "range", None), ("t", "x", "y", "theta")
"""The columns of each timed file :func:`_check_magnitudes` checks (bearings have their
own check, ids theirs)."""


def _csv(path, columns: tuple[str, ...], what: str) -> np.ndarray:
    return _csv_lines(path, columns, what)[0]


def _csv_lines(path, columns: tuple[str, ...], what: str) -> tuple[np.ndarray, list[int]]:
    """The columns of a CSV file ``(rows, len(columns))`` and each row's line number."""
    _, rows = read_rows(path, columns, what)
    if not rows:
        raise fail(path, 0, f"{what} has no data rows")
    return np.array([[r.float(c) for c in columns] for r in rows]), [r.line for r in rows]


def read_generic(
    odometry: str | Path,
    measurements: str | Path,
    landmarks: str | Path,
    groundtruth: str | Path | None = None,
) -> MRCLAMRobot:
    """The generic CSVs as an :class:`MRCLAMRobot` (landmark ids are their own barcodes)."""
    timed = [
        (p, *_csv_lines(p, cols, what))
        for p, cols, what in (
            (odometry, ("t", "v", "w"), "odometry CSV"),
            (measurements, ("t", "landmark", "range", "bearing"), "measurements CSV"),
            (groundtruth, ("t", "x", "y", "theta"), "ground-truth CSV"),
        )
        if p
    ]
    for (p, arr, lines), cols in zip(timed, (_ODO, _MEAS, _GT)):
        _check_sorted(arr[:, 0], p, lines)
        _check_magnitudes(arr, cols, p, lines)
    odo, meas = timed[0][1], timed[1][1]
    _check_ids(meas[:, 1], measurements, timed[1][2], "measured landmark", unique=False)
    _check_range_bearing(meas, measurements, timed[1][2])
    gt = timed[2][1] if groundtruth else None
    lm, lm_lines = _csv_lines(landmarks, ("id", "x", "y"), "landmarks CSV")
    _check_magnitudes(lm, (None, "x", "y"), landmarks, lm_lines)
    _check_ids(lm[:, 0], landmarks, lm_lines, "landmark id")
    ids = lm[:, 0].astype(int)
    return MRCLAMRobot(odo, meas, gt, lm[:, 1:3].copy(), ids, {int(i): int(i) for i in ids})


def write_poses(path: str | Path, times: np.ndarray, poses: np.ndarray) -> Path:
    """Write a pose track ``t,x,y,theta``."""
    rows = [(float(t), *map(float, p)) for t, p in zip(times, poses)]
    return write_rows(path, ("t", "x", "y", "theta"), rows)


def read_poses(path: str | Path, robot: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """``(times (n,), poses (n, 3))`` of a pose CSV, an MRCLAM ``.dat`` ground truth or an
    MRCLAM folder (its ``RobotN_Groundtruth``)."""
    path = Path(path)
    if path.is_dir():
        path = _find(path, f"Robot{robot}_Groundtruth")
    if path.name.endswith((".dat", ".dat.gz")):
        arr, lines = _read_dat(path, 4)
    else:
        arr, lines = _csv_lines(path, ("t", "x", "y", "theta"), "pose CSV")
    _check_sorted(arr[:, 0], path, lines)
    _check_magnitudes(arr, _GT, path, lines)  # a pose of 1e200 m made the RMSE None
    return arr[:, 0], arr[:, 1:4]
