"""models.jorge.recordings: a ground truth is told to be (a cut of) another recording by its
boxes, not its name."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dbn.errors import InputError
from models.jorge.recordings import same_recording, shared_boxes
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


def _boxes(truth: GroundTruth) -> int:
    return int(np.isfinite(truth.boxes[..., 0]).sum())


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 10**6), lo=st.integers(0, 29), span=st.integers(1, 30),
       ids=st.sets(st.integers(0, 3), min_size=1))
def test_a_cut_is_all_of_the_recording_and_the_recording_its_share(seed, lo, span, ids):
    full = _truth(seed)
    cut = _cut(full, lo, lo + span, sorted(ids))
    if _boxes(cut) == 0:
        assert shared_boxes(cut, full) == 0.0
        return
    assert shared_boxes(cut, full) == 1.0
    assert shared_boxes(full, cut) == pytest.approx(_boxes(cut) / _boxes(full))


def test_boxes_are_compared_by_frame_number_id_and_position():
    full = _truth(0)
    moved = GroundTruth("moved", full.frames, full.ids, full.boxes + 2.0)
    assert shared_boxes(moved, full) == 0.0  # 2 pixels off
    assert shared_boxes(moved, full, tol=2.0) == 1.0
    later = GroundTruth("later", full.frames + 1000, full.ids, full.boxes)
    assert shared_boxes(later, full) == 0.0  # other frames
    renamed = GroundTruth("renamed", full.frames, full.ids + 10, full.boxes)
    assert shared_boxes(renamed, full) == 0.0  # other people
    half = full.boxes.copy()
    half[:, :2] += 50.0  # two of four people moved in every frame
    part = GroundTruth("part", full.frames, full.ids, half)
    expected = _boxes(_cut(full, 0, 30, [2, 3])) / _boxes(full)
    assert shared_boxes(part, full) == pytest.approx(expected)


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
