"""Pruned domains keep the unpruned model's probabilities (issue 16, fourth round).

``child_table(..., truncate=True)`` divides each row by its mass over every admissible
label, so on the full domain it is the renormalised table and on a pruned domain it is the
full table's columns; a window over pruned domains (``NetworkConfig.truncate_pruned``,
kept-mass nodes ``m{k}``) has the unpruned joint restricted to the kept labels. Oracles:
the unpruned table and a dense enumeration of the window's joint."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from models.jorge.labels import LabelParams, admissible_labels, birth_stroke, child_table
from models.jorge.network import LabelGraph, kept_name, node_name, solve
from tests.models.jorge.test_jorge_groups import CFG, _dense_log_joint, merge_split_strokes

F = frozenset
labels_strategy = st.frozensets(st.integers(0, 5), min_size=1, max_size=3)
domain_strategy = st.lists(labels_strategy, min_size=1, max_size=4, unique=True)


def _params(p_new, p_merge, gmax, p_join, roots_only):
    q = (0.6, 0.25, 0.15)
    return LabelParams(p_new, p_merge, 0.6, gmax, p_part=0.3, new_group_probs=q, p_join=p_join,
                       child_new_groups=not roots_only)


@settings(max_examples=60, deadline=None)
@given(doms=st.lists(domain_strategy, min_size=1, max_size=2), shared=st.lists(st.booleans(), min_size=2, max_size=2),
       p_new=st.floats(0.01, 0.4), p_merge=st.floats(0.0, 0.5), gmax=st.integers(3, 5),
       p_join=st.sampled_from([0.0, 0.1]), roots_only=st.booleans(), keep=st.randoms(use_true_random=False))
def test_truncated_rows_are_the_unpruned_rows(doms, shared, p_new, p_merge, gmax, p_join, roots_only, keep):
    params = _params(p_new, p_merge, gmax, p_join, roots_only)
    flags, new = shared[: len(doms)], F({99})
    full = admissible_labels(doms, flags, new, gmax, partial=True, max_new=1 if roots_only else 3,
                             join=p_join > 0)
    t_full = child_table(doms, flags, full, new, params, truncate=True)
    # on the full domain: a distribution per row, the renormalised table
    np.testing.assert_allclose(t_full.sum(-1), 1.0, atol=1e-12)
    np.testing.assert_allclose(t_full, child_table(doms, flags, full, new, params), atol=1e-12)
    # on a pruned domain (the new label always kept): the same entries, rows sum to what is kept
    pruned = [full[0]] + [lab for lab in full[1:] if keep.random() < 0.5]
    t = child_table(doms, flags, pruned, new, params, truncate=True)
    np.testing.assert_allclose(t, t_full[..., [full.index(lab) for lab in pruned]], atol=1e-12)
    assert np.all(t.sum(-1) <= 1.0 + 1e-12)


def test_children_are_single_new_objects_when_new_groups_are_at_roots_only():
    params = LabelParams(p_new=0.05, max_group_size=3, new_group_probs=(0.5, 0.3, 0.2), child_new_groups=False)
    net = replace(CFG, labels=params)
    strokes = merge_split_strokes(3)
    g = LabelGraph(net, fps=25.0)
    for s in strokes:
        g.add_stroke(s)
    for k, node in enumerate(g.nodes):
        born_here = [lab for lab in node.domain if all(birth_stroke(o) == k for o in lab)]
        assert born_here == [F({k})] if node.parents else len(born_here) == 3


SMALL = replace(CFG, labels=replace(CFG.labels, new_group_probs=(1.0,), p_join=0.0))
"""Single new objects, no joins: the unpruned domains stay small enough to enumerate."""


def _pruned_graph():
    strokes = merge_split_strokes(3)
    g = LabelGraph(SMALL, fps=25.0)
    for s in strokes:
        g.add_stroke(s)
    return g, strokes


def test_a_pruned_window_is_the_unpruned_joint_restricted():
    """The dense log joint over the pruned domains equals the unpruned one on the kept
    labels, up to one constant (the evidence's normaliser); renormalised rows do not."""
    g, strokes = _pruned_graph()
    active = list(range(len(strokes)))
    names, full = _dense_log_joint(g.window(active))
    doms_full = {n: g.window(active).domains[n] for n in names}
    rng = np.random.default_rng(0)
    for k in active:  # keep the true label, the new label and a random half of the rest
        dom = g.nodes[k].domain
        truth = F(strokes[k].truth)
        g.set_domain(k, [lab for lab in dom if lab in (truth, F({k})) or rng.random() < 0.5])
    win = g.window(active)
    assert any(kept_name(k) in win.evidence for k in active)
    _, pruned = _dense_log_joint(win)
    idx = np.ix_(*[[doms_full[n].index(lab) for lab in win.domains[n]] for n in names])
    finite = np.isfinite(full[idx])
    np.testing.assert_array_equal(np.isfinite(pruned), finite)
    diff = pruned[finite] - full[idx][finite]  # (-inf minus -inf left out: no NaN warning)
    np.testing.assert_allclose(diff, diff.flat[0], atol=1e-9)
    res = solve(win)  # exact inference on the window with kept-mass nodes against the oracle
    assert abs(res.log_prob - np.max(pruned)) < 1e-9
    renorm = replace(g.config, truncate_pruned=False)
    g.config = renorm
    _, old = _dense_log_joint(g.window(active))
    d_old = old[finite] - full[idx][finite]
    assert np.ptp(d_old) > 1e-6  # the renormalised rows distort the restricted joint


def test_kept_nodes_only_where_a_row_lost_mass():
    g, strokes = _pruned_graph()
    win = g.window(list(range(len(strokes))))
    assert not any(name.startswith("m") for name in win.evidence)
    assert all(node_name(k) in win.domains for k in range(len(strokes)))
