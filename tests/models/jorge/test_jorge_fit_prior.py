"""``models.jorge.fit_prior.shrink``: a fit on little data shrunk towards a prior network,
against the closed form of the Dirichlet (Beta) posterior mean."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from dbn.errors import InputError
from models.jorge.evidence import palette_gain_bin
from models.jorge.fit import count_events, fit_counts
from models.jorge.fit_prior import shrink
from models.jorge.labels import LabelParams
from models.jorge.network import FITTED_LABELS, NetworkConfig
from models.jorge.strokes import build_strokes, load_caviar

XML = Path(__file__).resolve().parents[2] / "data" / "jorge" / "caviar.xml"
RATES = ("p_new", "p_merge", "p_merge_one_split", "p_merge_both_split", "p_split", "p_part",
         "p_join")


@pytest.fixture(scope="module")
def fit():
    """(counts, fitted, prior) on SIMULATED strokes of the tiny CAVIAR example."""
    prior = NetworkConfig()
    counts = count_events(build_strokes(3, load_caviar(XML)), prior)
    return counts, fit_counts(counts, prior), prior


def test_zero_is_the_fit_and_a_huge_strength_the_prior(fit):
    counts, fitted, prior = fit
    assert shrink(fitted, prior, counts, 0.0) == fitted
    big = shrink(fitted, prior, counts, 1e12)
    for name in (*RATES, "new_group_probs", "split_cover"):
        np.testing.assert_allclose(getattr(big.labels, name), getattr(prior.labels, name),
                                   rtol=1e-9, err_msg=name)  # fmt: skip
    for name in ("palette_gain_table", "palette_missing_table"):
        np.testing.assert_allclose(np.exp(getattr(big, name)), np.exp(getattr(prior, name)),
                                   atol=1e-9, err_msg=name)  # fmt: skip
    for name in ("size_mu_single", "size_slope", "size_sigma"):
        assert getattr(big, name) == pytest.approx(getattr(prior, name), rel=1e-9), name


def test_the_size_likelihood_takes_the_normal_inverse_gamma_posterior(fit):
    """The textbook conjugate update (precision form, from the strokes' own areas) gives
    the posterior mean of the coefficients and 1 / E[1 / sigma^2]."""
    counts, fitted, prior = fit
    lam, gmax = 25.0, prior.labels.max_group_size
    k, y = (np.array(v, dtype=np.float64) for v in zip(*counts.sizes))
    x = np.stack([np.ones_like(k), np.log(np.minimum(k, gmax))], axis=1)
    n = len(y)
    s0 = lam * x.T @ x / n  # the prior precision of beta, in units of sigma^-2
    b0 = np.array([prior.size_mu_single, prior.size_slope])
    prec = x.T @ x + s0
    beta = np.linalg.solve(prec, s0 @ b0 + x.T @ y)
    a_n = lam / 2 + n / 2
    b_n = lam * prior.size_sigma**2 / 2 + (y @ y + b0 @ s0 @ b0 - beta @ prec @ beta) / 2
    got = shrink(fitted, prior, counts, lam)
    assert (got.size_mu_single, got.size_slope) == pytest.approx(tuple(beta), rel=1e-10)
    assert got.size_sigma == pytest.approx(np.sqrt(b_n / a_n), rel=1e-10)
    assert n > 2 and abs(fitted.size_slope - prior.size_slope) > 0.01  # not the prior's alone


def test_the_posterior_mean_of_a_rate_and_of_a_table_row(fit):
    counts, fitted, prior = fit
    lam = 40.0
    got = shrink(fitted, prior, counts, lam)
    p0 = prior.labels.p_new
    assert got.labels.p_new == pytest.approx((counts.new + 1 + lam * p0) / (counts.children + 2 + lam))
    bins, width = prior.palette_gain_bins, 2 * prior.pool_size + 1
    n = np.zeros(width)  # the events of row (m = 1, bin 0): new people, nobody known
    for m, u, e in counts.palette_gains:
        if m == 1 and palette_gain_bin(bins, u) == 0:
            n[int(np.clip(e, -prior.pool_size, prior.pool_size)) + prior.pool_size] += 1
    want = (n + 1 + lam * np.exp(prior.palette_gain_table[1][0])) / (n.sum() + width + lam)
    np.testing.assert_allclose(np.exp(got.palette_gain_table[1][0]), want, rtol=1e-12)
    assert n.sum() > 0  # the row has events: the check is not the prior's row alone


@settings(max_examples=40, deadline=None)
@given(lam=st.floats(0.0, 1e6))
def test_each_estimate_lies_between_the_fit_and_the_prior(fit, lam):
    counts, fitted, prior = fit
    got = shrink(fitted, prior, counts, lam)
    for name in RATES:
        a, b = getattr(fitted.labels, name), getattr(prior.labels, name)
        lo, hi = min(a, b), max(a, b)
        assert lo - 1e-12 <= getattr(got.labels, name) <= hi + 1e-12, name
    for name in ("palette_gain_table", "palette_missing_table"):
        p = np.exp(np.asarray(getattr(got, name)))
        np.testing.assert_allclose(p.sum(axis=-1), 1.0, rtol=1e-12)
        lo = np.minimum(np.exp(getattr(fitted, name)), np.exp(getattr(prior, name)))
        hi = np.maximum(np.exp(getattr(fitted, name)), np.exp(getattr(prior, name)))
        assert np.all(p >= lo * (1 - 1e-9)) and np.all(p <= hi * (1 + 1e-9)), name
    assert sum(got.labels.new_group_probs) == pytest.approx(1.0)
    for name in ("size_mu_single", "size_slope"):
        a, b = getattr(fitted, name), getattr(prior, name)
        assert min(a, b) - 1e-12 <= getattr(got, name) <= max(a, b) + 1e-12, name


def test_a_larger_group_cap_takes_the_priors_last_row_and_bad_priors_are_refused():
    base = NetworkConfig(labels=replace(FITTED_LABELS, max_group_size=6))
    counts = count_events(build_strokes(3, load_caviar(XML)), base)
    fitted = fit_counts(counts, base)
    prior = NetworkConfig()  # groups of up to 5: gain table rows m = 0..5
    big = shrink(fitted, prior, counts, 1e12)
    np.testing.assert_allclose(np.exp(big.palette_gain_table[6]), np.exp(prior.palette_gain_table[5]),
                               atol=1e-9)  # fmt: skip
    assert len(big.labels.new_group_probs) == 6 and big.labels.new_group_probs[5] < 1e-9
    for lam in (-1.0, float("nan"), float("inf")):
        with pytest.raises(InputError, match="prior strength"):
            shrink(fitted, prior, counts, lam)
    small_pool = NetworkConfig(pool_size=10, labels=LabelParams(max_group_size=5),
                               palette_gain_table=np.zeros((6, 5, 21)).tolist(),
                               palette_missing_table=())  # fmt: skip
    with pytest.raises(InputError, match=r"prior palette_gain_table: shape .*\(another pool_size"):
        shrink(fitted, small_pool, counts, 10.0)
