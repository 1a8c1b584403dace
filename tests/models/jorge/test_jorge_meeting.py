"""SIMULATED CAVIAR-like meetings (models/jorge/meeting.py, issue 16): the scene holds one
group of k people, and the default pipeline (build_strokes, label_online with the fitted
defaults, score) labels its strokes, groups of three and four included, within the error
measured over ten scenes (benchmark key ``error_rate_meeting_sim``)."""

from __future__ import annotations

import numpy as np
import pytest

from dbn.errors import InputError
from models.jorge.meeting import simulate_meeting
from models.jorge.online import OnlineConfig, label_online, score
from models.jorge.strokes import build_strokes, regions


@pytest.mark.parametrize("k", [3, 4, 5])
def test_the_members_gather_into_one_region_and_leave(k):
    truth = simulate_meeting(0, k)
    assert truth.boxes.shape[1] == k + 2 and truth.fps == 25.0
    same = regions(truth.boxes, 0.05)
    together = same[:, 0, :k].all(axis=1)
    assert together.any()  # at some frame all k members are one region
    frames = np.flatnonzero(together)
    visible = ~np.isnan(truth.boxes[..., 0])
    assert visible[: frames[0], :k].any(axis=0).sum() >= k - 1  # they arrive, not born together
    assert not visible[-1, :k].any()  # and all leave before the end
    gathered = [f for f, gs in enumerate(truth.groups) if gs == (frozenset(range(k)),)]
    # while all have arrived they are one region, but for brief breaks (box sizes vary)
    assert gathered and together[gathered].mean() > 0.8
    lo = truth.boxes[..., :2] - truth.boxes[..., 2:] / 2
    hi = truth.boxes[..., :2] + truth.boxes[..., 2:] / 2
    inside = (hi[..., 0] > 0) & (lo[..., 0] < 384) & (hi[..., 1] > 0) & (lo[..., 1] < 288)
    assert inside[visible].all()


def test_same_seed_same_scene_and_bad_input():
    a, b = simulate_meeting(3, 4), simulate_meeting(3, 4)
    np.testing.assert_array_equal(a.boxes, b.boxes)
    assert not np.array_equal(a.boxes, simulate_meeting(4, 4).boxes, equal_nan=True)
    with pytest.raises(InputError, match="group_size"):
        simulate_meeting(0, 1)
    with pytest.raises(InputError, match="num_frames"):
        simulate_meeting(0, 3, num_frames=5)


def _errors(k: int, scenes) -> tuple[float, float, int]:
    """Pooled LE / NT over all strokes and over strokes of 3+ people, and the 3+ count."""
    wrong = total = wrong3 = total3 = 0
    for i in scenes:
        strokes = build_strokes([0, i], simulate_meeting(i, k))
        sc = score(strokes, label_online(strokes, OnlineConfig()).labels)
        big = {s.index for s in strokes if len(s.truth) >= 3}
        wrong, total = wrong + sc.label_errors, total + sc.num_strokes
        wrong3, total3 = wrong3 + len(big & set(sc.errors)), total3 + len(big)
    return wrong / total, wrong3 / max(total3, 1), total3


@pytest.mark.parametrize("k", [3, 4])
def test_a_simulated_meeting_is_labelled_within_the_users_overall_bar(k):
    """Scene 0 of each size (the first, not chosen): the whole default pipeline stays within
    the users' overall bar of 0.20 (measured 0.012 for k = 3, 0.172 for k = 4). Its strokes
    of 3+ people: 0 of 7 wrong for k = 3, but 13 of 15 for k = 4 (a brief break of the
    group lets a new object in, which then stays: benchmarks/jorge.py); the 3+ bar is
    checked pooled over ten scenes in the slow test below."""
    rate, rate3, n3 = _errors(k, [0])
    assert n3 >= 5  # the group of k is seen as one region in several strokes
    assert rate <= 0.20


@pytest.mark.slow
def test_ten_simulated_meetings_of_3_and_4_people():
    """Pooled over scenes 0-9 (stroke seeds [0, i]) the default pipeline was measured at
    0.120 (k = 3) and 0.144 (k = 4) over all strokes, 0.27 and 0.44 over strokes of three
    or more people; with stroke seeds 0-4 (the full benchmark, ``error_rate_meeting_sim``)
    0.134 / 0.156 and 0.37 / 0.52: within the users' 0.20 overall, not their 0.35 on 3+
    strokes. Bars: the seed-0 figures plus 0.05 (a regression check, not the users' bar)."""
    for k, (bar, bar3) in {3: (0.17, 0.33), 4: (0.20, 0.49)}.items():
        rate, rate3, n3 = _errors(k, range(10))
        assert n3 >= 50
        assert rate <= bar, (k, rate)
        assert rate3 <= bar3, (k, rate3)
