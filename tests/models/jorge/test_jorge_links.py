"""Links given to the labeller instead of the on-line link rule (a low-level tracker's
merges and splits, or the true predecessors as an oracle)."""

from __future__ import annotations

import pytest

from dbn.errors import InputError
from models.jorge.online import OnlineLabeller, label_online
from models.jorge.scoring import link_accuracy, true_links
from models.jorge.strokes import make_stroke


def _crossing():
    """Person 0 (palette 0-4) ends at x=10, person 1 (palette 5-9) at x=100; person 0
    reappears at x=100, next to where person 1 ended, and person 1 at x=10."""
    return [
        make_stroke(0, 0, 10, (0, 0), (10, 0), [0, 1, 2, 3, 4], {0}),
        make_stroke(1, 0, 10, (90, 0), (100, 0), [5, 6, 7, 8, 9], {1}),
        make_stroke(2, 12, 20, (100, 0), (110, 0), [0, 1, 2, 3, 4], {0}),
        make_stroke(3, 13, 20, (10, 0), (20, 0), [5, 6, 7, 8, 9], {1}),
    ]


def test_true_links_keep_the_networks_limits():
    s = [make_stroke(i, 0, 5 + i, (10 * i, 0), (10 * i, 0), [i], {i}) for i in range(3)]
    # all three people meet: three true predecessors, the two latest-ending are kept
    s.append(make_stroke(3, 20, 30, (10, 0), (10, 0), [0, 1, 2], {0, 1, 2}))
    # the group parts three ways: stroke 3 has room for two children, first come
    s += [make_stroke(4 + i, 40 + i, 50, (10 * i, 0), (10 * i, 0), [i], {i}) for i in range(3)]
    assert true_links(s) == [(), (), (), (1, 2), (3,), (3,), ()]
    assert true_links(s, max_parents=1, max_children=1) == [(), (), (), (2,), (3,), (), ()]


def test_given_links_replace_the_link_rule():
    s = _crossing()
    by_rule = label_online(s, fps=25.0)
    assert [tuple(n.parents) for n in by_rule.labeller.graph.nodes][2:] == [(1,), (0,)]
    given = label_online(s, fps=25.0, links=true_links(s))
    parents = [tuple(n.parents) for n in given.labeller.graph.nodes]
    assert parents == [(), (), (0,), (1,)]
    assert link_accuracy(s, parents) == 1.0
    # with the true links the people keep their objects
    assert given.labels[2] == given.labels[0] and given.labels[3] == given.labels[1]


@pytest.mark.parametrize("parents", [(4,), (1, 1), (0, 1, 2), (-1,), (3,), ("a",), 3])
def test_bad_links_are_rejected_before_any_change(parents):
    s = _crossing()
    lab = OnlineLabeller(fps=25.0)
    for st in s[:2]:
        lab.add_stroke(st)
    lab.add_stroke(make_stroke(2, 11, 12, (10, 0), (10, 0), [0, 1, 2], {0}), (0,))
    lab.add_stroke(make_stroke(3, 11, 12, (10, 0), (10, 0), [0, 1, 2], {0}), (0,))
    before = (dict(lab.labels), len(lab.graph), len(lab.records),
              [tuple(n.children) for n in lab.graph.nodes])
    # (4,): not earlier; (1, 1): repeated; three: too many; (-1,): no such stroke;
    # (3,): stroke 3 ends at frame 12, the new one starts at 12; ("a",), 3: not indices;
    # and (0,) below: stroke 0 already has two children
    nxt = make_stroke(4, 12, 30, (0, 0), (1, 1), [1, 2])
    with pytest.raises(InputError, match="stroke 4"):
        lab.add_stroke(nxt, parents)
    with pytest.raises(InputError, match="max_children"):
        lab.add_stroke(make_stroke(4, 40, 50, (0, 0), (1, 1), [1, 2]), (0,))
    assert (dict(lab.labels), len(lab.graph), len(lab.records),
            [tuple(n.children) for n in lab.graph.nodes]) == before


def test_label_online_needs_one_link_set_per_stroke():
    with pytest.raises(InputError, match="3 link sets for 4 strokes"):
        label_online(_crossing(), fps=25.0, links=[(), (), (0,)])


def test_the_protocol_takes_links_and_rejects_bad_ones_before_any_change():
    import jax

    from models.jorge.api import LinkedStroke, make

    s = _crossing()
    links = true_links(s)
    tracker = make(fps=25.0)
    state = tracker.init(jax.random.key(0))
    for st, parents in zip(s, links):
        state, info = tracker.step(jax.random.key(0), state, LinkedStroke(st, parents))
    assert [tuple(n.parents) for n in state.labeller.graph.nodes] == [(), (), (0,), (1,)]
    assert info.label == tuple(sorted(state.labeller.labels[1]))
    assert [state.labeller.labels[k] for k in range(4)] == label_online(s, fps=25.0, links=links).labels
    before = tracker.fingerprint(state)
    with pytest.raises(InputError, match="stroke 4"):
        tracker.step(jax.random.key(0), state, LinkedStroke(make_stroke(4, 30, 40, (0, 0), (1, 1), [1]), (9,)))
    assert repr(tracker.fingerprint(state)) == repr(before)
