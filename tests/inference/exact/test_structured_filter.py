"""Structured (frontier) exact filtering against brute force on the unrolled net, the
dense DBNFilter, the hand-written numpy pass and pgmpy."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from benchmarks._chains_numpy import numpy_factored_filter
from dbn import pgmpy_adapter as pa
from dbn.cpds import TabularCPD
from dbn.dbn import TwoSliceDBN, prev, slice_name
from dbn.errors import (
    EvidenceError,
    FrontierTooLargeError,
    ModelError,
    ShapeError,
    UnknownVariableError,
)
from dbn.examples import coupled_chains, sample_coupled_chains
from dbn.variables import DiscreteVariable
from inference.exact.dbn_filter import DBNFilter
from inference.exact.enumeration import brute_force_map, brute_force_marginals
from inference.exact.structured_filter import StructuredFilter

TOL = 1e-9


def random_dbn(seed: int, max_vars: int = 4, max_card: int = 3) -> TwoSliceDBN:
    """2..max_vars variables per slice, cardinalities 1..max_card, random intra- and
    inter-slice edges (v0 always persists), tables with some exact zeros."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, max_vars + 1))
    k = max_card + 1
    cards = [max(2, int(rng.integers(1, k)))] + [int(c) for c in rng.integers(1, k, size=n - 1)]
    names = [f"v{i}" for i in range(n)]
    card = dict(zip(names, cards))
    card.update({prev(v): k for v, k in card.items()})

    def table(parents, child):
        shape = (*(card[p] for p in parents), card[child])
        rows = rng.dirichlet(np.full(shape[-1], 0.7), size=int(np.prod(shape[:-1])))
        rows = np.where(rng.random(rows.shape) < 0.1, 0.0, rows)
        rows[np.arange(rows.shape[0]), rng.integers(shape[-1], size=rows.shape[0])] += 0.05
        return (rows / rows.sum(axis=1, keepdims=True)).reshape(shape)

    initial, transition = [], []
    for i, v in enumerate(names):
        intra = [u for u in names[:i] if rng.random() < 0.4][:2]
        inter = [prev(u) for u in names if rng.random() < 0.35][:2]
        if i == 0 and prev(v) not in inter:
            inter = [prev(v)]
        initial.append(TabularCPD(v, intra, table(intra, v)))
        trans = [p for p in intra if rng.random() < 0.8] + inter
        transition.append(TabularCPD(v, trans, table(trans, v)))
    return TwoSliceDBN([DiscreteVariable(v, card[v]) for v in names], initial, transition)


def random_evidence(seed: int, dbn: TwoSliceDBN, T: int):
    """Hard columns with missing entries (-1) and soft columns with NaN rows."""
    rng = np.random.default_rng(seed)
    hard, soft = {}, {}
    for v in dbn.variables:
        if rng.random() < 0.5:
            col = rng.integers(0, v.cardinality, size=T)
            hard[v.name] = np.where(rng.random(T) < 0.4, -1, col)
        if rng.random() < 0.3:
            rows = rng.random((T, v.cardinality)) + 0.05
            rows[rng.random(T) < 0.3] = np.nan
            soft[v.name] = rows
    return hard, soft


def unrolled(hard, soft, upto: int):
    h = {slice_name(n, t): int(c[t]) for n, c in hard.items() for t in range(upto) if c[t] >= 0}
    s = {
        slice_name(n, t): r[t]
        for n, r in soft.items()
        for t in range(upto)
        if not np.all(np.isnan(r[t]))
    }
    return h, s


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), T=st.integers(1, 3))
def test_filter_smoother_viterbi_equal_brute_force_on_the_unrolled_net(seed: int, T: int) -> None:
    dbn = random_dbn(seed)
    flt = StructuredFilter(dbn, query=dbn.names)
    hard, soft = random_evidence(seed + 1, dbn, T)
    h, s = unrolled(hard, soft, T)
    try:
        full, logz = brute_force_marginals(dbn.unroll(T), h, s)
    except EvidenceError:
        with pytest.raises(EvidenceError):
            flt.filter(hard, soft, T)
        return
    res = flt.filter(hard, soft, T)
    assert abs(res.log_likelihood - logz) < TOL
    small = StructuredFilter(dbn).filter(hard, soft, T)  # interface only: the dense path
    np.testing.assert_allclose(small.log_normalizers, res.log_normalizers, atol=TOL, rtol=0)
    for n in dbn.interface:
        np.testing.assert_allclose(small.marginals[n], res.marginals[n], atol=TOL, rtol=0)
    sm = flt.smooth(hard, soft, T)
    assert abs(sm.log_likelihood - logz) < TOL
    for t in range(T):
        upto, _ = brute_force_marginals(dbn.unroll(t + 1), *unrolled(hard, soft, t + 1))
        for v in dbn.variables:
            key = slice_name(v.name, t)
            observed = v.name in hard and hard[v.name][t] >= 0
            want = np.eye(v.cardinality)[hard[v.name][t]] if observed else upto[key]
            np.testing.assert_allclose(res.marginals[v.name][t], want, atol=TOL, rtol=0)
            want = np.eye(v.cardinality)[hard[v.name][t]] if observed else full[key]
            np.testing.assert_allclose(sm.marginals[v.name][t], want, atol=TOL, rtol=0)
    path, lp = flt.viterbi(hard, soft, T)
    _, best = brute_force_map(dbn.unroll(T), h, s)
    assert abs(lp - best) < TOL
    config = {slice_name(n, t): int(path[n][t]) for n in dbn.names for t in range(T)}
    bn = dbn.unroll(T)
    score = bn.log_joint(config) + sum(np.log(vec[config[k]]) for k, vec in s.items())
    assert abs(score - best) < TOL
    assert all(config[k] == val for k, val in h.items())


@settings(max_examples=15, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), T=st.integers(1, 6))
def test_equals_dbn_filter_and_online_steps_equal_batch(seed: int, T: int) -> None:
    dbn = random_dbn(seed, max_vars=7, max_card=2)  # wider: interfaces up to 2**7
    hard, _ = random_evidence(seed + 2, dbn, T)
    dense = DBNFilter(dbn)
    flt = StructuredFilter(dbn, dense_limit=0)  # the einsum plan at every slice
    small = StructuredFilter(dbn)  # small interfaces: one matrix per distinct row
    try:
        ref = dense.filter(hard, num_timesteps=T)
    except EvidenceError:
        with pytest.raises(EvidenceError):
            flt.filter(hard, num_timesteps=T)
        return
    res = flt.filter(hard, num_timesteps=T)
    assert abs(res.log_likelihood - ref.log_likelihood) < TOL
    res_small = small.filter(hard, num_timesteps=T)
    np.testing.assert_allclose(res_small.log_normalizers, ref.log_normalizers, atol=TOL, rtol=0)
    for n in flt.interface:
        np.testing.assert_allclose(res_small.marginals[n], res.marginals[n], atol=TOL, rtol=0)
    np.testing.assert_allclose(res.log_normalizers, ref.log_normalizers, atol=TOL, rtol=0)
    for n in flt.interface:
        np.testing.assert_allclose(res.marginals[n], dense.marginals_of(ref.beliefs, n), atol=TOL)
    np.testing.assert_allclose(res.last.belief.reshape(-1), ref.beliefs[-1], atol=TOL)
    # marginal consistency: the marginals of one joint, each normalised
    for n, m in res.marginals.items():
        np.testing.assert_allclose(m.sum(axis=1), 1.0, atol=1e-12)
        axes = tuple(a for a, u in enumerate(flt.interface) if u != n)
        np.testing.assert_allclose(res.last.belief.sum(axis=axes), m[-1], atol=1e-12)
    state = None
    for t in range(T):
        ev = {n: int(c[t]) for n, c in hard.items() if c[t] >= 0}
        state = flt.init(ev) if state is None else flt.step(state, ev)
        for n, m in flt.marginals(state).items():
            np.testing.assert_allclose(m, res.marginals[n][t], atol=1e-12)
    assert abs(state.log_likelihood - res.log_likelihood) < 1e-10


def test_coupled_chains_equal_the_numpy_pass_and_finite_over_long_runs() -> None:
    dbn = coupled_chains(6)
    _, ys = sample_coupled_chains(np.random.default_rng(0), 6, 300)
    res = StructuredFilter(dbn).filter({f"y{i}": ys[:, i] for i in range(6)})
    marg, logz = numpy_factored_filter(ys)
    for i in range(6):
        np.testing.assert_allclose(res.marginals[f"x{i}"], marg[:, i], atol=TOL, rtol=0)
    np.testing.assert_allclose(res.log_normalizers, logz, atol=TOL, rtol=0)
    # 100,000 slices: finite, normalised, and the first slices equal a short run
    _, ys = sample_coupled_chains(np.random.default_rng(1), 2, 100_000)
    flt = StructuredFilter(coupled_chains(2))
    long = flt.filter({"y0": ys[:, 0], "y1": ys[:, 1]})
    assert np.all(np.isfinite(long.log_normalizers)) and np.isfinite(long.log_likelihood)
    np.testing.assert_allclose(long.marginals["x1"].sum(axis=1), 1.0, atol=1e-12)
    head = flt.filter({"y0": ys[:500, 0], "y1": ys[:500, 1]})
    np.testing.assert_allclose(head.marginals["x0"], long.marginals["x0"][:500], atol=1e-12)
    # few distinct evidence rows: the dense path (one matrix per row) equals the plan's
    soft = np.array([[0.3, 1.0], [1.0, 0.5]])[ys[:500, 1]]
    soft[::7] = np.nan
    ev = {"y0": np.where(np.arange(500) % 5 == 0, -1, ys[:500, 0])}
    dense = flt.filter(ev, {"x1": soft})
    plain = StructuredFilter(coupled_chains(2), dense_limit=0).filter(ev, {"x1": soft})
    np.testing.assert_allclose(dense.log_normalizers, plain.log_normalizers, atol=1e-12)
    for n in ("x0", "x1"):
        np.testing.assert_allclose(dense.marginals[n], plain.marginals[n], atol=1e-12)


def test_equals_pgmpy_forward_inference() -> None:
    dbn = coupled_chains(2)
    _, ys = sample_coupled_chains(np.random.default_rng(3), 2, 4)
    res = StructuredFilter(dbn).filter({f"y{i}": ys[:, i] for i in range(2)})
    model = pa.dbn_to_pgmpy(dbn)
    evidence = {(f"y{i}", t): str(int(ys[t, i])) for i in range(2) for t in range(4)}
    theirs = pa.pgmpy_dbn_forward(model, [("x0", 3), ("x1", 3)], evidence)
    for n in ("x0", "x1"):
        np.testing.assert_allclose(res.marginals[n][3], theirs[(n, 3)], atol=TOL, rtol=0)


def test_memory_guard_raises_before_allocating_and_names_the_approximations() -> None:
    with pytest.raises(ModelError, match="refuse|entries") as err:
        DBNFilter(coupled_chains(12))
    assert err.type is not FrontierTooLargeError
    flt = StructuredFilter(coupled_chains(12))  # the dense engine refuses; this fits
    assert flt.predicted_size([f"y{i}" for i in range(12)]) == 2**12
    with pytest.raises(
        FrontierTooLargeError, match=r"67,108,864 entries.*'bk'.*'particle'.*'rbpf'"
    ):
        StructuredFilter(coupled_chains(26))
    with pytest.raises(FrontierTooLargeError, match="limit of 100 "):
        StructuredFilter(coupled_chains(8), max_size=100)


def test_bad_input_raises_before_any_state_changes() -> None:
    dbn = coupled_chains(2)
    flt = StructuredFilter(dbn)
    state = flt.init({"y0": 1})
    snapshot = (state.t, state.belief.copy(), state.log_likelihood)
    with pytest.raises(EvidenceError, match="unknown"):
        flt.step(state, {"z": 1})
    with pytest.raises(EvidenceError, match="out of range"):
        flt.step(state, {"y0": 2})
    with pytest.raises(EvidenceError, match="shape"):
        flt.step(state, None, {"y0": np.ones(3)})
    assert (state.t, state.log_likelihood) == snapshot[::2]
    np.testing.assert_array_equal(state.belief, snapshot[1])
    with pytest.raises(ShapeError, match="length"):
        flt.filter({"y0": np.zeros(3, int), "y1": np.zeros(4, int)})
    with pytest.raises(ShapeError, match="1-D"):
        flt.filter({"y0": np.zeros((3, 2), int)})
    with pytest.raises(EvidenceError, match="slice 0: 0.5 is not a state"):
        flt.filter({"y0": np.full(3, 0.5)})
    with pytest.raises(EvidenceError, match="slice 2"):
        flt.filter({"y0": np.array([0, 1, 5])})
    with pytest.raises(ShapeError, match=r"\(num_timesteps, 2\)"):
        flt.filter(soft_evidence={"y0": np.ones((3, 3))})
    with pytest.raises(EvidenceError, match="slice 1"):
        flt.filter(soft_evidence={"y0": np.array([[1.0, 1.0], [-1.0, 1.0]])})
    with pytest.raises(UnknownVariableError, match="nope"):
        StructuredFilter(dbn, query=["nope"])
    with pytest.raises(ModelError, match="TwoSliceDBN"):
        StructuredFilter(dbn.unroll(2))
    with pytest.raises(UnknownVariableError, match="transition slice"):  # not a valid 2TBN
        x = DiscreteVariable("x", 2)
        TwoSliceDBN(
            [x], [TabularCPD("x", [], [0.5, 0.5])], [TabularCPD("x", [prev("w")], np.eye(2))]
        )


def test_interface_variable_whose_only_child_is_barren_smooths_like_brute_force() -> None:
    # c is in the interface only through b (never observed, not in the interface), so the
    # backward plan drops b and keeps prev(c) through a constant factor
    a, c = DiscreteVariable("a", 2), DiscreteVariable("c", 2)
    b, y = DiscreteVariable("b", 3), DiscreteVariable("y", 2)
    rng = np.random.default_rng(0)
    pb = rng.dirichlet(np.ones(3), 2)
    py = rng.dirichlet(np.ones(2), (2, 2))
    init = [TabularCPD("a", [], [0.3, 0.7]), TabularCPD("c", [], [0.6, 0.4])]
    init += [TabularCPD("b", ["c"], pb), TabularCPD("y", ["a", "c"], py)]
    trans = [TabularCPD("a", [prev("a")], [[0.8, 0.2], [0.1, 0.9]]), init[1]]
    trans += [TabularCPD("b", [prev("c")], pb), init[3]]
    dbn = TwoSliceDBN([a, c, b, y], init, trans)
    assert dbn.interface == ("a", "c")
    ys = np.array([0, 1, 1, 0])
    sm = StructuredFilter(dbn).smooth({"y": ys})
    full, logz = brute_force_marginals(dbn.unroll(4), {f"y_{t}": int(ys[t]) for t in range(4)})
    assert abs(sm.log_likelihood - logz) < TOL
    for t in range(4):
        for n in ("a", "c"):
            np.testing.assert_allclose(sm.marginals[n][t], full[f"{n}_{t}"], atol=TOL, rtol=0)
