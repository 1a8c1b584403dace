"""The declarative layer: variables, CPDs, BayesNet and two-slice DBN validation."""

from __future__ import annotations

import re

import networkx as nx
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.stats import multivariate_normal

from dbn.bayesnet import BayesNet, check_evidence
from dbn.cpds import DeterministicCPD, LinearGaussianCPD, TabularCPD
from dbn.dbn import TwoSliceDBN, prev, slice_name
from dbn.errors import (
    CPDShapeError,
    CycleError,
    DuplicateNameError,
    EvidenceError,
    ModelError,
    NegativeProbabilityError,
    NotNormalizedError,
    UnknownVariableError,
)
from dbn.variables import ContinuousVariable, DiscreteVariable

A = DiscreteVariable("a", 2)
B = DiscreteVariable("b", 3, ("lo", "mid", "hi"))


def test_variable_validation() -> None:
    with pytest.raises(ModelError, match="cardinality"):
        DiscreteVariable("x", 0)
    with pytest.raises(ModelError, match="state names"):
        DiscreteVariable("x", 2, ("only",))
    with pytest.raises(ModelError, match="dim"):
        ContinuousVariable("y", 0)
    assert B.index("hi") == 2 and B.index(1) == 1
    with pytest.raises(EvidenceError, match="no state named 'top'"):
        B.index("top")
    with pytest.raises(EvidenceError, match="out of range"):
        B.index(3)


def test_row_not_summing_to_one_names_node_row_and_value() -> None:
    with pytest.raises(NotNormalizedError, match=r"'b'.*a=1.*0\.9"):
        TabularCPD("b", ["a"], [[0.2, 0.3, 0.5], [0.2, 0.3, 0.4]])
    TabularCPD("b", ["a"], [[0.2, 0.3, 0.5], [0.2, 0.3, 0.5 + 5e-10]])  # within 1e-9


def test_negative_entry_names_node_and_value() -> None:
    with pytest.raises(NegativeProbabilityError, match=r"'a'.*-0\.1"):
        TabularCPD("a", [], [1.1, -0.1])
    with pytest.raises(NegativeProbabilityError):
        TabularCPD("a", [], [np.nan, 1.0])


def test_shape_mismatch_cycle_unknown_parent_duplicates() -> None:
    good_a = TabularCPD("a", [], [0.5, 0.5])
    with pytest.raises(CPDShapeError, match=r"'b'.*\(3, 3\).*\(2, 3\)"):
        BayesNet([A, B], [good_a, TabularCPD("b", ["a"], np.full((3, 3), 1 / 3))])
    with pytest.raises(UnknownVariableError, match="'zz'"):
        BayesNet([A, B], [good_a, TabularCPD("b", ["zz"], np.full((2, 3), 1 / 3))])
    with pytest.raises(CycleError, match="cycle"):
        BayesNet(
            [A, B],
            [TabularCPD("a", ["b"], np.full((3, 2), 0.5)), TabularCPD("b", ["a"], np.full((2, 3), 1 / 3))],
        )
    with pytest.raises(DuplicateNameError, match="'a'"):
        BayesNet([A, DiscreteVariable("a", 3)], [good_a])
    with pytest.raises(DuplicateNameError, match="'a'"):
        BayesNet([A], [good_a, good_a])
    with pytest.raises(ModelError, match="no CPD"):
        BayesNet([A, B], [good_a])


def test_tables_are_read_only_values() -> None:
    table = np.array([0.5, 0.5])
    cpd = TabularCPD("a", [], table)
    table[0] = 0.9  # the CPD copied it
    assert cpd.table[0] == 0.5
    with pytest.raises(ValueError):
        cpd.table[0] = 0.1


def test_deterministic_cpd_counter() -> None:
    c = DiscreteVariable("c", 4)
    new = DiscreteVariable("new", 2)
    cpd = DeterministicCPD("c", ["c0", "new"], lambda c0, n: np.minimum(c0 + n, 3))
    bn = BayesNet(
        [DiscreteVariable("c0", 4), new, c],
        [TabularCPD("c0", [], np.full(4, 0.25)), TabularCPD("new", [], [0.7, 0.3]), cpd],
    )
    table = bn.table("c")
    assert table.shape == (4, 2, 4)
    assert table[1, 1, 2] == 1.0 and table[3, 1, 3] == 1.0 and table[2, 0, 2] == 1.0
    np.testing.assert_allclose(table.sum(axis=-1), 1.0)
    bad = DeterministicCPD("c", ["c0", "new"], lambda c0, n: c0 + n)  # reaches 4
    with pytest.raises(CPDShapeError, match="state 4"):
        BayesNet([DiscreteVariable("c0", 4), new, c], [bn.cpd("c0"), bn.cpd("new"), bad])


def test_linear_gaussian_log_prob_matches_scipy_and_sample_moments() -> None:
    import jax

    W = np.array([[1.0, 0.5], [0.0, 2.0]])
    cov = np.array([[1.0, 0.3], [0.3, 0.5]])
    cpd = LinearGaussianCPD("x", ["u"], [W], [0.1, -0.2], cov)
    u = np.array([0.3, -1.0])
    x = np.array([[0.2, 0.1], [1.0, -3.0]])
    expected = multivariate_normal(W @ u + [0.1, -0.2], cov).logpdf(x)
    np.testing.assert_allclose(cpd.log_prob(x, {"u": u}), expected, rtol=1e-12)
    keys = jax.random.split(jax.random.PRNGKey(3), 4000)
    draws = np.stack([cpd.sample(k, {"u": u}) for k in keys[:2000]])
    se = np.sqrt(np.diag(cov) / len(draws))
    assert np.all(np.abs(draws.mean(0) - (W @ u + [0.1, -0.2])) < 4 * se)
    with pytest.raises(ModelError, match="positive definite"):
        LinearGaussianCPD("x", [], [], [0.0, 0.0], [[1.0, 2.0], [2.0, 1.0]])


def test_evidence_validation() -> None:
    bn = BayesNet([A, B], [TabularCPD("a", [], [0.5, 0.5]), TabularCPD("b", ["a"], np.full((2, 3), 1 / 3))])
    hard, soft = check_evidence(bn, {"b": "mid"}, {"a": [0.2, 1.0]})
    assert hard == {"b": 1} and soft["a"].tolist() == [0.2, 1.0]
    for bad, match in [({"c": 0}, "unknown"), ({"b": 5}, "out of range"), ({"b": "x"}, "no state")]:
        with pytest.raises(EvidenceError, match=match):
            check_evidence(bn, bad)
    for lik, match in [([1.0], "shape"), ([-1.0, 1.0], "nonnegative"), ([0.0, 0.0], "all zero")]:
        with pytest.raises(EvidenceError, match=match):
            check_evidence(bn, None, {"a": lik})


def test_renumbered_says_whether_int_states_mean_names_to_pgmpy() -> None:
    assert DiscreteVariable("r", 3, ("1", "2", "3")).renumbered
    assert DiscreteVariable("s", 2, ("-1", "0")).renumbered
    assert not A.renumbered and not B.renumbered  # ("0", "1") are the indices; words


def test_two_slice_dbn_unroll_structure() -> None:
    x, y = DiscreteVariable("x", 3), DiscreteVariable("y", 2)
    T = np.full((3, 3), 1 / 3)
    E = np.full((3, 2), 0.5)
    dbn = TwoSliceDBN(
        [x, y],
        [TabularCPD("x", [], np.full(3, 1 / 3)), TabularCPD("y", ["x"], E)],
        [TabularCPD("x", [prev("x")], T), TabularCPD("y", ["x"], E)],
    )
    assert dbn.interface == ("x",)
    bn = dbn.unroll(4)
    assert len(bn) == 8
    assert bn.parents(slice_name("x", 3)) == (slice_name("x", 2),)
    assert bn.parents(slice_name("y", 2)) == (slice_name("x", 2),)
    with pytest.raises(UnknownVariableError, match="transition slice.*'z\\[t-1\\]'"):
        TwoSliceDBN([x, y], dbn.initial_cpds, [TabularCPD("x", [prev("z")], T), dbn.transition_cpds[1]])
    with pytest.raises(CPDShapeError, match="transition slice"):
        TwoSliceDBN([x, y], dbn.initial_cpds, [TabularCPD("x", [prev("y")], T), dbn.transition_cpds[1]])
    with pytest.raises(ModelError):
        dbn.unroll(0)


def test_continuous_two_slice_dbn_unrolls_and_exact_filter_refuses_it() -> None:
    from inference.exact.dbn_filter import DBNFilter

    x, y = ContinuousVariable("x", 2), ContinuousVariable("y", 1)
    obs = LinearGaussianCPD("y", ["x"], [np.ones((1, 2))], [0.0], [[1.0]])
    dbn = TwoSliceDBN(
        [x, y],
        [LinearGaussianCPD("x", [], [], [0.0, 0.0], np.eye(2)), obs],
        [LinearGaussianCPD("x", [prev("x")], [0.9 * np.eye(2)], [0.0, 0.0], 0.1 * np.eye(2)), obs],
    )
    assert dbn.interface == ("x",)
    bn = dbn.unroll(3)
    cpd = bn.cpd(slice_name("x", 2))
    assert cpd.parents == (slice_name("x", 1),)
    np.testing.assert_allclose(cpd.mean({slice_name("x", 1): np.ones(2)}), [0.9, 0.9])
    with pytest.raises(ModelError, match="continuous"):
        DBNFilter(dbn)


_X = DiscreteVariable("x", 2)
_X0 = TabularCPD("x", [], [0.5, 0.5])
_XT = TabularCPD("x", [prev("x")], [[0.9, 0.1], [0.2, 0.8]])


@pytest.mark.parametrize(
    ("build", "error", "needle"),
    [
        (lambda: DiscreteVariable("x", 2**62), ModelError, "is over 16,777,216"),
        (lambda: DiscreteVariable("x", 2, 5), ModelError, "state_names must be a sequence"),
        (lambda: DiscreteVariable("x", 2, "ab"), ModelError, "state_names must be a sequence"),
        (lambda: TabularCPD(None, [], [0.5, 0.5]), ModelError, "non-empty name, got None"),
        (lambda: TabularCPD("y", None, [0.5, 0.5]), ModelError, "parents must be a sequence"),
        (lambda: LinearGaussianCPD("z", [], [], [np.nan], [[1.0]]), ModelError,
         "bias must be finite"),
        (lambda: LinearGaussianCPD("z", [], [], ["a"], [[1.0]]), ModelError, "bias is not an array of numbers"),
        (lambda: LinearGaussianCPD("z", ["u"], [[[np.inf]]], [0.0], [[1.0]]), ModelError,
         "weight of parent 'u' must be finite"),
        (lambda: LinearGaussianCPD("z", ["u"], None, [0.0], [[1.0]]), CPDShapeError,
         "weights must be a sequence"),
        (lambda: BayesNet(None, [_X0]), ModelError, "variables must be a sequence"),
        (lambda: BayesNet([_X], None), ModelError, "cpds must be a sequence"),
        (lambda: TwoSliceDBN([_X], [_X0], [None]), ModelError, "not a CPD: None"),
        (lambda: TwoSliceDBN([_X], [_X0], "x"), ModelError, "transition_cpds must be a sequence"),
        (lambda: TwoSliceDBN([_X], [_X0], [_XT]).unroll(10**9), ModelError, "over 1,000,000 nodes"),
    ],
)
def test_malformed_declarations_are_model_errors(build, error, needle) -> None:
    """Each raised Python's or numpy's own error (TypeError, AttributeError, ValueError), was
    accepted (a NaN mean, a CPD of variable None, the state names 'a', 'b' of "ab"), or hung
    (2**62 default state names, an unrolled net of 10^9 nodes)."""
    with pytest.raises(error, match=re.escape(needle)):
        build()


def test_evidence_that_is_not_a_mapping_is_an_evidence_error() -> None:
    """A list of pairs or a bare name raised AttributeError ('list' has no 'items')."""
    from inference.exact import marginals, variable_elimination

    bn = BayesNet([A], [TabularCPD("a", [], [0.5, 0.5])])
    with pytest.raises(EvidenceError, match="evidence must be a mapping"):
        check_evidence(bn, [("a", 1)])
    with pytest.raises(EvidenceError, match="soft evidence must be a mapping"):
        marginals(bn, None, "a")
    assert variable_elimination(bn, "a").variables == ("a",)  # one name, as a sequence of one


@settings(max_examples=60, deadline=None)
@given(n=st.integers(1, 12), seed=st.integers(0, 2**32 - 1))
def test_topological_order_is_networkx_lexicographic_order(n: int, seed: int) -> None:
    """BayesNet's own heap-based order equals networkx's lexicographical_topological_sort
    (the oracle it replaced) on random DAGs whose names are declared out of order."""
    rng = np.random.default_rng(seed)
    names = [f"v{k}" for k in rng.permutation(n)]
    parents = {c: [p for p in names[:i] if rng.random() < 0.3] for i, c in enumerate(names)}
    variables = [DiscreteVariable(v, 2) for v in rng.permutation(names)]
    cpds = [TabularCPD(c, ps, np.full((2,) * len(ps) + (2,), 0.5)) for c, ps in parents.items()]
    bn = BayesNet(variables, cpds)
    assert bn.topological_order() == tuple(nx.lexicographical_topological_sort(bn.graph))


def test_a_cycle_is_named_along_its_path() -> None:
    a, b, c = (DiscreteVariable(x, 2) for x in "abc")
    half = np.full((2, 2), 0.5)
    with pytest.raises(CycleError, match=r"cycle: (a -> b -> c -> a|b -> c -> a -> b|c -> a -> b -> c)"):
        BayesNet([a, b, c], [TabularCPD("a", ["c"], half), TabularCPD("b", ["a"], half),
                             TabularCPD("c", ["b"], half)])


def test_bayes_net_sample_takes_a_seed_and_refuses_bad_sizes() -> None:
    """``BayesNet.sample``: an int seed is ``np.random.default_rng(seed)`` (it raised
    AttributeError: 'int' object has no attribute 'random'); a negative or fractional
    size raised numpy's ValueError or Python's TypeError."""
    from dbn.errors import InputError
    from dbn.pgmpy_adapter import bundled_network

    bn = bundled_network("asia")
    by_seed, by_rng = bn.sample(7, 50), bn.sample(np.random.default_rng(7), 50)
    assert all(np.array_equal(by_seed[n], by_rng[n]) for n in bn.nodes)
    assert all(v.shape == (0,) for v in bn.sample(0, 0).values())
    for rng, n, needle in ((0, -1, "num_samples"), (0, 2.5, "num_samples"),
                           (0, True, "num_samples"), (-3, 1, "rng"), ("x", 1, "rng")):
        with pytest.raises(InputError, match=needle):
            bn.sample(rng, n)


def test_a_variable_object_where_a_name_is_wanted_says_to_give_its_name() -> None:
    from dbn.cpds import TabularCPD
    from dbn.errors import ModelError
    from dbn.variables import DiscreteVariable

    a, b = DiscreteVariable("a", 2), DiscreteVariable("b", 2)
    with pytest.raises(ModelError, match=r"give 'a'\)"):
        TabularCPD(a, [], [0.5, 0.5])
    with pytest.raises(ModelError, match=r"parent names .* give 'b'\)"):
        TabularCPD("a", [b], [[0.5, 0.5]] * 2)
