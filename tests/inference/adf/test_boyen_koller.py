"""Boyen-Koller filtering against the exact DBN filter (the oracle)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dbn.cpds import LinearGaussianCPD, TabularCPD
from dbn.dbn import TwoSliceDBN, prev
from dbn.errors import EvidenceError, ModelError, ShapeError, UnknownVariableError
from dbn.examples import coupled_chains, sample_coupled_chains
from dbn.variables import ContinuousVariable, DiscreteVariable
from inference.adf.boyen_koller import BoyenKoller, auto_clusters, bk_filter
from inference.adf.slice_plan import SlicePlan
from inference.exact.dbn_filter import DBNFilter

TOL = 1e-9


def _chains(n: int, T: int, seed: int):
    dbn = coupled_chains(n)
    _, ys = sample_coupled_chains(np.random.default_rng(seed), n, T)
    return dbn, {f"y{i}": ys[:, i] for i in range(n)}


def _exact_marginals(dbn, ev, names):
    f = DBNFilter(dbn)
    res = f.filter(ev)
    return {n: f.marginals_of(res.beliefs, n) for n in names}, res


def test_one_cluster_equals_exact_on_coupled_chains() -> None:
    n = 5
    dbn, ev = _chains(n, 40, seed=3)
    names = [f"x{i}" for i in range(n)]
    exact, res = _exact_marginals(dbn, ev, names)
    out = bk_filter(dbn, ev, clusters=[names])
    assert out.method == "bk" and out.info["clusters"] == [names]
    for name in names:
        np.testing.assert_allclose(out.marginals[name], exact[name], atol=TOL, rtol=0)
    np.testing.assert_allclose(out.log_likelihoods, res.log_normalizers, atol=TOL, rtol=0)


def _kl(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    with np.errstate(divide="ignore", invalid="ignore"):
        terms = np.where(p > 0, p * np.log(p / q), 0.0)
    return terms.sum(axis=-1)


def test_per_chain_error_is_small_and_does_not_accumulate() -> None:
    """Seed 002 / Boyen-Koller: the projection error contracts, so the KL between exact
    and BK chain marginals late in a long run is no larger than early on."""
    n, T = 6, 300
    early, late, overall = [], [], []
    for seed in range(3):
        dbn, ev = _chains(n, T, seed)
        names = [f"x{i}" for i in range(n)]
        exact, _ = _exact_marginals(dbn, ev, names)
        out = bk_filter(dbn, ev)
        assert out.info["clusters"] == [[x] for x in names]
        kl = np.stack([_kl(exact[x], out.marginals[x]) for x in names], axis=1)  # (T, n)
        assert np.all(kl >= -1e-12)
        early.append(kl[10:60].mean())
        late.append(kl[-50:].mean())
        overall.append(kl.mean())
    # the approximation is not exact (coupling matters) but small ...
    assert 0 < np.mean(overall) < 0.05
    # ... and bounded over time: late error within a factor 2 of early error
    assert np.mean(late) <= 2.0 * np.mean(early)


def test_auto_clusters_join_intra_slice_edges() -> None:
    a, b, c, y = (DiscreteVariable(n, 2) for n in "abcy")
    row = [0.5, 0.5]
    t2 = [[0.9, 0.1], [0.2, 0.8]]
    t3 = np.full((2, 2, 2), 0.5)
    init = [
        TabularCPD("a", [], row),
        TabularCPD("b", ["a"], t2),
        TabularCPD("c", [], row),
        TabularCPD("y", ["b", "c"], t3),
    ]
    trans = [
        TabularCPD("a", [prev("a")], t2),
        TabularCPD("b", ["a", prev("b")], t3),
        TabularCPD("c", [prev("c")], t2),
        TabularCPD("y", ["b", "c"], t3),
    ]
    dbn = TwoSliceDBN([a, b, c, y], init, trans)
    # a-b share an intra-slice edge; c is joined to b only through the observation y
    assert auto_clusters(dbn) == (("a", "b"), ("c",))


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), T=st.integers(1, 6))
def test_random_dbns_one_cluster_exact_and_normalised(factories, seed: int, T: int) -> None:
    dbn = factories.random_dbn(seed)
    rng = np.random.default_rng(seed + 1)
    card_o = dbn.initial_net.cardinality("o")
    ev = {"o": rng.integers(-1, card_o, size=T)}
    flt = DBNFilter(dbn)
    try:
        res = flt.filter(ev)
    except EvidenceError:
        with pytest.raises(EvidenceError):
            bk_filter(dbn, ev, clusters=[list(dbn.interface)])
        return
    one = bk_filter(dbn, ev, query=["a", "b", "h"], clusters=[list(dbn.interface)])
    np.testing.assert_allclose(one.log_likelihoods, res.log_normalizers, atol=TOL, rtol=0)
    state = None
    for t in range(T):
        slice_ev = {"o": int(ev["o"][t])} if ev["o"][t] >= 0 else {}
        exact = flt.slice_marginals(state, slice_ev)
        state = flt.init(slice_ev) if t == 0 else flt.step(state, slice_ev)
        for q in ("a", "b", "h"):
            np.testing.assert_allclose(one.marginals[q][t], exact[q], atol=TOL, rtol=0)
    try:
        auto = bk_filter(dbn, ev, query=["a", "b", "h"])
    except EvidenceError:  # possible: the approximate belief can rule the evidence out
        return
    for q in ("a", "b", "h"):
        np.testing.assert_allclose(auto.marginals[q].sum(axis=1), 1.0, atol=TOL)
        assert np.all(auto.marginals[q] >= 0)


def test_online_equals_batch_and_step_is_pure() -> None:
    dbn, ev = _chains(4, 12, seed=5)
    bk = BoyenKoller(dbn)
    batch = bk_filter(dbn, ev)
    state = bk.init({n: int(c[0]) for n, c in ev.items()})
    lls = [state.step_log_likelihood]
    for t in range(1, 12):
        before = [b.copy() for b in state.beliefs]
        new = bk.step(state, {n: int(c[t]) for n, c in ev.items()})
        for b0, b1 in zip(before, state.beliefs):
            np.testing.assert_array_equal(b0, b1)
        state = new
        lls.append(state.step_log_likelihood)
    np.testing.assert_allclose(lls, batch.log_likelihoods, atol=1e-12)
    assert abs(state.log_likelihood - batch.log_likelihood) < 1e-9
    for i in range(4):
        np.testing.assert_allclose(bk.marginal(state, f"x{i}"), batch.marginals[f"x{i}"][-1])


def test_cost_per_step_does_not_grow_with_the_number_of_chains() -> None:
    """The plan's largest clique is the same at 16 and 64 chains: a step is linear in n."""
    sizes = [BoyenKoller(coupled_chains(n)).max_clique_size for n in (16, 64)]
    assert sizes[0] == sizes[1] <= 8


def test_slice_plan_matches_brute_force() -> None:
    rng = np.random.default_rng(0)
    cards = {"a": 2, "b": 3, "c": 2, "d": 2}
    scopes = [("a", "b"), ("b", "c"), ("c", "d", "a"), ("d",), ()]
    targets = [("a",), ("d", "b")]
    facs = [rng.random([cards[v] for v in s]) for s in scopes]
    margs, log_z = SlicePlan(cards, scopes, targets).run(facs)
    joint = np.einsum("ab,bc,cda,d->abcd", *facs[:4]) * facs[4]
    assert abs(log_z - np.log(joint.sum())) < 1e-12
    p = joint / joint.sum()
    np.testing.assert_allclose(margs[0], p.sum(axis=(1, 2, 3)), atol=1e-14)
    np.testing.assert_allclose(margs[1], p.sum(axis=(0, 2)).T, atol=1e-14)


def test_bad_clusters_and_inputs_raise_clear_errors() -> None:
    dbn, ev = _chains(3, 5, seed=0)
    with pytest.raises(ModelError, match="do not cover the interface.*x2"):
        BoyenKoller(dbn, clusters=[["x0"], ["x1"]])
    with pytest.raises(ModelError, match="disjoint"):
        BoyenKoller(dbn, clusters=[["x0", "x1"], ["x1", "x2"]])
    with pytest.raises(ModelError, match="not an interface variable"):
        BoyenKoller(dbn, clusters=[["x0", "x1", "x2", "y0"]])
    with pytest.raises(UnknownVariableError, match="zz"):
        BoyenKoller(dbn, clusters=[["x0", "x1", "x2", "zz"]])
    with pytest.raises(UnknownVariableError, match="nope"):
        bk_filter(dbn, {**ev, "nope": np.zeros(5, int)})
    with pytest.raises(ShapeError, match="y1"):
        bk_filter(dbn, {"y0": ev["y0"], "y1": ev["y1"][:3]})
    with pytest.raises(EvidenceError, match="y0"):
        bk_filter(dbn, {"y0": np.full(5, 7)})
    bk = BoyenKoller(dbn)
    with pytest.raises(EvidenceError, match="unknown"):
        bk.init({"unknown": 1})
    x = ContinuousVariable("x")
    lg = LinearGaussianCPD("x", [], [], [0.0], [[1.0]])
    lg2 = LinearGaussianCPD("x", [prev("x")], [[[1.0]]], [0.0], [[1.0]])
    with pytest.raises(ModelError, match="continuous"):
        BoyenKoller(TwoSliceDBN([x], [lg], [lg2]))


def test_soft_evidence_one_cluster_equals_exact() -> None:
    dbn, ev = _chains(3, 8, seed=2)
    rng = np.random.default_rng(0)
    soft = rng.random((8, 2)) + 0.1
    soft[3] = np.nan  # no soft evidence at slice 3
    names = ["x0", "x1", "x2"]
    out = bk_filter(dbn, ev, clusters=[names], soft_evidence={"x1": soft})
    flt = DBNFilter(dbn)
    state = None
    for t in range(8):
        hard = {n: int(c[t]) for n, c in ev.items()}
        sv = {} if t == 3 else {"x1": soft[t]}
        state = flt.init(hard, sv) if t == 0 else flt.step(state, hard, sv)
        assert abs(out.log_likelihoods[: t + 1].sum() - state.log_likelihood) < TOL
        for n in names:
            np.testing.assert_allclose(out.marginals[n][t], flt.marginal(state, n), atol=TOL)
    with pytest.raises(EvidenceError, match="x1"):
        bk_filter(dbn, ev, soft_evidence={"x1": -soft})
