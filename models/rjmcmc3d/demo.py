"""Demo of the seed 003 multi-camera RJ-MCMC 3-D tracker (``dbntrack demo``).

The scene and the people are SIMULATED (real multi-camera video is not available to the
project); where ``../shared/data/pets2009/View_001.xml`` is present, its real Tsai
calibration is read and rectified to show seed 003's vertical-vanishing-point mapping.
"""

from __future__ import annotations

import time

import numpy as np

from models import datasets
from models.rjmcmc3d.geometry import (
    apply_homography,
    homography_jacobian,
    rectified_projection,
    vertical_vanishing_point,
)
from models.rjmcmc3d.geometry import projection_matrix as _projection
from models.rjmcmc3d.metrics import evaluate
from models.rjmcmc3d.model import TrackerParams
from models.rjmcmc3d.scene import (
    coverage_fractions,
    default_scene,
    load_tsai_xml,
    render_frame,
    simulate_walkers,
)
from models.rjmcmc3d.tracker import RJMCMCTracker

__all__ = ["run_demo"]


def _pets_rectification() -> None:
    try:
        path = datasets.require("pets2009", "View_001.xml")
    except FileNotFoundError:
        print("PETS2009 calibration not found: skipping the real-camera rectification.")
        return
    cam, _ = load_tsai_xml(path)
    P = _projection(cam)
    v = vertical_vanishing_point(P)
    Pr, rect = rectified_projection(cam)
    x0 = np.array([cam.width, cam.height]) / 2
    J = homography_jacobian(rect.H, x0)
    print(
        f"PETS2009 View_001 (real Tsai calibration, {cam.width}x{cam.height}): vertical "
        f"vanishing point at ({v[0] / v[2]:.0f}, {v[1] / v[2]:.0f}) px;"
    )
    print(
        f"  after H = G R T it is at infinity (w = {(rect.H @ v)[2]:.1e}); Jacobian at the "
        f"image centre = rotation by {np.degrees(np.arctan2(J[1, 0], J[0, 0])):.2f} deg"
    )
    corner = np.array([30.0, 30.0])
    print(
        f"  a corner pixel {corner.tolist()} moves to "
        f"{np.round(apply_homography(rect.H, corner), 1).tolist()}"
    )


def run_demo(quick: bool = True) -> None:
    """Track a few SIMULATED people across three partially overlapping cameras."""
    num_frames = 15 if quick else 60
    params = TrackerParams(num_moves=600 if quick else 1500, burn_in=200 if quick else 500)
    scene = default_scene(0)
    cov = coverage_fractions(scene, step=0.25)
    print(
        "SIMULATED scene: 20 m x 8 m hall, 3 cameras; floor seen by 0/1/2/3 cameras: "
        + " / ".join(f"{100 * c:.0f}%" for c in cov)
    )
    _pets_rectification()
    truth = simulate_walkers(1, scene, num_frames, 4)
    tracker = RJMCMCTracker(scene, params)
    state = tracker.init_state()
    results = []
    t0 = time.perf_counter()
    for t in range(num_frames):
        frame = render_frame(2, scene, truth, t)
        state, res = tracker.step(t, state, frame)
        results.append(res)
    dt = (time.perf_counter() - t0) / num_frames
    m = evaluate(truth.frames, results)
    print(
        f"tracked {num_frames} frames, {params.num_moves} RJ-MCMC moves/frame, "
        f"{1000 * dt:.0f} ms/frame"
    )
    print(
        f"MOTA {m['mota']:.3f}  IDF1 {m['idf1']:.3f}  ID switches {m['id_switches']}  "
        f"(ground plane, 0.5 m, py-motmetrics)"
    )
    last = results[-1]
    print(
        "last frame: track  x [m]  y [m]  height [m]   (truth: "
        + ", ".join(f"({x:.1f}, {y:.1f})" for x, y in truth.frames[-1].u)
        + ")"
    )
    for i, X in zip(last.ids, last.X, strict=True):
        print(f"  {i:3d}  {X[0]:6.2f} {X[1]:6.2f} {X[4]:6.2f}")
