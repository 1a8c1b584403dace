"""Box files of the group labeller (seed 004): CAVIAR CVML XML, PETS2009 XML, MOTChallenge.

Inputs (``docs/formats.md``): a CAVIAR CVML ground-truth file (``<frame number>``,
``<objectlist><object id><box xc yc w h>``, ``<grouplist>``), a PETS2009 XML of the same
frame/object/box layout, or a MOTChallenge text file ``frame,id,bb_left,bb_top,w,h[,conf,
...]`` (``gt.txt``, or a tracker's output; rows with ``conf = 0`` are ignored, as in
MOT16+ ``gt.txt``; ``id = -1`` detections cannot make strokes; a ground truth being
scored also reads the classes of a MOT16/17/20 ``gt.txt``,
:func:`read_mot_truth`). An ETH / UCY ``obsmat.txt`` (tracks in world metres,
:mod:`models.jorge.eth`) is read through a SIMULATED oblique camera. Any of them may be
gzipped. A MOTChallenge file's frame rate is the ``frameRate`` of the ``seqinfo.ini``
beside it or one folder up (the challenge's ``SEQ/gt/gt.txt`` and ``SEQ/seqinfo.ini``);
without one it is assumed to be 25 fps, CAVIAR's (:func:`mot_frame_rate`).

Outputs: strokes CSV ``stroke,start,end,label,truth`` (``label``: the object ids the
stroke is labelled with, separated by spaces; ``truth``: the people in the region), after
the header lines ``# seed=S``, ``# strokes={...}`` (the
:class:`~models.jorge.strokes.StrokeConfig` the strokes were built with, JSON) and, for an
obsmat file, ``# view={...}`` (its :class:`~models.jorge.eth.ObliqueView`): what
``dbntrack eval`` needs to rebuild the same strokes; MOTChallenge tracks
``frame,id,bb_left,bb_top,w,h,1,-1,-1,-1`` (one row per frame and per object of a stroke's
label, the region's box).
"""

from __future__ import annotations

import configparser
import dataclasses
import json
import math
from pathlib import Path

import numpy as np

from dbn.errors import DBNError, InputError, in_file
from models.io.table import as_float, as_int, fail, read_lines, require_file, write_rows

__all__ = ["read_boxes", "read_mot", "read_mot_truth", "mot_distractor_classes",
           "mot_frame_rate", "frame_rate_source", "is_obsmat", "is_mot", "is_xml",
           "is_mot_gt", "mot_sequence",
           "write_strokes", "read_stroke_rows", "read_strokes", "read_strokes_header",
           "write_mot_tracks"]

MOT_DEFAULT_FPS = 25.0
"""Frame rate assumed for a MOTChallenge file without a ``seqinfo.ini`` (CAVIAR's)."""


def mot_frame_rate(path: str | Path) -> tuple[float | None, Path | None]:
    """``(frameRate, seqinfo.ini)`` of a MOTChallenge box file: the ``[Sequence]``
    ``frameRate`` of the ``seqinfo.ini`` in the file's folder or the one above it
    (``SEQ/gt/gt.txt`` -> ``SEQ/seqinfo.ini``), nearest first; ``(None, None)`` when
    there is none or it has no ``frameRate``.

    Raises
    ------
    InputError
        A ``seqinfo.ini`` that cannot be read, or a ``frameRate`` that is not a finite
        number > 0 (naming the file).
    """
    ini = _seqinfo(Path(path))
    if ini is None:
        return None, None
    text = _ini_option(ini, "frameRate")
    if text is None:
        return None, None
    try:
        fps = float(text)
    except ValueError:
        fps = float("nan")
    if not (np.isfinite(fps) and fps > 0):
        raise fail(ini, 0, f"[Sequence] frameRate = {text!r}: expected a number > 0")
    return fps, ini


def _seqinfo(path: Path) -> Path | None:
    """The ``seqinfo.ini`` in the folder of ``path`` or the one above it, nearest first."""
    for folder in (path.parent, path.parent.parent):
        if (folder / "seqinfo.ini").is_file():
            return folder / "seqinfo.ini"
    return None


def _ini_option(ini: Path, option: str) -> str | None:
    """``[Sequence] option`` of a ``seqinfo.ini``, None when absent; a file that is not
    INI is an :class:`InputError` naming it."""
    parser = configparser.ConfigParser(interpolation=None)
    try:
        parser.read_string("".join(read_lines(ini, "seqinfo.ini")), source=str(ini))
    except configparser.Error as exc:
        raise fail(ini, getattr(exc, "lineno", 0) or 0, f"not an INI file ({type(exc).__name__})") from None
    return parser.get("Sequence", option) if parser.has_option("Sequence", option) else None


def _mot_fields(line: str) -> list[str]:
    """The fields of one MOTChallenge line: comma-separated (an empty field stays, so a
    missing value is an error in its own column, never a shift of the next ones), or
    separated by white space where the line has no comma."""
    text = line.strip()
    return [x.strip() for x in text.split(",")] if "," in text else text.split()


MOT_DISTRACTOR_CLASSES = (2, 7, 8, 12)
"""Classes of a MOT16/17/20 ground truth whose boxes are not scored (person on vehicle,
static person, distractor, reflection): a result's box matched to one of them is dropped,
as the challenge's evaluation does; MOT20 adds 6, non-motorised vehicle
(:func:`mot_distractor_classes`)."""

MOT_CLASS_FIELDS = 9
"""Fields of a MOT16/17/20 ground-truth row, ``frame,id,bb_left,bb_top,w,h,flag,class,
visibility``: the only layout with a class (MOT15's and the results' 10 fields end in
world coordinates)."""


def _mot_rows(path: Path, classes: bool):
    """Each row of a MOTChallenge file: ``(line, frame, id, (left, top, w, h), conf,
    class)``, ``conf`` NaN where the row has none, ``class`` None unless ``classes`` and
    the row has :data:`MOT_CLASS_FIELDS` fields (an int in 1..12). Frames >= 0 and boxes
    of positive size within the pixel bound are checked on every row."""
    from models.jorge.strokes import MAX_PIXELS

    for line_no, line in enumerate(read_lines(path, "MOTChallenge file"), start=1):
        fields = _mot_fields(line)
        if not any(fields) or fields[0].startswith("#"):
            continue
        if len(fields) < 6:
            raise fail(path, line_no, f"{len(fields)} fields, need frame,id,x,y,w,h")
        fr, oid = (
            as_int(fields[0], path, line_no, "frame"),
            as_int(fields[1], path, line_no, "id"),
        )
        x, y, w, h = (as_float(v, path, line_no, n) for v, n in zip(fields[2:6], "xywh"))
        conf = np.nan
        if len(fields) > 6:
            conf = as_float(fields[6], path, line_no, "conf", allow_empty=True)
        cls = None
        if classes and len(fields) == MOT_CLASS_FIELDS:
            cls = as_int(fields[7], path, line_no, "class")
            if not 1 <= cls <= 12:
                raise fail(path, line_no, f"class = {cls}: a {MOT_CLASS_FIELDS}-field "
                           "ground-truth row is frame,id,box,flag,class,visibility "
                           "with class 1..12")  # fmt: skip
        if fr < 0:
            raise fail(path, line_no, f"frame = {fr}: frames count from 0 (MOTChallenge's from 1)")
        if w <= 0 or h <= 0:
            raise fail(path, line_no, f"box width/height must be > 0, got {w}, {h}")
        if max(abs(x + w / 2), abs(y + h / 2), w, h) > MAX_PIXELS:
            raise fail(path, line_no, f"box {x}, {y}, {w}, {h} is beyond {MAX_PIXELS:g} pixels")
        yield line_no, fr, oid, (x, y, w, h), conf, cls


def is_mot_gt(path: str | Path) -> bool:
    """A MOTChallenge ground truth's file name, ``gt.txt`` (or ``.gz``)."""
    return Path(path).name.lower().removesuffix(".gz") == "gt.txt"


def mot_sequence(path: str | Path) -> str | None:
    """The sequence of a MOTChallenge ground truth ``gt.txt`` (or ``.gz``): its folder's
    name, or the one above a ``gt`` folder (``PETS09-S2L1/gt/gt.txt`` -> ``PETS09-S2L1``);
    None for another file name or a ``gt.txt`` without a folder."""
    parts = Path(path).parts
    if len(parts) < 2 or not is_mot_gt(path):
        return None
    return parts[-3] if parts[-2].lower() == "gt" and len(parts) >= 3 else parts[-2]


def read_mot(path: str | Path):
    """A MOTChallenge box file as a :class:`models.jorge.strokes.GroundTruth` named by its
    sequence (:func:`mot_sequence`) or else its file name; its ``fps`` from
    :func:`mot_frame_rate`, else :data:`MOT_DEFAULT_FPS`. Rows with ``conf = 0`` are not
    people."""
    path = Path(path)
    return _people(path, _mot_rows(path, classes=False))


def read_mot_truth(path: str | Path):
    """A MOTChallenge ground truth being scored, read once as the challenge's evaluation
    reads ``gt.txt``: ``(GroundTruth, distractors)``. A row of :data:`MOT_CLASS_FIELDS`
    fields is a person only if its class is 1 (pedestrian) and its flag is not 0.
    ``distractors``: ``frame -> (boxes, distractor)``, the box ``(n, 4)`` as ``(left, top,
    w, h)`` of every such row, whatever its flag, and whether its class is a distractor
    (:func:`mot_distractor_classes`): what a result is matched against before scoring.
    Empty for a file without classes (nothing is dropped)."""
    path = Path(path)
    rows = list(_mot_rows(path, classes=True))
    ignored = mot_distractor_classes(path)
    boxes: dict[int, list] = {}
    for _, fr, _, box, _, cls in rows:
        if cls is not None:
            boxes.setdefault(fr, []).append((*box, cls in ignored))
    distractors = {f: (np.array([r[:4] for r in v], float), np.array([r[4] for r in v], bool))
                   for f, v in boxes.items()}
    return _people(path, rows), distractors


def _people(path: Path, rows):
    """The :class:`~models.jorge.strokes.GroundTruth` of the rows of :func:`_mot_rows`
    that are people: ``conf != 0`` and class 1 where the row has a class."""
    from models.jorge.strokes import _assemble

    frames: dict[int, dict[int, tuple]] = {}
    for line_no, fr, oid, (x, y, w, h), conf, cls in rows:
        if conf == 0 or cls not in (None, 1):
            continue
        if oid < 0:
            raise fail(path, line_no, f"id = {oid}: detections without ids cannot make "
                       "strokes (give tracks with ids, e.g. gt.txt)")  # fmt: skip
        objs = frames.setdefault(fr, {})
        if oid in objs:
            raise fail(path, line_no, f"id {oid} appears twice in frame {fr}")
        objs[oid] = (x + w / 2, y + h / 2, w, h)
    if not frames:
        raise fail(path, 0, "no boxes")
    fps, _ = mot_frame_rate(path)
    try:
        fps = MOT_DEFAULT_FPS if fps is None else fps
        return _assemble(mot_sequence(path) or path.name, sorted(frames.items()), [], fps=fps)
    except DBNError as exc:
        raise in_file(exc, path) from None


def mot_distractor_classes(path: str | Path) -> tuple[int, ...]:
    """:data:`MOT_DISTRACTOR_CLASSES`, and class 6 for a MOT20 sequence (its
    ``seqinfo.ini`` ``[Sequence]`` ``name`` starts with ``MOT20``), as the challenge's
    evaluation does."""
    ini = _seqinfo(Path(path))
    name = _ini_option(ini, "name") if ini is not None else None
    extra = (6,) if name is not None and name.upper().startswith("MOT20") else ()
    return tuple(sorted(MOT_DISTRACTOR_CLASSES + extra))


def read_boxes(path: str | Path, view=None):
    """A :class:`~models.jorge.strokes.GroundTruth` from CAVIAR / PETS2009 XML, MOT text,
    or an ETH / UCY ``obsmat`` file (named ``obsmat*``: world metres seen through the
    SIMULATED camera ``view``, an :class:`~models.jorge.eth.ObliqueView`, default
    ``ObliqueView()``; :func:`models.jorge.eth.load_eth`).

    Raises
    ------
    InputError
        A ``view`` for a file that is not an obsmat file (its boxes are the file's own);
        a bad file, naming it (and the line or element).
    """
    from models.jorge.eth import load_eth
    from models.jorge.strokes import load_ground_truth

    path = require_file(path, "box file")
    if is_obsmat(path):
        return load_eth(path, view)
    if view is not None:
        raise InputError(f"{path}: a camera view applies only to an ETH / UCY obsmat file "
                         "(tracks in metres); this file has image boxes")  # fmt: skip
    if not is_xml(path):
        return read_mot(path)
    return load_ground_truth(path)  # its errors name the file (and line or element)


def frame_rate_source(path: str | Path) -> str:
    """Where :func:`read_boxes` takes the file's frame rate from: the XML format's own
    (CAVIAR 25, PETS2009 7), a MOTChallenge ``seqinfo.ini`` (its path), or "assumed 25
    fps" (:data:`MOT_DEFAULT_FPS`)."""
    path = Path(path)
    if is_obsmat(path):
        return "file format (ETH / UCY obsmat, 2.5 annotations per second)"
    if is_xml(path):
        return "file format (CAVIAR 25 fps, PETS2009 7 fps)"
    _, ini = mot_frame_rate(path)
    if ini is not None:
        return str(ini)
    return (f"assumed {MOT_DEFAULT_FPS:g} fps: no seqinfo.ini frameRate beside the MOTChallenge file; "
            "give config fps (the link gates are in seconds)")


def is_obsmat(path: str | Path) -> bool:
    """An ETH / UCY ``obsmat`` file (its name starts with ``obsmat``: tracks in metres)."""
    return Path(path).name.lower().startswith("obsmat")


def is_mot(path: str | Path) -> bool:
    """A MOTChallenge text file: neither XML nor obsmat (:func:`read_boxes`'s rule)."""
    return not is_obsmat(path) and not is_xml(path)


def is_xml(path: str | Path) -> bool:
    """CAVIAR / PETS2009 XML (``.xml`` or ``.xml.gz``), else MOTChallenge text."""
    return Path(path).name.lower().removesuffix(".gz").endswith(".xml")


def _ids(label) -> str:
    return " ".join(str(int(o)) for o in sorted(label))


def write_strokes(path, strokes, labels, seed: int | None = None, view=None, parents=None,
                  fps=None, network=None, source: str | None = None) -> Path:
    """The header (``# seed=S`` where ``seed`` is given, ``# strokes={StrokeConfig fields}``
    where the :class:`~models.jorge.strokes.StrokeSet` ``strokes`` has a config, ``#
    view={ObliqueView fields}`` where ``view`` is given, ``# fps=F`` where ``fps``, the
    labeller's frame rate, is given, ``# network={...}`` where ``network``, the
    labeller's :class:`~models.jorge.network.NetworkConfig` fields set away from the
    defaults, is given, ``# input=regions`` where ``source`` says the strokes came from a
    regions file, :mod:`models.io.jorge_regions`) then ``stroke,start,end,label,truth``
    rows, with a ``parents`` column (each stroke's links: earlier stroke indices,
    space-separated; empty for a root) where ``parents`` (a sequence of int sequences, one
    per stroke) is given."""
    if source not in (None, "boxes", "regions"):
        raise InputError(f"write_strokes: source = {source!r}: expected 'boxes' or 'regions'")
    rows = [(s.index, s.start, s.end, _ids(lab), _ids(s.truth)) for s, lab in zip(strokes, labels)]
    columns: tuple = ("stroke", "start", "end", "label", "truth")
    if parents is not None:
        rows = [(*r, _ids(par)) for r, par in zip(rows, parents)]
        columns += ("parents",)
    head = [] if seed is None else [f"seed={int(seed)}"]
    if getattr(strokes, "config", None) is not None:
        head.append("strokes=" + json.dumps(dataclasses.asdict(strokes.config)))
    if view is not None:
        head.append("view=" + json.dumps(dataclasses.asdict(view)))
    if fps is not None:
        head.append(f"fps={float(fps)!r}")
    if network is not None:
        head.append("network=" + json.dumps(dict(network)))
    if source is not None:
        head.append(f"input={source}")
    return write_rows(path, columns, rows, head)


_HEADER_KEYS = {"seed": int, "strokes": dict, "view": dict, "fps": float, "network": dict,
                "input": str}


def read_strokes_header(path: str | Path) -> dict:
    """The header of a strokes CSV (:func:`write_strokes`): ``seed`` (int), ``strokes``
    (the :class:`~models.jorge.strokes.StrokeConfig` fields), ``view`` (the
    :class:`~models.jorge.eth.ObliqueView` fields), ``fps`` (float), ``network`` (the
    :class:`~models.jorge.network.NetworkConfig` fields the run set) and ``input``
    (``"regions"`` for strokes read from a regions file), each where the file has it
    (files of earlier versions carry only the seed).

    Raises
    ------
    InputError
        A ``# seed=`` line that is not an integer, a ``# strokes=``, ``# view=`` or
        ``# network=`` line that is not a JSON object, a ``# fps=`` line that is not a
        finite number > 0, an ``# input=`` other than ``boxes`` or ``regions``, or one of
        them twice (naming the file and line).
        Other leading ``#`` lines are comments.
    """
    path = require_file(path, "strokes CSV")
    out: dict = {}
    for line_no, line in enumerate(read_lines(path, "strokes CSV"), start=1):
        if not line.startswith("#"):
            break
        key, eq, value = line[1:].strip().partition("=")
        key = key.strip()
        if not eq or key not in _HEADER_KEYS:
            continue  # another comment
        if key in out:
            raise fail(path, line_no, f"a second '# {key}=' header line")
        parsed = _header_value(key, value)
        if parsed is None:
            kind = {"seed": "an integer", "fps": "a finite number > 0",
                    "input": "'boxes' or 'regions'"}.get(key, "a JSON object")  # fmt: skip
            raise fail(path, line_no, f"{key} = {value.strip()!r}: expected {kind}")
        out[key] = parsed
    return out


def _header_value(key: str, value: str):
    """A header line's value as :data:`_HEADER_KEYS` types it; ``None`` where it is not."""
    if key == "input":
        return value.strip() if value.strip() in ("boxes", "regions") else None
    try:
        parsed = int(value) if key == "seed" else json.loads(value)
    except ValueError:
        return None
    if isinstance(parsed, bool):
        return None
    if key == "fps":
        ok = isinstance(parsed, int | float) and math.isfinite(parsed) and parsed > 0
        return float(parsed) if ok else None
    return parsed if isinstance(parsed, _HEADER_KEYS[key]) else None


def read_strokes(path: str | Path) -> tuple[int | None, list[dict]]:
    """``(seed, rows)`` of a strokes CSV: the header's seed (the whole header:
    :func:`read_strokes_header`) and :func:`read_stroke_rows`."""
    return read_strokes_header(path).get("seed"), read_stroke_rows(path)


def read_stroke_rows(path: str | Path) -> list[dict]:
    """The rows of a strokes CSV (:func:`write_strokes`), each ``stroke``, ``start``,
    ``end`` (ints), ``label`` and ``truth`` (frozensets of ints; ``truth`` empty where
    the file has no such column) and ``parents`` (a sorted tuple of earlier stroke
    indices; ``None`` where the file has no such column, as in files of earlier versions).

    Raises
    ------
    InputError
        A missing column, a label, truth or parents that is not ints (>= 0) separated by
        spaces, an empty label, or a parent that is not an earlier stroke (naming the file
        and line).
    """
    from models.io.table import read_rows

    _, rows = read_rows(path, ("stroke", "start", "end", "label"), "strokes CSV")
    out = []
    for r in rows:
        try:
            label = frozenset(int(x) for x in r["label"].split())
            truth = frozenset(int(x) for x in r.get("truth", "").split())
        except ValueError:
            raise r.fail(f"label {r['label']!r} / truth {r.get('truth')!r}: ints separated "
                         "by spaces expected") from None  # fmt: skip
        if not label:
            raise r.fail("empty label")
        if min(label | truth) < 0:
            raise r.fail(f"label {r['label']!r} / truth {r.get('truth')!r}: objects count from 0")
        out.append({"stroke": r.int("stroke"), "start": r.int("start"), "end": r.int("end"),
                    "label": label, "truth": truth, "parents": _parents(r)})  # fmt: skip
    return out


def _parents(row) -> tuple[int, ...] | None:
    """A row's ``parents`` (:func:`read_stroke_rows`): distinct earlier strokes, sorted."""
    if "parents" not in row:
        return None
    try:
        parents = [int(x) for x in (row["parents"] or "").split()]
    except ValueError:
        raise row.fail(f"parents {row['parents']!r}: stroke indices separated by spaces "
                       "expected") from None  # fmt: skip
    stroke = row.int("stroke")
    if len(set(parents)) != len(parents) or not all(0 <= p < stroke for p in parents):
        raise row.fail(f"parents {row['parents']!r}: distinct earlier strokes (0..{stroke - 1}) "
                       "expected")  # fmt: skip
    return tuple(sorted(parents))


def write_mot_tracks(path, strokes, labels) -> Path:
    """MOTChallenge rows ``frame,id,bb_left,bb_top,w,h,1,-1,-1,-1`` (ids = object + 1)."""
    rows = []
    for s, lab in zip(strokes, labels):
        ext = s.extent if s.extent is not None else np.full((s.frames.size, 2), 10.0)
        for fr, (cx, cy), (w, h) in zip(s.frames, s.positions, ext):
            for o in sorted(lab):
                rows.append((int(fr), int(o) + 1, round(cx - w / 2, 2), round(cy - h / 2, 2),
                             round(w, 2), round(h, 2), 1, -1, -1, -1))  # fmt: skip
    rows.sort(key=lambda r: (r[0], r[1]))
    path = Path(path)
    with open(path, "w", encoding="utf-8") as f:
        f.writelines(",".join(str(x) for x in r) + "\n" for r in rows)
    return path
