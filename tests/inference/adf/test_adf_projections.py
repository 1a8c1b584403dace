"""ADF projections: NIW KL projection (property tests), Gaussian moment matching,
categorical marginals, Student-t predictive."""

from __future__ import annotations

import jax
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.stats import multivariate_t

from inference.adf import (
    NIW,
    categorical_marginals,
    gaussian_moment_match,
    mix_categoricals,
    niw_predictive_logpdf_np,
    niw_project,
    normalize_log,
    student_t_logpdf,
    student_t_logpdf_np,
)
from tests.inference.adf.niw_oracle import niw_expected_stats_np, niw_project_np


@pytest.fixture(autouse=True)
def _float64():
    """jax in float64 for these exactness checks (no global setting)."""
    with jax.enable_x64(True):
        yield


def random_niw(rng, m, r):
    A = rng.normal(size=(m, r, r))
    C = A @ np.swapaxes(A, -1, -2) + r * np.eye(r) * rng.uniform(0.1, 3.0, size=(m, 1, 1))
    return NIW(
        rng.normal(size=(m, r)) * rng.uniform(0.1, 3.0),
        rng.uniform(0.2, 20.0, m),
        r - 1 + rng.uniform(1.0, 40.0, m),
        C,
    )


def stats(theta, w=None):
    P, h, s, g = niw_expected_stats_np(theta)
    if w is None:
        return P, h, s, g
    return np.einsum("m,mij->ij", w, P), w @ h, w @ s, w @ g


seeds = st.integers(0, 2**31 - 1)


@settings(max_examples=25, deadline=None)
@given(seed=seeds, r=st.sampled_from([1, 4, 9]))
def test_one_component_projects_to_itself(seed, r):
    rng = np.random.default_rng(seed)
    th = random_niw(rng, 1, r)
    out = niw_project(np.ones((1, 1)), NIW(*(x[None] for x in th)))
    np.testing.assert_allclose(out.a[0], th.a[0], rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(out.kappa[0], th.kappa[0], rtol=1e-9)
    np.testing.assert_allclose(out.eta[0], th.eta[0], rtol=1e-9)
    np.testing.assert_allclose(out.C[0], th.C[0], rtol=1e-9, atol=1e-9 * np.abs(th.C).max())


@settings(max_examples=25, deadline=None)
@given(seed=seeds, r=st.sampled_from([1, 4, 9]), m=st.sampled_from([2, 5]))
def test_projection_reproduces_four_expected_statistics(seed, r, m):
    rng = np.random.default_rng(seed)
    th = random_niw(rng, m, r)
    w = rng.dirichlet(np.ones(m))
    out = niw_project(w[None], NIW(*(x[None] for x in th)))
    target = stats(th, w)
    got = stats(NIW(out.a[0], out.kappa[0], out.eta[0], out.C[0]))
    for t, g in zip(target, got):
        np.testing.assert_allclose(g, t, rtol=1e-8, atol=1e-8 * max(1.0, np.abs(t).max()))


@settings(max_examples=15, deadline=None)
@given(seed=seeds, m=st.sampled_from([2, 5]))
def test_projection_order_invariant_and_batched(seed, m):
    rng = np.random.default_rng(seed)
    r = 4
    th = random_niw(rng, m, r)
    w = rng.dirichlet(np.ones(m))
    perm = rng.permutation(m)
    batch_w = np.stack([w, w[perm]])
    batch = NIW(*(np.stack([x, x[perm]]) for x in th))
    out = niw_project(batch_w, batch)
    for f in out:
        np.testing.assert_allclose(f[0], f[1], rtol=1e-10, atol=1e-12)
    ref = niw_project_np(w, th)  # the plain numpy oracle agrees
    np.testing.assert_allclose(out.C[0], ref.C, rtol=1e-9)
    np.testing.assert_allclose(out.eta[0], ref.eta, rtol=1e-9)


def test_zero_weight_component_is_padding():
    rng = np.random.default_rng(1)
    th = random_niw(rng, 3, 3)
    w = np.array([0.3, 0.0, 0.7])
    a = niw_project(w[None], NIW(*(x[None] for x in th)))
    b = niw_project(w[[0, 2]][None], NIW(*(x[None][:, [0, 2]] for x in th)))
    for x, y in zip(a, b):
        np.testing.assert_allclose(x, y, rtol=1e-12)


def test_student_t_matches_scipy():
    rng = np.random.default_rng(0)
    r = 3
    th = random_niw(rng, 1, r)
    o = rng.normal(size=r)
    nu = th.eta[0] - r + 1
    scale = th.C[0] * (th.kappa[0] + 1) / (th.kappa[0] * nu)
    ref = multivariate_t(loc=th.a[0], shape=scale, df=nu).logpdf(o)
    assert niw_predictive_logpdf_np(o, NIW(*(x[0] for x in th))) == pytest.approx(ref, rel=1e-10)
    assert student_t_logpdf_np(o, nu, th.a[0], scale) == pytest.approx(ref, rel=1e-10)
    assert float(student_t_logpdf(o, nu, th.a[0], scale)) == pytest.approx(ref, rel=1e-10)


def test_gaussian_moment_match_against_direct_formula():
    rng = np.random.default_rng(2)
    w = rng.dirichlet(np.ones(4))
    mu = rng.normal(size=(4, 2))
    A = rng.normal(size=(4, 2, 2))
    S = A @ np.swapaxes(A, 1, 2) + np.eye(2)
    m, c = gaussian_moment_match(w, mu, S)
    m_ref = w @ mu
    c_ref = sum(w[i] * (S[i] + np.outer(mu[i] - m_ref, mu[i] - m_ref)) for i in range(4))
    np.testing.assert_allclose(m, m_ref, rtol=1e-12)
    np.testing.assert_allclose(c, c_ref, rtol=1e-12)
    m1, c1 = gaussian_moment_match(np.ones(1), mu[:1], S[:1])  # one component: itself
    np.testing.assert_allclose(c1, S[0], rtol=1e-12)


def test_categorical_pieces():
    rng = np.random.default_rng(3)
    joint = rng.uniform(size=(3, 4))
    m0, m1 = categorical_marginals(joint)
    np.testing.assert_allclose(m0, joint.sum(1) / joint.sum(), rtol=1e-12)
    np.testing.assert_allclose(m1, joint.sum(0) / joint.sum(), rtol=1e-12)
    l0, _ = categorical_marginals(np.log(joint), log=True)
    np.testing.assert_allclose(l0, m0, rtol=1e-12)
    p, ln = normalize_log(np.array([0.0, -np.inf, np.log(3.0)]))
    np.testing.assert_allclose(p, [0.25, 0.0, 0.75], rtol=1e-12)
    assert float(ln) == pytest.approx(np.log(4.0))
    t = rng.dirichlet(np.ones(5), size=3)
    mix = mix_categoricals(np.array([1.0, 2.0, 1.0]), t)
    np.testing.assert_allclose(mix, (t[0] + 2 * t[1] + t[2]) / 4, rtol=1e-12)
