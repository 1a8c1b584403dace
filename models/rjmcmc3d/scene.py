"""A calibrated multi-camera scene, rendered (SIMULATED data) for the seed 003 tracker.

Real multi-camera video is not available to this project, so the observations of seed 003
(section 3.3: foreground maps ``D_v`` and colour images ``I_v``; section 3.4: a per-view
person detector) are rendered from a calibrated model:

- pinhole cameras (three by default, with partial overlap as in the seed's metro scene:
  most of the floor is seen by one camera, a minority by two or more; people appear at
  very different image sizes across views; each camera has its own colour shift), images
  rectified by the vertical-vanishing-point homography of seed 003, section 2;
- a loader for Tsai calibration XML (PETS2009 ``View_001.xml``), so a real camera can be
  read and rectified;
- people as three elliptic cylinders (legs, torso, head; seed 003, fig. 3) with height
  and orientation, projected to axis-aligned boxes in the rectified views;
- foreground maps ``D(x)`` in [0, 1] with noise, silhouettes that do not fill their boxes
  and false-alarm blobs; colour images with per-person region colours;
- a noisy per-view detector (misses, foot-position noise, false alarms);
- Langevin walkers (seed 003, eq. 7) entering and leaving the floor.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import NamedTuple

import numpy as np

from dbn.errors import InputError
from models.rjmcmc3d.geometry import (
    Camera,
    Rectification,
    apply_homography,
    camera_center,
    ground_homography,
    look_at_camera,
    rectified_projection,
)

__all__ = [
    "BODY_HALF_AXES",
    "BODY_Z",
    "BoxProjector",
    "Frame",
    "FrameTruth",
    "Scene",
    "Truth",
    "coverage_fractions",
    "default_scene",
    "depths",
    "detect",
    "load_tsai_xml",
    "part_boxes",
    "render_frame",
    "scene_from_cameras",
    "simulate_walkers",
    "visible_views",
]

# Body model (seed 003, fig. 3): legs, torso, head as elliptic cylinders.
# z-extent of each part as fractions of the height h.
BODY_Z = np.array([[0.0, 0.48], [0.48, 0.86], [0.86, 1.0]])
# (half-thickness along the facing direction, half-width across it), metres.
BODY_HALF_AXES = np.array([[0.12, 0.17], [0.13, 0.22], [0.11, 0.10]])
_NUM_ANGLES = 8
_ANG = np.linspace(0.0, 2.0 * np.pi, _NUM_ANGLES, endpoint=False)
_CT = BODY_HALF_AXES[:, 0, None] * np.cos(_ANG)[None, :]  # (3, A) along the facing
_CW = BODY_HALF_AXES[:, 1, None] * np.sin(_ANG)[None, :]  # (3, A) across it


class Scene(NamedTuple):
    """A calibrated scene.

    Attributes
    ----------
    cameras : tuple of Camera, length num_views
        The (unrectified) pinhole cameras.
    P : ndarray, shape (num_views, 3, 4)
        Projection matrices of the rectified images (``H_perp K [R | t]``).
    rects : tuple of Rectification
        The rectifications of seed 003, section 2.
    centers : ndarray, shape (num_views, 3)
        Camera centres (world metres).
    floor : ndarray, shape (4,)
        ``(x_min, x_max, y_min, y_max)`` of the walkable area (metres).
    width, height : int
        Rectified image size (pixels), the same for every view.
    colour_gain : ndarray, shape (num_views, 3)
        Per-camera multiplicative colour shift.
    sigma_px : ndarray, shape (num_views,)
        Standard deviation (pixels) of the detector's foot position in each view.
    background : ndarray, shape (num_views, height, width, 3), float32
        Background colour image of each view.
    """

    cameras: tuple[Camera, ...]
    P: np.ndarray
    rects: tuple[Rectification, ...]
    centers: np.ndarray
    floor: np.ndarray
    width: int
    height: int
    colour_gain: np.ndarray
    sigma_px: np.ndarray
    background: np.ndarray

    @property
    def num_views(self) -> int:
        return len(self.cameras)


class FrameTruth(NamedTuple):
    """Ground truth of one frame: ``ids (n,)``, ``u (n, 2)``, ``h (n,)``, ``alpha (n,)``."""

    ids: np.ndarray
    u: np.ndarray
    h: np.ndarray
    alpha: np.ndarray


class Truth(NamedTuple):
    """A simulated sequence: per-frame truth and each person's region colours.

    ``colours[id]`` has shape (3, 3): RGB of legs, torso, head.
    """

    frames: list[FrameTruth]
    colours: np.ndarray
    tau: float


class Frame(NamedTuple):
    """The observations of one time step (seed 003, sec. 3.3 and 3.4).

    Attributes
    ----------
    D : ndarray, shape (num_views, height, width), float32
        Foreground (background-distance) maps in [0, 1].
    image : ndarray, shape (num_views, height, width, 3), float32
        Colour images in [0, 1].
    det_view : ndarray, shape (num_dets,), int
        View of each detection.
    det_px : ndarray, shape (num_dets, 2)
        Detected foot position in the rectified image (pixels).
    det_ground : ndarray, shape (num_dets, 2)
        That foot position mapped to the ground plane (metres).
    """

    D: np.ndarray
    image: np.ndarray
    det_view: np.ndarray
    det_px: np.ndarray
    det_ground: np.ndarray


# ---------------------------------------------------------------------------------------
# Cameras
# ---------------------------------------------------------------------------------------
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
    root = ET.parse(path).getroot()
    geo, intr, extr = root.find("Geometry"), root.find("Intrinsic"), root.find("Extrinsic")
    if geo is None or intr is None or extr is None:
        raise InputError(f"{path}: missing Geometry/Intrinsic/Extrinsic element")
    g = {k: float(v) for k, v in geo.attrib.items()}
    i = {k: float(v) for k, v in intr.attrib.items()}
    e = {k: float(v) for k, v in extr.attrib.items()}
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
        ``(x_min, x_max, y_min, y_max)``.
    colour_gain : ndarray, shape (num_views, 3)
    sigma_px : ndarray, shape (num_views,)
    """
    rng = np.random.default_rng(seed)
    width, height = cameras[0].width, cameras[0].height
    if any(c.width != width or c.height != height for c in cameras):
        raise InputError("cameras: every view must have the same image size")
    Ps, rects = zip(*(rectified_projection(c) for c in cameras), strict=True)
    gain = np.asarray(colour_gain, dtype=np.float64)
    bg = []
    for v in range(len(cameras)):
        tex = 0.36 + 0.12 * _smooth_texture(rng, height, width)
        bg.append(np.clip(tex * gain[v], 0, 1).astype(np.float32))
    return Scene(
        tuple(cameras),
        np.stack(Ps),
        tuple(rects),
        np.stack([camera_center(c) for c in cameras]),
        np.asarray(floor, dtype=np.float64),
        width,
        height,
        gain,
        np.asarray(sigma_px, dtype=np.float64),
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


# ---------------------------------------------------------------------------------------
# Projection of the body model
# ---------------------------------------------------------------------------------------
def _projection_coefficients(P: np.ndarray) -> np.ndarray:
    """Linear map from ``(x, y, 1, cos a, sin a, h)`` to the projected body points.

    Returns
    -------
    ndarray, shape (6, 3 * V * 3 * 2 * A)
        Row ``r`` multiplies the ``r``-th feature; the columns are the homogeneous image
        coordinates of the sampled points, ordered (coordinate, view, part, z level,
        angle).
    """
    V = P.shape[0]
    Pk = [np.moveaxis(P[:, :, k], 1, 0)[:, :, None, None, None] for k in range(4)]  # (3, V,1,1,1)
    ct = _CT[None, None, :, None, :]  # (1, 1, 3, 1, A)
    cw = _CW[None, None, :, None, :]
    z = BODY_Z[None, None, :, :, None]  # (1, 1, 3, 2, 1)
    shape = (3, V, 3, 2, _NUM_ANGLES)
    rows = [
        Pk[0],  # x
        Pk[1],  # y
        Pk[3],  # 1
        ct * Pk[0] + cw * Pk[1],  # cos a
        ct * Pk[1] - cw * Pk[0],  # sin a
        z * Pk[2],  # h
    ]
    return np.stack([np.broadcast_to(r, shape).reshape(-1) for r in rows])


def _box_limits(width: int, height: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Clip limits and signs of the ``(x0, y0, -x1, -y1)`` rows used by :func:`_boxes_from_points`."""
    lo = np.array([[0.0], [0.0], [-width], [-height]])
    hi = np.array([[width], [height], [0.0], [0.0]], dtype=float)
    sign = np.array([[1.0], [1.0], [-1.0], [-1.0]])
    return lo, hi, sign


def _boxes_from_points(proj: np.ndarray, limits: tuple) -> np.ndarray:
    """Part boxes from projected points.

    Parameters
    ----------
    proj : ndarray, shape (3, V * 3, 2 A)
        Homogeneous image coordinates of each (view, part)'s sampled points.
    limits : tuple
        From :func:`_box_limits`.

    Returns
    -------
    ndarray, shape (V * 3, 4), int64
        ``(floor(min x), floor(min y), ceil(max x), ceil(max y))`` clipped to the image
        (clipping to integer limits commutes with floor and ceil); all zero for a part
        with a sampled point behind (or on) a camera plane.
    """
    lo, hi, sign = limits
    w = proj[2]
    front = None
    if not w.min() > 1e-6:
        ok = w > 1e-6
        front = ok.all(axis=1)
        w = np.where(ok, w, 1.0)
    xy = proj[:2] / w
    ext = np.concatenate((xy.min(-1), -xy.max(-1)))  # (x0, y0, -x1, -y1)
    np.maximum(ext, lo, out=ext)
    np.minimum(ext, hi, out=ext)
    np.floor(ext, out=ext)  # ceil(x1) = -floor(-x1)
    ext *= sign
    if front is not None:
        ext[:, ~front] = 0.0
    return ext.T.astype(np.int64)


def part_boxes(
    P: np.ndarray, u: np.ndarray, h: np.ndarray, alpha: np.ndarray, width: int, height: int
) -> np.ndarray:
    """Image boxes of the three body cylinders of each person in each rectified view.

    Each elliptic cylinder's top and bottom ellipses are sampled at 8 angles and
    projected; in a rectified view (seed 003, sec. 2) the silhouette of an upright
    cylinder is bounded by the axis-aligned box of these points (seed 003, fig. 3).
    A part with a sampled point behind a camera is not seen in that view (empty box).

    The points of each person are projected by the same one-person product as
    :meth:`BoxProjector.one` (the tracker's per-move path), so both give bit-identical
    boxes; the loop runs over the people of one frame (a few dozen at most).

    Parameters
    ----------
    P : ndarray, shape (num_views, 3, 4)
    u : ndarray, shape (num_people, 2)
        Ground positions.
    h, alpha : ndarray, shape (num_people,)
        Heights (m) and orientations (rad, facing direction w.r.t. the x axis).
    width, height : int
        Image size (boxes are clipped to it).

    Returns
    -------
    boxes : ndarray, shape (num_views, num_people, 3, 4), int64
        ``(x0, y0, x1, y1)`` half-open pixel boxes; empty (``x1 <= x0``) when not seen.
    """
    V = P.shape[0]
    C = _projection_coefficients(P)
    limits = _box_limits(width, height)
    out = np.zeros((V, u.shape[0], 3, 4), dtype=np.int64)
    for i, (x, y, hh, a) in enumerate(zip(u[:, 0], u[:, 1], h, alpha)):
        feat = [float(x), float(y), 1.0, math.cos(a), math.sin(a), float(hh)]
        proj = np.dot(feat, C).reshape(3, V * 3, 2 * _NUM_ANGLES)
        out[:, i] = _boxes_from_points(proj, limits).reshape(V, 3, 4)
    return out


class BoxProjector:
    """Fast :func:`part_boxes` for one person (the per-move hot path of the tracker).

    Gives exactly the boxes of :func:`part_boxes` (same product, same rounding) as
    nested lists ``boxes[v][part] = [x0, y0, x1, y1]``, with the union box per view
    and the distance to each camera. The projection of the 3 x 16 sampled body points
    into every view is one ``(6,) @ (6, V * 144)`` product.
    """

    def __init__(self, scene: Scene) -> None:
        V = scene.num_views
        self.V = V
        self.P = scene.P
        self.C = _projection_coefficients(scene.P)
        self.shape = (3, V * 3, 2 * _NUM_ANGLES)
        self.limits = _box_limits(scene.width, scene.height)
        self.width, self.height = scene.width, scene.height
        self.centers = scene.centers[:, :2].tolist()

    def one(self, x: float, y: float, h: float, a: float) -> tuple[list, list, list]:
        """Boxes (V, 3, 4), union boxes (V, 4) and camera distances (V,) as lists."""
        feat = [x, y, 1.0, math.cos(a), math.sin(a), h]
        b = _boxes_from_points(np.dot(feat, self.C).reshape(self.shape), self.limits)
        boxes = b.reshape(self.V, 3, 4).tolist()
        bbox = []
        for parts in boxes:
            x0 = y0 = 1 << 40
            x1 = y1 = -1
            for b0, b1, b2, b3 in parts:
                if b2 > b0 and b3 > b1:
                    x0 = b0 if b0 < x0 else x0
                    y0 = b1 if b1 < y0 else y0
                    x1 = b2 if b2 > x1 else x1
                    y1 = b3 if b3 > y1 else y1
            bbox.append([x0, y0, x1, y1] if x1 >= 0 else [0, 0, 0, 0])
        depth = [math.hypot(x - cx, y - cy) for cx, cy in self.centers]
        return boxes, bbox, depth


def depths(centers: np.ndarray, u: np.ndarray) -> np.ndarray:
    return np.hypot(u[None, :, 0] - centers[:, None, 0], u[None, :, 1] - centers[:, None, 1])


def coverage_fractions(scene: Scene, step: float = 0.1) -> np.ndarray:
    """Fraction of the floor whose standing person (1.7 m) is fully seen by 0, 1, 2, 3+ views.

    Returns
    -------
    ndarray, shape (4,)
    """
    xs = np.arange(scene.floor[0] + step / 2, scene.floor[1], step)
    ys = np.arange(scene.floor[2] + step / 2, scene.floor[3], step)
    gx, gy = np.meshgrid(xs, ys, indexing="ij")
    u = np.stack([gx.ravel(), gy.ravel()], axis=1)
    seen = visible_views(scene, u)
    k = np.minimum(seen.sum(0), 3)
    return np.bincount(k, minlength=4) / k.size


def visible_views(scene: Scene, u: np.ndarray, h: float = 1.7) -> np.ndarray:
    """Whether a person standing at ``u`` (num, 2) is seen whole in each view, (num_views, num)."""
    n = u.shape[0]
    foot = np.concatenate([u, np.zeros((n, 1)), np.ones((n, 1))], axis=1)
    head = foot.copy()
    head[:, 2] = h
    out = []
    for P in scene.P:
        ok = np.ones(n, dtype=bool)
        for X in (foot, head):
            p = X @ P.T
            ok &= p[:, 2] > 1e-6
            x = p[:, 0] / np.where(ok, p[:, 2], 1.0)
            y = p[:, 1] / np.where(ok, p[:, 2], 1.0)
            ok &= (x >= 0) & (x < scene.width) & (y >= 0) & (y < scene.height)
        out.append(ok)
    return np.stack(out)


# ---------------------------------------------------------------------------------------
# Walkers (seed 003, eq. 7)
# ---------------------------------------------------------------------------------------
_TORSO_PALETTE = np.array(
    [
        [0.85, 0.15, 0.15],
        [0.15, 0.35, 0.85],
        [0.15, 0.7, 0.25],
        [0.9, 0.8, 0.15],
        [0.9, 0.9, 0.9],
        [0.1, 0.1, 0.12],
        [0.6, 0.2, 0.7],
        [0.95, 0.5, 0.1],
        [0.2, 0.75, 0.8],
    ]
)
_LEGS_PALETTE = np.array(
    [[0.12, 0.12, 0.3], [0.2, 0.2, 0.2], [0.45, 0.35, 0.2], [0.7, 0.7, 0.65], [0.05, 0.05, 0.05]]
)


def _random_boundary_point(rng: np.random.Generator, floor: np.ndarray) -> tuple[np.ndarray, int]:
    side = int(rng.integers(4))
    lx, hx, ly, hy = floor
    if side == 0:
        return np.array([lx, rng.uniform(ly, hy)]), side
    if side == 1:
        return np.array([hx, rng.uniform(ly, hy)]), side
    if side == 2:
        return np.array([rng.uniform(lx, hx), ly]), side
    return np.array([rng.uniform(lx, hx), hy]), side


def _goal_for(rng: np.random.Generator, floor: np.ndarray, start_side: int) -> np.ndarray:
    lx, hx, ly, hy = floor
    # people mostly walk along the hall; exit through the opposite end or a side
    if start_side in (0, 1) or rng.random() < 0.7:
        if start_side == 0 or (start_side > 1 and rng.random() < 0.5):
            return np.array([hx + 1.0, rng.uniform(ly, hy)])
        if start_side == 1 or start_side > 1:
            return np.array([lx - 1.0, rng.uniform(ly, hy)])
    return np.array([rng.uniform(lx, hx), ly - 1.0 if start_side == 3 else hy + 1.0])


def simulate_walkers(
    seed: int,
    scene: Scene,
    num_frames: int,
    num_people: int,
    tau: float = 0.2,
    speed: float = 1.2,
    beta: float = 0.5,
) -> Truth:
    """SIMULATED walkers: Langevin motion (seed 003, eq. 7) with a drift to an exit.

    About ``num_people`` people are on the floor at any time: each enters at the edge,
    walks towards an exit with velocity ``v_t = a v_{t-1} + (1 - a) v_goal + b w_t``
    (``a = exp(-beta tau)``, ``b = 0.3 speed sqrt(1 - a^2)``), ``u_t = u_{t-1} + tau v_t``,
    and leaves when outside the floor; a new walker then enters after a short delay.

    Parameters
    ----------
    seed : int
    scene : Scene
    num_frames, num_people : int
    tau : float
        Frame interval (s).
    speed : float
        Preferred walking speed (m/s).
    beta : float
        Velocity damping (1/s).

    Returns
    -------
    Truth
    """
    if num_frames < 1 or num_people < 1:
        raise InputError(f"num_frames={num_frames} and num_people={num_people} must be >= 1")
    rng = np.random.default_rng(seed)
    a = math.exp(-beta * tau)
    b = 0.3 * speed * math.sqrt(1 - a * a)
    floor = scene.floor
    walkers: list[dict] = []
    colours: list[np.ndarray] = []
    next_id = 0
    pending = []  # frames at which new walkers enter

    def new_walker(inside: bool) -> dict:
        nonlocal next_id
        if inside:
            start = np.array(
                [rng.uniform(floor[0] + 1, floor[1] - 1), rng.uniform(floor[2] + 1, floor[3] - 1)]
            )
            side = int(rng.integers(4))
        else:
            start, side = _random_boundary_point(rng, floor)
        goal = _goal_for(rng, floor, side)
        d = goal - start
        v = speed * rng.uniform(0.8, 1.2) * d / np.linalg.norm(d)
        skin = np.array([0.55, 0.4, 0.3]) + rng.normal(0, 0.06, 3)
        colours.append(
            np.clip(
                np.stack(
                    [
                        _LEGS_PALETTE[rng.integers(len(_LEGS_PALETTE))] + rng.normal(0, 0.05, 3),
                        _TORSO_PALETTE[rng.integers(len(_TORSO_PALETTE))] + rng.normal(0, 0.05, 3),
                        skin,
                    ]
                ),
                0,
                1,
            )
        )
        w = {
            "id": next_id,
            "u": start,
            "v": v,
            "goal": goal,
            "pref": np.linalg.norm(v),
            "h": float(np.clip(rng.normal(1.72, 0.08), 1.5, 1.95)),
        }
        next_id += 1
        return w

    for _ in range(num_people):
        walkers.append(new_walker(inside=True))
    frames = []
    for t in range(num_frames):
        while pending and pending[0] <= t:
            pending.pop(0)
            walkers.append(new_walker(inside=False))
        for w in walkers:
            d = w["goal"] - w["u"]
            vgoal = w["pref"] * d / max(np.linalg.norm(d), 1e-9)
            w["v"] = a * w["v"] + (1 - a) * vgoal + b * rng.normal(size=2)
            w["u"] = w["u"] + tau * w["v"]
        alive = []
        for w in walkers:
            inside = floor[0] <= w["u"][0] <= floor[1] and floor[2] <= w["u"][1] <= floor[3]
            if inside:
                alive.append(w)
            else:
                pending.append(t + 1 + int(rng.geometric(0.25)))
        pending.sort()
        walkers = alive
        ids = np.array([w["id"] for w in walkers], dtype=np.int64)
        u = np.array([w["u"] for w in walkers]).reshape(-1, 2)
        hh = np.array([w["h"] for w in walkers])
        al = np.array([math.atan2(w["v"][1], w["v"][0]) for w in walkers])
        frames.append(FrameTruth(ids, u, hh, al))
    return Truth(frames, np.stack(colours), tau)


# ---------------------------------------------------------------------------------------
# Rendering and detection
# ---------------------------------------------------------------------------------------
def _ellipse_mask(hh: int, ww: int) -> np.ndarray:
    yy = (np.arange(hh) + 0.5) / hh * 2 - 1
    xx = (np.arange(ww) + 0.5) / ww * 2 - 1
    return (yy[:, None] ** 2 + xx[None, :] ** 2) <= 1.0


def render_frame(seed: int, scene: Scene, truth: Truth, t: int) -> Frame:
    """Render the SIMULATED observations of frame ``t``: ``D_v``, ``I_v`` and detections.

    People are painted far to near (occlusion); each body part fills the ellipse
    inscribed in its box (silhouettes are not boxes). Foreground: ``D ~ 0.8`` with noise
    and 10% drop-outs on people, ``|N(0, 0.1)|`` on the background, plus false-alarm
    blobs (reflections) of ``D ~ 0.7``. Colours: each region's colour times the camera's
    gain, plus pixel noise. Detections: :func:`detect`.

    Parameters
    ----------
    seed : int
        Base seed; the frame uses ``default_rng([seed, t])`` (frames render lazily).
    scene : Scene
    truth : Truth
    t : int
        Frame index.
    """
    rng = np.random.default_rng([seed, t])
    ft = truth.frames[t]
    V, H, W = scene.num_views, scene.height, scene.width
    D = np.abs(rng.normal(0.0, 0.1, (V, H, W))).astype(np.float32)
    img = scene.background + rng.normal(0.0, 0.03, (V, H, W, 3)).astype(np.float32)
    owner = np.full((V, H, W), -1, dtype=np.int32)
    boxes = part_boxes(scene.P, ft.u, ft.h, ft.alpha, W, H)
    depth = depths(scene.centers, ft.u)
    for v in range(V):
        for _fa in range(int(rng.poisson(1.5))):
            bw, bh = int(rng.integers(6, 30)), int(rng.integers(4, 20))
            x0, y0 = int(rng.integers(0, W - bw)), int(rng.integers(H // 3, H - bh))
            D[v, y0 : y0 + bh, x0 : x0 + bw] = np.clip(rng.normal(0.7, 0.15, (bh, bw)), 0, 1)
            img[v, y0 : y0 + bh, x0 : x0 + bw] *= 1.3
        for n in np.argsort(-depth[v], kind="stable"):
            col = truth.colours[ft.ids[n]] * scene.colour_gain[v]
            for p in range(3):
                x0, y0, x1, y1 = boxes[v, n, p]
                if x1 <= x0 or y1 <= y0:
                    continue
                m = _ellipse_mask(y1 - y0, x1 - x0) if p != 1 else np.ones((y1 - y0, x1 - x0), bool)
                img[v, y0:y1, x0:x1][m] = col[p]
                owner[v, y0:y1, x0:x1][m] = n
                D[v, y0:y1, x0:x1][m] = 0.8
    person = owner >= 0
    noise = rng.normal(0.0, 0.15, person.sum()).astype(np.float32)
    drop = rng.random(person.sum()) < 0.1
    D[person] = np.where(drop, 0.15, 0.8 + noise)
    img[person] += rng.normal(0.0, 0.04, (person.sum(), 3)).astype(np.float32)
    np.clip(D, 0.0, 1.0, out=D)
    np.clip(img, 0.0, 1.0, out=img)
    dv, dp, dg = detect(rng, scene, ft, boxes, owner)
    return Frame(D, img, dv, dp, dg)


def detect(
    rng: np.random.Generator,
    scene: Scene,
    ft: FrameTruth,
    boxes: np.ndarray,
    owner: np.ndarray,
    p_detect: float = 0.85,
    false_alarm_rate: float = 0.4,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A SIMULATED per-view person detector (seed 003, sec. 3.4, "Human Detection").

    A person is detectable in a view when its foot point is in the image, its box is at
    least 14 px tall and at least half of its silhouette is unoccluded; it is then
    detected with probability ``p_detect`` at its foot pixel plus ``N(0, sigma_px^2)``
    noise. False alarms: Poisson(``false_alarm_rate``) per view, uniform in the lower
    two thirds of the image. Each detection is mapped to the ground plane.

    Returns
    -------
    det_view : ndarray, shape (num_dets,), int
    det_px : ndarray, shape (num_dets, 2)
    det_ground : ndarray, shape (num_dets, 2)
    """
    V, H, W = owner.shape
    views, pxs = [], []
    n = ft.u.shape[0]
    foot = np.concatenate([ft.u, np.zeros((n, 1)), np.ones((n, 1))], axis=1)
    for v in range(V):
        if n:
            p = foot @ scene.P[v].T
            fx, fy = p[:, 0] / p[:, 2], p[:, 1] / p[:, 2]
            counts = np.bincount(owner[v][owner[v] >= 0], minlength=n)
            for i in range(n):
                b = boxes[v, i]
                area = sum(max(0, bb[2] - bb[0]) * max(0, bb[3] - bb[1]) for bb in b)
                tall = b[:, 3].max() - b[:, 1].min()
                if not (0 <= fx[i] < W and 0 <= fy[i] < H and p[i, 2] > 0):
                    continue
                if tall < 14 or area == 0 or counts[i] < 0.5 * 0.85 * area:
                    continue
                if rng.random() < p_detect:
                    views.append(v)
                    pxs.append([fx[i], fy[i]] + rng.normal(0, scene.sigma_px[v], 2))
        for _ in range(int(rng.poisson(false_alarm_rate))):
            views.append(v)
            pxs.append([rng.uniform(0, W), rng.uniform(H / 3, H)])
    det_view = np.array(views, dtype=np.int64)
    det_px = np.array(pxs, dtype=np.float64).reshape(-1, 2)
    ground = np.zeros((len(views), 2))
    for v in range(V):
        sel = det_view == v
        if sel.any():
            Hg = ground_homography(scene.P[v])
            ground[sel] = apply_homography(np.linalg.inv(Hg), det_px[sel])
    return det_view, det_px, ground
