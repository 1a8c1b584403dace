"""Complex numbers in a declaration or in soft evidence are refused, naming the field;
a CPD keeps copies of the arrays it is given; ``BayesNet.log_joint`` names an assignment
that is not a mapping.

numpy's float conversion keeps the real part with only a ``ComplexWarning``: a CPD table
``[0.5, 0.5 + 1j]`` was accepted as ``[0.5, 0.5]`` and a likelihood ``[1 + 1j, 1]`` as
``[1, 1]``.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from dbn.bayesnet import check_likelihood
from dbn.cpds import ConditionalLinearGaussianCPD, LinearGaussianCPD, TabularCPD
from dbn.errors import CPDShapeError, EvidenceError, ModelError

J = np.complex128(1j)

CASES = [
    ("table", CPDShapeError, lambda: TabularCPD("a", [], np.array([0.5, 0.5 + J]))),
    ("bias", ModelError,
     lambda: LinearGaussianCPD("y", [], [], np.array([1.0 + J]), np.eye(1))),
    ("cov", ModelError,
     lambda: LinearGaussianCPD("y", [], [], [0.0], np.eye(1) + 0 * J)),
    ("weight of parent 'x'", ModelError,
     lambda: LinearGaussianCPD("y", ["x"], [np.array([[2.0 + J]])], [0.0], np.eye(1))),
    ("bias", ModelError,
     lambda: ConditionalLinearGaussianCPD("y", ["k"], [], [], np.array([[J], [0.0]]),
                                          np.ones((2, 1, 1)))),
    ("soft evidence on 'a'", EvidenceError,
     lambda: check_likelihood("a", 2, np.array([1.0 + J, 1.0]))),
]  # fmt: skip


@pytest.mark.parametrize(("field", "error", "make"), CASES, ids=[c[0] for c in CASES])
def test_complex_numbers_are_refused_naming_the_field(field, error, make):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no ComplexWarning either
        with pytest.raises(error, match="complex") as exc:
            make()
    assert field in str(exc.value)


def test_complex_dtype_with_zero_imaginary_parts_is_refused_too():
    """The dtype decides (as numpy's own cast does), not the values: a real table carried
    in a complex array is a caller's mistake worth naming, not a guess to make."""
    with pytest.raises(CPDShapeError, match="complex"):
        TabularCPD("a", [], np.array([0.5, 0.5], dtype=complex))


def test_a_cpd_copies_the_callers_arrays():
    """The Gaussian CPDs froze the caller's own bias, cov and weight arrays (read-only, so
    the caller's next ``b[0] = 1`` raised numpy's error); the CPD keeps a copy."""
    b, S, W = np.array([0.0]), np.eye(1), np.array([[2.0]])
    cpd = LinearGaussianCPD("y", ["x"], [W], b, S)
    b2, S2 = np.zeros((2, 1)), np.ones((2, 1, 1))
    ccpd = ConditionalLinearGaussianCPD("y", ["k"], [], [], b2, S2)
    t = np.array([0.5, 0.5])
    tcpd = TabularCPD("a", [], t)
    for a in (b, S, W, b2, S2, t):
        assert a.flags.writeable
        a[...] = 7.0  # the caller changes its arrays: the CPDs keep theirs
    assert cpd.bias.tolist() == [0.0] and cpd.weights[0].tolist() == [[2.0]]
    assert cpd.cov.tolist() == [[1.0]] and ccpd.bias.tolist() == [[0.0], [0.0]]
    assert tcpd.table.tolist() == [0.5, 0.5]
    assert not cpd.bias.flags.writeable and not ccpd.cov.flags.writeable


def test_log_joint_names_an_assignment_that_is_not_a_mapping():
    """A list of pairs or None raised Python's AttributeError."""
    from dbn.bayesnet import BayesNet
    from dbn.variables import DiscreteVariable

    bn = BayesNet([DiscreteVariable("a", 2)], [TabularCPD("a", [], [0.4, 0.6])])
    assert np.isclose(bn.log_joint({"a": 1}), np.log(0.6))
    with pytest.raises(EvidenceError, match="assignment must be a mapping"):
        bn.log_joint([("a", 1)])
    with pytest.raises(EvidenceError, match=r"assignment misses variable\(s\) \['a'\]"):
        bn.log_joint(None)
