"""The meeting estimate (models.jorge.estimate): pooled and per-scene figures, checked
against labelling the same scenes directly; bad input refused before anything runs."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from dbn.errors import InputError
from models.jorge.estimate import _summarise, estimate_meetings, main, mean_and_standard_error
from models.jorge.fit import meeting_strokes
from models.jorge.links import WHY_NOT_PARENT
from models.jorge.online import label_online
from models.jorge.recall import missed_link_counts, missed_links
from models.jorge.scoring import first_errors, score, true_links

R = len(WHY_NOT_PARENT)


def _direct(scenes, k, fps, oracle):
    rows = []
    for s in scenes:
        (st,) = meeting_strokes((s,), (k,), fps=fps)
        links = true_links(st.strokes) if oracle else None
        res = label_online(st, links=links)
        wrong = set(score(st, res.labels).errors)
        big = [i for i, x in enumerate(st.strokes) if len(x.truth) >= 3]
        rows.append((len(st.strokes), len(wrong), len(big), sum(i in wrong for i in big),
                     len(first_errors(st.strokes, wrong)),
                     *missed_link_counts(missed_links(st.strokes, res.labeller.graph)).values()))
    return np.array(rows)


@pytest.mark.parametrize("oracle", [False, True])
def test_estimate_pools_what_labelling_each_scene_gives(oracle):
    rows = _direct((11, 12), 3, 7.0, oracle)
    est = estimate_meetings((11, 12), sizes=(3,), fps=7.0, true_links=oracle)[3]
    assert est.scenes == 2
    assert est.strokes == rows[:, 0].sum() and est.strokes_3plus == rows[:, 2].sum()
    assert est.error == rows[:, 1].sum() / rows[:, 0].sum()
    assert est.scene_mean == pytest.approx(np.mean(rows[:, 1] / rows[:, 0]))
    assert est.first_mistakes == rows[:, 4].sum()
    assert list(est.missed_links.values()) == rows[:, 5:].sum(axis=0).tolist()
    assert est.first_mistake_missed_links.keys() == est.missed_links.keys()
    assert all(est.first_mistake_missed_links[r] <= est.missed_links[r] for r in WHY_NOT_PARENT)
    if not oracle:  # at 7 fps the gap limit misses links (module docstring of benchmarks.jorge)
        assert est.missed_links["gap"] > 0
    shares = np.array([est.first_unrepresentable, est.first_pruned, est.first_not_chosen])
    if est.first_mistakes:  # they partition the first mistakes
        assert shares.sum() == pytest.approx(1.0) and ((shares >= 0) & (shares <= 1)).all()
    else:
        assert np.isnan(shares).all()


def test_summary_of_hand_made_rows():
    rows = np.array([[10, 1, 4, 2, 1, 1, 0, 0], [20, 2, 0, 0, 1, 0, 0, 1], [30, 9, 6, 1, 2, 1, 0, 1]])
    missed = np.zeros((3, 2 * R), np.int64)
    missed[0, 0], missed[2, 0], missed[1, 2], missed[2, R] = 3, 2, 1, 1  # gap, slot; 1 gap first
    rows = np.hstack([rows, missed])
    est = _summarise(rows, above=0.35)
    assert est.missed_links == {**dict.fromkeys(WHY_NOT_PARENT, 0), "gap": 5, "slot": 1}
    assert est.first_mistake_missed_links == {**dict.fromkeys(WHY_NOT_PARENT, 0), "gap": 1}
    assert (est.strokes, est.strokes_3plus) == (60, 10)
    assert est.error == 12 / 60 and est.error_3plus == 3 / 10
    assert est.scene_mean == pytest.approx((0.1 + 0.1 + 0.3) / 3)
    assert est.scene_se == pytest.approx(np.std([0.1, 0.1, 0.3], ddof=1) / math.sqrt(3))
    # the 3+ rates only over the scenes that have 3+ strokes: 0.5 and 1/6
    assert est.scene_mean_3plus == pytest.approx((0.5 + 1 / 6) / 2)
    assert est.scenes_above == 1
    assert est.first_mistakes == 4
    assert (est.first_unrepresentable, est.first_pruned, est.first_not_chosen) == (0.5, 0.0, 0.5)
    one = _summarise(rows[:1], above=0.35)
    assert math.isnan(one.scene_se) and math.isnan(one.scene_se_3plus)
    none = _summarise(np.array([[10, 0, 4, 0, 0, 0, 0, 0] + [0] * 2 * R]), above=0.35)
    assert none.first_mistakes == 0 and math.isnan(none.first_pruned)


@pytest.mark.parametrize("kwargs", [
    {"scenes": ()},
    {"scenes": (1, 1)},
    {"scenes": (1,), "sizes": (1,)},
    {"scenes": (1,), "sizes": ()},
    {"scenes": (1,), "fps": 0.0},
    {"scenes": (1,), "fps": float("nan")},
    {"scenes": (1,), "workers": 0},
])
def test_bad_input_is_refused(kwargs):
    with pytest.raises(InputError):
        estimate_meetings(**kwargs)


def test_command_line_prints_one_json_line(capsys):
    main(["--scenes", "11", "12", "--sizes", "3", "--fps", "7"])
    out = json.loads(capsys.readouterr().out)
    assert out["3"]["scenes"] == 1 and out["fps"] == 7.0 and "SIMULATED" in out["simulated"]
    with pytest.raises(InputError):
        main(["--scenes", "12", "11"])


def test_mean_and_standard_error_by_hand() -> None:
    """Two values a, b: mean (a + b) / 2 and standard error |a - b| / 2; NaN where undefined."""
    assert mean_and_standard_error(np.array([0.1, 0.4])) == pytest.approx((0.25, 0.15))
    mean, se = mean_and_standard_error(np.array([0.3]))
    assert mean == 0.3 and math.isnan(se)
    assert all(math.isnan(v) for v in mean_and_standard_error(np.array([])))
