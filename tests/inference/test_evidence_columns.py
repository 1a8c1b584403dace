"""Columnar DBN evidence (inference.evidence_columns): what is accepted, what each bad
column raises, and that the error names the column and the row."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dbn.errors import EvidenceError, NonFiniteError, ShapeError, UnknownEvidenceError
from dbn.examples import switching_lds
from inference.evidence_columns import check_columns, first_bad_row

DBN = switching_lds()  # s: discrete (2 states), x: continuous (2), y: continuous (1)


def test_accepts_and_normalises_every_kind() -> None:
    cols = check_columns(
        DBN,
        {"s": np.array([0, -1, 1]), "y": [0.1, np.nan, 0.3], "x": np.zeros((3, 2))},
        {"s": [[0.2, 0.8], [np.nan, np.nan], [1.0, 0.0]]},
    )
    assert cols.num_timesteps == 3
    assert cols.discrete["s"].dtype == np.int64
    assert cols.continuous["y"].shape == (3, 1)  # a 1-D column of a 1-D variable
    np.testing.assert_array_equal(cols.soft["s"][1], [1.0, 1.0])  # all NaN: no evidence
    assert check_columns(DBN, None, None, num_timesteps=4).num_timesteps == 4


@pytest.mark.parametrize(
    ("evidence", "soft", "error", "match"),
    [
        ({"z": [0]}, None, UnknownEvidenceError, "'z'"),
        (None, {"z": [[1.0]]}, UnknownEvidenceError, "'z'"),
        ({"s": [[0, 1]]}, None, ShapeError, "'s' must be 1-D"),
        ({"s": [0.0, 1.0]}, None, EvidenceError, "'s' must hold integer"),
        ({"s": [0, 2, 1]}, None, EvidenceError, "state 2 at slice 1"),
        ({"s": [0, 1], "y": [0.0, 1.0, 2.0]}, None, ShapeError, "'y' has length 3, expected 2"),
        ({"x": np.zeros((3, 3))}, None, ShapeError, r"'x' must have shape \(num_timesteps, 2\)"),
        ({"x": [[0.0, 0.0], [np.nan, 1.0]]}, None, NonFiniteError, "'x': row 1"),
        ({"y": [0.0, 1.0, np.inf]}, None, NonFiniteError, "'y': row 2"),
        (None, {"y": [[1.0]]}, EvidenceError, "continuous variable 'y'"),
        (None, {"s": [[1.0, 1.0, 1.0]]}, ShapeError, r"'s' must have shape \(num_timesteps, 2\)"),
        (None, {"s": [[0.0, 0.0]]}, EvidenceError, "'s': every row"),
        (None, {"s": [[-1.0, 2.0]]}, EvidenceError, "'s': every row"),
        ({}, None, ShapeError, "num_timesteps >= 1"),
        ([0, 1], None, EvidenceError, "mapping"),
    ],
)
def test_bad_columns_name_the_column(evidence, soft, error, match) -> None:
    with pytest.raises(error, match=match):
        check_columns(DBN, evidence, soft)


def test_length_is_checked_before_values() -> None:
    # a column both too long and out of range is reported for its length
    with pytest.raises(ShapeError, match="length"):
        check_columns(DBN, {"s": [0, 5, 1]}, None, num_timesteps=2)


@settings(max_examples=80, deadline=None)
@given(st.integers(1, 8), st.integers(1, 3), st.integers(0, 2**31 - 1))
def test_first_bad_row_is_the_first_partial_or_infinite_row(T, d, seed) -> None:
    rng = np.random.default_rng(seed)
    arr = rng.normal(size=(T, d))
    kinds = rng.integers(0, 4, size=T)  # 0, 1 good; 2 all NaN (good); 3 bad
    arr[kinds == 2] = np.nan
    for t in np.flatnonzero(kinds == 3):
        arr[t, rng.integers(d)] = rng.choice([np.inf, -np.inf, np.nan])
        if d == 1 and np.isnan(arr[t, 0]):
            arr[t, 0] = np.inf  # one NaN in a 1-wide row is a missing row, not a bad one
    expect = [t for t in range(T) if kinds[t] == 3]
    assert first_bad_row(arr) == (expect[0] if expect else None)
