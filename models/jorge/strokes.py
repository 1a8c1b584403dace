"""Ground truth loaders (CAVIAR CVML, PETS2009) and the simulated low-level tracker of
seed 004, section 3: it turns per-person boxes into *strokes*.

A stroke is a maximal run of consecutive frames in which one image region (an isolated
person, or a group of people whose boxes overlap) is followed without a break. Seed 004
(section 3) ends a stroke when neighbouring regions conflict (overlap) and when a region
is occluded by the background; the Bayes net of :mod:`models.jorge.network` then labels
the strokes.

What is real and what is simulated
----------------------------------
* Real: the boxes (CAVIAR / PETS2009 ground truth; see ``../shared/data/README.md``),
  hence each stroke's region centre and region size (``Stroke.extent``, the bounding box
  of its people's boxes per frame).
* Simulated (seeded): the occlusions by the background (boxes dropped for gaps of a few
  frames) and the colours. The ground truth has no appearance, so each person gets a
  palette of ``num_colours`` distinct colours drawn from a shared pool of ``pool_size``
  colours (so people share colours); each dominant colour of a stroke is one of its
  people's palette colours with probability ``match_prob`` and otherwise a colour outside
  their palettes. A group stroke's colours are drawn from the union of its members'
  palettes. The palette a label receives when it is created at a stroke (seed 004,
  sec. 4.1) is simulated as the palette of the stroke's people (a clean estimate over
  the whole segment), so that a stroke's colour matches its right label with
  probability ``match_prob``, as eq. 6 assumes.

Rules of the simulated tracker (defaults of issue 4)
----------------------------------------------------
1. In each frame the visible boxes are joined into regions: two people are in one region
   when their boxes overlap with IoU > ``iou_threshold`` (0.05), closed transitively.
2. Background occlusion: each person has gaps of ``gap_min``..``gap_max`` (5-15) frames,
   on average ``gaps_per_100`` (4) gap starts per 100 frames of presence. A region
   vanishes during a gap of its lowest-id member (so a region of any size vanishes at the
   rate of one person).
3. A stroke continues while the same set of people forms a region in consecutive frames;
   any change of the member set (merge, split, a vanished region) ends it, and a new
   stroke starts with the new region.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from dbn.checks import (
    check_nonnegative,
    check_number_fields,
    check_size,
    check_type,
    is_real_number,
    is_whole,
    make_rng,
    real_array,
    whole_array,
)
from dbn.errors import (
    DBNError,
    FileFormatError,
    InputError,
    ModelError,
    NonFiniteError,
    ShapeError,
    TimeOrderError,
    in_file,
)
from models.io.xmlfile import read_xml_root

__all__ = [
    "GroundTruth",
    "Stroke",
    "StrokeConfig",
    "StrokeSet",
    "load_caviar",
    "load_pets2009",
    "load_ground_truth",
    "resample",
    "head",
    "check_lower_rate",
    "pairwise_iou",
    "regions",
    "region_labels",
    "gap_mask",
    "build_strokes",
    "make_stroke",
    "PETS2009_FPS",
    "check_frame_rate",
]


# --------------------------------------------------------------------------------------
# ground truth
# --------------------------------------------------------------------------------------
@dataclass(frozen=True)
class GroundTruth:
    """Per-frame boxes of every person of a sequence.

    Attributes
    ----------
    name : str
        Sequence name.
    frames : ndarray, shape (num_frames,)
        Frame numbers, strictly increasing.
    ids : ndarray, shape (num_ids,)
        Person ids of the annotation.
    boxes : ndarray, shape (num_frames, num_ids, 4)
        Boxes ``(xc, yc, w, h)`` in pixels; NaN where the person is absent.
    groups : tuple of tuple of frozenset
        Annotated groups per frame (CAVIAR grouplists; empty for PETS2009). Kept for
        reference; the stroke builder uses box overlap, as a low-level tracker would.
    fps : float
        Frame rate (25).
    """

    name: str
    frames: np.ndarray
    ids: np.ndarray
    boxes: np.ndarray
    groups: tuple = ()
    fps: float = 25.0

    def __post_init__(self) -> None:
        check_type("GroundTruth.name", self.name, str, InputError)
        fps = check_frame_rate(self.fps, "GroundTruth.fps", InputError)
        frames = whole_array("GroundTruth.frames", self.frames)
        boxes = real_array("GroundTruth.boxes", self.boxes)
        ids = whole_array("GroundTruth.ids", self.ids)
        if frames.ndim != 1:
            raise ShapeError(f"GroundTruth.frames must be 1-D, got shape {frames.shape}")
        if boxes.shape != (frames.shape[0], ids.shape[0], 4):
            raise ShapeError(
                f"GroundTruth.boxes must have shape (num_frames, num_ids, 4) = "
                f"({frames.shape[0]}, {ids.shape[0]}, 4), got {boxes.shape}"
            )
        if frames.size > 1 and np.any(np.diff(frames) <= 0):
            k = int(np.argmax(np.diff(frames) <= 0))
            raise TimeOrderError(
                f"GroundTruth.frames out of order: frame {frames[k + 1]} after {frames[k]}"
            )
        if len(set(ids.tolist())) != ids.size:
            raise InputError(f"GroundTruth.ids has duplicates: {ids.tolist()}")
        present = ~np.isnan(boxes)
        if np.any(present.any(-1) != present.all(-1)):
            raise InputError("GroundTruth.boxes: a box has some but not all coordinates NaN")
        if np.any(np.isinf(boxes)):
            raise NonFiniteError("GroundTruth.boxes holds an infinite coordinate")
        wh = boxes[..., 2:][present[..., 2:]]
        if np.any(wh <= 0):
            raise InputError(f"GroundTruth.boxes: width/height must be > 0, got {wh[wh <= 0][0]}")
        _check_pixels(boxes, frames, ids)
        object.__setattr__(self, "frames", frames)
        object.__setattr__(self, "ids", ids)
        object.__setattr__(self, "boxes", boxes)
        object.__setattr__(self, "fps", fps)

    @property
    def num_frames(self) -> int:
        return int(self.frames.shape[0])

    @property
    def num_boxes(self) -> int:
        """Annotated boxes: (frame, person) pairs where the person is present."""
        return int(np.isfinite(self.boxes[..., 0]).sum())

    @property
    def duration_s(self) -> float:
        """Duration in seconds at ``fps`` frames per second."""
        return self.num_frames / self.fps


def _check_pixels(boxes: np.ndarray, frames: np.ndarray, ids: np.ndarray) -> None:
    """:class:`InputError` naming the first frame and id whose box centre is beyond
    :data:`MAX_PIXELS` or whose width or height exceeds it (NaN boxes: absent)."""
    with np.errstate(invalid="ignore"):
        bad = (np.abs(boxes) > MAX_PIXELS).any(-1)
    if bad.any():
        r, c = np.argwhere(bad)[0]
        raise InputError(
            f"GroundTruth.boxes: frame {frames[r]} id {ids[c]}: box {boxes[r, c].tolist()} "
            f"is beyond {MAX_PIXELS:g} pixels (centre or size; a unit or scale mistake?)"
        )


def _int_attr(elem: ET.Element, key: str, path, where: str) -> int:
    """An integer attribute; missing or malformed is a FileFormatError naming the element."""
    text = elem.get(key)
    try:
        return int(text)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise FileFormatError(
            path, f"{where}: <{elem.tag} {key}={text!r}> is not an integer"
        ) from None


MAX_PIXELS = 1e6
"""Largest pixel coordinate or box side the readers, :class:`GroundTruth` and the
labeller accept: a larger one is a unit or scale mistake, not an image."""

PETS2009_FPS = 7.0
"""Frame rate of the PETS2009 cameras ("~7" fps for every view, PETS2009 dataset page,
http://www.cvg.rdg.ac.uk/PETS2009/a.html); CAVIAR is 25 fps."""


def _assemble(name: str, per_frame: list[tuple[int, dict[int, tuple[float, ...]]]], groups,
              fps: float = 25.0) -> GroundTruth:
    frames = np.array([f for f, _ in per_frame], dtype=np.int64)
    if frames.size > 1 and np.any(np.diff(frames) <= 0):
        k = int(np.argmax(np.diff(frames) <= 0))
        raise TimeOrderError(f"{name}: frame {frames[k + 1]} comes after frame {frames[k]}")
    ids = sorted({i for _, objs in per_frame for i in objs})
    col = {i: c for c, i in enumerate(ids)}
    boxes = np.full((len(per_frame), len(ids), 4), np.nan)
    for r, (_, objs) in enumerate(per_frame):
        for i, b in objs.items():
            boxes[r, col[i]] = b
    return GroundTruth(name=name, frames=frames, ids=np.array(ids, dtype=np.int64),
                       boxes=boxes, groups=tuple(groups), fps=fps)


def _parse_box(elem: ET.Element | None, where: str) -> tuple[float, float, float, float]:
    if elem is None:
        raise InputError(f"{where}: object without a <box>")
    try:
        b = tuple(float(elem.get(k)) for k in ("xc", "yc", "w", "h"))  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise InputError(f"{where}: malformed box {elem.attrib}") from None
    if not all(np.isfinite(b)):
        raise NonFiniteError(f"{where}: non-finite box {elem.attrib}")
    if b[2] <= 0 or b[3] <= 0:
        raise InputError(f"{where}: box width/height must be > 0, got {elem.attrib}")
    if max(abs(v) for v in b) > MAX_PIXELS:
        raise InputError(f"{where}: box {elem.attrib} is beyond {MAX_PIXELS:g} pixels")
    return b  # type: ignore[return-value]


def _parse_frames(root: ET.Element, path, with_groups: bool):
    per_frame = []
    groups = []
    for fr in root.iter("frame"):
        number = _int_attr(fr, "number", path, "frame")
        objs: dict[int, tuple[float, ...]] = {}
        ol = fr.find("objectlist")
        for o in ol.findall("object") if ol is not None else []:
            oid = _int_attr(o, "id", path, f"frame {number}: object")
            where = f"frame {number} object {oid}"
            if oid in objs:
                raise FileFormatError(path, f"{where}: id appears twice in the frame")
            objs[oid] = _parse_box(o.find("box"), where)
        per_frame.append((number, objs))
        if with_groups:
            gl = fr.find("grouplist")
            gs = []
            for g in gl.findall("group") if gl is not None else []:
                members = g.findtext("members", "")
                try:
                    gs.append(frozenset(int(m) for m in members.split(",") if m.strip()))
                except ValueError:
                    raise FileFormatError(
                        path, f"frame {number}: group members {members!r} are not integer ids"
                    ) from None
            groups.append(tuple(gs))
    if not per_frame:
        raise FileFormatError(path, f"no <frame> elements under <{root.tag}>")
    return per_frame, groups


def _load_xml(path, with_groups: bool, fps: float) -> GroundTruth:
    """Parse, check and assemble; every library error names ``path``."""
    root = read_xml_root(path)
    stem = Path(path).name if with_groups else Path(path).name.split(".")[0]
    name = root.get("name") or stem
    try:
        per_frame, groups = _parse_frames(root, path, with_groups)
        return _assemble(name, per_frame, groups, fps=fps)
    except DBNError as exc:
        raise in_file(exc, path) from None


def load_caviar(path: str | Path) -> GroundTruth:
    """Load a CAVIAR CVML ground-truth file (``.xml`` or ``.xml.gz``).

    Parameters
    ----------
    path : path-like
        E.g. ``datasets.require("caviar", "ms3ggt.xml.gz")``.

    Returns
    -------
    GroundTruth
        Boxes ``(xc, yc, w, h)`` per frame and person, and the annotated grouplists.

    Raises
    ------
    FileFormatError
        Naming the file (and the line or element): missing, empty, truncated or
        malformed XML, no ``<frame>``, a non-integer frame number, id or group member, a
        duplicated id in a frame.
    TimeOrderError, InputError, NonFiniteError
        (message prefixed by the file) frames out of order, a malformed, empty or
        non-finite box.
    """
    return _load_xml(path, with_groups=True, fps=25.0)


def load_pets2009(path: str | Path) -> GroundTruth:
    """Load the PETS2009 S2.L1 ground truth (OpenTraj XML: frame -> object id -> box).

    Same return value and errors as :func:`load_caviar`; ``groups`` is empty and ``fps``
    is :data:`PETS2009_FPS` (7: the PETS2009 cameras' frame rate).
    """
    return _load_xml(path, with_groups=False, fps=PETS2009_FPS)


def load_ground_truth(path: str | Path) -> GroundTruth:
    """Load either format: CAVIAR if the file has grouplists, else PETS2009."""
    root = read_xml_root(path)
    if root.find(".//grouplist") is not None:
        return load_caviar(path)
    return load_pets2009(path)


def resample(truth: GroundTruth, fps: float) -> GroundTruth:
    """The ground truth as a camera at a lower frame rate ``fps`` would record it: the
    frames nearest to the times ``i / fps`` (the first frame kept), renumbered
    ``0, 1, ...`` at the new rate; boxes and group lists of the kept frames unchanged.

    The stroke builder's gaps are counted in frames and the link rule's limits in
    seconds, so the same scene at 7 fps (PETS2009's rate) tests longer gaps against the
    same limits than at 25 fps (CAVIAR's; issue 16, thirty-first round: SIMULATED meetings
    at 7 fps).

    Parameters
    ----------
    truth : GroundTruth
    fps : float
        New frame rate, at most ``truth.fps``.

    Returns
    -------
    GroundTruth
        ``name`` unchanged, ``fps`` the new rate, about ``num_frames * fps / truth.fps``
        frames.

    Raises
    ------
    InputError
        ``fps`` not a positive finite number, or above ``truth.fps``.
    """
    fps = check_lower_rate(fps, truth.fps, "resample")
    keep = np.unique(np.round(np.arange(0.0, truth.num_frames, truth.fps / fps)).astype(np.int64))
    keep = keep[keep < truth.num_frames]
    groups = tuple(truth.groups[i] for i in keep) if truth.groups else ()
    return GroundTruth(truth.name, np.arange(keep.size), truth.ids, truth.boxes[keep], groups, fps)


def head(truth: GroundTruth, seconds: float) -> GroundTruth:
    """The first ``seconds`` of the ground truth: its frames ``0 .. ceil(seconds * fps) - 1``
    (by position), with the people who appear in them; a shorter sequence is returned
    whole. A smaller size of the same data, e.g. for a benchmark's ``--quick`` run.

    Parameters
    ----------
    truth : GroundTruth
    seconds : float
        A positive finite number.

    Returns
    -------
    GroundTruth
        ``name``, ``fps`` and frame numbers unchanged.

    Raises
    ------
    InputError
        ``seconds`` not a positive finite number.
    """
    seconds = check_nonnegative("head: seconds", seconds)  # a real number, not a bool
    if not 0 < seconds < np.inf:
        raise InputError(f"head: seconds must be a positive finite number, got {seconds!r}")
    n = min(truth.num_frames, int(np.ceil(seconds * truth.fps)))
    present = ~np.isnan(truth.boxes[:n, :, 0]).all(axis=0)
    groups = truth.groups[:n] if truth.groups else ()
    return GroundTruth(truth.name, truth.frames[:n], truth.ids[present], truth.boxes[:n][:, present],
                       groups, truth.fps)


def check_lower_rate(fps: object, source_fps: float, where: str) -> float:
    """``fps`` as a float, checked as a rate to resample to (:func:`resample`): a positive
    finite number at most ``source_fps``; an :class:`InputError` naming ``where`` else."""
    fps = check_frame_rate(fps, where, InputError)
    if fps > source_fps:
        raise InputError(f"{where}: fps {fps:g} is above the source's {source_fps:g}")
    return fps


# --------------------------------------------------------------------------------------
# strokes
# --------------------------------------------------------------------------------------
@dataclass(frozen=True)
class StrokeConfig:
    """Settings of the simulated low-level tracker and colours (issue 4 defaults).

    Attributes
    ----------
    iou_threshold : float
        Boxes of two people with IoU above this join one (group) region.
    gaps_per_100 : float
        Background-occlusion gap starts per person per 100 frames in which the person is
        seen (the per-frame hazard times 100).
    gap_min, gap_max : int
        Gap length range in frames (uniform, inclusive).
    num_colours : int
        N, dominant colours per stroke (seed 004 uses 5).
    pool_size : int
        Size of the shared colour pool the palettes are drawn from.
    match_prob : float
        Probability that one dominant colour of a stroke is one of its people's colours.
    """

    iou_threshold: float = 0.05
    gaps_per_100: float = 4.0
    gap_min: int = 5
    gap_max: int = 15
    num_colours: int = 5
    pool_size: int = 12
    match_prob: float = 0.8

    def __post_init__(self) -> None:
        check_number_fields(self)
        if not 0.0 <= self.iou_threshold < 1.0:
            raise InputError(f"StrokeConfig.iou_threshold must be in [0, 1), got {self.iou_threshold}")
        if self.gaps_per_100 < 0:
            raise InputError(f"StrokeConfig.gaps_per_100 must be >= 0, got {self.gaps_per_100}")
        if not 1 <= self.gap_min <= self.gap_max:
            raise InputError(
                f"StrokeConfig gap range must satisfy 1 <= gap_min <= gap_max, got "
                f"{self.gap_min}..{self.gap_max}"
            )
        if not 1 <= self.num_colours <= self.pool_size:
            raise InputError(
                f"StrokeConfig.num_colours must be in 1..pool_size={self.pool_size}, got {self.num_colours}"
            )
        if not 0.0 < self.match_prob <= 1.0:
            raise InputError(f"StrokeConfig.match_prob must be in (0, 1], got {self.match_prob}")


def check_frame_rate(fps: object, where: str, error: type[Exception] = ModelError) -> float:
    """``fps`` as a float if it is a finite number > 0 (a bool is not a number here);
    else ``error`` naming ``where``. The link gates and the inference period are in
    seconds, so every entry point that takes a frame rate checks it with this, and none
    of them assumes one (``None``: the error says to give it)."""
    if fps is None:
        raise error(f"{where}: fps is required (the strokes' frame rate, e.g. StrokeSet.fps): "
                    "the link gates and the inference period are in seconds")
    if not is_real_number(fps) or not (np.isfinite(fps) and fps > 0):
        raise error(f"{where}: fps must be a finite number > 0, got {fps!r}")
    return float(fps)


@dataclass(frozen=True)
class Stroke:
    """One stroke: a region followed without a break.

    Attributes
    ----------
    index : int
        Position in its :class:`StrokeSet` (ordered by start frame).
    start, end : int
        First and last frame numbers (``end >= start``).
    frames : ndarray, shape (num_points,)
        Frame numbers of the stroke.
    positions : ndarray, shape (num_points, 2)
        Region centre ``(x, y)`` in pixels per frame.
    colours : ndarray, shape (num_colours,)
        Indices of the N dominant colours in the pool (distinct, sorted; simulated).
    truth : frozenset of int
        The people in the region (for scoring only; never seen by the labeller).
    palette : ndarray, shape (num_palette,), optional
        The colours a label gets when it is created at this stroke (seed 004, sec. 4.1:
        "the first time a new label is created and associated to a segment, a set of
        dominant colors is assigned to the label"). Simulated as the palette of the
        people in the region, as if extracted cleanly over the whole segment; defaults to
        ``colours``. The default network's palette evidence (the count, gain and
        missing-colour tables of :class:`models.jorge.network.NetworkConfig`) is fitted on
        such clean palettes: strokes whose palette is only their noisy ``colours`` are
        labelled much worse with it (CAVIAR training sequences, stroke seeds 0-2: error
        about 0.6 instead of 0.0-0.04, about 0.3 without the missing-colour table), so give
        them ``palette_missing_table=()``, or refit the tables on such strokes whose
        people are known (:func:`models.jorge.fit.fit_parameters`).
    extent : ndarray, shape (num_points, 2), optional
        Width and height in pixels of the region's box per frame (the bounding box of its
        people's boxes), recorded by :func:`build_strokes`; the label network uses it as
        evidence on the number of people (:func:`models.jorge.evidence.size_log_likelihood`).
        ``None``: unknown (no size evidence).
    """

    index: int
    start: int
    end: int
    frames: np.ndarray
    positions: np.ndarray
    colours: np.ndarray
    truth: frozenset = field(default_factory=frozenset)
    palette: np.ndarray | None = None
    extent: np.ndarray | None = None

    def __post_init__(self) -> None:
        if self.palette is None:
            object.__setattr__(self, "palette", np.asarray(self.colours))

    @property
    def start_pos(self) -> np.ndarray:
        return self.positions[0]

    @property
    def end_pos(self) -> np.ndarray:
        return self.positions[-1]


def make_stroke(
    index: int,
    start: int,
    end: int,
    start_pos,
    end_pos,
    colours,
    truth=frozenset(),
    pool_size: int = 12,
    size=None,
) -> Stroke:
    """Build a validated stroke from its end points (for synthetic tests and users).

    Parameters
    ----------
    index : int
        Stroke index.
    start, end : int
        First and last frame, ``end >= start``.
    start_pos, end_pos : array_like, shape (2,)
        Region centre at the first and last frame.
    colours : array_like of int, shape (num_colours,)
        Distinct colour indices in ``0..pool_size-1``; not empty.
    truth : iterable of int
        The people in the stroke (scoring only).
    pool_size : int
        Number of colours in the pool.
    size : array_like, shape (2,), optional
        Width and height of the region's box, the same at every point (``Stroke.extent``);
        ``None`` for no size.

    Raises
    ------
    TimeOrderError
        ``end < start``.
    InputError
        Empty, repeated or out-of-range colours; a size that is not positive.
    NonFiniteError
        A non-finite position or size.
    """
    index = check_size("stroke index", index)
    start, end = _frame_number(index, "start", start), _frame_number(index, "end", end)
    if end < start:
        raise TimeOrderError(f"stroke {index}: end frame {end} is before start frame {start}")
    pos = real_array(f"stroke {index}: start_pos/end_pos", [start_pos, end_pos])
    if pos.shape != (2, 2):
        raise ShapeError(f"stroke {index}: start_pos/end_pos must have shape (2,), got {pos.shape}")
    if not np.all(np.isfinite(pos)):
        raise NonFiniteError(f"stroke {index}: non-finite position {pos.tolist()}")
    col = _check_colours(index, colours, pool_size)
    frames = np.array([start, end]) if end > start else np.array([start])
    positions = pos if end > start else pos[:1]
    extent = None
    if size is not None:
        wh = real_array(f"stroke {index}: size", size)
        if wh.shape != (2,):
            raise ShapeError(f"stroke {index}: size must have shape (2,), got {wh.shape}")
        if not np.all(np.isfinite(wh)):
            raise NonFiniteError(f"stroke {index}: non-finite size {wh.tolist()}")
        if np.any(wh <= 0):
            raise InputError(f"stroke {index}: size (width, height) must be > 0, got {wh.tolist()}")
        extent = np.tile(wh, (positions.shape[0], 1))
    return Stroke(index, start, end, frames, positions, col, frozenset(int(t) for t in truth),
                  extent=extent)


def _frame_number(index: int, name: str, value) -> int:
    """A stroke's ``start`` / ``end`` frame as an int: an integer or a whole float, not a
    bool; else :class:`InputError` naming the stroke (text, NaN raised Python's errors and
    1.5 was truncated to 1)."""
    if not is_real_number(value) or not is_whole(value):
        raise InputError(f"stroke {index}: {name} must be a whole frame number, got {value!r}")
    return int(value)


def _check_colours(index: int, colours, pool_size: int) -> np.ndarray:
    col = np.asarray(colours)
    if col.ndim != 1 or col.size == 0:
        raise InputError(f"stroke {index}: colour set must be a non-empty 1-D list, got {colours!r}")
    if not np.issubdtype(col.dtype, np.integer):
        raise InputError(f"stroke {index}: colours must be integer indices, got {colours!r}")
    if np.any(col < 0) or np.any(col >= pool_size):
        raise InputError(f"stroke {index}: colour ids must be in 0..{pool_size - 1}, got {col.tolist()}")
    if np.unique(col).size != col.size:
        raise InputError(f"stroke {index}: repeated colour ids {col.tolist()}")
    return np.sort(col).astype(np.int64)


@dataclass(frozen=True)
class StrokeSet:
    """The strokes of one sequence, ordered by start frame (then by index).

    Attributes
    ----------
    strokes : tuple of Stroke
    palettes : ndarray, shape (num_ids, num_colours)
        Each person's simulated palette (pool indices).
    ids : ndarray, shape (num_ids,)
        Person ids (rows of ``palettes``).
    config : StrokeConfig
    fps : float
    num_frames : int
    name : str
    """

    strokes: tuple
    palettes: np.ndarray
    ids: np.ndarray
    config: StrokeConfig
    fps: float = 25.0
    num_frames: int = 0
    name: str = ""

    def __len__(self) -> int:
        return len(self.strokes)

    def __iter__(self):
        return iter(self.strokes)

    def __getitem__(self, k: int) -> Stroke:
        return self.strokes[k]

    @property
    def num_groups(self) -> int:
        """Number of group strokes (more than one person)."""
        return sum(len(s.truth) > 1 for s in self.strokes)

    @property
    def duration_s(self) -> float:
        return self.num_frames / self.fps

    @classmethod
    def from_strokes(cls, strokes, pool_size: int = 12, fps: float | None = None, name: str = "") -> StrokeSet:
        """Wrap hand-made strokes (e.g. from :func:`make_stroke`) at frame rate ``fps``
        (required), checking them.

        Raises
        ------
        InputError
            ``fps`` missing or not a finite number > 0; indices that are not ``0..n-1``
            in start order, or bad colours.
        """
        fps = check_frame_rate(fps, "StrokeSet.from_strokes", InputError)
        if isinstance(strokes, str) or not isinstance(strokes, Iterable):
            raise InputError(f"StrokeSet.from_strokes: strokes must be a list of Stroke, got "
                             f"{strokes!r:.60}")  # fmt: skip
        strokes = tuple(strokes)
        for k, s in enumerate(strokes):
            check_type(f"StrokeSet.from_strokes: strokes[{k}]", s, Stroke, InputError)
            if s.index != k:
                raise InputError(f"stroke at position {k} has index {s.index}; indices must be 0..n-1")
            if s.end < s.start:
                raise TimeOrderError(f"stroke {k}: end frame {s.end} is before start frame {s.start}")
            _check_colours(k, s.colours, pool_size)
            if k and s.start < strokes[k - 1].start:
                raise TimeOrderError(
                    f"stroke {k} starts at frame {s.start}, before stroke {k - 1} ({strokes[k - 1].start})"
                )
        num_colours = strokes[0].colours.size if strokes else 5
        config = StrokeConfig(num_colours=num_colours, pool_size=pool_size)
        last = max((s.end for s in strokes), default=-1)
        return cls(strokes, np.zeros((0, num_colours), np.int64), np.zeros(0, np.int64), config,
                   fps, last + 1, name)


def pairwise_iou(boxes: np.ndarray) -> np.ndarray:
    """Intersection over union of every pair of boxes, frame by frame.

    Parameters
    ----------
    boxes : ndarray, shape (num_frames, num_ids, 4)
        ``(xc, yc, w, h)``, NaN where absent.

    Returns
    -------
    ndarray, shape (num_frames, num_ids, num_ids)
        IoU; 0 where a box is absent.
    """
    lo = boxes[..., :2] - boxes[..., 2:] / 2
    hi = boxes[..., :2] + boxes[..., 2:] / 2
    inter_wh = np.minimum(hi[:, :, None], hi[:, None]) - np.maximum(lo[:, :, None], lo[:, None])
    inter = np.prod(np.clip(inter_wh, 0.0, None), axis=-1)
    area = boxes[..., 2] * boxes[..., 3]
    union = area[:, :, None] + area[:, None] - inter
    with np.errstate(invalid="ignore", divide="ignore"):
        iou = inter / union
    return np.nan_to_num(iou, nan=0.0)


def region_labels(boxes: np.ndarray, iou_threshold: float) -> np.ndarray:
    """Region of each person per frame: people joined by overlapping boxes (transitively).

    One graph over (frame, person) nodes whose edges are the overlaps, its connected
    components found at once (scipy); the overlaps are computed in blocks of frames over
    the people seen in the block, so memory stays bounded when a long sequence has
    hundreds of ids (the dense frames x ids^2 closure it replaces did not).

    Parameters
    ----------
    boxes : ndarray, shape (num_frames, num_ids, 4)
        ``(xc, yc, w, h)``, NaN where absent.
    iou_threshold : float
        Two boxes with IoU above it are joined.

    Returns
    -------
    ndarray of int64, shape (num_frames, num_ids)
        The lowest column (id index) of the person's region, -1 where the person is absent.
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    boxes = np.asarray(boxes, dtype=np.float64)
    num_frames, num_ids = boxes.shape[:2]
    if boxes.size == 0:
        return np.full((num_frames, num_ids), -1, dtype=np.int64)
    visible = ~np.isnan(boxes[..., 0])
    node = np.arange(num_frames * num_ids).reshape(num_frames, num_ids)
    src, dst = [np.zeros(0, np.int64)], [np.zeros(0, np.int64)]
    for a in range(0, num_frames, _REGION_CHUNK):
        cols = np.flatnonzero(visible[a:a + _REGION_CHUNK].any(0))  # ids seen in the chunk
        f, i, j = np.nonzero(np.triu(pairwise_iou(boxes[a:a + _REGION_CHUNK][:, cols]) > iou_threshold, 1))
        src.append(node[a + f, cols[i]])
        dst.append(node[a + f, cols[j]])
    src_a, dst_a = np.concatenate(src), np.concatenate(dst)
    graph = coo_matrix((np.ones(src_a.size), (src_a, dst_a)), shape=(node.size, node.size))
    _, comp = connected_components(graph, directed=False)
    lowest = np.full(comp.max() + 1, num_ids, dtype=np.int64)
    np.minimum.at(lowest, comp, np.tile(np.arange(num_ids), num_frames))
    return np.where(visible, lowest[comp].reshape(num_frames, num_ids), -1)


_REGION_CHUNK = 64
"""Frames per block of :func:`region_labels`' pairwise overlaps (memory chunk x ids^2)."""


def regions(boxes: np.ndarray, iou_threshold: float) -> np.ndarray:
    """Region membership per frame as a dense relation (:func:`region_labels`, expanded).

    Parameters
    ----------
    boxes : ndarray, shape (num_frames, num_ids, 4)
    iou_threshold : float

    Returns
    -------
    ndarray of bool, shape (num_frames, num_ids, num_ids)
        ``same[f, i, j]``: i and j are both visible and in one region at frame f
        (``same[f, i, i]`` is visibility). Memory frames x ids^2: for short sequences and
        tests; :func:`build_strokes` uses the labels.
    """
    lab = region_labels(boxes, iou_threshold)
    return (lab[:, :, None] == lab[:, None]) & (lab >= 0)[:, :, None]


def gap_mask(seed, visible: np.ndarray, config: StrokeConfig) -> np.ndarray:
    """Simulated background occlusions: the frames each person is hidden.

    A gap starts at each frame in which the person is present and not already hidden
    with probability ``gaps_per_100 / 100`` (a renewal process: ``gaps_per_100`` gap
    starts per 100 frames seen); its length is uniform on ``gap_min..gap_max``.

    Parameters
    ----------
    seed : int or numpy Generator
        Randomness (explicit).
    visible : ndarray of bool, shape (num_frames, num_ids)
    config : StrokeConfig

    Returns
    -------
    ndarray of bool, shape (num_frames, num_ids)
        True where the person is hidden by the simulated occlusion.
    """
    rng = make_rng(seed)
    num_frames, num_ids = visible.shape
    rate = config.gaps_per_100 / 100.0
    p_start = min(1.0, rate)
    # all random numbers drawn up front (same seed, same result, whatever the loop does)
    starts = rng.random((num_frames, num_ids)) < p_start
    lengths = rng.integers(config.gap_min, config.gap_max + 1, size=(num_frames, num_ids))
    hidden = np.zeros((num_frames, num_ids), dtype=bool)
    until = np.full(num_ids, -1)
    for f in range(num_frames):  # a renewal process: one pass over frames, vectorised over people
        begin = starts[f] & visible[f] & (until < f)
        until = np.where(begin, f + lengths[f] - 1, until)
        hidden[f] = visible[f] & (until >= f)
    return hidden


def _simulate_colours(rng, members: list[frozenset], palettes: np.ndarray, id_col: dict,
                      config: StrokeConfig) -> list[np.ndarray]:
    n, pool = config.num_colours, config.pool_size
    out = []
    for m in members:
        union = np.unique(palettes[[id_col[i] for i in m]].ravel())
        base = rng.choice(union, size=n, replace=False) if union.size > n else union.copy()
        keep = rng.random(n) < config.match_prob
        outside = np.setdiff1d(np.arange(pool), union)
        swap = ~keep
        if swap.any() and outside.size:
            k = min(int(swap.sum()), outside.size)
            repl = rng.choice(outside, size=k, replace=False)
            base[np.flatnonzero(swap)[:k]] = repl
        out.append(np.sort(base).astype(np.int64))
    return out


def build_strokes(seed, truth: GroundTruth, config: StrokeConfig | None = None) -> StrokeSet:
    """The simulated low-level tracker: strokes from ground-truth boxes (seed 004, sec. 3).

    Parameters
    ----------
    seed : int
        Seed of the simulated occlusion gaps and colours (explicit, first).
    truth : GroundTruth
        Boxes per frame and person.
    config : StrokeConfig, optional
        Defaults of issue 4 when omitted.

    Returns
    -------
    StrokeSet
        ``num_strokes`` strokes ordered by start frame, each with positions, N simulated
        dominant colours and its true member set.
    """
    config = StrokeConfig() if config is None else config
    if config.num_colours > config.pool_size:
        raise InputError(f"num_colours {config.num_colours} > pool_size {config.pool_size}")
    ss = make_rng(seed).bit_generator.seed_seq  # SeedSequence(seed); seed -1: InputError
    gap_seed, palette_seed, colour_seed = ss.spawn(3)
    boxes = truth.boxes
    visible = ~np.isnan(boxes[..., 0])
    hidden = gap_mask(np.random.default_rng(gap_seed), visible, config)
    num_ids = truth.ids.size
    # the lowest-id member of each person's region decides whether the region is hidden
    first_member = region_labels(boxes, config.iou_threshold)  # (F, I), -1 absent
    is_head = first_member == np.arange(num_ids)[None]
    region_hidden = np.take_along_axis(hidden, np.clip(first_member, 0, None), axis=1)
    shown_head = is_head & visible & ~region_hidden

    lo = boxes[..., :2] - boxes[..., 2:] / 2
    hi = boxes[..., :2] + boxes[..., 2:] / 2
    open_: dict[frozenset, dict] = {}
    done: list[dict] = []
    ids = truth.ids
    for f in range(truth.num_frames):
        here = {}
        for h in np.flatnonzero(shown_head[f]):
            cols = np.flatnonzero(first_member[f] == h)
            key = frozenset(int(ids[c]) for c in cols)
            rlo, rhi = lo[f, cols].min(0), hi[f, cols].max(0)
            here[key] = (0.5 * (rlo + rhi), rhi - rlo)
        for key in list(open_):
            if key not in here:
                done.append(open_.pop(key))
        for key, (centre, extent) in here.items():
            if key in open_:
                open_[key]["frames"].append(int(truth.frames[f]))
                open_[key]["pos"].append(centre)
                open_[key]["ext"].append(extent)
            else:
                open_[key] = {"truth": key, "frames": [int(truth.frames[f])], "pos": [centre],
                              "ext": [extent]}
    done.extend(open_.values())
    done.sort(key=lambda d: (d["frames"][0], d["frames"][-1], sorted(d["truth"])))

    prng = np.random.default_rng(palette_seed)
    palettes = np.stack(
        [np.sort(prng.choice(config.pool_size, size=config.num_colours, replace=False)) for _ in ids]
    ) if num_ids else np.zeros((0, config.num_colours), np.int64)
    id_col = {int(i): c for c, i in enumerate(ids)}
    colours = _simulate_colours(np.random.default_rng(colour_seed), [d["truth"] for d in done],
                                palettes, id_col, config)
    strokes = tuple(
        Stroke(k, d["frames"][0], d["frames"][-1], np.array(d["frames"], dtype=np.int64),
               np.array(d["pos"], dtype=np.float64), colours[k], d["truth"],
               np.unique(palettes[[id_col[i] for i in d["truth"]]]),
               np.array(d["ext"], dtype=np.float64))
        for k, d in enumerate(done)
    )
    return StrokeSet(strokes, palettes.astype(np.int64), ids.copy(), config, truth.fps,
                     truth.num_frames, truth.name)
