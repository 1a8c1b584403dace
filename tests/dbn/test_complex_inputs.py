"""Complex numbers in a declaration or in soft evidence are refused, naming the field.

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
