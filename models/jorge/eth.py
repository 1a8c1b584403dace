"""Tracks in world metres as image boxes: ETH ``obsmat`` files through a SIMULATED camera.

The ETH / UCY pedestrian annotations (Pellegrini et al. 2009; ``seq_eth`` in
``../shared/data/eth``) give each person's ground position in metres, not an image box, so
they make no regions and no strokes by themselves. :class:`ObliqueView` is an assumed
camera, not the recording's: an orthographic view tilted ``tilt_deg`` below the horizon,
looking along the world ``+y`` axis, in which each person is an upright cylinder of radius
``radius_m`` and height ``height_m``. Two people overlap in it when they are close across
the view or one stands behind the other, as in an oblique surveillance view (CAVIAR,
PETS2009). Its settings are physical sizes fixed before anything was scored on ETH; they
set how often people's boxes merge, so every figure on such a sequence is a figure on a
SIMULATED view of real motion.

``obsmat.txt``: whitespace columns ``frame, id, x, z, y, vx, vz, vy`` (metres, metres per
second; ``z`` is height, unused). Frame numbers are video frames, annotated every
``step``-th frame (ETH: every 6th of 15 fps, so 2.5 annotations per second).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from dbn.errors import DBNError, InputError, in_file
from models.io.table import as_float, as_int, fail, read_lines

__all__ = ["ObliqueView", "ETH_FPS", "read_obsmat", "load_eth"]

ETH_FPS = 2.5
"""Annotation rate of the ETH / UCY ``obsmat`` files (one row per person every 0.4 s)."""


@dataclass(frozen=True)
class ObliqueView:
    """A SIMULATED orthographic camera over the ground plane (module docstring).

    Attributes
    ----------
    tilt_deg : float
        Angle of the viewing direction below the horizon, in (0, 90] degrees (90: straight
        down, people are discs; small: people stand in front of each other).
    radius_m, height_m : float
        A person's radius and height in metres (> 0).
    px_per_m : float
        Image scale (> 0); the labeller's gates are relative to the box size, so this
        changes nothing but the units of the boxes.
    """

    tilt_deg: float = 45.0
    radius_m: float = 0.25
    height_m: float = 1.75
    px_per_m: float = 50.0

    def __post_init__(self) -> None:
        for name in ("tilt_deg", "radius_m", "height_m", "px_per_m"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise InputError(f"ObliqueView.{name} must be a finite number, got {value!r}")
            if value <= 0:
                raise InputError(f"ObliqueView.{name} must be > 0, got {value!r}")
            object.__setattr__(self, name, float(value))  # 90 and 90.0: one view, one repr
        if self.tilt_deg > 90:
            raise InputError(f"ObliqueView.tilt_deg must be in (0, 90], got {self.tilt_deg!r}")

    def boxes(self, ground: np.ndarray) -> np.ndarray:
        """Image boxes of people standing at ``ground``.

        Parameters
        ----------
        ground : ndarray, shape (..., 2)
            Ground positions ``(x, y)`` in metres (NaN where absent).

        Returns
        -------
        ndarray, shape (..., 4)
            Boxes ``(xc, yc, w, h)`` in pixels, image ``y`` pointing down: with tilt ``t``,
            the cylinder's image spans ``x +- r`` across and, upwards, ``(y - r) sin t`` to
            ``(y + r) sin t + H cos t``.
        """
        ground = np.asarray(ground, dtype=np.float64)
        if ground.shape[-1:] != (2,):
            raise InputError(f"ObliqueView.boxes: ground must have shape (..., 2), got {ground.shape}")
        t = math.radians(self.tilt_deg)
        r, s = self.radius_m, self.px_per_m
        h = 2 * r * math.sin(t) + self.height_m * math.cos(t)
        up = (ground[..., 1] - r) * math.sin(t) + h / 2
        out = np.empty(ground.shape[:-1] + (4,))
        out[..., 0] = s * ground[..., 0]
        out[..., 1] = -s * up
        out[..., 2] = np.where(np.isnan(ground[..., 0]), np.nan, s * 2 * r)
        out[..., 3] = np.where(np.isnan(ground[..., 0]), np.nan, s * h)
        return out


def read_obsmat(path: str | Path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rows of an ETH / UCY ``obsmat`` file (module docstring).

    Returns
    -------
    frames : ndarray, shape (n,) int64
        Video frame numbers.
    ids : ndarray, shape (n,) int64
        Person ids.
    ground : ndarray, shape (n, 2)
        Ground positions ``(x, y)`` in metres (columns 3 and 5).

    Raises
    ------
    FileFormatError
        (an :class:`~dbn.errors.InputError`) naming the file and line: fewer than 5
        columns, a field that is not a finite number, a frame or id that is not an integer,
        a person twice in one frame, or no rows.
    """
    rows, seen = [], set()
    for line_no, line in enumerate(read_lines(path, "obsmat file"), start=1):
        fields = line.split()
        if not fields or fields[0].startswith("#"):
            continue
        if len(fields) < 5:
            raise fail(path, line_no, f"{len(fields)} columns, need frame id x z y [vx vz vy]")
        frame = as_int(fields[0], path, line_no, "frame")  # "7.8000000e+02" is 780
        pid = as_int(fields[1], path, line_no, "id")
        x, y = as_float(fields[2], path, line_no, "x"), as_float(fields[4], path, line_no, "y")
        if (frame, pid) in seen:
            raise fail(path, line_no, f"id {pid} appears twice in frame {frame}")
        seen.add((frame, pid))
        rows.append((frame, pid, x, y))
    if not rows:
        raise fail(path, 0, "no rows")
    table = np.array(rows, dtype=np.float64)
    return table[:, 0].astype(np.int64), table[:, 1].astype(np.int64), table[:, 2:]


def _frame_index(uniq: np.ndarray) -> np.ndarray:
    """Annotation index of each of the distinct, sorted frames ``uniq``: consecutive
    annotated frames ``d`` video frames apart are ``max(1, round(d / step))`` indices
    apart, ``step`` the most common such ``d`` (a gap in the annotation stays a gap of
    empty frames)."""
    if uniq.size == 1:
        return np.zeros(1, np.int64)
    diffs, counts = np.unique(np.diff(uniq), return_counts=True)
    step = int(diffs[np.argmax(counts)])
    jumps = np.maximum(1, np.floor(np.diff(uniq) / step + 0.5)).astype(np.int64)
    return np.concatenate([[0], np.cumsum(jumps)])


def load_eth(path: str | Path, view: ObliqueView | None = None, fps: float = ETH_FPS,
             name: str | None = None):
    """An ``obsmat`` file as a :class:`~models.jorge.strokes.GroundTruth` seen through a
    SIMULATED :class:`ObliqueView` (default settings when omitted).

    ``frames`` are annotation indices (video frame / step, so consecutive annotations are
    consecutive frames, and frames nobody is in are kept empty), ``fps`` the annotation
    rate (:data:`ETH_FPS`), ``name`` the file's stem unless given, ``groups`` empty (the
    file of who walks together is not the overlap of boxes the stroke builder uses).

    Raises
    ------
    InputError
        ``view`` not an :class:`ObliqueView`, ``fps`` not a finite number > 0 (before the
        file is read); a bad file, naming it and the line (:func:`read_obsmat`).
    """
    from models.jorge.strokes import _assemble, check_frame_rate

    view = ObliqueView() if view is None else view
    if not isinstance(view, ObliqueView):
        raise InputError(f"load_eth: view must be an ObliqueView, got {type(view).__name__}")
    fps = check_frame_rate(fps, "load_eth", InputError)
    path = Path(path)
    frames, ids, ground = read_obsmat(path)
    uniq = np.unique(frames)
    index = _frame_index(uniq)
    row_of = dict(zip(uniq.tolist(), index.tolist()))
    boxes = view.boxes(ground)
    per_frame: list[tuple[int, dict]] = [(k, {}) for k in range(int(index[-1]) + 1)]
    for f, pid, box in zip(frames.tolist(), ids.tolist(), boxes):
        per_frame[row_of[f]][1][pid] = tuple(box)
    try:
        return _assemble(name or path.name.split(".")[0], per_frame, [], fps=fps)
    except DBNError as exc:
        raise in_file(exc, path) from None
