"""The box link gate (issue 16): a new stroke links to an earlier one only if its first
region box meets the earlier last box grown by the motion allowance, so a neighbour in a
crowd is not taken for a parent while split parts and merges still are."""

from __future__ import annotations

from dataclasses import replace

import pytest

from dbn.errors import ModelError
from models.jorge.network import LabelGraph, NetworkConfig
from models.jorge.strokes import make_stroke


def _crowd(with_sizes: bool = True):
    """A pair (stroke 0, box y 75..125) next to a third person (stroke 1, y 135..185);
    one of the pair comes out (stroke 2, inside the pair's box) and the third person walks
    on (stroke 3, 60 px below the pair's centre)."""

    def s(k, start, end, pos, size, truth):
        return make_stroke(
            k, start, end, pos, pos, [0, 1, 2], truth, size=size if with_sizes else None
        )

    return [
        s(0, 0, 10, (100, 100), (60, 50), {0, 1}),
        s(1, 0, 10, (100, 160), (20, 50), {2}),
        s(2, 12, 20, (80, 100), (20, 50), {0}),
        s(3, 12, 20, (100, 160), (20, 50), {2}),
    ]


def _parents(gate: str, strokes) -> list[tuple]:
    # the gate alone: without the merge test, which would also drop the spurious merge
    g = LabelGraph(replace(NetworkConfig(), gate=gate, merge_area=0.0, merge_cover=0.0), fps=25.0)
    for st in strokes:
        g.add_stroke(st)
    return [g.nodes[k].parents for k in range(len(strokes))]


def test_box_gate_drops_the_neighbour_the_centre_gate_takes():
    scaled = _parents("scaled", _crowd())
    boxes = _parents("boxes", _crowd())
    assert scaled[3] == (0, 1)  # the pair's centre is within 1.2 region sizes: spurious
    assert boxes[3] == (1,)
    assert scaled[2] == boxes[2] == (0,)  # the part inside the pair's box


def test_box_gate_without_boxes_is_the_scaled_gate():
    assert _parents("boxes", _crowd(False)) == _parents("scaled", _crowd(False))


def test_box_gate_settings_are_checked():
    with pytest.raises(ModelError):
        NetworkConfig(v_box=-1.0)
    with pytest.raises(ModelError):
        NetworkConfig(gate="box")
