"""The ground truth at a lower frame rate (:func:`models.jorge.strokes.resample`): the
frames nearest to ``i / fps``, renumbered, boxes unchanged (issue 16, thirty-first round:
SIMULATED meetings at PETS2009's 7 fps)."""

from __future__ import annotations

import numpy as np
import pytest

from dbn.errors import InputError
from models.jorge.meeting import simulate_meeting
from models.jorge.strokes import GroundTruth, build_strokes, resample


def _truth(n: int = 25) -> GroundTruth:
    boxes = np.full((n, 2, 4), np.nan)
    boxes[:, 0] = np.stack([np.arange(n, dtype=float), np.full(n, 50.0), np.full(n, 10.0), np.full(n, 20.0)], 1)
    boxes[n // 2:, 1] = [100.0, 50.0, 10.0, 20.0]  # the second person comes in half-way
    groups = tuple((frozenset({0}),) for _ in range(n))
    return GroundTruth("t", np.arange(100, 100 + n), np.array([3, 7]), boxes, groups, 25.0)


def test_the_frames_nearest_each_new_time_are_kept_and_renumbered():
    t = _truth()
    r = resample(t, 7.0)
    kept = np.round(np.arange(0, 25, 25 / 7)).astype(int)  # 0, 4, 7, 11, 14, 18, 21
    assert r.fps == 7.0 and r.name == t.name
    np.testing.assert_array_equal(r.frames, np.arange(kept.size))
    np.testing.assert_array_equal(r.ids, t.ids)
    np.testing.assert_array_equal(r.boxes, t.boxes[kept])
    assert r.groups == tuple(t.groups[i] for i in kept)
    assert r.duration_s == pytest.approx(t.duration_s, abs=1 / 7)


def test_the_same_rate_is_the_same_ground_truth():
    t = _truth()
    r = resample(t, 25.0)
    np.testing.assert_array_equal(r.boxes, t.boxes)
    np.testing.assert_array_equal(r.frames, np.arange(t.num_frames))


@pytest.mark.parametrize("fps", [0.0, -7.0, float("nan"), float("inf"), True, "7", None, 30.0])
def test_bad_rates_name_the_function(fps):
    with pytest.raises(InputError, match="resample"):
        resample(_truth(), fps)


def test_a_meeting_at_seven_frames_per_second_has_the_same_people_in_fewer_frames():
    t = simulate_meeting(0, 3)
    r = resample(t, 7.0)
    assert r.num_frames == pytest.approx(t.num_frames * 7 / 25, abs=1)
    s = build_strokes(0, r)
    assert s.fps == 7.0
    assert set().union(*(x.truth for x in s)) <= set(t.ids.tolist())
