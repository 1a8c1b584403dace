"""models.jorge.recordings: a ground truth is told to be (a cut of) another recording by its
boxes, not its name."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dbn.errors import InputError
from models.jorge.recordings import frame_offset, same_recording, shared_boxes
from models.jorge.strokes import GroundTruth


def _truth(seed: int, frames: int = 30, people: int = 4, first: int = 0) -> GroundTruth:
    """Random boxes, each person absent in some frames (NaN)."""
    rng = np.random.default_rng(seed)
    boxes = rng.uniform(10, 300, size=(frames, people, 4))
    boxes[rng.random((frames, people)) < 0.3] = np.nan
    return GroundTruth("t", np.arange(first, first + frames), np.arange(people), boxes)


def _cut(truth: GroundTruth, lo: int, hi: int, ids=None) -> GroundTruth:
    """Frames ``lo:hi`` (positions) and the persons at positions ``ids`` (default all)."""
    ids = np.arange(truth.ids.size) if ids is None else np.asarray(ids)
    return GroundTruth("cut", truth.frames[lo:hi], truth.ids[ids], truth.boxes[lo:hi][:, ids])


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 10**6), lo=st.integers(0, 29), span=st.integers(1, 30),
       ids=st.sets(st.integers(0, 3), min_size=1))
def test_a_cut_is_all_of_the_recording_and_the_recording_its_share(seed, lo, span, ids):
    full = _truth(seed)
    cut = _cut(full, lo, lo + span, sorted(ids))
    if cut.num_boxes == 0:
        assert shared_boxes(cut, full) == 0.0
        return
    assert shared_boxes(cut, full) == 1.0
    assert shared_boxes(full, cut) == pytest.approx(cut.num_boxes / full.num_boxes)


def test_boxes_are_compared_by_position_whatever_the_frame_numbers_and_ids():
    full = _truth(0)
    moved = GroundTruth("moved", full.frames, full.ids, full.boxes + 2.0)
    assert shared_boxes(moved, full) == 0.0  # 2 pixels off
    assert shared_boxes(moved, full, tol=2.0) == 1.0
    later = GroundTruth("later", full.frames + 1000, full.ids, full.boxes)
    assert frame_offset(later, full) == -1000
    assert shared_boxes(later, full) == 1.0  # renumbered frames
    assert shared_boxes(full, later) == 1.0
    renamed = GroundTruth("renamed", full.frames, full.ids[::-1] + 10, full.boxes[:, ::-1])
    assert shared_boxes(renamed, full) == 1.0  # renumbered people
    half = full.boxes.copy()
    half[:, :2] += 50.0  # two of four people moved in every frame
    part = GroundTruth("part", full.frames, full.ids, half)
    expected = _cut(full, 0, 30, [2, 3]).num_boxes / full.num_boxes
    assert shared_boxes(part, full) == pytest.approx(expected)
    assert shared_boxes(_truth(1), full) == 0.0  # another recording
    assert frame_offset(_truth(1), full) is None


def test_a_motchallenge_conversion_is_the_same_recording():
    """MOTChallenge's convention: frames from 1 (PETS2009's XML: from 0), its own ids, the
    corners rounded to whole pixels; read back, every box is within a pixel of its own."""
    full = _truth(3, frames=60, people=6)
    xc, yc, w, h = np.moveaxis(full.boxes, -1, 0)
    corner = np.stack([np.round(xc - w / 2) + w / 2, np.round(yc - h / 2) + h / 2, w, h], -1)
    mot = GroundTruth("gt", full.frames + 1, np.arange(6)[::-1] + 1, corner)
    assert frame_offset(mot, full) == -1
    assert shared_boxes(mot, full) == 1.0
    assert same_recording(mot, {"other": _truth(4), "full": full}) == "full"


def test_the_frame_offset_is_the_one_the_moving_boxes_vote_for():
    """A person standing still matches at every shift; the walking one at the true shift."""
    frames = np.arange(40)
    still = np.tile([[100.0, 100.0, 20.0, 50.0]], (40, 1))
    walk = np.stack([10.0 + 3 * frames, 200 + 0 * frames, 20 + 0 * frames, 50 + 0 * frames], 1)
    full = GroundTruth("f", frames, np.arange(2), np.stack([still, walk], 1))
    cut = GroundTruth("c", frames[5:30] + 70, np.arange(2), full.boxes[5:30])
    assert frame_offset(cut, full) == -70
    assert shared_boxes(cut, full) == 1.0
    only_still = GroundTruth("s", frames + 7, np.arange(1), full.boxes[:, :1])
    assert frame_offset(only_still, full) == -7  # the shift lining up the most frames
    one = GroundTruth("one", [500], [0], full.boxes[:1, :1])
    assert frame_offset(one, full) == -461  # ties: the smallest |shift|
    a0, a1, nan = [1.0, 2, 3, 4], [9.0, 8, 7, 6], [np.nan] * 4
    two = GroundTruth("two", [0, 1], [0], [[a0], [a1]])
    twins = GroundTruth("twins", [10, 20, 21], [0, 1], [[a0, a0], [a0, nan], [a1, nan]])
    assert frame_offset(two, twins) == 20  # a box votes once per shift, twins or not


def test_same_recording_names_the_first_recording_holding_enough_of_the_boxes():
    a, b = _truth(1), _truth(2)
    cut = _cut(b, 10, 20)
    assert same_recording(cut, {"a": a, "b": b}) == "b"
    assert same_recording(cut, {"a": a}) is None
    assert same_recording(b, {"cut": cut}) is None  # a third of b's boxes
    assert same_recording(b, {"cut": cut}, share=0.3) == "cut"
    assert same_recording(a, {}) is None
    for bad in (0.0, 1.5, float("nan")):
        with pytest.raises(InputError, match="share"):
            same_recording(a, {"a": a}, share=bad)
    with pytest.raises(InputError, match="tol"):
        same_recording(a, {"a": a}, tol=-1.0)
