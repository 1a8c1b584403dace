"""Groups of 3, 4 and 5 people (issue 16): hand-made merge/split stroke graphs whose true
labelling is in the domains (representable) and is the MAP (recoverable), with exact
inference checked against a dense enumeration of the joint; groups first seen as groups
(new groups of m objects)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from models.jorge.labels import LabelParams, admissible_labels, new_objects
from models.jorge.network import LabelGraph, NetworkConfig, node_name, solve
from models.jorge.online import OnlineConfig, OnlineLabeller
from models.jorge.strokes import make_stroke

POOL = 40
PARAMS = LabelParams(max_group_size=5, new_group_probs=(0.6, 0.1, 0.1, 0.1, 0.1), p_join=0.02)
CFG = NetworkConfig(pool_size=POOL, labels=PARAMS, size_min_reference=2, size_reference_neighbours=0,
                    size_reference_quantile=0.0, size_mu_single=0.0, size_slope=1.0, size_sigma=0.3,
                    palette_count_table=(), palette_gain_table=(), palette_missing_table=())
"""Region sizes are exact here (width 20 per person): the reference is the smallest
region (one person) and the log area grows by log k. No palette colour-count, gain or
missing-colour evidence: these strokes' palettes are their five colours, not their
people's palettes (the tables fitted on simulated palettes of a 12-colour pool do not
apply)."""


def _palette(p: int) -> list[int]:
    return list(range(5 * p, 5 * p + 5))


def _colours(people) -> list[int]:
    """Five colours from the members' palettes, as many from each as possible."""
    people = sorted(people)
    out = []
    j = 0
    while len(out) < 5:
        p = people[j % len(people)]
        c = _palette(p)[j // len(people)]
        out.append(c)
        j += 1
    return sorted(set(out))


def _stroke(k, start, end, pos, end_pos, people):
    return make_stroke(k, start, end, pos, end_pos, _colours(people), people, pool_size=POOL,
                       size=(20.0 * len(people), 50.0))


def merge_split_strokes(k: int):
    """k people: the first a = k - 2 (3 -> 1, 4 -> 2, 5 -> 3) merge one by one into group
    A, the last two into group B, A and B merge into the k-group, which splits back into
    A and B. Person p is born at stroke p."""
    a = k - 2
    strokes = [_stroke(p, 0, 10 * max(p, 1), (100 + 10 * p, 100), (100 + 10 * p, 100), {p}) for p in range(a)]
    strokes += [_stroke(a + i, 0, 10 * a, (200 + 10 * i, 300), (200 + 5 * i, 300), {a + i}) for i in range(2)]
    n = len(strokes)
    group = {0}
    last = 0
    for p in range(1, a):  # A grows: {0, 1}, {0, 1, 2}, ...
        group = group | {p}
        t = 10 * p + 2
        strokes.append(_stroke(n, t, t + 6, (100 + 10 * p, 100), (100 + 10 * p, 100), group))
        last, n = n, n + 1
    t = 10 * a + 2
    strokes.append(_stroke(n, t, t + 6, (202, 300), (160, 200), {a, a + 1}))  # B
    b_idx, n = n, n + 1
    if a > 1:  # A walks to the meeting point
        strokes.append(_stroke(n, t, t + 6, (100 + 10 * (a - 1), 100), (150, 190), set(range(a))))
        last, n = n, n + 1
    else:
        strokes[0] = _stroke(0, 0, t + 6, (100, 100), (150, 190), {0})
    t += 8
    strokes.append(_stroke(n, t, t + 6, (155, 195), (155, 195), set(range(k))))
    n += 1
    t += 8
    strokes.append(_stroke(n, t, t + 6, (145, 195), (100, 195), set(range(a))))
    strokes.append(_stroke(n + 1, t, t + 6, (165, 195), (220, 195), {a, a + 1}))
    del last, b_idx
    strokes.sort(key=lambda s: (s.start, s.index))
    return strokes


def _graph(strokes, cfg=CFG):
    g = LabelGraph(cfg, fps=25.0)
    for s in strokes:
        g.add_stroke(s)
    return g


def _dense_log_joint(win):
    """Enumeration oracle: log p(x_active, r = 1, soft evidence) as one dense array over
    the active label nodes, every CPD table broadcast onto it (no junction tree)."""
    names = [node_name(k) for k in win.active]
    axis = {n: i for i, n in enumerate(names)}
    shape = [win.bn.cardinality(n) for n in names]
    out = np.zeros(shape)
    for var, cpd in win.bn.cpds.items():
        table = np.asarray(cpd.table)
        vars_ = [*cpd.parents, var]
        if var in win.evidence:
            table = table[..., win.evidence[var]]
            vars_ = vars_[:-1]
        keep = [v in axis for v in vars_]
        table = table[tuple(slice(None) if k else 0 for k in keep)]
        vars_ = [v for v, k in zip(vars_, keep) if k]
        order = np.argsort([axis[v] for v in vars_])
        table = np.transpose(table, order)
        full = [1] * len(names)
        for v in vars_:
            full[axis[v]] = shape[axis[v]]
        with np.errstate(divide="ignore"):
            out = out + np.log(table).reshape(full)
    for n, lik in win.soft_evidence.items():
        full = [1] * len(names)
        full[axis[n]] = shape[axis[n]]
        with np.errstate(divide="ignore"):
            out = out + np.log(lik).reshape(full)
    return names, out


def _check_window(win):
    res = solve(win)
    names, lj = _dense_log_joint(win)
    assert res.log_prob == pytest.approx(lj.max(), abs=1e-9)
    ours = tuple(win.domains[n].index(res.labels[int(n[1:])]) for n in names)
    assert lj[ours] == pytest.approx(lj.max(), abs=1e-9)
    logz = np.logaddexp.reduce(lj.ravel())
    assert res.log_evidence == pytest.approx(logz, abs=1e-9)
    p = np.exp(lj - logz)
    for i, n in enumerate(names):
        m = p.sum(axis=tuple(j for j in range(len(names)) if j != i))
        np.testing.assert_allclose(res.marginals[int(n[1:])], m, atol=1e-10)
    return res


def _online(strokes, cfg=CFG) -> OnlineLabeller:
    """The on-line labeller over the strokes (inference every frame, every node kept
    active, domains pruned as usual, no re-identification pass)."""
    lab = OnlineLabeller(OnlineConfig(network=cfg, period_s=0.04, max_active=64, reid_prior=0.0), fps=25.0)
    for s in strokes:
        lab.add_stroke(s)
    lab.finish()
    return lab


@pytest.mark.parametrize("k", [3, 4, 5])
def test_k_person_merge_and_split_is_representable_and_recovered(k):
    strokes = merge_split_strokes(k)
    assert max(len(s.truth) for s in strokes) == k
    lab = _online(strokes)
    for s in strokes:  # representable: the true label is still in the (pruned) domain
        assert frozenset(s.truth) in lab.graph.nodes[s.index].domain, (s.index, s.truth)
    for s in strokes:  # recoverable: the MAP labelling is the truth
        assert lab.labels[s.index] == frozenset(s.truth), (s.index, lab.labels[s.index], s.truth)


@pytest.mark.parametrize("k", [3, 4, 5])
def test_k_person_window_against_enumeration(k):
    """The last three nodes (the k-group and its two parts) active, the rest frozen to
    their true labels: MAP and marginals equal the dense enumeration."""
    strokes = merge_split_strokes(k)
    g = _online(strokes).graph
    n = len(strokes)
    for s in strokes[: n - 3]:
        g.freeze(s.index, frozenset(s.truth))
    res = _check_window(g.window([s.index for s in strokes[n - 3:]]))
    for s in strokes[n - 3:]:
        assert res.labels[s.index] == frozenset(s.truth)


def test_seed_max_group_size_three_cannot_represent_four():
    """The root cause of groups of 4+ always being wrong with the old cap of 3."""
    strokes = merge_split_strokes(4)
    g = _graph(strokes, replace(CFG, labels=LabelParams(max_group_size=3)))
    four = [s for s in strokes if len(s.truth) == 4][0]
    assert frozenset(four.truth) not in g.nodes[four.index].domain


def _group_walks_in(m):
    """m people enter together (a root stroke), walk, split into m // 2 and the rest;
    a bystander of one person's size."""
    people = set(range(m))
    part = set(range(m // 2))

    def stroke(k, start, end, pos, end_pos, who):
        return make_stroke(k, start, end, pos, end_pos, _colours(who), who, pool_size=POOL,
                           size=(20.0 * len(who), 50.0))

    return [
        stroke(0, 0, 50, (300, 250), (300, 250), {7}),  # a bystander (one person's size)
        stroke(1, 0, 20, (100, 100), (100, 100), people),
        stroke(2, 22, 40, (100, 100), (100, 100), people),
        stroke(3, 42, 50, (90, 100), (60, 100), part),
        stroke(4, 42, 50, (110, 100), (140, 100), people - part),
    ], part


FIVE_SPLIT = pytest.mark.xfail(strict=True, reason=(
    "the model's own MAP (unpruned, exact) is a group of 4 split 2 + 2: eq. 9 spreads "
    "P_split over 2^m - 2 parts (30 for 5, 14 for 4), which outweighs size-only evidence of "
    "sigma 0.3 (colours cannot tell: the members share the birth palette); before issue 16's "
    "fourth round the pruned on-line labeller (rows renormalised over pruned domains) ended "
    "elsewhere than the model's MAP and happened to find the truth"))


@pytest.mark.parametrize("m", [2, 3, pytest.param(5, marks=FIVE_SPLIT)])
def test_group_first_seen_as_a_group_is_a_new_group(m):
    """The root's new label holds m objects and the parts take disjoint pieces of it.
    With the seed's single l_new (q = (1,)) the root can only be one object."""
    strokes, part = _group_walks_in(m)
    g = _online(strokes).graph
    group = new_objects(1, m)
    assert group in g.nodes[1].domain
    res = _check_window(g.window(range(5)))
    assert res.labels[1] == group
    assert res.labels[2] == group
    assert len(res.labels[3]) == len(part) and len(res.labels[4]) == m - len(part)
    assert res.labels[3] | res.labels[4] == group
    seed = _graph(strokes, NetworkConfig(pool_size=POOL, labels=LabelParams(max_group_size=5)))
    assert all(len(lab) == 1 for lab in seed.nodes[1].domain)


def test_join_label_admissible_only_with_p_join():
    F = frozenset
    with_join = admissible_labels([[F({1, 2})]], [False], F({7}), 5, join=True)
    assert F({1, 2, 7}) in with_join
    assert F({1, 2, 7}) not in admissible_labels([[F({1, 2})]], [False], F({7}), 5)
    assert F({1, 2, 7}) not in admissible_labels([[F({1, 2})]], [False], F({7}), 2, join=True)


def _links(scale: float, fps: float, gate: str) -> list:
    """Parents of every stroke of a merge/split layout drawn ``scale`` times larger and
    sampled at ``fps`` (the same motion in seconds)."""
    f = fps / 25.0
    strokes = [
        make_stroke(0, 0, int(10 * f), (0, 0), (scale * 20, 0), [0, 1], size=(scale * 25, scale * 25)),
        make_stroke(1, 0, int(10 * f), (scale * 80, 0), (scale * 50, 0), [2, 3], size=(scale * 25, scale * 25)),
        make_stroke(2, int(20 * f), int(30 * f), (scale * 35, 0), (scale * 35, 0), [0, 2],
                    size=(scale * 50, scale * 25)),
        make_stroke(3, int(40 * f), int(50 * f), (scale * 10, 0), (0, 0), [0, 1], size=(scale * 25, scale * 25)),
        make_stroke(4, int(40 * f), int(50 * f), (scale * 60, 0), (scale * 90, 0), [2, 3],
                    size=(scale * 25, scale * 25)),
    ]
    g = LabelGraph(NetworkConfig(gate=gate), fps=fps)
    for s in strokes:
        g.add_stroke(s)
    return [n.parents for n in g.nodes]


def test_scaled_gate_links_the_same_motion_at_any_image_scale_and_frame_rate():
    want = [(), (), (0, 1), (2,), (2,)]
    assert _links(1.0, 25.0, "scaled") == want
    assert _links(2.0, 7.0, "scaled") == want
    assert _links(1.0, 25.0, "pixels") == want
    assert _links(2.0, 7.0, "pixels") != want  # the pixel gate does not carry over


@pytest.mark.parametrize("m", [2, 3])
def test_pruned_online_labels_are_the_unpruned_map(m):
    """With pruned domains (cap 12) the on-line labeller ends where exact inference on the
    whole unpruned network does (``truncate_pruned``; issue 16, fourth round). Not for
    m = 5: there the instant cap (12 labels) at the start of the part of three people
    keeps the 3-person labels and drops the 2-person part of the group of 4 that the
    unpruned MAP gives it (that MAP is itself wrong, see ``FIVE_SPLIT``)."""
    strokes, _ = _group_walks_in(m)
    online = _online(strokes)
    exact = solve(_graph(strokes).window(range(len(strokes))))
    assert [online.labels[k] for k in range(len(strokes))] == [exact.labels[k] for k in range(len(strokes))]
