"""Multi-camera files of the 3-D tracker (seed 003): view folders, 3-D tracks.

Input: one folder per camera view, each holding its Tsai calibration (one ``.xml`` file,
PETS2009 ``View_00k.xml`` layout: ``Geometry``, ``Intrinsic``, ``Extrinsic``) and one
foreground mask per frame (``*.png``, sorted by name = frame order; grey or RGB, values
above 0.5 are foreground), in the camera's own (unrectified) image. Optional ``colour``
sub-folder: the colour frames (same names). Every view has the same frames and size
(``dbntrack track`` checks the count, and the frame numbers in the names where they have
them).

The masks are warped into seed 003's rectified images (nearest neighbour), and person
detections (the tracker's data-driven proposals) are the feet (bottom centre) of the
connected foreground blobs at least ``min_blob`` pixels large, mapped to the ground (feet
on or above a view's horizon map behind the camera or to infinity: they are dropped).

Output ``tracks3d.txt``: MOTChallenge 3-D style ``frame,id,-1,-1,-1,-1,conf,x,y,z``
(frames from 1, metres, ``z = 0`` on the ground, ``conf`` = presence probability); the
same format is read as the truth by ``dbntrack eval rjmcmc3d``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from dbn.errors import DBNError, FileFormatError, InputError
from models.io.table import as_float, as_int, fail, read_lines, write_rows
from models.rjmcmc3d.frames import MAX_METRES

__all__ = ["ViewFolder", "read_view", "warp", "detections", "write_tracks3d", "read_tracks3d"]


class ViewFolder:
    """One view: ``camera`` (unrectified :class:`Camera`), ``masks`` (paths), ``colour``,
    ``calibration`` (the path of its Tsai .xml)."""

    def __init__(self, folder: str | Path, scale: float = 1.0) -> None:
        from models.rjmcmc3d.scene import load_tsai_xml

        folder = Path(folder)
        if not folder.is_dir():
            raise InputError(f"{folder}: not a folder (expected a view folder: .xml + .png)")
        xmls = sorted(folder.glob("*.xml"))
        if len(xmls) != 1:
            raise InputError(f"{folder}: expected one Tsai calibration .xml, found {len(xmls)}")
        try:
            self.camera, _ = load_tsai_xml(xmls[0], scale)
        except DBNError:
            raise
        except Exception as exc:  # ElementTree / missing attribute
            raise InputError(f"{xmls[0]}: not a Tsai calibration ({exc})") from None
        self.calibration = xmls[0]
        self.masks = sorted(folder.glob("*.png"))
        if not self.masks:
            raise InputError(f"{folder}: no foreground mask (.png)")
        col = folder / "colour"
        self.colour = [col / m.name for m in self.masks] if col.is_dir() else None
        self.folder = folder


def read_view(folder: str | Path, scale: float = 1.0) -> ViewFolder:
    """Read one view folder (module docstring)."""
    return ViewFolder(folder, scale)


def read_png(path: Path, shape: tuple[int, int], channels: int | None = None) -> np.ndarray:
    """A PNG as float32 in [0, 1], grey ``(h, w)`` or RGB ``(h, w, 3)``; size checked.

    The conversion is explicit: an 8-bit (16-bit) integer image is divided by 255
    (65535); a float image (matplotlib reads PNGs as float in [0, 1]) must already lie
    in [0, 1]. A float value outside [0, 1], NaN or inf is a :class:`FileFormatError`
    naming the file: it is never rescaled by guess (a 0-255 mask read as 0-1 would
    count every blob several times).
    """
    import matplotlib.image as mpimg

    try:
        raw = np.asarray(mpimg.imread(path))
    except Exception as exc:
        raise FileFormatError(path, f"not a readable PNG ({exc})") from None
    img = _unit_float(raw, path)
    if img.ndim not in (2, 3) or img.shape[:2] != shape:
        raise FileFormatError(path, f"image is {'x'.join(map(str, img.shape[1::-1]))}, "
                              f"calibration says {shape[1]}x{shape[0]}")  # fmt: skip
    if channels == 3:
        return img[..., :3] if img.ndim == 3 else np.repeat(img[..., None], 3, axis=2)
    return img[..., :3].mean(-1) if img.ndim == 3 else img


def _unit_float(raw: np.ndarray, path: Path) -> np.ndarray:
    """``raw`` as float32 in [0, 1]: uint8 / 255, uint16 / 65535, floats checked."""
    if raw.dtype == np.uint8 or raw.dtype == np.uint16:
        return raw.astype(np.float32) / np.float32(np.iinfo(raw.dtype).max)
    if raw.dtype.kind != "f":
        raise FileFormatError(path, f"pixel type {raw.dtype}, expected uint8, uint16 or float")
    bad = ~((raw >= 0.0) & (raw <= 1.0))  # NaN is bad too
    if bad.any():
        i = np.unravel_index(int(np.argmax(bad)), raw.shape)
        raise FileFormatError(path, f"pixel {tuple(map(int, i))} = {raw[i]!r} is outside "
                              "[0, 1] (float images must be in [0, 1])")  # fmt: skip
    return raw.astype(np.float32)


def warp(image: np.ndarray, H: np.ndarray, shape: tuple[int, int], fill: float = 0.0):
    """``out[y, x] = image[H^{-1} (x, y)]`` (nearest neighbour), ``shape = (h, w)``: the
    image seen through the homography ``H`` (source pixel -> output pixel)."""
    h, w = shape
    ys, xs = np.mgrid[0:h, 0:w]
    pts = np.stack([xs.ravel() + 0.5, ys.ravel() + 0.5, np.ones(h * w)])
    src = np.linalg.solve(H, pts)
    sx = np.floor(src[0] / src[2]).astype(np.int64)
    sy = np.floor(src[1] / src[2]).astype(np.int64)
    ok = (src[2] > 0) & (sx >= 0) & (sx < image.shape[1]) & (sy >= 0) & (sy < image.shape[0])
    out = np.full((h * w, *image.shape[2:]), fill, dtype=image.dtype)
    out[ok] = image[sy[ok], sx[ok]]
    return out.reshape(h, w, *image.shape[2:])


def detections(D: np.ndarray, min_blob: int) -> np.ndarray:
    """Feet ``(n, 2)`` (pixels) of the connected blobs of ``D > 0.5`` (>= ``min_blob`` px)."""
    from scipy import ndimage

    lab, n = ndimage.label(D > 0.5)
    feet = []
    for k, sl in enumerate(ndimage.find_objects(lab), start=1):
        if sl is None or (lab[sl] == k).sum() < min_blob:
            continue
        ys, xs = np.nonzero(lab[sl] == k)
        feet.append([sl[1].start + xs.mean() + 0.5, sl[0].start + ys.max() + 1.0])
    return np.array(feet, dtype=np.float64).reshape(-1, 2)


def write_tracks3d(path, frames: list[int], ids: list, X: list, presence: list) -> Path:
    """MOTChallenge 3-D rows ``frame,id,-1,-1,-1,-1,conf,x,y,z`` (no header)."""
    path = Path(path)
    with open(path, "w", encoding="utf-8") as f:
        for fr, i, x, p in zip(frames, ids, X, presence):
            for k in range(len(i)):
                f.write(f"{fr},{int(i[k])},-1,-1,-1,-1,{float(p[k]):.4f},"
                        f"{float(x[k, 0]):.4f},{float(x[k, 1]):.4f},0\n")  # fmt: skip
    return path


def read_tracks3d(path: str | Path) -> dict[int, tuple[np.ndarray, np.ndarray]]:
    """``frame -> (ids (n,), ground positions (n, 2))`` of a MOT 3-D file (frames and ids
    >= 0; an id at most once per frame; ``|x|, |y| <=``
    :data:`~models.rjmcmc3d.frames.MAX_METRES`, 1e6 m, the tracker's bound on its
    detections' ground positions)."""
    path = Path(path)
    out: dict[int, tuple[list, list]] = {}
    for line_no, line in enumerate(read_lines(path, "tracks file"), start=1):
        fields = [x.strip() for x in line.split(",")]
        if not line.strip() or fields[0].startswith("#"):
            continue
        if len(fields) < 10:
            msg = f"{len(fields)} fields, need frame,id,-1,-1,-1,-1,conf,x,y,z"
            raise fail(path, line_no, msg)
        fr, i = (
            as_int(fields[0], path, line_no, "frame"),
            as_int(fields[1], path, line_no, "id"),
        )
        if fr < 0 or i < 0:
            raise fail(path, line_no, f"frame = {fr}, id = {i}: both count from 0")
        xy = [as_float(fields[k], path, line_no, "xyz"[k - 7]) for k in (7, 8)]
        if max(map(abs, xy)) > MAX_METRES:  # 1e200 overflowed motmetrics' distances
            raise fail(path, line_no, f"x, y = {xy[0]:g}, {xy[1]:g}: beyond "
                       f"{MAX_METRES:g} m (a unit mistake?)")  # fmt: skip
        ids, pos = out.setdefault(fr, ([], []))
        if i in ids:
            raise fail(path, line_no, f"id {i} appears twice in frame {fr}")
        ids.append(i)
        pos.append(xy)
    return {fr: (np.array(i, np.int64), np.array(p).reshape(-1, 2)) for fr, (i, p) in out.items()}


__all__ += ["read_png", "write_rows"]
