"""The benchmark's pooled recall keys (issue 16): where the right labels were lost, from
per-stroke masks whose counts we know."""

from __future__ import annotations

import numpy as np
import pytest

from benchmarks.jorge import _recall_keys, _recall_row
from models.jorge.links import WHY_NOT_PARENT
from models.jorge.recall import DomainRecall, MissedLink

T, F = True, False


def _row(sizes, admissible, kept, chosen, parents_right, first, missed=()) -> dict:
    rec = DomainRecall(*(np.array(x, bool) for x in (admissible, kept, chosen, parents_right)))
    return {"sizes": np.array(sizes), **_recall_row(rec, np.array(first, bool), list(missed))}


def test_recall_keys_condition_as_documented():
    row = _row(sizes=[1, 3, 3, 4, 3, 3], admissible=[T, T, F, T, F, T], kept=[T, F, F, T, F, T],
               chosen=[T, F, F, F, F, T], parents_right=[T, T, F, T, T, T],
               first=[F, T, F, T, T, F])
    keys = _recall_keys([row])
    assert keys["true_label_kept"] == pytest.approx(3 / 4)  # 0, 3, 5 of 0, 1, 3, 5
    assert keys["true_label_admissible_group_3plus"] == pytest.approx(3 / 5)  # 1, 3, 5 of 1-5
    assert keys["true_label_kept_group_3plus"] == pytest.approx(2 / 3)  # 3, 5 of 1, 3, 5
    assert keys["true_label_chosen_group_3plus"] == 0.5  # 5 of the kept 3, 5
    assert keys["group_3plus_wrong_parents"] == pytest.approx(1 / 5)  # 2
    assert keys["group_3plus_unrepresentable"] == pytest.approx(1 / 5)  # 4: right parents
    assert keys["first_mistakes"] == 3
    for kind in ("unrepresentable", "pruned", "not_chosen"):  # 4, 1, 3: one each
        assert keys[f"first_mistake_{kind}"] == pytest.approx(1 / 3), kind


def test_recall_keys_pool_strokes_over_rows():
    a = _row([1, 1, 1, 1], [T, T, T, T], [T, T, T, F], [T, T, T, F], [T] * 4, [F, F, F, T])
    b = _row([1, 1], [T, T], [T, T], [T, T], [T, T], [F, F])
    keys = _recall_keys([a, b])
    assert keys["true_label_kept"] == pytest.approx(5 / 6)  # not the mean of 3/4 and 1
    assert keys["first_mistakes"] == 1 and keys["first_mistake_pruned"] == 1.0
    assert np.isnan(keys["true_label_admissible_group_3plus"])  # no stroke of 3+


def test_missed_links_are_counted_by_reason_over_rows_and_at_first_mistakes():
    a = _row([1, 3, 3], [T, F, F], [T, F, F], [T, F, F], [T, T, F], [F, T, F],
             missed=[MissedLink(1, 7, 0, "gap"), MissedLink(1, 8, 0, "reach"),
                     MissedLink(2, 9, 0, "gap")])
    b = _row([2, 2], [F, T], [F, T], [F, T], [T, T], [T, F],
             missed=[MissedLink(0, 4, 0, "gap"), MissedLink(1, 5, 0, "slot")])
    keys = _recall_keys([a, b])
    assert list(keys["missed_links"]) == list(WHY_NOT_PARENT)  # every reason, zeros too
    zero = dict.fromkeys(WHY_NOT_PARENT, 0)
    assert keys["missed_links"] == {**zero, "gap": 3, "reach": 1, "slot": 1}
    # at the first mistakes only: a's stroke 1 and b's stroke 0
    assert keys["first_mistake_missed_links"] == {**zero, "gap": 2, "reach": 1}
