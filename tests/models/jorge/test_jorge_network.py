"""The label network against brute-force enumeration and pgmpy (models/jorge/network.py)."""

from __future__ import annotations

import itertools
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dbn.errors import InputError, ModelError, TimeOrderError, UnknownVariableError
from models.jorge.labels import format_label
from models.jorge.network import FITTED_LABELS, LabelGraph, NetworkConfig, node_name, solve
from models.jorge.strokes import make_stroke

# the seed's label model (no new groups, no joins, as the default): with new groups and
# joins the unpruned domains of this window run to thousands of labels, too many to enumerate
SEED_LABELS = replace(FITTED_LABELS, new_group_probs=(1.0,), p_join=0.0)
GROUP_LABELS = replace(FITTED_LABELS, new_group_probs=(0.67, 0.18, 0.07, 0.04, 0.04), p_join=0.12)


def _graph(colour_mode: str = "ratio") -> LabelGraph:
    """Two people merge (s2), the group splits (s3, s4), s3 goes on (s5). The palettes are
    the strokes' noisy colours (``make_stroke``'s default), not their people's palettes, so
    no missing-colour evidence (it reads a palette as a clean estimate)."""
    g = LabelGraph(NetworkConfig(colour_mode=colour_mode, labels=SEED_LABELS, palette_missing_table=()), fps=25.0)
    strokes = [
        make_stroke(0, 0, 10, (0, 10), (10, 10), [0, 1, 2, 3, 4], {0}),
        make_stroke(1, 0, 10, (0, 40), (10, 40), [5, 6, 7, 8, 9], {1}),
        make_stroke(2, 12, 20, (12, 25), (20, 25), [0, 1, 5, 6, 10], {0, 1}),
        make_stroke(3, 22, 30, (22, 15), (30, 15), [0, 1, 2, 3, 11], {0}),
        make_stroke(4, 22, 30, (22, 35), (30, 70), [5, 6, 7, 10, 11], {1}),
        make_stroke(5, 32, 40, (32, 15), (40, 15), [0, 1, 2, 8, 9], {0}),
    ]
    for s in strokes:
        g.add_stroke(s)
    return g


def test_structure_of_the_example():
    g = _graph()
    assert [g.nodes[k].parents for k in range(6)] == [(), (), (0, 1), (2,), (2,), (3,)]
    assert [g.structure(k) for k in range(6)] == ["ROOT", "ROOT", "MERGE", "SPLIT", "SPLIT", "OCCLUSION"]
    assert frozenset({0, 1}) in g.nodes[2].domain
    assert frozenset({0}) in g.nodes[3].domain and frozenset({1}) in g.nodes[4].domain


def _brute_force(win):
    """Every configuration of the active label nodes, scored from the tables directly."""
    bn = win.bn
    names = [node_name(k) for k in win.active]
    best, best_lp, joint = None, -np.inf, {}
    for states in itertools.product(*[range(bn.cardinality(n)) for n in names]):
        x = dict(zip(names, states))
        x.update({node_name(b): 0 for b in win.boundary})
        x.update(win.evidence)
        with np.errstate(divide="ignore"):
            lp = bn.log_joint(x) + sum(np.log(win.soft_evidence[n][x[n]]) for n in names)
        joint[states] = lp
        if lp > best_lp:
            best, best_lp = x, lp
    return names, joint, best, best_lp


@pytest.mark.parametrize("mode", ["ratio", "eq6"])
def test_map_and_marginals_against_brute_force(mode):
    g = _graph(mode)
    win = g.window(range(6))
    assert set(win.evidence) == {"r3_4"}
    res = solve(win)
    names, joint, best, best_lp = _brute_force(win)
    assert res.log_prob == pytest.approx(best_lp, abs=1e-9)
    assert {node_name(k): win.domains[node_name(k)].index(v) for k, v in res.labels.items()} == {
        n: best[n] for n in names}
    lps = np.array(list(joint.values()))
    logz = np.logaddexp.reduce(lps)
    assert res.log_evidence == pytest.approx(logz, abs=1e-9)
    probs = np.exp(lps - logz)
    for i, n in enumerate(names):
        m = np.zeros(win.bn.cardinality(n))
        for states, p in zip(joint, probs):
            m[states[i]] += p
        np.testing.assert_allclose(res.marginals[int(n[1:])], m, atol=1e-12)
    # the two children of the split never share an object
    assert not (res.labels[3] & res.labels[4])


def test_frozen_boundary_window_against_brute_force():
    g = _graph()
    g.freeze(0, frozenset({0}))
    g.freeze(1, frozenset({1}))
    g.freeze(2, frozenset({0, 1}))
    win = g.window([3, 4, 5])
    assert win.boundary == (2,)
    res = solve(win)
    _, _, best, best_lp = _brute_force(win)
    assert res.log_prob == pytest.approx(best_lp, abs=1e-9)
    assert res.labels[3] == frozenset({0}) and res.labels[4] == frozenset({1})


def test_same_as_pgmpy(assert_window_matches_pgmpy):
    g = _graph()
    win = g.window(range(6))
    assert_window_matches_pgmpy(win, 6)


def test_bad_strokes_leave_the_graph_unchanged():
    g = _graph()
    before = (len(g), [n.domain for n in g.nodes], [list(n.children) for n in g.nodes])
    with pytest.raises(InputError):
        g.add_stroke(make_stroke(9, 50, 60, (0, 0), (1, 1), [1, 2]))  # wrong index
    with pytest.raises(TimeOrderError):
        g.add_stroke(make_stroke(6, 5, 60, (0, 0), (1, 1), [1, 2]))  # starts before stroke 5
    bad = make_stroke(6, 50, 60, (0, 0), (1, 1), [1, 2])
    object.__setattr__(bad, "colours", np.array([], dtype=np.int64))
    with pytest.raises(InputError):
        g.add_stroke(bad)
    ended = make_stroke(6, 50, 60, (0, 0), (1, 1), [1, 2])
    object.__setattr__(ended, "end", 40)
    with pytest.raises(TimeOrderError):
        g.add_stroke(ended)
    after = (len(g), [n.domain for n in g.nodes], [list(n.children) for n in g.nodes])
    assert before == after
    with pytest.raises(InputError):
        g.freeze(5, frozenset({42}))


def test_state_names_are_labels():
    g = _graph()
    win = g.window(range(6))
    names = win.bn.variable("x2").state_names
    assert names == tuple(format_label(x) for x in win.domains["x2"])


@settings(max_examples=25, deadline=None)
@given(data=st.data())
def test_random_small_networks_against_brute_force(random_window, data):
    """Random stroke layouts: MAP log probability, MAP and marginals equal enumeration."""
    win = random_window(data)
    res = solve(win)
    names, joint, best, best_lp = _brute_force(win)
    assert res.log_prob == pytest.approx(best_lp, abs=1e-9)
    lps = np.array(list(joint.values()))
    logz = np.logaddexp.reduce(lps)
    probs = np.exp(lps - logz)
    for i, name in enumerate(names):
        m = np.zeros(win.bn.cardinality(name))
        for states, p in zip(joint, probs):
            m[states[i]] += p
        np.testing.assert_allclose(res.marginals[int(name[1:])], m, atol=1e-10)


def test_window_rejects_unknown_nodes():
    g = _graph()
    with pytest.raises(UnknownVariableError):
        g.window([0, 42])
    g.freeze(0, frozenset({0}))
    with pytest.raises(InputError):
        g.window([0, 1])


def test_unpruned_domains_too_large_raise_a_model_error():
    """With new groups and joins the unpruned domains of the example grow along its chain;
    the window refuses a table past the limit with a ModelError (not a raw MemoryError)
    before it builds any table, while the on-line labeller, which prunes, labels the strokes."""
    from models.jorge.online import OnlineConfig, label_online

    seed = _graph()
    cfg = NetworkConfig(colour_mode="ratio", labels=GROUP_LABELS)
    g = LabelGraph(cfg, fps=25.0)
    for node in seed.nodes:
        g.add_stroke(node.stroke)
    with pytest.raises(ModelError, match="node 5: its CPD table"):
        g.window(range(6))
    assert not g._cpd_memo  # refused before any table was built (node 4's holds 5e7)
    labels = label_online([n.stroke for n in seed.nodes], OnlineConfig(network=cfg), fps=25.0).labels
    assert labels[3] != labels[4]


def test_window_and_link_names_still_importable_from_network():
    """The window's Bayes net and its solution moved to ``models.jorge.window``, the link
    rule to ``models.jorge.links``: the names users imported from
    ``models.jorge.network`` are the same objects, and the graph keeps its link methods."""
    from models.jorge import links, network, window

    for name in ("WindowNet", "Inference", "solve", "node_name", "restriction_name", "kept_name",
                 "colour_name"):
        assert getattr(network, name) is getattr(window, name), name
        assert name in network.__all__, name
    assert issubclass(network.LabelGraph, links.LinkRule)
    for name in ("candidate_parents", "check_links", "nested"):
        assert getattr(network.LabelGraph, name) is getattr(links.LinkRule, name), name
