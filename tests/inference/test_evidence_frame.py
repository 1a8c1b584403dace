"""Evidence as a pandas DataFrame (a column per variable, a row per slice) filters as the
same columns given as arrays: the oracle is ``inference.filter`` on the dict of columns."""

from __future__ import annotations

import jax
import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import inference
from dbn.cpds import LinearGaussianCPD
from dbn.dbn import TwoSliceDBN, prev
from dbn.errors import EvidenceError, ShapeError, UnknownEvidenceError
from dbn.examples import coupled_chains
from dbn.variables import ContinuousVariable
from inference.evidence_columns import columns_from_frame

DBN = coupled_chains(2)


def _same(a, b) -> None:
    assert a.method == b.method
    for name in b.marginals:
        np.testing.assert_allclose(a.marginals[name], b.marginals[name], atol=1e-12)
    np.testing.assert_allclose(a.log_likelihoods, b.log_likelihoods, atol=1e-12)


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(st.integers(-1, 1), st.integers(-1, 1)), min_size=1, max_size=10),
       st.sampled_from(["Int64", "float", "category", "names"]))  # fmt: skip
def test_a_frame_with_gaps_filters_as_its_columns(rows, kind) -> None:
    """Gaps as pandas writes them (``pd.NA`` in a nullable Int64, NaN in floats, a missing
    category, None among state names) are unobserved slices (-1 in the oracle)."""
    cols = {"y0": np.array([r[0] for r in rows]), "y1": np.array([r[1] for r in rows])}
    frame = pd.DataFrame({k: pd.array([None if s < 0 else int(s) for s in v], dtype="Int64")
                          for k, v in cols.items()})  # fmt: skip
    if kind == "float":
        frame = frame.astype("float64")
    elif kind == "category":
        frame = frame.astype("category")
    elif kind == "names":
        frame = frame.astype(object).apply(lambda c: c.map(lambda s: None if s is pd.NA
                                                           else str(s)))  # fmt: skip
    _same(inference.filter(DBN, frame), inference.filter(DBN, cols))


@pytest.mark.parametrize("method", ["exact", "bk", "particle"])
def test_every_method_reads_a_frame(method) -> None:
    frame = pd.DataFrame({"y0": [0, 1, 1, 0], "y1": [1, 1, 0, 0]})
    key = jax.random.key(0) if method == "particle" else None
    _same(inference.filter(DBN, frame, method, key=key),
          inference.filter(DBN, {c: frame[c].to_numpy() for c in frame}, method, key=key))


@pytest.mark.parametrize(("frame", "error", "needle"), [
    (pd.DataFrame([[0, 1]]), EvidenceError, "(str) or (name, component) pairs, got 0"),
    (pd.DataFrame([[0, 1]], columns=["y0", "y0"]), EvidenceError, "['y0'] given more than once"),
    (pd.DataFrame({(0, "a"): [1]}), EvidenceError, "or (name, component) pairs, got (0, 'a')"),
    (pd.DataFrame({("y0", 0, "a"): [1]}), EvidenceError, "got ('y0', 0, 'a')"),
    (pd.DataFrame({("y0", 0): [1], ("y0", 1): ["a"]}), EvidenceError,
     "'y0' has 2 component columns, and they must hold numbers"),
    (pd.DataFrame({("y0", 0): [1], ("y0", 1): [0]}), ShapeError, "'y0'"),
    (pd.DataFrame({"zz": [0]}), UnknownEvidenceError, "unknown variable 'zz'"),
    (pd.DataFrame({"y0": [0.5]}), EvidenceError, "'y0' at slice 0: 0.5 is not a state"),
    (pd.DataFrame({"y0": [True]}), EvidenceError, "'y0' at slice 0: True is not a state name"),
])  # fmt: skip
def test_a_bad_frame_is_refused_naming_the_column(frame, error, needle) -> None:
    with pytest.raises(error) as exc:
        inference.filter(DBN, frame)
    assert needle in str(exc.value)


def test_other_evidence_passes_through_unchanged() -> None:
    ev = {"y0": [0, 1]}
    assert columns_from_frame(ev) is ev and columns_from_frame(None) is None


@pytest.mark.parametrize("pairs", [False, True], ids=["names", "pairs"])
@pytest.mark.parametrize("engine", ["structured", "bk"])
def test_rows_of_a_frame_step_the_online_filters_as_its_columns_filter(engine, pairs) -> None:
    """``for _, row in frame.iterrows(): step(state, row)``: a row of a column with a gap
    holds floats (1.0) and NaN, which the column reader takes and the slice reader
    refused ("state must be an int or a name, got 1.0"); a Series was not a mapping."""
    from inference.adf.boyen_koller import BoyenKoller

    frame = pd.DataFrame({"y0": [0, 1, None, 1, 0], "y1": [1, 1, 0, None, 0]}, dtype="Int64")
    flt = inference.online_filter(DBN) if engine == "structured" else BoyenKoller(DBN)
    batch = inference.filter(DBN, frame, "exact" if engine == "structured" else "bk")
    state = None
    if pairs:  # a row's index is (name, component): each name's one value
        frame = pd.concat({"y0": frame[["y0"]], "y1": frame[["y1"]]}, axis=1)
    rows = frame.astype(float).iterrows()
    for t, (_, row) in enumerate(rows):
        assert isinstance(row["y0"], float) if not pairs else row.index.nlevels == 2
        state = flt.init(row) if state is None else flt.step(state, row)
        for name in ("x0", "x1"):
            marginal = (flt.marginals(state)[name] if engine == "structured"
                        else flt.marginal(state, name))  # fmt: skip
            np.testing.assert_allclose(marginal, batch.marginals[name][t], atol=1e-12)


@pytest.mark.parametrize(("state", "needle"), [(0.5, "got 0.5"), (float("inf"), "got inf")])
def test_a_slice_state_that_is_no_whole_number_is_refused(state, needle) -> None:
    with pytest.raises(EvidenceError, match=needle):
        inference.online_filter(DBN).init({"y0": state})


def test_subclasses_of_pandas_and_pgmpy_classes_are_read_as_theirs() -> None:
    """A DataFrame subclass (a user's, geopandas') and a pgmpy DBN subclass were refused:
    the checks compared the class's own name."""
    from dbn import pgmpy_adapter as pa
    from dbn.checks import instance_of

    class Frame(pd.DataFrame):
        pass

    frame = Frame({"y0": [0, 1, 1], "y1": [1, 0, 0]})
    cols = {c: frame[c].to_numpy() for c in ("y0", "y1")}
    _same(inference.filter(DBN, frame), inference.filter(DBN, cols))
    theirs = pa.dbn_to_pgmpy(DBN)
    theirs.__class__ = type("MyDBN", (type(theirs),), {})
    _same(inference.filter(theirs, cols), inference.filter(DBN, cols))
    assert instance_of(frame, "pandas", "DataFrame") and not instance_of(cols, "pandas", "dict")


def _planar_dbn() -> TwoSliceDBN:
    """A 2-D position seen through 2-D noise: continuous variables of dimension 2."""
    move = [[0.9, 0.1], [0.0, 0.8]]
    see = LinearGaussianCPD("y", ["x"], [np.eye(2)], [0, 0], 0.5 * np.eye(2))
    return TwoSliceDBN([ContinuousVariable("x", 2), ContinuousVariable("y", 2)],
                       [LinearGaussianCPD("x", [], [], [0, 0], np.eye(2)), see],
                       [LinearGaussianCPD("x", [prev("x")], [move], [0, 0], 0.3 * np.eye(2)),
                        see])  # fmt: skip


def test_a_continuous_variable_s_dimensions_as_column_pairs_filter_as_its_array() -> None:
    """``pd.concat({"y": frame}, axis=1)`` labels the columns ``("y", "east")``, ...: they
    are ``y``'s dimensions in the frame's order (a MultiIndex was refused, so a
    continuous variable of dimension > 1 could not come in a DataFrame); a NaN row is an
    unobserved slice. The oracle: the same particle filter run on the (T, 2) array."""
    ys = np.random.default_rng(0).normal(size=(6, 2))
    ys[2] = np.nan
    frame = pd.concat({"y": pd.DataFrame({"east": ys[:, 0], "north": ys[:, 1]})}, axis=1)
    assert frame.columns.tolist() == [("y", "east"), ("y", "north")]
    key, dbn = jax.random.key(3), _planar_dbn()
    got = inference.filter(dbn, frame, "particle", key=key, num_particles=300)
    want = inference.filter(dbn, {"y": ys}, "particle", key=key, num_particles=300)
    np.testing.assert_array_equal(got.means["x"], want.means["x"])
    np.testing.assert_array_equal(got.log_likelihoods, want.log_likelihoods)
    assert columns_from_frame(frame)["y"].shape == (6, 2)


def test_soft_evidence_and_single_components_as_column_pairs() -> None:
    """Soft evidence as ``(name, state)`` pairs is the (T, cardinality) array; a name
    with one component is its plain column (state names stay names)."""
    like = np.array([[0.9, 0.1], [np.nan, np.nan], [0.2, 0.8], [0.5, 0.5]])
    soft = pd.DataFrame(like, columns=pd.MultiIndex.from_product([["y0"], [0, 1]]))
    ev = pd.concat({"y1": pd.DataFrame({"": ["1", "0", None, "1"]})}, axis=1)
    got = inference.filter(DBN, ev, soft_evidence=soft)
    want = inference.filter(DBN, {"y1": np.array([1, 0, -1, 1])}, soft_evidence={"y0": like})
    _same(got, want)
    assert not np.allclose(got.marginals["x0"], inference.filter(DBN, {"y1": [1, 0, -1, 1]})
                           .marginals["x0"])  # fmt: skip
