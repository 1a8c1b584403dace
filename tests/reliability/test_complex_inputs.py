"""Complex numbers are refused, naming the input: numpy's float conversion drops their
imaginary parts with only a ``ComplexWarning``, so a complex observation or parameter ran
as its real part (the Kalman filter, every DBN engine's evidence columns, the localization
model's numbers). The zajdel readers refused them already."""

from __future__ import annotations

import warnings

import jax
import numpy as np
import pytest

import inference
from dbn.checks import refuse_complex
from dbn.cpds import LinearGaussianCPD
from dbn.dbn import TwoSliceDBN, prev
from dbn.errors import DBNError, EvidenceError, InputError
from dbn.examples import coupled_chains
from dbn.variables import ContinuousVariable
from inference.kalman import LinearGaussianParams, kalman_filter
from models.localization.model import RangeBearingLocalizationModel


def _walk() -> TwoSliceDBN:
    """A random walk seen in noise: two continuous variables of dimension 1."""
    see = LinearGaussianCPD("y", ["x"], [[[1.0]]], [0.0], [[0.5]])
    return TwoSliceDBN([ContinuousVariable("x"), ContinuousVariable("y")],
                       [LinearGaussianCPD("x", [], [], [0.0], [[1.0]]), see],
                       [LinearGaussianCPD("x", [prev("x")], [[[1.0]]], [0.0], [[0.1]]), see])


def _params(**change) -> LinearGaussianParams:
    one = np.eye(1)
    return LinearGaussianParams(one, one, one, one, np.zeros(1), one)._replace(**change)


@pytest.mark.parametrize("call", [
    lambda: kalman_filter(_params(), np.array([[1.0 + 2.0j]])),
    lambda: kalman_filter(_params(F=np.eye(1) * (1 + 1j)), np.array([[1.0]])),
    lambda: inference.filter(coupled_chains(2), {"y0": np.array([0, 1], complex), "y1": [0, 1]}),
    lambda: inference.filter(_walk(), {"y": np.array([1.0, 2.0j])}, "particle",
                             key=jax.random.key(0), num_particles=10),
    lambda: RangeBearingLocalizationModel(np.array([[1j, 0.0]]), [0, 0, 0], [1, 1, 1]),
], ids=["kalman observations", "kalman F", "discrete column", "continuous column",
        "landmarks"])  # fmt: skip
def test_a_complex_input_is_refused_not_cast(call) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no ComplexWarning on the way to the error
        with pytest.raises(DBNError, match="complex numbers"):
            call()


def test_refuse_complex_lets_real_and_unreadable_values_pass() -> None:
    for value in ([1, 2.5], np.zeros(3, np.float32), [[1], [1, 2]], "abc", None):
        refuse_complex("x", value)
    with pytest.raises(InputError, match="x holds complex"):
        refuse_complex("x", [1, 2j])
    with pytest.raises(EvidenceError):
        refuse_complex("x", np.ones(2, np.complex64), EvidenceError)
