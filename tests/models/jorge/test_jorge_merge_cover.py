"""The cover test of the link rule's merge test (issue 16, fifteenth round): a merged
region covers both its parts, so two parents are linked only if the new stroke's first
box covers at least ``merge_cover`` of each parent's last box (grown by the box gate's
slack); a neighbour that only touches the region is not a parent."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dbn.errors import ModelError
from models.jorge.network import LabelGraph, NetworkConfig
from models.jorge.strokes import make_stroke


def _scene(new_x: float, new_size=(44, 50)):
    """Two people side by side (boxes 20x50 centred at x=100 and x=122); a region of two
    people's size starts 2 frames after both end, centred at ``new_x``."""
    return [
        make_stroke(0, 0, 10, (100, 100), (100, 100), [0, 1], {0}, size=(20, 50)),
        make_stroke(1, 0, 10, (122, 100), (122, 100), [2, 3], {1}, size=(20, 50)),
        make_stroke(2, 12, 20, (new_x, 100), (new_x, 100), [0, 1], {0}, size=new_size),
    ]


def _graph(merge_cover: float, strokes) -> LabelGraph:
    g = LabelGraph(replace(NetworkConfig(), merge_cover=merge_cover), fps=25.0)
    for s in strokes:
        g.add_stroke(s)
    return g


def _slack(g: LabelGraph, j: int, new) -> float:
    cfg = g.config
    return g._scale[j] * cfg.v_box * (new.start - g.nodes[j].stroke.end) / g.fps


def test_a_region_holding_both_keeps_both_parents():
    assert _graph(0.2, _scene(111)).nodes[-1].parents == (0, 1)


def test_a_region_that_only_touches_a_neighbour_keeps_its_nearest_parent():
    # wide enough for the area test, covering person 0, meeting person 1's box at its edge
    scene = _scene(90)
    assert _graph(0.0, scene).nodes[-1].parents == (0, 1)  # the area test alone: a merge
    assert _graph(0.2, scene).nodes[-1].parents == (0,)
    # the cover test holds without the area test too
    g = LabelGraph(replace(NetworkConfig(), merge_area=0.0, merge_cover=0.2), fps=25.0)
    for s in scene:
        g.add_stroke(s)
    assert g.nodes[-1].parents == (0,)


def test_cover_is_the_overlap_share_of_the_grown_parent_box():
    scene = _scene(90)
    g = _graph(0.0, scene[:2])
    new = scene[2]
    got = g._cover(new, np.array([0, 1]))
    want = []
    for j, x in ((0, 100.0), (1, 122.0)):
        s = _slack(g, j, new)
        px = (x - 10 - s, x + 10 + s)
        py = (75 - s, 125 + s)
        ox = max(0.0, min(112.0, px[1]) - max(68.0, px[0]))
        oy = max(0.0, min(125.0, py[1]) - max(75.0, py[0]))
        want.append(ox * oy / ((px[1] - px[0]) * (py[1] - py[0])))
    np.testing.assert_allclose(got, want, rtol=1e-12)
    assert got[0] > 0.8 and got[1] < 0.2


@settings(max_examples=40, deadline=None)
@given(x=st.floats(80, 140), w=st.floats(20, 80), cover=st.floats(0.01, 1.0))
def test_the_test_keeps_a_merge_iff_both_parents_are_covered(x, w, cover):
    scene = _scene(x, (w, 50))
    g = _graph(0.0, scene[:2])
    both = g.candidate_parents(scene[2]).tolist()
    shares = g._cover(scene[2], np.array(sorted(both))) if len(both) == 2 else None
    got = _graph(cover, scene).nodes[-1].parents
    if len(both) < 2:
        assert len(got) == len(both)
    elif bool(np.all(shares >= cover)):
        assert set(got) == set(both)
    else:
        assert got == (both[0],)  # the nearest


def test_strokes_without_boxes_are_not_tested():
    plain = [make_stroke(s.index, s.start, s.end, s.positions[0], s.positions[-1], s.colours, s.truth)
             for s in _scene(90)]
    assert _graph(0.9, plain).nodes[-1].parents == _graph(0.0, plain).nodes[-1].parents


@pytest.mark.parametrize("bad", [-0.1, 1.5, np.nan])
def test_merge_cover_is_checked(bad):
    with pytest.raises(ModelError, match="merge_cover"):
        NetworkConfig(merge_cover=bad)
