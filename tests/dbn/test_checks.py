"""dbn.checks: the argument checks and the one bound on times, spreads and parameters."""

import numpy as np
import pytest

from dbn.checks import MAX_SCALE, MIN_SCALE, check_count, check_nonnegative
from dbn.errors import ConfigError, InputError


def test_scale_bounds_square_to_normal_finite_floats():
    """The readers' and configs' bounds hold their promise: a value at the bound survives
    squaring in float64 (neither inf nor a subnormal), so no Gaussian overflows on it."""
    with np.errstate(all="raise"):
        big, small = np.float64(MAX_SCALE) ** 2, np.float64(MIN_SCALE) ** 2
    assert np.isfinite(big) and small >= np.finfo(np.float64).tiny


def test_trackers_share_the_scale_bound():
    """The Zajdel and localization readers take their time bound from dbn.checks."""
    from models.io import localization
    from models.zajdel import data

    assert data.MAX_TIME == localization.MAX_TIME == MAX_SCALE


@pytest.mark.parametrize("value", [0, -1, 2.5, True, "3", None])
def test_check_count_refuses_non_counts(value):
    with pytest.raises(ConfigError, match="n_items"):
        check_count("n_items", value, ConfigError)


@pytest.mark.parametrize("value", [-1e-9, float("nan"), True, "1"])
def test_check_nonnegative_refuses(value):
    with pytest.raises(InputError, match="rate"):
        check_nonnegative("rate", value)


def test_checks_return_plain_python_numbers():
    assert type(check_count("n", np.int64(3))) is int
    assert type(check_nonnegative("x", np.float32(0.5))) is float


def test_make_rng_is_numpy_seeding_with_the_library_error() -> None:
    from dbn.checks import make_rng

    a, b = make_rng(7).random(3), np.random.default_rng(7).random(3)
    np.testing.assert_array_equal(a, b)
    g = np.random.default_rng(1)
    assert make_rng(g) is g and make_rng([1, 2]).random() == np.random.default_rng([1, 2]).random()
    for bad in (-1, 2.5, "x", True, object()):
        with pytest.raises(InputError, match="seed must be an integer >= 0"):
            make_rng(bad)


@pytest.mark.parametrize("simulate", [
    "models.jorge.simulate:simulate_ground_truth", "models.zajdel.simulate:simulate_office",
])  # fmt: skip
def test_simulators_name_a_bad_seed(simulate) -> None:
    """numpy's "expected non-negative integer" named no argument."""
    import importlib

    module, name = simulate.split(":")
    with pytest.raises(InputError, match=r"seed must be an integer >= 0 .*, got -1"):
        getattr(importlib.import_module(module), name)(-1)


def test_check_size_takes_zero_and_refuses_the_rest() -> None:
    from dbn.checks import check_size

    assert check_size("n", 0) == 0 and type(check_size("n", np.int64(3))) is int
    for bad in (-1, 2.5, True, "3", None):
        with pytest.raises(ConfigError, match="n must be an integer >= 0"):
            check_size("n", bad, ConfigError)


def test_evidence_state_reads_a_state_as_a_column_does() -> None:
    import pandas as pd

    from dbn.checks import evidence_state

    for unobserved in (None, -1, np.int64(-1), float("nan"), np.float32("nan"), pd.NA, pd.NaT):
        assert evidence_state(unobserved) is None
    assert evidence_state(2.0) == 2 and type(evidence_state(np.float64(2.0))) is int
    for kept in (0.5, float("inf"), "wet", True, 3):
        assert evidence_state(kept) is kept


def test_real_array_and_whole_array_name_what_is_not_numbers():
    """The shared conversions: complex, text and ragged lists are named; whole_array takes
    whole floats and integer arrays (as they are, beyond 2**53 too) and refuses 1.5 or NaN."""
    from dbn.checks import real_array, whole_array

    assert real_array("x", [1, 2]).dtype == np.float64
    for bad, needle in ((np.array([1j]), "x holds complex"), (["a"], "x is not an array"),
                        ([[1.0], [1.0, 2.0]], "x is not an array")):  # fmt: skip
        with pytest.raises(InputError, match=needle):
            real_array("x", bad)
    big = np.array([2**62 + 1], dtype=np.int64)
    assert whole_array("i", big).tolist() == [2**62 + 1] and whole_array("i", [3.0]).tolist() == [3]
    source = np.array([1, 2])
    assert whole_array("i", source) is not source
    for bad in ([1.5], [np.nan], [np.inf], ["a"], [1j]):
        with pytest.raises(InputError, match="i "):
            whole_array("i", bad)
    with pytest.raises(ConfigError, match="i must be whole numbers"):
        whole_array("i", [0.5], ConfigError)


def test_is_real_number_refuses_bools_complex_and_text():
    """np.number takes complex scalars, which numpy orders by their real parts: a complex
    k-NN threshold, frame rate or prior strength passed their range checks."""
    from dbn.checks import is_real_number

    for ok in (0, 2.5, np.int64(3), np.float32(1.5), float("nan"), float("inf")):
        assert is_real_number(ok), ok
    for bad in (True, np.bool_(False), 1j, np.complex128(2 + 1j), "1", None, np.ones(1)):
        assert not is_real_number(bad), bad
