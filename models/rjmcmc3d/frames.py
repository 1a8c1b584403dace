"""What a :class:`~models.rjmcmc3d.types.Frame` must hold, checked before any tracking.

Images are float in [0, 1]: ``D`` (background distance) and ``image`` (RGB) of any float
dtype with every value in ``[0, 1]``. An 8-bit image (0..255) is NOT accepted as is (the
likelihood would read 255 as 255 times "certainly foreground" and count extra people,
issue 14): convert it explicitly with :func:`unit_image`. Detections: ``det_view`` integer
views in ``0..num_views-1``, ``det_px`` and ``det_ground`` finite, shape ``(num_dets, 2)``;
both with ``|x| <= 1e6`` (pixels, metres).
"""

from __future__ import annotations

import numpy as np

from dbn.errors import InputError, NonFiniteError, ShapeError

__all__ = ["MAX_METRES", "check_frame", "unit_image"]

MAX_METRES = 1e6


def unit_image(image: np.ndarray) -> np.ndarray:
    """An 8-bit image (uint8, 0..255) as float32 in [0, 1] (``image / 255``).

    Raises
    ------
    InputError
        ``image`` is not ``uint8``.
    """
    a = np.asarray(image)
    if a.dtype != np.uint8:
        raise InputError(f"unit_image expects a uint8 image, got dtype {a.dtype}")
    return a.astype(np.float32) / np.float32(255.0)


def _check_unit(name: str, a: np.ndarray, shape: tuple[int, ...]) -> None:
    if a.shape != shape:
        raise ShapeError(f"frame.{name} has shape {a.shape}, expected {shape}")
    if not np.issubdtype(a.dtype, np.floating):
        hint = (
            " (convert 8-bit images with models.rjmcmc3d.unit_image)" if a.dtype == np.uint8 else ""
        )
        raise InputError(f"frame.{name} must be float in [0, 1], got dtype {a.dtype}{hint}")
    if not np.all(np.isfinite(a)):
        raise NonFiniteError(f"frame.{name} holds NaN or infinity")
    lo, hi = float(a.min(initial=0.0)), float(a.max(initial=0.0))
    if lo < 0.0 or hi > 1.0:
        raise InputError(
            f"frame.{name} must be in [0, 1], got values in [{lo:g}, {hi:g}]"
            " (8-bit images: divide by 255, see models.rjmcmc3d.unit_image)"
        )


def _check_points(name: str, a: np.ndarray, n: int, bound: float | None) -> None:
    if a.shape != (n, 2):
        raise ShapeError(f"frame.{name} has shape {a.shape}, expected ({n}, 2)")
    if not np.issubdtype(a.dtype, np.floating) and not np.issubdtype(a.dtype, np.integer):
        raise InputError(f"frame.{name} must be real numbers, got dtype {a.dtype}")
    if not np.all(np.isfinite(a)):
        raise NonFiniteError(f"frame.{name} holds NaN or infinity")
    if bound is not None and a.size and np.abs(a).max() > bound:
        raise InputError(f"frame.{name} holds |value| > {bound:g}")


def check_frame(scene, frame) -> None:
    """Raise a :mod:`dbn.errors` class if ``frame`` cannot be tracked in ``scene``.

    Raises
    ------
    ShapeError, NonFiniteError, InputError
        Wrong shapes, NaN/inf, images not float in [0, 1], views out of range.
    """
    shape = (scene.num_views, scene.height, scene.width)
    _check_unit("D", np.asarray(frame.D), shape)
    _check_unit("image", np.asarray(frame.image), (*shape, 3))
    dv = np.asarray(frame.det_view)
    if dv.ndim != 1 or not np.issubdtype(dv.dtype, np.integer):
        raise InputError(f"frame.det_view must be 1-D integer views, got {dv.dtype} {dv.shape}")
    if dv.size and (dv.min() < 0 or dv.max() >= scene.num_views):
        raise InputError(f"frame.det_view holds a view outside 0..{scene.num_views - 1}")
    n = dv.shape[0]
    _check_points("det_px", np.asarray(frame.det_px), n, MAX_METRES)
    _check_points("det_ground", np.asarray(frame.det_ground), n, MAX_METRES)
