"""The merge test of the link rule (issue 16, sixth round): a merged region holds both
parents' people, so two parents are linked only if the new stroke's box is at least as
large as each parent's box."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from dbn.errors import ModelError
from models.jorge.network import LabelGraph, NetworkConfig
from models.jorge.strokes import make_stroke


def _scene(new_size):
    """Two people side by side (boxes 20x50 at x=100 and x=122, touching); a new region
    starts between them, 2 frames later, with box ``new_size``."""
    return [
        make_stroke(0, 0, 10, (100, 100), (100, 100), [0, 1], {0}, size=(20, 50)),
        make_stroke(1, 0, 10, (122, 100), (122, 100), [2, 3], {1}, size=(20, 50)),
        make_stroke(2, 12, 20, (104, 100), (104, 100), [0, 1], {0}, size=new_size),
    ]


def _parents(merge_area: float, strokes) -> tuple:
    # the area test alone (the cover test, ``merge_cover``, has its own file)
    g = LabelGraph(replace(NetworkConfig(), merge_area=merge_area, merge_cover=0.0), fps=25.0)
    for st in strokes:
        g.add_stroke(st)
    return g.nodes[-1].parents


def test_a_region_the_size_of_one_person_keeps_only_its_nearest_parent():
    assert _parents(0.0, _scene((18, 48))) == (0, 1)  # without the test: a merge
    assert _parents(1.0, _scene((18, 48))) == (0,)


def test_a_region_holding_both_keeps_both_parents():
    assert _parents(1.0, _scene((42, 50))) == (0, 1)
    # at the bound (20 x 50, both parents' area) and just below it
    assert _parents(1.0, _scene((20, 50))) == (0, 1)
    assert _parents(1.0, _scene((19.9, 50))) == (0,)


def test_strokes_without_boxes_are_not_tested():
    plain = [make_stroke(s.index, s.start, s.end, s.positions[0], s.positions[-1], s.colours, s.truth)
             for s in _scene((20, 50))]
    assert _parents(1.0, plain) == _parents(0.0, plain)


@pytest.mark.parametrize("bad", [-0.5, np.nan, np.inf])
def test_merge_area_is_checked(bad):
    with pytest.raises(ModelError, match="merge_area"):
        NetworkConfig(merge_area=bad)
