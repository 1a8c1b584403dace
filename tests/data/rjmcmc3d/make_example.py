"""Write the tiny SIMULATED multi-camera example (run from the repository root): the
default 3-camera hall at 384 x 288 px (the default size; at 96 x 72 a person is a few pixels and the tracker finds nobody), 2 walkers, 6 frames (models.rjmcmc3d.scene, seed 1):
per view a Tsai calibration XML and foreground masks in the camera's own image (the
rendered rectified maps warped back), and the truth as MOTChallenge 3-D rows."""

import json
import math
from pathlib import Path

import matplotlib.image as mpimg
import numpy as np

from models.io.rjmcmc3d import warp
from models.rjmcmc3d.scene import default_scene, render_frame, simulate_walkers

out = Path("tests/data/rjmcmc3d")
scene = default_scene(0)
truth = simulate_walkers(1, scene, 6, 2)
for v, cam in enumerate(scene.cameras):
    d = out / f"view{v}"
    d.mkdir(exist_ok=True)
    R = cam.R
    ry = -math.asin(R[2, 0])
    rx, rz = math.atan2(R[2, 1], R[2, 2]), math.atan2(R[1, 0], R[0, 0])
    K = cam.K
    t = cam.t * 1000.0
    (d / "calibration.xml").write_text(
        f'<?xml version="1.0"?>\n<Camera name="view{v}">\n'
        f'  <Geometry width="{cam.width}" height="{cam.height}" ncx="{cam.width}" '
        f'nfx="{cam.width}" dx="1" dy="1" dpx="1" dpy="1"/>\n'
        f'  <Intrinsic focal="{float(K[1, 1])!r}" kappa1="0" cx="{float(K[0, 2])!r}" cy="{float(K[1, 2])!r}" '
        f'sx="{float(K[0, 0] / K[1, 1])!r}"/>\n'
        f'  <Extrinsic tx="{float(t[0])!r}" ty="{float(t[1])!r}" tz="{float(t[2])!r}" rx="{rx!r}" ry="{ry!r}" '
        f'rz="{rz!r}"/>\n</Camera>\n'
    )
frames = []
for k in range(6):
    fr = render_frame(2, scene, truth, k)
    for v in range(scene.num_views):
        H = scene.rects[v].H
        m = warp((fr.D[v] > 0.5).astype(np.float32), np.linalg.inv(H), (scene.height, scene.width))
        mpimg.imsave(out / f"view{v}" / f"mask_{k:04d}.png", m, cmap="gray", vmin=0, vmax=1)
with open(out / "truth3d.txt", "w") as f:
    for k, ft in enumerate(truth.frames):
        for i, u in zip(ft.ids, ft.u):
            f.write(f"{k + 1},{int(i)},-1,-1,-1,-1,1,{u[0]:.4f},{u[1]:.4f},0\n")
(out / "config.json").write_text(
    json.dumps({"floor": [0, 20, 0, 8], "num_moves": 300, "burn_in": 100, "min_blob": 6}) + "\n"
)
(out / "bad_truth3d.txt").write_text("1,1,-1,-1,-1,-1,1,2.0,3.0,0\n2,1,-1,-1,-1,-1,1,abc,3.0,0\n")
