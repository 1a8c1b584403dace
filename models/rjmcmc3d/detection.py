"""A SIMULATED per-view person detector (seed 003, section 3.4, "Human Detection")."""

from __future__ import annotations

import numpy as np

from models.rjmcmc3d.geometry import apply_homography, ground_homography
from models.rjmcmc3d.types import FrameTruth, Scene

__all__ = ["detect"]


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
