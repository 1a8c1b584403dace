"""VE, junction tree and MAP against brute-force enumeration and against pgmpy."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dbn import pgmpy_adapter as pa
from dbn.errors import (
    EvidenceError,
    InputError,
    ModelError,
    NegativeProbabilityError,
    ShapeError,
)
from inference.exact import Factor, JunctionTree, log_evidence, map_assignment, variable_elimination
from inference.exact.enumeration import brute_force_map, brute_force_marginals, joint_factor

TOL = 1e-9


@settings(max_examples=120, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), ev_seed=st.integers(0, 2**31 - 1))
def test_engines_equal_enumeration(factories, seed: int, ev_seed: int) -> None:
    bn = factories.random_bn(seed)
    hard, soft = factories.random_evidence(ev_seed, bn)
    logz = joint_factor(bn, hard, soft).log_normalizer()
    jt = JunctionTree(bn)
    if not np.isfinite(logz):  # impossible evidence: every engine says so
        with pytest.raises(EvidenceError):
            jt.calibrate(hard, soft)
        with pytest.raises(EvidenceError):
            map_assignment(bn, hard, soft)
        hidden = [n for n in bn.nodes if n not in hard]
        if hidden:
            with pytest.raises(EvidenceError):
                variable_elimination(bn, hidden[:1], hard, soft)
        assert log_evidence(bn, hard, soft) == -np.inf
        return
    expected, expected_logz = brute_force_marginals(bn, hard, soft)
    cal = jt.calibrate(hard, soft)
    assert abs(cal.log_evidence - expected_logz) < TOL
    assert abs(log_evidence(bn, hard, soft) - expected_logz) < TOL
    for n in bn.nodes:
        assert abs(cal.marginals[n].sum() - 1.0) < TOL
        if n in hard:
            assert cal.marginals[n][hard[n]] == 1.0
            continue
        np.testing.assert_allclose(cal.marginals[n], expected[n], atol=TOL, rtol=0)
        ve = variable_elimination(bn, [n], hard, soft).probabilities()
        np.testing.assert_allclose(ve, expected[n], atol=TOL, rtol=0)
    hidden = [n for n in bn.nodes if n not in hard]
    if len(hidden) >= 2:  # a joint query equals the enumerated joint
        q = hidden[:2]
        joint = joint_factor(bn, hard, soft).keep(q).probabilities(q)
        np.testing.assert_allclose(
            variable_elimination(bn, q, hard, soft).probabilities(q), joint, atol=TOL
        )
    config, lp = map_assignment(bn, hard, soft)
    _, best = brute_force_map(bn, hard, soft)
    assert abs(lp - best) < TOL
    full = {**config, **hard}
    attained = bn.log_joint(full) + sum(float(np.log(soft[k][full[k]])) for k in soft)
    assert abs(attained - best) < TOL  # the returned configuration attains the maximum


def test_factor_value_semantics() -> None:
    f = Factor.from_table(("a", "b"), np.array([[0.1, 0.2], [0.3, 0.4]]))
    g = Factor.from_table(("b", "c"), np.array([[1.0, 2.0], [3.0, 4.0]]))
    before = f.log_values.copy()
    h = f * g
    assert h.variables == ("a", "b", "c")
    np.testing.assert_allclose(h.values[1, 0, 1], 0.3 * 2.0)
    np.testing.assert_array_equal(f.log_values, before)
    np.testing.assert_allclose(f.marginalize(["a"]).values, [0.4, 0.6])
    np.testing.assert_allclose(f.reduce({"b": 1}).values, [0.2, 0.4])
    assert f.normalize().values.sum() == pytest.approx(1.0)
    with pytest.raises(ValueError):
        f.log_values[0, 0] = 0.0


def test_bad_evidence_leaves_tree_usable_and_unchanged() -> None:
    bn = pa.bundled_network("asia")
    jt = JunctionTree(bn)
    before = jt.calibrate({"asia": "yes"})
    with pytest.raises(EvidenceError, match="unknown"):
        jt.calibrate({"nope": "yes"})
    with pytest.raises(EvidenceError, match="no state named"):
        jt.calibrate({"asia": "maybe"})
    with pytest.raises(EvidenceError, match="shape"):
        jt.calibrate(soft_evidence={"asia": [1.0, 2.0, 3.0]})
    state = bn.variable("asia").index("yes")
    zero = np.ones(2)
    zero[state] = 0.0
    with pytest.raises(EvidenceError, match="likelihood zero"):
        jt.calibrate({"asia": "yes"}, {"asia": zero})
    after = jt.calibrate({"asia": "yes"})
    for n in bn.nodes:
        np.testing.assert_array_equal(before.marginals[n], after.marginals[n])


@pytest.mark.parametrize("name", pa.EXAMPLE_NETWORKS)
def test_example_networks_equal_pgmpy(name: str) -> None:
    bn = pa.bundled_network(name)
    model = pa.to_pgmpy(bn)
    jt = JunctionTree(bn)
    rng = np.random.default_rng(abs(hash(name)) % 2**32)
    cases = [{}]
    for _ in range(20):  # a random evidence set of positive probability
        nodes = rng.choice(bn.nodes, size=min(3, len(bn) - 1), replace=False)
        ev = {
            str(n): bn.variable(str(n)).state_names[rng.integers(bn.cardinality(str(n)))]
            for n in nodes
        }
        if np.isfinite(log_evidence(bn, ev)):
            cases.append(ev)
            break
    assert len(cases) == 2
    for ev in cases:
        cal = jt.calibrate(ev)
        hidden = [n for n in bn.nodes if n not in ev]
        theirs = pa.pgmpy_marginals(model, hidden, ev)
        for n in hidden:
            np.testing.assert_allclose(cal.marginals[n], theirs[n], atol=TOL, rtol=0)
            assert abs(cal.marginals[n].sum() - 1.0) < TOL


@pytest.mark.parametrize(("make", "error", "needle"), [
    (lambda: Factor(("a",), np.array(["x", "y"])), InputError, "log_values is not an array"),
    (lambda: Factor(("a",), np.array([1j, 0])), InputError, "log_values holds complex"),
    (lambda: Factor("ab", np.zeros((2, 2))), ModelError, "must be a tuple of names, got 'ab'"),
    (lambda: Factor(("a", "a"), np.zeros((2, 2))), ModelError, "must be distinct"),
    (lambda: Factor(("a",), np.zeros((2, 2))), ShapeError, "needs 1 axes, got shape (2, 2)"),
    (lambda: Factor.from_table(("a",), ["x", "y"]), InputError, "table is not an array"),
    (lambda: Factor.from_table("ab", np.ones((2, 2))), ModelError, "tuple of names, got 'ab'"),
    (lambda: Factor.from_table(("a",), [-1.0, 1.0]), NegativeProbabilityError, "negative"),
    (lambda: Factor.from_table(("a",), [np.nan, 1.0]), NegativeProbabilityError, "NaN"),
])  # fmt: skip
def test_a_factor_names_values_it_cannot_hold(make, error, needle) -> None:
    """Text raised numpy's ValueError, complex values lost their imaginary parts, 'ab'
    was read as the variables 'a' and 'b', shapes raised a bare ValueError, and a negative
    or NaN table became a NaN factor with only a RuntimeWarning."""
    with pytest.raises(error) as exc:
        make()
    assert needle in str(exc.value)
