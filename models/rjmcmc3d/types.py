"""The data types of the seed 003 scene: calibrated cameras and floor, ground truth of
the SIMULATED walkers, and one frame of observations.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from models.rjmcmc3d.geometry import Camera, Rectification

__all__ = ["Frame", "FrameTruth", "Scene", "Truth"]


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
        Foreground (background-distance) maps, float in [0, 1].
    image : ndarray, shape (num_views, height, width, 3), float32
        Colour images, float in [0, 1]. 8-bit images (uint8, 0..255) are rejected: convert
        them explicitly with :func:`models.rjmcmc3d.unit_image` (checks:
        :func:`models.rjmcmc3d.check_frame`).
    det_view : ndarray, shape (num_dets,), int
        View of each detection.
    det_px : ndarray, shape (num_dets, 2)
        Detected foot position in the rectified image (pixels).
    det_ground : ndarray, shape (num_dets, 2)
        That foot position mapped to the ground plane (metres).
    t : int or None
        Frame index (``None``: the frame after the tracker's last one). After the first
        frame it must advance by exactly one: a replayed, repeated or skipped frame is a
        :class:`~dbn.errors.TimeOrderError` naming ``frame.t``.
    """

    D: np.ndarray
    image: np.ndarray
    det_view: np.ndarray
    det_px: np.ndarray
    det_ground: np.ndarray
    t: int | None = None
