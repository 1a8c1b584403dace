"""The body model of seed 003 (fig. 3: legs, torso, head as elliptic cylinders) projected
to axis-aligned part boxes in the rectified views, and what the floor each camera sees.
"""

from __future__ import annotations

import math

import numpy as np

from models.rjmcmc3d import compiled
from models.rjmcmc3d.compiled import project_person
from models.rjmcmc3d.types import Scene

__all__ = [
    "BODY_HALF_AXES",
    "BODY_Z",
    "BoxProjector",
    "coverage_fractions",
    "depths",
    "part_boxes",
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
        self.centers_a = np.ascontiguousarray(scene.centers[:, :2], dtype=np.float64)

    def one(self, x: float, y: float, h: float, a: float) -> tuple[list, list, list]:
        """Boxes (V, 3, 4), union boxes (V, 4) and camera distances (V,) as lists.

        Compiled (:func:`~models.rjmcmc3d.compiled.project_person`) when numba is
        available.
        """
        if compiled.AVAILABLE:
            b, bb, d = project_person(
                self.C, x, y, h, a, self.V, self.width, self.height, self.centers_a
            )
            return b.tolist(), bb.tolist(), d.tolist()
        return self.one_numpy(x, y, h, a)

    def arrays(self, x: float, y: float, h: float, a: float) -> tuple:
        """Boxes (V, 3, 4), union boxes (V, 4) (int64) and distances (V,) as arrays (the
        compiled projection; only with numba)."""
        return project_person(self.C, x, y, h, a, self.V, self.width, self.height, self.centers_a)

    def one_arrays(self, x: float, y: float, h: float, a: float) -> tuple:
        """:meth:`one` followed by the boxes (V, 3, 4), union boxes (V, 4) (int64) and
        distances (V,) as arrays (the compiled likelihood reads those; only with numba)."""
        b, bb, d = project_person(
            self.C, x, y, h, a, self.V, self.width, self.height, self.centers_a
        )
        return b.tolist(), bb.tolist(), d.tolist(), b, bb, d

    def one_numpy(self, x: float, y: float, h: float, a: float) -> tuple[list, list, list]:
        """:meth:`one` with numpy (the reference of the compiled path)."""
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
