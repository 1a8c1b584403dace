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
# # Groups of pedestrians with a Bayes net of strokes (seed 004)
#
# Jorge, Marques & Abrantes label the *strokes* of a low-level tracker (pieces of
# trajectory broken by occlusions, merges and splits) with a Bayes net built on the fly:
# one label node per stroke, whose states are sets of object ids (a group is a set),
# restriction nodes that forbid two children of one stroke to share an object, and the
# stroke's dominant colours as soft evidence. We add one piece of evidence the paper does
# not use: the stroke's region size (its box area against the median of the strokes
# seen so far) as evidence on how many people its label holds, so that a one-person stroke
# leaving a group whose other member is hidden is not given the whole group's label
# (`NetworkConfig.size_evidence`, on by default). This notebook runs it on the CAVIAR
# **Meet_Split_3rdGuy** ground truth, the sequence of the paper.
#
# What is real and what is simulated: the boxes are the real CAVIAR ground truth; the
# occlusion gaps (boxes dropped for 5-15 frames) and the colours are **simulated** (the
# ground truth has neither). Without the data folder the notebook falls back to a
# **simulated** sequence and says so. Set `DBNTRACK_QUICK=1` for the small sizes CI runs.

# %%
import os

import matplotlib.pyplot as plt
import networkx as nx
import numpy as np

from dbn import pgmpy_adapter
from inference.exact import map_assignment
from models.jorge.demo import load_or_simulate
from models.jorge.labels import format_label
from models.jorge.network import NetworkConfig, solve
from models.jorge.online import OnlineConfig, OnlineLabeller, label_online
from models.jorge.scoring import colour_only_labels, optimal_people, score
from models.jorge.strokes import build_strokes

QUICK = os.environ.get("DBNTRACK_QUICK") == "1"
truth, real = load_or_simulate(0)
print(("real CAVIAR ground truth: " if real else "SIMULATED sequence (CAVIAR data absent): ")
      + f"{truth.name}, {truth.num_frames} frames, {truth.ids.size} people")

# %% [markdown]
# ## 1. Strokes
# The simulated low-level tracker joins people whose boxes overlap (IoU > 0.05) into one
# region, ends a stroke whenever the set of people in a region changes, and hides each
# person for 5-15 frames at a rate of 4 gap starts per 100 frames seen. Each stroke gets
# N = 5 dominant colours, each one of its people's palette colours with probability 0.8.
# The plot is seed 004's fig. 4a: one coordinate of each stroke against time, here
# coloured by the true set of people.

# %%
strokes = build_strokes(0, truth)
print(f"{len(strokes)} strokes, {strokes.num_groups} of them groups")
sets = sorted({tuple(sorted(s.truth)) for s in strokes})
cmap = plt.get_cmap("tab10")
fig, ax = plt.subplots(figsize=(9, 3.5))
for s in strokes:
    c = cmap(sets.index(tuple(sorted(s.truth))) % 10)
    ax.plot(s.frames / truth.fps, s.positions[:, 0], color=c, lw=3 if len(s.truth) > 1 else 1.5)
for i, t in enumerate(sets):
    ax.plot([], [], color=cmap(i % 10), label=str(list(t)))
ax.set(xlabel="time (s)", ylabel="column of the region centre (px)", title="strokes, by true people")
ax.legend(fontsize=7, ncol=2)
plt.show()

# %% [markdown]
# ## 2. On-line labelling
# Every T = 1 s the 16 most recent nodes are solved exactly (MAP labelling, eq. 11, and
# every node's marginal with a junction tree); older nodes are frozen to their MAP
# label, and labels whose posterior fell below 1e-3 are pruned, so one inference costs a
# bounded amount however long the sequence. Between inferences a new stroke takes the
# eq. 12 label from its colours and its labelled parents and siblings.
#
# In the seed's net a label only travels along links: once a person's stroke takes a new
# label (a missed link, a wrong MAP at a split), every later stroke of that person
# inherits the new object. A final off-line pass (our addition, `reid_prior`) renames an
# object born as a new label to an earlier object that had finished before it appeared,
# when its palette and the colours of its later one-person strokes favour that object
# (even prior odds), examining the objects in birth order. Both figures are printed.
#
# A person first seen inside a group (a new group's member, or a newcomer who joined)
# has the group's colours for a palette until a stroke of them alone is frozen. Inside
# the window, a stroke that continues such a person alone is scored on the parent
# stroke's palette, their latest view alone (`NetworkConfig.chain_palette`, a factor over
# the parent's and the child's labels folded into the child's CPD; issue 16's eleventh
# round): otherwise "a newcomer born as the member left" was scored on its own colours
# and won.
#
# A member of a group may be seen alone for a moment while the others are hidden, and
# then the whole group again. The link rule then links the new stroke to both the group's
# stroke and the member's (`NetworkConfig.nested_links`, issue 16's twelfth round), and the
# restriction between the group's two children admits the member inside the new stroke
# (`labels.restriction_allows`): before, the group came back as the member alone, or the
# member and a newcomer.

# %%
result = label_online(strokes, OnlineConfig())
ours = score(strokes, result.labels)
base = score(strokes, colour_only_labels(strokes))
eq6 = score(strokes, label_online(strokes, OnlineConfig(network=NetworkConfig(colour_mode="eq6"))).labels)
print(f"labelled in {result.seconds:.2f} s for {strokes.duration_s:.1f} s of video")
net_only = score(strokes, result.network_labels)
print(f"Bayes net: LE {ours.label_errors}/{ours.num_strokes} ({ours.error_rate:.1%}), "
      f"identity switches {ours.id_switches}")
print(f"Bayes net before the re-identification pass: LE {net_only.label_errors} ({net_only.error_rate:.1%})")
print(f"eq. 6 as written: LE {eq6.label_errors} ({eq6.error_rate:.1%})")
print(f"colour only (no network): LE {base.label_errors} ({base.error_rate:.1%})")

# %% [markdown]
# Seed 004's fig. 4b: the strokes coloured by their final label (object ids are matched to
# people as IDF1 does); errors are crossed.

# %%
people = optimal_people(strokes, result.labels)
names = sorted({format_label(lab) for lab in result.labels})
fig, ax = plt.subplots(figsize=(9, 3.5))
for s, lab in zip(strokes, result.labels):
    c = cmap(names.index(format_label(lab)) % 10)
    ax.plot(s.frames / truth.fps, s.positions[:, 0], color=c, lw=3 if len(lab) > 1 else 1.5)
    if s.index in ours.errors:
        mid = len(s.frames) // 2
        ax.plot(s.frames[mid] / truth.fps, s.positions[mid, 0], "kx", ms=9)
ax.set(xlabel="time (s)", ylabel="column (px)", title="MAP labels (x: labelling error)")
plt.show()
for k in ours.errors:
    s = strokes[k]
    meant = sorted(str(people.get(o)) for o in result.labels[k])
    print(f"stroke {k}: frames {s.start}-{s.end}, true {sorted(s.truth)}, "
          f"label {format_label(result.labels[k])} (stands for {meant})")

# %% [markdown]
# ## 3. The network at t = 12 s (seed 004, fig. 6)
# Grey nodes are frozen, white ones active; small squares are restriction nodes.

# %%
lab = OnlineLabeller(OnlineConfig(), fps=strokes.fps)
for s in strokes:
    if s.start > 12 * truth.fps:
        break
    lab.add_stroke(s)
lab.infer(int(12 * truth.fps))
g = lab.graph
graph = nx.DiGraph()
for k, node in enumerate(g.nodes):
    graph.add_node(f"x{k}")
    for p in node.parents:
        graph.add_edge(f"x{p}", f"x{k}")
restrictions = set()
for k in range(len(g)):
    for sib in g.siblings(k):
        if sib > k:
            r = f"r{k}_{sib}"
            restrictions.add(r)
            graph.add_edge(f"x{k}", r)
            graph.add_edge(f"x{sib}", r)
pos = {}
for k, node in enumerate(g.nodes):
    pos[f"x{k}"] = (node.stroke.start / truth.fps, node.stroke.positions[0, 0])
for r in restrictions:
    i, j = (int(v) for v in r[1:].split("_"))
    pos[r] = (0.5 * (pos[f"x{i}"][0] + pos[f"x{j}"][0]) + 0.3, 0.5 * (pos[f"x{i}"][1] + pos[f"x{j}"][1]))
fig, ax = plt.subplots(figsize=(9, 4))
hidden = [n for n in graph if n.startswith("x")]
colours = ["lightgrey" if g.nodes[int(n[1:])].frozen is not None else "white" for n in hidden]
nx.draw_networkx_nodes(graph, pos, nodelist=hidden, node_color=colours, edgecolors="k", node_size=320, ax=ax)
nx.draw_networkx_nodes(graph, pos, nodelist=sorted(restrictions), node_color="grey", node_shape="s", node_size=60, ax=ax)
nx.draw_networkx_edges(graph, pos, ax=ax, arrowsize=8)
nx.draw_networkx_labels(graph, pos, labels={n: format_label(lab.labels[int(n[1:])]) for n in hidden}, font_size=7, ax=ax)
ax.set(xlabel="start time (s)", ylabel="column (px)", title="label network at t = 12 s (grey: frozen)")
ax.tick_params(left=True, bottom=True, labelleft=True, labelbottom=True)
plt.show()

# %% [markdown]
# ## 4. Exact, and checked against pgmpy
# pgmpy 1.1.2's `map_query` builds the joint table of all the queried variables, so it
# can only check windows with a small joint: we take the windows of a run with at most 6
# active nodes and compare the last one whose joint has at most 10^5 configurations. The
# soft evidence (colours and size) becomes explicit binary children for pgmpy (virtual evidence as a
# node); our MAP log probability must equal the log probability of pgmpy's MAP.

# %%
small = label_online(strokes, OnlineConfig(max_active=6), keep_windows=True)
def joint_size(w):
    return float(np.prod([w.bn.cardinality(f"x{k}") for k in w.active]))
win = [w for w in small.labeller.windows if joint_size(w) <= 1e5][-1]
bn, ev = win.with_colour_nodes()
ours_map, ours_lp = map_assignment(bn, ev)
model = pgmpy_adapter.to_pgmpy(bn)
theirs = pgmpy_adapter.pgmpy_map(model, {n: bn.variable(n).state_names[s] for n, s in ev.items()})
theirs_lp = bn.log_joint({**{n: bn.variable(n).index(s) for n, s in theirs.items()}, **ev})
print(f"window of {len(win.active)} active nodes ({joint_size(win):.0f} joint configurations): "
      f"ours {ours_lp:.12f}, pgmpy {theirs_lp:.12f}")
assert abs(ours_lp - theirs_lp) < 1e-9
newest = win.active[-1]
print("marginal of the newest node:", np.round(solve(win).marginals[newest], 4),
      [format_label(x) for x in win.domains[f"x{newest}"]])

# %% [markdown]
# ## 5. Over seeds
# The error rate depends on the simulated gaps and colours; the benchmark
# (`python -m benchmarks jorge`) averages over five seeds and both CAVIAR sequences.

# %%
seeds = range(2 if QUICK else 5)
rates = []
for seed in seeds:
    st = build_strokes(seed, truth)
    rates.append((score(st, label_online(st).labels).error_rate,
                  score(st, colour_only_labels(st)).error_rate))
rates = np.array(rates)
print("error rate per seed (network, colour only):")
print(np.round(rates, 3))
print("means:", np.round(rates.mean(0), 3))

# %% [markdown]
# ## 6. Parameters learned on a declared training split (issue 16)
# The network's parameters are not picked by hand: `models.jorge.fit` declares a
# training split of the real sequences (`TRAIN_SEQUENCES`, simulation seeds 100-109)
# and a held-out validation part (`VALIDATION_SEQUENCES`: CAVIAR fra1gt and wk2gt,
# PETS2009 S2.L1) that is only ever scored. On training sequences the true people of
# every stroke are known, so the label nodes are observed and the maximum-likelihood
# CPD parameters are event frequencies (new objects, merges per structure, proper parts
# at splits, people joining unseen, new groups of m people) with one pseudo-count; the
# size likelihood is a least-squares fit, and the palette tables (how many distinct
# colours a region of k people shows, and how many colours a stroke adds to the palettes
# of the people its label names: the evidence that tells a group from one person) are
# add-one smoothed frequencies. A small documented search (`fit.SEARCH_GRID`, scored on
# the training split only, with the five seeds `fit.SCORE_SEEDS`; run it with
# `python -m models.jorge.fit --gates boxes`) then chose between these and the previous
# defaults, with new groups off, at roots only or anywhere, with joins only (a newcomer
# added to an inherited label) or with new groups at roots and joins, and with or without
# the merge test of the link rule (`NetworkConfig.merge_area`). Since the real training
# split has no CAVIAR-like group of three or more people, the search also scores
# SIMULATED meetings of 3-5 people (`fit.MEETING_SIZES`, other scenes than the
# benchmark's). It keeps only points fast enough
# for the bar (20x real time on every scoring set), and the current default
# (`fit.DEFAULT_POINT`) stays unless another point beats it by more than one standard error
# of the paired per-seed differences; the default network (`network.FITTED_LABELS`,
# `network.FITTED_PALETTE_GAINS`: since issue 16's tenth round new groups at roots and
# joins; since the twelfth, with nested links, the size counted once per region and the
# palette counts weighed 0.75 where a region continues, `NetworkConfig.palette_continued`,
# a dimension of the grid) is its result. A change the grid cannot express is confirmed on
# more scoring sets, `fit.CONFIRM_SEEDS`, with the rule written down before it runs: since
# the fourteenth round the colour-count evidence is the gain table given how many colours
# the label's known people already show (`NetworkConfig.palette_gain_bins`), alone, and a
# newcomer labelled into a group counts as a joiner as soon as that is its current label
# (`OnlineConfig.tentative_joiners`); since the fifteenth, a merge's second parent must be
# covered by the merged region's box, not merely touch it (`NetworkConfig.merge_cover`,
# chosen on how many links differ from the true ones on training-side data); since the
# twenty-first, a continuation or merge whose domain was capped before the window relabelled
# its parents gets back the label they now pass on (`OnlineConfig.restore_successors`); since
# the twenty-second, a split prior that prefers partitions (`LabelParams.split_cover`,
# `config.FITTED_SPLIT_COVER`, fitted on the training split; seed 004 draws the two parts of
# a split independently, so its prior expects a group of 4 or 5 to lose people at most
# splits). It helps groups of 4 and 5 in the SIMULATED meetings most; it landed on its fourth
# comparison, each on fresh seeds (`fit.CONFIRM_SEEDS`); since the twenty-third, that
# restriction node divides by the chance that two independently drawn parts of the group are
# compatible (`LabelParams.split_normalise`: observing the restriction on independent parts
# made every split of a group of four cost it against a group of three plus an unseen joiner);
# since the thirtieth, a new node's domain is capped on a posterior that leaves out the
# siblings' instant labels all the way up its chain (`OnlineConfig.clash_free_rank`: a label
# that a parent's sibling excluded for the moment is no longer dropped from the children);
# since the thirty-fourth, the palette evidence also counts the colours of the label's known
# people that the stroke's palette lacks (`NetworkConfig.palette_missing`,
# `config.FITTED_PALETTE_MISSING`): the gain table alone saw only the net gain, the same for
# the true label and for one that swaps a member for someone else.
# Seed 004's eq. 5 alone: `NetworkConfig(labels=replace(FITTED_LABELS, split_cover=()))`. Here we
# refit on fewer seeds and score the validation part with the default network and the
# colour-only baseline.

# %%
from models.jorge.fit import (
    TRAIN_SEEDS,
    TRAIN_SEQUENCES,
    VALIDATION_SEQUENCES,
    fit_parameters,
    load_sequence,
    training_strokes,
)
from models.jorge.labels import LabelParams
from models.jorge.network import FITTED_LABELS

print("training:", [n for _, n in TRAIN_SEQUENCES])
print("validation (held out):", [n for _, n in VALIDATION_SEQUENCES])
train = training_strokes(TRAIN_SEQUENCES[:2] if QUICK else TRAIN_SEQUENCES, seeds=TRAIN_SEEDS[:2])
if train:
    fitted = fit_parameters(train, NetworkConfig(labels=LabelParams(max_group_size=5))).labels
    for name in ("p_new", "p_merge", "p_merge_one_split", "p_merge_both_split", "p_split", "p_part", "p_join"):
        print(f"{name:20s} refit {getattr(fitted, name):.3f}   default {getattr(FITTED_LABELS, name):.3f}")
for folder, name in VALIDATION_SEQUENCES[: 1 if QUICK else None]:
    try:
        val = build_strokes(0, load_sequence(folder, name))
    except FileNotFoundError:
        print(f"{name}: absent")
        continue
    ours = score(val, label_online(val).labels)
    base = score(val, colour_only_labels(val, 5))
    print(f"{name}: {len(val)} strokes, error {ours.error_rate:.3f} (colour only {base.error_rate:.3f})")

# %% [markdown]
# Sequences of your own are held out by construction: put their ground truths in the data
# folder's `caviar/`, `pets2009/` or `mot/` (at any depth; a MOTChallenge `SEQ/gt/gt.txt`
# beside its `seqinfo.ini`) and `python -m benchmarks jorge` scores them as the split
# `unlisted`, on their own. A file that is a listed recording again is left out, found by
# its name (`fit.listed_copies`) or by its boxes (`models.jorge.recordings`): CAVIAR's
# archives hold `mws1gt1.xml`, the training recording Meet_WalkSplit from frame 100 on,
# which must not be scored as held out; MOTChallenge's `PETS09-S2L1` is our validation
# PETS2009 S2L1 with frames counted from 1 and other ids. Here a cut made the same way,
# its frames and ids renumbered, is recognised, with the frame shift.

# %%
from models.jorge.recordings import frame_offset, same_recording
from models.jorge.strokes import GroundTruth

try:
    names = ("ms3ggt.xml.gz", "mws1gt.xml.gz")
    listed = {n.split(".")[0]: load_sequence("caviar", n) for n in names}
except FileNotFoundError:
    print("CAVIAR ms3ggt / mws1gt: absent")
else:
    mws = listed["mws1gt"]
    later = mws.frames >= 100
    cut = GroundTruth("cut", mws.frames[later] - 100, mws.ids + 50, mws.boxes[later])
    print("mws1gt from frame 100 on, renumbered, is the recording of:", same_recording(cut, listed),
          "| frame shift:", frame_offset(cut, mws))

# %% [markdown]
# ## 7. Tracks in metres: ETH through a SIMULATED camera
# ETH `seq_eth` (Pellegrini et al. 2009) gives each pedestrian's ground position in metres,
# 2.5 times a second, and no image boxes, so by itself it makes no regions. `models.jorge.eth`
# looks at it through an assumed orthographic camera tilted 45 degrees (`ObliqueView`:
# people are upright cylinders of radius 0.25 m and height 1.75 m), so that people close
# across the view or one behind the other overlap, as in an oblique surveillance view. The
# view's settings decide how often people merge: every figure on it is a figure on a
# SIMULATED view of real motion. The benchmark scores it as its own split
# (`simulated_view`), never fitted on and kept out of the real views' pooled figures.

# %%
from collections import Counter

from models.jorge.eth import ObliqueView

print(ObliqueView())
try:
    eth = load_sequence("eth", "obsmat.txt.gz")
except FileNotFoundError:
    eth = None
    print("ETH seq_eth: absent")
if eth is not None:
    eth_strokes = build_strokes(0, eth)
    sizes = Counter(len(s.truth) for s in eth_strokes)
    print(f"{eth.name}: {eth.num_frames} annotations ({eth.duration_s:.0f} s), {eth.ids.size} people, "
          f"{len(eth_strokes)} strokes; people per stroke: {dict(sorted(sizes.items()))}")
    if not QUICK:  # about half a minute
        ours = score(eth_strokes, label_online(eth_strokes).labels)
        print(f"error {ours.error_rate:.3f} (colour only "
              f"{score(eth_strokes, colour_only_labels(eth_strokes, 5)).error_rate:.3f})")

# %% [markdown]
# ## 8. Your own files: the labeller's settings, and a sweep over them
# `dbntrack track jorge BOXES` runs all of the above on a box file (CAVIAR / PETS2009 XML,
# MOTChallenge, ETH `obsmat`). Its `--config` sets the stroke builder's fields and, over
# the fitted defaults, the labeller's: `network` (`NetworkConfig`: the link rule's gates,
# the evidence), `labels` (`LabelParams`, e.g. the group cap) and `online` (`OnlineConfig`).
# `strokes.csv` keeps the links and the network's settings, so `dbntrack eval` scores the
# labels and replays the same link rule to say who came into a region without a link.
# The defaults are the fit of section 6; other values are yours to validate. Strokes from
# your own low-level tracker (boxes per frame, dominant colours, optionally its links) go in
# as a regions file, `dbntrack track jorge REGIONS.jsonl`, labelled as they are
# (`models.io.jorge_regions`; `tests/data/jorge/regions.jsonl` is this example's strokes).

# %%
import json
import tempfile
from pathlib import Path

from models.cli import main

box_file = str(Path("..") / "tests" / "data" / "jorge" / "caviar.xml")  # a tiny CAVIAR example
tmp = Path(tempfile.mkdtemp())
(tmp / "cfg.json").write_text(json.dumps({"labels": {"max_group_size": 6},
                                          "network": {"max_gap_frames": 45}}))
main(["track", "jorge", box_file, "-o", str(tmp / "run"), "--config", str(tmp / "cfg.json"),
      "--truth", box_file, "--quiet"])
summary = json.loads((tmp / "run" / "summary.json").read_text())
print({k: summary["parameters"][k] for k in ("network", "labels", "online")})
print(open(tmp / "run" / "strokes.csv").read().splitlines()[:5])

# %% [markdown]
# A sweep runs one `dbntrack track` per grid point (`models.track.sweep_task.track_task`):
# the data is the rest of the command line, the seed `--seed`, and a dotted parameter name
# sets a field of a config object. `run_grid` runs it on a Dask cluster (here serially,
# the reference a cluster's run equals); from the shell, `dbntrack sweep
# tests/data/sweep_files.toml -o files.jsonl`. The occlusion gaps are simulated from the
# seed, so each setting is scored over several seeds.

# %%
from models.experiments import make_grid, run_grid
from models.track.sweep_task import track_task

grid = make_grid(["jorge"], [f"{box_file} --truth {box_file}"], seeds=range(3),
                 params={"network.max_gap_frames": [10, 30]})
records = run_grid(track_task, grid, serial=True, progress=False)
for gap in (10, 30):
    runs = [r["result"]["metrics"] for r in records
            if r["point"]["params"]["network.max_gap_frames"] == gap]
    print(f"max_gap_frames {gap}: error {np.mean([m['error_rate'] for m in runs]):.3f}, "
          f"people back without a link (gap) {np.mean([m['missed_links']['gap'] for m in runs]):.1f}")

# %% [markdown]
# ## 9. Parameters fitted on your files: `dbntrack fit jorge`
# The default network's parameters are the fit of section 6 on SIMULATED clean palettes. A
# low-level tracker of yours has its own noise: its colours, its region sizes, how often
# people meet. With files whose people you know (regions files with `truth`, or box
# files), `dbntrack fit jorge TRAIN... --validate HELD...` fits the same maximum-likelihood
# parameters on them (`models.track.jorge_fit`), keeps the config's settings, and writes
# `config.json` for `dbntrack track --config`; the summary gives each file's error with the
# default and the fitted network. Here the tracker's palettes are noisy (each stroke's
# dominant colours), and the files are SIMULATED strokes of the tiny example with other
# seeds: hold out whole recordings of yours instead. On the shared data, the same fit on the
# six training sequences took the held-out ones from 0.634 to 0.447 (README). On little data,
# `--prior-strength LAMBDA` shrinks each parameter row towards the config's network with
# LAMBDA pseudo-observations (`models.jorge.fit_prior`).

# %%
from dataclasses import replace

from models.io.jorge_regions import write_regions
from models.jorge.strokes import load_caviar


def noisy_regions(seed: int, name: str) -> str:
    """A regions file whose palettes are the strokes' dominant colours (SIMULATED)."""
    ss = build_strokes(seed, load_caviar(box_file))
    return str(write_regions(tmp / name, [replace(s, palette=s.colours) for s in ss], fps=ss.fps))


train = [noisy_regions(s, f"train_{s}.jsonl") for s in range(10, 16)]
held = [noisy_regions(s, f"held_{s}.jsonl") for s in range(20, 23)]
main(["fit", "jorge", *train, "--validate", *held, "-o", str(tmp / "fit"), "--quiet"])
fitted = json.loads((tmp / "fit" / "config.json").read_text())
print({k: round(v, 3) for k, v in fitted["labels"].items() if isinstance(v, float)})

# %% [markdown]
# How strong a prior? Choose it on the training files alone: `--folds K` with several
# strengths cuts the training files, in the order given, into K folds (keep one recording's
# files together, or name each file's recording with `--fold-by PATTERN`, a regular
# expression), labels each fold with the fits on the others, and fits the strength with
# the lowest mean error on all of them (`models.crossval`); `inf` is the prior itself, the
# config's network unchanged, so the choice can also be to keep it. The held-out files take
# no part in the choice, so their error is still a result. Here the noisy palettes make the
# plain fit the better one; on the shared data (README) clean palettes kept the default
# network or shrank strongly towards it.

# %%
main(["fit", "jorge", *train, "--validate", *held, "-o", str(tmp / "cv"), "--folds", "3",
      "--prior-strength", "0,100,1000,inf", "--quiet"])
cv = json.loads((tmp / "cv" / "summary.json").read_text())
print({k: cv["parameters"]["cross_validation"][k] for k in ("errors", "chosen")})
