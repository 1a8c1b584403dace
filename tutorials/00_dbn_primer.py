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
# # DBN primer: declare, filter, smooth, MAP, and check against pgmpy
#
# This notebook walks through the declarative layer (`dbn/`) and the exact engines
# (`inference/exact`) on two small models from `models/primer.py`:
#
# 1. a Bayes net: *is a person present, is the view occluded, does the detector fire*;
# 2. an HMM-like two-slice DBN: a person in one of three corridor zones, seen by a
#    detector that reports a zone or nothing (the data are **simulated** from the model).
#
# Set `DBNTRACK_QUICK=1` for the small sizes CI runs.

# %%
import os

import matplotlib.pyplot as plt
import numpy as np

import inference
from dbn import pgmpy_adapter as pa
from dbn.cpds import TabularCPD
from dbn.dbn import TwoSliceDBN, prev
from dbn.variables import DiscreteVariable
from inference.exact import JunctionTree, map_assignment, variable_elimination
from inference.exact.dbn_filter import DBNFilter
from models.primer import READINGS, ZONES, corridor_dbn, detector_bn, simulate_corridor

QUICK = os.environ.get("DBNTRACK_QUICK") == "1"

# %% [markdown]
# ## 1. A Bayes net
# Variables carry their cardinality and state names; a `TabularCPD` table has the parents'
# axes first and the child's last, so `table[parents]` is a row that sums to 1. The net is
# validated when built: a row that does not sum to 1, a negative entry, a cycle, an
# unknown parent or a shape mismatch raises an error naming the node and the value.

# %%
bn = detector_bn()
print(bn, bn.topological_order())
print(bn.table("detection"))

try:
    TabularCPD("detection", ["present"], [[0.9, 0.2], [0.1, 0.9]])
except ValueError as err:
    print(type(err).__name__, "-", err)

# %% [markdown]
# Every marginal in one junction-tree pass, a joint query by variable elimination, the
# most probable explanation by max-product, soft (virtual) evidence, and pgmpy's answer.

# %%
jt = JunctionTree(bn)
cal = jt.calibrate({"detection": "no"})
for name, p in cal.marginals.items():
    print(f"P({name} | detection=no) = {np.round(p, 4)}")
print("log P(detection=no) =", round(cal.log_evidence, 6))

joint = variable_elimination(bn, ["present", "occluded"], {"detection": "no"})
print("P(present, occluded | detection=no) =\n", joint.probabilities(["present", "occluded"]).round(4))

config, logp = map_assignment(bn, {"detection": "no"})
print("MAP:", {n: bn.variable(n).state_names[s] for n, s in config.items()}, "log P =", round(logp, 4))

soft = JunctionTree(bn).calibrate(soft_evidence={"detection": [0.3, 1.0]})
print("with a soft detection (likelihood 0.3 : 1):", soft.marginals["present"].round(4))

theirs = pa.pgmpy_marginals(pa.to_pgmpy(bn), ["present", "occluded"], {"detection": "no"})
print("max |ours - pgmpy| =", max(np.abs(theirs[n] - cal.marginals[n]).max() for n in theirs))

# %% [markdown]
# ## 2. A two-slice DBN
# A `TwoSliceDBN` declares one slice's variables, the CPDs of slice 0 and the CPDs of
# every later slice; a parent in the previous slice is written `prev(name)`. `unroll(T)`
# gives the Bayes net of `T` slices.

# %%
dbn = corridor_dbn()
print(dbn)
print(dbn.unroll(3), dbn.unroll(3).topological_order())

T = 60 if QUICK else 300
zones, readings = simulate_corridor(seed=1, num_timesteps=T, dbn=dbn)
flt = DBNFilter(dbn)
filt = flt.filter({"reading": readings})
smooth = flt.smooth({"reading": readings})
path, logp = flt.viterbi({"reading": readings})
print(f"log-likelihood {filt.log_likelihood:.3f}; Viterbi log P(path, readings) {logp:.3f}")
for name, est in [("filtered", filt.beliefs.argmax(1)), ("smoothed", smooth.posteriors.argmax(1)), ("Viterbi", path["zone"])]:
    print(f"{name:9s} zone accuracy {np.mean(est == zones):.2f}")

# %%
fig, axes = plt.subplots(3, 1, figsize=(10, 6), sharex=True)
for ax, (title, post) in zip(axes[:2], [("filtered P(zone | readings so far)", filt.beliefs),
                                         ("smoothed P(zone | all readings)", smooth.posteriors)]):
    ax.imshow(post.T, aspect="auto", cmap="Blues", vmin=0, vmax=1, interpolation="nearest")
    ax.plot(zones, "r.", ms=4, label="true zone")
    ax.set_yticks(range(3), ZONES)
    ax.set_title(title)
axes[0].legend(loc="upper right")
axes[2].plot(np.where(readings < 3, readings, np.nan), "k|", label="reading")
axes[2].plot(path["zone"], "g-", lw=1, label="Viterbi path")
axes[2].set_yticks(range(3), ZONES)
axes[2].set_xlabel("slice")
axes[2].legend(loc="upper right")
fig.tight_layout()

# %% [markdown]
# ### On-line use
# `init` / `step` absorb one slice at a time and return a new state (the old one is left
# as it was); the log-likelihood accumulates, the belief is normalised at every step.

# %%
state = flt.init({"reading": READINGS[readings[0]]})
for t in range(1, 10):
    state = flt.step(state, {"reading": int(readings[t])})
print(state.t, flt.marginal(state, "zone").round(4), round(state.log_likelihood, 4))
print("equals the batch filter:", np.allclose(state.belief, filt.beliefs[9]))

# %% [markdown]
# ### The same model in pgmpy
# `dbn_to_pgmpy` converts the template; pgmpy's `DBNInference.forward_inference` gives the
# same filtered marginal (one slice per call; see `benchmarks/dbn_filter.py` for the
# speed difference, and for pgmpy's error when several slices are asked at once).

# %%
model = pa.dbn_to_pgmpy(dbn)
evidence = {("reading", t): READINGS[r] for t, r in enumerate(readings[:15])}
theirs = pa.pgmpy_dbn_forward(model, [("zone", 14)], evidence)[("zone", 14)]
print("pgmpy:", theirs.round(6), " ours:", filt.beliefs[14].round(6))
back = pa.dbn_from_pgmpy(model)
print("round trip:", back)
# the pgmpy model and its evidence, as they are, go to every generic engine
print("inference.filter:", inference.filter(model, evidence).marginals["zone"][14].round(6))

# %% [markdown]
# ### Any cardinality, any slice structure
# A 3-state root node and an extra hidden variable inside the slice are no problem.

# %%
mode = DiscreteVariable("mode", 3)
x = DiscreteVariable("x", 2)
y = DiscreteVariable("y", 2)
rng = np.random.default_rng(0)
dbn2 = TwoSliceDBN(
    [mode, x, y],
    [TabularCPD("mode", [], [0.2, 0.3, 0.5]), TabularCPD("x", ["mode"], rng.dirichlet([1, 1], 3)),
     TabularCPD("y", ["x"], [[0.9, 0.1], [0.2, 0.8]])],
    [TabularCPD("mode", [prev("mode")], rng.dirichlet([1, 1, 1], 3)),
     TabularCPD("x", ["mode", prev("x")], rng.dirichlet([1, 1], (3, 2))),
     TabularCPD("y", ["x"], [[0.9, 0.1], [0.2, 0.8]])],
)
f2 = DBNFilter(dbn2)
res2 = f2.filter({"y": rng.integers(0, 2, size=20)})
print(f2, f2.marginals_of(res2.beliefs, "mode")[-1].round(4))
