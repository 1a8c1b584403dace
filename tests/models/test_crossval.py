"""K-fold cross-validation over files (``models.crossval``): folds, no leak, the choice."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dbn.errors import InputError
from models.crossval import cross_validate, fold_blocks, group_keys


@given(n=st.integers(2, 30), data=st.data())
@settings(max_examples=60, deadline=None)
def test_folds_are_contiguous_blocks_of_near_equal_size(n, data):
    k = data.draw(st.integers(2, n))
    items = [f"file{i}" for i in range(n)]
    folds = fold_blocks(items, k)
    assert len(folds) == k and [x for f in folds for x in f] == items
    sizes = [len(f) for f in folds]
    assert max(sizes) - min(sizes) <= 1 and sizes == sorted(sizes, reverse=True)


@given(values=st.lists(st.floats(-100, 100), min_size=2, max_size=12), data=st.data())
@settings(max_examples=60, deadline=None)
def test_every_item_is_scored_once_by_a_fit_that_never_saw_it(values, data):
    """The oracle: each item's error is that of the fit (a shifted mean) on the items of
    the other folds, recomputed here from the folds; every fit saw none of its fold."""
    items = list(range(len(values)))
    k = data.draw(st.integers(2, len(items)))
    shifts = data.draw(st.lists(st.integers(-3, 3), min_size=1, max_size=4, unique=True))
    seen = []

    def fit(train, shift):
        seen.append(set(train))
        return np.mean([values[i] for i in train]) + shift

    cv = cross_validate(items, k, shifts, fit, lambda model, i: abs(model - values[i]))
    assert len(seen) == k * len(shifts)
    for shift in shifts:
        assert sorted(cv.errors[shift]) == items
        for fold in cv.folds:
            rest = [i for i in items if i not in fold]
            for i in fold:
                want = abs(np.mean([values[j] for j in rest]) + shift - values[i])
                assert cv.errors[shift][i] == pytest.approx(want)
        assert cv.mean[shift] == pytest.approx(np.mean(list(cv.errors[shift].values())))
    fits = iter(seen)
    for _ in shifts:
        for fold in cv.folds:
            assert not next(fits) & set(fold)
    assert cv.mean[cv.chosen] == min(cv.mean.values())
    assert cv.chosen == next(s for s in shifts if cv.mean[s] == min(cv.mean.values()))
    for shift in shifts:  # the paired difference from the choice, item by item
        diff = [cv.errors[shift][i] - cv.errors[cv.chosen][i] for i in items]
        d, se = cv.versus_chosen(shift)
        assert d == pytest.approx(np.mean(diff), abs=1e-9) and d >= -1e-9
        assert se == pytest.approx(np.std(diff, ddof=1) / np.sqrt(len(items)), abs=1e-9)
    assert cv.versus_chosen(cv.chosen) == (0.0, 0.0)


def test_a_tie_chooses_the_first_candidate_given():
    cv = cross_validate(["a", "b", "c"], 3, [5, 1, 2], lambda train, c: c,
                        lambda c, item: 0.0 if c != 2 else 1.0)  # fmt: skip
    assert cv.chosen == 5 and cv.mean == {5: 0.0, 1: 0.0, 2: 1.0}
    assert cv.versus_chosen(2) == (1.0, 0.0) and cv.versus_chosen(1) == (0.0, 0.0)
    with pytest.raises(InputError, match=r"7 is not one of the candidates \[5, 1, 2\]"):
        cv.versus_chosen(7)


def test_the_progress_wraps_every_fit():
    calls = []

    def progress(jobs, total):
        calls.append(total)
        return jobs

    cross_validate(list("abcd"), 2, [0, 1, 2], lambda t, c: c, lambda m, x: 0.0, progress)
    assert calls == [6]


@pytest.mark.parametrize("items, k, candidates, needle", [
    (["a", "b"], 1, [0], "folds 1: expected an integer from 2 to the number"),
    (["a", "b"], 3, [0], r"folds 3: .*\(2\)"),
    (["a", "b"], 2.0, [0], "folds 2.0"),
    (["a", "b"], True, [0], "folds True"),
    (["a", "b", "a"], 2, [0], "'a' given twice"),
    (["a", ["b"]], 2, [0], r"item \['b'\] is not hashable"),
    (["a", "b"], 2, [], "expected at least one"),
    (["a", "b"], 2, [1, 1], "none twice"),
    (["a", "b"], 2, [1, [2]], "each hashable"),
])  # fmt: skip
def test_refusals(items, k, candidates, needle):
    with pytest.raises(InputError, match=needle):
        cross_validate(items, k, candidates, lambda t, c: 0, lambda m, x: 0.0)


@given(groups=st.lists(st.integers(0, 6), min_size=2, max_size=25), data=st.data())
@settings(max_examples=80, deadline=None)
def test_grouped_folds_hold_whole_groups(groups, data):
    """With groups, the distinct groups (in the order they first appear) are cut as items
    would be, and every item lands in its group's fold, in the order given."""
    distinct = list(dict.fromkeys(groups))
    if len(distinct) < 2:
        with pytest.raises(InputError, match=r"number of groups of training files \(1\)"):
            fold_blocks(list(range(len(groups))), 2, groups)
        return
    k = data.draw(st.integers(2, len(distinct)))
    items = [f"file{i}" for i in range(len(groups))]
    folds = fold_blocks(items, k, groups)
    group_of = dict(zip(items, groups))
    assert len(folds) == k and sorted(x for f in folds for x in f) == sorted(items)
    for fold in folds:
        assert fold == [x for x in items if x in fold]  # the order given
    held = [list(dict.fromkeys(group_of[x] for x in fold)) for fold in folds]
    assert [g for h in held for g in h] == distinct  # each group in one fold, in order
    assert held == fold_blocks(distinct, k)
    assert fold_blocks(items, k, items) == fold_blocks(items, k)  # one group per item


def test_a_grouped_cross_validation_never_fits_on_a_group_it_scores():
    items, groups = ["a0", "b0", "a1", "c0", "b1", "c1"], list("abacbc")
    seen = []

    def fit(train, c):
        seen.append(train)
        return c

    cv = cross_validate(items, 3, [0], fit, lambda m, x: 0.0, groups=groups)
    assert cv.folds == [["a0", "a1"], ["b0", "b1"], ["c0", "c1"]]
    assert seen == [["b0", "b1", "c0", "c1"], ["a0", "a1", "c0", "c1"], ["a0", "a1", "b0", "b1"]]
    with pytest.raises(InputError, match="2 groups for 6 items"):
        cross_validate(items, 2, [0], fit, lambda m, x: 0.0, groups=["a", "b"])
    with pytest.raises(InputError, match=r"the group \['b'\] of 'b0' is not hashable"):
        fold_blocks(items, 2, ["a", ["b"], "a", "c", "b", "c"])


def test_group_keys_take_the_first_group_or_the_whole_match():
    files = ["runs/walk_seed0.jsonl", "runs/walk_seed1.jsonl", "other/meet_seed0.jsonl"]
    assert group_keys(files, r"(\w+)_seed\d+") == ["walk", "walk", "meet"]
    assert group_keys(files, r"^.*/") == ["runs/", "runs/", "other/"]
    for pattern, needle in ((r"(\w+", "not a regular expression"),
                            (r"(x)?walk", "first group takes no part in the match in 'runs/w"),
                            (r"_seed\d+$", "no match in 'runs/walk_seed0.jsonl'")):
        with pytest.raises(InputError, match=needle):
            group_keys(files, pattern)


@pytest.mark.parametrize(("call", "needle"), [
    (lambda: fold_blocks("abc", 2), "items must be a list, got 'abc'"),
    (lambda: fold_blocks(5, 2), "items must be a list, got 5"),
    (lambda: fold_blocks(["a", "b"], 2, "xy"), "groups must be a list, got 'xy'"),
    (lambda: group_keys("abc", r"(\w)"), "items must be a list, got 'abc'"),
    (lambda: cross_validate(["a", "b"], 2, "ab", lambda t, c: 0, lambda m, i: 0.0),
     "candidates must be a list, got 'ab'"),
])  # fmt: skip
def test_a_string_is_not_a_list_of_items(call, needle):
    """A string was split into its letters (three 'files' a, b, c; candidates 'a' and
    'b'), and a number raised Python's TypeError."""
    with pytest.raises(InputError) as exc:
        call()
    assert needle in str(exc.value)
