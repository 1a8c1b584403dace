"""Camera geometry of seed 003: pinhole cameras, ground-plane homographies and the
vertical-vanishing-point rectification ``H = G R T`` (seed 003, section 2).

World coordinates are metres with the ground plane ``z = 0`` and ``z`` pointing up.
Image coordinates are pixels ``(x, y)`` with ``y`` pointing down.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from dbn.checks import real_array
from dbn.errors import InputError, NonFiniteError, ShapeError

__all__ = [
    "Camera",
    "Rectification",
    "apply_homography",
    "camera_center",
    "ground_homography",
    "homography_jacobian",
    "in_front",
    "look_at_camera",
    "projection_matrix",
    "rectification",
    "rectified_projection",
    "vertical_vanishing_point",
]


class Camera(NamedTuple):
    """A pinhole camera ``x ~ K (R X + t)``.

    Attributes
    ----------
    K : ndarray, shape (3, 3)
        Intrinsics (pixels).
    R : ndarray, shape (3, 3)
        World-to-camera rotation.
    t : ndarray, shape (3,)
        World-to-camera translation (metres).
    width, height : int
        Image size in pixels.
    """

    K: np.ndarray
    R: np.ndarray
    t: np.ndarray
    width: int
    height: int


class Rectification(NamedTuple):
    """The slant-removing homography of seed 003, section 2 and its factors.

    Attributes
    ----------
    H : ndarray, shape (3, 3)
        ``T^{-1} G R T``: seed 003's ``G R T`` followed by the translation back, so the
        chosen point ``x0`` keeps its pixel coordinates.
    G, R, T : ndarray, shape (3, 3)
        The factors: ``T`` moves ``x0`` to the origin, ``R`` rotates the translated
        vertical vanishing point onto the positive ``y`` axis, ``G`` sends it to infinity.
    y_inf : float
        Distance of the vanishing point from ``x0`` (``inf`` when already at infinity).
    """

    H: np.ndarray
    G: np.ndarray
    R: np.ndarray
    T: np.ndarray
    y_inf: float


def _check_matrix(name: str, value: np.ndarray, shape: tuple[int, ...]) -> np.ndarray:
    arr = real_array(name, value)
    if arr.shape != shape:
        raise ShapeError(f"{name} has shape {arr.shape}, expected {shape}")
    if not np.all(np.isfinite(arr)):
        raise NonFiniteError(f"{name} holds NaN or infinity: {arr.tolist()}")
    return arr


def projection_matrix(camera: Camera) -> np.ndarray:
    """``P = K [R | t]``, shape (3, 4)."""
    return camera.K @ np.concatenate([camera.R, camera.t[:, None]], axis=1)


def camera_center(camera: Camera) -> np.ndarray:
    """Optical centre ``-R^T t`` in world coordinates, shape (3,)."""
    return -camera.R.T @ camera.t


def in_front(camera: Camera, ground: np.ndarray) -> np.ndarray:
    """Whether ground points ``(x, y, 0)`` are in front of ``camera``: depth ``(R X + t)_z
    > 0``.

    A pixel above the horizon maps through the ground homography to a point behind the
    camera, on the ray's backward extension: a place the camera cannot see.

    Parameters
    ----------
    camera : Camera
    ground : ndarray, shape (n, 2)
        Points on the ground plane (metres).

    Returns
    -------
    ndarray, shape (n,), bool
    """
    g = np.asarray(ground, dtype=np.float64).reshape(-1, 2)
    return g @ camera.R[2, :2] + camera.t[2] > 0


def look_at_camera(
    position: np.ndarray,
    target: np.ndarray,
    focal: float,
    width: int,
    height: int,
) -> Camera:
    """A zero-roll pinhole camera at ``position`` looking at ``target``.

    Parameters
    ----------
    position, target : ndarray, shape (3,)
        Camera centre and a point on the optical axis (world metres).
    focal : float
        Focal length in pixels (square pixels, principal point at the image centre).
    width, height : int
        Image size in pixels.
    """
    pos = _check_matrix("position", position, (3,))
    tgt = _check_matrix("target", target, (3,))
    if focal <= 0:
        raise InputError(f"focal={focal} must be positive")
    fwd = tgt - pos
    if np.linalg.norm(fwd) == 0:
        raise InputError("position and target coincide")
    z = fwd / np.linalg.norm(fwd)
    right = np.cross(z, np.array([0.0, 0.0, 1.0]))
    if np.linalg.norm(right) < 1e-9:
        raise InputError("camera looks straight up or down: roll is undefined")
    x = right / np.linalg.norm(right)
    y = np.cross(z, x)  # points down in the image
    R = np.stack([x, y, z])
    K = np.array([[focal, 0.0, width / 2.0], [0.0, focal, height / 2.0], [0.0, 0.0, 1.0]])
    return Camera(K, R, -R @ pos, int(width), int(height))


def apply_homography(H: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Map points by a homography.

    Parameters
    ----------
    H : ndarray, shape (3, 3)
    points : ndarray, shape (..., 2)

    Returns
    -------
    ndarray, shape (..., 2)
    """
    pts = np.asarray(points, dtype=np.float64)
    hom = pts @ H[:, :2].T + H[:, 2]
    return hom[..., :2] / hom[..., 2:3]


def homography_jacobian(H: np.ndarray, point: np.ndarray) -> np.ndarray:
    """Jacobian ``d(x', y') / d(x, y)`` of a homography at ``point``, shape (2, 2).

    For ``G`` of seed 003, section 2 this is
    ``y_inf / (y - y_inf)^2 [[y_inf - y, x], [0, y_inf]]``.
    """
    x = np.array([point[0], point[1], 1.0])
    num = H @ x
    w = num[2]
    return (H[:2, :2] * w - np.outer(num[:2], H[2, :2])) / w**2


def ground_homography(P: np.ndarray) -> np.ndarray:
    """Homography from the ground plane ``(x, y, 1)`` (``z = 0``) to the image, (3, 3)."""
    P = _check_matrix("P", P, (3, 4))
    return P[:, [0, 1, 3]]


def vertical_vanishing_point(P: np.ndarray) -> np.ndarray:
    """Homogeneous image of the vertical direction ``(0, 0, 1, 0)``: ``P[:, 2]``, (3,)."""
    P = _check_matrix("P", P, (3, 4))
    return P[:, 2].copy()


def rectification(v_perp: np.ndarray, x0: np.ndarray) -> Rectification:
    """The homography mapping the vertical vanishing point to infinity (seed 003, sec. 2).

    ``T`` translates ``x0`` to the origin, ``R`` rotates the translated vanishing point
    onto the positive ``y`` axis at ``(0, y_inf)``, and

    .. math::

        G = \\begin{bmatrix} 1 & 0 & 0 \\\\ 0 & 1 & 0 \\\\ 0 & -1/y_\\infty & 1
        \\end{bmatrix}

    sends it to the point at infinity ``(0, y_inf, 0)``; ``G`` has identity Jacobian at
    the origin, so ``G R T`` acts as the rotation ``R`` near ``x0`` (a rigid motion,
    no linear distortion). The returned ``H = T^{-1} G R T`` adds the translation back.

    Parameters
    ----------
    v_perp : ndarray, shape (3,)
        Homogeneous vertical vanishing point (third coordinate may be 0).
    x0 : ndarray, shape (2,)
        The point where the map should be rigid (e.g. the image centre).

    Returns
    -------
    Rectification
    """
    v = _check_matrix("v_perp", v_perp, (3,))
    p0 = _check_matrix("x0", x0, (2,))
    T = np.array([[1.0, 0.0, -p0[0]], [0.0, 1.0, -p0[1]], [0.0, 0.0, 1.0]])
    vt = T @ v
    at_infinity = abs(vt[2]) < 1e-12 * np.linalg.norm(vt)
    direction = vt[:2] if at_infinity else vt[:2] / vt[2]
    if at_infinity and direction[1] < 0:  # a direction: pick the downward-pointing sign
        direction = -direction
    if np.linalg.norm(direction) == 0:
        raise InputError(f"v_perp={v.tolist()} coincides with x0={p0.tolist()}")
    theta = math.atan2(direction[0], direction[1])
    c, s = math.cos(theta), math.sin(theta)
    R = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    vr = R @ vt
    if at_infinity:
        y_inf = math.inf
        G = np.eye(3)
    else:
        y_inf = float(vr[1] / vr[2])
        G = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, -1.0 / y_inf, 1.0]])
    T_inv = np.array([[1.0, 0.0, p0[0]], [0.0, 1.0, p0[1]], [0.0, 0.0, 1.0]])
    return Rectification(T_inv @ G @ R @ T, G, R, T, y_inf)


def rectified_projection(camera: Camera) -> tuple[np.ndarray, Rectification]:
    """Projection matrix of the rectified image ``H P`` (3, 4), rigid at the image centre.

    In the rectified image every 3-D vertical line is a vertical image line, so the
    projection of an upright elliptic cylinder is bounded by an axis-aligned box
    (seed 003, section 2 and fig. 3).
    """
    P = projection_matrix(camera)
    centre = np.array([camera.width, camera.height]) / 2
    try:
        rect = rectification(vertical_vanishing_point(P), centre)
    except InputError:  # it said "v_perp=[...] coincides with x0=[...]"
        raise InputError(
            "a camera looks straight down (or up): the image of the vertical is the image "
            "centre, so the image cannot be rectified (seed 003 needs cameras that see the "
            "floor obliquely)"
        ) from None
    return rect.H @ P, rect
