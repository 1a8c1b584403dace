# ---
# jupyter:
#   jupytext:
#     text_representation:
#       extension: .py
#       format_name: percent
#       format_version: '1.3'
#       jupytext_version: 1.16.0
#   kernelspec:
#     display_name: Python 3
#     language: python
#     name: python3
# ---

# %% [markdown]
# # Multi-camera 3-D tracking with reversible-jump MCMC (seed 003)
#
# Yao & Odobez (seed 003) track a varying number of people on the ground plane of a
# calibrated scene seen by several partially overlapping cameras. The joint state holds,
# for each of M slots, a position, velocity, height and orientation plus an existence
# flag (eqs. 3-4). A reversible-jump Metropolis-Hastings chain (eq. 11) explores it with
# six moves (add, delete, stay, leave, switch, update), driven by a per-view person
# detector. The likelihood (eqs. 8-10) combines foreground maps and colour histograms
# over all views; the dynamics (eq. 7) carry a location-dependent noise term `C(u)` that
# encodes how badly the cameras localise a person at `u` on the floor.
#
# **Data.** Real multi-camera video is not available to the project, so the scene,
# the people, the foreground maps, the colour images and the detector are SIMULATED
# (`models.rjmcmc3d.scene`). The one real ingredient is the Tsai calibration of
# PETS2009 view 1, used below to show the rectification of section 2.

# %%
import os

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.patches import Ellipse, Rectangle

from models import datasets
from models.rjmcmc3d.geometry import (
    look_at_camera,
    projection_matrix,
    rectified_projection,
    vertical_vanishing_point,
)
from models.rjmcmc3d.metrics import evaluate
from models.rjmcmc3d.model import TrackerParams
from models.rjmcmc3d.scene import (
    FrameTruth,
    Truth,
    coverage_fractions,
    default_scene,
    load_tsai_xml,
    part_boxes,
    render_frame,
    simulate_walkers,
    visible_views,
)
from models.rjmcmc3d.tracker import RJMCMCTracker

QUICK = os.environ.get("DBNTRACK_QUICK") == "1"
MOVES = 600 if QUICK else 1500
BURN = 200 if QUICK else 500
print("quick mode" if QUICK else "full mode", f"- {MOVES} moves per frame")

# %% [markdown]
# ## 1. Rectification: the vertical vanishing point sent to infinity (section 2)
#
# People standing near the image border look slanted, because 3-D verticals meet at the
# vertical vanishing point `v`. The homography `H = G R T` translates a chosen point
# `x0` (the image centre) to the origin, rotates `v` onto the y axis and sends it to
# infinity with `G`; its Jacobian at `x0` is a rotation, so the image is not distorted
# there. Below, vertical 1.8 m poles on a ground grid, projected by the PETS2009 view 1
# camera (real calibration) before and after rectification.

# %%
pets = datasets.find("pets2009", "View_001.xml")
if pets is not None:
    cam, _ = load_tsai_xml(pets)
    print("PETS2009 View_001: real Tsai calibration")
else:
    cam = look_at_camera(np.array([0.0, -8.0, 7.0]), np.array([6.0, 6.0, 0.0]), 700, 768, 576)
    print("PETS2009 calibration absent: a SIMULATED tilted camera instead")
P = projection_matrix(cam)
Pr, rect = rectified_projection(cam)
v = vertical_vanishing_point(P)
print("vertical vanishing point:", np.round(v[:2] / v[2], 1), "-> after H:", np.round(rect.H @ v, 6))

centre = -cam.R.T @ cam.t
ahead = cam.R[2, :2] / np.linalg.norm(cam.R[2, :2])
side = np.array([-ahead[1], ahead[0]])
fig, axes = plt.subplots(1, 2, figsize=(12, 4.5))
for ax, M, title in ((axes[0], P, "original (undistorted) image"), (axes[1], Pr, "rectified: H P")):
    for d in np.linspace(8, 30, 6):
        for s in np.linspace(-12, 12, 7):
            g = centre[:2] + d * ahead + s * side
            pts = np.array([[g[0], g[1], 0.0, 1.0], [g[0], g[1], 1.8, 1.0]]) @ M.T
            if np.all(pts[:, 2] > 0):
                xy = pts[:, :2] / pts[:, 2:]
                ax.plot(xy[:, 0], xy[:, 1], "b-", lw=2)
    ax.set_xlim(0, cam.width)
    ax.set_ylim(cam.height, 0)
    ax.set_title(title)
plt.tight_layout()
plt.show()

# %% [markdown]
# ## 2. The simulated scene and the ground-plane uncertainty `C(u)` (eq. 7, fig. 2)
#
# A 20 m x 8 m hall and three cameras with partial overlap, as in the seed's metro
# scene: most of the floor is seen by one camera only. For each view that sees a
# person at `u`, a 3-pixel Gaussian noise on the foot position is carried to the floor
# by an unscented transform of the image-to-ground homography; the views are fused by
# adding informations. Far from a camera, the uncertainty stretches along the viewing
# direction.

# %%
scene = default_scene(0)
tracker = RJMCMCTracker(scene, TrackerParams(num_moves=MOVES, burn_in=BURN))
noise = tracker.noise
frac = coverage_fractions(scene, step=0.2)
print("floor seen by 0 / 1 / 2 / 3 cameras:", np.round(frac, 3))

xs, ys = np.arange(0.1, 20, 0.2), np.arange(0.1, 8, 0.2)
gx, gy = np.meshgrid(xs, ys, indexing="ij")
seen = visible_views(scene, np.stack([gx.ravel(), gy.ravel()], 1)).reshape(3, *gx.shape)
fig, ax = plt.subplots(figsize=(12, 5))
ax.imshow(seen.sum(0).T, origin="lower", extent=(0, 20, 0, 8), cmap="Greys", vmin=0, vmax=3, alpha=0.6)
for x in np.arange(1.0, 20, 2.0):
    for y in np.arange(1.0, 8, 2.0):
        i, j = noise.index(np.array([x, y]))
        C = noise.cov[i, j]
        w, V = np.linalg.eigh(C)
        ang = np.degrees(np.arctan2(V[1, 1], V[0, 1]))
        colour = "tab:green" if noise.num_seen[i, j] > 1 else ("tab:blue" if noise.num_seen[i, j] else "tab:red")
        ax.add_patch(Ellipse((x, y), 2 * np.sqrt(w[1]), 2 * np.sqrt(w[0]), angle=ang, fill=False, color=colour))
for c, name in zip(scene.centers, ["cam 0", "cam 1", "cam 2"], strict=True):
    ax.plot(c[0], np.clip(c[1], -0.5, 8.5), "k^")
    ax.annotate(name, (c[0], np.clip(c[1], -0.5, 8.5)), textcoords="offset points", xytext=(5, 5))
ax.set_xlim(-1, 21)
ax.set_ylim(-1, 9)
ax.set_title("1-sigma ground uncertainty C(u) (green: >= 2 views, blue: 1 view, red: none); grey = number of views")
ax.set_aspect("equal")
plt.show()

# %% [markdown]
# ## 3. One rendered frame: boxes, foreground maps, detections
#
# People are three elliptic cylinders (legs, torso, head); in the rectified views each
# projects to an axis-aligned box. The foreground map `D(x)` has noise, silhouettes that
# do not fill their boxes and false-alarm blobs; each camera shifts colours differently;
# the detector misses people and fires on nothing now and then.

# %%
num_frames = 20 if QUICK else 80
truth = simulate_walkers(1, scene, num_frames, 3 if QUICK else 6)
frame0 = render_frame(2, scene, truth, 0)
ft = truth.frames[0]
boxes = part_boxes(scene.P, ft.u, ft.h, ft.alpha, scene.width, scene.height)
fig, axes = plt.subplots(2, 3, figsize=(15, 7))
for view in range(3):
    axes[0, view].imshow(frame0.image[view])
    for n in range(len(ft.ids)):
        for b in boxes[view, n]:
            if b[2] > b[0] and b[3] > b[1]:
                axes[0, view].add_patch(Rectangle((b[0], b[1]), b[2] - b[0], b[3] - b[1], fill=False, color="w", lw=0.8))
    sel = frame0.det_view == view
    axes[0, view].plot(frame0.det_px[sel, 0], frame0.det_px[sel, 1], "y+", ms=12, mew=2)
    axes[0, view].set_title(f"camera {view}: truth boxes, detections (+)")
    axes[1, view].imshow(frame0.D[view], cmap="magma")
    axes[1, view].set_title(f"camera {view}: foreground map D(x)")
for a in axes.ravel():
    a.axis("off")
plt.tight_layout()
plt.show()

# %% [markdown]
# ## 4. Tracking
#
# One RJ-MCMC chain per frame (eq. 2), with the previous frame's posterior summarised
# per person by a Gaussian over position and velocity predicted through eq. 7. The
# incremental likelihood recomputes only the pixels of the people a move changes.

# %%
state = tracker.init_state()
results = []
for t in range(num_frames):
    state, res = tracker.step(t, state, render_frame(2, scene, truth, t))
    results.append(res)
metrics = evaluate(truth.frames, results)
print({k: round(v, 3) if isinstance(v, float) else v for k, v in metrics.items()})
print("acceptance rates of add, delete, stay, leave, switch, update in the last frame:",
      np.round(results[-1].accept_rate, 3))

# %%
last = results[-1]
colours = plt.cm.tab10(np.arange(10))
fig, axes = plt.subplots(1, 3, figsize=(15, 3.8))
frame = render_frame(2, scene, truth, num_frames - 1)
est = part_boxes(scene.P, last.X[:, :2], last.X[:, 4], last.X[:, 5], scene.width, scene.height)
for view in range(3):
    axes[view].imshow(frame.image[view])
    for n, tid in enumerate(last.ids):
        for b in est[view, n]:
            if b[2] > b[0] and b[3] > b[1]:
                axes[view].add_patch(Rectangle((b[0], b[1]), b[2] - b[0], b[3] - b[1], fill=False,
                                               color=colours[tid % 10], lw=1.5))
    axes[view].set_title(f"camera {view}: estimated body boxes (colour = track)")
    axes[view].axis("off")
plt.tight_layout()
plt.show()

fig, ax = plt.subplots(figsize=(12, 5))
for pid in np.unique(np.concatenate([f.ids for f in truth.frames])):
    tr = np.array([f.u[f.ids == pid][0] for f in truth.frames if pid in f.ids])
    ax.plot(tr[:, 0], tr[:, 1], "-", color="0.7", lw=5)
tracks: dict[int, list] = {}
for r in results:
    for tid, X in zip(r.ids, r.X, strict=True):
        tracks.setdefault(int(tid), []).append(X[:2])
for tid, pts in tracks.items():
    pts = np.array(pts)
    ax.plot(pts[:, 0], pts[:, 1], ".-", color=colours[tid % 10], label=f"track {tid}")
ax.set_xlim(0, 20)
ax.set_ylim(0, 8)
ax.set_aspect("equal")
ax.legend(loc="upper right", fontsize=7, ncol=2)
ax.set_title("ground-plane tracks (grey: truth)")
plt.show()

# %% [markdown]
# ## 5. Ablation of `C(u)` at a camera transition (like seed fig. 6)
#
# A scripted walker starts at the far end of camera 0's field (where depth is poorly
# measured) and walks into the part of the floor that cameras 2 and 1 see from close by.
# We track it with the ground-plane noise term and with `C(u) = 0` in eq. 7 (the update
# kernel then uses a fixed 0.1 m covariance), and count the tracks created. The outcome
# below is what this simulation gives; it is not tuned to reproduce the seed's figure.

# %%
def scripted_walker(start, velocity, n):
    frames, u = [], np.array(start, float)
    for _ in range(n):
        u = u + 0.2 * np.asarray(velocity)
        frames.append(FrameTruth(np.array([0]), u[None].copy(), np.array([1.75]),
                                 np.array([np.arctan2(velocity[1], velocity[0])])))
    return Truth(frames, np.array([[[0.1, 0.1, 0.3], [0.85, 0.15, 0.15], [0.55, 0.4, 0.3]]]), 0.2)


walk = scripted_walker((0.5, 7.0), (1.3, -0.25), 35 if QUICK else 60)
fig, ax = plt.subplots(figsize=(12, 4))
truth_path = np.array([f.u[0] for f in walk.frames])
ax.plot(truth_path[:, 0], truth_path[:, 1], "-", color="0.7", lw=6, label="truth")
for gn, style in ((True, "-"), (False, "--")):
    trk = RJMCMCTracker(scene, TrackerParams(num_moves=MOVES, burn_in=BURN, ground_noise=gn), noise)
    res = trk.run(3, [render_frame(4, scene, walk, t) for t in range(len(walk.frames))])
    m = evaluate(walk.frames, res)
    ids = sorted({int(i) for r in res for i in r.ids})
    print(f"C(u) {'on ' if gn else 'off'}: tracks created {len(ids)}, MOTA {m['mota']:.3f}, "
          f"IDF1 {m['idf1']:.3f}, ID switches {m['id_switches']}")
    for tid in ids:
        pts = np.array([r.X[r.ids == tid][0, :2] for r in res if tid in r.ids])
        ax.plot(pts[:, 0], pts[:, 1], style, marker=".", label=f"C(u) {'on' if gn else 'off'}: track {tid}")
ax.set_xlim(0, 20)
ax.set_ylim(0, 8)
ax.set_aspect("equal")
ax.legend(fontsize=7)
ax.set_title("a walker crossing from camera 0's far field into cameras 2 and 1")
plt.show()

# %% [markdown]
# ## 6. Incremental versus full likelihood
#
# The benchmark `python -m benchmarks rjmcmc3d` runs the same chain (same seed, same
# moves) with the likelihood recomputed from scratch at every move, checks that both
# chains end in the same state, and reports the time ratio. In pure numpy the
# incremental version is bounded by per-call overhead rather than by pixels (a move
# costs tens of microseconds: the proposal, the priors, projecting the changed person
# and histogramming its patch), so the ratio is much smaller than the ratio of pixels
# touched (about 100); see the benchmark's `speedup_vs_full_likelihood`,
# `speedup_likelihood_only`, `ms_per_move_shared` (the work both chains share) and the
# same figures at 768 x 576.
