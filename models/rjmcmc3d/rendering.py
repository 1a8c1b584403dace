"""Rendering of the SIMULATED observations of seed 003, section 3.3: foreground maps
``D_v`` and colour images ``I_v`` (occlusion, silhouettes, noise, false alarms).
"""

from __future__ import annotations

import numpy as np

from models.rjmcmc3d.detection import detect
from models.rjmcmc3d.projection import depths, part_boxes
from models.rjmcmc3d.types import Frame, Scene, Truth

__all__ = ["render_frame"]


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
