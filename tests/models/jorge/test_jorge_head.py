"""The first seconds of a ground truth (:func:`models.jorge.strokes.head`): a smaller size
of the same data (the jorge benchmark's ``--quick`` run labels the first minutes of its
SIMULATED-view sequence)."""

from __future__ import annotations

import numpy as np
import pytest

from dbn.errors import InputError
from models.jorge.strokes import GroundTruth, build_strokes, head


def _truth(n: int = 50) -> GroundTruth:
    boxes = np.full((n, 3, 4), np.nan)
    boxes[:, 0] = np.stack([np.arange(n, dtype=float), np.full(n, 50.0), np.full(n, 10.0), np.full(n, 20.0)], 1)
    boxes[n // 2:, 1] = [100.0, 50.0, 10.0, 20.0]  # the second person comes in half-way
    boxes[5:10, 2] = [200.0, 50.0, 10.0, 20.0]  # the third only in frames 5-9
    groups = tuple((frozenset({0}),) for _ in range(n))
    return GroundTruth("t", np.arange(100, 100 + n), np.array([3, 7, 9]), boxes, groups, 25.0)


def test_the_first_frames_and_the_people_in_them_are_kept():
    t = _truth()
    h = head(t, 0.6)  # 15 frames at 25 fps
    assert h.name == t.name and h.fps == t.fps and h.num_frames == 15
    np.testing.assert_array_equal(h.frames, t.frames[:15])
    np.testing.assert_array_equal(h.ids, [3, 9])  # 7 comes in at frame 25
    np.testing.assert_array_equal(h.boxes, t.boxes[:15][:, [0, 2]])
    assert h.groups == t.groups[:15]
    assert h.duration_s == pytest.approx(0.6)


def test_a_part_of_a_frame_rounds_up_and_more_than_the_whole_is_the_whole():
    t = _truth()
    assert head(t, 0.01).num_frames == 1
    whole = head(t, 1e6)
    np.testing.assert_array_equal(whole.boxes, t.boxes)
    np.testing.assert_array_equal(whole.ids, t.ids)


def test_its_strokes_hold_only_people_of_the_first_frames():
    t = _truth()
    s = build_strokes(0, head(t, 0.6))
    assert s.fps == 25.0
    assert set().union(*(x.truth for x in s)) == {3, 9}


@pytest.mark.parametrize("seconds", [0.0, -1.0, float("nan"), float("inf"), True, "5", None])
def test_bad_lengths_name_the_function(seconds):
    with pytest.raises(InputError, match="head: seconds"):
        head(_truth(), seconds)
