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
# # Generic DBN filtering: exact, Boyen-Koller, particle and Rao-Blackwellised
#
# One declaration, several engines:
#
# 1. a pgmpy user's dynamic Bayesian network, converted and filtered **exactly**;
# 2. the same family with **50 coupled chains**, where the exact belief has 2^50 states,
#    filtered with **Boyen-Koller** (a product of per-chain marginals), its error measured
#    against exact filtering where exact is still possible;
# 3. a **switching linear-Gaussian** model (a discrete manoeuvre switch driving a
#    continuous position/velocity state) filtered with a **Rao-Blackwellised particle
#    filter**, compared with a bootstrap particle filter on the same declaration.
#
# All data here are **simulated** from the models themselves (no real recordings).
# Set `DBNTRACK_QUICK=1` for the small sizes CI runs.

# %%
import os

import jax
import matplotlib.pyplot as plt
import numpy as np

import inference
from dbn import pgmpy_adapter as pa
from dbn.examples import coupled_chains, sample_coupled_chains, sample_switching_lds, switching_lds

QUICK = os.environ.get("DBNTRACK_QUICK") == "1"
rng = np.random.default_rng(0)

# %% [markdown]
# ## 1. A pgmpy DBN, filtered exactly
# The model: `n` binary chains in a line; chain `i` keeps its state with probability 0.9
# while its left neighbour is off and flips with probability 0.3 while it is on; each
# chain has one noisy binary sensor (wrong with probability 0.2). Suppose a pgmpy user has
# it as a `DynamicBayesianNetwork` (we build it here from our declaration, for brevity):
# `inference.filter` takes it as it is (through the pgmpy adapter) and, with
# `method="auto"`, runs the structured exact filter because its frontier is small.

# %%
n_small, T = 4, 40 if QUICK else 100
pgmpy_model = pa.dbn_to_pgmpy(coupled_chains(n_small))
print(pa.dbn_from_pgmpy(pgmpy_model))

states, ys = sample_coupled_chains(rng, n_small, T)
evidence = {f"y{i}": ys[:, i] for i in range(n_small)}
res = inference.filter(pgmpy_model, evidence)  # method="auto"
print("method:", res.method, "-", res.info["auto"])
p_on = np.stack([res.marginals[f"x{i}"][:, 1] for i in range(n_small)], 1)
print("log-likelihood of the sensor readings:", round(res.log_likelihood, 3))

# pgmpy's forward inference at one slice, for comparison
t_check = 5
pg = pa.pgmpy_dbn_forward(
    pgmpy_model,
    [("x0", t_check)],
    {(f"y{i}", t): str(int(ys[t, i])) for i in range(n_small) for t in range(t_check + 1)},
)
ours = np.array([1 - p_on[t_check, 0], p_on[t_check, 0]])
print("P(x0 | y_0:5): pgmpy", pg[("x0", t_check)].round(6), " ours", ours.round(6))

# %%
fig, axes = plt.subplots(n_small, 1, figsize=(8, 1.2 * n_small), sharex=True)
for i, ax in enumerate(axes):
    ax.plot(p_on[:, i], label="P(on | readings)")
    ax.plot(states[:, i], "k.", ms=3, label="simulated state")
    ax.set_ylabel(f"x{i}")
axes[0].legend(loc="upper right", fontsize=7)
axes[-1].set_xlabel("slice")
fig.suptitle("Exact filtered marginals, 4 coupled chains (simulated data)")
plt.show()

# %% [markdown]
# The same model from the command line: `write_two_slice_bif` writes it as the two-slice
# BIF file `dbntrack track dbn` reads (variables `x0_0` for slice 0, `x0_1` for the
# transition), every probability to the last bit, and `write_evidence` the readings as
# its evidence CSV (a `slice` column, one column per sensor). The marginals the command
# writes are those above.

# %%
import tempfile  # noqa: E402
from pathlib import Path  # noqa: E402

from models.cli import main as dbntrack  # noqa: E402
from models.io.dbn import read_marginals, write_evidence, write_two_slice_bif  # noqa: E402

folder = Path(tempfile.mkdtemp())
user_dbn = pa.dbn_from_pgmpy(pgmpy_model)
write_two_slice_bif(folder / "chains.bif", user_dbn)
write_evidence(folder / "readings.csv", user_dbn, evidence)
dbntrack(["track", "dbn", str(folder / "chains.bif"), str(folder / "readings.csv"),
          "-o", str(folder / "out"), "--quiet"])  # fmt: skip
cli_on = read_marginals(folder / "out" / "marginals.csv")["x0"][1][:, 1]
print("largest difference from inference.filter:", np.abs(cli_on - p_on[:, 0]).max())

# %% [markdown]
# ## 2. Fifty chains: Boyen-Koller
# The exact belief couples every chain: 2^n joint states, 2^50 at 50 chains, beyond any
# exact filter (the structured exact filter's frontier tables grow like 2^n: asked for
# 50 chains, it refuses before allocating and names the approximate methods).
# Boyen-Koller keeps one marginal per chain (the automatic clusters: chains share no edge
# inside a slice), propagates the product exactly through the template and projects back
# onto the clusters. First its error where exact filtering is still possible (8 chains):
# the KL divergence from the exact chain marginals, per slice. It stays small and does
# not grow with time: the projection errors contract instead of accumulating.

# %%
n8 = 8
states8, ys8 = sample_coupled_chains(rng, n8, T)
ev8 = {f"y{i}": ys8[:, i] for i in range(n8)}
dbn8 = coupled_chains(n8)
exact8 = inference.filter(dbn8, ev8, method="exact")
bk8 = inference.filter(dbn8, ev8, method="bk")
print("clusters:", bk8.info["clusters"])
p = np.stack([exact8.marginals[f"x{i}"] for i in range(n8)], 1)
q = np.stack([bk8.marginals[f"x{i}"] for i in range(n8)], 1)
kl = (p * np.log(p / q)).sum(-1)  # (T, chains)
print(f"mean KL {kl.mean():.2e}, last 20 slices {kl[-20:].mean():.2e}")

fig, ax = plt.subplots(figsize=(8, 2.5))
ax.semilogy(kl.mean(axis=1), label="mean over chains")
ax.semilogy(kl.max(axis=1), alpha=0.6, label="worst chain")
ax.set_xlabel("slice")
ax.set_ylabel("KL(exact || BK)")
ax.legend()
ax.set_title("Boyen-Koller approximation error over time, 8 chains (simulated data)")
plt.show()

# %%
n50 = 50
states50, ys50 = sample_coupled_chains(rng, n50, T)
bk50 = inference.filter(coupled_chains(n50), {f"y{i}": ys50[:, i] for i in range(n50)})
print("method:", bk50.method, "-", bk50.info["auto"])
p50 = np.stack([bk50.marginals[f"x{i}"][:, 1] for i in range(n50)], 1)
print("largest clique of a step:", bk50.info["max_clique_size"], "entries")
print("fraction of chain states recovered (MAP of marginal):", ((p50 > 0.5) == states50).mean())

fig, axes = plt.subplots(1, 2, figsize=(10, 3), sharey=True)
axes[0].imshow(states50.T, aspect="auto", cmap="Greys", interpolation="nearest")
axes[0].set_title("simulated states")
axes[1].imshow(p50.T, aspect="auto", cmap="Greys", vmin=0, vmax=1, interpolation="nearest")
axes[1].set_title("Boyen-Koller P(on)")
for ax in axes:
    ax.set_xlabel("slice")
axes[0].set_ylabel("chain")
plt.show()

# %% [markdown]
# ## 3. A switching linear-Gaussian model: Rao-Blackwellised particle filter
# A target moves along a line: `x = (position, velocity)`, `x_t = A x_{t-1} + noise`
# whose velocity noise depends on a discrete switch (`s = 0` cruising, `s = 1`
# manoeuvring; the CPD of `x` is a `ConditionalLinearGaussianCPD` with parent `s`), and a
# sensor reads the position with noise. The Rao-Blackwellised filter samples only the
# switch and carries the continuous state exactly, with a Kalman filter per particle; the
# bootstrap filter samples everything. Same declaration, same number of particles.

# %%
T_s, N = (40, 100) if QUICK else (150, 100)
slds = switching_lds()
s_true, x_true, y_obs = sample_switching_lds(rng, T_s)
rb = inference.filter(slds, {"y": y_obs}, "rbpf", key=jax.random.key(1), num_particles=N)
pf = inference.filter(slds, {"y": y_obs}, "particle", key=jax.random.key(1), num_particles=N)
for name, out in (("RBPF", rb), ("bootstrap PF", pf)):
    rmse = np.sqrt(np.mean((out.means["x"] - x_true) ** 2))
    print(f"{name:>13}: RMSE of the filtered state {rmse:.3f}")

fig, axes = plt.subplots(2, 1, figsize=(8, 4.5), sharex=True)
axes[0].plot(x_true[:, 0], "k-", lw=1, label="simulated position")
axes[0].plot(y_obs[:, 0], "k.", ms=3, alpha=0.5, label="readings")
axes[0].plot(rb.means["x"][:, 0], label="RBPF mean")
axes[0].plot(pf.means["x"][:, 0], "--", label="bootstrap PF mean")
axes[0].legend(fontsize=7)
axes[1].fill_between(np.arange(T_s), s_true, step="mid", color="0.85", label="simulated switch")
axes[1].plot(rb.marginals["s"][:, 1], label="RBPF P(manoeuvre)")
axes[1].plot(pf.marginals["s"][:, 1], "--", label="bootstrap P(manoeuvre)")
axes[1].set_xlabel("slice")
axes[1].legend(fontsize=7)
plt.show()

# %% [markdown]
# Over a short horizon the exact filter can enumerate every switch path (a Kalman filter
# per path); the RBPF's filtered mean then agrees with it within Monte-Carlo error (the
# test suite and `python -m benchmarks dbn_scale` check this with z-scores).
