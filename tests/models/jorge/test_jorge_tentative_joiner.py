"""Tentative joiners (issue 16, fourteenth round): a newcomer whose birth node is not frozen
yet but whose current label is a join (born beside inherited objects) is a joiner at once,
known only with its whole birth label, as :meth:`LabelGraph.freeze` will make it. Before,
until the freeze its birth palette (the whole region's colours) counted as its own, and a
continuation labelled the newcomer alone explained the pair's colours as well as the pair."""

from __future__ import annotations

from dataclasses import replace

import pytest

from dbn.errors import InputError
from models.jorge.fit import meeting_strokes
from models.jorge.labels import birth_stroke, label_objects
from models.jorge.online import OnlineConfig, OnlineLabeller
from tests.models.jorge.test_jorge_joiner_palette import _graph

ALONE, JOINER = frozenset({0}), frozenset({1})


def test_an_unfrozen_join_makes_its_newcomer_a_joiner_until_relabelled():
    g = _graph()
    g.freeze(0, ALONE)
    g.set_tentative_joiners({1: ALONE | JOINER})
    assert g._joiners == {1: ALONE | JOINER} and g._joined == {}
    objs = label_objects([JOINER, ALONE | JOINER], 2, g._own, g._joiners)
    assert objs.known_counts.tolist() == [0, 2]  # alone unknown, with its birth label known
    g.set_tentative_joiners({1: JOINER})  # relabelled a new object alone: not a joiner
    assert g._joiners == {}
    g.set_tentative_joiners({1: ALONE | JOINER, 0: ALONE})  # frozen node 0 is skipped
    assert g._joiners == {1: ALONE | JOINER}
    for bad in ({1: JOINER, 9: JOINER}, {1: JOINER, 2: frozenset({7})}):
        with pytest.raises(InputError):  # no node 9; a label outside node 2's domain
            g.set_tentative_joiners(bad)
    assert g._joiners == {1: ALONE | JOINER}  # nothing changed


def test_freezing_replaces_the_tentative_record():
    g = _graph()
    g.freeze(0, ALONE)
    g.set_tentative_joiners({1: ALONE | JOINER})
    g.freeze(1, JOINER)  # frozen alone after all
    assert g._joiners == {} and g._joined == {}
    h = _graph()
    h.freeze(0, ALONE)
    h.set_tentative_joiners({1: ALONE | JOINER})
    h.freeze(1, ALONE | JOINER)
    assert h._joiners == h._joined == {1: ALONE | JOINER}


def _expected(lab: OnlineLabeller) -> dict:
    g = lab.graph
    out = {}
    for k, label in lab.labels.items():
        born = [o for o in label if birth_stroke(o) == k]
        if g.nodes[k].frozen is None and born and len(born) < len(label):
            out.update(dict.fromkeys(born, label))
    return {**out, **g._joined}


def test_the_online_labeller_keeps_the_joiners_of_its_current_labels():
    """On SIMULATED meetings of 3 and 4 people: after every stroke the graph's joiners are
    the frozen ones and those of the current labels of unfrozen nodes; off, only the
    frozen ones."""
    seen = 0
    for strokes in meeting_strokes(seeds=(0,), sizes=(3, 4)):
        for on in (True, False):
            lab = OnlineLabeller(replace(OnlineConfig(), tentative_joiners=on), fps=strokes.fps)
            for s in strokes:
                lab.add_stroke(s)
                want = _expected(lab) if on else lab.graph._joined
                assert lab.graph._joiners == want
                seen += on and len(want) > len(lab.graph._joined)
    assert seen > 0  # some join was tentative at some point
