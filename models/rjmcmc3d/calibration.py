"""Calibrated scenes: the Tsai calibration XML loader (PETS2009 ``View_001.xml``) and
the default partial-overlap hall of three cameras (seed 003, section 2 and its metro
scene), images rectified by the vertical-vanishing-point homography.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from dbn.checks import MIN_SCALE, check_numbers, check_type, make_rng
from dbn.errors import FileFormatError, InputError, ShapeError
from models.io.xmlfile import read_xml_root
from models.rjmcmc3d.geometry import (
    Camera,
    camera_center,
    look_at_camera,
    rectified_projection,
)
from models.rjmcmc3d.types import Scene

__all__ = ["default_scene", "load_tsai_xml", "scene_from_cameras"]


_TSAI = {
    "Geometry": ("width", "height", "dpx", "dpy"),
    "Intrinsic": ("focal", "kappa1", "cx", "cy", "sx"),
    "Extrinsic": ("tx", "ty", "tz", "rx", "ry", "rz"),
}
_POSITIVE = ("width", "height", "dpx", "dpy", "focal", "sx")
_BOUNDS = {  # attribute -> (largest |value|, what it is beyond that)
    **dict.fromkeys(("rx", "ry", "rz"), (2 * math.pi, "beyond one turn: angles are radians "
                                                     "(degrees?)")),
    **dict.fromkeys(("tx", "ty", "tz"), (1e9, "beyond 1e9 mm (1,000 km): a unit mistake?")),
    **dict.fromkeys(("width", "height"), (1e5, "beyond 1e5 pixels")),
    **dict.fromkeys(("cx", "cy"), (1e6, "beyond 1e6 pixels")),
}
"""Ranges of the calibration's attributes: a rotation of 1e200 rad and a principal point
of 1e200 px ran (rc 0, or numpy's "Singular matrix"); outside them a value is a mistake."""
_FOCAL_PX = (1.0, 1e6)
"""Range of the focal lengths in pixels, ``sx focal / dpx`` and ``focal / dpy``: below one
pixel the camera matrix is singular to rounding (dpx = 1e200 gave numpy's "Singular
matrix"), above 1e6 its projections overflow."""


def _read_tsai(path) -> tuple[dict, dict, dict]:
    """The Geometry, Intrinsic and Extrinsic attributes as finite floats; a missing,
    malformed or truncated file, a missing element or attribute, a value that is not a
    finite number (or not > 0 where it must be) is a :class:`FileFormatError`."""
    root = read_xml_root(path, "calibration file")
    out = []
    for tag, keys in _TSAI.items():
        elem = root.find(tag)
        if elem is None:
            raise FileFormatError(path, f"no <{tag}> element (not a Tsai calibration?)")
        values = {}
        for k in keys:
            text = elem.get(k)
            try:
                v = float(text)  # type: ignore[arg-type]
            except (TypeError, ValueError):
                raise FileFormatError(path, f"<{tag} {k}={text!r}>: not a number") from None
            if not math.isfinite(v) or (k in _POSITIVE and v <= 0):
                need = "a finite number > 0" if k in _POSITIVE else "a finite number"
                raise FileFormatError(path, f"<{tag} {k}={text!r}>: must be {need}")
            if k in _BOUNDS and abs(v) > _BOUNDS[k][0]:
                raise FileFormatError(path, f"<{tag} {k}={text!r}>: {_BOUNDS[k][1]}")
            values[k] = v
        out.append(values)
    g, i, _ = out
    for name, f in (("sx focal / dpx", i["sx"] * i["focal"] / g["dpx"]),
                    ("focal / dpy", i["focal"] / g["dpy"])):  # fmt: skip
        if not _FOCAL_PX[0] <= f <= _FOCAL_PX[1]:
            lo, hi = _FOCAL_PX
            raise FileFormatError(path, f"focal length {name} = {f:g} pixels, outside "
                                  f"[{lo:g}, {hi:g}]: a unit mistake?")  # fmt: skip
    return out[0], out[1], out[2]


def load_tsai_xml(path: str | Path, scale: float = 1.0) -> tuple[Camera, float]:
    """Read a Tsai calibration (PETS2009 ``View_00k.xml``) as a pinhole camera.

    Tsai's model: ``X_c = R X_w + T`` with ``R = R_z(rz) R_y(ry) R_x(rx)``; undistorted
    sensor coordinates ``f X_c / Z_c`` (mm); pixels ``x = sx X_d / dpx + cx``,
    ``y = Y_d / dpy + cy`` with radial distortion ``X_u = X_d (1 + kappa1 r_d^2)``.
    The returned camera is the undistorted pinhole part (seed 003 rectifies after
    distortion removal); world units are converted from millimetres to metres.

    Parameters
    ----------
    path : str or Path
        The XML file.
    scale : float
        Image rescaling factor (0.5 halves the resolution).

    Returns
    -------
    camera : Camera
    kappa1 : float
        Tsai's radial distortion coefficient (1/mm^2), for reference.
    """
    g, i, e = _read_tsai(path)
    ca, sa = math.cos(e["rx"]), math.sin(e["rx"])
    cb, sb = math.cos(e["ry"]), math.sin(e["ry"])
    cg, sg = math.cos(e["rz"]), math.sin(e["rz"])
    R = np.array(
        [
            [cb * cg, cg * sa * sb - ca * sg, sa * sg + ca * cg * sb],
            [cb * sg, sa * sb * sg + ca * cg, ca * sb * sg - cg * sa],
            [-sb, cb * sa, ca * cb],
        ]
    )
    t = np.array([e["tx"], e["ty"], e["tz"]]) / 1000.0
    fx = i["sx"] * i["focal"] / g["dpx"]
    fy = i["focal"] / g["dpy"]
    K = np.array(
        [[fx * scale, 0.0, i["cx"] * scale], [0.0, fy * scale, i["cy"] * scale], [0, 0, 1]]
    )
    cam = Camera(K, R, t, int(round(g["width"] * scale)), int(round(g["height"] * scale)))
    return cam, i["kappa1"]


def _smooth_texture(rng: np.random.Generator, h: int, w: int, cells: int = 12) -> np.ndarray:
    coarse = rng.random((cells, cells, 3))
    yi = np.minimum((np.arange(h) * cells) // h, cells - 1)
    xi = np.minimum((np.arange(w) * cells) // w, cells - 1)
    return coarse[yi][:, xi]


def _check_scene_arrays(cameras, floor, colour_gain, sigma_px):
    """``(floor (4,), colour_gain (V, 3), sigma_px (V,))`` as float64, checked: at least one
    :class:`Camera`; ``floor`` ``x_min < x_max``, ``y_min < y_max``; gains >= 0; pixel
    noise > 0. Else a :mod:`dbn.errors` class naming the argument (an inverted floor or a
    negative noise built a scene that tracked nothing, and text raised numpy's error)."""
    if not isinstance(cameras, list | tuple) or not cameras:
        raise InputError(f"cameras must be a non-empty list of Camera, got {cameras!r:.60}")
    for i, c in enumerate(cameras):
        check_type(f"cameras[{i}]", c, Camera, InputError)
    V = len(cameras)
    floor = check_numbers("floor", floor, 4, error=InputError)
    if not (floor[0] < floor[1] and floor[2] < floor[3]):
        raise InputError(f"floor = {floor.tolist()}: need [x_min, x_max, y_min, y_max] with "
                         "x_min < x_max and y_min < y_max")  # fmt: skip
    gain = check_numbers("colour_gain", colour_gain, 3 * V, low=0.0, error=InputError)
    if np.shape(colour_gain) != (V, 3):
        raise ShapeError(f"colour_gain has shape {np.shape(colour_gain)}, expected ({V}, 3)")
    sigma = check_numbers("sigma_px", sigma_px, V, low=MIN_SCALE, error=InputError)
    return floor, gain.reshape(V, 3), sigma


def scene_from_cameras(
    seed: int,
    cameras: list[Camera],
    floor: np.ndarray,
    colour_gain: np.ndarray,
    sigma_px: np.ndarray,
) -> Scene:
    """Build a :class:`Scene` (rectified projections, background images) from cameras.

    Parameters
    ----------
    seed : int
        Seed of the background textures.
    cameras : list of Camera, length num_views
        All of the same image size.
    floor : ndarray, shape (4,)
        ``(x_min, x_max, y_min, y_max)``, metres, ``x_min < x_max`` and ``y_min < y_max``.
    colour_gain : ndarray, shape (num_views, 3)
        Each view's RGB gain, >= 0.
    sigma_px : ndarray, shape (num_views,)
        Each view's detector foot noise (pixels), > 0.

    Raises
    ------
    InputError, ShapeError, NonFiniteError
        Naming the argument, before anything is built.
    """
    rng = make_rng(seed)
    floor, gain, sigma_px = _check_scene_arrays(cameras, floor, colour_gain, sigma_px)
    width, height = cameras[0].width, cameras[0].height
    if any(c.width != width or c.height != height for c in cameras):
        raise InputError("cameras: every view must have the same image size")
    Ps, rects = zip(*(rectified_projection(c) for c in cameras), strict=True)
    bg = []
    for v in range(len(cameras)):
        tex = 0.36 + 0.12 * _smooth_texture(rng, height, width)
        bg.append(np.clip(tex * gain[v], 0, 1).astype(np.float32))
    return Scene(
        tuple(cameras),
        np.stack(Ps),
        tuple(rects),
        np.stack([camera_center(c) for c in cameras]),
        floor,
        width,
        height,
        gain,
        sigma_px,
        np.stack(bg),
    )


def default_scene(seed: int = 0, width: int = 384, height: int = 288) -> Scene:
    """The default partial-overlap scene: a 20 m x 8 m hall seen by three cameras.

    Camera 0 (high, wide) covers the west part from the south wall, camera 1 (a long
    lens) the east part from the north wall, camera 2 (low, close) the middle from the
    south wall, where people appear large. Most of the floor is seen by
    exactly one camera (see :func:`coverage_fractions`). SIMULATED geometry.
    """
    s = width / 384.0
    cams = [
        look_at_camera(
            np.array([4.5, -3.0, 8.7]), np.array([4.5, 3.4, 0.0]), 300 * s, width, height
        ),
        look_at_camera(
            np.array([16.7, 11.0, 6.7]), np.array([16.7, 3.1, 0.0]), 445 * s, width, height
        ),
        look_at_camera(
            np.array([9.9, -1.5, 3.7]), np.array([9.9, 4.2, 0.0]), 360 * s, width, height
        ),
    ]
    gain = np.array([[1.0, 1.0, 1.0], [1.15, 0.97, 0.82], [0.85, 1.0, 1.18]])
    return scene_from_cameras(seed, cams, np.array([0.0, 20.0, 0.0, 8.0]), gain, np.full(3, 3.0))
