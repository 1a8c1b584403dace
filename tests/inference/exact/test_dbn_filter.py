"""Discrete DBN inference against exact inference on the unrolled net, and pgmpy."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dbn import pgmpy_adapter as pa
from dbn.cpds import TabularCPD
from dbn.dbn import TwoSliceDBN, prev, slice_name
from dbn.errors import EvidenceError, ShapeError
from dbn.variables import DiscreteVariable
from inference.exact import JunctionTree, map_assignment
from inference.exact.dbn_filter import DBNFilter

TOL = 1e-9


def _columns(seed: int, dbn: TwoSliceDBN, T: int) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    cards = {v.name: v.cardinality for v in dbn.variables}
    cols = {"o": rng.integers(-1, cards["o"], size=T)}
    cols["b"] = np.where(rng.random(T) < 0.3, rng.integers(0, cards["b"], size=T), -1)
    return cols


def _slice_evidence(cols: dict[str, np.ndarray], t: int) -> dict[str, int]:
    return {n: int(c[t]) for n, c in cols.items() if c[t] >= 0}


def _unrolled_evidence(cols: dict[str, np.ndarray], upto: int) -> dict[str, int]:
    return {slice_name(n, s): int(c[s]) for n, c in cols.items() for s in range(upto) if c[s] >= 0}


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), T=st.integers(1, 5))
def test_filter_smoother_viterbi_equal_unrolled_net(factories, seed: int, T: int) -> None:
    dbn = factories.random_dbn(seed)
    flt = DBNFilter(dbn)
    cols = _columns(seed + 1, dbn, T)
    bn = dbn.unroll(T)
    jt = JunctionTree(bn)
    try:
        full = jt.calibrate(_unrolled_evidence(cols, T))
    except EvidenceError:
        with pytest.raises(EvidenceError):
            flt.filter(cols)
        return
    res = flt.filter(cols)
    sm = flt.smooth(cols)
    assert abs(res.log_likelihood - full.log_evidence) < TOL
    for t in range(T):
        # the filtering marginal is the unrolled net's posterior given slices 0..t only
        upto = jt.calibrate(_unrolled_evidence(cols, t + 1))
        for n in flt.interface:
            filt = flt.marginals_of(res.beliefs, n)[t]
            np.testing.assert_allclose(filt, upto.marginals[slice_name(n, t)], atol=TOL, rtol=0)
            assert abs(filt.sum() - 1.0) < TOL
            smoothed = flt.marginals_of(sm.posteriors, n)[t]
            np.testing.assert_allclose(smoothed, full.marginals[slice_name(n, t)], atol=TOL, rtol=0)
    path, lp = flt.viterbi(cols)
    _, best = map_assignment(bn, _unrolled_evidence(cols, T))
    assert abs(lp - best) < TOL
    config = {slice_name(n, t): int(path[n][t]) for n in dbn.names for t in range(T)}
    assert abs(bn.log_joint(config) - best) < TOL


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), T=st.integers(1, 6))
def test_online_steps_equal_batch_and_slice_marginals(factories, seed: int, T: int) -> None:
    dbn = factories.random_dbn(seed)
    flt = DBNFilter(dbn)
    cols = _columns(seed + 7, dbn, T)
    try:
        res = flt.filter(cols)
    except EvidenceError:
        return
    state = flt.init(_slice_evidence(cols, 0))
    states = [state]
    for t in range(1, T):
        state = flt.step(state, _slice_evidence(cols, t))
        states.append(state)
    for t, s in enumerate(states):  # each slice queried alone equals the multi-slice run
        np.testing.assert_allclose(s.belief, res.beliefs[t], atol=1e-12)
        assert s.t == t
    assert abs(state.log_likelihood - res.log_likelihood) < 1e-10
    # every variable of the last slice, against the unrolled net
    last = flt.slice_marginals(states[-2] if T > 1 else None, _slice_evidence(cols, T - 1))
    cal = JunctionTree(dbn.unroll(T)).calibrate(_unrolled_evidence(cols, T))
    for n in dbn.names:
        np.testing.assert_allclose(last[n], cal.marginals[slice_name(n, T - 1)], atol=TOL, rtol=0)
        assert abs(last[n].sum() - 1.0) < TOL


def _hmm(K: int, seed: int) -> TwoSliceDBN:
    rng = np.random.default_rng(seed)
    A = rng.dirichlet(np.ones(K), K)
    B = rng.dirichlet(np.ones(8), K)
    pi = rng.dirichlet(np.ones(K))
    x, y = DiscreteVariable("x", K), DiscreteVariable("y", 8)
    return TwoSliceDBN(
        [x, y],
        [TabularCPD("x", [], pi), TabularCPD("y", ["x"], B)],
        [TabularCPD("x", [prev("x")], A), TabularCPD("y", ["x"], B)],
    )


def test_finite_and_normalised_at_100000_slices() -> None:
    flt = DBNFilter(_hmm(16, 0))
    obs = np.random.default_rng(1).integers(8, size=100_000)
    res = flt.filter({"y": obs})
    assert np.all(np.isfinite(res.beliefs))
    np.testing.assert_allclose(res.beliefs.sum(axis=1), 1.0, atol=1e-12)
    assert np.isfinite(res.log_likelihood) and res.log_likelihood < 0
    # the same as the first 1,000 slices then continued on-line
    head = flt.filter({"y": obs[:1000]})
    np.testing.assert_allclose(head.beliefs, res.beliefs[:1000], atol=1e-12)


@pytest.mark.parametrize("K", [3, 4])
def test_equals_pgmpy_forward_inference_one_slice_per_call(K: int) -> None:
    dbn = _hmm(K, K)
    flt = DBNFilter(dbn)
    model = pa.dbn_to_pgmpy(dbn)
    obs = np.random.default_rng(K).integers(8, size=12)
    res = flt.filter({"y": obs})
    evidence = {("y", t): str(int(obs[t])) for t in range(len(obs))}
    for t in (0, 5, 11):
        theirs = pa.pgmpy_dbn_forward(model, [("x", t)], evidence)[("x", t)]
        np.testing.assert_allclose(res.beliefs[t], theirs, atol=TOL, rtol=0)


def test_bad_input_raises_and_state_is_unchanged() -> None:
    flt = DBNFilter(_hmm(4, 0))
    state = flt.init({"y": 3})
    snapshot = (state.t, state.belief.copy(), state.log_likelihood)
    with pytest.raises(EvidenceError, match="unknown"):
        flt.step(state, {"z": 1})
    with pytest.raises(EvidenceError, match="out of range"):
        flt.step(state, {"y": 8})
    with pytest.raises(EvidenceError, match="shape"):
        flt.step(state, None, {"y": np.ones(3)})
    assert state.t == snapshot[0] and state.log_likelihood == snapshot[2]
    np.testing.assert_array_equal(state.belief, snapshot[1])
    np.testing.assert_array_equal(
        flt.step(state, {"y": 2}).belief, flt.step(state, {"y": 2}).belief
    )
    with pytest.raises(ShapeError, match="length"):
        flt.filter({"y": np.zeros(3, int), "x": np.zeros(4, int)})
    with pytest.raises(EvidenceError, match="slice 0: 0.5 is not a state"):
        flt.filter({"y": np.full(3, 0.5)})
    with pytest.raises(EvidenceError, match="slice 2"):
        flt.filter({"y": np.array([0, 1, 9])})


def test_hard_and_soft_evidence_on_one_variable_match_the_unrolled_net() -> None:
    dbn = _hmm(3, 5)
    flt = DBNFilter(dbn)
    soft = {"x": np.array([0.2, 1.0, 0.5])}
    state = flt.init({"y": 1})
    marg = flt.slice_marginals(state, {"x": 2, "y": 4}, soft)
    assert marg["x"].tolist() == [0.0, 0.0, 1.0]
    stepped = flt.step(state, {"y": 4}, soft)
    cal = JunctionTree(dbn.unroll(2)).calibrate({"y_0": 1, "y_1": 4}, {"x_1": soft["x"]})
    np.testing.assert_allclose(flt.marginal(stepped, "x"), cal.marginals["x_1"], atol=TOL)
    assert abs(stepped.log_likelihood - cal.log_evidence) < TOL
