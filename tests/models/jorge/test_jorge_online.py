"""On-line labelling with bounded memory, scoring and the colour-only baseline."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from dbn.errors import DBNError, InputError, ModelError, TimeOrderError
from models.jorge.api import make
from models.jorge.network import LabelGraph, NetworkConfig
from models.jorge.online import OnlineConfig, OnlineLabeller, label_online
from models.jorge.reid import reidentify
from models.jorge.scoring import (
    after_crowd,
    colour_only_labels,
    first_errors,
    group_errors,
    link_accuracy,
    object_people,
    optimal_people,
    score,
    true_predecessors,
)
from models.jorge.simulate import simulate_ground_truth
from models.jorge.strokes import StrokeSet, build_strokes, load_caviar, make_stroke

F = frozenset


def _strokes():
    return [
        make_stroke(0, 0, 10, (0, 0), (10, 0), [0, 1, 2, 3, 4], {0}),
        make_stroke(1, 0, 10, (100, 0), (110, 0), [5, 6, 7, 8, 9], {1}),
        make_stroke(2, 15, 20, (12, 0), (20, 0), [0, 1, 2, 3, 4], {0}),
        make_stroke(3, 16, 20, (112, 0), (120, 0), [5, 6, 7, 8, 9], {1}),
    ]


def test_score_by_hand():
    s = _strokes()
    assert object_people(s) == {0: 0, 1: 1, 2: None, 3: None}
    assert optimal_people(s, [F({0}), F({1}), F({0}), F({1})]) == {0: 0, 1: 1}
    good = score(s, [F({0}), F({1}), F({0}), F({1})])
    assert good.label_errors == 0 and good.id_switches == 0
    bad = score(s, [F({0}), F({1}), F({2}), F({0})], mapping="first_seen")
    assert bad.label_errors == 2 and bad.errors == (2, 3) and bad.id_switches == 2
    assert bad.error_rate == 0.5
    # the best one-to-one matching: object 0 is person 0 (2 strokes), object 1 person 1
    best = score(s, [F({0}), F({1}), F({2}), F({0})])
    assert best.errors == (2, 3)
    # an early mistake: first-seen mapping blames every later stroke, optimal only one
    late = [F({0}), F({1}), F({2}), F({1})]
    swapped = [make_stroke(4, 30, 40, (20, 0), (30, 0), [0, 1], {0})]
    assert score(s + swapped, late + [F({2})], mapping="first_seen").errors == (2, 4)
    assert score(s + swapped, late + [F({2})]).errors == (0,)
    with pytest.raises(InputError):
        score(s, [F({0}), F({1}), F({2}), F({77})])
    with pytest.raises(InputError):
        score(s, [F({0})])


def test_label_online_takes_the_stroke_sets_frame_rate_and_needs_one_for_a_list():
    strokes = build_strokes(5, simulate_ground_truth(5, num_people=3, num_frames=120))
    seven = dataclasses.replace(strokes, fps=7.0)
    assert label_online(seven).labeller.graph.fps == 7.0
    assert label_online(seven, fps=7.0).labeller.graph.fps == 7.0
    with pytest.raises(InputError, match="fps=25.0 differs from the StrokeSet's own fps=7.0"):
        label_online(seven, fps=25.0)
    # a list cut from a stroke set has lost its rate: it must be given, not assumed
    with pytest.raises(InputError, match="carries no frame rate"):
        label_online(list(seven))
    assert label_online(list(seven), fps=7.0).labels == label_online(seven).labels
    for bad in (0.0, -7.0, float("nan"), "7", True):
        with pytest.raises(InputError, match="fps must be a finite number > 0"):
            label_online(list(seven), fps=bad)
        # the streaming labeller and the registry's tracker check the rate the same way
        with pytest.raises(ModelError, match="fps must be a finite number > 0"):
            OnlineLabeller(fps=bad)
        with pytest.raises(ModelError, match="fps must be a finite number > 0"):
            make(fps=bad)
    # and none of them assumes a rate (a 7 fps sequence at an assumed 25 fps would gate
    # its links 3.6 times too wide)
    for build in (OnlineLabeller, make, LabelGraph, lambda: StrokeSet.from_strokes(list(seven))):
        with pytest.raises(DBNError, match="fps is required"):
            build()


def test_an_inference_period_shorter_than_a_frame_is_refused():
    """fps = 1e-9 (a unit mistake) made ``add_stroke`` run 1e11 periodic inferences to
    reach a stroke 100 frames on (``dbntrack track jorge`` hung); a period of at least one
    frame is what the labeller can run, and a slow frame rate with a longer period runs."""
    strokes = build_strokes(5, simulate_ground_truth(5, num_people=3, num_frames=120))
    for fps in (1e-9, 0.5):
        with pytest.raises(ModelError, match=r"period_s x fps = 1 s x .* frames: the inference"):
            OnlineLabeller(fps=fps)
        with pytest.raises(ModelError, match="at least one frame"):
            label_online(dataclasses.replace(strokes, fps=fps))
    slow = dataclasses.replace(strokes, fps=0.5)
    res = label_online(slow, OnlineConfig(period_s=2.0))
    assert res.labeller.periodic_inferences >= 1 and len(res.labels) == len(strokes)


def test_colour_only_and_network_on_an_easy_case():
    s = _strokes()
    assert colour_only_labels(s) == [F({0}), F({1}), F({0}), F({1})]
    res = label_online(s, fps=25.0)
    assert res.labels == [F({0}), F({1}), F({0}), F({1})]


def test_bounded_memory_on_a_long_simulated_sequence():
    truth = simulate_ground_truth(5, num_people=8, num_frames=1200)
    strokes = build_strokes(5, truth)
    cfg = OnlineConfig(max_active=8, max_labels=6, period_s=1.0)
    res = label_online(strokes, cfg)
    g = res.labeller.graph
    assert len(res.labels) == len(strokes)
    assert all(r.num_active <= 8 for r in res.records)
    assert all(r.max_domain <= 6 for r in res.records)
    # inside the bound: every clique has at most (6 labels) ** (largest family) entries
    assert max(r.max_clique_entries for r in res.records) <= 6 ** 4
    frozen = [k for k, n in enumerate(g.nodes) if n.frozen is not None]
    assert len(frozen) >= len(strokes) - 8
    for k, n in enumerate(g.nodes):
        assert res.network_labels[k] in g.current_domain(k) or res.network_labels[k] == n.frozen
    # same input, same result
    again = label_online(strokes, cfg)
    assert again.labels == res.labels


def test_rejected_stroke_leaves_labeller_unchanged():
    lab = OnlineLabeller(fps=25.0)
    for s in _strokes():
        lab.add_stroke(s)
    before = (dict(lab.labels), len(lab.graph), len(lab.records))
    with pytest.raises(TimeOrderError):
        lab.add_stroke(make_stroke(4, 5, 30, (0, 0), (1, 1), [1, 2]))
    with pytest.raises(InputError):
        lab.add_stroke(make_stroke(7, 50, 60, (0, 0), (1, 1), [1, 2]))
    assert (dict(lab.labels), len(lab.graph), len(lab.records)) == before


def test_real_sequence_runs_on_line(shared_data):
    """Accuracy is measured (and reported) by ``benchmarks/jorge.py``; here: it runs,
    every label is admissible, and faster than real time."""
    truth = load_caviar(shared_data / "caviar" / "ms3ggt.xml.gz")
    st = build_strokes(0, truth)
    res = label_online(st)
    sc = score(st, res.labels)
    assert sc.num_strokes == len(st) and 0 <= sc.label_errors <= len(st)
    assert res.seconds < truth.duration_s
    assert np.isfinite([r.log_prob for r in res.records]).all()


def test_reidentification_pass():
    """An object lost to a missed link is found again by its colours; a look-alike that
    coexists with it, or one with other colours, is not."""
    far = [
        make_stroke(0, 0, 10, (0, 0), (10, 0), [0, 1, 2, 3, 4], {0}),
        make_stroke(1, 200, 210, (300, 200), (310, 200), [0, 1, 2, 3, 4], {0}),
        make_stroke(2, 205, 215, (100, 250), (110, 250), [5, 6, 7, 8, 9], {1}),
    ]
    off = label_online(far, OnlineConfig(reid_prior=0.0), fps=25.0)
    assert off.labels == off.network_labels == [F({0}), F({1}), F({2})]
    on = label_online(far, OnlineConfig(reid_prior=0.5), fps=25.0)
    assert on.network_labels == off.network_labels
    # stroke 1 is object 0 again; stroke 2 (other colours, and coexisting with 1) is not
    assert on.labels == [F({0}), F({0}), F({2})]
    assert score(far, on.labels).label_errors == 0
    assert score(far, off.labels).label_errors == 1
    # two look-alikes at the same time are never merged
    both = [
        make_stroke(0, 0, 10, (0, 0), (10, 0), [0, 1, 2, 3, 4], {0}),
        make_stroke(1, 5, 15, (300, 200), (310, 200), [0, 1, 2, 3, 4], {1}),
    ]
    assert label_online(both, OnlineConfig(reid_prior=0.5), fps=25.0).labels == [F({0}), F({1})]
    with pytest.raises(InputError):
        reidentify(on.labeller.graph, on.network_labels[:2], 0.5)
    with pytest.raises(InputError):
        reidentify(on.labeller.graph, on.network_labels, 1.0)


def _joined_graph(alone_colours):
    """A (colours 0-4) is lost after frame 10; B (5-9) walks on; a region of B and a
    newcomer starts at frame 20 (linked to B only: A's link was missed), then splits into
    the newcomer alone (``alone_colours``) and B alone."""
    g = LabelGraph(NetworkConfig(), with_domains=False, fps=25.0)
    for stroke, parents in [
        (make_stroke(0, 0, 10, (0, 0), (10, 0), [0, 1, 2, 3, 4], {0}), ()),
        (make_stroke(1, 0, 10, (300, 0), (310, 0), [5, 6, 7, 8, 9], {1}), ()),
        (make_stroke(2, 20, 30, (310, 0), (320, 0), [0, 1, 2, 5, 6, 7], {0, 1}), (1,)),
        (make_stroke(3, 31, 40, (320, 0), (330, 0), alone_colours, {0}), (2,)),
        (make_stroke(4, 31, 40, (340, 0), (350, 0), [5, 6, 7, 8, 9], {1}), (2,)),
    ]:
        g.add_stroke(stroke, parents)
    return g


def test_reidentification_of_a_newcomer_who_joined_a_group():
    """An object born inside a group (a join) is an earlier object seen again when its
    first stroke alone has that object's colours; with other colours it stays new."""
    labels = [F({0}), F({1}), F({1, 2}), F({2}), F({1})]
    same = reidentify(_joined_graph([0, 1, 2, 3, 4]), labels, 0.5)
    assert same == [F({0}), F({1}), F({0, 1}), F({0}), F({1})]
    other = reidentify(_joined_graph([8, 9, 10, 11]), labels, 0.5)
    assert other == labels


def test_first_errors_by_hand():
    s = _strokes() + [make_stroke(4, 30, 40, (20, 0), (30, 0), [0, 1], {0}),
                      make_stroke(5, 30, 40, (120, 0), (130, 0), [5, 6], {1})]
    # person 0: strokes 0, 2, 4; person 1: strokes 1, 3, 5
    assert first_errors(s, [2, 4, 5]) == (2, 5)  # 4 inherits from 2; 5's predecessor 3 is right
    assert first_errors(s, [4]) == (4,)
    assert first_errors(s, []) == ()
    with pytest.raises(InputError):
        first_errors(s, [6])


def test_group_errors_by_hand():
    s = [make_stroke(0, 0, 10, (0, 0), (1, 0), [0, 1], {0, 1, 2}),
         make_stroke(1, 0, 20, (50, 0), (51, 0), [0, 1], {7, 8}),
         make_stroke(2, 12, 20, (0, 0), (1, 0), [0, 1], {0, 3, 4, 5}),
         make_stroke(3, 12, 20, (9, 0), (9, 0), [0, 1], {6})]
    assert group_errors(s, [0, 1, 3]) == (1, 2)  # strokes 0 and 2 hold 3+; 0 is wrong
    assert group_errors(s, [1, 3]) == (0, 2)
    assert group_errors(s, [1, 2], min_people=2) == (2, 3)
    assert group_errors(s, [2], min_people=4) == (1, 1)
    assert group_errors(s[1:2], [1]) == (0, 0)


def test_after_crowd_by_hand():
    s = [make_stroke(0, 0, 10, (0, 0), (1, 0), [0, 1], {0, 1, 2}),
         make_stroke(1, 0, 20, (50, 0), (51, 0), [0, 1], {7, 8}),
         make_stroke(2, 12, 20, (0, 0), (1, 0), [0, 1], {0, 3}),   # person 0 was in the crowd 0
         make_stroke(3, 12, 20, (9, 0), (9, 0), [0, 1], {4, 5}),   # never
         make_stroke(4, 10, 20, (5, 0), (5, 0), [0, 1], {2, 6}),   # the crowd ends at 10, not before
         make_stroke(5, 25, 30, (5, 0), (5, 0), [0, 1], {2, 7})]   # person 2, later
    assert after_crowd(s, 2).tolist() == [False, False, True, False, False, True]
    assert not after_crowd(s, 3).any()  # no stroke of more than three people
    with pytest.raises(InputError, match="max_group_size"):
        after_crowd(s, 0)


def test_link_accuracy_by_hand():
    s = _strokes() + [make_stroke(4, 30, 40, (20, 0), (30, 0), [0, 1], {0, 1})]
    # true predecessors: none, none, 0, 1, and 4's people were last in 2 and 3
    assert true_predecessors(s) == [F(), F(), F({0}), F({1}), F({2, 3})]
    assert link_accuracy(s, [(), (), (0,), (1,), (2, 3)]) == 1.0
    assert link_accuracy(s, [(), (), (1,), (1,), (2,)]) == pytest.approx(3 / 5)
    with pytest.raises(InputError):
        link_accuracy(s, [()])


def test_scoring_and_reid_names_still_importable_from_online():
    """The scoring helpers and the re-identification pass moved to their own modules; the
    names users imported from ``models.jorge.online`` are the same objects."""
    from models.jorge import online, reid, scoring

    moved = ("Score", "after_crowd", "colour_only_labels", "first_errors", "link_accuracy",
             "object_people", "optimal_people", "score", "true_links", "true_predecessors")
    for name in moved:  # scoring's later names (stands_for) never lived in online
        assert name in scoring.__all__, name
        assert getattr(online, name) is getattr(scoring, name), name
        assert name in online.__all__, name
    assert online.reidentify is reid.reidentify
