# ---
# jupyter:
#   jupytext:
#     formats: ipynb,py:percent
#     text_representation:
#       extension: .py
#       format_name: percent
#       format_version: '1.3'
#       jupytext_version: 1.19.6
#   kernelspec:
#     display_name: Python 3
#     language: python
#     name: python3
# ---

# %% [markdown]
# # Robot localisation with the auxiliary particle filter (seed 002, section 1.3)
#
# A robot with pose $s_k = (x, y, \theta)$ moves by odometry $u_k$ with Gaussian noise and
# observes a high-dimensional vector $y_k$. Seed 002 localises it with
#
# * the **auxiliary particle filter** of Pitt & Shephard: ancestors are chosen with the
#   look-ahead weights $\pi_{k-1}^i\,p(y_k|\mu_k^i)$ (eq. 1.12, $\mu_k^i$ the transition
#   mean) and the moved particles are weighted by $p(y_k|s_k^j)/p(y_k|\mu_k^{i_j})$ (eq. 1.13);
# * a **non-parametric sensor model** (eq. 1.14): PCA projects $y_k$ to a feature $z_k$, a
#   k-d tree finds the $J$ nearest training features, and the likelihood is a mixture of
#   Gaussian kernels at their poses with weights $2(J-j+1)/(J(J+1))$ and a bandwidth of
#   half the training-grid cell;
# * an **outlier rule**: when the nearest training feature is farther than a threshold
#   (an occlusion), the measurement is skipped and the particles are only propagated.
#
# The filters are the generic ones of `inference.particle` (any model declaring an
# initial law, a transition sampler, a log-likelihood and a look-ahead point); the robot
# is declared in `models.localization`. Part 1 uses a **simulated** world with perceptual
# aliasing; part 2 the **real** UTIAS MRCLAM dataset 6. Set `DBNTRACK_QUICK=1` for the
# small sizes CI runs.

# %%
import copy
import os

import jax
import jax.numpy as jnp
import matplotlib.pyplot as plt
import numpy as np

from models.localization.experiments import mrclam_trials, synthetic_trials
from models.localization.simulate import (
    build_trained_world,
    cast_scans,
    knn_model_for,
    simulate_run,
)
from models.localization.tracker import Localizer

QUICK = os.environ.get("DBNTRACK_QUICK") == "1"
STEPS = 40 if QUICK else 120
RUNS = 4 if QUICK else 10

# %% [markdown]
# ## 1. A simulated world with perceptual aliasing
#
# A 12 m x 6 m floor (**simulated**) with five identical pillars along its middle and walls
# painted in stripes that repeat every 2 m. The robot's panoramic sensor casts 72 rays
# (maximum range 3 m) and reads depth and wall colour: a 144-dimensional observation. Away
# from the end walls, places 2 m apart along the corridor look the same. The training set
# is a grid of poses (0.2 m, 24 headings) with their scans; the outlier threshold is the
# 99% quantile of nearest-neighbour distances of clean scans at random poses.

# %%
trained = build_trained_world(0)
world, sensor = trained.world, trained.sensor
run = simulate_run(1, world, STEPS, outlier_rate=0.1)
print(
    f"{len(sensor.train_poses)} training poses, features of dimension {sensor.pca.components.shape[0]}"
)
print(
    f"outlier threshold {sensor.threshold:.3f}; {run.outlier.sum()} occluded scans in {STEPS} steps"
)

fig, (ax, ax2) = plt.subplots(1, 2, figsize=(13, 3.6))
for (p, q), c in zip(world.segments, world.colours):
    ax.plot([p[0], q[0]], [p[1], q[1]], color=plt.cm.viridis(c), lw=3)
ax.plot(run.poses[:, 0], run.poses[:, 1], "k-", lw=1, label="true path")
ax.plot(*run.poses[0, :2], "go", label="start")
ax.set_aspect("equal")
ax.set_title("simulated floor plan (wall colour = hue)")
ax.legend(loc="upper right", fontsize=8)
k_out = int(np.flatnonzero(run.outlier)[0]) if run.outlier.any() else 0
clean = cast_scans(world, run.poses[k_out + 1 : k_out + 2])[0]
ax2.plot(clean[:72] * 3, label="noise-free depth")
ax2.plot(
    run.observations[k_out, :72] * 3,
    label=f"observed at step {k_out}" + (" (occluded)" if run.outlier[k_out] else ""),
)
ax2.set_xlabel("ray")
ax2.set_ylabel("depth [m]")
ax2.legend(fontsize=8)
plt.tight_layout()
plt.show()

# %% [markdown]
# ### The k-NN likelihood is multi-modal
#
# For one observation, the likelihood of eq. 1.14 evaluated on a grid of positions (heading
# fixed at the true one): the aliased places light up too.

# %%
model = knn_model_for(trained, run)
k = 5
obs_k = sensor.preprocess(run.observations[k])
gx, gy = np.meshgrid(np.linspace(0.2, 11.8, 240), np.linspace(0.2, 5.8, 120))
grid = np.column_stack([gx.ravel(), gy.ravel(), np.full(gx.size, run.poses[k + 1, 2])])
ll = np.asarray(model.log_likelihood(jnp.asarray(grid), obs_k)).reshape(gx.shape)
plt.figure(figsize=(8, 3.6))
plt.imshow(np.exp(ll - ll.max()), origin="lower", extent=(0.2, 11.8, 0.2, 5.8), cmap="magma")
plt.plot(*run.poses[k + 1, :2], "c+", ms=14, mew=2, label="true position")
plt.title(f"k-NN likelihood of observation {k} (J={sensor.num_neighbours})")
plt.legend(loc="upper right")
plt.show()

# %% [markdown]
# ## 2. Particle clouds over time
#
# The stateful `Localizer` checks every input (shape, NaN/inf, time order) before it
# touches its state, then runs one jit-compiled APF step.

# %%
loc = Localizer(jax.random.key(0), model, 1000, "apf")
show = [0, 2, 10, STEPS - 1]
fig, axes = plt.subplots(1, len(show), figsize=(16, 3))
j = 0
for t in range(STEPS):
    loc.update(jax.random.key(100 + t), run.actions[t], run.observations[t], timestamp=float(t))
    if t in show:
        a = axes[j]
        x = np.asarray(loc.state.particles)
        a.scatter(x[:, 0], x[:, 1], s=1, alpha=0.3)
        a.plot(*run.poses[t + 1, :2], "r+", ms=12, mew=2)
        a.set_xlim(0, 12)
        a.set_ylim(0, 6)
        a.set_aspect("equal")
        a.set_title(
            f"step {t}"
            + (
                " (outlier skipped)"
                if not bool(sensor.preprocess(run.observations[t]).valid)
                else ""
            )
        )
        j += 1
plt.tight_layout()
plt.show()
print("final error [m]:", np.hypot(*(loc.mean()[:2] - run.poses[-1, :2])))

# %% [markdown]
# ## 3. SIR against APF with occlusion outliers
#
# The same simulated runs (10% occlusions, N = 1,000) through the bootstrap filter and the
# auxiliary filter; both use the outlier rule. A failure is a run ending more than 1 m off.
# (The benchmark `python -m benchmarks localization` reports these numbers.)

# %%
res = synthetic_trials(0, trained, num_runs=RUNS, num_timesteps=STEPS, num_particles=1000)
for name in ("sir", "apf"):
    r = res[name]
    print(
        f"{name.upper()}: RMSE {r['rmse'].mean():.3f} m, failure rate {np.mean(r['final_error'] > 1):.0%}"
    )
print(f"odometry alone: RMSE {res['dead_reckoning_rmse'].mean():.3f} m")
plt.figure(figsize=(8, 3))
for name in ("sir", "apf"):
    plt.plot(res[name]["errors"].mean(0), label=name.upper())
plt.xlabel("step")
plt.ylabel("mean position error [m]")
plt.title("simulated world: error over time (mean over runs)")
plt.legend()
plt.show()

# %% [markdown]
# ### Without the outlier rule
#
# Switch the threshold off and the occluded scans reach the filters. On this world the
# auxiliary filter suffers more than SIR: its look-ahead picks ancestors that agree with
# the corrupted observation before the move (full benchmark: RMSE 0.25 m against 0.21 m).
# The outlier rule is what makes both robust here.

# %%
blind = copy.copy(sensor)
blind.threshold = float("inf")
res_blind = synthetic_trials(
    0, trained._replace(sensor=blind), num_runs=RUNS, num_timesteps=STEPS, num_particles=1000
)
for name in ("sir", "apf"):
    r = res_blind[name]
    print(
        f"no outlier rule, {name.upper()}: RMSE {r['rmse'].mean():.3f} m, failure rate {np.mean(r['final_error'] > 1):.0%}"
    )

# %% [markdown]
# ## 4. Real data: UTIAS MRCLAM dataset 6, robot 1
#
# Odometry is the action; range-bearing measurements to the 15 known landmarks are the
# observation (a parametric likelihood with a small uniform outlier term, through the same
# engine); motion capture is the truth. Noise settings were chosen on robot 2.

# %%
try:
    mr = mrclam_trials(
        0, num_runs=1 if QUICK else 5, num_particles=2000, duration=60.0 if QUICK else 300.0
    )
except FileNotFoundError as exc:
    mr = None
    print("MRCLAM data absent, part 4 skipped:", exc)
if mr is not None:
    seq = mr["sequence"]
    print(f"APF RMSE {mr['rmse'].mean():.3f} m; odometry alone {mr['dead_reckoning_rmse']:.3f} m")
    t = seq.times[1:] - seq.times[0]
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(13, 3.6))
    a1.plot(t, mr["errors"][0], label="APF")
    dead_err = np.hypot(*(mr["dead_reckoning"][:, :2] - seq.truth[1:, :2]).T)
    a1.plot(t, dead_err, label="odometry alone")
    a1.set_xlabel("time [s]")
    a1.set_ylabel("position error [m]")
    a1.legend()
    a2.plot(seq.truth[:, 0], seq.truth[:, 1], "k-", lw=1, label="motion capture")
    a2.plot(mr["means"][0, :, 0], mr["means"][0, :, 1], lw=1, label="APF mean")
    a2.plot(mr["dead_reckoning"][:, 0], mr["dead_reckoning"][:, 1], lw=1, label="odometry")
    a2.plot(seq.landmarks[:, 0], seq.landmarks[:, 1], "r^", label="landmarks")
    a2.set_aspect("equal")
    a2.legend(fontsize=8)
    plt.tight_layout()
    plt.show()

# %% [markdown]
# ## 5. Your robot's noise: `dbntrack fit localization`
#
# The noise settings above were chosen on robot 2 by hand. For a robot of yours,
# `dbntrack fit localization` measures them against the ground truth of training runs (the
# robust spreads of the range, bearing and odometry errors, and the median range error as a
# bias), then searches how much the filter must widen them: the motion and the sensor noise
# each times 1, 2, 4 and 8, kept by the least position RMSE on the training runs. It writes
# a config for `dbntrack track localization`. Here robot 2 (its first 5 minutes) is the
# training run and robot 1 is held out, as in the benchmark; the command line is
# `dbntrack fit localization DATA/Robot2_Odometry.dat.gz --validate
# DATA/Robot1_Odometry.dat.gz --config cfg.json -o OUT`.

# %%
import json
import tempfile
from pathlib import Path

from models import datasets
from models.cli import main

try:
    folder = datasets.require("mrclam6")
except FileNotFoundError as exc:
    folder = None
    print("MRCLAM data absent, part 5 skipped:", exc)
if folder is not None:
    out = Path(tempfile.mkdtemp())
    small = {"duration": 30.0, "num_particles": 300, "search_scales": [1, 4]}
    cfg = small if QUICK else {"duration": 300.0, "num_particles": 1000}
    (out / "cfg.json").write_text(json.dumps(cfg))
    main(["fit", "localization", str(folder / "Robot2_Odometry.dat.gz"), "--validate",
          str(folder / "Robot1_Odometry.dat.gz"), "--config", str(out / "cfg.json"),
          "-o", str(out / "fit"), "--quiet"])  # fmt: skip
    fit = json.loads((out / "fit" / "summary.json").read_text())
    p = fit["parameters"]
    scales = p["search_scales"]
    grid = np.array([[r["error"] for r in p["search"] if r["motion_scale"] == m]
                     for m in scales])  # fmt: skip
    fig, ax = plt.subplots(figsize=(5, 4))
    im = ax.imshow(grid, cmap="viridis", origin="lower")
    ax.set_xticks(range(len(scales)), [f"x{s:g}" for s in scales])
    ax.set_yticks(range(len(scales)), [f"x{s:g}" for s in scales])
    ax.set_xlabel("sensor noise scale")
    ax.set_ylabel("motion noise scale")
    ax.set_title("training (robot 2) position RMSE [m]", fontsize=9)
    fig.colorbar(im)
    plt.show()

# %% [markdown]
# On the full run (5 minutes, N = 1,000, one seed) the search keeps motion x 4 and sensor
# x 8 (0.222 m on robot 2), then drops the measured range bias (0.217 m without it): 0.217 m
# on robot 2 against 0.220 m with the hand-chosen settings, and 0.150 m against 0.158 m on
# the held-out robot 1 (0.164 m with the bias kept); with three seeds (N = 2,000) the fit
# and the hand-chosen settings are level on robot 1 (0.162 m each), and the training runs
# still drop the bias (0.221 m without, 0.225 m with it). The median range error is +5 cm in
# every window we looked at, yet a filter given it does worse: the motion-capture truth's
# reference point need not be the sensor's, so the fit lets the training runs decide. The
# surface is flat (0.22 to 0.27 m over the 16 pairs); one scale for both the range and the
# bearing cannot widen them 2.7 and 5 times, as the hand-chosen settings do, but separate
# range and bearing scales (the triples of 1, 2, 4, 8, tried on each robot's first 5
# minutes, N = 2,000, one seed) fitted them no better (robot 1: the same best point; robot
# 2: 0.218 against 0.219 m, both with the bias). The fit is for a robot
# whose noise is not MRCLAM's: its held-out error is the figure to check before using its
# config.

# %% [markdown]
# ## Takeaways
#
# * The engine is generic: the same `auxiliary_filter` runs the k-NN model and the
#   range-bearing model; a model only declares its laws and a look-ahead point.
# * The outlier rule turns occlusions into pure prediction steps.
# * Odometry alone drifts by decimetres within a minute on the real robot; the filter
#   stays near the motion-capture truth.
# * `dbntrack fit localization` measures a robot's noise against ground truth and chooses
#   the filter's widening of it on training runs; held-out runs say whether it holds.
