"""Columnar DBN evidence (inference.evidence_columns): what is accepted, what each bad
column raises, and that the error names the column and the row."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dbn.cpds import TabularCPD
from dbn.dbn import TwoSliceDBN, prev
from dbn.errors import EvidenceError, NonFiniteError, ShapeError, UnknownEvidenceError
from dbn.examples import switching_lds
from dbn.variables import DiscreteVariable
from inference.evidence_columns import check_columns, first_bad_row
from inference.exact.dbn_evidence import sequence_likelihoods

DBN = switching_lds()  # s: discrete (2 states), x: continuous (2), y: continuous (1)
STATES = ("1", "2", "wet")  # numeric names: the name "1" is the index 0
NAMED = TwoSliceDBN(
    [DiscreteVariable("w", 3, STATES)],
    [TabularCPD("w", [], np.full(3, 1 / 3))],
    [TabularCPD("w", [prev("w")], np.full((3, 3), 1 / 3))],
)


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
        ({"s": [0.0, 0.5]}, None, EvidenceError, "'s' at slice 1: 0.5 is not a state"),
        ({"s": [0.0, 1e300]}, None, EvidenceError, "'s' at slice 1: 1e\\+300 is not a state"),
        ({"s": [True, False]}, None, EvidenceError, "'s' must hold integer"),
        ({"s": [0, 2, 1]}, None, EvidenceError, "state 2 at slice 1"),
        ({"s": [0, 1], "y": [0.0, 1.0, 2.0]}, None, ShapeError, "'y' has length 3, expected 2"),
        ({"x": np.zeros((3, 3))}, None, ShapeError, r"'x' must have shape \(num_timesteps, 2\)"),
        ({"x": [[0.0, 0.0], [np.nan, 1.0]]}, None, NonFiniteError, "'x' at slice 1"),
        ({"y": [0.0, 1.0, np.inf]}, None, NonFiniteError, "'y' at slice 2"),
        (None, {"y": [[1.0]]}, EvidenceError, "continuous variable 'y'"),
        (None, {"s": [[1.0, 1.0, 1.0]]}, ShapeError, r"'s' must have shape \(num_timesteps, 2\)"),
        (None, {"s": [[0.0, 0.0]]}, EvidenceError, "'s' at slice 0: .* is not a likelihood"),
        (None, {"s": [[-1.0, 2.0]]}, EvidenceError, "'s' at slice 0: .* is not a likelihood"),
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


@settings(max_examples=60, deadline=None)
@given(st.lists(st.integers(-1, 2), min_size=1, max_size=12), st.booleans())
def test_state_names_read_as_their_indices(states, as_array) -> None:
    """A column of state names (None = unobserved), as pgmpy users give them, is the
    column of their indices for both column readers (it was refused: "must hold integer
    states")."""
    names = [None if i < 0 else STATES[i] for i in states]
    col = np.array(names, dtype=object) if as_array else names
    np.testing.assert_array_equal(check_columns(NAMED, {"w": col}).discrete["w"], states)
    T, lam = sequence_likelihoods({"w": NAMED.variables[0]}, {"w": col})
    T0, lam0 = sequence_likelihoods({"w": NAMED.variables[0]}, {"w": np.array(states)})
    assert T == T0 == len(states)
    np.testing.assert_array_equal(lam["w"], lam0["w"])


@pytest.mark.parametrize(
    ("column", "match"),
    [
        (["1", "dry"], r"'w' at slice 1: 'dry' is not a state of 'w'"),
        # numpy writes [1, "2"] as ["1", "2"]: the index 1 would have been read as the name
        # "1", the index 0
        ([1, "2"], r"'w' at slice 0: 1 is not a state name: .* by index or by name, not both"),
        (np.array(["wet", 2], dtype=object), r"slice 1: 2 is not a state name"),
        ([["1"], ["2"]], r"'w' must be 1-D"),
        ([True, False], r"'w' must hold integer states \(-1 = unobserved\) or state names"),
        ([0.0, 1.5], r"'w' at slice 1: 1.5 is not a state"),
    ],
)
def test_bad_state_names_name_the_column_and_slice(column, match) -> None:
    for read in (lambda: check_columns(NAMED, {"w": column}),
                 lambda: sequence_likelihoods({"w": NAMED.variables[0]}, {"w": column})):
        with pytest.raises((EvidenceError, ShapeError), match=match):
            read()


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
